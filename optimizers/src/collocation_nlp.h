#pragma once
// The Ipopt transcription behind OptimizeByCollocation (private to chasles_optimizers; the
// public header never sees Ipopt).
//
// Variables, knot by knot (k = 0 … N, N = K − 1 intervals): qₖ, q̇ₖ, q̈ₖ (n each) and, for
// k < N, the duration hₖ of interval k. The jerk of interval k is uₖ = (q̈ₖ₊₁ − q̈ₖ)/hₖ: it is
// not a variable of its own (a variable would range over A/h_min … A/h₀, orders of magnitude
// apart as intervals shrink, while q̈ stays within its limits), but the motion is the same
// triple integrator with piecewise-constant jerk. Its exact steps are the defects
//   qₖ₊₁ − qₖ − q̇ₖ hₖ − (2q̈ₖ + q̈ₖ₊₁) hₖ²/6 = 0,   q̇ₖ₊₁ − q̇ₖ − (q̈ₖ + q̈ₖ₊₁) hₖ/2 = 0,
// i.e. qₖ + q̇ₖh + q̈ₖh²/2 + uₖh³/6 and q̇ₖ + q̈ₖh + uₖh²/2 with uₖ eliminated.
// Objective Σ hₖ + w Σₖ ‖q̈ₖ₊₁ − q̈ₖ‖²/hₖ (= T + w∫‖q⃛‖² dt exactly) + a small regularisation
// (Transcription::regularization).
// Bounds: q within the joint limits, |q̇| and |q̈| within theirs at the knots (q̈ is linear in
// each interval, so that is exact), hₖ >= min_interval, start/end q and q̇ fixed.
// Rows, in this order:
//   defects                    2n per interval
//   velocity control points    n per interval: |q̇ₖ + q̈ₖhₖ/2| <= v_max, the middle Bernstein
//                              coefficient of the quadratic velocity; with the knot bounds this
//                              bounds the velocity over the whole interval (convex hull)
//   jerk limits                2n per interval: q̈ₖ₊₁ − q̈ₖ ± Jhₖ (linear), with max_jerk
//   torques                    n per knot (and interval midpoint if asked), with max_effort
//   clearances                 one per (instant, link) pair
//   corridor                   per corridor row: ‖P(q − w)‖² <= δ² (P = I − d̂d̂ᵀ for a segment
//                              from w along the unit d̂, I for a waypoint) and, for a segment,
//                              0 <= d̂ᵀ(q − w) <= its length
//   half-interval motion       2 per interval with clearance pairs: ‖q(hₖ/2) − qₖ‖² and
//                              ‖qₖ₊₁ − q(hₖ/2)‖² <= max_step²
// Hessian: exact for the objective, defects, velocity control points and motion rows (all
// polynomial) and for corridor rows at knots (2λP on qₖ); torque and clearance rows, and
// corridor rows between knots, contribute no curvature. Measured against Ipopt's
// limited-memory mode: a Panda segment at K = 30 took 181 instead of 26 iterations, and with
// torque limits or around the planar post it did not finish within 5 s.

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <IpTNLP.hpp>

#include "chasles/collision/proximity.h"
#include "chasles/robot/dynamics.h"
#include "chasles/robot/robot_model.h"

