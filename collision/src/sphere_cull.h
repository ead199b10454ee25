#pragma once
/// \file
/// The fast path's bounding-sphere cull: for each of m query spheres, which of (up to 64)
/// spheres stored as structure of arrays overlap or touch it, as a bit mask. Internal to
/// chasles_collision (and its tests).
///
/// Every variant evaluates, lane by lane, exactly the scalar expression
///   (dx·dx + dy·dy) + dz·dz <= (r_i + r_q)·(r_i + r_q),  d = (x_i, y_i, z_i) − c_q,
/// in the same order with no fused multiply-add, so all of them return the same bits (touching
/// counts as overlapping, as in the rest of the fast path). Variants (simd.h): AVX2 (4 lanes),
/// SSE2 (2 lanes, the x86-64 baseline) and plain C++ elsewhere.

#include <cstddef>
#include <cstdint>

#include "simd.h"

#ifdef CHASLES_SIMD_X86
#include <immintrin.h>
#endif

namespace chasles::detail {

/// Arrays passed to OverlapMasks must be readable up to a multiple of this many entries: the
/// SIMD variants load whole lanes (and clear the bits past n).
constexpr std::size_t kCullLanes = 4;

/// Rounds n up to a multiple of kCullLanes.
constexpr std::size_t CullPadded(std::size_t n) { return (n + kCullLanes - 1) / kCullLanes * kCullLanes; }

/// The spheres of one cull: n <= 64 of them as structure of arrays (centres x, y, z, radii r),
/// each array readable up to CullPadded(n).
struct CullSpheres {
  const double* x;
  const double* y;
  const double* z;
  const double* r;
  std::size_t n;
};

/// For each query sphere j < m (centre (qx, qy, qz)[j], radius qr[j]): masks[j] has bit i set
/// when sphere i of `s` overlaps or touches it.
inline void OverlapMasksScalar(const CullSpheres& s, const double* qx, const double* qy, const double* qz,
                               const double* qr, std::size_t m, std::uint64_t* masks) {
  for (std::size_t j = 0; j < m; ++j) {
    std::uint64_t mask = 0;
    for (std::size_t i = 0; i < s.n; ++i) {
      const double dx = s.x[i] - qx[j], dy = s.y[i] - qy[j], dz = s.z[i] - qz[j];
      const double rr = s.r[i] + qr[j];
      mask |= static_cast<std::uint64_t>((dx * dx + dy * dy) + dz * dz <= rr * rr) << i;
    }
    masks[j] = mask;
  }
}

#ifdef CHASLES_SIMD_X86

inline void OverlapMasksSse2(const CullSpheres& s, const double* qx, const double* qy, const double* qz,
                             const double* qr, std::size_t m, std::uint64_t* masks) {
  const std::uint64_t valid = s.n >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << s.n) - 1;
  for (std::size_t j = 0; j < m; ++j) {
    const __m128d cx = _mm_set1_pd(qx[j]), cy = _mm_set1_pd(qy[j]), cz = _mm_set1_pd(qz[j]);
    const __m128d cr = _mm_set1_pd(qr[j]);
    std::uint64_t mask = 0;
    for (std::size_t i = 0; i < s.n; i += 2) {
      const __m128d dx = _mm_sub_pd(_mm_loadu_pd(s.x + i), cx);
      const __m128d dy = _mm_sub_pd(_mm_loadu_pd(s.y + i), cy);
      const __m128d dz = _mm_sub_pd(_mm_loadu_pd(s.z + i), cz);
      const __m128d rr = _mm_add_pd(_mm_loadu_pd(s.r + i), cr);
      const __m128d d2 = _mm_add_pd(_mm_add_pd(_mm_mul_pd(dx, dx), _mm_mul_pd(dy, dy)), _mm_mul_pd(dz, dz));
      mask |= static_cast<std::uint64_t>(_mm_movemask_pd(_mm_cmple_pd(d2, _mm_mul_pd(rr, rr)))) << i;
    }
    masks[j] = mask & valid;
  }
}

__attribute__((target("avx2"))) inline void OverlapMasksAvx2(const CullSpheres& s, const double* qx,
                                                             const double* qy, const double* qz,
                                                             const double* qr, std::size_t m,
                                                             std::uint64_t* masks) {
  const std::uint64_t valid = s.n >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << s.n) - 1;
  for (std::size_t j = 0; j < m; ++j) {
    const __m256d cx = _mm256_set1_pd(qx[j]), cy = _mm256_set1_pd(qy[j]), cz = _mm256_set1_pd(qz[j]);
    const __m256d cr = _mm256_set1_pd(qr[j]);
    std::uint64_t mask = 0;
    for (std::size_t i = 0; i < s.n; i += 4) {
      const __m256d dx = _mm256_sub_pd(_mm256_loadu_pd(s.x + i), cx);
      const __m256d dy = _mm256_sub_pd(_mm256_loadu_pd(s.y + i), cy);
      const __m256d dz = _mm256_sub_pd(_mm256_loadu_pd(s.z + i), cz);
      const __m256d rr = _mm256_add_pd(_mm256_loadu_pd(s.r + i), cr);
      const __m256d d2 =
          _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)), _mm256_mul_pd(dz, dz));
      const int bits = _mm256_movemask_pd(_mm256_cmp_pd(d2, _mm256_mul_pd(rr, rr), _CMP_LE_OQ));
      mask |= static_cast<std::uint64_t>(bits) << i;
    }
    masks[j] = mask & valid;
  }
}

#endif  // CHASLES_SIMD_X86

inline void OverlapMasks(SimdLevel level, const CullSpheres& s, const double* qx, const double* qy,
                         const double* qz, const double* qr, std::size_t m, std::uint64_t* masks) {
#ifdef CHASLES_SIMD_X86
  if (level == SimdLevel::kAvx2) return OverlapMasksAvx2(s, qx, qy, qz, qr, m, masks);
  if (level == SimdLevel::kSse2) return OverlapMasksSse2(s, qx, qy, qz, qr, m, masks);
#endif
  OverlapMasksScalar(s, qx, qy, qz, qr, m, masks);
}

}  // namespace chasles::detail
