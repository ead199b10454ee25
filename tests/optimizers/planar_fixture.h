#pragma once
// A planar 2R arm (links of 1 m along x, spheres of radius 0.08 m, joints about z, limits ±π)
// and one box "post" centred at (0, 1.5, 0): the stretched arm hits it around q1 = π/2, the
// folded arm (|q2| ≳ 2) never reaches it. Built in code so the tests do not depend on files.

#include <memory>
#include <string>

#include "chasles/collision/collision_checker.h"
#include "chasles/collision/scene.h"
#include "chasles/robot/robot_model.h"

namespace chasles::test {

inline std::shared_ptr<const RobotModel> PlanarArm() {
  std::string spheres1, spheres2;
  for (double x : {0.25, 0.5, 0.75, 1.0}) {
    const std::string s = "<collision><origin xyz=\"" + std::to_string(x) +
                          " 0 0\"/><geometry><sphere radius=\"0.08\"/></geometry></collision>";
    spheres1 += s;
    spheres2 += s;
  }
  const std::string urdf = R"(<?xml version="1.0"?>
<robot name="test_planar">
  <link name="base_link"/>
  <joint name="joint1" type="revolute">
    <parent link="base_link"/><child link="link1"/>
    <origin xyz="0 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3.141592653589793" upper="3.141592653589793" velocity="2" effort="10"/>
  </joint>
  <link name="link1">)" + spheres1 + R"(</link>
  <joint name="joint2" type="revolute">
    <parent link="link1"/><child link="link2"/>
    <origin xyz="1 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3.141592653589793" upper="3.141592653589793" velocity="2" effort="10"/>
  </joint>
  <link name="link2">)" + spheres2 + R"(</link>
</robot>)";
  return RobotModel::FromUrdf(urdf);
}

inline std::shared_ptr<const CollisionChecker> PlanarCheckerWithPost() {
  auto scene = std::make_shared<Scene>();
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(0.0, 1.5, 0.0);
  scene->AddObject(SceneObject{"post", Shape::Box(Eigen::Vector3d(0.4, 0.4, 0.4), pose)});
  return std::make_shared<CollisionChecker>(PlanarArm(), scene);
}

/// Start (0, 0) and goal (3, 0) on either side of the post, joined by a zig-zag through the
/// folded-elbow region: valid, but far longer than needed.
inline JointPath ZigZagAroundPost() {
  JointPath path{Eigen::Vector2d(0.0, 0.0)};
  for (int k = 1; k <= 7; ++k) path.push_back(Eigen::Vector2d(0.4 * k, k % 2 ? 2.2 : 2.8));
  path.push_back(Eigen::Vector2d(3.0, 0.0));
  return path;
}

}  // namespace chasles::test
