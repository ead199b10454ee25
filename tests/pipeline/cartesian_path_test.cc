// Cartesian moves (ComputeCartesianPath) against checks written here: the link's position on the
// commanded segment by a projection formula, its orientation by Eigen's quaternion slerp, and
// collisions by a second checker (the generic FCL path) at 0.001 rad joint steps.

#include <cmath>
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "../collision/test_util.h"
#include "chasles/pipeline/cartesian_path.h"
#include "chasles/robot/error.h"

namespace chasles {
namespace {

struct Arm {
  std::shared_ptr<const RobotModel> robot = test::LoadRobot("panda");
  int tcp = robot->FindLink("panda_tcp");
  Eigen::Isometry3d Pose(const Eigen::VectorXd& q) const {
    std::vector<Eigen::Isometry3d> poses;
    robot->ForwardKinematics(q, &poses);
    return poses[static_cast<std::size_t>(tcp)];
  }
};

std::shared_ptr<const CollisionChecker> CheckerFor(const Arm& arm, std::shared_ptr<const Scene> scene, bool fcl = false) {
  CollisionOptions options;
  options.force_fcl = fcl;
  return std::make_shared<CollisionChecker>(arm.robot, std::move(scene), options);
}

/// Distance from p to the segment a–b, and the parameter of the nearest point.
double SegmentDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double* u) {
  const Eigen::Vector3d d = b - a;
  *u = std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
  return (p - (a + *u * d)).norm();
}

/// Every state 0.001 rad apart along the joint path, on `checker`: how many collide.
int DenseCollisions(const JointPath& path, const CollisionChecker& checker) {
  int colliding = 0;
  for (std::size_t s = 0; s + 1 < path.size(); ++s) {
    const int n = std::max(1, static_cast<int>(std::ceil((path[s + 1] - path[s]).cwiseAbs().maxCoeff() / 0.001)));
    for (int i = 0; i <= n; ++i) colliding += checker.Check(path[s] + (path[s + 1] - path[s]) * (double(i) / n)).in_collision;
  }
  return colliding;
}

CartesianSpec LineSpec(const Arm& arm, const Eigen::Isometry3d& goal) {
  CartesianSpec spec;
  spec.link = arm.tcp;
  spec.waypoints = {goal};
  return spec;
}

TEST(CartesianPath, FollowsTheLineAndTurnsAlongTheSlerp) {
  const Arm arm;
  const auto checker = CheckerFor(arm, std::make_shared<Scene>());
  const Eigen::VectorXd start = test::PandaReady();
  const Eigen::Isometry3d a = arm.Pose(start);
  Eigen::Isometry3d b = a;
  b.translation() += Eigen::Vector3d(0.05, 0.25, -0.15);
  b.linear() = a.linear() * Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.2, 0.3, 1.0).normalized()).toRotationMatrix();
  const CartesianSpec spec = LineSpec(arm, b);
  const CartesianPathResult r = ComputeCartesianPath(*checker, start, spec);
  ASSERT_EQ(r.stop, CartesianStop::kComplete) << r.message;
  EXPECT_EQ(r.fraction, 1.0);
  EXPECT_EQ(r.waypoints_reached, 1);
  EXPECT_EQ(static_cast<int>(r.path.size()), r.steps + 1);
  EXPECT_GE(r.steps, static_cast<int>(std::ceil(0.3 / spec.max_step)));  // |Δp| ≈ 0.30 m
  const Eigen::Quaterniond qa(a.linear()), qb(b.linear());
  double worst_position = 0.0, worst_orientation = 0.0, worst_between = 0.0;
  for (std::size_t s = 0; s < r.path.size(); ++s) {
    const Eigen::Isometry3d x = arm.Pose(r.path[s]);
    double u = 0.0;
    worst_position = std::max(worst_position, SegmentDistance(x.translation(), a.translation(), b.translation(), &u));
    // The orientation where the position is along the line (both move by the same fraction).
    const Eigen::Quaterniond expected = qa.slerp(u, qb);
    worst_orientation = std::max(worst_orientation, expected.angularDistance(Eigen::Quaterniond(x.linear())));
    if (s + 1 < r.path.size()) {
      // Densely between states: the link stays near the line.
      for (int i = 1; i < 20; ++i) {
        const Eigen::VectorXd q = r.path[s] + (r.path[s + 1] - r.path[s]) * (i / 20.0);
        double v = 0.0;
        worst_between = std::max(worst_between, SegmentDistance(arm.Pose(q).translation(), a.translation(), b.translation(), &v));
      }
    }
  }
  EXPECT_LE(worst_position, spec.position_tolerance + 1e-9);
  EXPECT_LE(worst_orientation, 2.0 * spec.orientation_tolerance);
  EXPECT_LT(worst_between, 5e-4) << "the link leaves the line between states";
  EXPECT_LE(r.max_line_deviation, worst_between + 1e-4);  // the reported figure is of the same kind
  EXPECT_LE(r.max_position_error, spec.position_tolerance);
  // The last state is the waypoint (within the tolerances).
  EXPECT_LE((arm.Pose(r.path.back()).translation() - b.translation()).norm(), spec.position_tolerance);
}

