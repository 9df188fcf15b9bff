#include "rll/scene/camera.h"

namespace rll {

void Camera::setup(int width, int height) {
  m_width = width;
  m_height = height;
  m_forward = normalize(target - position);
  m_right = normalize(cross(m_forward, up));
  m_up = cross(m_right, m_forward);
  m_tan_half = std::tan(radians(fov) * 0.5f);
  m_aspect = float(width) / float(height);
  m_pixel_angle = 2 * m_tan_half / float(height);
}

Ray Camera::generate_ray(float x, float y) const {
  float sx = (2 * x / m_width - 1) * m_tan_half * m_aspect;
  float sy = (1 - 2 * y / m_height) * m_tan_half;
  Ray r;
  r.o = position;
  r.d = normalize(m_forward + m_right * sx + m_up * sy);
  return r;
}

}  // namespace rll
