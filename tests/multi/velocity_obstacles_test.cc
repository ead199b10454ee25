// Velocity obstacles: a planar disc base among moving discs. Every result is checked on its own
// terms — the trajectory evaluated every millisecond against the discs' true paths and the
// scene, its pieces' extrema against the limits — never by the planner's own figures.

#include "chasles/multi/velocity_obstacles.h"

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <random>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "chasles/collision/collision_checker.h"
#include "chasles/collision/scene.h"
#include "chasles/optimizers/time_parameterization.h"
#include "chasles/optimizers/verification.h"
#include "chasles/robot/error.h"
#include "chasles/robot/mobile.h"
#include "chasles/robot/robot_model.h"

namespace chasles {
namespace {

constexpr double kBaseRadius = 0.25;  // [m] the base's cylinder
constexpr double kDiscRadius = 0.3;   // [m]
constexpr double kDense = 1e-3;       // [s] independent checks every millisecond

/// A disc base: an upright cylinder of radius 0.25 m, 0.3 m tall, on (x, y, θ) within ±6 m.
std::shared_ptr<const RobotModel> DiscBase() {
  MobileDescription mobile;
  mobile.name = "disc_base";
  mobile.kind = RobotKind::kPlanar;
  mobile.workspace_min = Eigen::Vector3d(-6, -6, 0);
  mobile.workspace_max = Eigen::Vector3d(6, 6, 0);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(0, 0, 0.15);
  mobile.body.collision.push_back(Shape::Cylinder(kBaseRadius, 0.3, pose));
  return RobotFromMobile(mobile);
}

/// Different limits per axis, so the per-axis bounds are exercised.
KinematicLimits BaseLimits() {
  KinematicLimits limits;
  limits.max_velocity = Eigen::Vector3d(1.0, 0.8, 1.0);
  limits.max_acceleration = Eigen::Vector3d(1.0, 0.7, 2.0);
  return limits;
}

Eigen::VectorXd Q(double x, double y, double theta) { return Eigen::Vector3d(x, y, theta); }

MovingDisc Disc(const std::string& name, std::vector<double> times, std::vector<Eigen::Vector2d> centres) {
  MovingDisc disc;
  disc.name = name;
  disc.radius = kDiscRadius;
  disc.times = std::move(times);
  disc.centres = std::move(centres);
  return disc;
}

/// Smallest distance between the base's and the discs' centres minus both radii, with the
/// trajectory evaluated every millisecond (and at its end) and held at its end afterwards until
/// `until` [s].
double ClosestApproach(const TimedTrajectory& trajectory, const std::vector<MovingDisc>& discs, double until = 0.0) {
  double closest = std::numeric_limits<double>::infinity();
  const double end = std::max(trajectory.duration(), until);
  const int samples = static_cast<int>(std::ceil(end / kDense));
  for (int i = 0; i <= samples; ++i) {
    const double t = std::min(end, i * kDense);
    const Eigen::Vector2d base = trajectory.Evaluate(t).q.head<2>();
    for (const MovingDisc& disc : discs) {
      closest = std::min(closest, (base - disc.CentreAt(t)).norm() - kBaseRadius - disc.radius);
    }
  }
  return closest;
}

/// Largest |q̇ᵢ|/vᵢ and |q̈ᵢ|/aᵢ − 1 over the pieces, exactly at each polynomial's extrema.
void ExpectWithinLimits(const TimedTrajectory& trajectory, const KinematicLimits& limits) {
  for (std::size_t p = 0; p < trajectory.pieces().size(); ++p) {
    const TimedTrajectory::Piece& piece = trajectory.pieces()[p];
    for (int joint = 0; joint < 3; ++joint) {
      const Eigen::RowVectorXd row = piece.coefficients.row(joint);
      const double velocity = poly::MaxAbsDerivative(row.data(), static_cast<int>(row.size()), 1, piece.duration);
      const double acceleration = poly::MaxAbsDerivative(row.data(), static_cast<int>(row.size()), 2, piece.duration);
      EXPECT_LE(velocity, limits.max_velocity[joint] + 1e-9) << "piece " << p << " joint " << joint;
      EXPECT_LE(acceleration, limits.max_acceleration[joint] + 1e-9) << "piece " << p << " joint " << joint;
    }
  }
}

/// Starts at `start` at rest, pieces back to back and continuous, ends exactly on `goal` at rest.
void ExpectRestToRest(const TimedTrajectory& trajectory, const Eigen::VectorXd& start, const Eigen::VectorXd& goal) {
  ASSERT_FALSE(trajectory.empty());
  const TrajectorySample first = trajectory.Evaluate(0.0);
  EXPECT_EQ(first.q, start);
  EXPECT_EQ(first.qd, Eigen::VectorXd::Zero(3));
  const TrajectorySample last = trajectory.Evaluate(trajectory.duration());
  EXPECT_EQ(last.q, goal);  // exactly
  EXPECT_LE(last.qd.cwiseAbs().maxCoeff(), 1e-9);
  const auto& pieces = trajectory.pieces();
  for (std::size_t p = 1; p < pieces.size(); ++p) {
    const TimedTrajectory::Piece& before = pieces[p - 1];
    EXPECT_NEAR(pieces[p].t0, before.t0 + before.duration, 1e-9);
    const TrajectorySample end = before.State(before.duration), begin = pieces[p].State(0.0);
    EXPECT_LE((end.q - begin.q).cwiseAbs().maxCoeff(), 1e-9) << "piece " << p;
    EXPECT_LE((end.qd - begin.qd).cwiseAbs().maxCoeff(), 1e-9) << "piece " << p;
  }
}

std::string InvalidArgumentMessage(const std::function<void()>& call) {
  try {
    call();
  } catch (const Error& error) {
    EXPECT_EQ(error.code(), ErrorCode::kInvalidArgument) << error.what();
    return error.what();
  }
  ADD_FAILURE() << "no Error thrown";
  return "";
}

class VelocityObstaclesTest : public ::testing::Test {
 protected:
  VelocityObstacleResult Plan(const Eigen::VectorXd& start, const Eigen::VectorXd& goal,
                              const std::vector<MovingDisc>& discs,
                              const JointPath& guide = {}, const VelocityObstacleOptions& options = {}) {
    return PlanWithVelocityObstacles(*checker_, start, goal, discs, limits_, guide, options, Termination());
  }

