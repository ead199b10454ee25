#pragma once
/// \file
/// SinCos: sine and cosine together for the fast path's forward kinematics. Internal to
/// chasles_collision (and its tests).

#include <cmath>
#include <cstdint>
#include <cstring>

namespace chasles::detail {

/// sin x and cos x for the FK, within 2.3e-16 of the exact values (2 ulp) for |x| <= 1e5 rad;
/// std::sin/std::cos beyond that and for NaN. Branch-free, so the FK's joints overlap in the
/// pipeline (libm's sincos was a fifth of a state check): x = k·π/2 + r with k the nearest
/// integer to x·2/π and r = (x − k·hi) − k·lo (Cody–Waite: hi is π/2 to 33 bits, so k·hi is
/// exact for |k| < 2^20, and lo = π/2 − hi), |r| <= π/4 up to rounding; Taylor polynomials of
/// sin r (to r^15) and cos r (to r^16), whose first omitted terms are below 5e-17 there; then
/// the quadrant k mod 4 swaps and negates them.
inline void SinCos(double x, double* sin_x, double* cos_x) {
  constexpr double kTwoOverPi = 0x1.45f306dc9c883p-1;
  constexpr double kPiOver2Hi = 0x1.921fb544p+0;
  constexpr double kPiOver2Lo = 0x1.0b4611a626331p-34;
  constexpr double kRoundToInteger = 0x1.8p52;  // x + this − this rounds |x| < 2^51 to an integer
  if (!(std::abs(x) <= 1e5)) {
    *sin_x = std::sin(x);
    *cos_x = std::cos(x);
    return;
  }
  const double k = (x * kTwoOverPi + kRoundToInteger) - kRoundToInteger;
  const double r = (x - k * kPiOver2Hi) - k * kPiOver2Lo;
  const double r2 = r * r;
  const double s =
      r + r * r2 *
              (-1.0 / 6 + r2 * (1.0 / 120 + r2 * (-1.0 / 5040 + r2 * (1.0 / 362880 + r2 * (-1.0 / 39916800 +
               r2 * (1.0 / 6227020800 + r2 * (-1.0 / 1307674368000)))))));
  const double c =
      1.0 - 0.5 * r2 +
      r2 * r2 *
          (1.0 / 24 + r2 * (-1.0 / 720 + r2 * (1.0 / 40320 + r2 * (-1.0 / 3628800 + r2 * (1.0 / 479001600 +
           r2 * (-1.0 / 87178291200 + r2 * (1.0 / 20922789888000)))))));
  // sin(k·π/2 + r), cos(k·π/2 + r) for k mod 4 = 0, 1, 2, 3: (s, c), (c, −s), (−s, −c), (−c, s).
  const std::uint64_t quadrant = static_cast<std::uint64_t>(static_cast<std::int64_t>(k)) & 3;
  std::uint64_t s_bits, c_bits;
  std::memcpy(&s_bits, &s, sizeof s);
  std::memcpy(&c_bits, &c, sizeof c);
  const std::uint64_t swap = std::uint64_t{0} - (quadrant & 1);
  const std::uint64_t sin_bits = ((s_bits & ~swap) | (c_bits & swap)) ^ ((quadrant & 2) << 62);
  const std::uint64_t cos_bits = ((c_bits & ~swap) | (s_bits & swap)) ^ (((quadrant + 1) & 2) << 62);
  std::memcpy(sin_x, &sin_bits, sizeof sin_bits);
  std::memcpy(cos_x, &cos_bits, sizeof cos_bits);
}

}  // namespace chasles::detail
