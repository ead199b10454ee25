#pragma once
/// \file
/// The range rules the pipeline's queries check, with one message form (internal to
/// chasles_pipeline): `field = value must be within [lo, hi]` / `(0, hi]`.

#include <cmath>
#include <string>

#include "chasles/robot/error.h"

namespace chasles::detail {

/// \throws Error(kInvalidArgument) unless lo <= value <= hi (NaN fails).
inline void CheckRange(double value, double lo, double hi, const std::string& field) {
  if (!std::isfinite(value) || value < lo || value > hi) {
    ThrowInvalid(field + " = " + FormatNumber(value) + " must be within [" + FormatNumber(lo) + ", " + FormatNumber(hi) + "]");
  }
}

/// \throws Error(kInvalidArgument) unless 0 < value <= hi (NaN fails).
inline void CheckOpenRange(double value, double hi, const std::string& field) {
  if (!std::isfinite(value) || value <= 0.0 || value > hi) {
    ThrowInvalid(field + " = " + FormatNumber(value) + " must be within (0, " + FormatNumber(hi) + "]");
  }
}

}  // namespace chasles::detail
