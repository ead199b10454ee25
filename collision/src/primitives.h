#pragma once
/// \file
/// Scene primitives of the fast path (sphere, box, cylinder, capsule) and the closed-form
/// sphere tests against them: SphereHits, SphereDistance, and SphereDistances, the distance of
/// many spheres (structure of arrays) to one primitive at once. Internal to chasles_collision
/// (and its tests).
///
/// SphereDistances evaluates, lane by lane, exactly SphereDistance's expression in its order —
/// max(v, 0) as max(0, v) in SIMD (the same result for every v, NaN and −0 included), no fused
/// multiply-add — so its AVX2 (4 lanes), SSE2 (2 lanes) and scalar variants (simd.h) all return
/// SphereDistance's bits.

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "simd.h"

#ifdef CHASLES_SIMD_X86
#include <immintrin.h>
#endif

namespace chasles::detail {

enum PrimKind { kPrimSphere = 0, kPrimBox = 1, kPrimCylinder = 2, kPrimCapsule = 3 };

/// A scene primitive for the fast path, with its world->local transform precomputed.
struct Prim {
  int kind;
  int object;      // index into scene.objects()
  int allowed = -1;  // index into the checker's sets of links that may touch it, or -1
  double rt[9];    // world->local rotation (Rᵀ), row-major
  double p[3];     // world position of the centre
  double a, b, c;  // box half extents; sphere/cylinder/capsule: a = radius, b = half length
  double bound;    // bounding-sphere radius about p
};

/// The world point x in o's frame: l = Rᵀ(x − p).
inline void ToLocal(const Prim& o, const double* x, double* l) {
  const double d0 = x[0] - o.p[0], d1 = x[1] - o.p[1], d2 = x[2] - o.p[2];
  l[0] = o.rt[0] * d0 + o.rt[1] * d1 + o.rt[2] * d2;
  l[1] = o.rt[3] * d0 + o.rt[4] * d1 + o.rt[5] * d2;
  l[2] = o.rt[6] * d0 + o.rt[7] * d1 + o.rt[8] * d2;
}

/// Box o: the squared distance from world point x to the box (0 inside).
inline double BoxExcessSquared(const Prim& o, const double* x) {
  double l[3];
  ToLocal(o, x, l);
  const double e0 = std::max(std::abs(l[0]) - o.a, 0.0);
  const double e1 = std::max(std::abs(l[1]) - o.b, 0.0);
  const double e2 = std::max(std::abs(l[2]) - o.c, 0.0);
  return e0 * e0 + e1 * e1 + e2 * e2;
}

/// True when a sphere (world centre x, radius r) touches or overlaps primitive o.
inline bool SphereHits(const Prim& o, const double* x, double r) {
  switch (o.kind) {
    case kPrimSphere: {
      const double d0 = x[0] - o.p[0], d1 = x[1] - o.p[1], d2 = x[2] - o.p[2];
      const double rr = r + o.a;
      return d0 * d0 + d1 * d1 + d2 * d2 <= rr * rr;
    }
    case kPrimBox:
      return BoxExcessSquared(o, x) <= r * r;
    case kPrimCylinder: {
      double l[3];
      ToLocal(o, x, l);
      const double dz = std::max(std::abs(l[2]) - o.b, 0.0);
      if (dz > r) return false;
      const double rho2 = l[0] * l[0] + l[1] * l[1];
      if (rho2 <= o.a * o.a) return true;  // dz <= r already
      const double dr = std::sqrt(rho2) - o.a;
      return dr * dr + dz * dz <= r * r;
    }
    default: {  // capsule
      double l[3];
      ToLocal(o, x, l);
      const double dz = std::max(std::abs(l[2]) - o.b, 0.0);
      const double rr = r + o.a;
      return l[0] * l[0] + l[1] * l[1] + dz * dz <= rr * rr;
    }
  }
}

/// Distance from the surface of a sphere (centre x, radius r) to primitive o; <= 0 on contact.
inline double SphereDistance(const Prim& o, const double* x, double r) {
  switch (o.kind) {
    case kPrimSphere: {
      const double d0 = x[0] - o.p[0], d1 = x[1] - o.p[1], d2 = x[2] - o.p[2];
      return std::sqrt(d0 * d0 + d1 * d1 + d2 * d2) - r - o.a;
    }
    case kPrimBox:
      return std::sqrt(BoxExcessSquared(o, x)) - r;
    case kPrimCylinder: {
      double l[3];
      ToLocal(o, x, l);
      const double dz = std::max(std::abs(l[2]) - o.b, 0.0);
      const double dr = std::max(std::sqrt(l[0] * l[0] + l[1] * l[1]) - o.a, 0.0);
      return std::sqrt(dr * dr + dz * dz) - r;
    }
    default: {
      double l[3];
      ToLocal(o, x, l);
      const double dz = std::max(std::abs(l[2]) - o.b, 0.0);
      return std::sqrt(l[0] * l[0] + l[1] * l[1] + dz * dz) - r - o.a;
    }
  }
}

/// One lane type's operations for SphereDistancesBody: the scalar code's.
struct ScalarLanes {
  using T = double;
  static constexpr std::size_t kWidth = 1;
  static T Load(const double* p) { return *p; }
  static void Store(double* p, T v) { *p = v; }
  static T Set(double x) { return x; }
  static T Add(T a, T b) { return a + b; }
  static T Sub(T a, T b) { return a - b; }
  static T Mul(T a, T b) { return a * b; }
  static T Abs(T a) { return std::abs(a); }
  static T Max0(T a) { return std::max(a, 0.0); }
  static T Sqrt(T a) { return std::sqrt(a); }
};

#ifdef CHASLES_SIMD_X86
struct Sse2Lanes {
  using T = __m128d;
  static constexpr std::size_t kWidth = 2;
  static T Load(const double* p) { return _mm_loadu_pd(p); }
  static void Store(double* p, T v) { _mm_storeu_pd(p, v); }
  static T Set(double x) { return _mm_set1_pd(x); }
  static T Add(T a, T b) { return _mm_add_pd(a, b); }
  static T Sub(T a, T b) { return _mm_sub_pd(a, b); }
  static T Mul(T a, T b) { return _mm_mul_pd(a, b); }
  static T Abs(T a) { return _mm_andnot_pd(_mm_set1_pd(-0.0), a); }
  static T Max0(T a) { return _mm_max_pd(_mm_setzero_pd(), a); }  // (0 > a) ? 0 : a = std::max(a, 0.0)
  static T Sqrt(T a) { return _mm_sqrt_pd(a); }
};

#define CHASLES_AVX2_INLINE __attribute__((target("avx2"), always_inline))
struct Avx2Lanes {
  using T = __m256d;
  static constexpr std::size_t kWidth = 4;
  CHASLES_AVX2_INLINE static T Load(const double* p) { return _mm256_loadu_pd(p); }
  CHASLES_AVX2_INLINE static void Store(double* p, T v) { _mm256_storeu_pd(p, v); }
  CHASLES_AVX2_INLINE static T Set(double x) { return _mm256_set1_pd(x); }
  CHASLES_AVX2_INLINE static T Add(T a, T b) { return _mm256_add_pd(a, b); }
  CHASLES_AVX2_INLINE static T Sub(T a, T b) { return _mm256_sub_pd(a, b); }
  CHASLES_AVX2_INLINE static T Mul(T a, T b) { return _mm256_mul_pd(a, b); }
  CHASLES_AVX2_INLINE static T Abs(T a) { return _mm256_andnot_pd(_mm256_set1_pd(-0.0), a); }
  CHASLES_AVX2_INLINE static T Max0(T a) { return _mm256_max_pd(_mm256_setzero_pd(), a); }
  CHASLES_AVX2_INLINE static T Sqrt(T a) { return _mm256_sqrt_pd(a); }
};
#undef CHASLES_AVX2_INLINE
#endif  // CHASLES_SIMD_X86

namespace baseline {
#include "sphere_distances.inc"
}  // namespace baseline

#ifdef CHASLES_SIMD_X86
#pragma GCC push_options
#pragma GCC target("avx2")
namespace avx2 {
#include "sphere_distances.inc"
}  // namespace avx2
#pragma GCC pop_options
#endif

inline void SphereDistancesScalar(const Prim& o, const double* x, const double* y, const double* z, const double* r,
                                  std::size_t n, double* out) {
  baseline::SphereDistancesBody<ScalarLanes>(o, x, y, z, r, n, out);
}

#ifdef CHASLES_SIMD_X86
inline void SphereDistancesSse2(const Prim& o, const double* x, const double* y, const double* z, const double* r,
                                std::size_t n, double* out) {
  baseline::SphereDistancesBody<Sse2Lanes>(o, x, y, z, r, n, out);
}

__attribute__((target("avx2"))) inline void SphereDistancesAvx2(const Prim& o, const double* x, const double* y,
                                                                const double* z, const double* r, std::size_t n,
                                                                double* out) {
  avx2::SphereDistancesBody<Avx2Lanes>(o, x, y, z, r, n, out);
}
#endif

/// out[i] = SphereDistance(o, (x[i], y[i], z[i]), r[i]) for i < n (bit for bit). The arrays
/// must be readable, and out writable, up to n rounded up to a multiple of 4.
inline void SphereDistances(SimdLevel level, const Prim& o, const double* x, const double* y, const double* z,
                            const double* r, std::size_t n, double* out) {
#ifdef CHASLES_SIMD_X86
  if (level == SimdLevel::kAvx2) return SphereDistancesAvx2(o, x, y, z, r, n, out);
  if (level == SimdLevel::kSse2) return SphereDistancesSse2(o, x, y, z, r, n, out);
#endif
  SphereDistancesScalar(o, x, y, z, r, n, out);
}

}  // namespace chasles::detail