  std::shared_ptr<const RobotModel> robot_ = DiscBase();
  std::shared_ptr<Scene> scene_ = std::make_shared<Scene>();
  std::unique_ptr<CollisionChecker> checker_ = std::make_unique<CollisionChecker>(robot_, scene_);
  KinematicLimits limits_ = BaseLimits();
};

// ---------------------------------------------------------------------------------------------

TEST(MovingDisc, CentreAndVelocityFollowThePath) {
  const MovingDisc disc = Disc("d", {1.0, 3.0, 4.0}, {{0, 0}, {2, 0}, {2, 3}});
  EXPECT_EQ(disc.CentreAt(-5.0), Eigen::Vector2d(0, 0));  // stands at its first centre before
  EXPECT_EQ(disc.VelocityAt(0.5), Eigen::Vector2d(0, 0));
  EXPECT_TRUE(disc.CentreAt(2.0).isApprox(Eigen::Vector2d(1, 0)));
  EXPECT_TRUE(disc.VelocityAt(2.0).isApprox(Eigen::Vector2d(1, 0)));
  EXPECT_TRUE(disc.VelocityAt(3.0).isApprox(Eigen::Vector2d(0, 3)));  // right limit at a waypoint
  EXPECT_TRUE(disc.CentreAt(3.5).isApprox(Eigen::Vector2d(2, 1.5)));
  EXPECT_EQ(disc.CentreAt(9.0), Eigen::Vector2d(2, 3));  // and at its last after
  EXPECT_EQ(disc.VelocityAt(4.0), Eigen::Vector2d(0, 0));
}

TEST_F(VelocityObstaclesTest, CrossingDiscIsAvoidedWhereTheStraightRunHitsIt) {
  limits_.max_velocity = Eigen::Vector3d(1.0, 1.0, 1.0);  // the same in x and y: the straight runs agree
  limits_.max_acceleration = Eigen::Vector3d(1.0, 1.0, 2.0);
  const Eigen::VectorXd start = Q(-4, 0, 0), goal = Q(4, 0, 0);
  // The straight minimum-time run is at x = 0 at t = 4.5 s (8 m at 1 m/s, 1 m/s²); the disc
  // crosses the line there and then at 1 m/s.
  const std::vector<MovingDisc> discs = {Disc("crossing", {0.5, 8.5}, {{0, -4}, {0, 4}})};
  const TimedTrajectory naive = ParameterizeRestToRest({start, goal}, limits_);
  EXPECT_LT(ClosestApproach(naive, discs), -0.5);  // ignoring the disc runs straight into it
  // So does the planner itself when it is not told about the disc.
  const VelocityObstacleResult blind = Plan(start, goal, {});
  ASSERT_TRUE(blind.reached) << blind.message;
  EXPECT_LT(ClosestApproach(blind.trajectory, discs), -0.5);

  const VelocityObstacleResult result = Plan(start, goal, discs);
  ASSERT_TRUE(result.reached) << result.message;
  EXPECT_GT(ClosestApproach(result.trajectory, discs), 0.0);
  ExpectRestToRest(result.trajectory, start, goal);
  ExpectWithinLimits(result.trajectory, limits_);
  EXPECT_EQ(result.path.front(), start);
  EXPECT_EQ(result.path.back(), goal);
  EXPECT_GT(result.steps, 0);
}

TEST_F(VelocityObstaclesTest, HeadOnDiscIsPassed) {
  const Eigen::VectorXd start = Q(-4, 0, 0), goal = Q(4, 0, 0);
  // Along the base's line toward it at 0.8 m/s, on through its start.
  const std::vector<MovingDisc> discs = {Disc("oncoming", {0.0, 12.5}, {{5, 0}, {-5, 0}})};
  EXPECT_LT(ClosestApproach(ParameterizeRestToRest({start, goal}, limits_), discs), -0.5);
  EXPECT_LT(ClosestApproach(Plan(start, goal, {}).trajectory, discs), -0.5);  // blind, it meets the disc

  const VelocityObstacleResult result = Plan(start, goal, discs);
  ASSERT_TRUE(result.reached) << result.message;
  EXPECT_GT(ClosestApproach(result.trajectory, discs), 0.0);
  ExpectRestToRest(result.trajectory, start, goal);
  ExpectWithinLimits(result.trajectory, limits_);
}

TEST_F(VelocityObstaclesTest, LimitsHoldAndTheGoalIsExact) {
  // A diagonal run with a turn of 3 rad and two discs across it.
  const Eigen::VectorXd start = Q(-3, -2, -1.5), goal = Q(3, 2.5, 1.5);
  const std::vector<MovingDisc> discs = {Disc("a", {0.0, 10.0}, {{-2, 3}, {2, -3}}),
                                         Disc("b", {1.0, 6.0, 9.0}, {{4, 0}, {0, 0.5}, {-1, 4}})};
  const VelocityObstacleResult result = Plan(start, goal, discs);
  ASSERT_TRUE(result.reached) << result.message;
  ExpectRestToRest(result.trajectory, start, goal);
  ExpectWithinLimits(result.trajectory, limits_);
  EXPECT_GT(ClosestApproach(result.trajectory, discs), 0.0);
  // Dense samples too, and the verifier (limits, continuity, scene) as a third opinion.
  for (const TrajectorySample& sample : result.trajectory.Sample(kDense)) {
    for (int joint = 0; joint < 3; ++joint) {
      ASSERT_LE(std::abs(sample.qd[joint]), limits_.max_velocity[joint] + 1e-9) << "t = " << sample.t;
      ASSERT_LE(std::abs(sample.qdd[joint]), limits_.max_acceleration[joint] + 1e-9) << "t = " << sample.t;
    }
  }
  const VerificationReport report = VerifyTrajectory(result.trajectory, start, goal, *checker_, limits_);
  EXPECT_TRUE(report.ok) << report.reason;
}

TEST_F(VelocityObstaclesTest, GuideLeadsThroughTheGapInAWall) {
  // A wall across x = 0 with a 1 m gap for y in [1, 2].
  const auto wall = [&](const std::string& name, double y_low, double y_high) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = Eigen::Vector3d(0, 0.5 * (y_low + y_high), 0.3);
    scene_->AddObject(SceneObject{name, Shape::Box(Eigen::Vector3d(0.2, y_high - y_low, 0.6), pose)});
  };
  wall("wall_low", -6.0, 1.0);
  wall("wall_high", 2.0, 6.0);
  checker_ = std::make_unique<CollisionChecker>(robot_, scene_);
  const Eigen::VectorXd start = Q(-3, 0, 0), goal = Q(3, 0, 0.5);
  const JointPath guide = {start, Q(-0.6, 1.5, 0), Q(0.6, 1.5, 0), goal};
  for (std::size_t k = 1; k < guide.size(); ++k) ASSERT_TRUE(checker_->IsMotionFree(guide[k - 1], guide[k], 0.005));
  ASSERT_FALSE(checker_->IsMotionFree(start, goal, 0.005));  // the straight line is blocked
  // A disc crossing x = 1.5, behind the gap, downwards at 1 m/s, timed to meet the base there as
  // it comes along the guide when it is not told about the disc.
  const VelocityObstacleResult blind = Plan(start, goal, {}, guide);
  ASSERT_TRUE(blind.reached) << blind.message;
  double meet = 0.0;
  while (blind.trajectory.Evaluate(meet).q.x() < 1.5) meet += kDense;
  const double meet_y = blind.trajectory.Evaluate(meet).q.y();
  const std::vector<MovingDisc> discs = {
      Disc("behind", {meet - 5.0, meet + 5.0}, {{1.5, meet_y + 5.0}, {1.5, meet_y - 5.0}})};
  EXPECT_LT(ClosestApproach(blind.trajectory, discs), -0.5);

