#include "spline_problem.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "chasles/robot/kinematics.h"

namespace chasles {
namespace spline {
namespace {

constexpr double kClearanceScale = 0.05;  // [m] per unit of a clearance constraint

}  // namespace

bool Layout::Fixed(int i) const {
  if (i == 0 || i == num_control_points - 1) return true;
  if (i < first_free()) return start_at_rest;  // P₁ (and P₂) at rest; P₁ derived when moving
  if (i > last_free()) return end_at_rest;
  return false;
}

void Layout::Unpack(const double* x, Eigen::MatrixXd* control, Eigen::VectorXd* delta) const {
  const int k = num_control_points, m = num_spans();
  delta->resize(m);
  for (int j = 0; j < m; ++j) (*delta)[j] = x[SpanVariable(j)];
  control->resize(num_dofs, k);
  for (int d = 0; d < num_dofs; ++d) {
    for (int i = 0; i < k; ++i) {
      const int v = ControlVariable(d, i);
      if (v >= 0) {
        (*control)(d, i) = x[v];
      } else if (i < first_free()) {
        (*control)(d, i) = (i == 0 || start_at_rest) ? start[d] : start[d] + start_velocity[d] * (*delta)[0] / degree;
      } else {
        (*control)(d, i) = (i == k - 1 || end_at_rest) ? goal[d] : goal[d] - end_velocity[d] * (*delta)[m - 1] / degree;
      }
    }
  }
}

std::vector<double> Layout::Pack(const Eigen::MatrixXd& control, const Eigen::VectorXd& delta) const {
  std::vector<double> x(num_variables());
  for (int d = 0; d < num_dofs; ++d) {
    for (int i = first_free(); i <= last_free(); ++i) x[ControlVariable(d, i)] = control(d, i);
  }
  for (int j = 0; j < num_spans(); ++j) x[SpanVariable(j)] = delta[j];
  return x;
}

Problem::Problem(Layout layout, const KinematicLimits& limits, double jerk_weight, ClearanceSetup clearance)
    : layout_(std::move(layout)), limits_(limits), jerk_weight_(jerk_weight), clearance_(std::move(clearance)) {
  const int n = layout_.num_dofs, k = layout_.num_control_points, m = layout_.num_spans(), p = layout_.degree;
  slots_ = k + m;  // per joint: its K control points, then the m span durations
  slot_variable_.assign(static_cast<std::size_t>(n) * slots_, -1);
  seeds_.assign(n, RowMajorMatrix::Zero(k, slots_));
  for (int d = 0; d < n; ++d) {
    for (int i = 0; i < k; ++i) slot_variable_[d * slots_ + i] = layout_.ControlVariable(d, i);
    for (int j = 0; j < m; ++j) slot_variable_[d * slots_ + k + j] = layout_.SpanVariable(j);
    for (int i = layout_.first_free(); i <= layout_.last_free(); ++i) seeds_[d](i, i) = 1.0;
    if (!layout_.start_at_rest) seeds_[d](1, k) = layout_.start_velocity[d] / p;
    if (!layout_.end_at_rest) seeds_[d](k - 2, k + m - 1) = -layout_.end_velocity[d] / p;
  }
  joints_.assign(n, JointSpline(p, k, slots_));

  // Limit rows, skipping hodograph points that are constant: identically zero (all their
  // control points fixed and equal, e.g. the velocity and acceleration at an end at rest) or
  // a moving end's own velocity (its row could not change, and a velocity at the limit would
  // violate the margin for good).
  const int max_order = limits_.max_jerk.size() != 0 ? 3 : 2;
  for (int d = 0; d < n; ++d) {
    for (int r = 1; r <= max_order; ++r) {
      const Eigen::VectorXd& limit =
          r == 1 ? limits_.max_velocity : (r == 2 ? limits_.max_acceleration : limits_.max_jerk);
      for (int i = 0; i + r < k; ++i) {
        auto fixed_value = [&](int l) { return l < layout_.first_free() ? layout_.start[d] : layout_.goal[d]; };
        bool zero = true;
        for (int l = i; l <= i + r; ++l) zero = zero && layout_.Fixed(l) && fixed_value(l) == fixed_value(i);
        if (zero) continue;
        if (r == 1 && ((i == 0 && !layout_.start_at_rest) || (i == k - 2 && !layout_.end_at_rest))) continue;
        rows_.push_back(Row{d, r, i, 1.0 / limit[d]});
      }
    }
  }
  control_.resize(n, k);
  delta_.resize(m);
  q_.resize(n);
  q_grad_.setZero(n, slots_);
}

void Problem::ComputeSplines(const double* x) {
  layout_.Unpack(x, &control_, &delta_);
  const int k = layout_.num_control_points;
  Eigen::VectorXd row(k);
  for (int d = 0; d < layout_.num_dofs; ++d) {
    row = control_.row(d).transpose();
    joints_[d].Compute(row.data(), seeds_[d], delta_, k);
  }
}

void Problem::Scatter(int joint, const double* row, double scale, double* out) const {
  const int* variables = &slot_variable_[static_cast<std::size_t>(joint) * slots_];
  for (int s = 0; s < slots_; ++s) {
    if (variables[s] >= 0 && row[s] != 0.0) out[variables[s]] += scale * row[s];
  }
}

double Problem::Evaluate(const double* x, double* constraints, double* objective_gradient, double* jacobian) {
  ComputeSplines(x);  // with gradients always: they cost little next to the solver
  const int n = layout_.num_dofs, m = layout_.num_spans(), p = layout_.degree;
  const int num_variables = layout_.num_variables();
  if (objective_gradient != nullptr) std::fill(objective_gradient, objective_gradient + num_variables, 0.0);

  // Objective: ΣΔⱼ + w·Σ ∫₀^Δⱼ (q⃛)² dτ, q⃛(τ) = Σₑ bₑ τᵉ with bₑ = (e+3)(e+2)(e+1)·a_{e+3}.
  figures_ = Figures();
  for (int j = 0; j < m; ++j) {
    figures_.duration += delta_[j];
    if (objective_gradient != nullptr) objective_gradient[layout_.SpanVariable(j)] += 1.0;
  }
  if (jerk_weight_ > 0.0) {
    const int terms = p - 2;
    Eigen::RowVectorXd b_grad(slots_);
    for (int d = 0; d < n; ++d) {
      const JointSpline& spline = joints_[d];
      for (int j = 0; j < m; ++j) {
        const double h = delta_[j];
        double b[3], hp[6];  // hp[e] = hᵉ
        hp[0] = 1.0;
        for (int e = 1; e < 6; ++e) hp[e] = hp[e - 1] * h;
        for (int e = 0; e < terms; ++e) b[e] = (e + 3) * (e + 2) * (e + 1) * spline.coefficient(j, e + 3);
        double integral = 0.0, d_integral_dh = 0.0;
        for (int e = 0; e < terms; ++e) {
          for (int f = 0; f < terms; ++f) {
            integral += b[e] * b[f] * hp[e + f + 1] / (e + f + 1);
            d_integral_dh += b[e] * b[f] * hp[e + f];
          }
        }
        figures_.jerk_integral += integral;
        if (objective_gradient == nullptr) continue;
        for (int e = 0; e < terms; ++e) {
          double d_db = 0.0;  // ∂integral/∂bₑ
          for (int f = 0; f < terms; ++f) d_db += 2.0 * b[f] * hp[e + f + 1] / (e + f + 1);
          b_grad = ((e + 3) * (e + 2) * (e + 1) * d_db) * spline.coefficient_gradient(j, e + 3);
          Scatter(d, b_grad.data(), jerk_weight_, objective_gradient);
        }
        objective_gradient[layout_.SpanVariable(j)] += jerk_weight_ * d_integral_dh;
      }
    }
  }

  // The time scale that puts every derivative control point within its limit.
  for (const Row& row : rows_) {
    const double ratio = std::abs(joints_[row.joint].hodograph(row.order)[row.index]) * row.inverse_limit;
    figures_.hull_scale = std::max(figures_.hull_scale, std::pow(ratio, 1.0 / row.order));
  }
  const double objective = figures_.duration + jerk_weight_ * figures_.jerk_integral;
  if (constraints == nullptr) return objective;
  if (jacobian != nullptr) {
    std::fill(jacobian, jacobian + static_cast<std::size_t>(num_constraints()) * num_variables, 0.0);
  }
  int c = 0;
  for (const Row& row : rows_) {
    const JointSpline& spline = joints_[row.joint];
    const double inverse_bound = row.inverse_limit / (1.0 - kLimitMargin);
    const double ratio = spline.hodograph(row.order)[row.index] * inverse_bound;
    constraints[c] = 0.5 * (ratio * ratio - 1.0);
    if (jacobian != nullptr) {
      Scatter(row.joint, spline.hodograph_gradient(row.order).row(row.index).data(), ratio * inverse_bound,
              jacobian + static_cast<std::size_t>(c) * num_variables);
    }
    ++c;
  }
  for (const ClearanceSample& sample : clearance_.samples) {
    constraints[c] = ClearanceRow(sample, jacobian != nullptr,
                                  jacobian == nullptr ? nullptr : jacobian + static_cast<std::size_t>(c) * num_variables);
    // The row asks for `target`; the result must keep `required`.
    figures_.clearance_shortfall =
        std::max(figures_.clearance_shortfall, constraints[c] * kClearanceScale - (sample.target - sample.required));
    ++c;
  }
  return objective;
}

double Problem::ClearanceRow(const ClearanceSample& sample, bool gradients, double* jacobian_row) {
  const int n = layout_.num_dofs, p = layout_.degree, k = layout_.num_control_points;
  const int j = sample.span;
  const double tau = sample.fraction * delta_[j];
  for (int d = 0; d < n; ++d) {
    const JointSpline& spline = joints_[d];
    double value = 0.0, rate = 0.0, power = 1.0;
    if (gradients) q_grad_.row(d).setZero();
    for (int e = 0; e <= p; ++e) {
      value += spline.coefficient(j, e) * power;
      if (gradients) {
        q_grad_.row(d) += power * spline.coefficient_gradient(j, e);
        if (e + 1 <= p) rate += (e + 1) * spline.coefficient(j, e + 1) * power;
      }
      power *= tau;
    }
    q_[d] = value;
    if (gradients) q_grad_(d, k + j) += rate * sample.fraction;
  }
  clearance_.proximity->Query(q_, clearance_.query_range, &near_);
  const LinkProximity* nearest = nullptr;
  for (const LinkProximity& link : near_) {
    if (link.found() && (nearest == nullptr || link.distance < nearest->distance)) nearest = &link;
  }
  const double distance = nearest != nullptr ? nearest->distance : clearance_.query_range;
  const double value = (sample.target - (distance - clearance_.offset)) / kClearanceScale;
  if (!gradients || nearest == nullptr) return value;
  const Eigen::Vector3d away = nearest->link_point - nearest->obstacle_point;
  if (!(away.norm() > 0.0)) return value;  // contact: no direction to push along
  const RobotModel& robot = clearance_.proximity->robot();
  robot.ForwardKinematics(q_, &poses_);
  const Eigen::Vector3d local = poses_[nearest->link].inverse() * nearest->link_point;
  const Jacobian jac = PointJacobian(robot, q_, nearest->link, local);
  // ∂distance/∂q = n̂ᵀ·J_v, n̂ the unit vector from the obstacle to the link.
  const Eigen::RowVectorXd d_distance_dq = away.normalized().transpose() * jac.bottomRows<3>();
  for (int d = 0; d < n; ++d) {
    if (d_distance_dq[d] != 0.0) Scatter(d, q_grad_.row(d).data(), -d_distance_dq[d] / kClearanceScale, jacobian_row);
  }
  return value;
}

double Problem::ScaledObjective(double scale) const {
  return figures_.duration * scale + jerk_weight_ * figures_.jerk_integral / std::pow(scale, 5);
}

TimedTrajectory Problem::Trajectory(const double* x) const {
  Eigen::MatrixXd control;
  Eigen::VectorXd delta;
  layout_.Unpack(x, &control, &delta);
  const int n = layout_.num_dofs, k = layout_.num_control_points, m = layout_.num_spans(), p = layout_.degree;
  std::vector<JointSpline> splines(n, JointSpline(p, k, 0));
  const RowMajorMatrix no_seeds;
  Eigen::VectorXd row(k);
  for (int d = 0; d < n; ++d) {
    row = control.row(d).transpose();
    splines[d].Compute(row.data(), no_seeds, delta, 0);
  }
  const Eigen::VectorXd knots = ClampedKnots(p, delta);
  std::vector<TimedTrajectory::Piece> pieces(m);
  double t0 = 0.0;
  double values[6];
  for (int j = 0; j < m; ++j) {
    pieces[j].t0 = t0;
    pieces[j].duration = delta[j];
    pieces[j].coefficients.resize(n, p + 1);
    for (int d = 0; d < n; ++d) {
      splines[d].SpanCoefficients(knots, j, values);
      for (int e = 0; e <= p; ++e) pieces[j].coefficients(d, e) = values[e];
    }
    t0 += delta[j];
  }
  return TimedTrajectory(std::move(pieces), layout_.goal);
}

}  // namespace spline
}  // namespace chasles
