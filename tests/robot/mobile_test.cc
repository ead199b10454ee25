// Mobile robots (robot/mobile.h): the chain of coordinate joints places the body exactly at the
// SE(2) / SE(3) pose the coordinates describe, limits come from the description, and malformed
// descriptions get named errors.

#include <cmath>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "chasles/robot/mobile.h"
#include "test_util.h"

namespace chasles {
namespace {

constexpr double kPi = 3.14159265358979323846;

MobileDescription Base(RobotKind kind) {
  MobileDescription d;
  d.name = "mover";
  d.kind = kind;
  d.workspace_min = Eigen::Vector3d(-1, -2, 0.5);
  d.workspace_max = Eigen::Vector3d(8, 9, 3.5);
  d.turning_radius = 0.7;
  d.linear_velocity = 1.5;
  d.angular_velocity = 2.0;
  Eigen::Isometry3d front = Eigen::Isometry3d::Identity();
  front.translation() = Eigen::Vector3d(0.3, 0, 0.2);
  d.body.collision = {Shape::Sphere(0.2, front)};
  return d;
}

TEST(MobileRobotTest, PlanarBodyPoseIsTheSe2Pose) {
  const auto robot = RobotFromMobile(Base(RobotKind::kPlanar));
  EXPECT_EQ(robot->kind(), RobotKind::kPlanar);
  ASSERT_EQ(robot->num_dofs(), 3);
  EXPECT_EQ(robot->dof_names(), (std::vector<std::string>{"x", "y", "theta"}));
  EXPECT_EQ(robot->lower_limits(), Eigen::Vector3d(-1, -2, -kPi));
  EXPECT_EQ(robot->upper_limits(), Eigen::Vector3d(8, 9, kPi));
  EXPECT_EQ(robot->velocity_limits(), Eigen::Vector3d(1.5, 1.5, 2.0));
  const int body = robot->FindLink("body");
  ASSERT_GE(body, 0);
  std::vector<Eigen::Isometry3d> poses;
  for (const Eigen::Vector3d q : {Eigen::Vector3d(1, 2, 0.3), Eigen::Vector3d(-0.5, 7, -2.9)}) {
    robot->ForwardKinematics(q, &poses);
    const Eigen::Isometry3d expected =
        Eigen::Translation3d(q[0], q[1], 0) * Eigen::AngleAxisd(q[2], Eigen::Vector3d::UnitZ());
    EXPECT_TRUE(poses[body].isApprox(expected, 1e-12)) << poses[body].matrix();
  }
}

TEST(MobileRobotTest, CarsKeepTheirTurningRadiusAndAnUnwrappedHeadingRange) {
  for (RobotKind kind : {RobotKind::kDubinsCar, RobotKind::kReedsSheppCar}) {
    const auto robot = RobotFromMobile(Base(kind));
    EXPECT_EQ(robot->kind(), kind);
    EXPECT_TRUE(IsCar(robot->kind()));
    EXPECT_EQ(robot->motion().turning_radius, 0.7);
    EXPECT_EQ(robot->lower_limits()[2], -8 * kPi);
    EXPECT_EQ(robot->upper_limits()[2], 8 * kPi);
  }
}

TEST(MobileRobotTest, FreeFlyerBodyPoseIsZyxEuler) {
  MobileDescription d = Base(RobotKind::kFreeFlyer);
  d.max_tilt = 0.6;
  const auto robot = RobotFromMobile(d);
  ASSERT_EQ(robot->num_dofs(), 6);
  EXPECT_EQ(robot->dof_names(), (std::vector<std::string>{"x", "y", "z", "yaw", "pitch", "roll"}));
  EXPECT_EQ(robot->lower_limits()[2], 0.5);
  EXPECT_EQ(robot->upper_limits()[2], 3.5);
  EXPECT_EQ(robot->lower_limits()[4], -0.6);
  EXPECT_EQ(robot->upper_limits()[5], 0.6);
  const int body = robot->FindLink("body");
  std::vector<Eigen::Isometry3d> poses;
  Eigen::VectorXd q(6);
  q << 1, 2, 3, 2.5, -0.4, 0.3;
  robot->ForwardKinematics(q, &poses);
  const Eigen::Isometry3d expected = Eigen::Translation3d(1, 2, 3) * Eigen::AngleAxisd(2.5, Eigen::Vector3d::UnitZ()) *
                                     Eigen::AngleAxisd(-0.4, Eigen::Vector3d::UnitY()) *
                                     Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX());
  EXPECT_TRUE(poses[body].isApprox(expected, 1e-12));
  // The chained URDF-style FK agrees with the PoE form.
  std::vector<Eigen::Isometry3d> chained;
  robot->ForwardKinematicsByChaining(q, &chained);
  EXPECT_TRUE(chained[body].isApprox(poses[body], 1e-12));
}

TEST(MobileRobotTest, MalformedDescriptionsGetNamedErrors) {
  using testing::ExpectInvalid;
  MobileDescription d = Base(RobotKind::kPlanar);
  d.workspace_min.x() = 9;
  ExpectInvalid([&] { RobotFromMobile(d); }, "mobile.workspace_min.x = 9 must be < workspace_max.x = 8");
  d = Base(RobotKind::kDubinsCar);
  d.turning_radius = 0;
  ExpectInvalid([&] { RobotFromMobile(d); }, "mobile.turning_radius = 0 must be > 0 and finite");
  d = Base(RobotKind::kFreeFlyer);
  d.max_tilt = 1.6;
  ExpectInvalid([&] { RobotFromMobile(d); }, "mobile.max_tilt = 1.6 must be within (0, 1.5] rad");
  d = Base(RobotKind::kPlanar);
  d.body.collision.clear();
  ExpectInvalid([&] { RobotFromMobile(d); }, "mobile.body has no collision geometry");
  d = Base(RobotKind::kArm);
  ExpectInvalid([&] { RobotFromMobile(d); },
                "mobile.kind must be planar, dubins_car, reeds_shepp_car or free_flyer (got arm)");
  d = Base(RobotKind::kPlanar);
  d.linear_velocity = std::nan("");
  ExpectInvalid([&] { RobotFromMobile(d); }, "mobile.linear_velocity = nan must be > 0 and finite");
}

}  // namespace
}  // namespace chasles
