// Reference cases with known answers: one sphere (or box) on a prismatic slider along x
// against one obstacle at a known distance, on both the fast path and the FCL path.

#include <cmath>
#include <functional>
#include <sstream>

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include "chasles/collision/collision_checker.h"
#include "chasles/robot/error.h"
#include "test_util.h"

namespace chasles {
namespace {

using test::SliderRobot;

Eigen::VectorXd Q(double x) { return Eigen::VectorXd::Constant(1, x); }

std::shared_ptr<Scene> OneObject(const Shape& s) {
  auto scene = std::make_shared<Scene>();
  scene->AddObject({"obstacle", s}, "scene.obstacle");
  return scene;
}

Eigen::Isometry3d At(double x, double y, double z, const Eigen::Matrix3d& r = Eigen::Matrix3d::Identity()) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = r;
  t.translation() << x, y, z;
  return t;
}

struct Case {
  const char* name;
  Shape obstacle;
  double contact_q;  // slider position at which the sphere (r = 0.1) just touches
  std::function<double(double)> distance = {};  // exact distance at q (empty: contact_q - q)
};

std::vector<Case> Cases() {
  const Eigen::Matrix3d about_y = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::Matrix3d about_z = Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return {
      {"box_face", Shape::Box({0.2, 0.2, 0.2}, At(1, 0, 0)), 0.8},
      {"box_corner", Shape::Box({0.2, 0.2, 0.2}, At(1, 0, 0, about_z)), 1 - 0.1 * std::sqrt(2.0) - 0.1},
      {"sphere", Shape::Sphere(0.15, At(1, 0, 0)), 0.75},
      {"cylinder_side", Shape::Cylinder(0.1, 0.4, At(1, 0, 0)), 0.8},
      {"cylinder_cap", Shape::Cylinder(0.1, 0.4, At(1, 0, 0, about_y)), 0.7},
      // z-axis cylinder spanning z in [0.05, 0.45] at (1, 0.15): the sphere centre (q, 0, 0) is
      // nearest to its bottom rim: distance = hypot(hypot(1 - q, 0.15) - 0.1, 0.05) - 0.1.
      {"cylinder_rim", Shape::Cylinder(0.1, 0.4, At(1, 0.15, 0.25)),
       1 - std::sqrt(std::pow(0.1 + std::sqrt(0.01 - 0.0025), 2) - 0.0225),
       [](double q) { return std::hypot(std::hypot(1 - q, 0.15) - 0.1, 0.05) - 0.1; }},
      {"capsule_side", Shape::Capsule(0.1, 0.4, At(1, 0, 0)), 0.8},
      {"capsule_tip", Shape::Capsule(0.1, 0.4, At(1, 0, 0, about_y)), 0.6},
  };
}

class SphereVsPrimitive : public ::testing::TestWithParam<bool> {};

TEST_P(SphereVsPrimitive, TouchingSeparatedPenetrating) {
  const bool force_fcl = GetParam();
  auto robot = SliderRobot(Shape::Sphere(0.1));
  for (Case c : Cases()) {
    if (!c.distance) {
      const double contact = c.contact_q;
      c.distance = [contact](double q) { return contact - q; };
    }
    SCOPED_TRACE(std::string(c.name) + (force_fcl ? " fcl" : " fast"));
    CollisionOptions options;
    options.force_fcl = force_fcl;
    CollisionChecker checker(robot, OneObject(c.obstacle), options);
    EXPECT_EQ(checker.uses_fast_path(), !force_fcl);
    for (double d : {0.3, 0.05, 1e-3, 1e-6}) {
      EXPECT_TRUE(checker.IsValid(Q(c.contact_q - d))) << d;
      EXPECT_NEAR(checker.Clearance(Q(c.contact_q - d)), c.distance(c.contact_q - d), 1e-9) << d;
    }
    // Touching counts as contact (FCL's sphere tests use <=).
    EXPECT_NEAR(checker.Clearance(Q(c.contact_q)), 0.0, 1e-9);
    for (double d : {1e-6, 0.02, 0.05}) {
      EXPECT_FALSE(checker.IsValid(Q(c.contact_q + d))) << d;
      EXPECT_EQ(checker.Clearance(Q(c.contact_q + d)), 0.0) << d;
      const CollisionResult r = checker.Check(Q(c.contact_q + d));
      EXPECT_TRUE(r.in_collision);
      EXPECT_FALSE(r.self_collision);
      EXPECT_EQ(r.link_a, "mover");
      EXPECT_EQ(r.other, "obstacle");
    }
  }
}

TEST_P(SphereVsPrimitive, PaddingGrowsTheRobot) {
  CollisionOptions options;
  options.force_fcl = GetParam();
  options.padding = 0.05;
  CollisionChecker checker(SliderRobot(Shape::Sphere(0.1)), OneObject(Shape::Box({0.2, 0.2, 0.2}, At(1, 0, 0))),
                           options);
  // Unpadded contact at q = 0.8; padded at q = 0.75.
  EXPECT_FALSE(checker.IsValid(Q(0.76)));
  EXPECT_TRUE(checker.IsValid(Q(0.74)));
  EXPECT_NEAR(checker.Clearance(Q(0.70)), 0.05, 1e-9);
}

INSTANTIATE_TEST_SUITE_P(BothPaths, SphereVsPrimitive, ::testing::Values(false, true));

TEST(FclPath, BoxLinkVsBox) {
  CollisionChecker checker(SliderRobot(Shape::Box({0.2, 0.2, 0.2})), OneObject(Shape::Box({0.2, 0.2, 0.2}, At(1, 0, 0))));
  EXPECT_FALSE(checker.uses_fast_path());
  EXPECT_TRUE(checker.IsValid(Q(0.7)));
  EXPECT_NEAR(checker.Clearance(Q(0.7)), 0.1, 1e-6);
  EXPECT_FALSE(checker.IsValid(Q(0.81)));
  EXPECT_EQ(checker.Clearance(Q(0.81)), 0.0);
}

TEST(FclPath, CylinderLinkVsSphere) {
  // Cylinder link (radius 0.05, axis z) against a sphere of radius 0.1 at x = 1.
  CollisionChecker checker(SliderRobot(Shape::Cylinder(0.05, 0.3)), OneObject(Shape::Sphere(0.1, At(1, 0, 0))));
  EXPECT_NEAR(checker.Clearance(Q(0.5)), 0.35, 1e-6);
  EXPECT_TRUE(checker.IsValid(Q(0.84)));
  EXPECT_FALSE(checker.IsValid(Q(0.86)));
}

std::string OneVoxelBt() {
  octomap::OcTree tree(0.1);
  tree.updateNode(octomap::point3d(1.05f, 0.05f, 0.05f), true);
  std::stringstream s;
  tree.writeBinary(s);
  return s.str();
}

TEST(OctoMap, OneOccupiedVoxelVsSphere) {
  // The voxel spans [1.0, 1.1] x [0, 0.1] x [0, 0.1]; the sphere (r = 0.1) centre is at
  // (q, 0.05, 0.05), so the distance is 0.9 - q.
  auto scene = std::make_shared<Scene>();
  scene->AddOctoMap("voxel", OneVoxelBt(), Eigen::Isometry3d::Identity(), "scene.octomaps[0].data");
  ASSERT_EQ(scene->occupancy_maps().size(), 1u);
  for (bool force_fcl : {true, false}) {
    SCOPED_TRACE(force_fcl);
    CollisionOptions options;
    options.force_fcl = force_fcl;
    CollisionChecker checker(SliderRobot(Shape::Sphere(0.1, At(0, 0.05, 0.05))), scene, options);
    EXPECT_TRUE(checker.IsValid(Q(0.85)));
    EXPECT_NEAR(checker.Clearance(Q(0.85)), 0.05, 1e-6);
    EXPECT_FALSE(checker.IsValid(Q(0.91)));
    EXPECT_EQ(checker.Check(Q(0.95)).other, "voxel");
    EXPECT_FALSE(checker.IsValid(Q(1.05)));  // centre inside the voxel
    EXPECT_TRUE(checker.IsValid(Q(1.25)));   // past it
  }
  // The map pose moves the voxel: shift by +1 m in x.
  auto moved = std::make_shared<Scene>();
  moved->AddOctoMap("voxel", OneVoxelBt(), At(1, 0, 0), "scene.octomaps[0].data");
  CollisionChecker checker(SliderRobot(Shape::Sphere(0.1, At(0, 0.05, 0.05))), moved);
  EXPECT_TRUE(checker.IsValid(Q(1.05)));
  EXPECT_FALSE(checker.IsValid(Q(2.05)));
}

TEST(Options, InvalidPaddingIsNamed) {
  CollisionOptions options;
  options.padding = -0.1;
  try {
    options.Validate();
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("padding"), std::string::npos) << e.what();
  }
}

TEST(Scene, InvalidDimensionsAndPosesAreNamed) {
  Scene scene;
  const auto expect_error = [&](const Shape& s, const std::string& needle) {
    try {
      scene.AddObject({"bad", s}, "scene.boxes[3]");
      FAIL() << "expected an Error for " << needle;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("scene.boxes[3]"), std::string::npos) << e.what();
    }
  };
  expect_error(Shape::Box({0.1, -0.2, 0.1}), "size[1] = -0.2");
  expect_error(Shape::Sphere(NAN), "radius = nan");
  expect_error(Shape::Cylinder(0.1, 0.0), "length = 0");
  expect_error(Shape::Capsule(0.0, 1.0), "radius = 0");
  Eigen::Isometry3d bad = Eigen::Isometry3d::Identity();
  bad.translation().x() = INFINITY;
  expect_error(Shape::Sphere(0.1, bad), "not finite");
  EXPECT_TRUE(scene.empty());
}

}  // namespace
}  // namespace chasles
