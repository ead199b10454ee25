// Issue 16, "certified end to end": every trajectory the pipeline returns on the sphere path is
// free along its continuous motion. Seeded Panda queries whose starts and goals lie close to
// obstacles (the shelf, the cage, and a ring of posts with narrow gaps) are planned through
// PlanningPipeline; each returned TimedTrajectory is then re-checked independently: sampled so
// no joint moves more than 0.0005 rad between states, every state checked by a checker built on
// the generic FCL path (CollisionOptions::force_fcl), an implementation separate from the sphere
// path that certified it. No state may collide, and the reported min_clearance (a lower bound
// on the continuous minimum) may not exceed the smallest FCL clearance found.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "../budget_scale.h"
#include "../collision/test_util.h"
#include "../optimizers/test_util.h"
#include "dense_check.h"
#include "chasles/pipeline/plan_pipeline.h"
#include "chasles/planners/registry.h"

namespace chasles {
namespace {

/// A ring of eight thin posts around the Panda at 0.5 m with a low bar in front: gaps between
/// posts of about 0.35 m, so arms reaching between them pass close to two posts at once.
std::shared_ptr<Scene> PostRing() {
  auto scene = std::make_shared<Scene>();
  for (int k = 0; k < 8; ++k) {
    const double angle = k * M_PI / 4.0 + M_PI / 8.0;
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = Eigen::Vector3d(0.5 * std::cos(angle), 0.5 * std::sin(angle), 0.6);
    scene->AddObject({"post_" + std::to_string(k), Shape::Box({0.04, 0.04, 1.2}, pose)});
  }
  Eigen::Isometry3d bar = Eigen::Isometry3d::Identity();
  bar.translation() = Eigen::Vector3d(0.45, 0.0, 0.3);
  scene->AddObject({"bar", Shape::Cylinder(0.015, 0.5, bar * Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()))});
  return scene;
}

/// States the verification before issue 16 checked: every 0.005 rad of each piece, both ends.
int DiscreteStates(const TimedTrajectory& trajectory) {
  int states = 1;
  for (const TimedTrajectory::Piece& piece : trajectory.pieces()) {
    states += std::max(1, static_cast<int>(std::ceil(piece.MaxJointTravel() / 0.005)));
  }
  return states;
}

struct Case {
  const char* scene;
  std::shared_ptr<const Scene> obstacles;
  PostProcessing method;
};

TEST(CertifiedEndToEnd, NoReturnedPandaTrajectoryPenetratesWhenCheckedDenselyOnFcl) {
  PlannerRegistry registry;
  RegisterDefaultPlanners(&registry);
  const PlanningPipeline pipeline(registry);
  const auto panda = test::LoadRobot("panda");
  const std::vector<std::pair<const char*, std::shared_ptr<const Scene>>> scenes = {
      {"shelf", test::LoadScene("scenes/shelf.json")},
      {"cage", test::LoadScene("scenes/cage.json")},
      {"post ring", PostRing()},
  };
  const int per_scene = std::max(1, test::TestCases(24 * 20) / 20);
  std::mt19937_64 rng(test::TestSeed());
  int solved = 0, queries = 0, certified_states = 0, discrete_states = 0, tightened = 0;
  double verify_seconds = 0.0, parameterize_seconds = 0.0;
  double worst_gap = 0.0;  // largest dense-minimum minus reported min_clearance [m]
  for (const auto& [name, scene] : scenes) {
    const auto checker = std::make_shared<const CollisionChecker>(panda, scene);
    ASSERT_TRUE(checker->certifies_motion()) << name;
    CollisionOptions fcl_options;
    fcl_options.force_fcl = true;
    const CollisionChecker fcl(panda, scene, fcl_options);
    ASSERT_FALSE(fcl.certifies_motion());
    for (int c = 0; c < per_scene; ++c) {
      PlanQuery query;
      query.checker = checker;
      query.start = test::ConfigurationNearObstacles(*checker, rng, 0.03, test::PandaReady());
      do {
        query.goal = test::ConfigurationNearObstacles(*checker, rng, 0.03, test::PandaReady());
      } while ((query.goal - query.start).cwiseAbs().maxCoeff() < 1.0);
      query.seed = 1000 + static_cast<std::uint64_t>(c);
      // Mostly the time-optimal blends (tightest near the obstacles), some spline smoothing.
      query.trajectory.method = c % 8 == 7 ? PostProcessing::kSpline : PostProcessing::kTimeOptimal;
      query.trajectory.max_deviation = 0.1;
      query.trajectory.spline.time_budget = test::Budget(1.0);
      ++queries;
      SCOPED_TRACE(std::string(name) + " query " + std::to_string(c));
      const PlanOutcome outcome = pipeline.Plan(query, Termination::After(std::chrono::duration<double>(test::Budget(2.0))));
      ASSERT_NE(outcome.code, PlanOutcomeCode::kVerificationFailed) << outcome.message;
      if (outcome.code != PlanOutcomeCode::kSuccess) continue;
      ++solved;
      EXPECT_EQ(outcome.verification.collision_guarantee, "certified");
      EXPECT_EQ(outcome.verification.collision_guarantee_reason, "");
      certified_states += outcome.verification.states_checked;
      discrete_states += DiscreteStates(outcome.trajectory);
      tightened += outcome.optimizer.time_optimal.blends_tightened;
      verify_seconds += outcome.seconds.verify;
      parameterize_seconds += outcome.seconds.parameterize;

      const test::DenseCheck dense = test::CheckDensely(outcome.trajectory, fcl, 0.0005);
      EXPECT_EQ(dense.colliding, 0) << dense.colliding << " of " << dense.states << " states collide, first at "
                                    << dense.first_contact;
      // min_clearance bounds the continuous minimum from below; the dense FCL minimum is at or
      // above that minimum (rounding of the two distance computations: 1e-9 m).
      EXPECT_LE(outcome.quality.min_clearance, dense.min_clearance + 1e-9);
      EXPECT_GE(outcome.quality.min_clearance, 0.0);
      worst_gap = std::max(worst_gap, dense.min_clearance - outcome.quality.min_clearance);
    }
  }
  std::printf("[ stats    ] %d of %d queries solved; collision states: %d certified vs %d at 0.005 rad (%.2fx); "
              "%d blends tightened; min_clearance at most %.3g m below the dense FCL minimum; "
              "parameterize %.3f s, verify %.3f s in all\n",
              solved, queries, certified_states, discrete_states,
              discrete_states > 0 ? static_cast<double>(certified_states) / discrete_states : 0.0, tightened,
              worst_gap, parameterize_seconds, verify_seconds);
  EXPECT_GE(solved, std::min(60, queries * 9 / 10));
}

}  // namespace
}  // namespace chasles
