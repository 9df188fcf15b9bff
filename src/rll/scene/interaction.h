// The local geometry at a ray hit: position, normals, uv, material and light of the triangle.
#pragma once

#include "rll/core/image.h"
#include "rll/scene/hit.h"
#include "rll/scene/scene.h"

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

SurfaceHit make_surface_hit(const Scene& scene, const Hit& hit);

// Ray leaving p in direction d, offset to the side of the geometric normal that d points to.
Ray spawn_ray(const Vec3& p, const Vec3& ng, const Vec3& d, float tmax = kInf);
// Shadow ray from surface point p (geometric normal ng) to point y on a light with normal ny
// (zero for a point light): both ends are pushed off their surfaces and the ray is aimed from
// one offset end to the other, so that it never hits the light itself, even at grazing angles.
Ray spawn_ray_to(const Vec3& p, const Vec3& ng, const Vec3& y, const Vec3& ny);

// Bilinear lookup with repeat wrapping, v pointing up the image.
Rgb sample_texture(const Image& texture, Vec2 uv);

// Material albedo at a hit (texture applied).
Rgb albedo_at(const Scene& scene, const SurfaceHit& hit);
// Material roughness at a hit: the first channel of its roughness texture where it has one.
float roughness_at(const Scene& scene, const SurfaceHit& hit);

}  // namespace rll
