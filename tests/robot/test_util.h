#pragma once
// Shared helpers of the robot tests.

#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <memory>
#include <random>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "chasles/robot/error.h"
#include "chasles/robot/robot_model.h"

namespace chasles {
namespace testing {

inline std::string ReadExample(const std::string& relative) {
  const std::string path = std::string(CHASLES_SOURCE_DIR) + "/examples/" + relative;
  std::ifstream file(path);
  EXPECT_TRUE(file.good()) << "cannot open " << path;
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

/// Loads examples/robots/<name>.urdf with its .srdf.
inline std::shared_ptr<const RobotModel> LoadExampleRobot(const std::string& name) {
  return RobotModel::FromUrdf(ReadExample("robots/" + name + ".urdf"),
                              ReadExample("robots/" + name + ".srdf"));
}

/// Expects `fn` to throw Error(kInvalidArgument) with exactly `message`.
inline void ExpectInvalid(const std::function<void()>& fn, const std::string& message) {
  try {
    fn();
    ADD_FAILURE() << "no Error thrown; expected: " << message;
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_EQ(std::string(e.what()), message);
  }
}

/// The seed of a randomised test: CHASLES_TEST_SEED if set, else `fallback`.
inline std::uint64_t TestSeed(std::uint64_t fallback) {
  const char* s = std::getenv("CHASLES_TEST_SEED");
  return s ? std::strtoull(s, nullptr, 10) : fallback;
}

/// The case count of a randomised test: CHASLES_TEST_CASES if set, else `fallback`.
inline int TestCases(int fallback) {
  const char* s = std::getenv("CHASLES_TEST_CASES");
  return s ? std::atoi(s) : fallback;
}

/// Uniform in [0, 1) from the top 53 bits: the same on every standard library.
inline double Uniform(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

/// Uniform within the joint limits.
inline Eigen::VectorXd RandomConfiguration(const RobotModel& robot, std::mt19937_64& rng) {
  Eigen::VectorXd q(robot.num_dofs());
  for (int i = 0; i < q.size(); ++i) {
    q[i] = robot.lower_limits()[i] + (robot.upper_limits()[i] - robot.lower_limits()[i]) * Uniform(rng);
  }
  return q;
}

}  // namespace testing
}  // namespace chasles
