// A ray's closest hit on the scene's mesh, as every tracer reports it (Embree on the CPU, rll's
// own BVH on either device).
#pragma once

#include <cstdint>

#include "rll/core/math.h"

namespace rll {

struct Hit {
  float t = kInf;
  uint32_t tri = ~0u;
  float u = 0, v = 0;  // barycentrics of vertices 1 and 2: p = (1-u-v) p0 + u p1 + v p2
};

}  // namespace rll
