#pragma once
// Internal: number formatting for error messages of the robot module.

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "chasles/robot/error.h"

namespace chasles {
namespace robot_internal {

/// `x` with `precision` significant digits ("3.1416").
inline std::string FormatNumber(double x, int precision) {
  if (std::isnan(x)) return "nan";
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%.*g", precision, x);
  return buf;
}

}  // namespace robot_internal
}  // namespace chasles
