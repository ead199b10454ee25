#pragma once
/// \file
/// Internal to optimizers/: certified collision checks of timed-trajectory pieces — conservative
/// advancement over each polynomial (CollisionChecker::IsCurveCertified) with an exact per-joint
/// speed bound.
/// Used by VerifyTrajectory, MeasureTrajectory and the time-optimal blend check.

#include <vector>

#include <Eigen/Core>

#include "chasles/collision/collision_checker.h"
#include "chasles/optimizers/timed_trajectory.h"

namespace chasles::detail {

/// A local-time interval [begin, end] of one piece [s].
struct PieceSpan {
  double begin = 0.0;
  double end = 0.0;
};

/// Joint travel [rad] above which a piece is cut into spans for certification: the speed bound
/// of a span is its largest speed, so shorter spans of an accelerating piece get tighter bounds.
inline constexpr double kCertifiedSpanTravel = 0.25;

/// [0, duration] cut into equal spans of at most `max_travel` joint travel (by the piece's
/// MaxJointTravel; at least one span, at most 4096).
std::vector<PieceSpan> SplitPiece(const TimedTrajectory::Piece& piece, double max_travel);

/// Per joint, (end − begin)·max |q̇ᵢ| over the span, exactly (extrema of the polynomial), with
/// a relative margin of 1e-9 for rounding: a bound on |dqᵢ/ds| for s ∈ [0, 1].
Eigen::VectorXd SpanSpeedBound(const TimedTrajectory::Piece& piece, const PieceSpan& span);

/// The piece's position at local time tau [s] from its own polynomial (tau = 0 gives its
/// constant coefficients exactly), clamped into the robot's joint limits (NaN stays NaN).
void ClampedPosition(const TimedTrajectory::Piece& piece, double tau, const RobotModel& robot, Eigen::VectorXd* q);

/// The span as a curve q(s) = piece position at begin + s·(end − begin), clamped into the
/// robot's joint limits (as the returned samples are; clamping does not increase any speed).
CollisionChecker::Curve SpanCurve(const TimedTrajectory::Piece& piece, const PieceSpan& span,
                                  const RobotModel& robot);

/// The straight segment q(s) = a + s·(b − a), s ∈ [0, 1], clamped into the robot's joint limits
/// (as SpanCurve; clamping does not increase any speed, so |b − a| bounds |dq/ds|).
CollisionChecker::Curve SegmentCurve(const Eigen::VectorXd& a, const Eigen::VectorXd& b, const RobotModel& robot);

/// Largest deviation [rad] from its line that LineSegmentOf accepts in a piece: rounding of
/// the coefficients (~1e-16 rad), far below any motion of the robot's spheres that matters.
inline constexpr double kLineTolerance = 1e-12;

/// When the piece moves along one line — q(τ) = c₀ + d·σ(τ), every coefficient column after the
/// first a multiple of one direction d, up to at most kLineTolerance rad anywhere on the piece —
/// the joint-space segment it sweeps: *a = c₀ + d·min σ, *b = c₀ + d·max σ over [0, duration]
/// (exact extrema of the polynomial σ), and true. A time-optimal parameterization's pieces along
/// the path's segments are such; so is a piece that stands still. False for any other piece.
/// Collisions depend only on the configurations a piece visits, so certifying the straight
/// segment a → b certifies the piece, with a speed bound |b − a| that no time profile loosens.
bool LineSegmentOf(const TimedTrajectory::Piece& piece, Eigen::VectorXd* a, Eigen::VectorXd* b);

/// Certifies the span with IsCurveCertified; a span the checker does not certify is bisected
/// and its halves certified in time order, down to `max_depth` levels (this gets past the
/// advancement's state cap and loose bounds of long spans). Returns true when every part is
/// certified; otherwise false and *failed = the first part that was not, at the deepest level.
/// Only meaningful when checker.certifies_motion() (otherwise IsCurveCertified is discrete).
bool CertifySpan(const TimedTrajectory::Piece& piece, const PieceSpan& span, const CollisionChecker& checker,
                 int max_depth, CheckCounters* counters, PieceSpan* failed);

}  // namespace chasles::detail
