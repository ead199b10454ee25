// Direct collocation in Ipopt: near-minimum times on straight rest-to-rest segments (exact
// T* known), exact limits between knots, jerk limits with q̈ = 0 at rest, torque limits on the
// Panda, the jerk weight, clearance around the planar fixture's post (the straight line
// collides), named errors, stop(), determinism. Everything ok must pass VerifyTrajectory.

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "chasles/collision/collision_checker.h"
#include "chasles/optimizers/collocation.h"
#include "chasles/optimizers/verification.h"
#include "chasles/robot/dynamics.h"
#include "chasles/robot/error.h"
#include "../budget_scale.h"
#include "planar_fixture.h"
#include "test_util.h"

namespace chasles {
namespace {

using test::ReadFile;
using ::testing::HasSubstr;

/// Default options; the time budget (5 s) is scaled under the sanitizers (budget_scale.h).
CollocationOptions TestOptions() {
  CollocationOptions options;
  options.time_budget = test::Budget(options.time_budget);
  return options;
}

/// Exact minimum time of the straight rest-to-rest segment a→b.
double StraightMinimumTime(const Eigen::VectorXd& a, const Eigen::VectorXd& b, const KinematicLimits& limits) {
  const Eigen::VectorXd delta = (b - a).cwiseAbs();
  double V = std::numeric_limits<double>::infinity(), A = V;
  for (int i = 0; i < delta.size(); ++i) {
    V = std::min(V, limits.max_velocity[i] / delta[i]);
    A = std::min(A, limits.max_acceleration[i] / delta[i]);
  }
  return V * V <= A ? 1.0 / V + V / A : 2.0 / std::sqrt(A);
}

/// A lower bound on any rest-to-rest motion a→b: the slowest joint's own minimum time.
double JointwiseMinimumTime(const Eigen::VectorXd& a, const Eigen::VectorXd& b, const KinematicLimits& limits) {
  double best = 0.0;
  for (int i = 0; i < a.size(); ++i) {
    const double d = std::abs(b[i] - a[i]), v = limits.max_velocity[i], acc = limits.max_acceleration[i];
    best = std::max(best, v * v <= acc * d ? d / v + v / acc : 2.0 * std::sqrt(d / acc));
  }
  return best;
}

/// The example Panda (inertia, friction, sphere geometry) in an empty scene or with a box.
std::shared_ptr<const CollisionChecker> Panda(bool with_box) {
  const std::string dir = std::string(CHASLES_SOURCE_DIR) + "/examples/robots/";
  auto robot = RobotModel::FromUrdf(ReadFile(dir + "panda.urdf"), ReadFile(dir + "panda.srdf"));
  auto scene = std::make_shared<Scene>();
  if (with_box) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = Eigen::Vector3d(0.55, 0.0, 0.3);
    scene->AddObject(SceneObject{"box", Shape::Box(Eigen::Vector3d(0.2, 0.6, 0.6), pose)});
  }
  return std::make_shared<CollisionChecker>(robot, scene);
}

Eigen::VectorXd PandaHome() {
  Eigen::VectorXd q(7);
  q << 0.0, -0.6, 0.0, -2.2, 0.0, 1.6, 0.8;
  return q;
}

Eigen::VectorXd PandaAway() {
  Eigen::VectorXd q(7);
  q << 1.2, 0.3, 0.5, -1.2, 0.6, 2.2, -0.4;
  return q;
}

KinematicLimits PandaLimits(const RobotModel& robot) {
  KinematicLimits limits;
  limits.max_velocity = robot.velocity_limits();
  limits.max_acceleration = Eigen::VectorXd::Constant(7, 15.0);
  return limits;
}

/// Exact-limit figures of a trajectory, no checker needed.
void ExpectWithinLimits(const TimedTrajectory& trajectory, const KinematicLimits& limits) {
  const TrajectoryQuality quality = MeasureTrajectory(trajectory, limits, {}, nullptr);
  EXPECT_LE(quality.max_velocity_ratio, 1.0 + 1e-9);
  EXPECT_LE(quality.max_acceleration_ratio, 1.0 + 1e-9);
  if (limits.max_jerk.size() != 0) {
    EXPECT_LE(quality.max_jerk_ratio, 1.0 + 1e-9);
  }
}

void ExpectReportFigures(const OptimizerReport& report) {
  EXPECT_TRUE(report.ok) << report.message;
  EXPECT_EQ(report.status, "Solve_Succeeded");
  EXPECT_GT(report.iterations, 0);
  EXPECT_GT(report.solve_seconds, 0.0);
  EXPECT_LE(report.constraint_violation, 1e-7);
  EXPECT_GE(report.time_scale, 1.0);
}

TEST(Collocation, RestToRestStraightSegmentsNearMinimumTime) {
  test::Random rng(test::TestSeed());
  const int cases = test::TestCases(2);
  for (int c = 0; c < cases; ++c) {
    SCOPED_TRACE("case " + std::to_string(c));
    KinematicLimits limits;
    limits.max_velocity = rng.Vector(7, 0.5, 3.0);
    limits.max_acceleration = rng.Vector(7, 1.0, 10.0);
    const Eigen::VectorXd a = rng.Vector(7, -2.0, 2.0), b = rng.Vector(7, -2.0, 2.0);
    const TimedTrajectory warm = ParameterizeTimeOptimal({a, b}, limits);
    const double tstar = StraightMinimumTime(a, b, limits);
    ASSERT_NEAR(warm.duration(), tstar, 1e-9 * tstar);

    CollocationOptions options = TestOptions();  // K = 100
    const CollocationResult result = OptimizeByCollocation(warm, limits, options);
    ExpectReportFigures(result.report);
    ASSERT_FALSE(result.trajectory.empty());
    EXPECT_EQ(static_cast<int>(result.trajectory.pieces().size()), options.knots - 1);
    EXPECT_EQ(result.trajectory.degree(), 3);
    // Off the straight line the joints may beat T*, never their own minimum times.
    EXPECT_LE(result.trajectory.duration(), 1.01 * tstar);
    EXPECT_GE(result.trajectory.duration(), JointwiseMinimumTime(a, b, limits) * (1.0 - 1e-9));
    EXPECT_NEAR(result.report.objective, result.trajectory.duration() / result.report.time_scale,
                1e-9 * tstar);
    ExpectWithinLimits(result.trajectory, limits);
    const TrajectorySample first = result.trajectory.Evaluate(0.0);
    const TrajectorySample last = result.trajectory.Evaluate(result.trajectory.duration());
    EXPECT_TRUE(test::BitEqual(first.q, a));
    EXPECT_TRUE(test::BitEqual(last.q, b));
    EXPECT_EQ(first.qd.cwiseAbs().maxCoeff(), 0.0);  // the first knot's own value
    EXPECT_LE(last.qd.cwiseAbs().maxCoeff(), 1e-8);   // the last cubic's end: defects close to ~1e-9
  }
}

TEST(Collocation, PassesVerificationOnThePandaAroundABox) {
  const auto checker = Panda(true);
  const KinematicLimits limits = PandaLimits(checker->robot());
  ASSERT_FALSE(checker->IsMotionValid(PandaHome(), PandaAway(), 0.005)) << "the box must be in the way";
  Eigen::VectorXd via(7);
  via << 0.95, -0.81, -0.1, -2.38, -0.35, 2.36, 0.25;
  const JointPath path{PandaHome(), via, PandaAway()};
  ASSERT_TRUE(checker->IsMotionValid(path[0], path[1], 0.005) && checker->IsMotionValid(path[1], path[2], 0.005));
  const TimedTrajectory warm = ParameterizeTimeOptimal(path, limits, {}, checker.get());
  CollocationOptions options = TestOptions();
  options.knots = 40;
  const CollocationResult result = OptimizeByCollocation(warm, limits, options, checker.get());
  ExpectReportFigures(result.report);
  const VerificationReport verified = VerifyTrajectory(result.trajectory, path.front(), path.back(), *checker, limits);
  EXPECT_TRUE(verified.ok) << verified.reason;
  EXPECT_LT(result.trajectory.duration(), warm.duration());
}

TEST(Collocation, JerkLimitsHoldAndTheAccelerationIsZeroAtRest) {
  const auto checker = Panda(false);
  KinematicLimits limits = PandaLimits(checker->robot());
  limits.max_jerk = Eigen::VectorXd::Constant(7, 60.0);
  const TimedTrajectory warm = ParameterizeRestToRest({PandaHome(), PandaAway()}, limits);
  CollocationOptions options = TestOptions();
  options.knots = 40;
  const CollocationResult result = OptimizeByCollocation(warm, limits, options, checker.get());
  ExpectReportFigures(result.report);
  ExpectWithinLimits(result.trajectory, limits);
  EXPECT_EQ(result.trajectory.Evaluate(0.0).qdd.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_LE(result.trajectory.Evaluate(result.trajectory.duration()).qdd.cwiseAbs().maxCoeff(), 1e-9);
  // The straight jerk-limited profile is feasible, so collocation does as well up to its
  // tie-breaking regularisation (1e-3·T₀-relative at most; measured ~1e-5).
  EXPECT_LE(result.trajectory.duration(), warm.duration() * (1.0 + 1e-4));
  const VerificationReport verified = VerifyTrajectory(result.trajectory, PandaHome(), PandaAway(), *checker, limits);
  EXPECT_TRUE(verified.ok) << verified.reason;
  EXPECT_LE(verified.max_jerk_ratio, 1.0 + 1e-9);
}

TEST(Collocation, TorqueLimitsOnThePandaHold) {
  const auto checker = Panda(false);
  const RobotModel& robot = checker->robot();
  ASSERT_TRUE(HasInertia(robot));
  KinematicLimits limits = PandaLimits(robot);
  const TimedTrajectory warm = ParameterizeTimeOptimal({PandaHome(), PandaAway()}, limits);
  CollocationOptions options = TestOptions();
  options.knots = 30;
  const CollocationResult free = OptimizeByCollocation(warm, limits, options, checker.get());
  ASSERT_TRUE(free.report.ok) << free.report.message;

  // Half the unconstrained solution's peak torques (never below what holding still needs).
  Eigen::VectorXd peak = Eigen::VectorXd::Zero(7), hold = Eigen::VectorXd::Zero(7);
  for (const TrajectorySample& s : free.trajectory.Sample(0.002)) {
    peak = peak.cwiseMax(InverseDynamics(robot, s.q, s.qd, s.qdd).cwiseAbs());
    hold = hold.cwiseMax(GravityTorques(robot, s.q).cwiseAbs());
  }
  limits.max_effort = (0.5 * peak).cwiseMax(1.2 * hold + Eigen::VectorXd::Constant(7, 1.0));
  ASSERT_GT(MeasureTrajectory(free.trajectory, limits, {}, checker.get()).max_effort_ratio, 1.05)
      << "the limits must bind";

  const CollocationResult tight = OptimizeByCollocation(warm, limits, options, checker.get());
  ExpectReportFigures(tight.report);
  const VerificationReport verified = VerifyTrajectory(tight.trajectory, PandaHome(), PandaAway(), *checker, limits);
  EXPECT_TRUE(verified.ok) << verified.reason;
  EXPECT_LE(verified.max_effort_ratio, 1.0 + 1e-9);
  EXPECT_LE(MeasureTrajectory(tight.trajectory, limits, {}, checker.get(), 0.002).max_effort_ratio, 1.0 + 1e-3);
  EXPECT_GE(tight.trajectory.duration(), free.trajectory.duration() * (1.0 - 1e-6));
}

TEST(Collocation, TorqueLimitsHoldOnTheDualArmWhoseGrippersHaveMimicFingers) {
  // examples/robots/dual_arm: each gripper coordinate drives two fingers (the second a <mimic>),
  // so its force carries both fingers' inertia and friction (DofFriction: damping 5 + 5, Coulomb
  // 1 + 1). The limits bind, the grippers' too; VerifyTrajectory re-checks the efforts exactly by
  // inverse dynamics. (The result's torques are checked the same way inside the optimiser, which
  // slows the trajectory when they exceed a limit, so this shows the limits hold, not how close
  // the NLP's friction model is.)
  const std::string dir = std::string(CHASLES_SOURCE_DIR) + "/examples/robots/";
  auto robot = RobotModel::FromUrdf(ReadFile(dir + "dual_arm.urdf"), ReadFile(dir + "dual_arm.srdf"));
  ASSERT_EQ(robot->num_dofs(), 13);
  ASSERT_TRUE(HasInertia(*robot));
  const auto checker = std::make_shared<CollisionChecker>(robot, std::make_shared<Scene>());
  Eigen::VectorXd home(13), away(13);
  home << 0.0, 0.4, 0.2, -1.2, 0.0, 0.6, 0.0, 0.4, -0.2, -1.2, 0.0, 0.6, 0.0;
  away << 0.6, -0.3, 0.6, -0.4, 1.0, -0.5, 0.035, 0.8, -0.6, -1.8, -0.8, 0.9, 0.03;
  ASSERT_TRUE(checker->IsMotionValid(home, away, 0.005));
  KinematicLimits limits;
  limits.max_velocity = robot->velocity_limits();
  limits.max_acceleration = Eigen::VectorXd::Constant(13, 8.0);
  limits.max_acceleration[6] = limits.max_acceleration[12] = 0.5;
  const TimedTrajectory warm = ParameterizeTimeOptimal({home, away}, limits);
  CollocationOptions options = TestOptions();
  options.knots = 20;
  const CollocationResult free = OptimizeByCollocation(warm, limits, options, checker.get());
  ASSERT_TRUE(free.report.ok) << free.report.message;
  Eigen::VectorXd peak = Eigen::VectorXd::Zero(13), hold = Eigen::VectorXd::Zero(13);
  for (const TrajectorySample& s : free.trajectory.Sample(0.002)) {
    peak = peak.cwiseMax(InverseDynamics(*robot, s.q, s.qd, s.qdd).cwiseAbs());
    hold = hold.cwiseMax(GravityTorques(*robot, s.q).cwiseAbs());
  }
  // Coulomb friction is always there while a coordinate moves: keep above it (and gravity).
  Eigen::VectorXd coulomb(13);
  for (int d = 0; d < 13; ++d) coulomb[d] = DofFriction(*robot, d).friction;
  EXPECT_DOUBLE_EQ(coulomb[6], 2.0);
  limits.max_effort = (0.7 * peak).cwiseMax(1.2 * (hold + coulomb) + Eigen::VectorXd::Constant(13, 0.1));
  // The grippers' force just above their Coulomb friction: their viscous damping (10 N·s/m, half
  // of it the mimic finger's) is what limits their speed, so the gripper motions set the pace.
  for (int d : {6, 12}) {
    limits.max_effort[d] = coulomb[d] + 0.45;
    EXPECT_GT(peak[d], limits.max_effort[d] * 1.05) << "the gripper limit must bind";
  }
  ASSERT_GT(MeasureTrajectory(free.trajectory, limits, {}, checker.get()).max_effort_ratio, 1.05)
      << "the limits must bind";
  const CollocationResult tight = OptimizeByCollocation(warm, limits, options, checker.get());
  ExpectReportFigures(tight.report);
  const VerificationReport verified = VerifyTrajectory(tight.trajectory, home, away, *checker, limits);
  EXPECT_TRUE(verified.ok) << verified.reason;
  EXPECT_LE(verified.max_effort_ratio, 1.0 + 1e-9);
  EXPECT_LE(MeasureTrajectory(tight.trajectory, limits, {}, checker.get(), 0.002).max_effort_ratio, 1.0 + 1e-3);
}

TEST(Collocation, JerkWeightLowersTheJerkIntegral) {
  const auto checker = Panda(false);
  const KinematicLimits limits = PandaLimits(checker->robot());
  const TimedTrajectory warm = ParameterizeTimeOptimal({PandaHome(), PandaAway()}, limits);
  CollocationOptions options = TestOptions();
  options.knots = 30;
  const CollocationResult plain = OptimizeByCollocation(warm, limits, options, checker.get());
  options.jerk_weight = 1e-4;
  const CollocationResult smooth = OptimizeByCollocation(warm, limits, options, checker.get());
  ASSERT_TRUE(plain.report.ok) << plain.report.message;
  ExpectReportFigures(smooth.report);
  const TrajectoryQuality q0 = MeasureTrajectory(plain.trajectory, limits, {}, nullptr);
  const TrajectoryQuality q1 = MeasureTrajectory(smooth.trajectory, limits, {}, nullptr);
  EXPECT_LT(q1.jerk_integral, 0.5 * q0.jerk_integral);
  EXPECT_GE(q1.duration, q0.duration * (1.0 - 1e-6));
  EXPECT_NEAR(smooth.report.objective, q1.duration + options.jerk_weight * q1.jerk_integral,
              1e-6 * smooth.report.objective);
  const VerificationReport verified = VerifyTrajectory(smooth.trajectory, PandaHome(), PandaAway(), *checker, limits);
  EXPECT_TRUE(verified.ok) << verified.reason;
}

TEST(Collocation, ClearanceAroundThePostWhereTheStraightLineCollides) {
  const auto checker = test::PlanarCheckerWithPost();
  const JointPath path = test::ZigZagAroundPost();
  ASSERT_FALSE(checker->IsMotionValid(path.front(), path.back(), 0.005));
  KinematicLimits limits;
  limits.max_velocity = Eigen::Vector2d(2.0, 2.0);
  limits.max_acceleration = Eigen::Vector2d(4.0, 4.0);
  const TimedTrajectory warm = ParameterizeTimeOptimal(path, limits, {}, checker.get());
  CollocationOptions options = TestOptions();
  options.knots = 40;
  const CollocationResult result = OptimizeByCollocation(warm, limits, options, checker.get());
  ExpectReportFigures(result.report);
  const VerificationReport verified = VerifyTrajectory(result.trajectory, path.front(), path.back(), *checker, limits);
  EXPECT_TRUE(verified.ok) << verified.reason;
  // The clearance holds at every knot and interval midpoint (not the ends: they are given).
  const auto& pieces = result.trajectory.pieces();
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    const double t0 = pieces[k].t0, h = pieces[k].duration;
    if (k > 0) {
      EXPECT_GE(checker->Clearance(result.trajectory.Evaluate(t0).q), options.clearance - 1e-6) << k;
    }
    EXPECT_GE(checker->Clearance(result.trajectory.Evaluate(t0 + h / 2).q), options.clearance - 1e-6) << k;
  }
  EXPECT_GT(MeasureTrajectory(result.trajectory, limits, path, checker.get(), 0.001).min_clearance, 0.0);
  EXPECT_LT(result.trajectory.duration(), 0.6 * warm.duration());
}

TEST(Collocation, KeepsNonZeroEndVelocitiesOfTheWarmStart) {
  KinematicLimits limits;
  limits.max_velocity = Eigen::Vector3d(1.0, 2.0, 1.5);
  limits.max_acceleration = Eigen::Vector3d(3.0, 4.0, 2.0);
  const JointPath path{Eigen::Vector3d(0.0, 0.0, 0.0), Eigen::Vector3d(1.0, 0.5, -0.5)};
  TimeOptimalOptions timing;
  timing.start_velocity = 0.3 * (path[1] - path[0]);
  timing.end_velocity = 0.2 * (path[1] - path[0]);
  const TimedTrajectory warm = ParameterizeTimeOptimal(path, limits, timing);
  CollocationOptions options = TestOptions();
  options.knots = 20;
  const CollocationResult result = OptimizeByCollocation(warm, limits, options);
  ExpectReportFigures(result.report);
  EXPECT_EQ(result.report.time_scale, 1.0);
  EXPECT_LE((result.trajectory.Evaluate(0.0).qd - timing.start_velocity).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LE((result.trajectory.Evaluate(result.trajectory.duration()).qd - timing.end_velocity).cwiseAbs().maxCoeff(),
            1e-8);
  ExpectWithinLimits(result.trajectory, limits);
}

TEST(Collocation, RepeatsBitForBit) {
  KinematicLimits limits;
  limits.max_velocity = Eigen::Vector3d(1.0, 2.0, 1.5);
  limits.max_acceleration = Eigen::Vector3d(3.0, 4.0, 2.0);
  const TimedTrajectory warm =
      ParameterizeTimeOptimal({Eigen::Vector3d(0.0, 0.0, 0.0), Eigen::Vector3d(1.0, -0.5, 0.7)}, limits);
  CollocationOptions options = TestOptions();
  options.knots = 20;
  const CollocationResult a = OptimizeByCollocation(warm, limits, options);
  const CollocationResult b = OptimizeByCollocation(warm, limits, options);
  ASSERT_TRUE(a.report.ok) << a.report.message;
  ASSERT_EQ(a.trajectory.pieces().size(), b.trajectory.pieces().size());
  EXPECT_EQ(a.report.iterations, b.report.iterations);
  for (std::size_t k = 0; k < a.trajectory.pieces().size(); ++k) {
    EXPECT_EQ(a.trajectory.pieces()[k].duration, b.trajectory.pieces()[k].duration);
    EXPECT_TRUE(a.trajectory.pieces()[k].coefficients == b.trajectory.pieces()[k].coefficients);
  }
}

TEST(Collocation, ConcurrentCallsAgreeWithASequentialOne) {
  // Ipopt runs one solve at a time per process (Debian's MUMPS aborts on concurrent solves);
  // callers in several threads get the same result as alone.
  KinematicLimits limits;
  limits.max_velocity = Eigen::Vector3d(1.0, 2.0, 1.5);
  limits.max_acceleration = Eigen::Vector3d(3.0, 4.0, 2.0);
  const TimedTrajectory warm =
      ParameterizeTimeOptimal({Eigen::Vector3d(0.0, 0.0, 0.0), Eigen::Vector3d(1.0, -0.5, 0.7)}, limits);
  CollocationOptions options = TestOptions();
  options.knots = 20;
  const CollocationResult alone = OptimizeByCollocation(warm, limits, options);
  ASSERT_TRUE(alone.report.ok) << alone.report.message;
  std::vector<CollocationResult> results(4);
  std::vector<std::thread> threads;
  for (std::size_t i = 0; i < results.size(); ++i) {
    threads.emplace_back([&, i] { results[i] = OptimizeByCollocation(warm, limits, options); });
  }
  for (std::thread& thread : threads) thread.join();
  for (const CollocationResult& result : results) {
    EXPECT_TRUE(result.report.ok) << result.report.message;
    EXPECT_EQ(result.report.iterations, alone.report.iterations);
    EXPECT_EQ(result.trajectory.duration(), alone.trajectory.duration());
  }
}

TEST(Collocation, AWarmStartThatDoesNotMoveStays) {
  KinematicLimits limits;
  limits.max_velocity = Eigen::Vector2d(1.0, 1.0);
  limits.max_acceleration = Eigen::Vector2d(1.0, 1.0);
  const Eigen::Vector2d q(0.3, -0.2);
  const CollocationResult result = OptimizeByCollocation(ParameterizeRestToRest({q}, limits), limits, {});
  EXPECT_TRUE(result.report.ok);
  EXPECT_EQ(result.trajectory.duration(), 0.0);
  EXPECT_TRUE(test::BitEqual(result.trajectory.Evaluate(0.0).q, q));
}

TEST(Collocation, StopEndsTheSolveWithoutATrajectory) {
  KinematicLimits limits;
  limits.max_velocity = Eigen::Vector2d(1.0, 1.0);
  limits.max_acceleration = Eigen::Vector2d(1.0, 1.0);
  const TimedTrajectory warm = ParameterizeTimeOptimal({Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(1.0, 2.0)}, limits);
  CollocationOptions options = TestOptions();
  options.knots = 20;
  options.stop = [] { return true; };
  const CollocationResult result = OptimizeByCollocation(warm, limits, options);
  EXPECT_FALSE(result.report.ok);
  EXPECT_EQ(result.report.status, "User_Requested_Stop");
  EXPECT_THAT(result.report.message, HasSubstr("stopped by the caller"));
  EXPECT_TRUE(result.trajectory.empty());
}

TEST(Collocation, ImpossibleTorqueLimitsAreReportedNotOk) {
  const auto checker = Panda(false);
  const KinematicLimits kinematic = PandaLimits(checker->robot());
  const TimedTrajectory warm = ParameterizeTimeOptimal({PandaHome(), PandaAway()}, kinematic);
  KinematicLimits limits = kinematic;
  limits.max_effort = Eigen::VectorXd::Constant(7, 2.0);  // the shoulder cannot even hold the arm
  CollocationOptions options = TestOptions();
  options.knots = 10;
  options.max_iterations = 100;
  const CollocationResult result = OptimizeByCollocation(warm, limits, options, checker.get());
  EXPECT_FALSE(result.report.ok);
  EXPECT_FALSE(result.report.message.empty());
  EXPECT_TRUE(result.trajectory.empty());
}

void ExpectInvalid(const std::function<void()>& call, const std::string& message) {
  try {
    call();
    ADD_FAILURE() << "no exception, expected: " << message;
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_EQ(std::string(e.what()), message);
  }
}

TEST(Collocation, NamedErrors) {
  KinematicLimits limits;
  limits.max_velocity = Eigen::Vector2d(1.0, 1.0);
  limits.max_acceleration = Eigen::Vector2d(1.0, 1.0);
  const TimedTrajectory warm = ParameterizeTimeOptimal({Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(1.0, 2.0)}, limits);
  const auto with = [&](auto change) {
    CollocationOptions options;
    change(options);
    return [options, &warm, &limits] { OptimizeByCollocation(warm, limits, options); };
  };
  ExpectInvalid(with([](CollocationOptions& o) { o.knots = 1; }), "collocation knots = 1 must be >= 2");
  ExpectInvalid(with([](CollocationOptions& o) { o.knots = 2001; }), "collocation knots = 2001 must be at most 2000");
  ExpectInvalid(with([](CollocationOptions& o) { o.corridor = 1.5; }), "collocation corridor = 1.5 must be in (0, 1] rad");
  ExpectInvalid(with([](CollocationOptions& o) { o.jerk_weight = -1.0; }),
                "collocation jerk_weight = -1 must be finite and >= 0");
  ExpectInvalid(with([](CollocationOptions& o) { o.jerk_weight = std::nan(""); }),
                "collocation jerk_weight = nan must be finite and >= 0");
  ExpectInvalid(with([](CollocationOptions& o) { o.clearance = -0.5; }),
                "collocation clearance = -0.5 must be finite and >= 0");
  ExpectInvalid(with([](CollocationOptions& o) { o.activation_distance = -1.0; }),
                "collocation activation_distance = -1 must be finite and >= 0");
  ExpectInvalid(with([](CollocationOptions& o) { o.max_iterations = 0; }),
                "collocation max_iterations = 0 must be >= 1");
  ExpectInvalid(with([](CollocationOptions& o) { o.tolerance = 0.0; }),
                "collocation tolerance = 0 must be finite and > 0");
  ExpectInvalid(with([](CollocationOptions& o) { o.time_budget = -2.0; }),
                "collocation time_budget = -2 must be > 0");
  ExpectInvalid([&] { OptimizeByCollocation(TimedTrajectory(), limits, {}); }, "collocation warm_start is empty");
  KinematicLimits bad = limits;
  bad.max_velocity[1] = 0.0;
  ExpectInvalid([&] { OptimizeByCollocation(warm, bad, {}); }, "max_velocity[1] = 0 must be > 0");
  bad = limits;
  bad.max_acceleration[0] = -3.0;
  ExpectInvalid([&] { OptimizeByCollocation(warm, bad, {}); }, "max_acceleration[0] = -3 must be > 0");
  bad = limits;
  bad.max_effort = Eigen::Vector2d(5.0, 5.0);
  ExpectInvalid([&] { OptimizeByCollocation(warm, bad, {}); },
                "max_effort needs a robot with inertia on every moving link (pass its checker to collocation)");
  const auto panda = Panda(false);
  ExpectInvalid([&] { OptimizeByCollocation(warm, limits, {}, panda.get()); },
                "collocation warm_start has 2 joints, robot has 7");
}

}  // namespace
}  // namespace chasles

