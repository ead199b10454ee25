#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "chasles/robot/error.h"

namespace chasles {

std::string EscapeControlCharacters(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (const char ch : text) {
    const auto byte = static_cast<unsigned char>(ch);
    if (byte < 0x20 || byte == 0x7f) {
      static const char kHex[] = "0123456789abcdef";
      out += "\\x";
      out += kHex[byte >> 4];
      out += kHex[byte & 15];
    } else {
      out += ch;
    }
  }
  return out;
}

std::string FormatNumber(double value) {
  // Shortest decimal text that reads back exactly.
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  // Plain notation in the everyday range (100, not 1e+02); exponents only outside it.
  const double magnitude = std::fabs(value);
  const bool plain = magnitude == 0.0 || (magnitude >= 1e-4 && magnitude < 1e15);
  char buf[40];
  for (int precision = 1; precision <= 17; ++precision) {
    std::snprintf(buf, sizeof(buf), "%.*g", precision, value);
    if (plain && std::string(buf).find('e') != std::string::npos) continue;
    if (std::strtod(buf, nullptr) == value) break;
  }
  return buf;
}

}  // namespace chasles
