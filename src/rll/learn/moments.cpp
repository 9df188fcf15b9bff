#include "rll/learn/moments.h"

#include <algorithm>

#include "rll/scene/scene.h"

namespace rll {

double reward_scale(const Scene& scene) {
  double s = 0;
  for (const auto& l : scene.lights) {
    double lum = luminance(l.radiance);
    switch (l.type) {
      case LightType::Triangle:
        s = std::max(s, kPi * lum * (l.two_sided ? 2 : 1));
        break;
      case LightType::Point:
      case LightType::Spot:
      case LightType::Goniometric:
      case LightType::Projection:
        s = std::max(s, 4 * kPi * lum / double(scene.radius * scene.radius));
        break;
      case LightType::Directional:
        s = std::max(s, kPi * lum);
        break;
    }
  }
  return s > 0 ? s : 1.0;
}

}  // namespace rll
