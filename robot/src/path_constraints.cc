#include "chasles/robot/path_constraints.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include <Eigen/Cholesky>

#include "chasles/robot/error.h"
#include "chasles/robot/kinematics.h"
#include "chasles/robot/lie_group.h"

namespace chasles {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kMaxCertifyStates = 20000;
constexpr double kMinInterval = 1e-9;

const char* AxisName(int a) { return a == 0 ? "x" : a == 1 ? "y" : "z"; }

/// The per-dof sums of per-moving-joint levers (a dof drives its own joint and its mimics).
Eigen::VectorXd PerDof(const RobotModel& robot, const Eigen::VectorXd& moving) {
  Eigen::VectorXd out = Eigen::VectorXd::Zero(robot.num_dofs());
  for (int m = 0; m < robot.num_moving_joints(); ++m) {
    const int dof = robot.joints()[robot.moving_joint(m)].dof;
    if (dof >= 0) out[dof] += moving[m];
  }
  return out;
}

}  // namespace

PathConstraints::PathConstraints(std::shared_ptr<const RobotModel> robot, std::vector<OrientationConstraintSpec> orientation,
                                 std::vector<PositionConstraintSpec> position, std::string field)
    : robot_(std::move(robot)), orientation_(std::move(orientation)), position_(std::move(position)), field_(std::move(field)) {
  if (!robot_) ThrowInvalid(field_ + ": no robot");
  const auto check_link = [this](int link, const std::string& where) {
    if (link < 0 || link >= robot_->num_links()) {
      ThrowInvalid(where + ".link = " + std::to_string(link) + " is not a link of robot '" + robot_->name() + "' (" +
                   std::to_string(robot_->num_links()) + " links)");
    }
  };
  tolerance_.resize(num_errors());
  int row = 0;
  for (std::size_t i = 0; i < orientation_.size(); ++i) {
    OrientationConstraintSpec& c = orientation_[i];
    const std::string where = field_ + ".orientation[" + std::to_string(i) + "]";
    check_link(c.link, where);
    const double norm = c.orientation.coeffs().norm();
    if (!c.orientation.coeffs().allFinite() || !(norm > 1e-9)) {
      ThrowInvalid(where + ".orientation must be a finite quaternion of non-zero norm (got norm " + FormatNumber(norm) + ")");
    }
    c.orientation.normalize();
    const bool euler = c.parameterization == OrientationParameterization::kXyzEulerAngles;
    for (int a = 0; a < 3; ++a) {
      const double t = c.tolerance[a];
      const bool euler_y = euler && a == 1;
      if (!(t > 0 && (euler_y ? t < kPi / 2 : t <= kPi))) {
        ThrowInvalid(where + ".tolerance." + AxisName(a) + " = " + FormatNumber(t) + " must be within (0, " +
                     (euler_y ? std::string("π/2) with XYZ_EULER_ANGLES: at |y| = π/2 the x and z angles are "
                                                    "undefined (use ROTATION_VECTOR)")
                                      : std::string("π] [rad]")));
      }
      tolerance_[row++] = t;
    }
    levers_.push_back(PerDof(*robot_, AngularLevers(*robot_, c.link)));
  }
  for (std::size_t i = 0; i < position_.size(); ++i) {
    PositionConstraintSpec& c = position_[i];
    const std::string where = field_ + ".position[" + std::to_string(i) + "]";
    check_link(c.link, where);
    if (!c.point.allFinite()) ThrowInvalid(where + ".point must be finite");
    if (!c.region.matrix().allFinite()) ThrowInvalid(where + ".region must be a finite pose");
    for (int a = 0; a < 3; ++a) {
      const double h = c.half_extents[a];
      if (!(std::isfinite(h) && h >= 0)) {
        ThrowInvalid(where + ".half_extents." + AxisName(a) + " = " + FormatNumber(h) + " must be finite and >= 0 [m]");
      }
      tolerance_[row++] = h;
    }
    levers_.push_back(PerDof(*robot_, PointLevers(*robot_, c.link, c.point)));
  }
}

void PathConstraints::Errors(const Eigen::VectorXd& q, Eigen::VectorXd* errors) const {
  thread_local std::vector<Eigen::Isometry3d> poses;
  robot_->ForwardKinematics(q, &poses);
  ErrorsFromPoses(poses, errors);
}

