// Pinhole perspective camera.
#pragma once

#include "rll/core/math.h"

namespace rll {

struct Camera {
  Vec3 position{0, 0, 5};
  Vec3 target{0, 0, 0};
  Vec3 up{0, 1, 0};
  float fov = 45;  // vertical field of view, degrees

  // Precomputes the basis for a film of the given size; call before generate_ray.
  void setup(int width, int height);
  // Primary ray through film position (x, y) in pixels, y down.
  Ray generate_ray(float x, float y) const;
  // Angle subtended by one pixel at the image centre (radians), for ray footprints.
  float pixel_angle() const { return m_pixel_angle; }

 private:
  Vec3 m_forward, m_right, m_up;
  float m_tan_half = 0, m_aspect = 1, m_pixel_angle = 0;
  int m_width = 1, m_height = 1;
};

}  // namespace rll
