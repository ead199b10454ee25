#pragma once
/// \file
/// A planar 2R arm made of boxes, shared by the verification-repair tests: box links take the
/// discrete (FCL) checks, so a coarse collision_resolution can step over a thin obstacle.
/// Link 1: 1.0 m, link 2: 0.8 m, both 4 cm square, in the plane z = 0.

namespace chasles::test {

inline constexpr const char* kBoxArmUrdf = R"(<robot name="box_2r">
  <link name="base"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>
    <limit lower="-3.14159" upper="3.14159" velocity="2" effort="10"/></joint>
  <link name="l1"><collision><origin xyz="0.5 0 0"/><geometry><box size="1.0 0.04 0.04"/></geometry></collision></link>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="1.0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3.14159" upper="3.14159" velocity="2" effort="10"/></joint>
  <link name="l2"><collision><origin xyz="0.4 0 0"/><geometry><box size="0.8 0.04 0.04"/></geometry></collision></link>
</robot>)";

}  // namespace chasles::test
