#include "rll/core/rng.h"

#include "rll/core/error.h"

namespace rll {

const char* point_set_name(PointSet p) {
  return p == PointSet::Sobol ? "sobol" : "independent";
}

PointSet parse_point_set(const std::string& name, const char* flag) {
  if (name == "sobol") return PointSet::Sobol;
  if (name == "independent") return PointSet::Independent;
  fail("{} '{}': expected sobol or independent", flag, name);
}

}  // namespace rll
