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
  // Guide table (Chen's cutpoint method): m_guide[k] = first index whose cdf exceeds k/G.
  const size_t g = m_cdf.size();
  m_guide.resize(g + 1);
  size_t i = 0;
  for (size_t k = 0; k <= g; ++k) {
    const double edge = double(k) / double(g);
    while (i + 1 < m_cdf.size() && m_cdf[i] <= edge) ++i;
    m_guide[k] = uint32_t(i);
  }
}

size_t DiscreteDistribution::sample(double u, double* u_remapped) const {
  // First index whose cdf exceeds u; entries with zero pmf are never returned because their cdf
  // equals their predecessor's.
  // The guide table narrows the search to the entries between two cutpoints, usually one or two;
  // then a branchless upper bound over them (its halving steps compile to conditional moves,
  // which the branch predictor cannot miss). The result is the plain inverse-CDF index.
  const double* base = m_cdf.data();
  size_t n = m_cdf.size();
  if (!m_guide.empty()) {
    const size_t g = m_guide.size() - 1;
    const size_t k = std::min(size_t(u * double(g)), g - 1);
    base += m_guide[k];
    n = size_t(m_guide[k + 1] - m_guide[k]) + 1;
  }
  for (; n > 1;) {
    const size_t half = n / 2;
    base = base[half] <= u ? base + half : base;
    n -= half;
  }
  size_t i = std::min<size_t>(size_t(base - m_cdf.data()) + (*base <= u), m_cdf.size() - 1);
  while (m_pmf[i] == 0 && i > 0) --i;  // guard against u rounding onto a zero-width tail
  if (u_remapped) {
    double lo = i == 0 ? 0.0 : m_cdf[i - 1];
    double width = m_cdf[i] - lo;
    *u_remapped = width > 0 ? std::clamp((u - lo) / width, 0.0, 0x1.fffffffffffffp-1) : 0.0;
  }
  return i;
}

}  // namespace rll