TEST(CartesianPath, AStepThatStraysFromTheLineIsSplit) {
  const Arm arm;
  const auto checker = CheckerFor(arm, std::make_shared<Scene>());
  const Eigen::VectorXd start = test::PandaReady();
  const Eigen::Isometry3d a = arm.Pose(start);
  Eigen::Isometry3d b = a;
  b.translation() += Eigen::Vector3d(0.0, 0.4, -0.2);
  CartesianSpec spec = LineSpec(arm, b);
  spec.max_step = 0.1;  // long steps: the link bows away from the line between states
  spec.max_joint_jump = 1.0;
  spec.line_tolerance = 0.1;
  const CartesianPathResult loose = ComputeCartesianPath(*checker, start, spec);
  ASSERT_EQ(loose.stop, CartesianStop::kComplete) << loose.message;
  ASSERT_EQ(static_cast<int>(loose.path.size()), loose.steps + 1);
  spec.line_tolerance = 1e-4;
  const CartesianPathResult tight = ComputeCartesianPath(*checker, start, spec);
  ASSERT_EQ(tight.stop, CartesianStop::kComplete) << tight.message;
  EXPECT_EQ(tight.steps, loose.steps);
  EXPECT_EQ(tight.fraction, 1.0);
  EXPECT_GT(tight.path.size(), loose.path.size());
  // Densely, 50 points between states, against the line (projection written here).
  const auto farthest = [&](const JointPath& path) {
    double worst = 0.0, u = 0.0;
    for (std::size_t s = 0; s + 1 < path.size(); ++s) {
      for (int i = 0; i <= 50; ++i) {
        const Eigen::VectorXd q = path[s] + (path[s + 1] - path[s]) * (i / 50.0);
        worst = std::max(worst, SegmentDistance(arm.Pose(q).translation(), a.translation(), b.translation(), &u));
      }
    }
    return worst;
  };
  EXPECT_GT(farthest(loose.path), 1e-3) << "the long steps should stray (else this test shows nothing)";
  EXPECT_LT(farthest(tight.path), 1.5e-4);
  EXPECT_LE(tight.max_line_deviation, 1e-4);
}

TEST(CartesianPath, PassesThroughEveryWaypointInOrder) {
  const Arm arm;
  const auto checker = CheckerFor(arm, std::make_shared<Scene>());
  const Eigen::VectorXd start = test::PandaReady();
  const Eigen::Isometry3d a = arm.Pose(start);
  CartesianSpec spec = LineSpec(arm, a);
  spec.waypoints.clear();
  for (const Eigen::Vector3d& d : {Eigen::Vector3d(0.0, 0.15, 0.0), Eigen::Vector3d(0.0, 0.15, -0.15),
                                  Eigen::Vector3d(0.0, -0.1, -0.15)}) {
    Eigen::Isometry3d w = a;
    w.translation() += d;
    spec.waypoints.push_back(w);
  }
  const CartesianPathResult r = ComputeCartesianPath(*checker, start, spec);
  ASSERT_EQ(r.stop, CartesianStop::kComplete) << r.message;
  EXPECT_EQ(r.waypoints_reached, 3);
  // Each waypoint is hit by some state, in order.
  std::size_t s = 0;
  for (std::size_t w = 0; w < spec.waypoints.size(); ++w) {
    while (s < r.path.size() && (arm.Pose(r.path[s]).translation() - spec.waypoints[w].translation()).norm() > 1e-4) ++s;
    EXPECT_LT(s, r.path.size()) << "waypoint " << w << " is not reached in order";
  }
}

TEST(CartesianPath, StopsBeforeAnObstacleOnTheLineAndGoesThroughItWhenCollisionsAreIgnored) {
  const Arm arm;
  const Eigen::VectorXd start = test::PandaReady();
  const Eigen::Isometry3d a = arm.Pose(start);
  Eigen::Isometry3d b = a;
  b.translation() += Eigen::Vector3d(0.0, 0.3, 0.0);
  auto scene = std::make_shared<Scene>();
  Eigen::Isometry3d wall = Eigen::Isometry3d::Identity();
  wall.translation() = a.translation() + Eigen::Vector3d(0.0, 0.15, 0.0);
  scene->AddObject({"wall", Shape::Box({0.3, 0.02, 0.3}, wall)});
  const auto checker = CheckerFor(arm, scene);
  const auto fcl = CheckerFor(arm, scene, /*fcl=*/true);
  CartesianSpec spec = LineSpec(arm, b);
  const CartesianPathResult r = ComputeCartesianPath(*checker, start, spec);
  EXPECT_EQ(r.stop, CartesianStop::kCollision) << r.message;
  EXPECT_GT(r.fraction, 0.0);
  EXPECT_LT(r.fraction, 0.5);
  EXPECT_NE(r.message.find("waypoints[0]"), std::string::npos) << r.message;
  EXPECT_EQ(DenseCollisions(r.path, *fcl), 0);
  spec.check_collisions = false;
  const CartesianPathResult blind = ComputeCartesianPath(*checker, start, spec);
  EXPECT_EQ(blind.stop, CartesianStop::kComplete) << blind.message;
  EXPECT_GT(DenseCollisions(blind.path, *fcl), 0) << "the ignored wall is on the line";
}

