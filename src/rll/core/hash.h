// Bit mixing and random bits as floats: shared by the random streams (rng.h) and the Sobol'
// scrambles (sobol.h).
#pragma once

#include <cstdint>

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

}  // namespace rll