namespace chasles::collocation {

/// A time on the trajectory: interval k at the fraction σ ∈ [0, 1) of its duration (σ = 0 is
/// knot k).
struct Instant {
  int interval = 0;
  double fraction = 0.0;
  bool operator<(const Instant& o) const { return interval != o.interval ? interval < o.interval : fraction < o.fraction; }
  bool operator==(const Instant& o) const { return interval == o.interval && fraction == o.fraction; }
};

/// A clearance constraint: distance(link, nearest obstacle) >= minimum at an instant.
struct ClearancePair {
  Instant at;
  int link = 0;          ///< index into RobotModel::links()
  double minimum = 0.0;  ///< required distance [m]
};

/// A corridor constraint at an instant: the position within `radius` of the line from `origin`
/// along the unit `direction`, its projection within [inset, length − inset] (or within
/// `radius` of the point `origin` when `direction` is empty).
struct CorridorRow {
  Instant at;
  Eigen::VectorXd origin;
  Eigen::VectorXd direction;  ///< unit; empty = a waypoint
  double length = 0.0;
  double radius = 0.0;        ///< [rad] > 0
  double inset = 0.0;         ///< [rad] >= 0
};

/// Everything the transcription needs; sizes are checked by the caller.
struct Transcription {
  int num_dofs = 0;
  int knots = 0;
  double jerk_weight = 0.0;
  /// ρ [s]: tie-breaking terms ρ/h₀ Σ (hₖ₊₁ − hₖ)² + ρ/n Σₖ hₖ Σᵢ (q̈ₖᵢ/Aᵢ)² added to the
  /// objective. Minimum time alone leaves a flat optimal face (where the knots sit along a
  /// cruise, how a joint that does not limit the time gets there); Ipopt then drifts on it
  /// without converging. Both terms are <= ρ·(T/h₀ + T) for any trajectory.
  double regularization = 0.0;
  Eigen::VectorXd position_lower, position_upper;  ///< ±inf when unknown
  /// K × n, >= 0 (or empty): knot k's position bounds for joint i are pulled in by (k, i), so
  /// that the cubic between knots stays inside where it bulged out of a solve.
  Eigen::MatrixXd position_margin;
  Eigen::VectorXd max_velocity, max_acceleration;
  Eigen::VectorXd max_jerk;    ///< empty = none
  Eigen::VectorXd max_effort;  ///< empty = none (then `robot` may be null)
  /// Torque rows at the interval midpoints too, not only at the knots. Off: on the Panda with
  /// half its unconstrained peak torques (K = 30) the midpoint rows cost 56 instead of 44
  /// iterations for a 0.07 % shorter result, and at 30 % of the peaks they did not converge
  /// within 5 s where knots alone (and the final slow-down, 11 %) did.
  bool torque_at_midpoints = false;
  Eigen::VectorXd start_q, start_v, end_q, end_v;
  bool start_at_rest_acceleration = false;  ///< q̈₀ = 0 (jerk-limited start at rest)
  bool end_at_rest_acceleration = false;
  double min_interval = 0.0;      ///< lower bound on every hₖ [s], > 0
  /// Every interval's motion between its knots and its midpoint is bounded:
  /// ‖q(hₖ/2) − qₖ‖² <= max_step² and ‖qₖ₊₁ − q(hₖ/2)‖² <= max_step² (2 rows per interval).
  bool bounded_motion = false;
  double max_step = 0.0;  ///< [rad], Euclidean in joint space
  double nominal_interval = 0.0;  ///< warm-start hₖ [s] (scaling)
  const RobotModel* robot = nullptr;
  DynamicsOptions dynamics;
  const ObstacleProximity* proximity = nullptr;
  std::vector<ClearancePair> pairs;  ///< sorted by instant
  std::vector<CorridorRow> corridor;  ///< path-following rows, sorted by instant (empty = free)
  std::function<bool()> stop;
};

/// Index arithmetic of the variable vector.
struct Layout {
  int n = 0, intervals = 0;
  int stride() const { return 3 * n + 1; }
  int q(int k, int i) const { return k * stride() + i; }
  int v(int k, int i) const { return k * stride() + n + i; }
  int a(int k, int i) const { return k * stride() + 2 * n + i; }
  int h(int k) const { return k * stride() + 3 * n; }
  int size() const { return intervals * stride() + 3 * n; }
};

/// State (q, q̇, q̈) at point p (knot or interval midpoint) of the variable vector x.
void PointState(const Layout& layout, const double* x, int point, Eigen::VectorXd* q, Eigen::VectorXd* v,
                Eigen::VectorXd* a);
/// Position at an instant of the variable vector x.
Eigen::VectorXd PositionAt(const Layout& layout, const double* x, Instant at);

/// The multipliers of a solve, to start the next one of the same structure from.
struct Multipliers {
  Eigen::VectorXd lower, upper, rows;  ///< bound multipliers z_L, z_U and row multipliers λ
};

class CollocationNlp : public Ipopt::TNLP {
 public:
  /// `initial` is the starting point (Layout::size() values); `multipliers` (optional, sizes
  /// matching) start the duals when Ipopt's warm_start_init_point asks for them.
  CollocationNlp(const Transcription& transcription, Eigen::VectorXd initial, Multipliers multipliers = {});

  const Eigen::VectorXd& solution() const { return solution_; }
  const Multipliers& multipliers() const { return multipliers_; }
  /// Largest violation of any constraint or bound at the solution, unscaled.
  double violation() const { return violation_; }
  bool stopped() const { return stopped_; }

