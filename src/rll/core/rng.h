// Counter-based random numbers: every value is a hash of (seed, pixel, sample index, dimension),
// so a render is the same whatever the thread count or tile order.
#pragma once

#include <cstdint>
#include <string>

#include "rll/core/hash.h"
#include "rll/core/math.h"
#include "rll/core/sobol.h"

namespace rll {

// PCG32 (O'Neill 2014): a small sequential generator for preprocessing, tests and the random
// walk of the layered BSDF (RLL_HD: kernels run it).
class Pcg32 {
 public:
  RLL_HD explicit Pcg32(uint64_t seed = 0x853c49e6748fea9bull,
                        uint64_t stream = 0xda3e39cb94b95bdbull) {
    m_inc = (stream << 1u) | 1u;
    m_state = 0;
    next_u32();
    m_state += seed;
    next_u32();
  }
  RLL_HD uint32_t next_u32() {
    uint64_t old = m_state;
    m_state = old * 6364136223846793005ull + m_inc;
    uint32_t xorshifted = uint32_t(((old >> 18u) ^ old) >> 27u);
    uint32_t rot = uint32_t(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31));
  }
  RLL_HD float next_float() { return u32_to_unit_float(next_u32()); }
  RLL_HD double next_double() {
    uint64_t hi = next_u32(), lo = next_u32();
    return double(((hi << 32) | lo) >> 11) * 0x1p-53;
  }
  // Uniform integer in [0, bound).
  RLL_HD uint32_t next_bounded(uint32_t bound) {
    return uint32_t((uint64_t(next_u32()) * bound) >> 32);
  }

 private:
  uint64_t m_state, m_inc;
};

// Which points a render's samples use. `Sobol`: Owen-scrambled Sobol' points, scrambled per
// pixel, so that each pixel's samples are stratified in every dimension and in the 2D pairs the
// integrator draws together; `Independent`: a hash per (pixel, sample, dimension).
enum class PointSet : uint8_t { Sobol, Independent };
const char* point_set_name(PointSet p);
// Parses "sobol" or "independent"; throws rll::Error naming `flag` otherwise.
PointSet parse_point_set(const std::string& name, const char* flag);

// Per-sample stream: the numbers of sample `sample_index` of one pixel, dimension by dimension.
// Every value is a function of (seed, pixel, sample index, dimension) only. RLL_HD: it holds the
// view of the Sobol' tables it reads, the host's or a device copy.
class SampleStream {
 public:
  SampleStream() = default;
  // With the host's Sobol' tables (built on first use by a Sobol' stream).
  SampleStream(uint64_t seed, uint64_t pixel, uint64_t sample_index,
               PointSet points = PointSet::Independent)
      : SampleStream(points == PointSet::Sobol ? host_sobol_view() : SobolView{}, seed, pixel,
                     sample_index, points) {}
  // With the tables `sobol` points to (read by Sobol' streams only).
  RLL_HD SampleStream(const SobolView& sobol, uint64_t seed, uint64_t pixel, uint64_t sample_index,
                      PointSet points)
      : m_key(mix64(mix64(seed ^ 0x9e3779b97f4a7c15ull) ^ mix64(pixel + 0x632be59bd9b4e019ull) ^
                    mix64(sample_index * 0xd1342543de82ef95ull + 1))),
        m_index(uint32_t(sample_index)),
        m_dim(0),
        m_points(points),
        m_sobol(sobol) {
    if (points == PointSet::Sobol) {
      m_scramble =
          mix64(mix64(seed ^ 0x2545f4914f6cdd1dull) ^ mix64(pixel + 0x632be59bd9b4e019ull));
      m_shuffled = sobol_shuffled_index(m_index, 0, m_scramble);
    }
  }
  RLL_HD float next() { return u32_to_unit_float(next_u32()); }
  // 53 bits, for choices among millions of items (a float has only 24): with Sobol' points the
  // 32 stratified bits are topped up with independent low bits.
  RLL_HD double next_double() {
    if (m_points == PointSet::Independent)
      return double(mix64(m_key + 0x9e3779b97f4a7c15ull * ++m_dim) >> 11) * 0x1p-53;
    const uint64_t hi = next_u32();
    const uint64_t lo = mix64(m_key ^ (0xa0761d6478bd642full * m_dim)) >> 43;  // 21 bits
    return double((hi << 21) | lo) * 0x1p-53;
  }
  RLL_HD Vec2 next2() {
    float a = next();
    return {a, next()};
  }
  RLL_HD uint32_t dimension() const { return m_dim; }
  // Continue at dimension `dim`: integrators give each decision a fixed dimension, so that a
  // decision uses the same Sobol' dimension in every sample whatever the path did before.
  RLL_HD void seek(uint32_t dim) { m_dim = dim; }
  RLL_HD PointSet points() const { return m_points; }

 private:
  [[gnu::always_inline]] RLL_HD uint32_t next_u32() {
    if (m_points == PointSet::Independent)
      return uint32_t(mix64(m_key + 0x9e3779b97f4a7c15ull * ++m_dim) >> 32);
    const uint32_t dim = m_dim++;
    if (dim < kSobolDimensions)
      return scrambled_sobol_u32_shuffled(m_sobol, m_shuffled, dim, m_scramble);
    return scrambled_sobol_u32(m_sobol, m_index, dim, m_scramble);
  }
  uint64_t m_key = 0;       // (seed, pixel, sample): independent numbers
  uint64_t m_scramble = 0;  // (seed, pixel): the pixel's Owen scramble (Sobol' points only)
  uint32_t m_index = 0;
  uint32_t m_shuffled = 0;  // m_index shuffled for the first block of Sobol' dimensions
  uint32_t m_dim = 0;
  PointSet m_points = PointSet::Independent;
  SobolView m_sobol;
};

}  // namespace rll
