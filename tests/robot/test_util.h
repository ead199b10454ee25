#pragma once
// Shared helpers of the robot tests.

#include <fstream>
#include <functional>
#include <memory>
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

}  // namespace testing
}  // namespace chasles