void PathConstraints::ErrorsFromPoses(const std::vector<Eigen::Isometry3d>& poses, Eigen::VectorXd* errors) const {
  errors->resize(num_errors());
  int row = 0;
  for (const OrientationConstraintSpec& c : orientation_) {
    const Eigen::Matrix3d E = c.orientation.toRotationMatrix().transpose() * poses[c.link].linear();
    if (c.parameterization == OrientationParameterization::kRotationVector) {
      errors->segment<3>(row) = LogSO3(E);
    } else {  // E = Rx(x)·Ry(y)·Rz(z): E02 = sin y, E12 = −sin x cos y, E22 = cos x cos y, E01 = −cos y sin z, E00 = cos y cos z
      (*errors)[row] = std::atan2(-E(1, 2), E(2, 2));
      (*errors)[row + 1] = std::asin(std::clamp(E(0, 2), -1.0, 1.0));
      (*errors)[row + 2] = std::atan2(-E(0, 1), E(0, 0));
    }
    row += 3;
  }
  for (const PositionConstraintSpec& c : position_) {
    const Eigen::Vector3d p = poses[c.link] * c.point;
    errors->segment<3>(row) = c.region.linear().transpose() * (p - c.region.translation());
    row += 3;
  }
}

void PathConstraints::ErrorJacobian(const Eigen::VectorXd& q, Eigen::VectorXd* errors, Eigen::MatrixXd* jacobian) const {
  thread_local std::vector<Eigen::Isometry3d> poses;
  robot_->ForwardKinematics(q, &poses);
  ErrorsFromPoses(poses, errors);
  JacobianAt(q, poses, *errors, jacobian);
}

void PathConstraints::JacobianAt(const Eigen::VectorXd& q, const std::vector<Eigen::Isometry3d>& poses,
                                 const Eigen::VectorXd& errors, Eigen::MatrixXd* jacobian) const {
  jacobian->resize(num_errors(), robot_->num_dofs());
  int row = 0;
  for (const OrientationConstraintSpec& c : orientation_) {
    const Jacobian J = PointJacobian(*robot_, q, c.link, Eigen::Vector3d::Zero());
    const Eigen::Matrix3d Rt = c.orientation.toRotationMatrix().transpose();
    const Eigen::Vector3d e = errors.segment<3>(row);
    Eigen::Matrix3d map;  // error rate per angular velocity in the base frame
    if (c.parameterization == OrientationParameterization::kRotationVector) {
      // d log(E)/dt = J_l⁻¹(e)·ω_E, ω_E = R_tᵀ ω (E = R_tᵀ R turns with R_tᵀ ω on the left).
      const double theta = e.norm();
      const Eigen::Matrix3d K = Skew(e);
      const double k = theta < 1e-6 ? 1.0 / 12.0
                                     : 1.0 / (theta * theta) - (1.0 + std::cos(theta)) / (2.0 * theta * std::sin(theta));
      map = (Eigen::Matrix3d::Identity() - 0.5 * K + k * K * K) * Rt;
    } else {
      // Body angular velocity ω_b = Eᵀ R_tᵀ ω = Rᵀ ω; ẋ = (ω_bx cos z − ω_by sin z)/cos y,
      // ẏ = ω_bx sin z + ω_by cos z, ż = ω_bz − ẋ sin y.
      const Eigen::Matrix3d Rb = poses[static_cast<std::size_t>(c.link)].linear().transpose();
      const double sy = std::sin(e[1]), cy = std::cos(e[1]), sz = std::sin(e[2]), cz = std::cos(e[2]);
      Eigen::Matrix3d rates;
      rates << cz / cy, -sz / cy, 0.0,  //
          sz, cz, 0.0,                  //
          -sy * cz / cy, sy * sz / cy, 1.0;
      map = rates * Rb;
    }
    jacobian->middleRows<3>(row) = map * J.topRows<3>();
    row += 3;
  }
  for (const PositionConstraintSpec& c : position_) {
    const Jacobian J = PointJacobian(*robot_, q, c.link, c.point);
    jacobian->middleRows<3>(row) = c.region.linear().transpose() * J.bottomRows<3>();
    row += 3;
  }
}

Eigen::VectorXd PathConstraints::TightenedBounds(double shrink) const {
  Eigen::VectorXd bounds = shrink * tolerance_;
  for (int row = 0; row < 3 * static_cast<int>(orientation_.size()); ++row) {
    if (tolerance_[row] >= kPi) bounds[row] = kInf;
  }
  return bounds;
}

