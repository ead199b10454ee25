#pragma once
// Shared by the planner tests: the planar 2R arm of the planner contract problem.

namespace chasles::testing {

// A planar 2R arm (links of 1.0 m and 0.8 m along x, joints about z) made of spheres.
constexpr char kTwoLinkUrdf[] = R"(<?xml version="1.0"?>
<robot name="two_link">
  <link name="base"/>
  <link name="link1">
    <collision><origin xyz="0.25 0 0"/><geometry><sphere radius="0.05"/></geometry></collision>
    <collision><origin xyz="0.5 0 0"/><geometry><sphere radius="0.05"/></geometry></collision>
    <collision><origin xyz="0.75 0 0"/><geometry><sphere radius="0.05"/></geometry></collision>
    <collision><origin xyz="1.0 0 0"/><geometry><sphere radius="0.05"/></geometry></collision>
  </link>
  <link name="link2">
    <collision><origin xyz="0.2 0 0"/><geometry><sphere radius="0.05"/></geometry></collision>
    <collision><origin xyz="0.4 0 0"/><geometry><sphere radius="0.05"/></geometry></collision>
    <collision><origin xyz="0.6 0 0"/><geometry><sphere radius="0.05"/></geometry></collision>
    <collision><origin xyz="0.8 0 0"/><geometry><sphere radius="0.05"/></geometry></collision>
  </link>
  <joint name="j1" type="revolute">
    <parent link="base"/><child link="link1"/><axis xyz="0 0 1"/>
    <limit lower="-3.14" upper="3.14" velocity="2" effort="10"/>
  </joint>
  <joint name="j2" type="revolute">
    <parent link="link1"/><child link="link2"/><origin xyz="1.0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-2.8" upper="2.8" velocity="2" effort="10"/>
  </joint>
</robot>)";

}  // namespace chasles::testing
