#include "rll/core/sampling.h"

#include <algorithm>

namespace rll {

DiscreteDistribution::DiscreteDistribution(std::span<const float> weights)
    : m_pmf(weights.size()), m_cdf(weights.size()) {
  double sum = 0;
  for (float w : weights) sum += std::max(0.0f, w);
  m_total = sum;
  if (sum <= 0) return;
  double acc = 0;
  for (size_t i = 0; i < weights.size(); ++i) {
    double w = std::max(0.0f, weights[i]);
    m_pmf[i] = float(w / sum);
    acc += w / sum;
    m_cdf[i] = acc;
  }
  m_cdf.back() = 1.0;
}

size_t DiscreteDistribution::sample(double u, double* u_remapped) const {
  // First index whose cdf exceeds u; entries with zero pmf are never returned because their cdf
  // equals their predecessor's.
  auto it = std::upper_bound(m_cdf.begin(), m_cdf.end(), u);
  size_t i = std::min<size_t>(it - m_cdf.begin(), m_cdf.size() - 1);
  while (m_pmf[i] == 0 && i > 0) --i;  // guard against u rounding onto a zero-width tail
  if (u_remapped) {
    double lo = i == 0 ? 0.0 : m_cdf[i - 1];
    double width = m_cdf[i] - lo;
    *u_remapped = width > 0 ? std::clamp((u - lo) / width, 0.0, 0x1.fffffffffffffp-1) : 0.0;
  }
  return i;
}

}  // namespace rll
