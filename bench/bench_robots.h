#pragma once
/// \file
/// `chasles-bench --section robots` (issue 25, item 6): the robots the project ships beside the
/// Panda — a UR5 as spheres, as primitives and with a mimic-finger gripper, the mobile
/// manipulator (prismatic torso, continuous joints), the two-arm robot with mimic fingers — on seeded problems in one shelf
/// scene, in-process through the whole pipeline; every trajectory re-checked on the generic FCL
/// path every 0.002 rad (or m).

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "chasles/collision/scene.h"

namespace chasles {

/// The scene of that section: a table, a shelf board over it and two posts, in reach of each arm.
std::shared_ptr<Scene> RobotsBenchScene();

struct RobotsBenchOptions {
  std::string examples_dir;  ///< holds robots/<name>.urdf and .srdf
  std::vector<std::string> robots = {"panda", "ur5_spheres", "ur5", "ur5_gripper", "mobile_manipulator", "dual_arm"};
  int queries = 50;          ///< seeded start/goal pairs per robot
  double budget = 1.0;       ///< planning budget per query [s] (RRT-Connect)
  std::uint64_t seed = 1;
};

/// Prints a markdown table to stdout. \throws std::runtime_error when a file is missing.
void BenchRobots(const RobotsBenchOptions& options);

}  // namespace chasles
