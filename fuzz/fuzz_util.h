#pragma once
// Shared by the fuzz targets: reading example files, and the rule every target applies to a
// conversion: it either succeeds or throws chasles::Error. Anything else (another exception,
// a crash, a sanitizer report, a timeout, running out of memory) is a finding.

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>

#include "chasles/robot/error.h"

namespace chasles::fuzz {

inline std::string ReadSourceFile(const std::string& relative) {
  std::ifstream in(std::string(CHASLES_SOURCE_DIR) + "/" + relative, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

/// Splits `input` at the first `separator`: (before, after); after is empty without one.
inline std::pair<std::string_view, std::string_view> Split(std::string_view input, std::string_view separator) {
  const std::size_t at = input.find(separator);
  if (at == std::string_view::npos) return {input, {}};
  return {input.substr(0, at), input.substr(at + separator.size())};
}

/// Runs `f`; a chasles::Error is an expected answer to bad input.
template <typename F>
void Expect(F&& f) {
  try {
    f();
  } catch (const Error&) {
  }
}

}  // namespace chasles::fuzz
