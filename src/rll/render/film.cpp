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
}

}  // namespace rll
