#pragma once
// Private to chasles_optimizers: the nonlinear program of SmoothWithBSpline (objective,
// constraints and their exact gradients) over the free control points and the knot-span
// durations of a clamped B-spline in time. Solver-agnostic: spline_smoothing.cc hands it to
// NLopt.

#include <limits>
#include <vector>

#include <Eigen/Core>

#include "chasles/collision/collision_checker.h"
#include "chasles/collision/proximity.h"
#include "chasles/optimizers/time_parameterization.h"
#include "chasles/optimizers/timed_trajectory.h"
#include "spline_curve.h"

namespace chasles {
namespace spline {

/// The limit rows ask for |C⁽ʳ⁾ᵢ| <= (1 − kLimitMargin)·limit, so a solver's final point,
/// which meets its constraints to ~1e-6, meets the limits themselves (no time scaling).
constexpr double kLimitMargin = 1e-5;

/// Which control points are variables. P₀ = start and P_{K−1} = goal always. An end at rest
/// also fixes the next one (P₁ = start, P_{K−2} = goal: zero velocity) and, when
/// zero_rest_acceleration (K >= 6), the one after (P₂ = start, P_{K−3} = goal: zero
/// acceleration); a moving end fixes its velocity v through the next one,
/// P₁ = start + v₀·Δ₀/p and P_{K−2} = goal − v₁·Δ_{m−1}/p (a function of the span duration).
/// Variables x: the free control points joint by joint (P_{first_free} … P_{last_free} of
/// joint 0, then joint 1, …), then the m span durations.
struct Layout {
  int num_dofs = 0;
  int degree = 3;
  int num_control_points = 0;
  Eigen::VectorXd start, goal;
  Eigen::VectorXd start_velocity, end_velocity;  ///< zero at an end at rest
  bool start_at_rest = true;
  bool end_at_rest = true;
  bool zero_rest_acceleration = true;

  int num_spans() const { return num_control_points - degree; }
  int first_free() const { return start_at_rest && zero_rest_acceleration ? 3 : 2; }
  int last_free() const { return num_control_points - 1 - (end_at_rest && zero_rest_acceleration ? 3 : 2); }
  int free_per_joint() const { return last_free() - first_free() + 1; }
  int num_variables() const { return num_dofs * free_per_joint() + num_spans(); }
  /// Variable index of control point i of `joint`, or −1 when it is fixed or derived.
  int ControlVariable(int joint, int i) const {
    return i < first_free() || i > last_free() ? -1 : joint * free_per_joint() + (i - first_free());
  }
  int SpanVariable(int j) const { return num_dofs * free_per_joint() + j; }
  /// True when control point i is a constant (not a variable, not derived from a duration).
  bool Fixed(int i) const;

  /// All control points (num_dofs × K) and the span durations of x.
  void Unpack(const double* x, Eigen::MatrixXd* control, Eigen::VectorXd* delta) const;
  /// x of the given free control points and durations (the others are ignored).
  std::vector<double> Pack(const Eigen::MatrixXd& control, const Eigen::VectorXd& delta) const;
};

/// A state sampled for the clearance constraint: span j at local time fraction·Δⱼ. The
/// constraint asks for `target` [m] from every obstacle; `required` <= target is what the
/// result must keep (the difference is a margin for the dips between samples).
struct ClearanceSample {
  int span = 0;
  double fraction = 0.5;
  double target = 0.0;
  double required = 0.0;
};

/// Clearance constraints (none when `proximity` is null).
struct ClearanceSetup {
  const ObstacleProximity* proximity = nullptr;
  /// ObstacleProximity distance minus CollisionChecker::Clearance at the same state (the
  /// checker's padding) [m].
  double offset = 0.0;
  double query_range = 0.5;  ///< obstacles farther than this from a link are ignored [m]
  std::vector<ClearanceSample> samples;
};

/// min f(x) = ΣΔⱼ + w·Σ_joints ∫‖q⃛‖² dt subject to c(x) <= 0:
///   ((C⁽ʳ⁾ᵢ/bound)² − 1)/2, bound = (1 − 1e-5)·limit (a margin for the solver's own
///     tolerance), for r = 1 (velocity), 2 (acceleration) and, with max_jerk, 3
///     (jerk), every joint and index except the constant ones (zero at an end at rest, a
///     moving end's own velocity); one row per point rather than ±, which keeps SLSQP's
///     dense subproblems small; dimensionless, so a span that shrinks does not loosen its rows;
///   (target − (distance − offset))/0.05 m at every clearance sample, distance the smallest
///     link–obstacle distance there (gradient n̂ᵀ·J_v(q, link, point)·∂q/∂x).
class Problem {
 public:
  Problem(Layout layout, const KinematicLimits& limits, double jerk_weight, ClearanceSetup clearance);

  const Layout& layout() const { return layout_; }
  int num_variables() const { return layout_.num_variables(); }
  int num_constraints() const { return static_cast<int>(rows_.size() + clearance_.samples.size()); }
  const ClearanceSetup& clearance() const { return clearance_; }

  /// Returns f(x) and fills constraints[0 … M−1]; with gradients, also objective_gradient[N]
  /// and jacobian[M·N] (row-major, ∂cᵢ/∂xⱼ at i·N + j). Both gradient pointers null: values only.
  double Evaluate(const double* x, double* constraints, double* objective_gradient, double* jacobian);

  /// What the last Evaluate found besides f and c.
  struct Figures {
    double duration = 0.0;       ///< ΣΔⱼ [s]
    double jerk_integral = 0.0;  ///< Σ_joints ∫‖q⃛‖² dt [rad²/s⁵]
    /// maxᵣ,ᵢ (|C⁽ʳ⁾ᵢ|/limit)^(1/r): the spline slowed by this factor (if > 1) meets every
    /// limit everywhere.
    double hull_scale = 0.0;
    /// Largest shortfall below a sample's `required` clearance [m] (−inf without samples; only
    /// when constraints were evaluated).
    double clearance_shortfall = -std::numeric_limits<double>::infinity();
  };
  const Figures& figures() const { return figures_; }
  /// The objective of the last evaluated spline once slowed by `scale`: ΣΔ·s + w·J/s⁵.
  double ScaledObjective(double scale) const;

  /// The spline at x as one polynomial piece per span, ending exactly at the goal.
  TimedTrajectory Trajectory(const double* x) const;

 private:
  struct Row {
    int joint, order, index;
    double inverse_limit;
  };
  void ComputeSplines(const double* x);
  /// out[x-index] += scale·row for every slot that is a variable.
  void Scatter(int joint, const double* row, double scale, double* out) const;
  double ClearanceRow(const ClearanceSample& sample, bool gradients, double* jacobian_row);

  Layout layout_;
  KinematicLimits limits_;
  double jerk_weight_;
  ClearanceSetup clearance_;
  std::vector<Row> rows_;
  Figures figures_;
  int slots_;
  std::vector<int> slot_variable_;  // per joint: slots_ entries
  std::vector<RowMajorMatrix> seeds_;
  std::vector<JointSpline> joints_;
  Eigen::MatrixXd control_;
  Eigen::VectorXd delta_;
  // Scratch of the clearance rows.
  std::vector<LinkProximity> near_;
  std::vector<Eigen::Isometry3d> poses_;
  Eigen::VectorXd q_;
  RowMajorMatrix q_grad_;
};

}  // namespace spline
}  // namespace chasles
