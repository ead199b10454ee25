#pragma once
/// \file
/// Path constraints (MoveIt's path_constraints): a link's orientation kept within per-axis
/// tolerances of a target, a point of a link kept inside a box, at every state of a path. Each
/// constraint is three signed errors e_a with |e_a| <= tolerance_a. Besides evaluating them this
/// certifies them along a continuous motion (bounds on how fast the errors can change) and
/// projects a configuration onto them (for samplers).

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "chasles/robot/robot_model.h"

namespace chasles {

/// How an orientation error E = R_targetᵀ·R_link (a rotation in the target's frame) becomes
/// three numbers, as MoveIt's OrientationConstraint::parameterization.
enum class OrientationParameterization {
  /// log(E) = θ·u, the components of the rotation vector. Defined everywhere.
  kRotationVector,
  /// (x, y, z) with E = Rx(x)·Ry(y)·Rz(z) (intrinsic), y in [−π/2, π/2]. A z tolerance of π
  /// leaves the link free to turn about the target's z axis: x and y alone bound how far the
  /// link's z axis tilts (a glass kept upright).
  kXyzEulerAngles,
};

struct OrientationConstraintSpec {
  int link = -1;  ///< index into the robot's links
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  ///< target, in the base frame
  Eigen::Vector3d tolerance = Eigen::Vector3d::Constant(0.1);       ///< [rad] per axis, > 0
  OrientationParameterization parameterization = OrientationParameterization::kRotationVector;
};

struct PositionConstraintSpec {
  int link = -1;                                        ///< index into the robot's links
  Eigen::Vector3d point = Eigen::Vector3d::Zero();      ///< on the link, in its frame [m]
  Eigen::Isometry3d region = Eigen::Isometry3d::Identity();  ///< the box's centre and axes in the base frame
  Eigen::Vector3d half_extents = Eigen::Vector3d::Zero();    ///< [m] per box axis, >= 0 (0: a plane or a line)
};

class PathConstraints {
 public:
  /// A joint-space curve q(s), s ∈ [0, 1] (as CollisionChecker::Curve).
  using Curve = std::function<void(double s, Eigen::VectorXd* q)>;

  /// `field` names the constraints in errors ("path_constraints" → `path_constraints.orientation[1]`).
  /// \throws Error(kInvalidArgument) naming the field, index and rule: a link out of range, a
  ///         quaternion that is not finite or of norm 0 (normalised otherwise), a tolerance not
  ///         in (0, π] (x and z) — with kXyzEulerAngles y in (0, π/2) as the x and z angles are
  ///         undefined at |y| = π/2 —, a point, region or half extent not finite (or < 0).
  PathConstraints(std::shared_ptr<const RobotModel> robot, std::vector<OrientationConstraintSpec> orientation,
                  std::vector<PositionConstraintSpec> position, std::string field = "path_constraints");

  const RobotModel& robot() const { return *robot_; }
  const std::vector<OrientationConstraintSpec>& orientation() const { return orientation_; }
  const std::vector<PositionConstraintSpec>& position() const { return position_; }
  bool empty() const { return orientation_.empty() && position_.empty(); }
  /// 3 per constraint, orientation constraints first.
  int num_errors() const { return 3 * static_cast<int>(orientation_.size() + position_.size()); }
  /// The tolerances in the order of Errors() ([rad] then [m]).
  const Eigen::VectorXd& tolerances() const { return tolerance_; }

