// Counter-based random numbers: every value is a hash of (seed, pixel, sample index, dimension),
// so a render is the same whatever the thread count or tile order.
#pragma once

#include <cstdint>

#include "rll/core/math.h"

namespace rll {

// 64-bit finaliser of splitmix64: a bijective avalanche mix.
inline uint64_t mix64(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

inline float u32_to_unit_float(uint32_t v) {
  // 24 high bits into [0,1): exactly representable, never 1.
  return float(v >> 8) * 0x1p-24f;
}

// PCG32 (O'Neill 2014): a small sequential generator for preprocessing and tests.
class Pcg32 {
 public:
  explicit Pcg32(uint64_t seed = 0x853c49e6748fea9bull, uint64_t stream = 0xda3e39cb94b95bdbull) {
    m_inc = (stream << 1u) | 1u;
    m_state = 0;
    next_u32();
    m_state += seed;
    next_u32();
  }
  uint32_t next_u32() {
    uint64_t old = m_state;
    m_state = old * 6364136223846793005ull + m_inc;
    uint32_t xorshifted = uint32_t(((old >> 18u) ^ old) >> 27u);
    uint32_t rot = uint32_t(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31));
  }
  float next_float() { return u32_to_unit_float(next_u32()); }
  double next_double() {
    uint64_t hi = next_u32(), lo = next_u32();
    return double(((hi << 32) | lo) >> 11) * 0x1p-53;
  }
  // Uniform integer in [0, bound).
  uint32_t next_bounded(uint32_t bound) {
    return uint32_t((uint64_t(next_u32()) * bound) >> 32);
  }

 private:
  uint64_t m_state, m_inc;
};

// Per-sample stream: a key from (seed, pixel, sample index) and a dimension counter.
class SampleStream {
 public:
  SampleStream() = default;
  SampleStream(uint64_t seed, uint64_t pixel, uint64_t sample_index)
      : m_key(mix64(mix64(seed ^ 0x9e3779b97f4a7c15ull) ^ mix64(pixel + 0x632be59bd9b4e019ull) ^
                    mix64(sample_index * 0xd1342543de82ef95ull + 1))),
        m_dim(0) {}
  float next() { return u32_to_unit_float(uint32_t(mix64(m_key + 0x9e3779b97f4a7c15ull * ++m_dim) >> 32)); }
  // 53 random bits, for choices among millions of items (a float has only 24).
  double next_double() {
    return double(mix64(m_key + 0x9e3779b97f4a7c15ull * ++m_dim) >> 11) * 0x1p-53;
  }
  Vec2 next2() {
    float a = next();
    return {a, next()};
  }
  uint32_t dimension() const { return m_dim; }

 private:
  uint64_t m_key = 0;
  uint32_t m_dim = 0;
};

}  // namespace rll
