// The wavefront's two tracing calls, each one narrow function, so that a GPU version can call
// rll's own BVH (bvh/traverse.h) in their place; on the CPU they call Embree through Accel.
#pragma once

#include "rll/accel/accel.h"

namespace rll {

// Closest hit along `ray`; false if none.
inline bool trace_closest(const Accel& accel, const Ray& ray, Hit& hit) {
  return accel.intersect(ray, hit);
}

// True if anything lies along the shadow ray.
inline bool trace_shadow(const Accel& accel, const Ray& ray) {
  return accel.occluded(ray);
}

}  // namespace rll