  /// The tolerances tightened to shrink·tolerance for planning, except that an orientation axis
  /// whose tolerance is π stays unbounded (+inf): no angle exceeds π, and a tightened bound would
  /// cut that axis' circle — a link free to turn about the vertical could no longer turn all the way.
  Eigen::VectorXd TightenedBounds(double shrink) const;
  /// The signed errors at q, in the order of tolerances(): rotation-vector components or Euler
  /// angles [rad] of R_targetᵀ·R_link; the point's coordinates in the box frame [m].
  /// Precondition: q.size() == num_dofs() (no allocation once *errors has its size).
  void Errors(const Eigen::VectorXd& q, Eigen::VectorXd* errors) const;
  /// The errors at q (as Errors) and their Jacobian d errors / dq (num_errors() × num_dofs()),
  /// from the link's geometric Jacobian: a rotation vector e changes by J_l⁻¹(e)·R_targetᵀ·ω, the
  /// Euler angles by the inverse of their rate map (finite while |y| < π/2), the point in the box
  /// frame by R_boxᵀ·ṗ.
  void ErrorJacobian(const Eigen::VectorXd& q, Eigen::VectorXd* errors, Eigen::MatrixXd* jacobian) const;
  /// Every |error| <= its tolerance.
  bool Satisfied(const Eigen::VectorXd& q) const;
  /// max_a |e_a| / tolerance_a over all errors (<= 1: satisfied); 0 without constraints. For
  /// a box with a zero half extent the ratio uses 1e-9 m.
  double WorstRatio(const Eigen::VectorXd& q) const;
  /// Empty when satisfied; else the first violated error, e.g. `path_constraints.orientation[0]
  /// (link 'hand', rotation vector): x = 0.31 rad exceeds the tolerance 0.1 rad`; *link (optional)
  /// is then the constrained link.
  std::string Violation(const Eigen::VectorXd& q, int* link = nullptr) const;

  /// Certified: true only when every state q(s), s ∈ [0, 1], satisfies the constraints.
  /// `speed_bound[i]` bounds |dq_i/ds| over [0, 1] (a straight segment a→b: |b − a|). Each error
  /// changes at most as fast as the link turns or the point moves (the link's angular speed is at
  /// most Σ AngularLevers·speed, the point's speed Σ PointLevers·speed; a rotation-vector
  /// component at most (θ/2)/sin(θ/2) times the angular speed for θ up to the tolerance's norm, an
  /// Euler angle 1/cos(y_tol) times), so from a state whose least margin (tolerance − |error|,
  /// over rate) is r no state within r in s can violate them; intervals whose end margins do not
  /// cover them are bisected. Conservative: false after 20000 states or an interval below 1e-9.
  /// `*states` (optional) adds the states evaluated.
  bool IsCurveSatisfied(const Curve& curve, const Eigen::VectorXd& speed_bound, std::uint64_t* states = nullptr) const;
  /// IsCurveSatisfied of the straight segment a → b.
  bool IsSegmentSatisfied(const Eigen::VectorXd& a, const Eigen::VectorXd& b, std::uint64_t* states = nullptr) const;

  /// Moves *q onto the constraints tightened to TightenedBounds(shrink) (shrink in (0, 1]) by damped
  /// Gauss–Newton steps on the excess errors (ErrorJacobian), kept within the joint limits.
  /// True when every |e_a| <= its tightened bound + 1e-9 within max_iterations; false early
  /// after three iterations in a row that do not reduce the excess by 1 %.
  bool Project(Eigen::VectorXd* q, double shrink, int max_iterations = 30) const;

 private:
  /// Errors (as Errors) from the robot's link poses at q (RobotModel::ForwardKinematics).
  void ErrorsFromPoses(const std::vector<Eigen::Isometry3d>& poses, Eigen::VectorXd* errors) const;
  /// ErrorJacobian's Jacobian at q, given q's link poses and errors.
  void JacobianAt(const Eigen::VectorXd& q, const std::vector<Eigen::Isometry3d>& poses, const Eigen::VectorXd& errors,
                  Eigen::MatrixXd* jacobian) const;
  /// Per constraint (orientation then position): the bound on each error's rate per unit of
  /// Σ levers·speed (rotation vector: (θ/2)/sin(θ/2), Euler: 1/cos(y_tol), position: 1).
  double RateFactor(std::size_t c) const;
  /// Least margin over rate at q, in units of s for the per-constraint speeds `rates`
  /// (negative when violated; +inf when no constraint can change).
  double SafeRadius(const Eigen::VectorXd& q, const Eigen::VectorXd& rates) const;

  std::shared_ptr<const RobotModel> robot_;
  std::vector<OrientationConstraintSpec> orientation_;
  std::vector<PositionConstraintSpec> position_;
  std::string field_;
  Eigen::VectorXd tolerance_;
  /// Per constraint, per dof: the levers summed over the moving joints the dof drives.
  std::vector<Eigen::VectorXd> levers_;
};

}  // namespace chasles
