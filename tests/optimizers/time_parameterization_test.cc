// Exact minimum-time rest-to-rest parameterisation: reference durations, limits at 1 kHz,
// finite differences, multi-waypoint paths with reversals and duplicates, sampling, validation.

#include "chasles/optimizers/time_parameterization.h"

#include <cmath>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "chasles/optimizers/timed_trajectory.h"
#include "chasles/robot/error.h"
#include "random_paths.h"
#include "test_util.h"

namespace chasles {
namespace {

using test::BitEqual;
using test::FirstExceeding;
using test::Random;
using test::RandomLimits;
using test::RandomPath;
using test::ReferenceDuration;

constexpr int kDofs = 7;
constexpr double kPeriod = 1e-3;  // 1 kHz

TEST(RestToRest, StraightSegmentsHaveTheExactMinimumTimeAndRespectLimits) {
  Random rng(test::TestSeed());
  const int cases = test::TestCases(1000);
  int triangles = 0, trapezoids = 0;
  for (int c = 0; c < cases; ++c) {
    SCOPED_TRACE("case " + std::to_string(c) + " seed " + std::to_string(test::TestSeed()));
    const KinematicLimits limits = RandomLimits(rng, kDofs);
    const Eigen::VectorXd a = rng.Vector(kDofs, -2.0, 2.0);
    // Scale the motion over three decades so both profile shapes occur; freeze some joints.
    const double scale = std::pow(10.0, rng.Uniform(-2.5, 0.3));
    Eigen::VectorXd b = a + scale * rng.Vector(kDofs, -2.0, 2.0);
    for (int i = 0; i < kDofs; ++i) {
      if (rng.Uniform() < 0.15) b[i] = a[i];
    }
    if (b == a) b[0] += 0.5;

    bool triangle = false;
    const double expected = ReferenceDuration(a, b, limits, &triangle);
    (triangle ? triangles : trapezoids)++;
    const TimedTrajectory traj = ParameterizeRestToRest({a, b}, limits);
    ASSERT_LE(traj.pieces().size(), 3u);  // accelerate, cruise, decelerate
    ASSERT_NEAR(traj.duration(), expected, 1e-12 * expected);

    // The exact profile at 1 kHz: within limits, and central differences of positions agree
    // with the returned velocities (up to a·h where the acceleration jumps inside the window).
    const double h = kPeriod;
    double peak_velocity_ratio = 0.0;
    for (double t = 0.0; t <= traj.duration(); t += h) {
      const TrajectorySample x = traj.Evaluate(t);
      ASSERT_EQ(FirstExceeding(x.qd, limits.max_velocity, 1e-9), -1) << "t = " << t;
      ASSERT_EQ(FirstExceeding(x.qdd, limits.max_acceleration, 1e-9), -1) << "t = " << t;
      for (int i = 0; i < kDofs; ++i) {
        peak_velocity_ratio = std::fmax(peak_velocity_ratio, std::fabs(x.qd[i]) / limits.max_velocity[i]);
      }
      if (t - h <= 0.0 || t + h >= traj.duration()) continue;
      const Eigen::VectorXd fd = (traj.Evaluate(t + h).q - traj.Evaluate(t - h).q) / (2 * h);
      for (int i = 0; i < kDofs; ++i) {
        ASSERT_NEAR(fd[i], x.qd[i], limits.max_acceleration[i] * h + 1e-9) << "joint " << i << " t = " << t;
      }
    }
    // A trapezoid reaches the velocity limit of its binding joint (minimum time).
    if (!triangle) {
      EXPECT_GT(peak_velocity_ratio, 1.0 - 1e-3);
    }
    EXPECT_TRUE(BitEqual(traj.Evaluate(0.0).q, a));
    EXPECT_TRUE(BitEqual(traj.Evaluate(traj.duration()).q, b));
  }
  if (cases >= 200) {
    EXPECT_GT(triangles, cases / 20) << "too few triangular profiles exercised";
    EXPECT_GT(trapezoids, cases / 20) << "too few trapezoidal profiles exercised";
  }
}

TEST(RestToRest, BindingJointHitsItsAccelerationLimit) {
  KinematicLimits limits;
  limits.max_velocity = Eigen::Vector2d(1.0, 1.0);
  limits.max_acceleration = Eigen::Vector2d(2.0, 2.0);
  // Δ = (2, 1): V = 0.5, A = 1, V² ≤ A → trapezoid, T = 1/V + V/A = 2.5 s.
  const TimedTrajectory traj = ParameterizeRestToRest({Eigen::Vector2d(0, 0), Eigen::Vector2d(2, 1)}, limits);
  EXPECT_DOUBLE_EQ(traj.duration(), 2.5);
  ASSERT_EQ(traj.pieces().size(), 3u);
  EXPECT_DOUBLE_EQ(traj.pieces()[0].duration, 0.5);
  EXPECT_DOUBLE_EQ(traj.pieces()[1].duration, 1.5);
  // Right limit at a phase boundary: when the cruise phase starts, q̈ = 0.
  EXPECT_EQ(traj.Evaluate(traj.pieces()[1].t0).qdd, Eigen::Vector2d::Zero());
  EXPECT_DOUBLE_EQ(traj.Evaluate(0.25).qdd[0], 2.0);
  EXPECT_DOUBLE_EQ(traj.Evaluate(1.0).qd[0], 1.0);
  EXPECT_DOUBLE_EQ(traj.Evaluate(2.0).qdd[0], -2.0);  // decelerating from t = 2.0 on
  // At rest at both ends (accelerating from rest, decelerating into it).
  EXPECT_EQ(traj.Evaluate(0.0).qd, Eigen::Vector2d::Zero());
  EXPECT_NEAR(traj.Evaluate(2.5).qd.cwiseAbs().maxCoeff(), 0.0, 1e-15);
  EXPECT_DOUBLE_EQ(traj.Evaluate(0.0).qdd[0], 2.0);
  EXPECT_DOUBLE_EQ(traj.Evaluate(2.5).qdd[0], -2.0);
  EXPECT_EQ(traj.Evaluate(-1.0).q, Eigen::Vector2d(0, 0));
  EXPECT_EQ(traj.Evaluate(9.0).q, Eigen::Vector2d(2, 1));

  // Δ = (0.1, 0): V = 10, A = 20, V² > A → triangle, T = 2/√20.
  const TimedTrajectory tri = ParameterizeRestToRest({Eigen::Vector2d(0, 0), Eigen::Vector2d(0.1, 0)}, limits);
  EXPECT_NEAR(tri.duration(), 2.0 / std::sqrt(20.0), 1e-15);
  EXPECT_EQ(tri.pieces().size(), 2u);  // no cruise
  EXPECT_NEAR(tri.Evaluate(tri.duration() / 2).q[0], 0.05, 1e-15);
}

TEST(RestToRest, MultiWaypointPathsRespectLimitsEverywhere) {
  Random rng(test::TestSeed() + 1);
  const int cases = std::max(1, test::TestCases(1000) / 4);
  const double h = kPeriod;
  for (int c = 0; c < cases; ++c) {
    SCOPED_TRACE("case " + std::to_string(c));
    const KinematicLimits limits = RandomLimits(rng, kDofs);
    const JointPath path = RandomPath(rng, kDofs);
    const TimedTrajectory traj = ParameterizeRestToRest(path, limits);

    // Duplicates dropped; each segment takes its exact rest-to-rest time and the robot
    // passes every waypoint at rest.
    JointPath distinct{path.front()};
    for (const auto& q : path) {
      if (!(q == distinct.back())) distinct.push_back(q);
    }
    if (distinct.size() == 1) {
      ASSERT_EQ(traj.pieces().size(), 1u);
      EXPECT_EQ(traj.duration(), 0.0);
      continue;
    }
    double expected_total = 0.0;
    for (std::size_t k = 0; k + 1 < distinct.size(); ++k) {
      const TrajectorySample at = traj.Evaluate(expected_total);
      EXPECT_LE((at.q - distinct[k]).cwiseAbs().maxCoeff(), 1e-9) << k;
      EXPECT_LE(at.qd.cwiseAbs().maxCoeff(), 1e-9) << k;
      bool triangle;
      expected_total += ReferenceDuration(distinct[k], distinct[k + 1], limits, &triangle);
    }
    EXPECT_NEAR(traj.duration(), expected_total, 1e-12 * expected_total);
    EXPECT_TRUE(BitEqual(traj.Evaluate(0).q, path.front()));
    EXPECT_TRUE(BitEqual(traj.Evaluate(traj.duration()).q, path.back()));

    // 1 kHz: returned derivatives within limits; finite differences of positions too (1e-3);
    // positions equal the trapezoid-rule integral of the velocities up to the rule's error at
    // the acceleration jumps between pieces (≤ aᵢh²/4 each).
    const int kinks = static_cast<int>(traj.pieces().size()) + 1;
    std::vector<TrajectorySample> xs;
    for (long k = 0; k * h <= traj.duration(); ++k) xs.push_back(traj.Evaluate(k * h));
    Eigen::VectorXd integral = Eigen::VectorXd::Zero(kDofs);
    for (std::size_t k = 0; k < xs.size(); ++k) {
      ASSERT_EQ(FirstExceeding(xs[k].qd, limits.max_velocity, 1e-9), -1) << "t = " << xs[k].t;
      ASSERT_EQ(FirstExceeding(xs[k].qdd, limits.max_acceleration, 1e-9), -1) << "t = " << xs[k].t;
      ASSERT_TRUE(xs[k].q.allFinite());
      if (k == 0) continue;
      const Eigen::VectorXd fd_v = (xs[k].q - xs[k - 1].q) / h;
      ASSERT_EQ(FirstExceeding(fd_v, limits.max_velocity, 1e-3), -1) << "t = " << xs[k].t;
      if (k + 1 < xs.size()) {
        const Eigen::VectorXd fd_a = (xs[k + 1].q - 2 * xs[k].q + xs[k - 1].q) / (h * h);
        ASSERT_EQ(FirstExceeding(fd_a, limits.max_acceleration, 1e-3), -1) << "t = " << xs[k].t;
      }
      integral += 0.5 * h * (xs[k].qd + xs[k - 1].qd);
      const Eigen::VectorXd moved = xs[k].q - xs[0].q;
      for (int i = 0; i < kDofs; ++i) {
        ASSERT_NEAR(integral[i], moved[i], kinks * limits.max_acceleration[i] * h * h / 4 + 1e-9)
            << "joint " << i << " t = " << xs[k].t;
      }
    }
  }
}

TEST(RestToRest, SingleOrRepeatedWaypointGivesOneSampleThere) {
  KinematicLimits limits;
  limits.max_velocity = Eigen::Vector3d::Constant(1.0);
  limits.max_acceleration = Eigen::Vector3d::Constant(1.0);
  const Eigen::Vector3d q(0.1, -0.2, 0.3);
  for (const JointPath& path : {JointPath{q}, JointPath{q, q, q}}) {
    const TimedTrajectory traj = ParameterizeRestToRest(path, limits);
    ASSERT_FALSE(traj.empty());
    EXPECT_EQ(traj.duration(), 0.0);
    EXPECT_EQ(traj.num_dofs(), 3);
    const auto samples = traj.Sample(0.01);
    ASSERT_EQ(samples.size(), 1u);
    EXPECT_EQ(samples[0].t, 0.0);
    EXPECT_TRUE(BitEqual(samples[0].q, q));
    EXPECT_EQ(samples[0].qd, Eigen::Vector3d::Zero());
  }
  // Trailing duplicates that differ only in the sign of zero: the last waypoint bit for bit.
  const Eigen::Vector3d plus_zero(1.0, 0.0, 0.0), minus_zero(1.0, -0.0, 0.0);
  const TimedTrajectory traj = ParameterizeRestToRest({q, plus_zero, minus_zero}, limits);
  EXPECT_LE(traj.pieces().size(), 3u);
  EXPECT_TRUE(BitEqual(traj.Evaluate(traj.duration()).q, minus_zero));
}

TEST(Sample, FirstAndLastExactPeriodRespected) {
  Random rng(test::TestSeed() + 2);
  for (int c = 0; c < 50; ++c) {
    SCOPED_TRACE("case " + std::to_string(c));
    const KinematicLimits limits = RandomLimits(rng, kDofs);
    const JointPath path = RandomPath(rng, kDofs);
    const TimedTrajectory traj = ParameterizeRestToRest(path, limits);
    const double period = rng.Uniform(0.001, 0.05);
    const auto samples = traj.Sample(period);
    ASSERT_FALSE(samples.empty());
    EXPECT_EQ(samples.front().t, 0.0);
    EXPECT_TRUE(BitEqual(samples.front().q, path.front()));
    EXPECT_TRUE(BitEqual(samples.back().q, path.back()));
    EXPECT_EQ(samples.front().qd, Eigen::VectorXd::Zero(kDofs));
    EXPECT_LE(samples.back().qd.cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_EQ(samples.back().t, traj.duration());
    if (traj.duration() == 0.0) {
      EXPECT_EQ(samples.size(), 1u);
      continue;
    }
    // t = k·period for all but the last, which is the end; no gap beyond one period.
    for (std::size_t k = 0; k + 1 < samples.size(); ++k) {
      EXPECT_EQ(samples[k].t, static_cast<double>(k) * period);
      const double gap = samples[k + 1].t - samples[k].t;
      EXPECT_GT(gap, 0.0);
      EXPECT_LE(gap, period * (1 + 1e-9));
    }
    EXPECT_EQ(samples.size(), static_cast<std::size_t>(std::ceil(traj.duration() / period - 1e-9)) + 1);
    // Each sample equals Evaluate at its time.
    for (std::size_t k = 1; k + 1 < samples.size(); k += 7) {
      const TrajectorySample x = traj.Evaluate(samples[k].t);
      EXPECT_EQ(x.q, samples[k].q);
      EXPECT_EQ(x.qd, samples[k].qd);
    }
  }
}

TEST(Sample, DurationAnExactMultipleOfThePeriodGivesNoDuplicateEnd) {
  KinematicLimits limits;
  limits.max_velocity = Eigen::Vector2d(1.0, 1.0);
  limits.max_acceleration = Eigen::Vector2d(2.0, 2.0);
  const TimedTrajectory traj = ParameterizeRestToRest({Eigen::Vector2d(0, 0), Eigen::Vector2d(2, 1)}, limits);
  ASSERT_EQ(traj.duration(), 2.5);
  const auto samples = traj.Sample(0.5);
  ASSERT_EQ(samples.size(), 6u);
  EXPECT_EQ(samples[4].t, 2.0);
  EXPECT_EQ(samples[5].t, 2.5);
  EXPECT_TRUE(TimedTrajectory().Sample(0.1).empty());
}

template <typename F>
std::string ErrorMessage(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    return e.what();
  }
  return "<no error>";
}

TEST(Validation, LimitsAndPathMessagesNameFieldIndexValueAndRule) {
  KinematicLimits limits;
  limits.max_velocity = Eigen::VectorXd::Constant(7, 1.0);
  limits.max_acceleration = Eigen::VectorXd::Constant(7, 1.0);
  EXPECT_NO_THROW(limits.Validate(7));
  limits.max_velocity[2] = -1;
  EXPECT_EQ(ErrorMessage([&] { limits.Validate(7); }), "max_velocity[2] = -1 must be > 0");
  limits.max_velocity[2] = std::nan("");
  EXPECT_EQ(ErrorMessage([&] { limits.Validate(7); }), "max_velocity[2] = nan must be finite");
  limits.max_velocity[2] = 1.0;
  limits.max_acceleration[4] = 0.0;
  EXPECT_EQ(ErrorMessage([&] { limits.Validate(7); }), "max_acceleration[4] = 0 must be > 0");
  limits.max_acceleration[4] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(ErrorMessage([&] { limits.Validate(7); }), "max_acceleration[4] = inf must be finite");
  limits.max_acceleration = Eigen::VectorXd::Constant(6, 1.0);
  EXPECT_EQ(ErrorMessage([&] { limits.Validate(7); }), "max_acceleration has 6 values, robot has 7 joints");

  KinematicLimits two;
  two.max_velocity = Eigen::Vector2d(1, 1);
  two.max_acceleration = Eigen::Vector2d(1, 1);
  EXPECT_EQ(ErrorMessage([&] { ParameterizeRestToRest({}, two); }), "path has 0 waypoints, needs at least 1");
  EXPECT_EQ(ErrorMessage([&] { ParameterizeRestToRest({Eigen::Vector2d(0, 0), Eigen::Vector3d(0, 0, 0)}, two); }),
            "path[1] has 3 values, path[0] has 2");
  EXPECT_EQ(ErrorMessage([&] {
              ParameterizeRestToRest({Eigen::Vector2d(0, 0), Eigen::Vector2d(0, std::nan(""))}, two);
            }),
            "path[1][1] = nan must be finite");
  EXPECT_EQ(ErrorMessage([&] { ParameterizeRestToRest({Eigen::Vector3d(0, 0, 0)}, two); }),
            "max_velocity has 2 values, robot has 3 joints");
  const TimedTrajectory traj = ParameterizeRestToRest({Eigen::Vector2d(0, 0), Eigen::Vector2d(1, 1)}, two);
  EXPECT_EQ(ErrorMessage([&] { traj.Sample(0.0); }), "sample period = 0 must be finite and > 0");
  EXPECT_EQ(ErrorMessage([&] { traj.Sample(-1.0); }), "sample period = -1 must be finite and > 0");
  EXPECT_THROW(TimedTrajectory().Evaluate(0.0), Error);
}

}  // namespace
}  // namespace chasles
