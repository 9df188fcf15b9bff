// Bit mixing and random bits as floats: shared by the random streams (rng.h) and the Sobol'
// scrambles (sobol.h); and a streaming hash of values (scene fingerprints, file checksums).
#pragma once

#include <bit>
#include <cstdint>
#include <cstring>
#include <type_traits>
#include <vector>

#include "rll/core/math.h"

namespace rll {

// 64-bit finaliser of splitmix64: a bijective avalanche mix.
RLL_HD inline uint64_t mix64(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

RLL_HD inline float u32_to_unit_float(uint32_t v) {
  // 24 high bits into [0,1): exactly representable, never 1.
  return float(v >> 8) * 0x1p-24f;
}

// A 64-bit streaming hash over 8-byte words (splitmix64 finaliser per word), not cryptographic:
// it only has to tell scenes apart and catch damaged files.
class Hasher {
 public:
  void bytes(const void* data, size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    word(n);
    for (; n >= 8; n -= 8, p += 8) {
      uint64_t w;
      std::memcpy(&w, p, 8);
      word(w);
    }
    if (n > 0) {
      uint64_t w = 0;
      std::memcpy(&w, p, n);
      word(w);
    }
  }
  void word(uint64_t w) { m_h = mix64(m_h ^ (w + 0x9e3779b97f4a7c15ull)); }
  void add(float f) { word(std::bit_cast<uint32_t>(f)); }
  void add(const Vec3& v) {
    add(v.x);
    add(v.y);
    add(v.z);
  }
  void add(int64_t i) { word(uint64_t(i)); }
  template <typename T>
  void vector(const std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    bytes(v.data(), v.size() * sizeof(T));
  }
  uint64_t value() const { return m_h; }

 private:
  uint64_t m_h = 0xcbf29ce484222325ull;
};

}  // namespace rll
