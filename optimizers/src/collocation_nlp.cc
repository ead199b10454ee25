#include "collocation_nlp.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "chasles/robot/kinematics.h"

namespace chasles::collocation {
namespace {

constexpr double kIpoptInf = 1e19;  // Ipopt's default nlp_{lower,upper}_bound_inf
constexpr double kDifferenceStep = 1e-6;  // central differences of the torques [rad], [rad/s]
constexpr double kRowMargin = 1e-7;       // relative, on the velocity and jerk rows

double Bound(double value) { return std::isfinite(value) ? value : (value > 0.0 ? kIpoptInf : -kIpoptInf); }

}  // namespace

void PointState(const Layout& layout, const double* x, int point, Eigen::VectorXd* q, Eigen::VectorXd* v,
                Eigen::VectorXd* a) {
  const int k = point / 2;
  for (int i = 0; i < layout.n; ++i) {
    const double q0 = x[layout.q(k, i)], v0 = x[layout.v(k, i)], a0 = x[layout.a(k, i)];
    if (point % 2 == 0) {
      (*q)[i] = q0;
      (*v)[i] = v0;
      (*a)[i] = a0;
      continue;
    }
    // τ = h/2 on the cubic with jerk u = (q̈ₖ₊₁ − q̈ₖ)/h.
    const double h = x[layout.h(k)], a1 = x[layout.a(k + 1, i)];
    (*q)[i] = q0 + v0 * h / 2 + (5 * a0 + a1) * h * h / 48;
    (*v)[i] = v0 + (3 * a0 + a1) * h / 8;
    (*a)[i] = (a0 + a1) / 2;
  }
}

Eigen::VectorXd PositionAt(const Layout& layout, const double* x, Instant at) {
  const int k = at.interval;
  const double s = at.fraction;
  Eigen::VectorXd q(layout.n);
  for (int i = 0; i < layout.n; ++i) {
    q[i] = x[layout.q(k, i)];
    if (s == 0.0) continue;
    // q(σh) = qₖ + q̇ₖσh + (q̈ₖσ²/2 + (q̈ₖ₊₁ − q̈ₖ)σ³/6) h²: the cubic with u = (q̈ₖ₊₁ − q̈ₖ)/h.
    const double h = x[layout.h(k)], a0 = x[layout.a(k, i)], a1 = x[layout.a(k + 1, i)];
    q[i] += x[layout.v(k, i)] * s * h + (a0 * s * s / 2 + (a1 - a0) * s * s * s / 6) * h * h;
  }
  return q;
}

CollocationNlp::CollocationNlp(const Transcription& transcription, Eigen::VectorXd initial, Multipliers multipliers)
    : t_(transcription), initial_(std::move(initial)), start_multipliers_(std::move(multipliers)) {
  layout_.n = t_.num_dofs;
  layout_.intervals = t_.knots - 1;
  const int n = layout_.n, intervals = layout_.intervals;
  rows_defects_ = 2 * n * intervals;
  rows_velocity_ = n * intervals;
  rows_jerk_ = t_.max_jerk.size() != 0 ? 2 * n * intervals : 0;
  if (t_.max_effort.size() != 0) {
    for (int p = 0; p < 2 * intervals + 1; ++p) {
      if (p % 2 == 0 || t_.torque_at_midpoints) torque_points_.push_back(p);
    }
  }
  const int points = static_cast<int>(torque_points_.size());
  rows_torque_ = n * points;
  rows_clearance_ = static_cast<int>(t_.pairs.size());
  for (const CorridorRow& row : t_.corridor) {
    rows_corridor_ += row.direction.size() != 0 ? 2 : 1;
    if (row.at.fraction == 0.0 &&
        (corridor_knots_.empty() || corridor_knots_.back() != row.at.interval)) {
      corridor_knots_.push_back(row.at.interval);
    }
  }
  rows_motion_ = t_.bounded_motion ? 2 * intervals : 0;
  corridor_start_ = rows_defects_ + rows_velocity_ + rows_jerk_ + rows_torque_ + rows_clearance_;
  motion_start_ = corridor_start_ + rows_corridor_;
  if (rows_torque_ > 0) {
    torque_.resize(n, points);
    torque_jac_.assign(points, Eigen::MatrixXd(n, 3 * n));
    for (int i = 0; i < n; ++i) friction_.push_back(DofFriction(*t_.robot, i));
  }
  if (rows_clearance_ > 0) {
    for (const ClearancePair& pair : t_.pairs) instants_.push_back(pair.at);
    instants_.erase(std::unique(instants_.begin(), instants_.end()), instants_.end());
    distance_.assign(t_.pairs.size(), 0.0);
    distance_grad_.assign(t_.pairs.size(), Eigen::VectorXd::Zero(n));
    outside_.assign(t_.pairs.size(), OutsideModel());
    link_slot_.assign(t_.proximity->robot().num_links(), -1);
    for (std::size_t s = 0; s < t_.proximity->links().size(); ++s) link_slot_[t_.proximity->links()[s]] = static_cast<int>(s);
  }
  BuildStructure();
}

void CollocationNlp::BuildStructure() {
  const Layout& L = layout_;
  const int n = L.n;
  auto jac = [this](int row, int col) {
    jac_rows_.push_back(row);
    jac_cols_.push_back(col);
  };
  for (int k = 0; k < L.intervals; ++k) {
    for (int i = 0; i < n; ++i) {
      const int rp = 2 * n * k + i, rv = rp + n;
      for (int col : {L.q(k + 1, i), L.q(k, i), L.v(k, i), L.a(k, i), L.a(k + 1, i), L.h(k)}) jac(rp, col);
      for (int col : {L.v(k + 1, i), L.v(k, i), L.a(k, i), L.a(k + 1, i), L.h(k)}) jac(rv, col);
    }
  }
  int row = rows_defects_;
  for (int k = 0; k < L.intervals; ++k) {
    for (int i = 0; i < n; ++i, ++row) {
      for (int col : {L.v(k, i), L.a(k, i), L.h(k)}) jac(row, col);
    }
  }
  if (rows_jerk_ > 0) {
    for (int k = 0; k < L.intervals; ++k) {
      for (int i = 0; i < n; ++i) {
        for (int s = 0; s < 2; ++s, ++row) {
          for (int col : {L.a(k + 1, i), L.a(k, i), L.h(k)}) jac(row, col);
        }
      }
    }
  }
  for (int p : torque_points_) {
    const int k = p / 2;
    for (int i = 0; i < n; ++i, ++row) {
      for (int j = 0; j < n; ++j) jac(row, L.q(k, j));
      for (int j = 0; j < n; ++j) jac(row, L.v(k, j));
      for (int j = 0; j < n; ++j) jac(row, L.a(k, j));
      if (p % 2 == 1) {
        for (int j = 0; j < n; ++j) jac(row, L.a(k + 1, j));
        jac(row, L.h(k));
      }
    }
  }
  for (const ClearancePair& pair : t_.pairs) AddInstantColumns(row++, pair.at);
  for (const CorridorRow& corridor : t_.corridor) {
    AddInstantColumns(row++, corridor.at);
    if (corridor.direction.size() != 0) AddInstantColumns(row++, corridor.at);
  }
  for (int k = 0; k < (t_.bounded_motion ? L.intervals : 0); ++k) {
    for (int half = 0; half < 2; ++half, ++row) {
      for (int i = 0; i < n; ++i) {
        for (int col : {L.v(k, i), L.a(k, i), L.a(k + 1, i)}) jac(row, col);
      }
      jac(row, L.h(k));
    }
  }

  // Lower triangle of the Lagrangian's Hessian: objective and defects (exact). Clearance and
  // torque rows contribute no curvature here (see the driver's documentation).
  auto hess = [this](int r, int c) {
    hess_rows_.push_back(std::max(r, c));
    hess_cols_.push_back(std::min(r, c));
  };
  for (int k = 0; k < L.intervals; ++k) {
    for (int i = 0; i < n; ++i) {
      hess(L.h(k), L.v(k, i));
      hess(L.h(k), L.a(k, i));
      hess(L.a(k + 1, i), L.h(k));
      hess(L.a(k + 1, i), L.a(k, i));
      if (t_.bounded_motion) {
        hess(L.v(k, i), L.v(k, i));
        hess(L.a(k, i), L.v(k, i));
        hess(L.a(k + 1, i), L.v(k, i));
      }
    }
    hess(L.h(k), L.h(k));
    if (k > 0) hess(L.h(k), L.h(k - 1));
  }
  for (int k = 0; k <= L.intervals; ++k) {
    for (int i = 0; i < n; ++i) hess(L.a(k, i), L.a(k, i));
  }
  for (int k : corridor_knots_) {
    for (int r = 0; r < n; ++r) {
      for (int c = 0; c <= r; ++c) hess(L.q(k, r), L.q(k, c));
    }
  }
}

void CollocationNlp::AddInstantColumns(int row, Instant at) {
  const Layout& L = layout_;
  const int k = at.interval;
  const auto jac = [&](int col) {
    jac_rows_.push_back(row);
    jac_cols_.push_back(col);
  };
  for (int j = 0; j < L.n; ++j) jac(L.q(k, j));
  if (at.fraction == 0.0) return;
  for (int j = 0; j < L.n; ++j) jac(L.v(k, j));
  for (int j = 0; j < L.n; ++j) jac(L.a(k, j));
  for (int j = 0; j < L.n; ++j) jac(L.a(k + 1, j));
  jac(L.h(k));
}

void CollocationNlp::WriteInstantGradient(const double* x, Instant at, const Eigen::VectorXd& grad,
                                          double** out) const {
  const Layout& L = layout_;
  const int n = L.n;
  for (int j = 0; j < n; ++j) *(*out)++ = grad[j];
  if (at.fraction == 0.0) return;
  // q(σh) = qₖ + q̇ₖσh + (q̈ₖσ²/2 + (q̈ₖ₊₁ − q̈ₖ)σ³/6)h² (PositionAt).
  const int k = at.interval;
  const double h = x[L.h(k)], sg = at.fraction;
  const double c1 = (sg * sg / 2 - sg * sg * sg / 6) * h * h, c2 = sg * sg * sg / 6 * h * h;
  for (int j = 0; j < n; ++j) *(*out)++ = grad[j] * sg * h;
  for (int j = 0; j < n; ++j) *(*out)++ = grad[j] * c1;
  for (int j = 0; j < n; ++j) *(*out)++ = grad[j] * c2;
  double dh = 0.0;
  for (int j = 0; j < n; ++j) {
    const double a0 = x[L.a(k, j)], a1 = x[L.a(k + 1, j)];
    dh += grad[j] * (x[L.v(k, j)] * sg + (a0 * sg * sg / 2 + (a1 - a0) * sg * sg * sg / 6) * 2 * h);
  }
  *(*out)++ = dh;
}

bool CollocationNlp::get_nlp_info(Ipopt::Index& n, Ipopt::Index& m, Ipopt::Index& nnz_jac_g,
                                  Ipopt::Index& nnz_h_lag, IndexStyleEnum& index_style) {
  n = layout_.size();
  m = motion_start_ + rows_motion_;
  nnz_jac_g = static_cast<Ipopt::Index>(jac_rows_.size());
  nnz_h_lag = static_cast<Ipopt::Index>(hess_rows_.size());
  index_style = C_STYLE;
  return true;
}

void CollocationNlp::Bounds(std::vector<double>* x_l, std::vector<double>* x_u, std::vector<double>* g_l,
                            std::vector<double>* g_u) const {
  const Layout& L = layout_;
  const int n = L.n;
  x_l->assign(L.size(), 0.0);
  x_u->assign(L.size(), 0.0);
  for (int k = 0; k <= L.intervals; ++k) {
    for (int i = 0; i < n; ++i) {
      const double margin = t_.position_margin.size() != 0 ? t_.position_margin(k, i) : 0.0;
      (*x_l)[L.q(k, i)] = Bound(t_.position_lower[i] + margin);
      (*x_u)[L.q(k, i)] = Bound(t_.position_upper[i] - margin);
      (*x_l)[L.v(k, i)] = -t_.max_velocity[i];
      (*x_u)[L.v(k, i)] = t_.max_velocity[i];
      (*x_l)[L.a(k, i)] = -t_.max_acceleration[i];
      (*x_u)[L.a(k, i)] = t_.max_acceleration[i];
    }
    if (k < L.intervals) {
      (*x_l)[L.h(k)] = t_.min_interval;
      (*x_u)[L.h(k)] = kIpoptInf;
    }
  }
  auto fix = [&](int index, double value) { (*x_l)[index] = (*x_u)[index] = value; };
  for (int i = 0; i < n; ++i) {
    fix(L.q(0, i), t_.start_q[i]);
    fix(L.v(0, i), t_.start_v[i]);
    fix(L.q(L.intervals, i), t_.end_q[i]);
    fix(L.v(L.intervals, i), t_.end_v[i]);
    if (t_.start_at_rest_acceleration) fix(L.a(0, i), 0.0);
    if (t_.end_at_rest_acceleration) fix(L.a(L.intervals, i), 0.0);
  }
  const int m = motion_start_ + rows_motion_;
  g_l->assign(m, 0.0);
  g_u->assign(m, 0.0);
  int row = rows_defects_;
  // Rows get a 1e-7 relative margin: Ipopt relaxes constraint bounds by ~1e-8 (bound_relax_factor)
  // while variable bounds are honoured exactly, and a result just over a limit would have to be
  // slowed down (impossible with moving ends).
  for (int r = 0; r < rows_velocity_; ++r, ++row) {
    (*g_l)[row] = -t_.max_velocity[r % n] * (1.0 - kRowMargin);
    (*g_u)[row] = t_.max_velocity[r % n] * (1.0 - kRowMargin);
  }
  for (int r = 0; r < rows_jerk_; ++r, ++row) {
    // Even rows: q̈ₖ₊₁ − q̈ₖ + J h >= 0; odd rows: q̈ₖ₊₁ − q̈ₖ − J h <= 0.
    if (r % 2 == 0) (*g_u)[row] = kIpoptInf; else (*g_l)[row] = -kIpoptInf;
  }
  for (int r = 0; r < rows_torque_; ++r, ++row) {
    const int i = r % n;
    // The dof's Coulomb friction, its mimic joints' included (DofFriction).
    const double coulomb = t_.dynamics.include_friction ? friction_[i].friction : 0.0;
    (*g_l)[row] = -(t_.max_effort[i] - coulomb);
    (*g_u)[row] = t_.max_effort[i] - coulomb;
  }
  for (const ClearancePair& pair : t_.pairs) {
    (*g_l)[row] = pair.minimum;
    (*g_u)[row] = kIpoptInf;
    ++row;
  }
  for (const CorridorRow& corridor : t_.corridor) {
    (*g_l)[row] = -kIpoptInf;
    (*g_u)[row] = corridor.radius * corridor.radius;
    ++row;
    if (corridor.direction.size() == 0) continue;
    (*g_l)[row] = corridor.inset;
    (*g_u)[row] = corridor.length - corridor.inset;
    ++row;
  }
  for (int r = 0; r < rows_motion_; ++r, ++row) {
    (*g_l)[row] = -kIpoptInf;
    (*g_u)[row] = t_.max_step * t_.max_step;
  }
}

bool CollocationNlp::get_bounds_info(Ipopt::Index n, Ipopt::Number* x_l, Ipopt::Number* x_u, Ipopt::Index m,
                                     Ipopt::Number* g_l, Ipopt::Number* g_u) {
  std::vector<double> xl, xu, gl, gu;
  Bounds(&xl, &xu, &gl, &gu);
  std::copy(xl.begin(), xl.end(), x_l);
  std::copy(xu.begin(), xu.end(), x_u);
  std::copy(gl.begin(), gl.end(), g_l);
  std::copy(gu.begin(), gu.end(), g_u);
  return static_cast<int>(xl.size()) == n && static_cast<int>(gl.size()) == m;
}

bool CollocationNlp::get_scaling_parameters(Ipopt::Number& obj_scaling, bool& use_x_scaling, Ipopt::Index,
                                            Ipopt::Number* x_scaling, bool& use_g_scaling, Ipopt::Index,
                                            Ipopt::Number* g_scaling) {
  // Every variable and row in units of its natural size: velocities of their limit, intervals
  // of the warm start's h₀, defects of one interval's motion, torques of their limit.
  const Layout& L = layout_;
  const int n = L.n;
  const double h0 = t_.nominal_interval;
  obj_scaling = 10.0 / h0;  // ∂(scaled objective)/∂(scaled hₖ) = 10: measured best of 0.1 … 30
  use_x_scaling = true;
  for (int k = 0; k <= L.intervals; ++k) {
    for (int i = 0; i < n; ++i) {
      x_scaling[L.q(k, i)] = 1.0;
      x_scaling[L.v(k, i)] = 1.0 / t_.max_velocity[i];
      x_scaling[L.a(k, i)] = 1.0 / t_.max_acceleration[i];
    }
    if (k < L.intervals) x_scaling[L.h(k)] = 1.0 / h0;
  }
  use_g_scaling = true;
  int row = 0;
  for (int k = 0; k < L.intervals; ++k) {
    for (int i = 0; i < n; ++i) g_scaling[row + i] = 1.0 / (t_.max_velocity[i] * h0);
    for (int i = 0; i < n; ++i) g_scaling[row + n + i] = 1.0 / (t_.max_acceleration[i] * h0);
    row += 2 * n;
  }
  for (int r = 0; r < rows_velocity_; ++r, ++row) g_scaling[row] = 1.0 / t_.max_velocity[r % n];
  for (int r = 0; r < rows_jerk_; ++r, ++row) g_scaling[row] = 1.0 / t_.max_acceleration[(r / 2) % n];
  for (int r = 0; r < rows_torque_; ++r, ++row) g_scaling[row] = 1.0 / t_.max_effort[r % n];
  for (int r = 0; r < rows_clearance_; ++r, ++row) g_scaling[row] = 1.0;
  for (const CorridorRow& corridor : t_.corridor) {
    g_scaling[row++] = 1.0 / (corridor.radius * corridor.radius);
    if (corridor.direction.size() != 0) g_scaling[row++] = 1.0 / corridor.radius;
  }
  for (int r = 0; r < rows_motion_; ++r, ++row) g_scaling[row] = 1.0 / (t_.max_step * t_.max_step);
  return true;
}

bool CollocationNlp::get_starting_point(Ipopt::Index n, bool init_x, Ipopt::Number* x, bool init_z,
                                        Ipopt::Number* z_L, Ipopt::Number* z_U, Ipopt::Index m, bool init_lambda,
                                        Ipopt::Number* lambda) {
  if (!init_x || n != initial_.size()) return false;
  std::copy(initial_.data(), initial_.data() + n, x);
  const Multipliers& w = start_multipliers_;
  if (init_z) {
    if (w.lower.size() != n || w.upper.size() != n) return false;
    std::copy(w.lower.data(), w.lower.data() + n, z_L);
    std::copy(w.upper.data(), w.upper.data() + n, z_U);
  }
  if (init_lambda) {
    if (w.rows.size() != m) return false;
    std::copy(w.rows.data(), w.rows.data() + m, lambda);
  }
  return true;
}

// The objective: Σ hₖ + w Σ ‖q̈ₖ₊₁ − q̈ₖ‖²/hₖ plus the tie-breaking regularisation
// ρ/h₀ Σ (hₖ₊₁ − hₖ)² + ρ/n Σₖ hₖ Σᵢ (q̈ₖᵢ/Aᵢ)² (see Transcription::regularization).
bool CollocationNlp::eval_f(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Number& obj_value) {
  const Layout& L = layout_;
  const double w = t_.jerk_weight, rho = t_.regularization;
  const double spacing = rho / t_.nominal_interval;
  double total = 0.0;
  for (int k = 0; k < L.intervals; ++k) {
    const double h = x[L.h(k)];
    total += h;
    double jerk = 0.0, effort = 0.0;
    for (int i = 0; i < L.n; ++i) {
      const double d = x[L.a(k + 1, i)] - x[L.a(k, i)];
      const double a = x[L.a(k, i)] / t_.max_acceleration[i];
      jerk += d * d;
      effort += a * a;
    }
    total += w * jerk / h + rho / L.n * h * effort;
    if (k > 0) total += spacing * (h - x[L.h(k - 1)]) * (h - x[L.h(k - 1)]);
  }
  obj_value = total;
  return true;
}

bool CollocationNlp::eval_grad_f(Ipopt::Index n, const Ipopt::Number* x, bool, Ipopt::Number* grad_f) {
  const Layout& L = layout_;
  std::fill(grad_f, grad_f + n, 0.0);
  const double w = t_.jerk_weight, rho = t_.regularization;
  const double spacing = rho / t_.nominal_interval;
  for (int k = 0; k < L.intervals; ++k) {
    const double h = x[L.h(k)];
    grad_f[L.h(k)] += 1.0;
    if (k > 0) {
      const double step = 2 * spacing * (h - x[L.h(k - 1)]);
      grad_f[L.h(k)] += step;
      grad_f[L.h(k - 1)] -= step;
    }
    for (int i = 0; i < L.n; ++i) {
      const double d = x[L.a(k + 1, i)] - x[L.a(k, i)];
      grad_f[L.a(k + 1, i)] += 2 * w * d / h;
      grad_f[L.a(k, i)] -= 2 * w * d / h;
      grad_f[L.h(k)] -= w * d * d / (h * h);
      const double c = rho / (L.n * t_.max_acceleration[i] * t_.max_acceleration[i]);
      const double a = x[L.a(k, i)];
      grad_f[L.a(k, i)] += 2 * c * h * a;
      grad_f[L.h(k)] += c * a * a;
    }
  }
  return true;
}

double CollocationNlp::HalfMotion(const double* x, int k, int i, int half) const {
  // q(h/2) − qₖ = q̇ₖh/2 + (5q̈ₖ + q̈ₖ₊₁)h²/48; qₖ₊₁ − q(h/2) = q̇ₖh/2 + (11q̈ₖ + 7q̈ₖ₊₁)h²/48 (by the
  // position defect).
  const Layout& L = layout_;
  const double h = x[L.h(k)], a0 = x[L.a(k, i)], a1 = x[L.a(k + 1, i)];
  const double c0 = half == 0 ? 5.0 / 48 : 11.0 / 48, c1 = half == 0 ? 1.0 / 48 : 7.0 / 48;
  return x[L.v(k, i)] * h / 2 + (c0 * a0 + c1 * a1) * h * h;
}

void CollocationNlp::UpdateTorques(const double* x, bool derivatives) {
  if (torques_valid_ && (!derivatives || torque_derivatives_valid_)) return;
  const Layout& L = layout_;
  const int n = L.n;
  const RobotModel& robot = *t_.robot;
  DynamicsOptions frictionless = t_.dynamics;
  frictionless.include_friction = false;
  Eigen::VectorXd q(n), v(n), a(n);
  for (std::size_t slot = 0; slot < torque_points_.size(); ++slot) {
    const int k = static_cast<int>(slot);  // column of torque_ / entry of torque_jac_
    PointState(L, x, torque_points_[slot], &q, &v, &a);
    // The smooth part of the torque: RNEA + viscous damping. Coulomb friction (a step of
    // ±fᵢ in q̇ᵢ) is taken off the bounds instead (Bounds), so |τ| <= τmax holds whatever the
    // sign of q̇ near the knot.
    torque_.col(k) = InverseDynamics(robot, q, v, a, frictionless);
    if (t_.dynamics.include_friction) {
      for (int i = 0; i < n; ++i) torque_(i, k) += friction_[i].damping * v[i];
    }
    if (!derivatives) continue;
    // ∂τ/∂q̈ = M(q) exactly; ∂τ/∂q and ∂τ/∂q̇ by central differences of the frictionless
    // RNEA, plus the viscous damping on the diagonal of ∂τ/∂q̇.
    Eigen::MatrixXd& J = torque_jac_[k];
    for (int j = 0; j < n; ++j) {
      Eigen::VectorXd plus = q, minus = q;
      plus[j] += kDifferenceStep;
      minus[j] -= kDifferenceStep;
      J.col(j) = (InverseDynamics(robot, plus, v, a, frictionless) - InverseDynamics(robot, minus, v, a, frictionless)) /
                 (2 * kDifferenceStep);
      plus = v;
      minus = v;
      plus[j] += kDifferenceStep;
      minus[j] -= kDifferenceStep;
      J.col(n + j) = (InverseDynamics(robot, q, plus, a, frictionless) - InverseDynamics(robot, q, minus, a, frictionless)) /
                     (2 * kDifferenceStep);
      if (t_.dynamics.include_friction) J(j, n + j) += friction_[j].damping;
    }
    J.rightCols(n) = MassMatrix(robot, q);
  }
  torques_valid_ = true;
  torque_derivatives_valid_ = derivatives;
}

void CollocationNlp::UpdateClearances(const double* x) {
  if (clearances_valid_) return;
  const RobotModel& robot = t_.proximity->robot();
  std::vector<LinkProximity> near;
  std::vector<Eigen::Isometry3d> poses;
  std::size_t next = 0;  // pairs are sorted by instant
  for (const Instant& at : instants_) {
    const Eigen::VectorXd q = PositionAt(layout_, x, at);
    t_.proximity->Query(q, std::numeric_limits<double>::infinity(), &near);
    robot.ForwardKinematics(q, &poses);
    for (; next < t_.pairs.size() && t_.pairs[next].at == at; ++next) {
      const int link = t_.pairs[next].link;
      const LinkProximity& p = near[link_slot_[link]];
      distance_grad_[next].setZero();
      if (!p.found()) {
        distance_[next] = 1e3;  // no obstacle at all: far
        continue;
      }
      const Eigen::Vector3d away = p.link_point - p.obstacle_point;
      const double norm = away.norm();
      OutsideModel& model = outside_[next];
      if (p.distance > 0.0 && norm > 0.0) {
        // d(dist)/dq = n̂ᵀ J_v(q, link, point), the nearest point held fixed on the link.
        const Eigen::Vector3d local = poses[link].inverse() * p.link_point;
        const Jacobian jac = PointJacobian(robot, q, link, local);
        distance_[next] = p.distance;
        distance_grad_[next] = jac.bottomRows<3>().transpose() * (away / norm);
        model.valid = true;
        model.q = q;
        model.distance = p.distance;
        model.gradient = distance_grad_[next];
      } else if (model.valid) {
        // In contact the distance is 0 with no direction (no penetration depth): continue the
        // last outside value linearly, so a trial step into an obstacle is pushed back out.
        distance_[next] = std::min(0.0, model.distance + model.gradient.dot(q - model.q));
        distance_grad_[next] = model.gradient;
      } else {
        distance_[next] = 0.0;
      }
    }
  }
  clearances_valid_ = true;
}

bool CollocationNlp::eval_g(Ipopt::Index, const Ipopt::Number* x, bool new_x, Ipopt::Index, Ipopt::Number* g) {
  if (new_x) torques_valid_ = torque_derivatives_valid_ = clearances_valid_ = false;
  const Layout& L = layout_;
  const int n = L.n;
  for (int k = 0; k < L.intervals; ++k) {
    const double h = x[L.h(k)];
    for (int i = 0; i < n; ++i) {
      const double a0 = x[L.a(k, i)], a1 = x[L.a(k + 1, i)], v0 = x[L.v(k, i)];
      g[2 * n * k + i] = x[L.q(k + 1, i)] - x[L.q(k, i)] - v0 * h - (2 * a0 + a1) * h * h / 6;
      g[2 * n * k + n + i] = x[L.v(k + 1, i)] - v0 - (a0 + a1) * h / 2;
    }
  }
  int row = rows_defects_;
  for (int k = 0; k < L.intervals; ++k) {
    for (int i = 0; i < n; ++i) g[row++] = x[L.v(k, i)] + x[L.a(k, i)] * x[L.h(k)] / 2;
  }
  if (rows_jerk_ > 0) {
    for (int k = 0; k < L.intervals; ++k) {
      for (int i = 0; i < n; ++i) {
        const double d = x[L.a(k + 1, i)] - x[L.a(k, i)];
        const double jh = t_.max_jerk[i] * (1.0 - kRowMargin) * x[L.h(k)];
        g[row++] = d + jh;
        g[row++] = d - jh;
      }
    }
  }
  if (rows_torque_ > 0) {
    UpdateTorques(x, false);
    for (std::size_t slot = 0; slot < torque_points_.size(); ++slot) {
      for (int i = 0; i < n; ++i) g[row++] = torque_(i, slot);
    }
  }
  if (rows_clearance_ > 0) {
    UpdateClearances(x);
    for (double d : distance_) g[row++] = d;
  }
  for (const CorridorRow& corridor : t_.corridor) {
    const Eigen::VectorXd e = PositionAt(L, x, corridor.at) - corridor.origin;
    if (corridor.direction.size() == 0) {
      g[row++] = e.squaredNorm();
      continue;
    }
    const double along = corridor.direction.dot(e);
    g[row++] = (e - along * corridor.direction).squaredNorm();
    g[row++] = along;
  }
  for (int k = 0; k < (t_.bounded_motion ? L.intervals : 0); ++k) {
    for (int half = 0; half < 2; ++half) {
      double sum = 0.0;
      for (int i = 0; i < n; ++i) {
        const double e = HalfMotion(x, k, i, half);
        sum += e * e;
      }
      g[row++] = sum;
    }
  }
  return true;
}

bool CollocationNlp::eval_jac_g(Ipopt::Index, const Ipopt::Number* x, bool new_x, Ipopt::Index, Ipopt::Index nele_jac,
                                Ipopt::Index* iRow, Ipopt::Index* jCol, Ipopt::Number* values) {
  if (values == nullptr) {
    if (nele_jac != static_cast<Ipopt::Index>(jac_rows_.size())) return false;
    std::copy(jac_rows_.begin(), jac_rows_.end(), iRow);
    std::copy(jac_cols_.begin(), jac_cols_.end(), jCol);
    return true;
  }
  if (new_x) torques_valid_ = torque_derivatives_valid_ = clearances_valid_ = false;
  const Layout& L = layout_;
  const int n = L.n;
  double* out = values;
  for (int k = 0; k < L.intervals; ++k) {
    const double h = x[L.h(k)];
    for (int i = 0; i < n; ++i) {
      const double a0 = x[L.a(k, i)], a1 = x[L.a(k + 1, i)], v0 = x[L.v(k, i)];
      // Position defect: q(k+1), q(k), q̇(k), q̈(k), q̈(k+1), h(k).
      *out++ = 1.0;
      *out++ = -1.0;
      *out++ = -h;
      *out++ = -h * h / 3;
      *out++ = -h * h / 6;
      *out++ = -v0 - (2 * a0 + a1) * h / 3;
      // Velocity defect: q̇(k+1), q̇(k), q̈(k), q̈(k+1), h(k).
      *out++ = 1.0;
      *out++ = -1.0;
      *out++ = -h / 2;
      *out++ = -h / 2;
      *out++ = -(a0 + a1) / 2;
    }
  }
  for (int k = 0; k < L.intervals; ++k) {
    for (int i = 0; i < n; ++i) {
      // Velocity control point: q̇(k), q̈(k), h(k).
      *out++ = 1.0;
      *out++ = x[L.h(k)] / 2;
      *out++ = x[L.a(k, i)] / 2;
    }
  }
  if (rows_jerk_ > 0) {
    for (int k = 0; k < L.intervals; ++k) {
      for (int i = 0; i < n; ++i) {
        for (int s = 0; s < 2; ++s) {
          *out++ = 1.0;
          *out++ = -1.0;
          *out++ = (s == 0 ? 1.0 : -1.0) * t_.max_jerk[i] * (1.0 - kRowMargin);
        }
      }
    }
  }
  if (rows_torque_ > 0) {
    UpdateTorques(x, true);
    for (std::size_t slot = 0; slot < torque_points_.size(); ++slot) {
      const int p = torque_points_[slot];
      const Eigen::MatrixXd& J = torque_jac_[slot];
      if (p % 2 == 0) {
        for (int i = 0; i < n; ++i) {
          for (int j = 0; j < 3 * n; ++j) *out++ = J(i, j);
        }
        continue;
      }
      // Midpoint state (see PointState) through the chain rule.
      const int k = p / 2;
      const double h = x[L.h(k)];
      for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) *out++ = J(i, j);  // q(k)
        for (int j = 0; j < n; ++j) *out++ = J(i, j) * h / 2 + J(i, n + j);  // q̇(k)
        for (int j = 0; j < n; ++j) {
          *out++ = J(i, j) * 5 * h * h / 48 + J(i, n + j) * 3 * h / 8 + J(i, 2 * n + j) / 2;  // q̈(k)
        }
        for (int j = 0; j < n; ++j) {
          *out++ = J(i, j) * h * h / 48 + J(i, n + j) * h / 8 + J(i, 2 * n + j) / 2;  // q̈(k+1)
        }
        double dh = 0.0;
        for (int j = 0; j < n; ++j) {
          const double a0 = x[L.a(k, j)], a1 = x[L.a(k + 1, j)];
          dh += J(i, j) * (x[L.v(k, j)] / 2 + (5 * a0 + a1) * h / 24) + J(i, n + j) * (3 * a0 + a1) / 8;
        }
        *out++ = dh;
      }
    }
  }
  if (rows_clearance_ > 0) {
    UpdateClearances(x);
    for (std::size_t p = 0; p < t_.pairs.size(); ++p) WriteInstantGradient(x, t_.pairs[p].at, distance_grad_[p], &out);
  }
  for (const CorridorRow& corridor : t_.corridor) {
    // ∇‖Pe‖² = 2Pe (P symmetric and idempotent); ∇(d̂ᵀe) = d̂.
    const Eigen::VectorXd e = PositionAt(L, x, corridor.at) - corridor.origin;
    if (corridor.direction.size() == 0) {
      WriteInstantGradient(x, corridor.at, 2 * e, &out);
      continue;
    }
    WriteInstantGradient(x, corridor.at, 2 * (e - corridor.direction.dot(e) * corridor.direction), &out);
    WriteInstantGradient(x, corridor.at, corridor.direction, &out);
  }
  for (int k = 0; k < (t_.bounded_motion ? L.intervals : 0); ++k) {
    const double h = x[L.h(k)];
    for (int half = 0; half < 2; ++half) {
      const double c0 = half == 0 ? 5.0 / 48 : 11.0 / 48, c1 = half == 0 ? 1.0 / 48 : 7.0 / 48;
      double dh = 0.0;
      for (int i = 0; i < n; ++i) {
        const double e = HalfMotion(x, k, i, half);
        *out++ = 2 * e * h / 2;       // q̇(k)
        *out++ = 2 * e * c0 * h * h;  // q̈(k)
        *out++ = 2 * e * c1 * h * h;  // q̈(k+1)
        dh += 2 * e * (x[L.v(k, i)] / 2 + 2 * (c0 * x[L.a(k, i)] + c1 * x[L.a(k + 1, i)]) * h);
      }
      *out++ = dh;
    }
  }
  return out - values == static_cast<std::ptrdiff_t>(jac_rows_.size());
}

