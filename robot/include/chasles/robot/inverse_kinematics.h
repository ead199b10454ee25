#pragma once
/// \file
/// Numerical inverse kinematics of one link's pose (Lynch & Park, §6.2): Newton–Raphson on the
/// body twist error, or damped least squares, with joint limits, random restarts within a
/// budget, and several distinct solutions on request. Every returned solution is checked by
/// forward kinematics against the tolerances: a pose that cannot be reached is a failure with
/// a reason, never a wrong answer.

#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "chasles/robot/robot_model.h"

namespace chasles {

/// kNewtonRaphson: Δq = J_b⁺ V_b (pseudo-inverse), switching to damped steps for the rest of an
/// attempt once a full step made the error grow. kDampedLeastSquares: Δq = J_bᵀ(J_b J_bᵀ + λ²I)⁻¹ V_b
/// with λ² = damping² · min(1, 10 ‖V_b‖), so large errors are damped and the last steps are
/// Newton steps. Both limit each step to 0.6 rad (or m) per joint, clamp to the joint limits
/// (continuous joints wrap into [-π, π]) and abandon an attempt that stops improving.
/// Dofs that do not move `link` keep `initial_guess` (or 0 moved into their limits).
enum class IkMethod { kNewtonRaphson, kDampedLeastSquares };

struct IkRequest {
  int link = -1;                         ///< the link whose frame must reach `target`
  Eigen::Isometry3d target = Eigen::Isometry3d::Identity();  ///< in the base frame
  double position_tolerance = 1e-4;      ///< ‖p − p_target‖ bound [m], > 0
  double orientation_tolerance = 1e-3;   ///< rotation angle between frames [rad], > 0
  IkMethod method = IkMethod::kDampedLeastSquares;
  double damping = 0.05;                 ///< λ of damped least squares, >= 0
  int max_iterations = 100;              ///< per attempt, >= 1
  int max_solutions = 1;                 ///< distinct solutions wanted, >= 1
  double distinct_distance = 1e-2;       ///< min max-norm joint distance between solutions [rad]
  double time_budget = 0.05;             ///< [s], > 0: restarts stop when it is spent
  std::uint64_t seed = 1;                ///< restarts draw from this seed: same seed, same answers
  Eigen::VectorXd initial_guess;         ///< optional first attempt (empty = random)
  /// 0 = attempts until the budget is spent; else at most this many (1 with an initial guess: a
  /// local solve from it only, as a path that must stay on one branch needs).
  int max_attempts = 0;
  /// Optional extra acceptance test (e.g. collision-free); a rejected solution counts as a
  /// failed attempt and the search goes on.
  std::function<bool(const Eigen::VectorXd&)> accept;
  /// Optional: polled between attempts and every 16 iterations; true ends the search at once
  /// (client cancellation, a deadline) with what has been found so far.
  std::function<bool()> stop;
  /// \throws Error(kInvalidArgument) naming the field, e.g. `ik.position_tolerance = 0 must be > 0`.
  void Validate(const RobotModel& robot) const;
};

enum class IkStatus { kSuccess, kPartial, kNoSolution };

struct IkResult {
  IkStatus status = IkStatus::kNoSolution;  ///< kPartial: fewer than max_solutions found
  std::vector<Eigen::VectorXd> solutions;   ///< each within the tolerances and joint limits
  std::string message;                      ///< why none (or fewer) were found
  int attempts = 0;
  double best_position_error = 0.0;         ///< of the best attempt [m]
  double best_orientation_error = 0.0;      ///< of the best attempt [rad]
  double seconds = 0.0;
};

/// Solves `request` for `robot`. \throws Error(kInvalidArgument) when the request is invalid.
IkResult SolveIk(const RobotModel& robot, const IkRequest& request);

}  // namespace chasles