bool PathConstraints::Satisfied(const Eigen::VectorXd& q) const {
  if (empty()) return true;
  thread_local Eigen::VectorXd e;
  Errors(q, &e);
  return (e.cwiseAbs().array() <= tolerance_.array()).all();
}

double PathConstraints::WorstRatio(const Eigen::VectorXd& q) const {
  if (empty()) return 0.0;
  thread_local Eigen::VectorXd e;
  Errors(q, &e);
  return (e.cwiseAbs().array() / tolerance_.array().max(1e-9)).maxCoeff();
}

std::string PathConstraints::Violation(const Eigen::VectorXd& q, int* violated_link) const {
  if (empty()) return {};
  Eigen::VectorXd e;
  Errors(q, &e);
  for (int row = 0; row < num_errors(); ++row) {
    if (std::abs(e[row]) <= tolerance_[row]) continue;
    const std::size_t c = static_cast<std::size_t>(row / 3);
    const bool is_orientation = c < orientation_.size();
    const int link = is_orientation ? orientation_[c].link : position_[c - orientation_.size()].link;
    if (violated_link != nullptr) *violated_link = link;
    std::string text = field_ + (is_orientation ? ".orientation[" + std::to_string(c) + "] (link '"
                                                : ".position[" + std::to_string(c - orientation_.size()) + "] (link '") +
                       robot_->links()[link].name + "', ";
    if (is_orientation) {
      text += orientation_[c].parameterization == OrientationParameterization::kRotationVector ? "rotation vector"
                                                                                               : "XYZ Euler angles";
    } else {
      text += "point in the box frame";
    }
    const char* unit = is_orientation ? " rad" : " m";
    return text + "): " + AxisName(row % 3) + " = " + FormatNumber(e[row]) + unit + " exceeds the tolerance " +
           FormatNumber(tolerance_[row]) + unit;
  }
  return {};
}

double PathConstraints::RateFactor(std::size_t c) const {
  if (c >= orientation_.size()) return 1.0;
  const OrientationConstraintSpec& o = orientation_[c];
  if (o.parameterization == OrientationParameterization::kXyzEulerAngles) {
    // ẋ = (ω_x cos z − ω_y sin z)/cos y, ẏ = ω_x sin z + ω_y cos z, ż = ω_z − ẋ sin y (body ω):
    // each at most |ω|/cos y, and |y| <= y_tol while the constraint holds.
    return 1.0 / std::cos(o.tolerance[1]);
  }
  // d log(E)/dt = J⁻¹(θ)·ω, a normal matrix of norm (θ/2)/sin(θ/2), increasing in θ; θ = |log E|
  // <= |tolerance| while the constraint holds (and θ <= π).
  const double theta = std::min(kPi, o.tolerance.norm());
  return theta < 1e-6 ? 1.0 : (0.5 * theta) / std::sin(0.5 * theta);
}

double PathConstraints::SafeRadius(const Eigen::VectorXd& q, const Eigen::VectorXd& rates) const {
  thread_local Eigen::VectorXd e;
  Errors(q, &e);
  double radius = kInf;
  for (int c = 0; c < static_cast<int>(rates.size()); ++c) {
    double margin = kInf;
    for (int a = 0; a < 3; ++a) margin = std::min(margin, tolerance_[3 * c + a] - std::abs(e[3 * c + a]));
    if (!(margin >= 0)) return -1.0;  // violated (or not finite)
    radius = std::min(radius, rates[c] > 0 ? margin / rates[c] : kInf);
  }
  return radius;
}

