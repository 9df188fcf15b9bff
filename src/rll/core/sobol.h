// Owen-scrambled Sobol' points: the low-discrepancy sample values a render draws per pixel.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "rll/core/device.h"
#include "rll/core/hash.h"

namespace rll {

// Dimensions with their own Joe & Kuo (2008) direction numbers; later ones are padded.
inline constexpr uint32_t kSobolDimensions = 1024;

// The byte tables of the Sobol' points as kernels read them (DESIGN 6): per dimension, four tables
// of 256 entries, the index's bytes' contributions to the point with the point's bits reversed
// (the scramble works on reversed values, so that is what it reads). Owns nothing.
struct SobolView {
  const uint32_t* tables = nullptr;  // kSobolDimensions * 1024 entries
};

// The owner of a set of byte tables (4 MiB), built on the host from Joe & Kuo's direction numbers;
// a device renderer copies them to the device and points a SobolView there.
class SobolTables {
 public:
  SobolTables();
  SobolView view() const { return {m_tables.data()}; }
  size_t size() const { return m_tables.size(); }

 private:
  std::vector<uint32_t> m_tables;
};

// The host's tables, built once on first use.
const SobolTables& host_sobol_tables();
inline SobolView host_sobol_view() {
  return host_sobol_tables().view();
}

// Coordinate `dim` (< kSobolDimensions) of Sobol' point `index` with its 32 bits reversed.
RLL_HD inline uint32_t sobol_u32_reversed(const SobolView& sobol, uint32_t index, uint32_t dim) {
  const uint32_t* t = sobol.tables + size_t(dim) * 1024;
  return t[index & 255] ^ t[256 + ((index >> 8) & 255)] ^ t[512 + ((index >> 16) & 255)] ^
         t[768 + (index >> 24)];
}

// Coordinate `dim` (< kSobolDimensions) of Sobol' point `index`, as 32-bit fixed point
// (unscrambled).
uint32_t sobol_u32(uint32_t index, uint32_t dim);
// The same from the generator matrix column by column (tests check the tables against it).
uint32_t sobol_u32_reference(uint32_t index, uint32_t dim);

namespace detail {

// Reverses the order of the 32 bits of `v`.
RLL_HD inline uint32_t reverse_bits(uint32_t v) {
#if RLL_DEVICE_CODE
  return __brev(v);
#else
#if defined(__has_builtin)
#if __has_builtin(__builtin_bitreverse32)
  return __builtin_bitreverse32(v);
#endif
#endif
  v = ((v >> 1) & 0x55555555u) | ((v & 0x55555555u) << 1);
  v = ((v >> 2) & 0x33333333u) | ((v & 0x33333333u) << 2);
  v = ((v >> 4) & 0x0f0f0f0fu) | ((v & 0x0f0f0f0fu) << 4);
  return __builtin_bswap32(v);
#endif
}

// Laine–Karras style permutation keyed by a well-mixed 64-bit `key`: every step (add, multiply
// by an odd number, xor with an even multiple) is a bijection in which bit k of the result
// depends only on bits 0..k of its input, so applied to bit-reversed values it is a nested
// uniform scramble. Burley (2020)'s version (an add then four fixed xor-multiplies) correlates
// the scrambles of values one bit apart (z = 110 on 50,000 seeds per bit pair); multiplying by a
// key-dependent odd number first removes that (worst z = 3.7 over ~1,400 bit pairs).
RLL_HD inline uint32_t owen_permute_reversed(uint32_t x, uint64_t key) {
  x += uint32_t(key);
  x *= uint32_t(key >> 32) | 1u;
  x ^= x * 0x6c50b47cu;
  x ^= x * 0xb82f1e52u;
  return x;
}

// The nested uniform scramble of `v` keyed by a well-mixed 64-bit `key`.
RLL_HD inline uint32_t owen_scramble_keyed(uint32_t v, uint64_t key) {
  return reverse_bits(owen_permute_reversed(reverse_bits(v), key));
}

}  // namespace detail

// Nested uniform (Owen) scramble of a 32-bit fixed-point coordinate, hash-based (Laine–Karras style
// permutation applied to the bit-reversed value, as in Burley 2020 "Practical hash-based Owen
// scrambling"), keyed by `seed`. A bijection on uint32 for every seed that preserves (t,m,s)-nets.
RLL_HD inline uint32_t owen_scramble(uint32_t v, uint32_t seed) {
  // Hashed here so that nearby seeds (0, 1, 2...) give unrelated scrambles.
  return detail::owen_scramble_keyed(v, mix64(seed ^ 0x6a09e667f3bcc909ull));
}

// The index shuffle of a block of kSobolDimensions dimensions (see scrambled_sobol_u32).
RLL_HD inline uint32_t sobol_shuffled_index(uint32_t index, uint32_t block, uint64_t seed) {
  return detail::owen_scramble_keyed(index, mix64(seed ^ (0xbb67ae8584caa73bull * block)));
}
// Coordinate `dim` of the point whose index was already shuffled for dim's block.
RLL_HD inline uint32_t scrambled_sobol_u32_shuffled(const SobolView& sobol, uint32_t shuffled_index,
                                                    uint32_t dim, uint64_t seed) {
  const uint64_t key = mix64(seed + 0x9e3779b97f4a7c15ull * (uint64_t(dim) + 1));
  return detail::reverse_bits(detail::owen_permute_reversed(
      sobol_u32_reversed(sobol, shuffled_index, dim % kSobolDimensions), key));
}

// The point generator the renderer uses: coordinate `dim` (any value) of point `index` of an
// Owen-scrambled Sobol' sequence, scrambled by `seed` (a hash of pixel and render seed) with an
// independent scramble per dimension. Dimensions past the table are padded (Burley 2020): dimension
// `dim` reuses table dimension dim % kSobolDimensions, and each block of kSobolDimensions
// dimensions shuffles the index by its own nested uniform scramble keyed by (seed, block), so
// that each padded dimension is still stratified on its own and a block is a Sobol' sequence.
RLL_HD inline uint32_t scrambled_sobol_u32(const SobolView& sobol, uint32_t index, uint32_t dim,
                                           uint64_t seed) {
  // The shuffle is shared by the whole block, unlike the value scramble, so that the block's
  // dimensions keep their joint stratification (2D pairs in particular); each block is shuffled
  // independently.
  return scrambled_sobol_u32_shuffled(
      sobol, sobol_shuffled_index(index, dim / kSobolDimensions, seed), dim, seed);
}
// The same with the host's tables.
inline uint32_t scrambled_sobol_u32(uint32_t index, uint32_t dim, uint64_t seed) {
  return scrambled_sobol_u32(host_sobol_view(), index, dim, seed);
}

// A 32-bit fixed-point coordinate as a double in [0,1): exact.
RLL_HD inline double sobol_to_double(uint32_t v) {
  return double(v) * 0x1p-32;
}

}  // namespace rll
