// Coordinate(): every method on small teams of disc robots, the outcomes that are not solutions
// (conflicting starts and goals, a start in collision), reordering, committed motions, named
// errors, determinism. Every returned set is re-verified here with a team checker built
// independently of the coordinator, at 1 ms and 0.005 rad.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "chasles/multi/coordinator.h"
#include "chasles/robot/error.h"
#include "disc_robots.h"

namespace chasles {
namespace {

using test::Disc;
using test::EmptyFloor;
using ::testing::HasSubstr;

PlannerRegistry& Registry() {
  static PlannerRegistry* registry = [] {
    auto* r = new PlannerRegistry();
    RegisterDefaultPlanners(r);
    return r;
  }();
  return *registry;
}

CoordinationQuery Query(std::vector<TeamRobotSpec> robots, CoordinationMethod method,
                        std::shared_ptr<const Scene> scene = EmptyFloor()) {
  CoordinationQuery query;
  query.scene = std::move(scene);
  query.robots = std::move(robots);
  query.method = method;
  query.time_budget = 20.0;
  query.seed = 7;
  return query;
}

/// Four discs crossing a 1.5 m grid: two along x, two along y; the straight routes of "a" and "b"
/// meet at the origin at the same time. No goal is another robot's start, so one robot after
/// another is possible too.
std::vector<TeamRobotSpec> Cross4() {
  return {Disc("a", {-3, 0}, {3, 0}, 4), Disc("b", {0, -3}, {0, 3}, 3), Disc("c", {-3, 1.5}, {3, 1.5}, 2),
          Disc("d", {1.5, -3}, {1.5, 3}, 1)};
}

/// The independent check: limits exactly, states at <= 1 ms and <= 0.005 rad, scene, self and
/// robot against robot, through a composite built here.
void ExpectJointlyValid(const CoordinationQuery& query, const CoordinationOutcome& outcome) {
  ASSERT_EQ(outcome.code, CoordinationCode::kSuccess) << outcome.message;
  ASSERT_EQ(outcome.robots.size(), query.robots.size());
  std::vector<PlacedRobot> placements;
  std::vector<TimedTrajectory> trajectories;
  std::vector<Eigen::VectorXd> starts, goals;
  std::vector<KinematicLimits> limits;
  double makespan = 0.0, sum = 0.0;
  for (std::size_t k = 0; k < query.robots.size(); ++k) {
    placements.push_back(query.robots[k].placement);
    const RobotPlan& plan = outcome.robots[k];
    EXPECT_EQ(plan.name, query.robots[k].placement.name);
    trajectories.push_back(plan.trajectory);
    starts.push_back(query.robots[k].start);
    goals.push_back(query.robots[k].goal);
    limits.push_back(plan.limits);
    EXPECT_NEAR(plan.duration, plan.trajectory.duration(), 1e-12);
    EXPECT_GE(plan.wait_time + 1e-12, plan.start_delay);
    ASSERT_FALSE(plan.samples.empty());
    EXPECT_NEAR(plan.samples.back().t, plan.duration, 1e-12);
    makespan = std::max(makespan, plan.duration);
    sum += plan.duration;
  }
  EXPECT_NEAR(outcome.makespan, makespan, 1e-12);
  EXPECT_NEAR(outcome.sum_of_durations, sum, 1e-9);
  const CollisionChecker team(ComposeRobots(placements), query.scene);
  TeamVerificationOptions options;
  options.time_step = 1e-3;
  options.max_joint_step = 0.005;
  const TeamVerificationReport report = VerifyTeam(team, trajectories, starts, goals, limits, options);
  EXPECT_TRUE(report.ok) << report.reason;
  EXPECT_LE(report.max_velocity_ratio, 1.0 + 1e-9);
  EXPECT_LE(report.max_acceleration_ratio, 1.0 + 1e-9);
  // Certified along the continuous motion (sphere robots, primitives), else at least one check
  // per millisecond of the makespan.
  if (team.certifies_motion()) {
    EXPECT_GT(report.states_checked, 0u);
  } else {
    EXPECT_GE(static_cast<double>(report.states_checked), makespan / 1e-3);
  }
}

/// The straight, simultaneous plan collides: coordination is needed.
TEST(CoordinatorTest, CrossingOfFourNeedsCoordination) {
  const auto robots = Cross4();
  std::vector<PlacedRobot> placements;
  Eigen::VectorXd middle(8);
  for (std::size_t k = 0; k < robots.size(); ++k) {
    placements.push_back(robots[k].placement);
    middle.segment(2 * k, 2) = 0.5 * (robots[k].start + robots[k].goal);
  }
  const CollisionChecker team(ComposeRobots(placements), EmptyFloor());
  EXPECT_TRUE(team.Check(middle).in_collision);
}

class EveryMethod : public ::testing::TestWithParam<CoordinationMethod> {};

TEST_P(EveryMethod, SolvesTheFourDiscCrossingAndPassesJointVerification) {
  auto robots = Cross4();
  if (GetParam() == CoordinationMethod::kComposite) robots.resize(3);  // the composite is for small teams
  const CoordinationQuery query = Query(robots, GetParam());
  const CoordinationOutcome outcome = Coordinate(query, Registry(), Termination());
  ExpectJointlyValid(query, outcome);
  EXPECT_EQ(outcome.method, GetParam());
  ASSERT_EQ(outcome.attempts.size(), 1u);
  EXPECT_TRUE(outcome.attempts[0].succeeded);
  EXPECT_EQ(outcome.order.size(), query.robots.size());
  if (GetParam() == CoordinationMethod::kSequential) {
    // One after another: each starts when the one before has arrived.
    double clock = 0.0;
    for (const std::string& name : outcome.order) {
      for (const RobotPlan& plan : outcome.robots) {
        if (plan.name != name) continue;
        EXPECT_NEAR(plan.start_delay, clock, 1e-9) << name;
        clock = plan.duration;
      }
    }
    EXPECT_NEAR(outcome.makespan, clock, 1e-9);
  } else if (GetParam() != CoordinationMethod::kComposite) {
    // Somebody yields (waits, slows down or detours), and the set is faster than one after another.
    CoordinationQuery sequential = query;
    sequential.method = CoordinationMethod::kSequential;
    const CoordinationOutcome baseline = Coordinate(sequential, Registry(), Termination());
    ASSERT_EQ(baseline.code, CoordinationCode::kSuccess) << baseline.message;
    EXPECT_LT(outcome.makespan, baseline.makespan);
  }
}

INSTANTIATE_TEST_SUITE_P(Methods, EveryMethod,
                         ::testing::Values(CoordinationMethod::kPrioritized, CoordinationMethod::kVelocityTuning,
                                           CoordinationMethod::kComposite, CoordinationMethod::kSequential),
                         [](const auto& info) { return std::string(ToString(info.param)); });

TEST(CoordinatorTest, AutoReportsItsAttemptsAndTheMethodThatSucceeded) {
  const CoordinationQuery query = Query(Cross4(), CoordinationMethod::kAuto);
  const CoordinationOutcome outcome = Coordinate(query, Registry(), Termination());
  ExpectJointlyValid(query, outcome);
  ASSERT_FALSE(outcome.attempts.empty());
  EXPECT_TRUE(outcome.attempts.back().succeeded);
  EXPECT_EQ(outcome.attempts.back().method, outcome.method);
  for (std::size_t i = 0; i + 1 < outcome.attempts.size(); ++i) EXPECT_FALSE(outcome.attempts[i].succeeded);
  EXPECT_THAT(outcome.message, HasSubstr(ToString(outcome.method)));
}

TEST(CoordinatorTest, SameSeedSameTrajectories) {
  const CoordinationQuery query = Query(Cross4(), CoordinationMethod::kPrioritized);
  const CoordinationOutcome a = Coordinate(query, Registry(), Termination());
  const CoordinationOutcome b = Coordinate(query, Registry(), Termination());
  ASSERT_EQ(a.code, CoordinationCode::kSuccess) << a.message;
  ASSERT_EQ(b.code, CoordinationCode::kSuccess) << b.message;
  for (std::size_t k = 0; k < a.robots.size(); ++k) {
    ASSERT_EQ(a.robots[k].samples.size(), b.robots[k].samples.size());
    for (std::size_t i = 0; i < a.robots[k].samples.size(); ++i) {
      EXPECT_EQ(a.robots[k].samples[i].q, b.robots[k].samples[i].q);
    }
  }
}

/// A slow robot stands where the fast, higher-priority one is going; it cannot get away in time,
/// so the prioritized planner moves it ahead of the fast one.
TEST(CoordinatorTest, PrioritizedReordersWhenALowerRobotCannotGetAway) {
  CoordinationQuery query = Query({Disc("fast", {-4, 0}, {0, 0}, 2, 1.0), Disc("slow", {0, 0}, {4, 0}, 1, 0.1)},
                                  CoordinationMethod::kPrioritized);
  // A corridor: walls along y = ±0.55 keep them on the line.
  auto scene = std::make_shared<Scene>();
  test::AddWall(scene.get(), "north", 0.0, 0.9, 12.0, 0.6);
  test::AddWall(scene.get(), "south", 0.0, -0.9, 12.0, 0.6);
  query.scene = scene;
  const CoordinationOutcome outcome = Coordinate(query, Registry(), Termination());
  ExpectJointlyValid(query, outcome);
  EXPECT_GE(outcome.reorderings, 1);
  ASSERT_EQ(outcome.order.size(), 2u);
  EXPECT_EQ(outcome.order[0], "slow");
}

TEST(CoordinatorTest, OverlappingGoalsAreAnOutcomeNotACollidingSet) {
  for (CoordinationMethod method : {CoordinationMethod::kAuto, CoordinationMethod::kPrioritized}) {
    const CoordinationQuery query =
        Query({Disc("a", {-2, 0}, {0.2, 0}), Disc("b", {2, 0}, {-0.2, 0})}, method);
    const CoordinationOutcome outcome = Coordinate(query, Registry(), Termination());
    EXPECT_EQ(outcome.code, CoordinationCode::kGoalsInConflict) << outcome.message;
    EXPECT_THAT(outcome.message, HasSubstr("'a'"));
    EXPECT_THAT(outcome.message, HasSubstr("'b'"));
    EXPECT_THAT(outcome.message, HasSubstr("a/body"));
    EXPECT_TRUE(outcome.robots.empty());
  }
}

TEST(CoordinatorTest, OverlappingStartsAndAStartInAWallAreOutcomes) {
  const CoordinationOutcome starts = Coordinate(
      Query({Disc("a", {0, 0}, {2, 0}), Disc("b", {0.3, 0}, {-2, 0})}, CoordinationMethod::kAuto), Registry(),
      Termination());
  EXPECT_EQ(starts.code, CoordinationCode::kStartsInConflict) << starts.message;
  auto scene = std::make_shared<Scene>();
  test::AddWall(scene.get(), "pillar", 3.0, 3.0, 0.5, 0.5);
  const CoordinationOutcome wall = Coordinate(
      Query({Disc("a", {0, 0}, {2, 0}), Disc("b", {3, 3}, {-2, 0})}, CoordinationMethod::kAuto, scene), Registry(),
      Termination());
  EXPECT_EQ(wall.code, CoordinationCode::kStartInCollision) << wall.message;
  EXPECT_THAT(wall.message, HasSubstr("robot 'b'"));
  EXPECT_THAT(wall.message, HasSubstr("pillar"));
}

/// A scene's allowed pairs name the robots' own links: "body" may touch the pad, so the robot
/// that starts on it coordinates; each robot's checker gets the pair, the other robot still
/// collides with the pad, and a pair naming no robot's link is a named error.
TEST(CoordinatorTest, SceneAllowedCollisionsApplyToEveryRobotWithTheLink) {
  auto scene = std::make_shared<Scene>();
  test::AddWall(scene.get(), "pad", 3.0, 3.0, 0.5, 0.5);
  const auto query = [&](std::shared_ptr<const Scene> s) {
    return Query({Disc("a", {0, 0}, {2, 0}), Disc("b", {3, 3}, {-2, 0})}, CoordinationMethod::kPrioritized, s);
  };
  EXPECT_EQ(Coordinate(query(scene), Registry(), Termination()).code, CoordinationCode::kStartInCollision);
  auto allowed = std::make_shared<Scene>(*scene);
  allowed->AllowCollision("body", "pad");
  const CoordinationOutcome outcome = Coordinate(query(allowed), Registry(), Termination());
  ASSERT_EQ(outcome.code, CoordinationCode::kSuccess) << outcome.message;
  ASSERT_EQ(outcome.robots.size(), 2u);
  EXPECT_TRUE(outcome.robots[1].samples.front().q.isApprox(Eigen::Vector2d(3, 3)));
  EXPECT_TRUE(outcome.robots[1].samples.back().q.isApprox(Eigen::Vector2d(-2, 0)));
  // The pair is per link, not per robot: robot a (same link name) may also cross the pad; a
  // goal inside it is accepted.
  const CoordinationOutcome through = Coordinate(
      Query({Disc("a", {0, 0}, {3, 3.2}), Disc("b", {-3, -3}, {-2, 0})}, CoordinationMethod::kPrioritized, allowed),
      Registry(), Termination());
  EXPECT_EQ(through.code, CoordinationCode::kSuccess) << through.message;
  auto unknown = std::make_shared<Scene>(*scene);
  unknown->AllowCollision("gripper", "pad");
  try {
    Coordinate(query(unknown), Registry(), Termination());
    ADD_FAILURE() << "no error for a pair naming no robot's link";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("scene.allowed_collisions[0].link1 = 'gripper' is not a link of any robot"));
  }
}

/// A committed motion crosses the robot's straight route; the plan waits or detours, and never
/// meets it.
TEST(CoordinatorTest, AvoidsCommittedMotions) {
  CoordinationQuery query = Query({Disc("mover", {-3, 0}, {3, 0})}, CoordinationMethod::kPrioritized);
  const CoordinationOutcome alone = Coordinate(query, Registry(), Termination());
  ASSERT_EQ(alone.code, CoordinationCode::kSuccess) << alone.message;

  CommittedMotion crossing;
  crossing.id = "reservation 'cell/1'";
  crossing.placement.name = "crosser";
  crossing.placement.model = test::DiscRobot();
  KinematicLimits limits;
  limits.max_velocity = Eigen::Vector2d(1.0, 1.0);
  limits.max_acceleration = Eigen::Vector2d(2.0, 2.0);
  crossing.trajectory = ParameterizeRestToRest({Eigen::Vector2d(0, -3), Eigen::Vector2d(0, 3)}, limits);
  crossing.begin = 0.0;  // both would be at the origin after 3.25 s
  crossing.until = crossing.trajectory.duration() + 1.0;
  query.committed = {crossing};
  const CoordinationOutcome outcome = Coordinate(query, Registry(), Termination());
  ExpectJointlyValid(query, outcome);
  CommittedMotion mine;
  mine.id = "mover";
  mine.placement = query.robots[0].placement;
  mine.trajectory = outcome.robots[0].trajectory;
  mine.until = std::numeric_limits<double>::infinity();
  EXPECT_EQ(FindMotionConflict(mine, crossing, 0.0, 1e-3, 0.005), "");
  // The same route without waiting would have met it.
  mine.trajectory = alone.robots[0].trajectory;
  EXPECT_THAT(FindMotionConflict(mine, crossing, 0.0, 1e-3, 0.005), HasSubstr("collide at t = "));
}

/// min_robot_distance: two discs of radius 0.3 m passing on parallel lines 4 m apart and one
/// overtaking-free pair: the smallest centre distance minus both radii, by the exact formula.
TEST(CoordinatorTest, ReportsTheSmallestDistanceBetweenRobots) {
  // a: (-3, -2) → (3, -2); b: (3, 2) → (-3, 2). Centres stay exactly 4 m apart in y; in x they
  // cross, so the smallest centre distance is 4 m and the shapes are 4 − 0.6 = 3.4 m apart.
  const CoordinationQuery query =
      Query({Disc("a", {-3, -2}, {3, -2}), Disc("b", {3, 2}, {-3, 2})}, CoordinationMethod::kPrioritized);
  const CoordinationOutcome outcome = Coordinate(query, Registry(), Termination());
  ExpectJointlyValid(query, outcome);
  // Straight lines at the same speed meet at x = 0 at the same instant, a distance instant of
  // the 0.01 s grid (the motions are symmetric), so the measured minimum is the exact one up to
  // how far the crossing lies from an instant: 4 − 0.6 ≤ d ≤ √(4² + (2·0.01)²) − 0.6.
  EXPECT_GE(outcome.verification.min_robot_distance, 3.4 - 1e-9);
  EXPECT_LE(outcome.verification.min_robot_distance, std::hypot(4.0, 0.02) - 0.6 + 1e-9);
  // One robot: nothing to measure against, the cap.
  const CoordinationQuery alone = Query({Disc("a", {-3, -2}, {3, -2})}, CoordinationMethod::kPrioritized);
  EXPECT_EQ(Coordinate(alone, Registry(), Termination()).verification.min_robot_distance, kMaxReportedRobotDistance);
}

/// A robot walled in cannot be proven to have no path by a sampling planner that ran out of
/// time: the attempts say it found none within its share, and AUTO comes back to the methods its
/// shares stopped once the others have failed.
TEST(CoordinatorTest, AutoReturnsToMethodsItsSharesStoppedAndSaysWhyTheyStopped) {
  auto scene = std::make_shared<Scene>();
  // A closed square of walls around (3, 3); robot "b" stands inside, its goal is outside.
  test::AddWall(scene.get(), "n", 3.0, 4.2, 2.6, 0.2);
  test::AddWall(scene.get(), "s", 3.0, 1.8, 2.6, 0.2);
  test::AddWall(scene.get(), "e", 4.2, 3.0, 0.2, 2.6);
  test::AddWall(scene.get(), "w", 1.8, 3.0, 0.2, 2.6);
  CoordinationQuery query =
      Query({Disc("a", {-3, -3}, {-3, 3}), Disc("b", {3, 3}, {-1, 0})}, CoordinationMethod::kAuto, scene);
  query.time_budget = 1.0;
  const CoordinationOutcome outcome = Coordinate(query, Registry(), Termination());
  EXPECT_EQ(outcome.code, CoordinationCode::kNoSolution) << outcome.message;
  int prioritized = 0;
  for (const MethodAttemptReport& a : outcome.attempts) {
    EXPECT_FALSE(a.succeeded);
    EXPECT_THAT(a.message, ::testing::Not(HasSubstr("even alone"))) << ToString(a.method);
    if (a.method == CoordinationMethod::kPrioritized) {
      ++prioritized;
      // Its share ends while 'b' (or 'a' around it) is still being planned.
      EXPECT_THAT(a.message, ::testing::AnyOf(HasSubstr("robot 'b' found no path alone within"),
                                              HasSubstr("stopped while robot"), HasSubstr("stopped before every robot")));
    }
  }
  EXPECT_GE(prioritized, 2) << outcome.message;
}

TEST(CoordinatorTest, NamedErrors) {
  const auto expect_invalid = [](CoordinationQuery query, const std::string& text) {
    try {
      Coordinate(query, Registry(), Termination());
      ADD_FAILURE() << "no error; expected " << text;
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument) << e.what();
      EXPECT_THAT(e.what(), HasSubstr(text));
    }
  };
  expect_invalid(Query({Disc("a", {-2, 0}, {2, 0}), Disc("a", {2, 2}, {-2, 2})}, CoordinationMethod::kAuto),
                 "robots[1].name = 'a' is already the name of robots[0]");
  CoordinationQuery sizes = Query({Disc("a", {-2, 0}, {2, 0}), Disc("b", {2, 2}, {-2, 2})}, CoordinationMethod::kAuto);
  sizes.robots[1].start = Eigen::Vector3d(2, 2, 0);
  expect_invalid(sizes, "robots[1].start.positions has 3 values, robot 'disc' has 2 joints");
  CoordinationQuery nan = Query({Disc("a", {-2, 0}, {2, 0})}, CoordinationMethod::kAuto);
  nan.robots[0].goal[1] = std::nan("");
  expect_invalid(nan, "robots[0].goal.positions[1] = nan must be finite");
  CoordinationQuery name = Query({Disc("a b", {-2, 0}, {2, 0})}, CoordinationMethod::kAuto);
  expect_invalid(name, "robots[0].name = 'a b' must be");
  CoordinationQuery velocity = Query({Disc("a", {-2, 0}, {2, 0})}, CoordinationMethod::kAuto);
  velocity.robots[0].max_velocity = Eigen::Vector2d(1.0, -1.0);
  expect_invalid(velocity, "robots[0].max_velocity[1] = -1");
  CoordinationQuery padding = Query({Disc("a", {-2, 0}, {2, 0})}, CoordinationMethod::kAuto);
  padding.robot_padding = 2.0;
  expect_invalid(padding, "robot_padding = 2 must be within [0, 0.5]");
  CoordinationQuery empty = Query({}, CoordinationMethod::kAuto);
  expect_invalid(empty, "robots has 0 entries");
  CoordinationQuery planner = Query({Disc("a", {-2, 0}, {2, 0})}, CoordinationMethod::kAuto);
  planner.planner_id = "nope";
  try {
    Coordinate(planner, Registry(), Termination());
    ADD_FAILURE() << "unknown planner accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kNotFound);
    EXPECT_THAT(e.what(), HasSubstr("nope"));
  }
}

TEST(CoordinatorTest, StopsWhenCancelled) {
  const CoordinationQuery query = Query(Cross4(), CoordinationMethod::kAuto);
  const CoordinationOutcome outcome = Coordinate(query, Registry(), Termination::AlreadyStopped());
  EXPECT_EQ(outcome.code, CoordinationCode::kCancelled) << outcome.message;
  EXPECT_TRUE(outcome.robots.empty());
}

}  // namespace
}  // namespace chasles