bool PathConstraints::IsCurveSatisfied(const Curve& curve, const Eigen::VectorXd& speed_bound, std::uint64_t* states) const {
  if (empty()) return true;
  if (speed_bound.size() != robot_->num_dofs()) {
    ThrowInvalid("IsCurveSatisfied: speed_bound has " + std::to_string(speed_bound.size()) + " values, robot '" +
                 robot_->name() + "' has " + std::to_string(robot_->num_dofs()) + " joints");
  }
  Eigen::VectorXd rates(static_cast<Eigen::Index>(levers_.size()));
  for (std::size_t c = 0; c < levers_.size(); ++c) rates[static_cast<Eigen::Index>(c)] = RateFactor(c) * levers_[c].dot(speed_bound);
  if (!rates.allFinite()) return false;
  thread_local Eigen::VectorXd q;
  int evaluated = 0;
  const auto radius_at = [&](double s) {
    ++evaluated;
    curve(s, &q);
    return q.allFinite() ? SafeRadius(q, rates) : -1.0;
  };
  struct Interval {
    double s0, r0, s1, r1;
  };
  std::vector<Interval> stack;
  const double r0 = radius_at(0.0);
  const double r1 = r0 >= 0 ? radius_at(1.0) : -1.0;
  bool ok = r0 >= 0 && r1 >= 0;
  if (ok) stack.push_back({0.0, r0, 1.0, r1});
  while (ok && !stack.empty()) {
    const Interval iv = stack.back();
    stack.pop_back();
    if (iv.r0 + iv.r1 >= iv.s1 - iv.s0) continue;  // no state between can reach a bound
    if (iv.s1 - iv.s0 < kMinInterval || evaluated >= kMaxCertifyStates) {
      ok = false;
      break;
    }
    const double mid = 0.5 * (iv.s0 + iv.s1);
    const double rm = radius_at(mid);
    if (rm < 0) {
      ok = false;
      break;
    }
    stack.push_back({mid, rm, iv.s1, iv.r1});
    stack.push_back({iv.s0, iv.r0, mid, rm});  // earlier half first
  }
  if (states != nullptr) *states += static_cast<std::uint64_t>(evaluated);
  return ok;
}

bool PathConstraints::IsSegmentSatisfied(const Eigen::VectorXd& a, const Eigen::VectorXd& b, std::uint64_t* states) const {
  if (empty()) return true;
  const Eigen::VectorXd d = b - a;
  return IsCurveSatisfied([&a, &d](double s, Eigen::VectorXd* q) { *q = a + s * d; }, d.cwiseAbs(), states);
}

bool PathConstraints::Project(Eigen::VectorXd* q, double shrink, int max_iterations) const {
  if (empty()) return true;
  const int m = num_errors();
  const int n = robot_->num_dofs();
  const Eigen::VectorXd bound = TightenedBounds(shrink);
  Eigen::VectorXd e, excess(m);
  Eigen::MatrixXd J;
  thread_local std::vector<Eigen::Isometry3d> poses;
  constexpr double kDamping = 1e-6;  // λ² of the damped least squares
  double previous = kInf;
  int stalled = 0;
  for (int it = 0; it <= max_iterations; ++it) {
    robot_->ForwardKinematics(*q, &poses);
    ErrorsFromPoses(poses, &e);
    if (!e.allFinite()) return false;
    double total = 0.0;
    for (int r = 0; r < m; ++r) {
      const double over = std::abs(e[r]) - bound[r];
      excess[r] = over > 0 ? std::copysign(over, e[r]) : 0.0;
      if (over > 1e-9) total += over;
    }
    if (total == 0.0) return true;
    // Stalled (at a joint limit, or where the errors cannot all shrink): give up after three
    // iterations in a row that do not cut the excess by 1 %.
    stalled = total > 0.99 * previous ? stalled + 1 : 0;
    if (it == max_iterations || stalled == 3) break;
    previous = total;
    JacobianAt(*q, poses, e, &J);
    for (int r = 0; r < m; ++r) {
      if (excess[r] == 0.0) J.row(r).setZero();  // inside its bound: not pulled on
    }
    // A joint at a limit that the step would push further out is taken out of the step (its
    // column zeroed) and the step solved again, so the other joints do the work.
    const Eigen::VectorXd& lo = robot_->lower_limits();
    const Eigen::VectorXd& hi = robot_->upper_limits();
    Eigen::VectorXd next;
    for (int pass = 0; pass < n; ++pass) {
      const Eigen::MatrixXd A = J * J.transpose() + kDamping * Eigen::MatrixXd::Identity(m, m);
      next = *q - J.transpose() * A.ldlt().solve(excess);
      bool held = false;
      for (int i = 0; i < n; ++i) {
        const bool out = (next[i] < lo[i] && (*q)[i] <= lo[i]) || (next[i] > hi[i] && (*q)[i] >= hi[i]);
        if (out && !J.col(i).isZero()) {
          J.col(i).setZero();
          held = true;
        }
      }
      if (!held) break;
    }
    *q = next.cwiseMax(lo).cwiseMin(hi);
  }
  return false;
}

}  // namespace chasles
