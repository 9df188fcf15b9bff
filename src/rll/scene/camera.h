// Perspective camera: a pinhole, or a thin lens (depth of field) when lens_radius > 0.
#pragma once

#include <array>

#include "rll/core/device.h"
#include "rll/core/math.h"
#include "rll/core/sampling.h"

namespace rll {

struct Camera {
  Vec3 position{0, 0, 5};
  Vec3 target{0, 0, 0};
  Vec3 up{0, 1, 0};
  float fov = 45;  // vertical field of view, degrees
  // Thin lens: the lens's radius and the distance (along the viewing direction) of the plane in
  // focus, in scene units. 0: a pinhole.
  float lens_radius = 0;
  float focal_distance = 1e6f;
  // The part of the image plane the film sees, as {xmin, xmax, ymin, ymax} in units of
  // tan(fov / 2) (y up); all zero: the whole plane, {-aspect, aspect, -1, 1}.
  std::array<float, 4> screen_window{0, 0, 0, 0};

  // Precomputes the basis for a film of the given size; call before generate_ray.
  void setup(int width, int height);
  // Primary ray through film position (x, y) in pixels, y down (through the lens's centre).
  RLL_HD Ray generate_ray(float x, float y) const {
    Ray r;
    r.o = position;
    r.d = normalize(image_plane_point(x, y));
    return r;
  }
  // The same through the thin lens, at the point `lens` (in [0,1)^2) maps to on its disk.
  RLL_HD Ray generate_ray(float x, float y, Vec2 lens) const {
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
  RLL_HD bool has_lens() const { return lens_radius > 0; }
  // Where world point p lies on the film, in pixels (x, y; y down), as generate_ray's inverse
  // through the lens's centre; false behind the camera. ReSTIR's temporal reuse reprojects by it.
  RLL_HD bool raster(const Vec3& p, float& x, float& y) const {
    const Vec3 d = p - position;
    const float z = dot(d, m_forward);
    if (!(z > 0)) return false;
    const float sx = dot(d, m_right) / z, sy = dot(d, m_up) / z;
    x = (sx - m_x0) / (m_x1 - m_x0) * float(m_width);
    y = (m_y1 - sy) / (m_y1 - m_y0) * float(m_height);
    return true;
  }
  // Angle subtended by one pixel at the image centre (radians), for ray footprints.
  float pixel_angle() const { return m_pixel_angle; }

 private:
  // Camera-relative, at distance 1 along forward.
  RLL_HD Vec3 image_plane_point(float x, float y) const {
    if (m_whole) {  // the arithmetic of rll's pinhole camera before screen windows, bit for bit
      const float sx = (2 * x / m_width - 1) * m_tan_half * m_aspect;
      const float sy = (1 - 2 * y / m_height) * m_tan_half;
      return m_forward + m_right * sx + m_up * sy;
    }
    const float sx = m_x0 + (m_x1 - m_x0) * (x / float(m_width));
    const float sy = m_y1 - (m_y1 - m_y0) * (y / float(m_height));
    return m_forward + m_right * sx + m_up * sy;
  }
  Vec3 m_forward, m_right, m_up;
  float m_tan_half = 0, m_aspect = 1, m_pixel_angle = 0;
  float m_x0 = -1, m_x1 = 1, m_y0 = -1, m_y1 = 1;  // the screen window times tan(fov / 2)
  int m_width = 1, m_height = 1;
  bool m_whole = true;
};

}  // namespace rll
