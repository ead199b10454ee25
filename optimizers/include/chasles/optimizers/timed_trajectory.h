#pragma once
/// \file
/// Paths and timed trajectories in joint space. SI units and radians.

#include <string>
#include <vector>

#include <Eigen/Core>

#include "chasles/robot/joint_path.h"

namespace chasles {

/// One sample of a timed trajectory.
struct TrajectorySample {
  double t = 0.0;          ///< [s] from the start
  Eigen::VectorXd q;       ///< positions [rad] / [m]
  Eigen::VectorXd qd;      ///< velocities [rad/s] / [m/s]
  Eigen::VectorXd qdd;     ///< accelerations [rad/s²] / [m/s²]
  Eigen::VectorXd jerk;    ///< jerks [rad/s³] / [m/s³]
  Eigen::VectorXd effort;  ///< joint torques [N·m] / forces [N]; empty unless computed (pipeline)
};

/// A trajectory that is exact between samples: consecutive pieces, each a polynomial in time
/// per joint. Every optimiser returns this form: the time-optimal parameterisation gives
/// quadratic pieces (constant acceleration), collocation cubic pieces (constant jerk), the
/// B-spline smoother cubic or quintic pieces. Limits can therefore be checked exactly, at the
/// extrema of each polynomial, rather than at samples.
class TimedTrajectory {
 public:
  /// q(t0 + τ) = Σₖ coefficients.col(k) τᵏ for τ ∈ [0, duration].
  struct Piece {
    double t0 = 0.0;                ///< start time [s]
    double duration = 0.0;          ///< [s], >= 0
    Eigen::MatrixXd coefficients;   ///< num_dofs × (degree + 1), lowest power first
    int degree() const { return static_cast<int>(coefficients.cols()) - 1; }
    /// The `order`-th time derivative of joint `joint` at local time tau (this piece's own
    /// polynomial, also at its ends).
    double Derivative(int joint, int order, double tau) const;
    /// q, q̇, q̈ and jerk at local time tau from this piece's polynomials (t = t0 + tau); τ = 0
    /// gives the constant coefficients bit-exactly.
    TrajectorySample State(double tau) const;
    /// maxᵢ max_τ |q̇ᵢ(τ)| · duration: a bound on how far any joint moves over the piece [rad].
    double MaxJointTravel() const;
  };

  TimedTrajectory() = default;
  /// Pieces in time order with t0 = the previous piece's end; `end_position` (optional) is the
  /// exact final configuration, returned at t >= duration() instead of the last polynomial's
  /// value there (which carries rounding). Only the shapes are checked here (same rows, at
  /// least one column, non-empty end_position of the same size); VerifyTrajectory checks
  /// continuity and finiteness.
  /// \throws Error(kInvalidArgument) on mismatched sizes.
  explicit TimedTrajectory(std::vector<Piece> pieces, Eigen::VectorXd end_position = {});

  const std::vector<Piece>& pieces() const { return pieces_; }
  double duration() const;
  bool empty() const { return pieces_.empty(); }
  int num_dofs() const { return pieces_.empty() ? 0 : static_cast<int>(pieces_.front().coefficients.rows()); }
  /// Highest polynomial degree over the pieces (0 when empty).
  int degree() const;

  /// Exact state at time t [s], clamped to [0, duration()] (NaN counts as 0). At a piece
  /// boundary strictly inside, the piece that STARTS at t is used (right limit): q and q̇ are
  /// continuous there, q̈ and the jerk may jump. t <= 0 gives the first piece's start (its
  /// constant coefficient, bit-exactly); t >= duration() gives the end state with q =
  /// end_position when one was given.
  /// \throws Error(kFailedPrecondition) on an empty trajectory.
  TrajectorySample Evaluate(double t) const;
  /// Samples at t = 0, period, 2·period, … strictly before duration() (a multiple of the
  /// period within 1e-9·period of the end is skipped), then at duration() exactly. A
  /// zero-duration trajectory gives one sample; an empty one gives none.
  /// \throws Error(kInvalidArgument) when period is not finite and > 0 or would give more
  ///         than 1e8 samples.
  std::vector<TrajectorySample> Sample(double period) const;
  /// The configuration at every piece boundary: the start, each piece's end, with duplicates
  /// (consecutive equal configurations) kept.
  JointPath Waypoints() const;

  /// A new trajectory that runs this one `factor` times slower: t' = factor·t, so velocities
  /// scale by 1/factor, accelerations by 1/factor², jerks by 1/factor³. \throws kInvalidArgument
  /// unless factor is finite and > 0.
  TimedTrajectory TimeScaled(double factor) const;

 private:
  std::vector<Piece> pieces_;
  Eigen::VectorXd end_position_;
};

/// Standing still at `q` for `duration` [s] (>= 0): one constant piece from t = 0.
/// \throws Error(kInvalidArgument) when q is empty or not finite, or duration is not finite and >= 0.
TimedTrajectory HoldTrajectory(const Eigen::VectorXd& q, double duration);

/// The parts one after another on one time line (each part's pieces shifted to start when the
/// previous part ends); the end position is the last part's. Empty parts are skipped.
/// Continuity between parts is the caller's (VerifyTrajectory checks it).
/// \throws Error(kInvalidArgument) when the parts have different numbers of joints.
TimedTrajectory ConcatenateTrajectories(const std::vector<TimedTrajectory>& parts);

/// The same motion starting `delay` [s] (>= 0) later, standing at its start before.
TimedTrajectory DelayedTrajectory(const TimedTrajectory& trajectory, double delay);

/// Joints [first, first + count) of every piece (and of the end position).
/// \throws Error(kInvalidArgument) when the range is outside the trajectory's joints.
TimedTrajectory TrajectoryRows(const TimedTrajectory& trajectory, int first, int count);

/// Appends a piece that moves along the line q = origin + s·direction with the scalar profile
/// s(τ) = s0 + s1·τ + s2·τ² + s3·τ³ (unused terms 0) for τ ∈ [0, duration], starting at time t0.
TimedTrajectory::Piece LinePiece(double t0, double duration, const Eigen::VectorXd& origin,
                                 const Eigen::VectorXd& direction, double s0, double s1, double s2,
                                 double s3 = 0.0);

/// Polynomial helpers on coefficient vectors, lowest power first.
namespace poly {
/// p(x) by Horner's rule; coefficient i is c[i·stride] (stride > 1: a row of a column-major
/// matrix, read in place).
double Eval(const double* c, int size, double x, int stride = 1);
/// The k-th derivative's value at x (coefficients as for Eval).
double EvalDerivative(const double* c, int size, int k, double x, int stride = 1);
/// max |p^(k)(x)| over x ∈ [0, length], exact up to the root finder (bisection to ~1e-15
/// relative): the extremes are at the interval's ends or at real roots of p^(k+1).
/// `where` (optional) receives an x at which the maximum is attained.
double MaxAbsDerivative(const double* c, int size, int k, double length, double* where = nullptr);
/// min and max of p over [0, length].
void Range(const double* c, int size, double length, double* lo, double* hi);
}  // namespace poly

}  // namespace chasles