  bool get_nlp_info(Ipopt::Index& n, Ipopt::Index& m, Ipopt::Index& nnz_jac_g, Ipopt::Index& nnz_h_lag,
                    IndexStyleEnum& index_style) override;
  bool get_bounds_info(Ipopt::Index n, Ipopt::Number* x_l, Ipopt::Number* x_u, Ipopt::Index m, Ipopt::Number* g_l,
                       Ipopt::Number* g_u) override;
  bool get_scaling_parameters(Ipopt::Number& obj_scaling, bool& use_x_scaling, Ipopt::Index n,
                              Ipopt::Number* x_scaling, bool& use_g_scaling, Ipopt::Index m,
                              Ipopt::Number* g_scaling) override;
  bool get_starting_point(Ipopt::Index n, bool init_x, Ipopt::Number* x, bool init_z, Ipopt::Number* z_L,
                          Ipopt::Number* z_U, Ipopt::Index m, bool init_lambda, Ipopt::Number* lambda) override;
  bool eval_f(Ipopt::Index n, const Ipopt::Number* x, bool new_x, Ipopt::Number& obj_value) override;
  bool eval_grad_f(Ipopt::Index n, const Ipopt::Number* x, bool new_x, Ipopt::Number* grad_f) override;
  bool eval_g(Ipopt::Index n, const Ipopt::Number* x, bool new_x, Ipopt::Index m, Ipopt::Number* g) override;
  bool eval_jac_g(Ipopt::Index n, const Ipopt::Number* x, bool new_x, Ipopt::Index m, Ipopt::Index nele_jac,
                  Ipopt::Index* iRow, Ipopt::Index* jCol, Ipopt::Number* values) override;
  bool eval_h(Ipopt::Index n, const Ipopt::Number* x, bool new_x, Ipopt::Number obj_factor, Ipopt::Index m,
              const Ipopt::Number* lambda, bool new_lambda, Ipopt::Index nele_hess, Ipopt::Index* iRow,
              Ipopt::Index* jCol, Ipopt::Number* values) override;
  void finalize_solution(Ipopt::SolverReturn status, Ipopt::Index n, const Ipopt::Number* x,
                         const Ipopt::Number* z_L, const Ipopt::Number* z_U, Ipopt::Index m,
                         const Ipopt::Number* g, const Ipopt::Number* lambda, Ipopt::Number obj_value,
                         const Ipopt::IpoptData* ip_data, Ipopt::IpoptCalculatedQuantities* ip_cq) override;
  bool intermediate_callback(Ipopt::AlgorithmMode mode, Ipopt::Index iter, Ipopt::Number obj_value,
                             Ipopt::Number inf_pr, Ipopt::Number inf_du, Ipopt::Number mu, Ipopt::Number d_norm,
                             Ipopt::Number regularization_size, Ipopt::Number alpha_du, Ipopt::Number alpha_pr,
                             Ipopt::Index ls_trials, const Ipopt::IpoptData* ip_data,
                             Ipopt::IpoptCalculatedQuantities* ip_cq) override;

 private:
  void BuildStructure();
  void UpdateTorques(const double* x, bool derivatives);
  /// Joint i's motion over the first (half 0) or second (half 1) half of interval k.
  double HalfMotion(const double* x, int k, int i, int half) const;
  void UpdateClearances(const double* x);
  /// Jacobian structure of a row that depends on the position at `at` only.
  void AddInstantColumns(int row, Instant at);
  /// Writes that row's values: ∂q(at)/∂x chained with `grad` = ∂row/∂q (the columns of
  /// AddInstantColumns, in that order).
  void WriteInstantGradient(const double* x, Instant at, const Eigen::VectorXd& grad, double** out) const;
  void Bounds(std::vector<double>* x_l, std::vector<double>* x_u, std::vector<double>* g_l,
              std::vector<double>* g_u) const;

  const Transcription& t_;
  Layout layout_;
  Eigen::VectorXd initial_, solution_;
  Multipliers start_multipliers_, multipliers_;
  double violation_ = 0.0;
  bool stopped_ = false;
  int rows_defects_ = 0, rows_velocity_ = 0, rows_jerk_ = 0, rows_torque_ = 0, rows_clearance_ = 0,
      rows_corridor_ = 0, rows_motion_ = 0;
  int corridor_start_ = 0;  ///< first corridor row
  std::vector<int> corridor_knots_;  ///< distinct knots with corridor rows (their q-blocks in the Hessian)
  std::vector<int> jac_rows_, jac_cols_, hess_rows_, hess_cols_;
  // Caches for the current x (Ipopt's new_x).
  bool torques_valid_ = false, torque_derivatives_valid_ = false, clearances_valid_ = false;
  std::vector<int> torque_points_;            ///< points (2k knot, 2k + 1 midpoint) with torque rows
  Eigen::MatrixXd torque_;                    ///< n × torque_points_.size()
  std::vector<Eigen::MatrixXd> torque_jac_;   ///< per torque point n × 3n (∂τ/∂q, ∂τ/∂q̇, ∂τ/∂q̈)
  std::vector<JointFriction> friction_;       ///< per dof, its mimic joints' included (DofFriction)
  std::vector<Instant> instants_;             ///< distinct instants of pairs, sorted
  std::vector<double> distance_;              ///< per pair
  std::vector<Eigen::VectorXd> distance_grad_;  ///< per pair, ∂d/∂q at its instant
  struct OutsideModel {  ///< per pair: the last evaluation out of contact
    bool valid = false;
    Eigen::VectorXd q, gradient;
    double distance = 0.0;
  };
  std::vector<OutsideModel> outside_;
  int motion_start_ = 0;  ///< first motion row
  std::vector<int> link_slot_;                ///< link index → position in proximity->links(), -1
};

}  // namespace chasles::collocation
