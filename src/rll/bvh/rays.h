// Batches of rays for testing and timing tracers: the same rays go to Embree, rll's BVH on the
// CPU and the GPU kernels. Each ray depends only on the seed and its index.
#pragma once

#include <cstdint>
#include <vector>

#include "rll/scene/hit.h"
#include "rll/scene/scene.h"

namespace rll {

// n rays of four kinds, a quarter each, in this order: origins uniform in the scene's bounds
// grown by a tenth of their diagonal, with uniform directions; origins on random triangles
// (tmin = ray_epsilon), uniform directions; camera rays through random film positions; shadow
// segments between two random surface points (finite tmax, short of the second point).
std::vector<Ray> test_rays(const Scene& scene, size_t n, uint64_t seed);

// One camera ray per pixel of a width x height film (through a random point of the pixel).
std::vector<Ray> camera_rays(const Scene& scene, int width, int height, uint64_t seed);

// From each hit of rays[i] (hits[i].tri valid), a cosine-distributed ray around the geometric
// normal on the side the ray came from; misses give no ray.
std::vector<Ray> bounce_rays(const Mesh& mesh, const std::vector<Ray>& rays,
                             const std::vector<Hit>& hits, uint64_t seed);

// From each hit, a shadow ray to a uniform point on a uniformly chosen emissive
// triangle (any triangle where the scene has none), stopping short of it; misses give no ray.
std::vector<Ray> shadow_rays(const Scene& scene, const std::vector<Hit>& hits, uint64_t seed);

// Whether two tracers found the same hit for a ray (a miss: tri == ~0u): both missed, or hit the
// same triangle at the same distance up to float rounding or at the same point (barycentrics
// within 1e-2: t is ill-conditioned for a ray grazing the triangle's plane, as rays leaving a
// surface do, and two tracers' t differ by up to 2% there, while barycentrics on a sky dome's
// large triangles differ by 1e-3 at equal t), or hit different triangles at the same distance
// (a tie, a ray through a shared edge).
bool hits_agree(const Hit& a, const Hit& b);

// The point a hit names on the mesh.
Vec3 hit_point(const Mesh& mesh, const Hit& hit);

}  // namespace rll
