// Issue 25, item 5: a trajectory that fails the final dense verification is repaired before it
// is reported. The robot is a planar 2R arm made of boxes (so every check is discrete: the
// planner checks motions at the request's collision_resolution, the verification at 0.005 rad)
// and the obstacle a 2 mm plate along the x axis. At collision_resolution 0.1 the planner steps
// over the plate; the verification finds the contact; the pipeline must then replan the
// segments that collide and return a trajectory that is free when re-checked 10× denser than
// the verification — or, where no free path exists, VERIFICATION_FAILED naming what it tried.

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "../box_arm.h"
#include "dense_check.h"
#include "chasles/pipeline/plan_pipeline.h"
#include "chasles/planners/registry.h"

namespace chasles {
namespace {

using test::kBoxArmUrdf;

/// A 2 mm plate along the x axis, from r = `inner` to r = 2.1 m, 1 m tall.
std::shared_ptr<const Scene> Plate(double inner) {
  auto scene = std::make_shared<Scene>();
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d((inner + 2.1) / 2.0, 0.0, 0.0);
  scene->AddObject({"plate", Shape::Box({2.1 - inner, 0.002, 1.0}, pose)});
  return scene;
}

PlanQuery CrossingQuery(std::shared_ptr<const CollisionChecker> checker, std::uint64_t seed) {
  PlanQuery query;
  query.checker = std::move(checker);
  // Start and goal on either side of the plate, link 2 outstretched: the straight motion sweeps
  // link 2 through it between states 0.0975 rad apart.
  query.start = Eigen::Vector2d(-0.55, 0.0);
  query.goal = Eigen::Vector2d(0.62, 0.0);
  query.collision_resolution = 0.1;
  query.seed = seed;
  return query;
}

/// True when some segment of `path` collides at states 0.0005 rad apart.
bool PathCollidesDensely(const JointPath& path, const CollisionChecker& checker) {
  for (std::size_t k = 0; k + 1 < path.size(); ++k) {
    if (!checker.IsMotionValid(path[k], path[k + 1], 0.0005)) return true;
  }
  return false;
}

class VerificationRepair : public ::testing::Test {
 protected:
  VerificationRepair() : pipeline_(registry_) { RegisterDefaultPlanners(&registry_); }
  PlannerRegistry registry_;
  PlanningPipeline pipeline_;
  std::shared_ptr<const RobotModel> robot_ = RobotModel::FromUrdf(kBoxArmUrdf);
};

TEST_F(VerificationRepair, PathsThroughAThinPlateAreReplannedAndReturnedFree) {
  // With r >= 1.3 m blocked, folding link 2 (q2 ≈ 2) lets the arm pass under the plate.
  const auto checker = std::make_shared<const CollisionChecker>(robot_, Plate(1.3));
  ASSERT_FALSE(checker->certifies_motion());
  int repaired = 0;
  for (std::uint64_t seed = 1; seed <= 12; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const PlanOutcome out = pipeline_.Plan(CrossingQuery(checker, seed), Termination::After(std::chrono::seconds(5)));
    ASSERT_EQ(out.code, PlanOutcomeCode::kSuccess) << out.message;
    const test::DenseCheck dense = test::CheckDensely(out.trajectory, *checker, 0.0005);
    EXPECT_EQ(dense.colliding, 0) << dense.first_contact;
    if (!out.repair.attempted()) {
      EXPECT_FALSE(PathCollidesDensely(out.path, *checker));
      continue;
    }
    // The failure was the plate (the planner's path, or the shortcuts taken at the same coarse
    // resolution, crossed it).
    EXPECT_TRUE(out.repair.repaired) << out.repair.Describe();
    EXPECT_NE(out.repair.failure.find("'plate'"), std::string::npos) << out.repair.failure;
    EXPECT_FALSE(PathCollidesDensely(out.path, *checker));
    ASSERT_FALSE(out.repair.actions.empty());
    EXPECT_NE(out.repair.actions.back().find("replanned"), std::string::npos) << out.repair.Describe();
    EXPECT_NE(out.repair.actions.back().find("verified"), std::string::npos) << out.repair.Describe();
    EXPECT_NE(out.message.find("repaired after verification found"), std::string::npos) << out.message;
    EXPECT_GT(out.seconds.repair, 0.0);
    ++repaired;
  }
  std::printf("[ repair ] %d of 12 seeds stepped over the plate and were repaired\n", repaired);
  // The scene is built so that the coarse checks step over the plate; a test that never meets
  // the failure proves nothing.
  EXPECT_GE(repaired, 3);
}

TEST_F(VerificationRepair, WithNoFreePathTheOutcomeNamesEveryRepairTried) {
  // With r >= 0.9 m blocked, link 1 itself crosses the plate: start and goal are not connected.
  const auto checker = std::make_shared<const CollisionChecker>(robot_, Plate(0.9));
  int failed = 0;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    PlanQuery query = CrossingQuery(checker, seed);
    query.repair_budget = 0.3;
    const PlanOutcome out = pipeline_.Plan(query, Termination::After(std::chrono::seconds(1)));
    ASSERT_NE(out.code, PlanOutcomeCode::kSuccess) << "a trajectory through the plate was returned";
    EXPECT_TRUE(out.trajectory.empty());
    if (out.code != PlanOutcomeCode::kVerificationFailed) continue;  // the planner itself found nothing
    ++failed;
    EXPECT_FALSE(out.repair.repaired);
    ASSERT_FALSE(out.repair.actions.empty());
    EXPECT_NE(out.message.find("repairs tried: "), std::string::npos) << out.message;
    EXPECT_NE(out.message.find(out.repair.failure), std::string::npos) << out.message;
    // Replanning a segment that must cross the plate finds nothing within its budget.
    bool replanning_failed = false;
    for (const std::string& action : out.repair.actions) {
      replanning_failed |= action.find("found no path") != std::string::npos ||
                           action.find("replanning stopped") != std::string::npos;
    }
    EXPECT_TRUE(replanning_failed) << out.repair.Describe();
  }
  std::printf("[ repair ] %d of 6 seeds stepped over the plate; every repair failed as it must\n", failed);
  EXPECT_GE(failed, 2);
}

TEST_F(VerificationRepair, AFirstTrajectoryThatPassesIsNotRepaired) {
  const auto checker = std::make_shared<const CollisionChecker>(robot_, Plate(1.3));
  PlanQuery query = CrossingQuery(checker, 1);
  query.collision_resolution = 0.005;  // the planner checks as finely as the verification
  const PlanOutcome out = pipeline_.Plan(query, Termination::After(std::chrono::seconds(5)));
  ASSERT_EQ(out.code, PlanOutcomeCode::kSuccess) << out.message;
  EXPECT_FALSE(out.repair.attempted());
  EXPECT_TRUE(out.repair.actions.empty());
  EXPECT_EQ(out.seconds.repair, 0.0);
}

}  // namespace
}  // namespace chasles
