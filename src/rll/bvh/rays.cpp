// Ray batches for the tracer tests and benchmarks.
#include "rll/bvh/rays.h"

#include <algorithm>
#include <cmath>

#include "rll/core/parallel.h"
#include "rll/core/rng.h"
#include "rll/core/sampling.h"

namespace rll {

namespace {

Vec3 uniform_direction(Pcg32& rng) {
  float a = rng.next_float();
  return sample_uniform_sphere({a, rng.next_float()});
}

Vec3 point_on_triangle(const Mesh& mesh, uint32_t tri, Pcg32& rng) {
  float a = rng.next_float();
  Vec2 b = sample_uniform_triangle({a, rng.next_float()});
  return mesh.vertex(tri, 0) * b.x + mesh.vertex(tri, 1) * b.y +
         mesh.vertex(tri, 2) * (1 - b.x - b.y);
}

Vec3 random_surface_point(const Mesh& mesh, Pcg32& rng) {
  return point_on_triangle(mesh, rng.next_bounded(uint32_t(mesh.triangles.size())), rng);
}

// A segment from a to b, open at both ends by ray_epsilon.
Ray segment(const Vec3& a, const Vec3& b) {
  Ray r;
  r.o = a;
  Vec3 d = b - a;
  float dist = length(d);
  r.d = dist > 0 ? d / dist : Vec3(0, 0, 1);
  r.tmin = ray_epsilon(a);
  r.tmax = std::max(r.tmin, dist - ray_epsilon(b));
  return r;
}

// Calls make(i, rng) for every i in [0, n) in parallel, the generator seeded by (seed, i).
template <typename Make>
void fill(std::vector<Ray>& out, uint64_t seed, const Make& make) {
  parallel_for(out.size(), 4096, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      Pcg32 rng(seed, i);
      out[i] = make(i, rng);
    }
  });
}

// The indices of the rays that hit.
std::vector<uint32_t> hit_indices(const std::vector<Hit>& hits) {
  std::vector<uint32_t> idx;
  for (size_t i = 0; i < hits.size(); ++i)
    if (hits[i].tri != ~0u) idx.push_back(uint32_t(i));
  return idx;
}

}  // namespace

Vec3 hit_point(const Mesh& mesh, const Hit& hit) {
  return mesh.vertex(hit.tri, 0) * (1 - hit.u - hit.v) + mesh.vertex(hit.tri, 1) * hit.u +
         mesh.vertex(hit.tri, 2) * hit.v;
}

bool hits_agree(const Hit& a, const Hit& b) {
  bool a_hit = a.tri != ~0u, b_hit = b.tri != ~0u;
  if (a_hit != b_hit) return false;
  if (!a_hit) return true;
  bool same_t = std::fabs(a.t - b.t) <= 1e-4f * std::max({1.0f, std::fabs(a.t), std::fabs(b.t)});
  if (a.tri != b.tri) return same_t;
  return same_t || (std::fabs(a.u - b.u) < 1e-2f && std::fabs(a.v - b.v) < 1e-2f);
}

std::vector<Ray> test_rays(const Scene& scene, size_t n, uint64_t seed) {
  std::vector<Ray> rays(n);
  if (scene.mesh.triangles.empty()) return rays;
  Bounds3 box = scene.bounds;
  Vec3 grow = box.diagonal() * 0.1f;
  box.lo -= grow;
  box.hi += grow;
  Camera camera = scene.camera;
  camera.setup(scene.width, scene.height);
  fill(rays, seed, [&](size_t i, Pcg32& rng) {
    Ray r;
    switch (4 * i / n) {
      case 0: {
        float a = rng.next_float(), b = rng.next_float(), c = rng.next_float();
        r.o = box.lo + box.diagonal() * Vec3(a, b, c);
        r.d = uniform_direction(rng);
        return r;
      }
      case 1:
        r.o = random_surface_point(scene.mesh, rng);
        r.d = uniform_direction(rng);
        r.tmin = ray_epsilon(r.o);
        return r;
      case 2: {
        float x = rng.next_float() * float(scene.width);
        return camera.generate_ray(x, rng.next_float() * float(scene.height));
      }
      default: {
        Vec3 a = random_surface_point(scene.mesh, rng);
        return segment(a, random_surface_point(scene.mesh, rng));
      }
    }
  });
  return rays;
}

std::vector<Ray> camera_rays(const Scene& scene, int width, int height, uint64_t seed) {
  Camera camera = scene.camera;
  camera.setup(width, height);
  std::vector<Ray> rays(size_t(width) * size_t(height));
  fill(rays, seed, [&](size_t i, Pcg32& rng) {
    float x = float(i % size_t(width)) + rng.next_float();
    return camera.generate_ray(x, float(i / size_t(width)) + rng.next_float());
  });
  return rays;
}

std::vector<Ray> bounce_rays(const Mesh& mesh, const std::vector<Ray>& rays,
                             const std::vector<Hit>& hits, uint64_t seed) {
  std::vector<uint32_t> idx = hit_indices(hits);
  std::vector<Ray> out(idx.size());
  fill(out, seed, [&](size_t i, Pcg32& rng) {
    const Hit& h = hits[idx[i]];
    Vec3 n = normalize(mesh.face_cross(h.tri));
    if (dot(n, rays[idx[i]].d) > 0) n = -n;
    float a = rng.next_float();
    Ray r;
    r.o = hit_point(mesh, h);
    r.d = normalize(Frame(n).to_world(sample_cosine_hemisphere({a, rng.next_float()})));
    r.tmin = ray_epsilon(r.o);
    return r;
  });
  return out;
}

std::vector<Ray> shadow_rays(const Scene& scene, const std::vector<Hit>& hits, uint64_t seed) {
  std::vector<uint32_t> emitters;
  for (size_t t = 0; t < scene.mesh.light.size(); ++t)
    if (scene.mesh.light[t] >= 0) emitters.push_back(uint32_t(t));
  if (emitters.empty())
    for (size_t t = 0; t < scene.mesh.triangles.size(); ++t) emitters.push_back(uint32_t(t));
  std::vector<uint32_t> idx = hit_indices(hits);
  std::vector<Ray> out(idx.size());
  fill(out, seed, [&](size_t i, Pcg32& rng) {
    Vec3 p = hit_point(scene.mesh, hits[idx[i]]);
    uint32_t e = emitters[rng.next_bounded(uint32_t(emitters.size()))];
    return segment(p, point_on_triangle(scene.mesh, e, rng));
  });
  return out;
}

}  // namespace rll
