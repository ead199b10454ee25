#pragma once
// ReadFile for every test directory's helpers (tests/*/test_util.h include it).

#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

namespace chasles::test {

/// The whole file at `path`; a file that cannot be opened fails the test (and reads as empty).
inline std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  EXPECT_TRUE(in.good()) << "cannot open " << path;
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace chasles::test