TEST(CartesianPath, ReportsWhereThePathEnds) {
  const Arm arm;
  const auto checker = CheckerFor(arm, std::make_shared<Scene>());
  const Eigen::VectorXd start = test::PandaReady();
  const Eigen::Isometry3d a = arm.Pose(start);
  {  // out of reach: the path goes as far as the arm does
    Eigen::Isometry3d far = a;
    far.translation() += Eigen::Vector3d(1.5, 0.0, 0.0);
    CartesianSpec spec = LineSpec(arm, far);
    spec.max_joint_jump = 6.0;  // (the joints speed up as the arm straightens: the jump test ends it first)
    const CartesianPathResult r = ComputeCartesianPath(*checker, start, spec);
    EXPECT_EQ(r.stop, CartesianStop::kUnreachable) << r.message;
    EXPECT_GT(r.fraction, 0.0);
    EXPECT_LT(r.fraction, 1.0);
    EXPECT_EQ(r.waypoints_reached, 0);
    EXPECT_NE(r.message.find("waypoints[0], step"), std::string::npos) << r.message;
    EXPECT_GT(r.path.size(), 1u);
  }
  {  // a joint may not move more than max_joint_jump per step
    Eigen::Isometry3d b = a;
    b.translation() += Eigen::Vector3d(0.0, 0.2, 0.0);
    CartesianSpec spec = LineSpec(arm, b);
    spec.max_step = 0.05;
    spec.max_joint_jump = 0.01;
    const CartesianPathResult r = ComputeCartesianPath(*checker, start, spec);
    EXPECT_EQ(r.stop, CartesianStop::kJointJump) << r.message;
    EXPECT_EQ(r.path.size(), 1u);
    EXPECT_EQ(r.fraction, 0.0);
    EXPECT_NE(r.message.find("max_joint_jump 0.01"), std::string::npos) << r.message;
    // MoveIt's relative test: 1 × the mean step ends the path at the first step above the mean.
    spec.max_joint_jump = 0.5;
    spec.max_step = 0.01;
    spec.jump_threshold = 1.0;
    const CartesianPathResult relative = ComputeCartesianPath(*checker, start, spec);
    EXPECT_EQ(relative.stop, CartesianStop::kRelativeJump) << relative.message;
    EXPECT_LT(relative.fraction, 1.0);
    EXPECT_GT(relative.path.size(), 1u);
  }
  {  // a start in collision
    auto scene = std::make_shared<Scene>();
    scene->AddObject({"block", Shape::Box({0.2, 0.2, 0.2}, a)});
    const auto blocked = CheckerFor(arm, scene);
    const CartesianPathResult r = ComputeCartesianPath(*blocked, start, LineSpec(arm, a));
    EXPECT_EQ(r.stop, CartesianStop::kStartInvalid);
    EXPECT_EQ(r.fraction, 0.0);
    EXPECT_NE(r.message.find("block"), std::string::npos) << r.message;
  }
}

TEST(CartesianPath, NamesTheFieldOfAnInvalidSpec) {
  const Arm arm;
  const auto checker = CheckerFor(arm, std::make_shared<Scene>());
  const Eigen::VectorXd start = test::PandaReady();
  const CartesianSpec good = LineSpec(arm, arm.Pose(start));
  const auto message = [&](const CartesianSpec& spec, const Eigen::VectorXd& q) {
    try {
      ComputeCartesianPath(*checker, q, spec);
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CartesianSpec s = good;
  s.max_step = 0.0;
  EXPECT_EQ(message(s, start), "max_step = 0 must be within [0.0001, 0.5]");
  s = good;
  s.waypoints.front().translation().x() = std::nan("");
  EXPECT_EQ(message(s, start), "waypoints[0] must be finite");
  s = good;
  s.waypoints.front().linear() *= 2.0;
  EXPECT_EQ(message(s, start), "waypoints[0].orientation must be a rotation (a unit quaternion)");
  s = good;
  s.waypoints.clear();
  EXPECT_EQ(message(s, start), "waypoints: a Cartesian move needs at least one waypoint");
  s = good;
  s.jump_threshold = 0.5;
  EXPECT_EQ(message(s, start), "jump_threshold = 0.5 must be 0 (off) or a finite value >= 1");
  s = good;
  s.line_tolerance = 0.5;
  EXPECT_EQ(message(s, start), "line_tolerance = 0.5 must be within [1e-05, 0.1]");
  s = good;
  s.link = 99;
  EXPECT_EQ(message(s, start), "link = 99 is not a link of robot 'panda'");
  Eigen::VectorXd bad = start;
  bad[3] = std::nan("");
  EXPECT_NE(message(good, bad).find("start.positions[3]"), std::string::npos) << message(good, bad);
}

}  // namespace
}  // namespace chasles
