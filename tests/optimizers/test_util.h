#pragma once
// Shared helpers for the optimizers tests: seeded, platform-independent random numbers and
// the settable seed / case count (CHASLES_TEST_SEED, CHASLES_TEST_CASES).

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <algorithm>
#include <random>
#include <string>

#include <Eigen/Core>

#include "../read_file.h"

namespace chasles::test {

inline std::uint64_t TestSeed() {
  const char* env = std::getenv("CHASLES_TEST_SEED");
  return env ? std::strtoull(env, nullptr, 10) : 20260521u;
}

/// `fallback` cases unless CHASLES_TEST_CASES overrides it.
inline int TestCases(int fallback) {
  const char* env = std::getenv("CHASLES_TEST_CASES");
  return env ? std::atoi(env) : fallback;
}

class Random {
 public:
  explicit Random(std::uint64_t seed) : rng_(seed) {}
  double Uniform() { return static_cast<double>(rng_() >> 11) * 0x1.0p-53; }
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  int Index(int n) { return std::min(n - 1, static_cast<int>(Uniform() * n)); }
  Eigen::VectorXd Vector(int n, double lo, double hi) {
    Eigen::VectorXd v(n);
    for (int i = 0; i < n; ++i) v[i] = Uniform(lo, hi);
    return v;
  }

 private:
  std::mt19937_64 rng_;
};

inline bool BitEqual(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  if (a.size() != b.size()) return false;
  for (int i = 0; i < a.size(); ++i) {
    if (std::memcmp(&a[i], &b[i], sizeof(double)) != 0) return false;
  }
  return true;
}

}  // namespace chasles::test
