// A mesh's FCL BVH is built once per mesh object and kept while the mesh lives (issue 25: robot
// preprocessing once per robot, not per request): every checker of a mesh robot — one per scene
// it plans in — shares the BVHs of its meshes.

#include <memory>

#include <gtest/gtest.h>

#include "chasles/collision/collision_checker.h"
#include "test_util.h"
#include "../../collision/src/fcl_geometry.h"

namespace chasles {
namespace {

TEST(MeshBvh, OneMeshObjectGetsOneBvh) {
  const Shape cube = test::CubeMeshShape(0.1, Eigen::Isometry3d::Identity());
  const FclGeom first = MakeGeom(cube);
  const FclGeom again = MakeGeom(cube);
  EXPECT_EQ(first.geom.get(), again.geom.get());
  EXPECT_TRUE(first.center == again.center);
  EXPECT_EQ(first.radius, again.radius);
  // Kept while the mesh lives, even when no geometry built from it is held any more.
  const void* bvh = first.geom.get();
  {
    const FclGeom dropped = MakeGeom(cube);
    EXPECT_EQ(dropped.geom.get(), bvh);
  }
  EXPECT_EQ(MakeGeom(cube).geom.get(), bvh);
  // The same triangles in another mesh object: a BVH of its own (a mesh is matched by object,
  // not by content).
  const Shape twin = test::CubeMeshShape(0.1, Eigen::Isometry3d::Identity());
  EXPECT_NE(MakeGeom(twin).geom.get(), first.geom.get());
  // A primitive is never shared.
  const Shape ball = Shape::Sphere(0.1);
  EXPECT_NE(MakeGeom(ball).geom.get(), MakeGeom(ball).geom.get());
}

TEST(MeshBvh, CheckersOfOneMeshRobotInTwoScenesAnswerAsAloneAndAgree) {
  // A one-link slider whose link is a mesh cube (FCL path), checked in two scenes: the second
  // checker reuses the first's BVH, and both answer as the geometry says.
  const auto robot = test::SliderRobot(test::CubeMeshShape(0.1, Eigen::Isometry3d::Identity()));
  auto wall_at = [](double x) {
    auto scene = std::make_shared<Scene>();
    Eigen::Isometry3d at = Eigen::Isometry3d::Identity();
    at.translation().x() = x;
    scene->AddObject({"wall", Shape::Box({0.1, 2.0, 2.0}, at)});
    return scene;
  };
  const CollisionChecker near(robot, wall_at(1.0));
  const CollisionChecker far(robot, wall_at(3.0));
  ASSERT_FALSE(near.uses_fast_path());
  for (double x = 0.0; x <= 3.5; x += 0.01) {
    Eigen::VectorXd q(1);
    q << x;
    // The cube spans x ± 0.1 and the wall w ± 0.05: they overlap when |x − w| < 0.15.
    const double gap_near = std::abs(x - 1.0) - 0.15, gap_far = std::abs(x - 3.0) - 0.15;
    if (std::abs(gap_near) > 1e-6) {
      EXPECT_EQ(near.IsValid(q), gap_near > 0.0) << x;
    }
    if (std::abs(gap_far) > 1e-6) {
      EXPECT_EQ(far.IsValid(q), gap_far > 0.0) << x;
    }
  }
}

}  // namespace
}  // namespace chasles
