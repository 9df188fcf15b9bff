// The local geometry at a ray hit: position, normals, uv, material and light of the triangle;
// the rays leaving it and the textures looked up there. RLL_HD over the scene's views: the CPU
// renderer and the GPU kernels call the same functions.
#pragma once

#include <cmath>

#include "rll/core/image.h"
#include "rll/scene/hit.h"
#include "rll/scene/scene.h"
#include "rll/scene/scene_view.h"

namespace rll {

struct SurfaceHit {
  Vec3 p;
  Vec3 ng;  // unit geometric normal, as wound (not flipped)
  Vec3 ns;  // unit shading normal, on the same side as ng
  Vec2 uv;
  uint32_t tri = 0;
  uint32_t material = 0;
  int32_t light = -1;
};

RLL_HD inline SurfaceHit make_surface_hit(const MeshView& m, const Hit& hit) {
  const Triangle& t = m.triangles[hit.tri];
  float b0 = 1 - hit.u - hit.v;
  SurfaceHit s;
  s.tri = hit.tri;
  s.p = m.positions[t[0]] * b0 + m.positions[t[1]] * hit.u + m.positions[t[2]] * hit.v;
  Vec3 c = m.face_cross(hit.tri);
  float len = length(c);
  s.ng = len > 0 ? c / len : Vec3(0, 0, 1);
  s.ns = s.ng;
  if (!m.normals.empty()) {
    Vec3 n = m.normals[t[0]] * b0 + m.normals[t[1]] * hit.u + m.normals[t[2]] * hit.v;
    float nl = length(n);
    if (nl > 1e-6f && std::isfinite(nl)) s.ns = dot(n, s.ng) < 0 ? -n / nl : n / nl;
  }
  if (!m.uvs.empty()) {
    const Vec2 &a = m.uvs[t[0]], &b = m.uvs[t[1]], &d = m.uvs[t[2]];
    s.uv = {a.x * b0 + b.x * hit.u + d.x * hit.v, a.y * b0 + b.y * hit.u + d.y * hit.v};
  } else {
    s.uv = {hit.u, hit.v};
  }
  s.material = m.material[hit.tri];
  s.light = m.light[hit.tri];
  return s;
}
inline SurfaceHit make_surface_hit(const Scene& scene, const Hit& hit) {
  return make_surface_hit(scene.mesh.view(), hit);
}

// Ray leaving p in direction d, offset to the side of the geometric normal that d points to.
RLL_HD inline Ray spawn_ray(const Vec3& p, const Vec3& ng, const Vec3& d, float tmax = kInf) {
  Ray r;
  r.o = p + face_forward(ng, d) * ray_epsilon(p);
  r.d = d;
  r.tmin = 0;
  r.tmax = tmax;
  return r;
}

// Shadow ray from surface point p (geometric normal ng) to point y on a light with normal ny
// (zero for a point light): both ends are pushed off their surfaces and the ray is aimed from
// one offset end to the other, so that it never hits the light itself, even at grazing angles.
RLL_HD inline Ray spawn_ray_to(const Vec3& p, const Vec3& ng, const Vec3& y, const Vec3& ny) {
  Vec3 d0 = y - p;
  Ray r;
  r.o = p + face_forward(ng, d0) * ray_epsilon(p);
  Vec3 target = length_sq(ny) > 0 ? y + face_forward(ny, -d0) * ray_epsilon(y) : y;
  Vec3 d = target - r.o;
  float len = length(d);
  r.d = d / len;
  r.tmin = 0;
  r.tmax = len * (1 - 1e-4f);
  return r;
}

// The shadow ray of a next-event sample from p (geometric normal ng) to the point `ls` drew on
// `light`: spawn_ray_to that point, or for a directional light (ls.dist infinite) a ray along
// ls.wi that ends past the scene's bounding sphere (scene_center, scene_radius), so that it tests
// the scene and never the sky dome. The renderers and the oracle's estimates trace the same.
RLL_HD inline Ray shadow_ray_to_light(const Vec3& p, const Vec3& ng, const Light& light,
                                      const LightLiSample& ls, const Vec3& scene_center,
                                      float scene_radius) {
  if (std::isfinite(ls.dist))
    return spawn_ray_to(p, ng, ls.point, light.type == LightType::Triangle ? light.n : Vec3(0));
  return spawn_ray(p, ng, ls.wi, length(p - scene_center) + 1.01f * scene_radius);
}

// A path's footprint (the learning samplers' cell size) widened by the segment of length t from
// the previous vertex, whose direction d meets the surface (geometric normal ng) at |cos| of at
// least 1e-2: R_k = R_{k-1} + t / sqrt(p_prev |cos|), with p_prev the solid-angle density of
// the direction that left the previous vertex (at the camera, 1 / pixel_angle^2).
RLL_HD inline float widen_footprint(float footprint, float t, float prev_dir_pdf, const Vec3& d,
                                    const Vec3& ng) {
  return footprint + t / std::sqrt(prev_dir_pdf * std::max(1e-2f, absdot(d, ng)));
}

inline Rgb sample_texture(const Image& texture, Vec2 uv) {
  return sample_texture(texture.texel_view(), uv);
}

// Material albedo at a hit (texture applied).
RLL_HD inline Rgb albedo_at(const SceneView& scene, const SurfaceHit& hit) {
  const MaterialData& m = scene.materials[hit.material];
  if (m.albedo_texture < 0) return m.albedo;
  return m.albedo * sample_texture(scene.textures[m.albedo_texture], hit.uv);
}

// Material roughness at a hit: the first channel of its roughness texture where it has one.
RLL_HD inline float roughness_at(const SceneView& scene, const SurfaceHit& hit) {
  const MaterialData& m = scene.materials[hit.material];
  if (m.roughness_texture < 0) return m.roughness;
  return std::max(0.0f, sample_texture(scene.textures[m.roughness_texture], hit.uv).x);
}

// Radiance the light of a hit emits towards w (pointing away): a textured light's emission at
// the hit's uv, any other light's radiance.
RLL_HD inline Rgb emitted_radiance(const SceneView& scene, const Light& light, const SurfaceHit& sh,
                                   const Vec3& w) {
  const Rgb L = emitted_radiance(light, w);
  if (!light.textured || is_black(L)) return L;
  return emission_at(scene, scene.materials[sh.material], sh.uv);
}

}  // namespace rll
