#pragma once
// Disc robots for the coordination tests: a sphere of radius 0.3 m at z = 0.3 m on two prismatic
// joints (x, y) with limits [-5, 5] m and 1 m/s (unless given), so a team of them is cheap to plan
// for and easy to reason about. Built in code so the tests do not depend on files.

#include <memory>
#include <string>

#include "chasles/collision/scene.h"
#include "chasles/multi/coordinator.h"
#include "chasles/robot/robot_model.h"

namespace chasles::test {

inline std::shared_ptr<const RobotModel> DiscRobot(double velocity = 1.0, double radius = 0.3) {
  const std::string v = std::to_string(velocity);
  const std::string urdf = R"(<?xml version="1.0"?>
<robot name="disc">
  <link name="base"/>
  <joint name="x" type="prismatic">
    <parent link="base"/><child link="slider"/><axis xyz="1 0 0"/>
    <limit lower="-5" upper="5" velocity=")" + v + R"(" effort="100"/>
  </joint>
  <link name="slider"/>
  <joint name="y" type="prismatic">
    <parent link="slider"/><child link="body"/><axis xyz="0 1 0"/>
    <limit lower="-5" upper="5" velocity=")" + v + R"(" effort="100"/>
  </joint>
  <link name="body">
    <collision><origin xyz="0 0 0.3"/><geometry><sphere radius=")" + std::to_string(radius) + R"("/></geometry></collision>
  </link>
</robot>)";
  return RobotModel::FromUrdf(urdf);
}

inline TeamRobotSpec Disc(const std::string& name, Eigen::Vector2d start, Eigen::Vector2d goal, int priority = 0,
                          double velocity = 1.0) {
  TeamRobotSpec spec;
  spec.placement.name = name;
  spec.placement.model = DiscRobot(velocity);
  spec.start = start;
  spec.goal = goal;
  spec.priority = priority;
  return spec;
}

inline std::shared_ptr<const Scene> EmptyFloor() { return std::make_shared<Scene>(); }

/// A wall (box) centred at (x, y) with the given extents, 0.6 m high.
inline void AddWall(Scene* scene, const std::string& name, double x, double y, double sx, double sy) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(x, y, 0.3);
  scene->AddObject(SceneObject{name, Shape::Box(Eigen::Vector3d(sx, sy, 0.6), pose)});
}

}  // namespace chasles::test