  const VelocityObstacleResult result = Plan(start, goal, discs, guide);
  ASSERT_TRUE(result.reached) << result.message;
  ExpectRestToRest(result.trajectory, start, goal);
  ExpectWithinLimits(result.trajectory, limits_);
  EXPECT_GT(ClosestApproach(result.trajectory, discs), 0.0);
  for (const TrajectorySample& sample : result.trajectory.Sample(kDense)) {
    ASSERT_TRUE(checker_->IsValid(sample.q)) << "t = " << sample.t << " q = " << sample.q.transpose();
  }
}

TEST_F(VelocityObstaclesTest, DiscParkedOnTheGoalBoxesTheBaseIn) {
  const Eigen::VectorXd start = Q(-1, 0, 0), goal = Q(2, 0, 0);
  const std::vector<MovingDisc> discs = {Disc("parked", {0.0}, {{2, 0}})};  // there for good
  const VelocityObstacleResult result = Plan(start, goal, discs);
  EXPECT_FALSE(result.reached);
  EXPECT_NE(result.message.find("boxed in"), std::string::npos) << result.message;
  EXPECT_NE(result.message.find("t = "), std::string::npos) << result.message;
  EXPECT_NE(result.message.find("(x, y) = ("), std::string::npos) << result.message;
  // It stopped short, at rest, and never touched the disc.
  const TrajectorySample last = result.trajectory.Evaluate(result.trajectory.duration());
  EXPECT_LE(last.qd.cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_GT((last.q.head<2>() - Eigen::Vector2d(2, 0)).norm(), kBaseRadius + kDiscRadius);
  EXPECT_GT(ClosestApproach(result.trajectory, discs), 0.0);
  ExpectWithinLimits(result.trajectory, limits_);
}

TEST_F(VelocityObstaclesTest, ShortMaxDurationStopsWithWhereAndWhen) {
  const Eigen::VectorXd start = Q(-4, 0, 0), goal = Q(4, 0, 0);
  VelocityObstacleOptions options;
  options.max_duration = 2.0;
  const VelocityObstacleResult result = Plan(start, goal, {}, {}, options);
  EXPECT_FALSE(result.reached);
  EXPECT_NE(result.message.find("max_duration = 2 s"), std::string::npos) << result.message;
  EXPECT_NE(result.message.find("(x, y) = ("), std::string::npos) << result.message;
  EXPECT_GE(result.trajectory.duration(), 2.0);
  const TrajectorySample last = result.trajectory.Evaluate(result.trajectory.duration());
  EXPECT_LE(last.qd.cwiseAbs().maxCoeff(), 1e-9);  // braked to rest
  EXPECT_LT(last.q.x(), 0.0);
  EXPECT_EQ(result.path.back(), last.q);
  ExpectWithinLimits(result.trajectory, limits_);
}

TEST_F(VelocityObstaclesTest, StoppedTerminationReturnsAtOnce) {
  const VelocityObstacleResult result =
      PlanWithVelocityObstacles(*checker_, Q(-4, 0, 0), Q(4, 0, 0), {}, limits_, {}, {}, Termination::AlreadyStopped());
  EXPECT_FALSE(result.reached);
  EXPECT_NE(result.message.find("termination"), std::string::npos) << result.message;
  EXPECT_EQ(result.steps, 0);
  EXPECT_EQ(result.trajectory.Evaluate(0.0).q, Q(-4, 0, 0));
}

/// Seeded random crossings: CHASLES_TEST_SEED and CHASLES_TEST_CASES override the defaults.
TEST_F(VelocityObstaclesTest, RandomCrossingsKeepLimitsEndpointsAndClearance) {
  const char* seed_text = std::getenv("CHASLES_TEST_SEED");
  const char* cases_text = std::getenv("CHASLES_TEST_CASES");
  const std::uint64_t seed = seed_text ? std::strtoull(seed_text, nullptr, 10) : 20261127u;
  const int cases = cases_text ? std::atoi(cases_text) : 40;
  std::mt19937_64 rng(seed);
  const auto uniform = [&rng](double low, double high) {
    return low + (high - low) * (static_cast<double>(rng() >> 11) * 0x1.0p-53);
  };
  int reached = 0, clear = 0;
  for (int k = 0; k < cases; ++k) {
    const Eigen::VectorXd start = Q(uniform(-5, -3), uniform(-4, 4), uniform(-3, 3));
    const Eigen::VectorXd goal = Q(uniform(3, 5), uniform(-4, 4), uniform(-3, 3));
    // 1 to 5 discs on straight runs at 0.2–1 m/s, none on the start at t = 0 or parked on the goal.
    std::vector<MovingDisc> discs;
    const int count = 1 + static_cast<int>(uniform(0, 5));
    while (static_cast<int>(discs.size()) < count) {
      const Eigen::Vector2d from(uniform(-6, 6), uniform(-6, 6)), to(uniform(-6, 6), uniform(-6, 6));
      const double begin = uniform(0, 5), speed = uniform(0.2, 1.0);
      MovingDisc disc = Disc("d" + std::to_string(discs.size()), {begin, begin + (to - from).norm() / speed}, {from, to});
      disc.radius = uniform(0.1, 0.5);
      const double room = kBaseRadius + disc.radius + 0.1;
      if ((from - start.head<2>()).norm() > room && (to - goal.head<2>()).norm() > room) discs.push_back(disc);
    }
    const VelocityObstacleResult result = Plan(start, goal, discs);
    SCOPED_TRACE("case " + std::to_string(k) + " (seed " + std::to_string(seed) + "): " + result.message);
    ExpectWithinLimits(result.trajectory, limits_);
    const Eigen::VectorXd end = result.trajectory.Evaluate(result.trajectory.duration()).q;
    ExpectRestToRest(result.trajectory, start, result.reached ? goal : end);
    EXPECT_EQ(result.message.empty(), result.reached);
    const VerificationReport report =
        VerifyTrajectory(result.trajectory, start, result.reached ? goal : end, *checker_, limits_);
    EXPECT_TRUE(report.ok) << report.reason;
    reached += result.reached ? 1 : 0;
    clear += ClosestApproach(result.trajectory, discs) > 0.0 ? 1 : 0;
  }
  // Reactive and incomplete: a disc can still outrun the base, so rates rather than every case.
  EXPECT_GE(reached, 0.9 * cases);
  EXPECT_GE(clear, 0.95 * cases);
}

TEST_F(VelocityObstaclesTest, InvalidInputIsRefusedNamingTheField) {
  const Eigen::VectorXd start = Q(-4, 0, 0), goal = Q(4, 0, 0);
  // An arm (two revolute links) is not a planar base.
  const std::string urdf = R"(<?xml version="1.0"?>
<robot name="two_link">
  <link name="base"/>
  <joint name="shoulder" type="revolute">
    <parent link="base"/><child link="upper"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" velocity="1" effort="10"/>
  </joint>
  <link name="upper">
    <collision><origin xyz="0.25 0 0"/><geometry><box size="0.5 0.1 0.1"/></geometry></collision>
  </link>
  <joint name="elbow" type="revolute">
    <parent link="upper"/><child link="fore"/><origin xyz="0.5 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" velocity="1" effort="10"/>
  </joint>
  <link name="fore">
    <collision><origin xyz="0.25 0 0"/><geometry><box size="0.5 0.1 0.1"/></geometry></collision>
  </link>
</robot>)";
  const CollisionChecker arm(RobotModel::FromUrdf(urdf), std::make_shared<Scene>());
  std::string message = InvalidArgumentMessage([&] {
    PlanWithVelocityObstacles(arm, Q(0, 0, 0), Q(1, 1, 0), {}, limits_, {}, {}, Termination());
  });
  EXPECT_NE(message.find("robot 'two_link'"), std::string::npos) << message;
  EXPECT_NE(message.find("planar"), std::string::npos) << message;

  message = InvalidArgumentMessage([&] { Plan(Q(std::nan(""), 0, 0), goal, {}); });
  EXPECT_EQ(message, "start[0] = nan must be finite");

  message = InvalidArgumentMessage([&] {
    Plan(start, goal, {Disc("ok", {0.0}, {{0, 3}}), Disc("bad", {0.0, 0.7, 0.5}, {{0, 0}, {1, 0}, {2, 0}})});
  });
  EXPECT_EQ(message, "discs[1].times[2] = 0.5 must be greater than the previous 0.7");

  message = InvalidArgumentMessage([&] { Plan(start, goal, {Disc("short", {0.0, 1.0, 2.0}, {{0, 0}, {1, 0}})}); });
  EXPECT_NE(message.find("discs[0].centres"), std::string::npos) << message;

  message = InvalidArgumentMessage([&] {
    MovingDisc disc = Disc("flat", {0.0}, {{0, 0}});
    disc.radius = 0.0;
    Plan(start, goal, {disc});
  });
  EXPECT_EQ(message, "discs[0].radius = 0 must be finite and > 0");

  message = InvalidArgumentMessage([&] {
    VelocityObstacleOptions options;
    options.heading_samples = 2;
    Plan(start, goal, {}, {}, options);
  });
  EXPECT_NE(message.find("options.heading_samples = 2"), std::string::npos) << message;

  message = InvalidArgumentMessage([&] { Plan(start, goal, {}, {start, Eigen::Vector2d(1, 1)}); });
  EXPECT_NE(message.find("guide[1]"), std::string::npos) << message;
}

}  // namespace
}  // namespace chasles
