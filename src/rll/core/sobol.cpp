// Sobol' generator matrices from Joe & Kuo's direction numbers.
#include "rll/core/sobol.h"

#include <bit>
#include <boost/random/detail/sobol_table.hpp>
#include <cassert>
#include <memory>
#include <vector>

namespace rll {
namespace {

using JoeKuo = boost::random::detail::qrng_tables::sobol;
static_assert(JoeKuo::max_dimension >= kSobolDimensions, "Boost's table is too short");

// Column k of dimension d is the 32-bit direction number v_k, the value bit k of the index XORs in.
struct SobolMatrices {
  uint32_t columns[kSobolDimensions][32];

  SobolMatrices() {
    // Dimension 0 is van der Corput's sequence: the index's bits reversed.
    for (uint32_t k = 0; k < 32; ++k) columns[0][k] = 1u << (31 - k);
    for (uint32_t d = 1; d < kSobolDimensions; ++d) {
      // Primitive polynomial x^s + a_1 x^(s-1) + ... + a_(s-1) x + 1, coefficients as bits.
      const uint32_t poly = JoeKuo::polynomial(d - 1);
      const uint32_t s = uint32_t(std::bit_width(poly)) - 1;
      uint32_t* v = columns[d];
      // The table's m_k (odd, below 2^k) as fixed point: v_k = m_k / 2^k, k counted from 1.
      for (uint32_t k = 0; k < s; ++k) v[k] = uint32_t(JoeKuo::minit(d - 1, k)) << (31 - k);
      // Bratley & Fox's recurrence m_k = 2 a_1 m_(k-1) ^ ... ^ 2^(s-1) a_(s-1) m_(k-s+1)
      // ^ 2^s m_(k-s) ^ m_(k-s), divided by 2^k: the shifts become plain terms, and the last one
      // a shift right by s. Exact in 32 bits, as every v_k up to k = 32 is.
      for (uint32_t k = s; k < 32; ++k) {
        uint32_t x = v[k - s] ^ (v[k - s] >> s);
        for (uint32_t i = 1; i < s; ++i)
          if ((poly >> (s - i)) & 1u) x ^= v[k - i];
        v[k] = x;
      }
    }
  }
};

const SobolMatrices& sobol_matrices() {
  static const auto matrices = std::make_unique<SobolMatrices>();  // 128 KiB, built on first use
  return *matrices;
}

}  // namespace

// Per dimension and byte of the index, the XOR of the columns of that byte's set bits, for all
// 256 byte values: a point is then four table reads, whatever the index (a shuffled index has
// about 16 set bits, which the bit-by-bit loop paid for one by one).
SobolTables::SobolTables() : m_tables(size_t(kSobolDimensions) * 4 * 256) {
  const SobolMatrices& matrices = sobol_matrices();
  std::vector<uint32_t>& t = m_tables;
  for (uint32_t d = 0; d < kSobolDimensions; ++d)
    for (uint32_t b = 0; b < 4; ++b) {
      uint32_t* row = &t[(size_t(d) * 4 + b) * 256];
      row[0] = 0;
      for (uint32_t x = 1; x < 256; ++x)
        row[x] = row[x & (x - 1)] ^
                 detail::reverse_bits(matrices.columns[d][8 * b + std::countr_zero(x)]);
    }
}

const SobolTables& host_sobol_tables() {
  static const SobolTables tables;  // 4 MiB, built on first use
  return tables;
}

uint32_t sobol_u32(uint32_t index, uint32_t dim) {
  assert(dim < kSobolDimensions);
  return detail::reverse_bits(sobol_u32_reversed(host_sobol_view(), index, dim));
}

uint32_t sobol_u32_reference(uint32_t index, uint32_t dim) {
  assert(dim < kSobolDimensions);
  const uint32_t* v = sobol_matrices().columns[dim];
  uint32_t x = 0;
  for (; index != 0; index &= index - 1) x ^= v[std::countr_zero(index)];
  return x;
}

}  // namespace rll
