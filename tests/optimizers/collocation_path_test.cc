// Collocation along a path: the result stays within the corridor of the path and passes every
// interior waypoint in order (checked on samples 0.1 ms apart against a polyline distance written
// here), closed paths move, the free mode refuses a path that returns to its start, and the
// returned positions, velocities and accelerations agree with each other: finite differences of
// the 10 kHz positions stay within the limits, and the pieces meet at every knot.

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "chasles/optimizers/collocation.h"
#include "chasles/optimizers/time_parameterization.h"
#include "chasles/optimizers/verification.h"
#include "chasles/robot/error.h"
#include "../budget_scale.h"
#include "test_util.h"

namespace chasles {
namespace {

using ::testing::HasSubstr;

constexpr double kPeriod = 1e-4;  // [s] the independent checks' sample spacing

CollocationOptions AlongOptions(double corridor) {
  CollocationOptions options;
  options.knots = 40;
  options.corridor = corridor;
  options.time_budget = test::Budget(options.time_budget);
  return options;
}

KinematicLimits Limits7() {
  KinematicLimits limits;
  limits.max_velocity = (Eigen::VectorXd(7) << 2.0, 2.0, 2.0, 2.0, 2.5, 2.5, 2.5).finished();
  limits.max_acceleration = (Eigen::VectorXd(7) << 10.0, 8.0, 10.0, 10.0, 12.0, 12.0, 12.0).finished();
  return limits;
}

/// Distance from x to the polyline, written out independently of the code under test.
double DistanceToPolyline(const Eigen::VectorXd& x, const JointPath& path) {
  double best = (x - path.front()).norm();
  for (std::size_t k = 0; k + 1 < path.size(); ++k) {
    const Eigen::VectorXd ab = path[k + 1] - path[k];
    const double len2 = ab.squaredNorm();
    const double s = len2 > 0.0 ? std::clamp((x - path[k]).dot(ab) / len2, 0.0, 1.0) : 0.0;
    best = std::min(best, (x - path[k] - s * ab).norm());
  }
  return best;
}

/// Checks a result along `path` on samples kPeriod apart: inside the corridor everywhere (to
/// rounding), within it of every interior waypoint in order, the reported bound no lower than
/// any sampled distance, finite differences within the limits (1e-6 relative), and the pieces
/// continuous in q, q̇ and q̈ at every knot.
void ExpectAlongPath(const CollocationResult& result, const JointPath& path, const KinematicLimits& limits,
                     double corridor) {
  ASSERT_TRUE(result.report.ok) << result.report.message;
  const TimedTrajectory& trajectory = result.trajectory;
  const std::vector<TrajectorySample> samples = trajectory.Sample(kPeriod);
  double farthest = 0.0;
  for (const TrajectorySample& s : samples) farthest = std::max(farthest, DistanceToPolyline(s.q, path));
  EXPECT_LE(farthest, corridor + 1e-12);
  EXPECT_LE(farthest, result.report.path_deviation + 1e-12) << "the reported bound is below a sampled distance";
  EXPECT_LE(result.report.path_deviation, corridor);
  // Interior waypoints in order: each one's closest sample comes after the previous one's.
  std::size_t after = 0;
  const double reach = corridor + limits.max_velocity.norm() * kPeriod;  // a sample may miss the closest instant
  for (std::size_t w = 1; w + 1 < path.size(); ++w) {
    std::size_t best = after;
    for (std::size_t s = after; s < samples.size(); ++s) {
      if ((samples[s].q - path[w]).norm() < (samples[best].q - path[w]).norm()) best = s;
      if ((samples[best].q - path[w]).norm() <= reach && (samples[s].q - path[w]).norm() > 2 * reach) break;
    }
    EXPECT_LE((samples[best].q - path[w]).norm(), reach) << "waypoint " << w;
    after = best;
  }
  // Finite differences of the returned positions.
  for (std::size_t s = 1; s + 1 < samples.size(); ++s) {
    const double dt0 = samples[s].t - samples[s - 1].t, dt1 = samples[s + 1].t - samples[s].t;
    if (std::abs(dt0 - dt1) > 1e-9) continue;  // the last, shorter step
    const Eigen::VectorXd v = (samples[s + 1].q - samples[s].q) / dt1;
    const Eigen::VectorXd a = (samples[s + 1].q - 2 * samples[s].q + samples[s - 1].q) / (dt0 * dt1);
    for (int i = 0; i < v.size(); ++i) {
      ASSERT_LE(std::abs(v[i]), limits.max_velocity[i] * (1 + 1e-6)) << "t = " << samples[s].t << " joint " << i;
      ASSERT_LE(std::abs(a[i]), limits.max_acceleration[i] * (1 + 1e-6)) << "t = " << samples[s].t << " joint " << i;
    }
  }
  // The pieces meet at every knot.
  const auto& pieces = trajectory.pieces();
  for (std::size_t k = 0; k + 1 < pieces.size(); ++k) {
    for (int i = 0; i < trajectory.num_dofs(); ++i) {
      for (int order = 0; order <= 2; ++order) {
        const double end = pieces[k].Derivative(i, order, pieces[k].duration);
        const double next = pieces[k + 1].Derivative(i, order, 0.0);
        EXPECT_LE(std::abs(end - next), 1e-12 * std::max(1.0, std::abs(next)))
            << "knot " << k + 1 << " joint " << i << " derivative " << order;
      }
    }
  }
  EXPECT_LE((trajectory.Evaluate(trajectory.duration()).q - path.back()).norm(), 0.0);
}

/// A lower bound on any rest-to-rest motion from a that comes within r of b and ends at c: per
/// joint, the distances it must cover before and after, each at least as long as accelerating
/// from (or braking to) rest at the limit allows.
double ExcursionLowerBound(const Eigen::VectorXd& a, const Eigen::VectorXd& b, const Eigen::VectorXd& c, double r,
                           const KinematicLimits& limits) {
  double best = 0.0;
  for (int i = 0; i < a.size(); ++i) {
    const double V = limits.max_velocity[i], A = limits.max_acceleration[i];
    const auto leg = [&](double d) { return d <= 0.0 ? 0.0 : std::max(d / V, std::sqrt(2 * d / A)); };
    best = std::max(best, leg(std::abs(b[i] - a[i]) - r) + leg(std::abs(b[i] - c[i]) - r));
  }
  return best;
}

TEST(CollocationAlongPath, FollowsAnExcursionAndComesBack) {
  // The case: a 0.5 rad excursion ending 0.01 rad from the start came back as 0.073 s
  // straight to the goal.
  const KinematicLimits limits = Limits7();
  Eigen::VectorXd a(7), b(7), c(7);
  a << 0.0, -0.6, 0.0, -2.2, 0.0, 1.6, 0.8;
  b = a + 0.5 * (Eigen::VectorXd(7) << 1.0, 0.4, -0.6, 0.8, 0.2, -0.5, 0.7).finished().normalized();
  c = a + Eigen::VectorXd::Constant(7, 0.01 / std::sqrt(7.0));
  const JointPath path{a, b, c};
  TimeOptimalOptions topp;
  topp.max_deviation = 0.05;
  const TimedTrajectory warm = ParameterizeTimeOptimal(path, limits, topp);
  const CollocationResult result = OptimizeByCollocation(warm, limits, AlongOptions(0.05), nullptr, &path);
  ExpectAlongPath(result, path, limits, 0.05);
  EXPECT_GE(result.trajectory.duration(), ExcursionLowerBound(a, b, c, 0.05, limits));
  EXPECT_LE(result.trajectory.duration(), warm.duration() * (1 + 1e-6)) << "slower than its TOPP warm start";
}

TEST(CollocationAlongPath, AClosedPathMovesThroughItsWaypoints) {
  const KinematicLimits limits = Limits7();
  Eigen::VectorXd a(7), b(7), c(7);
  a << 0.0, -0.6, 0.0, -2.2, 0.0, 1.6, 0.8;
  b = a;
  b[0] += 0.6;
  b[3] += 0.3;
  c = b;
  c[1] += 0.4;
  c[5] -= 0.3;
  const JointPath path{a, b, c, a};
  const TimedTrajectory warm = ParameterizeTimeOptimal(path, limits);
  const CollocationResult result = OptimizeByCollocation(warm, limits, AlongOptions(0.05), nullptr, &path);
  ExpectAlongPath(result, path, limits, 0.05);
  EXPECT_GT(result.trajectory.duration(), 0.5 * warm.duration());
  EXPECT_LE(result.trajectory.duration(), warm.duration() * (1 + 1e-6));
}

TEST(CollocationAlongPath, TheFreeModeSaysWhyItCannotOptimiseAClosedPath) {
  const KinematicLimits limits = Limits7();
  Eigen::VectorXd a = Eigen::VectorXd::Zero(7), b = Eigen::VectorXd::Constant(7, 0.3);
  const TimedTrajectory warm = ParameterizeTimeOptimal({a, b, a}, limits);
  const CollocationResult result = OptimizeByCollocation(warm, limits, AlongOptions(0.05));
  EXPECT_FALSE(result.report.ok);
  EXPECT_TRUE(result.trajectory.empty());
  EXPECT_THAT(result.report.message, HasSubstr("returns to its start at rest"));
}

TEST(CollocationAlongPath, RandomPathsStayInTheCorridorWithConsistentSamples) {
  test::Random rng(test::TestSeed());
  const int cases = test::TestCases(3);
  const KinematicLimits limits = Limits7();
  for (int c = 0; c < cases; ++c) {
    SCOPED_TRACE("case " + std::to_string(c));
    JointPath path{rng.Vector(7, -1.5, 1.5)};
    const int waypoints = 3 + rng.Index(4);
    while (static_cast<int>(path.size()) < waypoints) path.push_back(path.back() + rng.Vector(7, -0.6, 0.6));
    const double corridor = rng.Uniform(0.02, 0.1);
    TimeOptimalOptions topp;
    topp.max_deviation = corridor;
    const TimedTrajectory warm = ParameterizeTimeOptimal(path, limits, topp);
    const CollocationResult result = OptimizeByCollocation(warm, limits, AlongOptions(corridor), nullptr, &path);
    ExpectAlongPath(result, path, limits, corridor);
    EXPECT_LE(result.trajectory.duration(), warm.duration() * (1 + 1e-6));
  }
}

TEST(CollocationAlongPath, JerkLimitedItPassesTheCornersInsteadOfStopping) {
  KinematicLimits limits = Limits7();
  limits.max_jerk = Eigen::VectorXd::Constant(7, 60.0);
  Eigen::VectorXd a(7), b(7), c(7);
  a << 0.0, -0.6, 0.0, -2.2, 0.0, 1.6, 0.8;
  b = a + Eigen::VectorXd::Constant(7, 0.3);
  c = b;
  c.head(3) -= Eigen::Vector3d(0.5, 0.2, 0.4);
  const JointPath path{a, b, c};
  const TimedTrajectory stops = ParameterizeRestToRest(path, limits);
  const CollocationResult result = OptimizeByCollocation(stops, limits, AlongOptions(0.05), nullptr, &path);
  ExpectAlongPath(result, path, limits, 0.05);
  const TrajectoryQuality quality = MeasureTrajectory(result.trajectory, limits, {}, nullptr);
  EXPECT_LE(quality.max_jerk_ratio, 1.0 + 1e-9);
  EXPECT_LT(result.trajectory.duration(), stops.duration());
}

TEST(CollocationAlongPath, NamedErrors) {
  const KinematicLimits limits = Limits7();
  const Eigen::VectorXd a = Eigen::VectorXd::Zero(7), b = Eigen::VectorXd::Constant(7, 0.3);
  const TimedTrajectory warm = ParameterizeTimeOptimal({a, b}, limits);
  const JointPath elsewhere{b, a};
  EXPECT_THROW(
      {
        try {
          OptimizeByCollocation(warm, limits, AlongOptions(0.05), nullptr, &elsewhere);
        } catch (const Error& e) {
          EXPECT_THAT(e.what(), HasSubstr("not the warm start's start and end"));
          throw;
        }
      },
      Error);
  const JointPath path{a, b};
  for (double corridor : {0.0, -1.0, 2.0, std::nan("")}) {
    EXPECT_THROW(
        {
          try {
            OptimizeByCollocation(warm, limits, AlongOptions(corridor), nullptr, &path);
          } catch (const Error& e) {
            EXPECT_THAT(e.what(), HasSubstr("collocation corridor = "));
            throw;
          }
        },
        Error);
  }
}

}  // namespace
}  // namespace chasles
