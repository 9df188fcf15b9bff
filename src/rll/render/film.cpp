#include "rll/render/film.h"

#include <algorithm>

namespace rll {

uint32_t Film::min_count() const {
  return m_count.empty() ? 0 : *std::min_element(m_count.begin(), m_count.end());
}

Image Film::resolve() const {
  Image img(m_w, m_h);
  for (size_t i = 0; i < m_count.size(); ++i) {
    if (!m_count[i]) continue;
    double inv = 1.0 / m_count[i];
    img[i] = Rgb(float(m_sum[3 * i] * inv), float(m_sum[3 * i + 1] * inv), float(m_sum[3 * i + 2] * inv));
  }
  return img;
}

void Film::clear() {
  std::fill(m_sum.begin(), m_sum.end(), 0.0);
  std::fill(m_count.begin(), m_count.end(), 0u);
  if (camera_vertex()) track_camera_vertex();
}

void Film::track_camera_vertex() {
  const size_t n = m_count.size();
  m_vertex.cell.assign(n, CameraVertexSample::kNone);
  m_vertex.light_pmf.assign(n, 0.0);
  m_vertex.sampled.assign(n, 0);
  m_vertex.shadow.assign(n, 0);
  m_vertex.visible.assign(n, 0);
}

void Film::add_camera_vertex(int x, int y, const CameraVertexSample& v) {
  const size_t i = size_t(y) * m_w + x;
  if (v.cell != CameraVertexSample::kNone) m_vertex.cell[i] = v.cell;
  if (v.sampled) {
    m_vertex.light_pmf[i] += v.light_pmf;
    ++m_vertex.sampled[i];
  }
  m_vertex.shadow[i] += v.shadow;
  m_vertex.visible[i] += v.visible;
}

}  // namespace rll
