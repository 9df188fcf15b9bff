// Closest-hit and any-hit traversal of rll's BVH (bvh/bvh.h): RLL_HD functions that the CPU runs
// directly and the GPU kernels of cuda/trace.cu run unchanged. Conventions as the Embree tracer
// (accel/embree.cpp): both sides of a triangle count, hits lie in (ray.tmin, ray.tmax),
// degenerate triangles are never hit, barycentrics as Hit documents them.
#pragma once

#include "rll/bvh/bvh.h"
#include "rll/scene/hit.h"

namespace rll {

namespace bvh_detail {

// A ray prepared once for all the boxes and triangles it meets: reciprocal directions for the
// slab tests, and the shear of Woop, Benthin & Wald (2013) that makes the triangle test
// watertight (no ray slips through an edge shared by two triangles).
struct PreparedRay {
  Vec3 o, inv_d;
  int kx, ky, kz;
  float sx, sy, sz;
  float tmin;
};

RLL_HD inline PreparedRay prepare(const Ray& ray) {
  PreparedRay r;
  r.o = ray.o;
  r.tmin = ray.tmin;
  // A zero component would make 0 * inf = NaN in the slab test: a tiny one keeps it finite.
  auto safe_inv = [](float d) {
    constexpr float kTiny = 1e-20f;
    return 1.0f / (std::fabs(d) > kTiny ? d : std::copysign(kTiny, d));
  };
  r.inv_d = Vec3(safe_inv(ray.d.x), safe_inv(ray.d.y), safe_inv(ray.d.z));
  Vec3 a = abs(ray.d);
  r.kz = a.x > a.y ? (a.x > a.z ? 0 : 2) : (a.y > a.z ? 1 : 2);
  r.kx = r.kz == 2 ? 0 : r.kz + 1;
  r.ky = r.kx == 2 ? 0 : r.kx + 1;
  r.sz = 1.0f / ray.d[r.kz];
  r.sx = ray.d[r.kx] * r.sz;
  r.sy = ray.d[r.ky] * r.sz;
  return r;
}

// Minimum and maximum without NaN handling (no NaN reaches them: see prepare): one instruction
// on either device, where std::fmin is a library call on the host.
RLL_HD inline float min_f(float a, float b) {
#if RLL_DEVICE_CODE
  return fminf(a, b);
#else
  return a < b ? a : b;
#endif
}
RLL_HD inline float max_f(float a, float b) {
#if RLL_DEVICE_CODE
  return fmaxf(a, b);
#else
  return a > b ? a : b;
#endif
}

// The node's four 16-byte parts, through the read-only cache on the GPU.
RLL_HD inline BvhNode load_node(const BvhNode* nodes, uint32_t i) {
#if RLL_DEVICE_CODE
  const float4* p = reinterpret_cast<const float4*>(nodes + i);
  BvhNode n;
  float4 a = __ldg(p), b = __ldg(p + 1), c = __ldg(p + 2);
  uint4 d = __ldg(reinterpret_cast<const uint4*>(p + 3));
  n.left_xy[0] = a.x, n.left_xy[1] = a.y, n.left_xy[2] = a.z, n.left_xy[3] = a.w;
  n.right_xy[0] = b.x, n.right_xy[1] = b.y, n.right_xy[2] = b.z, n.right_xy[3] = b.w;
  n.z[0] = c.x, n.z[1] = c.y, n.z[2] = c.z, n.z[3] = c.w;
  n.child[0] = d.x, n.child[1] = d.y, n.count[0] = d.z, n.count[1] = d.w;
  return n;
#else
  return nodes[i];
#endif
}

RLL_HD inline BvhTriangle load_triangle(const BvhTriangle* triangles, uint32_t i) {
#if RLL_DEVICE_CODE
  const float4* p = reinterpret_cast<const float4*>(triangles + i);
  float4 a = __ldg(p), b = __ldg(p + 1), c = __ldg(p + 2);
  BvhTriangle t;
  t.p0 = Vec3(a.x, a.y, a.z);
  t.tri = __float_as_uint(a.w);
  t.p1 = Vec3(b.x, b.y, b.z);
  t.p2 = Vec3(c.x, c.y, c.z);
  return t;
#else
  return triangles[i];
#endif
}

// Whether the ray meets the box within [tmin, tmax], and where it enters (tnear). tmax grows by 2
// gamma(3) (Ize 2013) so that rounding never culls a box the ray touches.
RLL_HD inline bool hit_box(const PreparedRay& r, float lox, float hix, float loy, float hiy,
                           float loz, float hiz, float tmax, float& tnear) {
  float tx0 = (lox - r.o.x) * r.inv_d.x, tx1 = (hix - r.o.x) * r.inv_d.x;
  float ty0 = (loy - r.o.y) * r.inv_d.y, ty1 = (hiy - r.o.y) * r.inv_d.y;
  float tz0 = (loz - r.o.z) * r.inv_d.z, tz1 = (hiz - r.o.z) * r.inv_d.z;
  float t0 = max_f(max_f(min_f(tx0, tx1), min_f(ty0, ty1)), max_f(min_f(tz0, tz1), r.tmin));
  float t1 = min_f(min_f(max_f(tx0, tx1), max_f(ty0, ty1)), min_f(max_f(tz0, tz1), tmax));
  tnear = t0;
  return t0 <= t1 * 1.0000004f;
}

// The watertight ray-triangle test (Woop et al. 2013): the edge functions are exact in sign up
// to the fallback to double where one is zero, so that a ray through a shared edge or vertex
// hits at least one of the triangles. Both sides count; degenerate triangles (det 0) never hit.
RLL_HD inline bool hit_triangle(const PreparedRay& r, const BvhTriangle& tri, float tmax, float& t,
                                float& b1, float& b2) {
  Vec3 a = tri.p0 - r.o, b = tri.p1 - r.o, c = tri.p2 - r.o;
  float ax = a[r.kx] - r.sx * a[r.kz], ay = a[r.ky] - r.sy * a[r.kz];
  float bx = b[r.kx] - r.sx * b[r.kz], by = b[r.ky] - r.sy * b[r.kz];
  float cx = c[r.kx] - r.sx * c[r.kz], cy = c[r.ky] - r.sy * c[r.kz];
  float u = cx * by - cy * bx;  // the weight of p0
  float v = ax * cy - ay * cx;  // p1
  float w = bx * ay - by * ax;  // p2
  if (u == 0 || v == 0 || w == 0) {
    u = float(double(cx) * double(by) - double(cy) * double(bx));
    v = float(double(ax) * double(cy) - double(ay) * double(cx));
    w = float(double(bx) * double(ay) - double(by) * double(ax));
  }
  if ((u < 0 || v < 0 || w < 0) && (u > 0 || v > 0 || w > 0)) return false;
  float det = u + v + w;
  if (det == 0) return false;
  float az = r.sz * a[r.kz], bz = r.sz * b[r.kz], cz = r.sz * c[r.kz];
  float t_scaled = u * az + v * bz + w * cz;
  float inv_det = 1.0f / det;
  t = t_scaled * inv_det;
  if (!(t > r.tmin && t < tmax)) return false;
  b1 = v * inv_det;
  b2 = w * inv_det;
  return true;
}

// The traversal both queries share: a stack of far children with their entry distances (a
// popped child is skipped if a closer hit has been found since), leaves tested as soon as
// their box is met, the nearer inner child first.
template <bool kAnyHit>
RLL_HD inline bool traverse(const BvhView& bvh, const Ray& ray, Hit& hit) {
  if (bvh.nodes.empty()) return false;
  const PreparedRay r = prepare(ray);
  float tmax = ray.tmax;
  bool found = false;
  uint32_t stack[kBvhStackSize];
  float stack_t[kBvhStackSize];
  int sp = 0;
  uint32_t k = 0;
  // Tests a leaf's triangles; true when an any-hit query is answered.
  auto leaf = [&](uint32_t child, uint32_t count) {
    uint32_t first = child & ~kBvhLeaf;
    for (uint32_t i = first; i < first + count; ++i) {
      const BvhTriangle tri = load_triangle(bvh.triangles.data, i);
      float th, b1, b2;
      if (!hit_triangle(r, tri, tmax, th, b1, b2)) continue;
      found = true;
      if (kAnyHit) return true;
      tmax = th;
      hit.t = th;
      hit.tri = tri.tri;
      hit.u = b1;
      hit.v = b2;
    }
    return false;
  };
  // Named scalars rather than arrays indexed by a run-time side, so that the GPU keeps them in
  // registers.
  for (;;) {
    const BvhNode n = load_node(bvh.nodes.data, k);
    const uint32_t c0 = n.child[0], c1 = n.child[1];
    float t0, t1;
    bool e0 = hit_box(r, n.left_xy[0], n.left_xy[1], n.left_xy[2], n.left_xy[3], n.z[0], n.z[1],
                      tmax, t0);
    bool e1 = hit_box(r, n.right_xy[0], n.right_xy[1], n.right_xy[2], n.right_xy[3], n.z[2], n.z[3],
                      tmax, t1);
    if (e0 && (c0 & kBvhLeaf)) {
      e0 = false;
      if (leaf(c0, n.count[0])) return true;
    }
    if (e1 && (c1 & kBvhLeaf)) {
      e1 = false;
      if (leaf(c1, n.count[1])) return true;
    }
    if (e0 && e1) {
      bool right_first = t1 < t0;
      stack[sp] = right_first ? c0 : c1;
      stack_t[sp] = right_first ? t0 : t1;
      ++sp;
      k = right_first ? c1 : c0;
      continue;
    }
    if (e0 || e1) {
      k = e0 ? c0 : c1;
      continue;
    }
    // Pop the next child that may still hold a hit nearer than the nearest so far.
    do {
      if (sp == 0) return found;
      --sp;
    } while (stack_t[sp] > tmax);
    k = stack[sp];
  }
}

}  // namespace bvh_detail

// The closest hit in (ray.tmin, ray.tmax); `hit` is written only when there is one.
RLL_HD inline bool intersect(const BvhView& bvh, const Ray& ray, Hit& hit) {
  return bvh_detail::traverse<false>(bvh, ray, hit);
}

// Whether anything lies in (ray.tmin, ray.tmax).
RLL_HD inline bool occluded(const BvhView& bvh, const Ray& ray) {
  Hit unused;
  return bvh_detail::traverse<true>(bvh, ray, unused);
}

}  // namespace rll
