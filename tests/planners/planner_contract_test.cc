// The planner contract, run over every registered planner (after OMPL's tests/base/PlannerTest.h):
// solve, clear, solve again; an already-triggered termination returns promptly; seeded runs repeat.

#include <chrono>
#include <thread>

#include <gtest/gtest.h>

#include "chasles/collision/collision_checker.h"
#include "chasles/planners/registry.h"
#include "chasles/robot/error.h"
#include "two_link_arm.h"

namespace chasles {
namespace {

using testing::kTwoLinkUrdf;

class PlannerContractTest : public ::testing::TestWithParam<std::string> {
 protected:
  static void SetUpTestSuite() {
    registry_ = new PlannerRegistry();
    RegisterDefaultPlanners(registry_);
    auto robot = RobotModel::FromUrdf(kTwoLinkUrdf);
    auto scene = std::make_shared<Scene>();
    // A wall at x = 1.2 between start (pointing +y) and goal (pointing -y): the arm must fold
    // or swing around through -x.
    Eigen::Isometry3d wall = Eigen::Isometry3d::Identity();
    wall.translation() = Eigen::Vector3d(1.4, 0.0, 0.0);
    scene->AddObject({"wall", Shape::Box(Eigen::Vector3d(0.2, 0.3, 0.5), wall)});
    checker_ = std::make_shared<const CollisionChecker>(robot, scene);
  }
  static void TearDownTestSuite() {
    delete registry_;
    registry_ = nullptr;
    checker_.reset();
  }

  PlanningProblem Problem(std::uint64_t seed = 7) const {
    PlanningProblem p;
    p.checker = checker_;
    p.start = Eigen::Vector2d(1.2, 0.0);
    p.goal = Eigen::Vector2d(-1.2, 0.0);
    p.goal_tolerance = 1e-3;
    p.max_step = 0.005;
    p.seed = seed;
    if (registry_->Spec(GetParam()).optimizing) p.parameters["max_iterations"] = 1000;
    return p;
  }

  void ExpectValidSolution(const PlannerResult& r, const PlanningProblem& p) const {
    ASSERT_EQ(r.status, PlanStatus::kExactSolution) << r.message;
    ASSERT_GE(r.path.size(), 2u);
    EXPECT_EQ(r.path.front(), p.start);
    EXPECT_EQ(r.path.back(), p.goal);
    for (size_t i = 0; i + 1 < r.path.size(); ++i) {
      EXPECT_TRUE(checker_->IsMotionValid(r.path[i], r.path[i + 1], p.max_step)) << "segment " << i;
    }
    EXPECT_GT(r.state_checks, 0u);
  }

