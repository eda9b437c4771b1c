#pragma once
// Four doubles in one AVX2 register (GCC vector extension) and the few operations the MLS kernels use
// on them: loads and stores of partial blocks, fused multiply-add, lane sums and lane compression.
#include <cstdint>
#include <cstring>

#ifdef __AVX__
#include <immintrin.h>
#endif

#include "core/types.hpp"

namespace lamina::mls::simd {

using Real4 = Real __attribute__((vector_size(32)));  // four doubles (one AVX2 register)

// Builds without AVX (the sanitizer build, -march=x86-64-v2) warn that these helpers return 32-byte
// vectors by value, an ABI that differs from AVX builds; they are inline, for the MLS kernels only.
#pragma GCC diagnostic ignored "-Wpsabi"

/// Four consecutive values from p (unaligned).
inline Real4 load4(const Real* p) {
#ifdef __AVX__
  const __m256d v = _mm256_loadu_pd(p);
  return reinterpret_cast<const Real4&>(v);
#else
  Real4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
#endif
}

/// Stores the four values of v at p (unaligned). (With AVX one 32-byte store: GCC lowered the memcpy of a
/// vector from a stack copy into two 16-byte moves in a loop.)
inline void store4(Real* p, const Real4& v) {
#ifdef __AVX__
  _mm256_storeu_pd(p, reinterpret_cast<const __m256d&>(v));
#else
  std::memcpy(p, &v, sizeof v);
#endif
}

#ifdef __AVX__
/// Lane masks of the first 0..4 lanes (for the masked loads and stores of a partial group).
alignas(32) inline constexpr std::int64_t first_lanes_mask[5][4] = {
    {0, 0, 0, 0}, {-1, 0, 0, 0}, {-1, -1, 0, 0}, {-1, -1, -1, 0}, {-1, -1, -1, -1}};
inline __m256i first_lanes(Index lanes) { return _mm256_load_si256(reinterpret_cast<const __m256i*>(first_lanes_mask[lanes])); }
#endif

/// The first `lanes` (1..4) values from p, the other lanes zero (nothing past them is read).
inline Real4 load4(const Real* p, Index lanes) {
  if (lanes == 4) return load4(p);
#ifdef __AVX__
  const __m256d v = _mm256_maskload_pd(p, first_lanes(lanes));
  return reinterpret_cast<const Real4&>(v);
#else
  Real4 v = {0.0, 0.0, 0.0, 0.0};
  for (Index l = 0; l < lanes; ++l) v[l] = p[l];
  return v;
#endif
}

/// Stores the first `lanes` (1..4) values of v at p.
inline void store4(Real* p, const Real4& v, Index lanes) {
  if (lanes == 4) {
    store4(p, v);
    return;
  }
#ifdef __AVX__
  _mm256_maskstore_pd(p, first_lanes(lanes), reinterpret_cast<const __m256d&>(v));
#else
  for (Index l = 0; l < lanes; ++l) p[l] = v[l];
#endif
}

/// Stores a0 b0 c0 a1 b1 c1 a2 b2 c2 a3 b3 c3 at p (four 3-vectors from three vectors of components).
inline void store_interleaved3(Real* p, const Real4& a, const Real4& b, const Real4& c) {
#ifdef __AVX__
  const __m256d x = reinterpret_cast<const __m256d&>(a), y = reinterpret_cast<const __m256d&>(b),
                z = reinterpret_cast<const __m256d&>(c);
  const __m256d even = _mm256_unpacklo_pd(x, y);     // a0 b0 a2 b2
  const __m256d odd = _mm256_unpackhi_pd(x, y);      // a1 b1 a3 b3
  const __m256d c_a = _mm256_shuffle_pd(z, odd, 0);  // c0 a1 c2 a3
  const __m256d b_c = _mm256_shuffle_pd(odd, z, 15); // b1 c1 b3 c3
  _mm256_storeu_pd(p, _mm256_permute2f128_pd(even, c_a, 0x20));  // a0 b0 c0 a1
  _mm256_storeu_pd(p + 4, _mm256_blend_pd(b_c, even, 0b1100));    // b1 c1 a2 b2
  _mm256_storeu_pd(p + 8, _mm256_permute2f128_pd(c_a, b_c, 0x31)); // c2 a3 b3 c3
#else
  for (int l = 0; l < 4; ++l) {
    p[3 * l] = a[l];
    p[3 * l + 1] = b[l];
    p[3 * l + 2] = c[l];
  }
#endif
}

/// Calls block(j, lanes) for j = 0, 4, 8, ... < n: lanes = 4, and n - j for the last, partial group.
template <class Block>
inline void for_each_group_of_four(Index n, Block&& block) {
  Index j = 0;
  for (; j + 4 <= n; j += 4) block(j, Index{4});
  if (j < n) block(j, n - j);
}

/// Calls block(lanes) for the entries j .. j + 3 (j = 0, 4, 8, ... < n) of every array in `columns`,
/// lanes[c] holding array c's four values; in the last partial block (n % 4 entries) the lanes past n
/// are zero, so sums over the lanes need no tail loop.
template <int Columns, class Block>
void for_each_block_of_four(const Real* const (&columns)[Columns], Index n, Block&& block) {
  Index j = 0;
  for (; j + 4 <= n; j += 4) {
    Real4 lanes[Columns];
    for (int c = 0; c < Columns; ++c) lanes[c] = load4(columns[c] + j);
    block(lanes);
  }
  if (j < n) {
    Real4 lanes[Columns];
    for (int c = 0; c < Columns; ++c) lanes[c] = load4(columns[c] + j, n - j);
    block(lanes);
  }
}

inline Real sum_lanes(const Real4& v) { return (v[0] + v[1]) + (v[2] + v[3]); }

/// out[k] = sum_lanes(v[k]) for k < Count (the same sums, bitwise), four vectors at a time.
template <int Count>
inline void sum_lanes(const Real4* v, Real* out) {
  int k = 0;
#ifdef __AVX__
  for (; k + 4 <= Count; k += 4) {
    const __m256d a = reinterpret_cast<const __m256d&>(v[k]), b = reinterpret_cast<const __m256d&>(v[k + 1]);
    const __m256d c = reinterpret_cast<const __m256d&>(v[k + 2]), d = reinterpret_cast<const __m256d&>(v[k + 3]);
    const __m256d ab = _mm256_hadd_pd(a, b);  // a0+a1 b0+b1 a2+a3 b2+b3
    const __m256d cd = _mm256_hadd_pd(c, d);  // c0+c1 d0+d1 c2+c3 d2+d3
    const __m256d sums = _mm256_add_pd(_mm256_permute2f128_pd(ab, cd, 0x21), _mm256_blend_pd(ab, cd, 0b1100));
    _mm256_storeu_pd(out + k, sums);
  }
#endif
  for (; k < Count; ++k) out[k] = sum_lanes(v[k]);
}

/// a * b + c, fused where the CPU has FMA (x86-64-v3). The build turns off the compiler's own
/// contraction (CMakeLists.txt: it changed an MPM case's rounding-sensitive path); these sums of
/// products are only rounded better by it.
inline Real4 multiply_add(const Real4& a, const Real4& b, const Real4& c) {
#ifdef __FMA__
  return __builtin_ia32_vfmaddpd256(a, b, c);
#else
  return a * b + c;
#endif
}
inline Real4 multiply_add(const Real4& a, Real b, const Real4& c) { return multiply_add(a, Real4{b, b, b, b}, c); }

using Mask4 = std::int64_t __attribute__((vector_size(32)));  // lane masks of Real4 comparisons (0 / -1)

#ifdef __AVX2__
/// Lane permutations that move the kept lanes of a four-double vector (a 4-bit mask) to its front, in
/// order, as indices of 32-bit halves for _mm256_permutevar8x32_epi32 (the other lanes: don't care).
struct CompressLanes {
  alignas(32) std::int32_t index[16][8];
  constexpr CompressLanes() : index{} {
    for (int mask = 0; mask < 16; ++mask) {
      int out = 0;
      for (int lane = 0; lane < 4; ++lane)
        if (mask & (1 << lane)) {
          index[mask][2 * out] = 2 * lane;
          index[mask][2 * out + 1] = 2 * lane + 1;
          ++out;
        }
      for (; out < 4; ++out) {
        index[mask][2 * out] = 0;
        index[mask][2 * out + 1] = 1;
      }
    }
  }
};
constexpr CompressLanes compress_lanes_table{};
const __m256i* const compress_lanes = reinterpret_cast<const __m256i*>(compress_lanes_table.index);

/// The lanes of v picked by a compress_lanes permutation.
inline __m256d compress(const Real4& v, __m256i permutation) {
  return _mm256_castsi256_pd(_mm256_permutevar8x32_epi32(_mm256_castpd_si256(reinterpret_cast<const __m256d&>(v)), permutation));
}
#endif

}  // namespace lamina::mls::simd
