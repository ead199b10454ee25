// Issue 25, robots as people ship them: the mobile manipulator in examples/robots (a prismatic
// torso, three continuous roll joints, a published-style SRDF with stale entries) loads with
// warnings, and every trajectory the pipeline returns for it is free when re-checked
// independently — sampled so no joint moves more than 0.0005 (rad or m) between states, each
// state checked on the generic FCL path.

#include <algorithm>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "../budget_scale.h"
#include "../collision/test_util.h"
#include "../optimizers/test_util.h"
#include "chasles/pipeline/plan_pipeline.h"
#include "chasles/planners/registry.h"
#include "chasles/robot/error.h"
#include "dense_check.h"

namespace chasles {
namespace {

std::string Read(const std::string& name) { return test::ReadFile(test::ExamplePath("robots/" + name)); }

Eigen::VectorXd MobileManipulatorReady() {
  Eigen::VectorXd q(8);
  q << 0.2, 0.0, 0.3, 0.0, 1.0, 0.0, 0.6, 0.0;
  return q;
}

/// A table in front of the robot with a shelf board above it and a post beside it: the arm
/// reaches over the table, under the board and around the post.
std::shared_ptr<Scene> Workbench() {
  auto scene = std::make_shared<Scene>();
  const auto at = [](double x, double y, double z) {
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.translation() << x, y, z;
    return t;
  };
  scene->AddObject({"table", Shape::Box({0.6, 1.2, 0.04}, at(0.85, 0.0, 0.7))});
  scene->AddObject({"board", Shape::Box({0.4, 1.2, 0.02}, at(0.95, 0.0, 1.15))});
  scene->AddObject({"post", Shape::Cylinder(0.03, 1.2, at(0.6, 0.45, 0.6))});
  return scene;
}

TEST(ShippedRobots, MobileManipulatorLoadsWithItsStaleSrdfEntriesAsWarnings) {
  const std::string urdf = Read("mobile_manipulator.urdf");
  const std::string srdf = Read("mobile_manipulator.srdf");
  const auto robot = RobotModel::FromUrdf(urdf, srdf);
  ASSERT_EQ(robot->num_dofs(), 8);
  const auto& warnings = robot->load_warnings();
  const auto mentions = [&](const std::string& name) {
    return std::any_of(warnings.begin(), warnings.end(),
                       [&](const std::string& w) { return w.find("'" + name + "'") != std::string::npos; });
  };
  EXPECT_TRUE(mentions("bellows_link2"));
  EXPECT_TRUE(mentions("laser_link"));
  for (const std::string& w : warnings) std::printf("[ warning ] %s\n", w.c_str());
  // The joint kinds as described: a prismatic torso (metres), continuous rolls limited to ±π.
  const Joint& torso = robot->joints()[robot->dof_joint(0)];
  EXPECT_EQ(torso.type, JointType::kPrismatic);
  EXPECT_DOUBLE_EQ(robot->upper_limits()[0], 0.386);
  for (int d : {3, 5, 7}) {
    EXPECT_EQ(robot->joints()[robot->dof_joint(d)].type, JointType::kContinuous) << d;
    EXPECT_DOUBLE_EQ(robot->lower_limits()[d], -M_PI);
    EXPECT_DOUBLE_EQ(robot->upper_limits()[d], M_PI);
  }
  // strict_srdf: the first stale entry is an error naming it.
  try {
    RobotModel::FromUrdf(urdf, srdf, {}, {}, /*strict_srdf=*/true);
    ADD_FAILURE() << "strict_srdf accepted an SRDF naming links the URDF lacks";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("bellows_link2"), std::string::npos) << e.what();
  }
  // Free at zero and at 'ready' under its allowed pairs, on both collision paths.
  CollisionOptions fcl_options;
  fcl_options.force_fcl = true;
  const CollisionChecker spheres(robot, std::make_shared<Scene>());
  const CollisionChecker fcl(robot, std::make_shared<Scene>(), fcl_options);
  ASSERT_TRUE(spheres.certifies_motion());  // certified with a prismatic joint in every chain
  for (const Eigen::VectorXd& q : {Eigen::VectorXd(Eigen::VectorXd::Zero(8)), MobileManipulatorReady()}) {
    EXPECT_FALSE(spheres.Check(q).in_collision) << q.transpose();
    EXPECT_FALSE(fcl.Check(q).in_collision) << q.transpose();
  }
}

TEST(ShippedRobots, NoMobileManipulatorTrajectoryCollidesWhenCheckedDenselyOnFcl) {
  PlannerRegistry registry;
  RegisterDefaultPlanners(&registry);
  const PlanningPipeline pipeline(registry);
  const auto robot = RobotModel::FromUrdf(Read("mobile_manipulator.urdf"), Read("mobile_manipulator.srdf"));
  const auto scene = Workbench();
  const auto checker = std::make_shared<const CollisionChecker>(robot, scene);
  ASSERT_TRUE(checker->certifies_motion());
  CollisionOptions fcl_options;
  fcl_options.force_fcl = true;
  const CollisionChecker fcl(robot, scene, fcl_options);
  const int queries = std::max(4, test::TestCases(40));
  std::mt19937_64 rng(test::TestSeed());
  int solved = 0, dense_states = 0;
  double torso_travel = 0.0;
  for (int c = 0; c < queries; ++c) {
    PlanQuery query;
    query.checker = checker;
    query.start = test::ConfigurationNearObstacles(*checker, rng, 0.05, MobileManipulatorReady());
    do {
      query.goal = test::ConfigurationNearObstacles(*checker, rng, 0.05, MobileManipulatorReady());
    } while ((query.goal - query.start).cwiseAbs().maxCoeff() < 1.0);
    query.seed = 2000 + static_cast<std::uint64_t>(c);
    query.trajectory.max_deviation = 0.1;
    SCOPED_TRACE("query " + std::to_string(c));
    const PlanOutcome outcome = pipeline.Plan(query, Termination::After(std::chrono::duration<double>(test::Budget(2.0))));
    ASSERT_NE(outcome.code, PlanOutcomeCode::kVerificationFailed) << outcome.message;
    if (outcome.code != PlanOutcomeCode::kSuccess) continue;
    ++solved;
    EXPECT_EQ(outcome.verification.collision_guarantee, "certified");
    const test::DenseCheck dense = test::CheckDensely(outcome.trajectory, fcl, 0.0005);
    dense_states += dense.states;
    EXPECT_EQ(dense.colliding, 0) << dense.colliding << " of " << dense.states << " states collide, first at "
                                  << dense.first_contact;
    EXPECT_LE(outcome.quality.min_clearance, dense.min_clearance + 1e-9);
    for (std::size_t k = 1; k < outcome.path.size(); ++k) {
      torso_travel += std::abs(outcome.path[k][0] - outcome.path[k - 1][0]);
    }
  }
  std::printf("[ stats    ] %d of %d mobile manipulator queries solved; %d states re-checked on FCL; "
              "the torso travelled %.2f m in all\n",
              solved, queries, dense_states, torso_travel);
  EXPECT_GE(solved, queries * 9 / 10);
  EXPECT_GT(torso_travel, 0.0);  // the prismatic joint takes part in the plans
}

/// Plans between configurations near the obstacles of `scene` for `robot` (certified on its
/// spheres), with the robot's effort limits; every trajectory re-checked densely on FCL, every
/// sample's effort within the limits. Returns how far the gripper coordinates `grippers` moved
/// in all (they must be planned too, not only carried).
double PlanNearObstaclesAndRecheck(const std::shared_ptr<const RobotModel>& robot, std::shared_ptr<const Scene> scene,
                                   std::uint64_t seed_base, const std::vector<int>& grippers) {
  PlannerRegistry registry;
  RegisterDefaultPlanners(&registry);
  const PlanningPipeline pipeline(registry);
  const int n = robot->num_dofs();
  const auto checker = std::make_shared<const CollisionChecker>(robot, scene);
  EXPECT_TRUE(checker->certifies_motion());
  CollisionOptions fcl_options;
  fcl_options.force_fcl = true;
  const CollisionChecker fcl(robot, scene, fcl_options);
  const int queries = std::max(4, test::TestCases(10));
  std::mt19937_64 rng(test::TestSeed());
  int solved = 0;
  double gripper_travel = 0.0;
  for (int c = 0; c < queries; ++c) {
    PlanQuery query;
    query.checker = checker;
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(n);
    query.start = test::ConfigurationNearObstacles(*checker, rng, 0.05, zero);
    do {
      query.goal = test::ConfigurationNearObstacles(*checker, rng, 0.05, zero);
    } while ((query.goal - query.start).cwiseAbs().maxCoeff() < 1.0);
    query.seed = seed_base + static_cast<std::uint64_t>(c);
    query.trajectory.max_deviation = 0.1;
    query.trajectory.max_effort = robot->effort_limits();
    SCOPED_TRACE("query " + std::to_string(c));
    const PlanOutcome outcome = pipeline.Plan(query, Termination::After(std::chrono::duration<double>(test::Budget(2.0))));
    EXPECT_NE(outcome.code, PlanOutcomeCode::kVerificationFailed) << outcome.message;
    if (outcome.code != PlanOutcomeCode::kSuccess) continue;
    ++solved;
    EXPECT_EQ(outcome.verification.collision_guarantee, "certified");
    const test::DenseCheck dense = test::CheckDensely(outcome.trajectory, fcl, 0.0005);
    EXPECT_EQ(dense.colliding, 0) << dense.colliding << " of " << dense.states << " states collide, first at "
                                  << dense.first_contact;
    for (const TrajectorySample& sample : outcome.samples) {
      EXPECT_EQ(sample.effort.size(), n);
      for (int d = 0; d < n && d < sample.effort.size(); ++d) {
        EXPECT_LE(std::abs(sample.effort[d]), robot->effort_limits()[d] * (1.0 + 1e-6)) << robot->dof_names()[d];
      }
    }
    for (int g : grippers) gripper_travel += std::abs(outcome.goal[g] - query.start[g]);
  }
  std::printf("[ stats    ] %d of %d %s queries solved\n", solved, queries, robot->name().c_str());
  EXPECT_GE(solved, queries * 9 / 10);
  return gripper_travel;
}

TEST(ShippedRobots, DualArmWithMimicGrippersPlansAndNoTrajectoryCollidesOrExceedsItsEffort) {
  // examples/robots/dual_arm: 13 coordinates for 15 moving joints (each gripper's second finger
  // is a <mimic>), near a table and a post.
  const auto robot = RobotModel::FromUrdf(Read("dual_arm.urdf"), Read("dual_arm.srdf"));
  ASSERT_EQ(robot->num_dofs(), 13);
  auto scene = std::make_shared<Scene>();
  Eigen::Isometry3d at = Eigen::Isometry3d::Identity();
  at.translation() << 0.75, 0.0, 0.4;
  scene->AddObject({"table", Shape::Box({0.6, 1.2, 0.1}, at)});
  at.translation() << 0.55, 0.0, 0.75;
  scene->AddObject({"post", Shape::Cylinder(0.04, 0.6, at)});
  EXPECT_GT(PlanNearObstaclesAndRecheck(robot, scene, 3000, {6, 12}), 0.0);
}

TEST(ShippedRobots, Ur5WithAGripperPlansAndNoTrajectoryCollidesOrExceedsItsEffort) {
  // examples/robots/ur5_gripper: a 6-joint arm with a parallel gripper whose second finger is a
  // <mimic>: 7 coordinates, the SRDF's groups "manipulator" and "gripper".
  const auto robot = RobotModel::FromUrdf(Read("ur5_gripper.urdf"), Read("ur5_gripper.srdf"));
  ASSERT_EQ(robot->num_dofs(), 7);
  EXPECT_EQ(robot->dof_names()[6], "finger_joint");
  EXPECT_TRUE(robot->load_warnings().empty());
  const CollisionChecker alone(robot, std::make_shared<Scene>());
  EXPECT_TRUE(alone.IsValid(Eigen::VectorXd::Zero(7)));
  Eigen::VectorXd open = Eigen::VectorXd::Zero(7);
  open[6] = 0.04;
  EXPECT_TRUE(alone.IsValid(open));
  // The shelf of the mesh-robot bench: a table, a board over it, two posts.
  auto scene = std::make_shared<Scene>();
  const auto box = [&](const char* name, double sx, double sy, double sz, double x, double y, double z) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() << x, y, z;
    scene->AddObject({name, Shape::Box({sx, sy, sz}, pose)});
  };
  box("table", 0.6, 1.2, 0.04, 0.55, 0.0, -0.05);
  box("board", 0.35, 1.0, 0.02, 0.55, 0.0, 0.4);
  box("post_left", 0.04, 0.04, 0.8, 0.35, 0.45, 0.35);
  box("post_right", 0.04, 0.04, 0.8, 0.35, -0.45, 0.35);
  EXPECT_GT(PlanNearObstaclesAndRecheck(robot, scene, 5000, {6}), 0.0);
}

}  // namespace
}  // namespace chasles
