#pragma once
/// \file
/// Which instruction set the fast path's SIMD kernels use (sphere_cull.h,
/// forward_kinematics.h). Internal to chasles_collision (and its tests).
///
/// The library is built for the x86-64 baseline (SSE2); kernels that gain from AVX2 are also
/// compiled with target("avx2") — never "fma", so no multiply-add is fused and every variant
/// gives the same bits — and chosen once at run time.

#if defined(__x86_64__) || defined(_M_X64)
#define CHASLES_SIMD_X86 1
#endif

namespace chasles::detail {

enum class SimdLevel { kScalar, kSse2, kAvx2 };

/// The widest level this CPU runs (checked once).
inline SimdLevel BestSimdLevel() {
#ifdef CHASLES_SIMD_X86
  // __builtin_cpu_init: libgcc's CPU data may not be set up yet when a checker is built by a
  // static initializer.
  static const SimdLevel best = (__builtin_cpu_init(), __builtin_cpu_supports("avx2")) ? SimdLevel::kAvx2 : SimdLevel::kSse2;
  return best;
#else
  return SimdLevel::kScalar;
#endif
}

/// True when this CPU runs `level` (for tests that compare the variants).
inline bool SimdLevelRuns(SimdLevel level) {
#ifdef CHASLES_SIMD_X86
  return level != SimdLevel::kAvx2 || BestSimdLevel() == SimdLevel::kAvx2;
#else
  return level == SimdLevel::kScalar;
#endif
}

}  // namespace chasles::detail
