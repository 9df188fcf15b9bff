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
  const bool whole = screen_window == std::array<float, 4>{0, 0, 0, 0};
  m_whole = whole;
  m_x0 = (whole ? -m_aspect : screen_window[0]) * m_tan_half;
  m_x1 = (whole ? m_aspect : screen_window[1]) * m_tan_half;
  m_y0 = (whole ? -1 : screen_window[2]) * m_tan_half;
  m_y1 = (whole ? 1 : screen_window[3]) * m_tan_half;
  m_pixel_angle = whole ? 2 * m_tan_half / float(height) : (m_y1 - m_y0) / float(height);
}

}  // namespace rll
