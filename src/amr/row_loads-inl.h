// Row loads for the vectorised basis reconstruction on x86 (basis_batch.cpp): a cell and its
// neighbour along x, and with smooth shading their packed gradients, fetched per lane by one load
// each instead of a gather per float. Included by basis_batch.cpp, and with it once per
// instruction set (Highway's foreach_target); EXA_PAIR_LOADS says whether this target has them.
#if defined(EXABRICKS_AMR_ROW_LOADS_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef EXABRICKS_AMR_ROW_LOADS_INL_H_
#undef EXABRICKS_AMR_ROW_LOADS_INL_H_
#else
#define EXABRICKS_AMR_ROW_LOADS_INL_H_
#endif

#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace exa {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

#undef EXA_PAIR_LOADS
#if HWY_TARGET == HWY_AVX2 || HWY_TARGET == HWY_SSE4 || HWY_TARGET == HWY_AVX3
// A cell's value and its neighbour's along x are adjacent floats: one 64-bit load per lane fetches
// both, where a gather loads every float on its own (on Zen 3 frames with AVX2 gathers took 1.06 to
// 1.25 times as long; docs/performance-log.md). Lane i gets values[row[i]] in r0 and
// values[row[i] + 1] in r1. AVX-512 gathers the pairs as 64-bit elements.
#define EXA_PAIR_LOADS 1
HWY_INLINE __m128d loadPair(const float* p) {
  return _mm_castsi128_pd(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p)));
}
HWY_INLINE __m128d loadTwoPairs(const float* p, const float* q) {
  return _mm_loadh_pd(loadPair(p), reinterpret_cast<const double*>(q));
}
#if HWY_TARGET == HWY_AVX3
// Sixteen lanes: two gathers of eight 64-bit pairs (half the elements of two float gathers), then
// the lower and upper floats of the pairs sorted into two vectors. Lanes outside the brick's
// support (`live` false; their hat factors are zero) load nothing and get zero: 1.03 times faster
// frames on `plt_drop`, shaded or not.
HWY_INLINE void loadPairs(hn::Full512<float>, const float* values, hn::Vec512<int32_t> row, hn::Vec512<float>& r0,
                          hn::Vec512<float>& r1, hn::Mask512<float> live) {
  const __mmask16 m = live.raw;
  const __m512d none = _mm512_setzero_pd();
  const __m512 a =
      _mm512_castpd_ps(_mm512_mask_i32gather_pd(none, __mmask8(m), _mm512_castsi512_si256(row.raw), values, 4));
  const __m512 b = _mm512_castpd_ps(
      _mm512_mask_i32gather_pd(none, __mmask8(m >> 8), _mm512_extracti64x4_epi64(row.raw, 1), values, 4));
  const __m512i even = _mm512_set_epi32(30, 28, 26, 24, 22, 20, 18, 16, 14, 12, 10, 8, 6, 4, 2, 0);
  r0.raw = _mm512_permutex2var_ps(a, even, b);
  r1.raw = _mm512_permutex2var_ps(a, _mm512_add_epi32(even, _mm512_set1_epi32(1)), b);
}
#endif
#if HWY_TARGET == HWY_AVX2
HWY_INLINE void loadPairs(hn::Full256<float>, const float* values, hn::Vec256<int32_t> row, hn::Vec256<float>& r0,
                          hn::Vec256<float>& r1, hn::Mask256<float>) {
  alignas(32) int32_t i[8];
  _mm256_store_si256(reinterpret_cast<__m256i*>(i), row.raw);
  // Lanes 0, 1, 4, 5 and 2, 3, 6, 7, so that the in-lane shuffles below keep the order.
  const __m256 a =
      _mm256_castpd_ps(_mm256_insertf128_pd(_mm256_castpd128_pd256(loadTwoPairs(values + i[0], values + i[1])),
                                            loadTwoPairs(values + i[4], values + i[5]), 1));
  const __m256 b =
      _mm256_castpd_ps(_mm256_insertf128_pd(_mm256_castpd128_pd256(loadTwoPairs(values + i[2], values + i[3])),
                                            loadTwoPairs(values + i[6], values + i[7]), 1));
  r0.raw = _mm256_shuffle_ps(a, b, _MM_SHUFFLE(2, 0, 2, 0));
  r1.raw = _mm256_shuffle_ps(a, b, _MM_SHUFFLE(3, 1, 3, 1));
}
#endif
HWY_INLINE void loadPairs(hn::Full128<float>, const float* values, hn::Vec128<int32_t> row, hn::Vec128<float>& r0,
                          hn::Vec128<float>& r1, hn::Mask128<float>) {
  alignas(16) int32_t i[4];
  _mm_store_si128(reinterpret_cast<__m128i*>(i), row.raw);
  const __m128 a = _mm_castpd_ps(loadTwoPairs(values + i[0], values + i[1]));
  const __m128 b = _mm_castpd_ps(loadTwoPairs(values + i[2], values + i[3]));
  r0.raw = _mm_shuffle_ps(a, b, _MM_SHUFFLE(2, 0, 2, 0));
  r1.raw = _mm_shuffle_ps(a, b, _MM_SHUFFLE(3, 1, 3, 1));
}

