#pragma once
/// \file
/// The independent re-check of returned trajectories shared by the pipeline tests: every state
/// at most a given joint step apart, checked on a second checker (the generic FCL path), and
/// query configurations near obstacles.

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "../collision/test_util.h"
#include "chasles/collision/collision_checker.h"
#include "chasles/optimizers/timed_trajectory.h"

namespace chasles::test {

/// A valid configuration within `near` metres of an obstacle (and not closer than 2 mm); `fallback`
/// (with a test failure) when none is found.
inline Eigen::VectorXd ConfigurationNearObstacles(const CollisionChecker& checker, std::mt19937_64& rng, double near,
                                                  const Eigen::VectorXd& fallback) {
  for (int tries = 0; tries < 20000; ++tries) {
    const Eigen::VectorXd q = test::RandomConfig(checker.robot(), rng);
    if (!checker.IsValid(q)) continue;
    const double c = checker.Clearance(q);
    if (c > 0.002 && c < near) return q;
  }
  ADD_FAILURE() << "no configuration near the obstacles found";
  return fallback;
}

struct DenseCheck {
  int states = 0;
  int colliding = 0;
  std::string first_contact;
  double min_clearance = std::numeric_limits<double>::infinity();
};

/// Every state at most `step` of joint motion apart (each piece's own polynomial, clamped into
/// the joint limits as the returned samples are, and the exact end), checked on `fcl`; the
/// clearance at every 10th of them.
inline DenseCheck CheckDensely(const TimedTrajectory& trajectory, const CollisionChecker& fcl, double step) {
  DenseCheck out;
  const RobotModel& robot = fcl.robot();
  const auto check = [&](const Eigen::VectorXd& raw, double t) {
    const Eigen::VectorXd q = raw.cwiseMax(robot.lower_limits()).cwiseMin(robot.upper_limits());
    ++out.states;
    const CollisionResult contact = fcl.Check(q);
    if (contact.in_collision) {
      if (out.colliding++ == 0) {
        out.first_contact = "t = " + std::to_string(t) + " s: '" + contact.link_a + "' / '" + contact.other + "'";
      }
    }
    // The clearance (FCL distances, slower) at every 10th state: min_clearance must be at or
    // below the clearance of any state of the trajectory.
    if (out.states % 10 == 1) out.min_clearance = std::min(out.min_clearance, fcl.Clearance(q));
  };
  for (const TimedTrajectory::Piece& piece : trajectory.pieces()) {
    const int m = std::max(1, static_cast<int>(std::ceil(piece.MaxJointTravel() / step)));
    for (int i = 0; i < m; ++i) {
      const double tau = piece.duration * i / m;
      check(piece.State(tau).q, piece.t0 + tau);
    }
  }
  check(trajectory.Evaluate(trajectory.duration()).q, trajectory.duration());
  return out;
}

}  // namespace chasles::test
