#include "piece_certification.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace chasles::detail {

std::vector<PieceSpan> SplitPiece(const TimedTrajectory::Piece& piece, double max_travel) {
  constexpr double kMaxSpans = 4096.0;
  const double travel = piece.MaxJointTravel();
  const double count = std::ceil(travel / max_travel);
  const int n = std::max(1, static_cast<int>(std::min(kMaxSpans, std::isfinite(count) ? count : kMaxSpans)));
  std::vector<PieceSpan> out(n);
  for (int i = 0; i < n; ++i) {
    out[i].begin = i == 0 ? 0.0 : piece.duration * i / n;
    out[i].end = i + 1 == n ? piece.duration : piece.duration * (i + 1) / n;
  }
  return out;
}

Eigen::VectorXd SpanSpeedBound(const TimedTrajectory::Piece& piece, const PieceSpan& span) {
  const Eigen::Index n = piece.coefficients.rows();
  const int size = static_cast<int>(piece.coefficients.cols());
  const double length = span.end - span.begin;
  Eigen::VectorXd out(n);
  std::vector<double> row(size), shifted(size);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (int k = 0; k < size; ++k) row[k] = piece.coefficients(i, k);
    // Taylor coefficients at `begin`: p(begin + x) = Σ p⁽ᵏ⁾(begin)/k! xᵏ.
    double factorial = 1.0;
    for (int k = 0; k < size; ++k) {
      if (k > 0) factorial *= k;
      shifted[k] = poly::EvalDerivative(row.data(), size, k, span.begin) / factorial;
    }
    out[i] = length * poly::MaxAbsDerivative(shifted.data(), size, 1, length) * (1.0 + 1e-9);
  }
  return out;
}

void ClampedPosition(const TimedTrajectory::Piece& piece, double tau, const RobotModel& robot, Eigen::VectorXd* q) {
  const Eigen::MatrixXd& c = piece.coefficients;
  const Eigen::VectorXd& lower = robot.lower_limits();
  const Eigen::VectorXd& upper = robot.upper_limits();
  const Eigen::Index n = c.rows();
  q->resize(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    double value = 0.0;
    for (Eigen::Index k = c.cols() - 1; k >= 0; --k) value = value * tau + c(i, k);
    (*q)[i] = std::isnan(value) ? value : std::min(upper[i], std::max(lower[i], value));  // NaN stays NaN
  }
}

CollisionChecker::Curve SpanCurve(const TimedTrajectory::Piece& piece, const PieceSpan& span,
                                  const RobotModel& robot) {
  const TimedTrajectory::Piece* p = &piece;
  const RobotModel* r = &robot;
  const double begin = span.begin, end = span.end;
  return [p, r, begin, end](double s, Eigen::VectorXd* q) {
    ClampedPosition(*p, s >= 1.0 ? end : begin + s * (end - begin), *r, q);
  };
}

bool CertifySpan(const TimedTrajectory::Piece& piece, const PieceSpan& span, const CollisionChecker& checker,
                 int max_depth, CheckCounters* counters, PieceSpan* failed) {
  if (checker.IsCurveCertified(SpanCurve(piece, span, checker.robot()), SpanSpeedBound(piece, span), counters)) {
    return true;
  }
  const double mid = 0.5 * (span.begin + span.end);
  if (max_depth <= 0 || !(mid > span.begin && mid < span.end)) {
    *failed = span;
    return false;
  }
  return CertifySpan(piece, {span.begin, mid}, checker, max_depth - 1, counters, failed) &&
         CertifySpan(piece, {mid, span.end}, checker, max_depth - 1, counters, failed);
}

double SpanClearanceLipschitz(const TimedTrajectory::Piece& piece, const PieceSpan& span,
                              const CollisionChecker& checker) {
  if (!checker.certifies_motion()) return std::numeric_limits<double>::infinity();
  const Eigen::VectorXd speed = SpanSpeedBound(piece, span);
  const std::vector<double> sweep = checker.SweepBounds(Eigen::VectorXd::Zero(speed.size()), speed);
  double out = 0.0;
  for (double d : sweep) out = std::max(out, d);
  return out;
}

}  // namespace chasles::detail