  static PlannerRegistry* registry_;
  static std::shared_ptr<const CollisionChecker> checker_;
};

PlannerRegistry* PlannerContractTest::registry_ = nullptr;
std::shared_ptr<const CollisionChecker> PlannerContractTest::checker_;

TEST_P(PlannerContractTest, ProblemIsNotTrivial) {
  const PlanningProblem p = Problem();
  EXPECT_TRUE(checker_->IsValid(p.start));
  EXPECT_TRUE(checker_->IsValid(p.goal));
  EXPECT_FALSE(checker_->IsMotionValid(p.start, p.goal, p.max_step)) << "the straight line must collide";
}

TEST_P(PlannerContractTest, SolveClearSolve) {
  auto planner = registry_->Create(GetParam());
  EXPECT_EQ(planner->spec().id, GetParam());
  const PlanningProblem p = Problem();
  planner->Setup(p);
  ExpectValidSolution(planner->Solve(Termination::After(std::chrono::seconds(5))), p);
  planner->Clear();
  planner->Setup(p);
  ExpectValidSolution(planner->Solve(Termination::After(std::chrono::seconds(5))), p);
}

TEST_P(PlannerContractTest, AlreadyStoppedTerminationReturnsPromptly) {
  auto planner = registry_->Create(GetParam());
  planner->Setup(Problem());
  const auto t0 = std::chrono::steady_clock::now();
  const PlannerResult r = planner->Solve(Termination::AlreadyStopped());
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_NE(r.status, PlanStatus::kExactSolution);
  EXPECT_EQ(r.status, PlanStatus::kCancelled) << r.message;
  EXPECT_LT(seconds, 1.0);  // liveness bound, not a speed claim
}

TEST_P(PlannerContractTest, CancelFromAnotherThreadStopsAnAnytimeSolve) {
  if (!registry_->Spec(GetParam()).optimizing) {
    GTEST_SKIP() << "returns at its first solution; AlreadyStoppedTerminationReturnsPromptly covers it";
  }
  auto planner = registry_->Create(GetParam());
  PlanningProblem p = Problem();
  p.parameters.erase("max_iterations");
  planner->Setup(p);
  Termination termination;  // no budget: only Cancel() ends it
  std::thread canceller([termination] {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    termination.Cancel();
  });
  const PlannerResult r = planner->Solve(termination);  // would run forever without Cancel()
  canceller.join();
  EXPECT_EQ(termination.Reason(), StopReason::kCancelled);
  // An anytime planner keeps what it found before the cancellation.
  if (r.status == PlanStatus::kExactSolution) ExpectValidSolution(r, p);
}

TEST_P(PlannerContractTest, SeededRunsAreReproducible) {
  const std::string id = GetParam();
  const PlanningProblem p = Problem(42);
  auto a = registry_->Create(id);
  auto b = registry_->Create(id);
  a->Setup(p);
  b->Setup(p);
  const PlannerResult ra = a->Solve(Termination::After(std::chrono::seconds(5)));
  const PlannerResult rb = b->Solve(Termination::After(std::chrono::seconds(5)));
  ASSERT_EQ(ra.status, PlanStatus::kExactSolution);
  ASSERT_EQ(rb.status, PlanStatus::kExactSolution);
  ASSERT_EQ(ra.path.size(), rb.path.size());
  for (size_t i = 0; i < ra.path.size(); ++i) EXPECT_EQ(ra.path[i], rb.path[i]) << "waypoint " << i;
}

INSTANTIATE_TEST_SUITE_P(AllPlanners, PlannerContractTest,
                         ::testing::Values("rrt_connect", "rrt", "rrt_star", "informed_rrt_star", "prm",
                                           "prm_star", "lazy_prm_star", "bit_star", "astar", "potential_field",
                                           "wavefront"),
                         [](const auto& info) { return info.param; });

// RRT-Connect keeps a thread's space and planner for its next request with the same joint
// bounds (ompl_planner.cc, ReusableRrtConnect). Each test runs on a new thread, whose slot starts
// empty, so the first plan there is built from nothing.
class RrtConnectReuseTest : public ::testing::Test {
 protected:
  static std::shared_ptr<const CollisionChecker> Checker(bool wall) {
    auto scene = std::make_shared<Scene>();
    if (wall) {
      Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
      pose.translation() = Eigen::Vector3d(1.4, 0.0, 0.0);
      scene->AddObject({"wall", Shape::Box(Eigen::Vector3d(0.2, 0.3, 0.5), pose)});
    }
    return std::make_shared<const CollisionChecker>(RobotModel::FromUrdf(kTwoLinkUrdf), scene);
  }
  static PlanningProblem Problem(std::shared_ptr<const CollisionChecker> checker, std::uint64_t seed) {
    PlanningProblem p;
    p.checker = std::move(checker);
    p.start = Eigen::Vector2d(1.2, 0.0);
    p.goal = Eigen::Vector2d(-1.2, 0.0);
    p.goal_tolerance = 1e-3;
    p.max_step = 0.005;
    p.seed = seed;
    return p;
  }
  static PlannerResult Plan(const PlanningProblem& p) {
    PlannerRegistry registry;
    RegisterDefaultPlanners(&registry);
    auto planner = registry.Create("rrt_connect");
    planner->Setup(p);
    return planner->Solve(Termination::After(std::chrono::seconds(5)));
  }
  template <class F>
  static void OnNewThread(F f) {
    std::thread t(f);
    t.join();
  }
};

TEST_F(RrtConnectReuseTest, APlanAfterOtherRequestsIsThePlanOfANewThread) {
  const auto wall = Checker(true);
  PlannerResult first, again, other;
  OnNewThread([&] { first = Plan(Problem(wall, 42)); });
  OnNewThread([&] {
    PlanningProblem different = Problem(wall, 5);
    different.start = Eigen::Vector2d(0.9, 0.3);
    other = Plan(different);
    again = Plan(Problem(wall, 42));
  });
  ASSERT_EQ(first.status, PlanStatus::kExactSolution) << first.message;
  ASSERT_EQ(other.status, PlanStatus::kExactSolution) << other.message;
  ASSERT_EQ(again.status, PlanStatus::kExactSolution) << again.message;
  EXPECT_EQ(first.graph_states, again.graph_states);
  EXPECT_EQ(first.state_checks, again.state_checks);
  ASSERT_EQ(first.path.size(), again.path.size());
  for (size_t i = 0; i < first.path.size(); ++i) EXPECT_EQ(first.path[i], again.path[i]) << "waypoint " << i;
}

TEST_F(RrtConnectReuseTest, EachRequestIsCheckedAgainstItsOwnScene) {
  const auto wall = Checker(true);
  PlanningProblem blocked = Problem(wall, 3);
  blocked.start = Eigen::Vector2d(0.0, 0.0);  // straight along +x, through the wall
  ASSERT_FALSE(wall->IsValid(blocked.start));
  PlannerResult open, walled, stuck;
  OnNewThread([&] {
    open = Plan(Problem(Checker(false), 3));
    walled = Plan(Problem(wall, 3));
    stuck = Plan(blocked);  // would plan in the open scene had the first request's checker been kept
  });
  ASSERT_EQ(open.status, PlanStatus::kExactSolution) << open.message;
  ASSERT_EQ(walled.status, PlanStatus::kExactSolution) << walled.message;
  for (size_t i = 0; i + 1 < walled.path.size(); ++i) {
    EXPECT_TRUE(wall->IsMotionValid(walled.path[i], walled.path[i + 1], 0.001)) << "segment " << i;
  }
  EXPECT_NE(stuck.status, PlanStatus::kExactSolution);  // OMPL refuses the colliding start
  EXPECT_EQ(stuck.graph_states, 0u) << stuck.message;
}

TEST_F(RrtConnectReuseTest, AKeptPlannerHoldsNoChecker) {
  std::weak_ptr<const CollisionChecker> watched;
  OnNewThread([&] {
    auto checker = Checker(true);
    watched = checker;
    EXPECT_EQ(Plan(Problem(checker, 9)).status, PlanStatus::kExactSolution);
    checker.reset();
    EXPECT_TRUE(watched.expired()) << "the thread's kept planner still holds the request's checker";
  });
}

TEST(PlannerRegistryTest, EveryDefaultPlannerIsCoveredByTheContractTest) {
  PlannerRegistry registry;
  RegisterDefaultPlanners(&registry);
  const std::vector<std::string> expected = {"astar", "bit_star", "informed_rrt_star", "lazy_prm_star",
                                             "potential_field", "prm", "prm_star", "rrt", "rrt_connect",
                                             "rrt_star", "wavefront"};
  EXPECT_EQ(registry.Ids(), expected);
}

TEST(PlannerRegistryTest, UnknownPlannerIsNotFoundAndListsKnownIds) {
  PlannerRegistry registry;
  RegisterDefaultPlanners(&registry);
  try {
    registry.Create("rrt_sharp");
    FAIL() << "expected Error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kNotFound);
    EXPECT_EQ(std::string(e.what()),
              "planner.planner_id = 'rrt_sharp' is unknown (known: astar, bit_star, informed_rrt_star, "
              "lazy_prm_star, potential_field, prm, prm_star, rrt, rrt_connect, rrt_star, wavefront)");
  }
}

TEST(PlannerRegistryTest, DuplicateRegistrationIsRejected) {
  PlannerRegistry registry;
  RegisterDefaultPlanners(&registry);
  EXPECT_THROW(RegisterDefaultPlanners(&registry), Error);
}

TEST(ParameterTest, ResolveFillsDefaultsAndRejectsBadValues) {
  PlannerRegistry registry;
  RegisterDefaultPlanners(&registry);
  const PlannerSpec& rrt = registry.Spec("rrt");
  const ParameterValues resolved = ResolveParameters(rrt, {{"range", 0.5}});
  EXPECT_EQ(resolved.at("range"), 0.5);
  EXPECT_EQ(resolved.at("goal_bias"), 0.05);

  const auto message = [](const PlannerSpec& spec, const ParameterValues& v) {
    try {
      ResolveParameters(spec, v);
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message(rrt, {{"range", -1}}),
            "planner.parameters['range'] = -1 must be within [0, 100] (planner 'rrt')");
  EXPECT_EQ(message(rrt, {{"goal_bias", 1.5}}),
            "planner.parameters['goal_bias'] = 1.5 must be within [0, 1] (planner 'rrt')");
  EXPECT_EQ(message(rrt, {{"foo", 1}}),
            "planner.parameters['foo'] is not a parameter of planner 'rrt' (known: range, goal_bias, constrained_space, constraint_delta)");
  EXPECT_EQ(message(registry.Spec("prm"), {{"max_nearest_neighbors", 2.5}}),
            "planner.parameters['max_nearest_neighbors'] = 2.5 must be an integer");
  EXPECT_EQ(message(rrt, {{"range", std::nan("")}}), "planner.parameters['range'] = nan must be finite");
}

TEST(TerminationTest, ReasonsAndCopiesShareCancellation) {
  Termination never;
  EXPECT_FALSE(never.ShouldStop());
  const Termination copy = never;
  copy.Cancel();
  EXPECT_EQ(never.Reason(), StopReason::kCancelled);

  const Termination past_budget = Termination::After(std::chrono::seconds(-1));
  EXPECT_EQ(past_budget.Reason(), StopReason::kBudget);
  EXPECT_EQ(past_budget.SecondsLeft(), 0.0);

  const auto now = Termination::Clock::now();
  const Termination deadline(now + std::chrono::hours(1), now - std::chrono::seconds(1));
  EXPECT_EQ(deadline.Reason(), StopReason::kDeadline);
}

}  // namespace
}  // namespace chasles