// A row's two cells with their packed gradients (gradients.h: a cell's value, then its gradient)
// are four adjacent words: one 128-bit load per lane, transposed (lane i: cell pairs[2 row[i]] in
// v0, g0, its neighbour along x in v1, g1), where values and gradients took a 64-bit load each
// (performance.md). Every lane loads: indices are clamped into the brick, and the hat factors of
// missing or unreached cells are zero.
#if HWY_TARGET == HWY_AVX3
HWY_INLINE void loadQuads(hn::Full512<float>, const float* pairs, hn::Vec512<int32_t> row, hn::Vec512<float>& v0,
                          hn::Vec512<float>& g0, hn::Vec512<float>& v1, hn::Vec512<float>& g1) {
  alignas(64) int32_t i[16];
  _mm512_store_si512(reinterpret_cast<__m512i*>(i), row.raw);
  __m512 q[4]; // q[k]: the quads of lanes 4k to 4k + 3
  for (int k = 0; k < 4; ++k) {
    __m512 z = _mm512_castps128_ps512(_mm_loadu_ps(pairs + 2 * i[4 * k]));
    z = _mm512_insertf32x4(z, _mm_loadu_ps(pairs + 2 * i[4 * k + 1]), 1);
    z = _mm512_insertf32x4(z, _mm_loadu_ps(pairs + 2 * i[4 * k + 2]), 2);
    q[k] = _mm512_insertf32x4(z, _mm_loadu_ps(pairs + 2 * i[4 * k + 3]), 3);
  }
  // Lanes 0-7's first words (v0) then second (g0) from q[0], q[1]; plus two, the third and fourth.
  const __m512i first = _mm512_set_epi32(29, 25, 21, 17, 13, 9, 5, 1, 28, 24, 20, 16, 12, 8, 4, 0);
  const __m512i third = _mm512_add_epi32(first, _mm512_set1_epi32(2));
  const __m512 a01 = _mm512_permutex2var_ps(q[0], first, q[1]), b01 = _mm512_permutex2var_ps(q[0], third, q[1]);
  const __m512 a23 = _mm512_permutex2var_ps(q[2], first, q[3]), b23 = _mm512_permutex2var_ps(q[2], third, q[3]);
  v0.raw = _mm512_shuffle_f32x4(a01, a23, _MM_SHUFFLE(1, 0, 1, 0));
  g0.raw = _mm512_shuffle_f32x4(a01, a23, _MM_SHUFFLE(3, 2, 3, 2));
  v1.raw = _mm512_shuffle_f32x4(b01, b23, _MM_SHUFFLE(1, 0, 1, 0));
  g1.raw = _mm512_shuffle_f32x4(b01, b23, _MM_SHUFFLE(3, 2, 3, 2));
}
#endif
#if HWY_TARGET == HWY_AVX2
HWY_INLINE void loadQuads(hn::Full256<float>, const float* pairs, hn::Vec256<int32_t> row, hn::Vec256<float>& v0,
                          hn::Vec256<float>& g0, hn::Vec256<float>& v1, hn::Vec256<float>& g1) {
  alignas(32) int32_t i[8];
  _mm256_store_si256(reinterpret_cast<__m256i*>(i), row.raw);
  __m256 a[4]; // a[k]: the quads of lanes k and k + 4
  for (int k = 0; k < 4; ++k)
    a[k] = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(pairs + 2 * i[k])),
                                _mm_loadu_ps(pairs + 2 * i[k + 4]), 1);
  const __m256 t0 = _mm256_unpacklo_ps(a[0], a[1]), t1 = _mm256_unpacklo_ps(a[2], a[3]);
  const __m256 t2 = _mm256_unpackhi_ps(a[0], a[1]), t3 = _mm256_unpackhi_ps(a[2], a[3]);
  v0.raw = _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(1, 0, 1, 0));
  g0.raw = _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(3, 2, 3, 2));
  v1.raw = _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(1, 0, 1, 0));
  g1.raw = _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(3, 2, 3, 2));
}
#endif
HWY_INLINE void loadQuads(hn::Full128<float>, const float* pairs, hn::Vec128<int32_t> row, hn::Vec128<float>& v0,
                          hn::Vec128<float>& g0, hn::Vec128<float>& v1, hn::Vec128<float>& g1) {
  alignas(16) int32_t i[4];
  _mm_store_si128(reinterpret_cast<__m128i*>(i), row.raw);
  v0.raw = _mm_loadu_ps(pairs + 2 * i[0]), g0.raw = _mm_loadu_ps(pairs + 2 * i[1]);
  v1.raw = _mm_loadu_ps(pairs + 2 * i[2]), g1.raw = _mm_loadu_ps(pairs + 2 * i[3]);
  _MM_TRANSPOSE4_PS(v0.raw, g0.raw, v1.raw, g1.raw);
}
#else
#define EXA_PAIR_LOADS 0
#endif

} // namespace HWY_NAMESPACE
} // namespace exa
HWY_AFTER_NAMESPACE();

#endif