bool CollocationNlp::eval_h(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Number obj_factor, Ipopt::Index,
                            const Ipopt::Number* lambda, bool, Ipopt::Index nele_hess, Ipopt::Index* iRow,
                            Ipopt::Index* jCol, Ipopt::Number* values) {
  if (values == nullptr) {
    if (nele_hess != static_cast<Ipopt::Index>(hess_rows_.size())) return false;
    std::copy(hess_rows_.begin(), hess_rows_.end(), iRow);
    std::copy(hess_cols_.begin(), hess_cols_.end(), jCol);
    return true;
  }
  const Layout& L = layout_;
  const int n = L.n;
  const double w = t_.jerk_weight * obj_factor;
  const double rho = t_.regularization * obj_factor;
  const double spacing = rho / t_.nominal_interval;
  double* out = values;
  std::vector<double> diagonal((L.intervals + 1) * n, 0.0);
  for (int k = 0; k < L.intervals; ++k) {
    const double h = x[L.h(k)];
    double hh = 0.0;
    for (int i = 0; i < n; ++i) {
      const double lp = lambda[2 * n * k + i], lv = lambda[2 * n * k + n + i];
      const double lc = lambda[rows_defects_ + n * k + i];
      const double a0 = x[L.a(k, i)], a1 = x[L.a(k + 1, i)], d = a1 - a0;
      const double c = rho / (n * t_.max_acceleration[i] * t_.max_acceleration[i]);
      *out++ = -lp;                                                                  // (h, q̇ₖ)
      *out++ = -lp * 2 * h / 3 - lv / 2 + lc / 2 + 2 * w * d / (h * h) + 2 * c * a0;  // (h, q̈ₖ)
      *out++ = -lp * h / 3 - lv / 2 - 2 * w * d / (h * h);                          // (q̈ₖ₊₁, h)
      *out++ = -2 * w / h;                                                           // (q̈ₖ₊₁, q̈ₖ)
      diagonal[k * n + i] += 2 * w / h + 2 * c * h;
      diagonal[(k + 1) * n + i] += 2 * w / h;
      if (t_.bounded_motion) {
        // λ ∇²(e²) = 2λ(∇e ∇eᵀ + e ∇²e) for e = q̇h/2 + (c₀q̈ₖ + c₁q̈ₖ₊₁)h², over (q̇ₖ, q̈ₖ, q̈ₖ₊₁, h).
        double vv = 0.0, av = 0.0, bv = 0.0, hv = 0.0, ha = 0.0, hb = 0.0, aa = 0.0, ba = 0.0, bb = 0.0, hh2 = 0.0;
        for (int half = 0; half < 2; ++half) {
          const double lm = 2 * lambda[motion_start_ + 2 * k + half];
          const double c0 = half == 0 ? 5.0 / 48 : 11.0 / 48, c1 = half == 0 ? 1.0 / 48 : 7.0 / 48;
          const double e = HalfMotion(x, k, i, half);
          const double gv = h / 2, ga = c0 * h * h, gb = c1 * h * h;
          const double gh = x[L.v(k, i)] / 2 + 2 * (c0 * a0 + c1 * a1) * h;
          vv += lm * gv * gv;
          av += lm * ga * gv;
          bv += lm * gb * gv;
          aa += lm * ga * ga;
          ba += lm * gb * ga;
          bb += lm * gb * gb;
          hv += lm * (gh * gv + e / 2);
          ha += lm * (gh * ga + e * 2 * c0 * h);
          hb += lm * (gh * gb + e * 2 * c1 * h);
          hh2 += lm * (gh * gh + e * 2 * (c0 * a0 + c1 * a1));
        }
        out[-4] += hv;
        out[-3] += ha;
        out[-2] += hb;
        out[-1] += ba;
        *out++ = vv;  // (q̇ₖ, q̇ₖ)
        *out++ = av;  // (q̈ₖ, q̇ₖ)
        *out++ = bv;  // (q̈ₖ₊₁, q̇ₖ)
        diagonal[k * n + i] += aa;
        diagonal[(k + 1) * n + i] += bb;
        hh += hh2;
      }
      hh += -lp * (2 * a0 + a1) / 3 + 2 * w * d * d / (h * h * h);
    }
    const bool inner = k > 0, before_last = k + 1 < L.intervals;
    *out++ = hh + 2 * spacing * ((inner ? 1 : 0) + (before_last ? 1 : 0));  // (h, h)
    if (inner) *out++ = -2 * spacing;                                         // (hₖ, hₖ₋₁)
  }
  for (double value : diagonal) *out++ = value;
  // Corridor rows at knots: λ·2P on qₖ (lower triangle), summed over the knot's rows.
  std::size_t next = 0;
  int row = corridor_start_;
  for (int k : corridor_knots_) {
    Eigen::MatrixXd block = Eigen::MatrixXd::Zero(n, n);
    for (; next < t_.corridor.size() && t_.corridor[next].at.interval <= k; ++next) {
      const CorridorRow& corridor = t_.corridor[next];
      const double l = lambda[row];
      row += corridor.direction.size() != 0 ? 2 : 1;
      if (corridor.at.interval != k || corridor.at.fraction != 0.0) continue;
      block.diagonal().array() += 2 * l;
      if (corridor.direction.size() != 0) block -= 2 * l * corridor.direction * corridor.direction.transpose();
    }
    for (int r = 0; r < n; ++r) {
      for (int c = 0; c <= r; ++c) *out++ = block(r, c);
    }
  }
  return out - values == static_cast<std::ptrdiff_t>(hess_rows_.size());
}

