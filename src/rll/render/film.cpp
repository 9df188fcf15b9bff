#include "rll/render/film.h"

#include <algorithm>
#include <cmath>

#include "rll/core/error.h"
#include "rll/core/memory_budget.h"

namespace rll {

void check_film_memory(int64_t width, int64_t height, double bytes_per_pixel,
                       const std::string& source, const std::string& kept) {
  const double bytes = double(width) * double(height) * bytes_per_pixel;
  if (bytes <= double(memory_budget_bytes())) return;
  // The largest film of this aspect ratio that fits, as a suggestion.
  const double scale = std::sqrt(double(memory_budget_bytes()) / bytes);
  const int64_t w = std::max<int64_t>(1, int64_t(double(width) * scale)),
                h = std::max<int64_t>(1, int64_t(double(height) * scale));
  fail(
      "a film of {}x{} pixels ({}) needs {} ({:.0f} bytes a pixel: {}), more than {}: render it "
      "smaller with --res WIDTHxHEIGHT (at most about {}x{} here){}",
      width, height, source, format_bytes(bytes), bytes_per_pixel, kept, memory_budget_phrase(), w,
      h,
      source.rfind("--res", 0) == 0 ? "" : ", or lower the resolution the scene's film asks for");
}

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
