// Ray queries against the scene's triangles: the renderer's only view of the ray tracer.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "rll/core/math.h"
#include "rll/scene/hit.h"
#include "rll/scene/mesh.h"

namespace rll {

// Rays recorded by an Accel for replay (benchmarks): not thread-safe, record with one thread.
struct RayLog {
  std::vector<Ray> closest, shadow;
};

class Accel {
 public:
  explicit Accel(const Mesh& mesh);
  ~Accel();
  Accel(const Accel&) = delete;
  Accel& operator=(const Accel&) = delete;

  // Closest hit in (ray.tmin, ray.tmax); false if none.
  bool intersect(const Ray& ray, Hit& hit) const;
  // True if anything lies in (ray.tmin, ray.tmax).
  bool occluded(const Ray& ray) const;
  // Re-reads vertex positions (same topology) and refits the hierarchy.
  void update_vertices(const Mesh& mesh);
  // Records every ray traced while set (nullptr stops); for the ray-rate benchmark.
  void set_log(RayLog* log) { m_log = log; }

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
  RayLog* m_log = nullptr;
};

}  // namespace rll