void CollocationNlp::finalize_solution(Ipopt::SolverReturn, Ipopt::Index n, const Ipopt::Number* x,
                                       const Ipopt::Number* z_L, const Ipopt::Number* z_U, Ipopt::Index m,
                                       const Ipopt::Number* g, const Ipopt::Number* lambda, Ipopt::Number,
                                       const Ipopt::IpoptData*, Ipopt::IpoptCalculatedQuantities*) {
  solution_ = Eigen::Map<const Eigen::VectorXd>(x, n);
  multipliers_.lower = Eigen::Map<const Eigen::VectorXd>(z_L, n);
  multipliers_.upper = Eigen::Map<const Eigen::VectorXd>(z_U, n);
  multipliers_.rows = Eigen::Map<const Eigen::VectorXd>(lambda, m);
  std::vector<double> xl, xu, gl, gu;
  Bounds(&xl, &xu, &gl, &gu);
  violation_ = 0.0;
  for (int r = 0; r < m; ++r) violation_ = std::max({violation_, gl[r] - g[r], g[r] - gu[r]});
  for (int j = 0; j < n; ++j) violation_ = std::max({violation_, xl[j] - x[j], x[j] - xu[j]});
}

bool CollocationNlp::intermediate_callback(Ipopt::AlgorithmMode, Ipopt::Index, Ipopt::Number, Ipopt::Number,
                                           Ipopt::Number, Ipopt::Number, Ipopt::Number, Ipopt::Number,
                                           Ipopt::Number, Ipopt::Number, Ipopt::Index, const Ipopt::IpoptData*,
                                           Ipopt::IpoptCalculatedQuantities*) {
  if (t_.stop && t_.stop()) {
    stopped_ = true;
    return false;
  }
  return true;
}

}  // namespace chasles::collocation
