#include "piece_certification.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

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

CollisionChecker::Curve SegmentCurve(const Eigen::VectorXd& a, const Eigen::VectorXd& b, const RobotModel& robot) {
  const RobotModel* r = &robot;
  return [a, delta = Eigen::VectorXd(b - a), r](double s, Eigen::VectorXd* q) {
    const Eigen::VectorXd& lower = r->lower_limits();
    const Eigen::VectorXd& upper = r->upper_limits();
    q->resize(a.size());
    for (Eigen::Index i = 0; i < a.size(); ++i) (*q)[i] = std::min(upper[i], std::max(lower[i], a[i] + s * delta[i]));
  };
}

bool LineSegmentOf(const TimedTrajectory::Piece& piece, Eigen::VectorXd* a, Eigen::VectorXd* b) {
  const Eigen::MatrixXd& c = piece.coefficients;
  const Eigen::Index m = c.cols();
  const double length = piece.duration;
  if (c.rows() == 0 || m == 0 || !(length >= 0.0) || !std::isfinite(length) || !c.allFinite()) return false;
  // The direction: the largest column after the first (none, or all zero: the piece stands still).
  Eigen::Index widest = 0;
  double norm = 0.0;
  for (Eigen::Index k = 1; k < m; ++k) {
    const double v = c.col(k).cwiseAbs().maxCoeff();
    if (v > norm) {
      norm = v;
      widest = k;
    }
  }
  if (widest == 0) {
    *a = c.col(0);
    *b = c.col(0);
    return true;
  }
  const Eigen::VectorXd d = c.col(widest);
  const double dd = d.squaredNorm();
  std::vector<double> sigma(static_cast<std::size_t>(m), 0.0);  // σ(τ), σ(0) = 0
  double deviation = 0.0;  // bound on |q(τ) − c₀ − d·σ(τ)|∞ over the piece
  double power = 1.0;      // length^k
  for (Eigen::Index k = 1; k < m; ++k) {
    power *= length;
    const double s = c.col(k).dot(d) / dd;
    sigma[static_cast<std::size_t>(k)] = s;
    deviation += (c.col(k) - s * d).cwiseAbs().maxCoeff() * power;
  }
  if (!(deviation <= kLineTolerance)) return false;
  double lo = 0.0, hi = 0.0;
  poly::Range(sigma.data(), static_cast<int>(m), length, &lo, &hi);
  *a = c.col(0) + lo * d;
  *b = c.col(0) + hi * d;
  return a->allFinite() && b->allFinite();
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

}  // namespace chasles::detail
