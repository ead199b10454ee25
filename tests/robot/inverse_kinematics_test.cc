// Inverse kinematics: success rate on random reachable poses (every solution checked by FK
// here), unreachable targets, distinct solutions, `accept`, determinism, and validation.
#include "chasles/robot/inverse_kinematics.h"

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "chasles/robot/lie_group.h"
#include "test_util.h"

namespace chasles {
namespace {

using testing::RandomConfiguration;
using testing::TestCases;
using testing::TestSeed;
using testing::Uniform;
using testing::ExpectInvalid;
using testing::LoadExampleRobot;



Eigen::Isometry3d LinkPose(const RobotModel& robot, const Eigen::VectorXd& q, int link) {
  std::vector<Eigen::Isometry3d> poses;
  robot.ForwardKinematics(q, &poses);
  return poses[link];
}

/// Checks a returned solution independently: size, limits, and both tolerances by FK.
::testing::AssertionResult IsValidSolution(const RobotModel& robot, const IkRequest& request,
                                           const Eigen::VectorXd& q) {
  if (q.size() != robot.num_dofs()) return ::testing::AssertionFailure() << "wrong size";
  for (int i = 0; i < q.size(); ++i) {
    if (!(q[i] >= robot.lower_limits()[i] && q[i] <= robot.upper_limits()[i])) {
      return ::testing::AssertionFailure() << "q[" << i << "] = " << q[i] << " outside limits";
    }
  }
  const Eigen::Isometry3d T = LinkPose(robot, q, request.link);
  const double pe = (T.translation() - request.target.translation()).norm();
  // Orientation error independently of LogSO3: angle from the trace.
  const double c = ((T.linear().transpose() * request.target.linear()).trace() - 1.0) / 2.0;
  const double oe = std::acos(std::min(1.0, std::max(-1.0, c)));
  if (pe > request.position_tolerance) return ::testing::AssertionFailure() << "position error " << pe;
  if (oe > request.orientation_tolerance + 1e-7) {  // acos is inaccurate near 0 (≈1e-8)
    return ::testing::AssertionFailure() << "orientation error " << oe;
  }
  return ::testing::AssertionSuccess();
}

struct RobotCase {
  const char* name;
  const char* tip;
};

class IkSuccessRateTest : public ::testing::TestWithParam<RobotCase> {};

TEST_P(IkSuccessRateTest, RandomReachablePoses) {
  const auto robot = LoadExampleRobot(GetParam().name);
  const int link = robot->FindLink(GetParam().tip);
  ASSERT_GE(link, 0);
  std::mt19937_64 rng(TestSeed(7u));
  const int cases = TestCases(1000);
  int successes = 0;
  for (int i = 0; i < cases; ++i) {
    IkRequest request;
    request.link = link;
    request.target = LinkPose(*robot, RandomConfiguration(*robot, rng), link);
    request.seed = rng();
    const IkResult result = SolveIk(*robot, request);
    if (result.status == IkStatus::kSuccess) {
      ++successes;
      ASSERT_EQ(result.solutions.size(), 1u);
      ASSERT_TRUE(IsValidSolution(*robot, request, result.solutions[0])) << "case " << i;
      EXPECT_TRUE(result.message.empty());
      EXPECT_LE(result.best_position_error, request.position_tolerance);
    } else {
      EXPECT_EQ(result.status, IkStatus::kNoSolution);
      EXPECT_TRUE(result.solutions.empty());
      EXPECT_FALSE(result.message.empty());
    }
    EXPECT_GE(result.attempts, 1);
  }
  const double rate = static_cast<double>(successes) / cases;
  RecordProperty("success_rate", std::to_string(rate));
  EXPECT_GE(rate, 0.995) << successes << " of " << cases;
}

TEST_P(IkSuccessRateTest, NewtonRaphsonAlsoSolves) {
  const auto robot = LoadExampleRobot(GetParam().name);
  const int link = robot->FindLink(GetParam().tip);
  std::mt19937_64 rng(TestSeed(7u) + 1);
  const int cases = std::max(1, TestCases(1000) / 5);
  int successes = 0;
  for (int i = 0; i < cases; ++i) {
    IkRequest request;
    request.link = link;
    request.method = IkMethod::kNewtonRaphson;
    request.target = LinkPose(*robot, RandomConfiguration(*robot, rng), link);
    const IkResult result = SolveIk(*robot, request);
    if (result.status == IkStatus::kSuccess) {
      ++successes;
      ASSERT_TRUE(IsValidSolution(*robot, request, result.solutions[0])) << "case " << i;
    }
  }
  EXPECT_GE(static_cast<double>(successes) / cases, 0.99) << successes << " of " << cases;
}

INSTANTIATE_TEST_SUITE_P(ExampleRobots, IkSuccessRateTest,
                         ::testing::Values(RobotCase{"ur5", "tool0"}, RobotCase{"panda", "panda_tcp"}),
                         [](const ::testing::TestParamInfo<RobotCase>& info) {
                           return std::string(info.param.name);
                         });

TEST(IkTest, UnreachablePoseIsNoSolutionWithReason) {
  const auto robot = LoadExampleRobot("ur5");
  IkRequest request;
  request.link = robot->FindLink("tool0");
  request.target.translation() << 2.0, 0.0, 0.3;  // the UR5 reaches about 0.95 m
  request.time_budget = 0.01;
  const IkResult result = SolveIk(*robot, request);
  EXPECT_EQ(result.status, IkStatus::kNoSolution);
  EXPECT_TRUE(result.solutions.empty());
  EXPECT_GT(result.attempts, 1);
  EXPECT_GT(result.best_position_error, 0.5);
  EXPECT_NE(result.message.find("no solution within 0.01 s ("), std::string::npos) << result.message;
  EXPECT_NE(result.message.find("best position error"), std::string::npos) << result.message;
  EXPECT_NE(result.message.find("out of reach"), std::string::npos) << result.message;
  EXPECT_GE(result.seconds, 0.01);
}

TEST(IkTest, SeveralDistinctUr5Solutions) {
  const auto robot = LoadExampleRobot("ur5");
  IkRequest request;
  request.link = robot->FindLink("tool0");
  Eigen::VectorXd q(6);
  q << 0.4, -1.2, 1.3, -0.8, 1.1, 0.5;
  request.target = LinkPose(*robot, q, request.link);
  request.max_solutions = 8;
  request.distinct_distance = 0.1;
  request.time_budget = 0.5;
  const IkResult result = SolveIk(*robot, request);
  // The UR5 has up to 8 analytic branches, and ±2π joint ranges add more; 8 must be found.
  ASSERT_EQ(result.status, IkStatus::kSuccess) << result.message;
  ASSERT_EQ(result.solutions.size(), 8u);
  for (size_t a = 0; a < result.solutions.size(); ++a) {
    EXPECT_TRUE(IsValidSolution(*robot, request, result.solutions[a])) << a;
    for (size_t b = 0; b < a; ++b) {
      const double d = (result.solutions[a] - result.solutions[b]).cwiseAbs().maxCoeff();
      EXPECT_GE(d, request.distinct_distance) << a << " vs " << b;
    }
  }
}

TEST(IkTest, PartialWhenFewerSolutionsExist) {
  // The planar 2R reaches a planar pose (position and heading q1 + q2) in exactly one
  // configuration, so asking for two gives kPartial with that one.
  const auto robot = LoadExampleRobot("planar_2r");
  IkRequest request;
  request.link = robot->FindLink("tool");
  const Eigen::Vector2d q(0.3, 1.1);
  request.target = LinkPose(*robot, q, request.link);
  request.max_solutions = 2;
  request.time_budget = 0.02;
  const IkResult result = SolveIk(*robot, request);
  EXPECT_EQ(result.status, IkStatus::kPartial);
  ASSERT_EQ(result.solutions.size(), 1u);
  EXPECT_TRUE(IsValidSolution(*robot, request, result.solutions[0]));
  EXPECT_LT((result.solutions[0] - Eigen::VectorXd(q)).norm(), 1e-3);
  EXPECT_NE(result.message.find("found 1 of 2 distinct solutions within 0.02 s"), std::string::npos)
      << result.message;
}

TEST(IkTest, AcceptRejectingEverythingGivesNoSolution) {
  const auto robot = LoadExampleRobot("panda");
  IkRequest request;
  request.link = robot->FindLink("panda_tcp");
  Eigen::VectorXd q(7);
  q << 0, -0.785, 0, -2.356, 0, 1.571, 0.785;
  request.target = LinkPose(*robot, q, request.link);
  request.time_budget = 0.01;
  int calls = 0;
  request.accept = [&calls](const Eigen::VectorXd&) {
    ++calls;
    return false;
  };
  const IkResult result = SolveIk(*robot, request);
  EXPECT_EQ(result.status, IkStatus::kNoSolution);
  EXPECT_TRUE(result.solutions.empty());
  EXPECT_GT(calls, 0);
  EXPECT_NE(result.message.find("rejected by accept"), std::string::npos) << result.message;
  // Accepting only configurations with joint 1 > 0 gives such a solution.
  request.accept = [](const Eigen::VectorXd& s) { return s[0] > 0.5; };
  request.time_budget = 0.2;
  const IkResult some = SolveIk(*robot, request);
  ASSERT_EQ(some.status, IkStatus::kSuccess) << some.message;
  EXPECT_GT(some.solutions[0][0], 0.5);
  EXPECT_TRUE(IsValidSolution(*robot, request, some.solutions[0]));
}

TEST(IkTest, SameSeedSameAnswerAndInitialGuessIsUsed) {
  const auto robot = LoadExampleRobot("panda");
  IkRequest request;
  request.link = robot->FindLink("panda_tcp");
  Eigen::VectorXd q(7);
  q << 0.3, -0.5, 0.2, -2.0, 0.1, 1.8, 0.4;
  request.target = LinkPose(*robot, q, request.link);
  request.seed = 99;
  const IkResult a = SolveIk(*robot, request);
  const IkResult b = SolveIk(*robot, request);
  ASSERT_EQ(a.status, IkStatus::kSuccess);
  ASSERT_EQ(b.status, IkStatus::kSuccess);
  EXPECT_EQ(a.solutions[0], b.solutions[0]);
  EXPECT_EQ(a.attempts, b.attempts);
  // A guess close to a solution converges on the first attempt, next to it.
  request.initial_guess = q + Eigen::VectorXd::Constant(7, 0.02);
  const IkResult c = SolveIk(*robot, request);
  ASSERT_EQ(c.status, IkStatus::kSuccess);
  EXPECT_EQ(c.attempts, 1);
  EXPECT_LT((c.solutions[0] - q).cwiseAbs().maxCoeff(), 0.1);
}

TEST(IkTest, LinkFixedToTheRootIsSolvedOnlyAtItsPose) {
  const auto robot = LoadExampleRobot("ur5");
  IkRequest request;
  request.link = robot->root_link();
  request.time_budget = 0.01;
  EXPECT_EQ(SolveIk(*robot, request).status, IkStatus::kSuccess);
  request.target.translation() << 0.1, 0, 0;
  const IkResult result = SolveIk(*robot, request);
  EXPECT_EQ(result.status, IkStatus::kNoSolution);
  EXPECT_EQ(result.attempts, 1);
}

TEST(IkTest, ValidateNamesEveryRule) {
  const auto robot = LoadExampleRobot("ur5");
  IkRequest ok;
  ok.link = robot->FindLink("tool0");
  EXPECT_NO_THROW(ok.Validate(*robot));
  auto expect = [&](const std::function<void(IkRequest&)>& edit, const std::string& message) {
    IkRequest r = ok;
    edit(r);
    ExpectInvalid([&] { r.Validate(*robot); }, message);
    ExpectInvalid([&] { SolveIk(*robot, r); }, message);
  };
  expect([](IkRequest& r) { r.link = 12; }, "ik.link = 12 is not a link of robot 'ur5' (8 links)");
  expect([](IkRequest& r) { r.link = -1; }, "ik.link = -1 is not a link of robot 'ur5' (8 links)");
  expect([](IkRequest& r) { r.position_tolerance = 0; }, "ik.position_tolerance = 0 must be > 0");
  expect([](IkRequest& r) { r.position_tolerance = NAN; }, "ik.position_tolerance = nan must be > 0");
  expect([](IkRequest& r) { r.position_tolerance = INFINITY; },
         "ik.position_tolerance = inf must be finite");
  expect([](IkRequest& r) { r.orientation_tolerance = -0.001; },
         "ik.orientation_tolerance = -0.001 must be > 0");
  expect([](IkRequest& r) { r.damping = -1; }, "ik.damping = -1 must be >= 0");
  expect([](IkRequest& r) { r.max_iterations = 0; }, "ik.max_iterations = 0 must be >= 1");
  expect([](IkRequest& r) { r.max_solutions = 0; }, "ik.max_solutions = 0 must be >= 1");
  expect([](IkRequest& r) { r.distinct_distance = -0.5; }, "ik.distinct_distance = -0.5 must be >= 0");
  expect([](IkRequest& r) { r.time_budget = 0; }, "ik.time_budget = 0 must be > 0");
  expect([](IkRequest& r) { r.target.translation().x() = NAN; }, "ik.target(0, 3) = nan must be finite");
  expect([](IkRequest& r) { r.target.linear() *= 1.1; },
         "ik.target is not in SE(3): its rotation has ‖RᵀR − I‖ = 0.36 (must be <= 1e-06)");
  expect([](IkRequest& r) { r.target.linear() = -Eigen::Matrix3d::Identity(); },
         "ik.target is not in SE(3): its rotation has determinant -1 (must be +1)");
  expect([](IkRequest& r) { r.target.matrix()(3, 0) = 1; },
         "ik.target is not in SE(3): its last row must be (0, 0, 0, 1)");
  expect([](IkRequest& r) { r.initial_guess = Eigen::VectorXd::Zero(5); },
         "ik.initial_guess has 5 values, robot 'ur5' has 6 joints");
  expect([](IkRequest& r) { r.initial_guess = Eigen::VectorXd::Constant(6, 4.0); },
         "ik.initial_guess[2] = 4 must be within [-3.141592653589793, 3.141592653589793] (joint 'elbow_joint')");
}

}  // namespace
}  // namespace chasles