namespace chasles {
namespace {

// Figures for docs/ (no assertions on time): random straight rest-to-rest 7-DOF segments with
// random limits at K = 100, as the benchmark aim. Run with
//   optimizers_collocation_test --gtest_also_run_disabled_tests --gtest_filter=*Figures*
// (CHASLES_TEST_CASES sets the number of segments, default 20; CHASLES_COLLOCATION_KNOTS the
// knots, default 100).
TEST(Collocation, DISABLED_FiguresForTheDocs) {
  test::Random rng(test::TestSeed());
  const int cases = test::TestCases(20);
  double worst_ratio = 0.0, sum_ratio = 0.0, sum_ms = 0.0, max_ms = 0.0, sum_iterations = 0.0;
  int max_iterations = 0, not_ok = 0;
  for (int c = 0; c < cases; ++c) {
    KinematicLimits limits;
    limits.max_velocity = rng.Vector(7, 0.5, 3.0);
    limits.max_acceleration = rng.Vector(7, 1.0, 10.0);
    const Eigen::VectorXd a = rng.Vector(7, -2.0, 2.0), b = rng.Vector(7, -2.0, 2.0);
    const TimedTrajectory warm = ParameterizeTimeOptimal({a, b}, limits);
    CollocationOptions options;
    if (const char* knots = std::getenv("CHASLES_COLLOCATION_KNOTS")) options.knots = std::atoi(knots);
    const CollocationResult result = OptimizeByCollocation(warm, limits, options);
    if (!result.report.ok) {
      ++not_ok;
      continue;
    }
    const double ratio = result.trajectory.duration() / StraightMinimumTime(a, b, limits);
    const double ms = 1e3 * result.report.solve_seconds;
    worst_ratio = std::max(worst_ratio, ratio);
    sum_ratio += ratio;
    sum_ms += ms;
    max_ms = std::max(max_ms, ms);
    sum_iterations += result.report.iterations;
    max_iterations = std::max(max_iterations, result.report.iterations);
  }
  const int ok = cases - not_ok;
  std::printf("K = %d, %d segments, %d not ok: duration/T* mean %.5f max %.5f; %.0f ms mean, %.0f ms max; "
              "iterations mean %.1f, max %d\n",
              std::getenv("CHASLES_COLLOCATION_KNOTS") ? std::atoi(std::getenv("CHASLES_COLLOCATION_KNOTS")) : 100,
              cases, not_ok, sum_ratio / ok, worst_ratio, sum_ms / ok, max_ms, sum_iterations / ok, max_iterations);

  // The Panda around the box (clearance), and with torque limits, at the same K.
  const auto checker = Panda(true);
  KinematicLimits limits = PandaLimits(checker->robot());
  Eigen::VectorXd via(7);
  via << 0.95, -0.81, -0.1, -2.38, -0.35, 2.36, 0.25;
  const TimedTrajectory warm = ParameterizeTimeOptimal({PandaHome(), via, PandaAway()}, limits, {}, checker.get());
  CollocationOptions options;
  if (const char* knots = std::getenv("CHASLES_COLLOCATION_KNOTS")) options.knots = std::atoi(knots);
  const CollocationResult around = OptimizeByCollocation(warm, limits, options, checker.get());
  std::printf("Panda around the box: ok %d, %.3f s (warm start %.3f s), %.0f ms, %d iterations; %s\n", around.report.ok,
              around.trajectory.empty() ? 0.0 : around.trajectory.duration(), warm.duration(),
              1e3 * around.report.solve_seconds, around.report.iterations, around.report.message.c_str());
  const auto empty = Panda(false);
  const TimedTrajectory straight = ParameterizeTimeOptimal({PandaHome(), PandaAway()}, limits);
  const CollocationResult free = OptimizeByCollocation(straight, limits, options, empty.get());
  Eigen::VectorXd peak = Eigen::VectorXd::Zero(7), hold = Eigen::VectorXd::Zero(7);
  for (const TrajectorySample& s : free.trajectory.Sample(0.002)) {
    peak = peak.cwiseMax(InverseDynamics(empty->robot(), s.q, s.qd, s.qdd).cwiseAbs());
    hold = hold.cwiseMax(GravityTorques(empty->robot(), s.q).cwiseAbs());
  }
  limits.max_effort = (0.5 * peak).cwiseMax(1.2 * hold + Eigen::VectorXd::Constant(7, 1.0));
  const CollocationResult torque = OptimizeByCollocation(straight, limits, options, empty.get());
  std::printf("Panda with half the peak torques: ok %d, %.3f s (free %.3f s), %.0f ms (free %.0f ms), %d iterations; %s\n",
              torque.report.ok, torque.trajectory.empty() ? 0.0 : torque.trajectory.duration(),
              free.trajectory.duration(), 1e3 * torque.report.solve_seconds, 1e3 * free.report.solve_seconds,
              torque.report.iterations, torque.report.message.c_str());
}

}  // namespace
}  // namespace chasles
