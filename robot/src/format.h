#pragma once
// Internal: number formatting for error messages of the robot module.

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace chasles {
namespace robot_internal {

/// Shortest decimal text that reads back as exactly `x` ("2", "0.0825", "nan", "-inf").
inline std::string FormatNumber(double x) {
  if (std::isnan(x)) return "nan";
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  char buf[40];
  for (int precision = 1; precision <= 17; ++precision) {
    std::snprintf(buf, sizeof(buf), "%.*g", precision, x);
    if (std::strtod(buf, nullptr) == x) break;
  }
  return buf;
}

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
