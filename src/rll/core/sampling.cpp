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

}  // namespace rll
