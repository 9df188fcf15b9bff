#include "rll/scene/camera.h"

#include "rll/core/sampling.h"

namespace rll {

void Camera::setup(int width, int height) {
  m_width = width;
  m_height = height;
  m_forward = normalize(target - position);
  m_right = normalize(cross(m_forward, up));
  m_up = cross(m_right, m_forward);
  m_tan_half = std::tan(radians(fov) * 0.5f);
  m_aspect = float(width) / float(height);
  const bool whole = screen_window == std::array<float, 4>{0, 0, 0, 0};
  m_whole = whole;
  m_x0 = (whole ? -m_aspect : screen_window[0]) * m_tan_half;
  m_x1 = (whole ? m_aspect : screen_window[1]) * m_tan_half;
  m_y0 = (whole ? -1 : screen_window[2]) * m_tan_half;
  m_y1 = (whole ? 1 : screen_window[3]) * m_tan_half;
  m_pixel_angle = whole ? 2 * m_tan_half / float(height) : (m_y1 - m_y0) / float(height);
}

Vec3 Camera::image_plane_point(float x, float y) const {
  if (m_whole) {  // the arithmetic of rll's pinhole camera before screen windows, bit for bit
    const float sx = (2 * x / m_width - 1) * m_tan_half * m_aspect;
    const float sy = (1 - 2 * y / m_height) * m_tan_half;
    return m_forward + m_right * sx + m_up * sy;
  }
  const float sx = m_x0 + (m_x1 - m_x0) * (x / float(m_width));
  const float sy = m_y1 - (m_y1 - m_y0) * (y / float(m_height));
  return m_forward + m_right * sx + m_up * sy;
}

Ray Camera::generate_ray(float x, float y) const {
  Ray r;
  r.o = position;
  r.d = normalize(image_plane_point(x, y));
  return r;
}

Ray Camera::generate_ray(float x, float y, Vec2 lens) const {
  if (!(lens_radius > 0)) return generate_ray(x, y);
  // The pinhole ray meets the plane in focus (distance focal_distance along forward) at
  // `focus`; the thin-lens ray leaves a point of the lens's disk towards it.
  const Vec3 focus = image_plane_point(x, y) * focal_distance;
  const Vec2 d = sample_uniform_disk_concentric(lens);
  const Vec3 o = m_right * (d.x * lens_radius) + m_up * (d.y * lens_radius);
  Ray r;
  r.o = position + o;
  r.d = normalize(focus - o);
  return r;
}

}  // namespace rll
