#include "chasles/optimizers/timed_trajectory.h"

#include <algorithm>
#include <cmath>

#include "chasles/robot/error.h"

namespace chasles {
namespace poly {
namespace {

/// Coefficients of the k-th derivative.
std::vector<double> Derivative(const double* c, int size, int k) {
  std::vector<double> out;
  for (int i = k; i < size; ++i) {
    double factor = 1.0;
    for (int j = 0; j < k; ++j) factor *= static_cast<double>(i - j);
    out.push_back(factor * c[i]);
  }
  return out;
}

/// Real roots of p in the open interval (lo, hi), sorted. The polynomial is split into
/// monotone pieces at the roots of p' (found the same way), and each piece with a sign change
/// holds exactly one root, found by bisection.
void Roots(const std::vector<double>& p, double lo, double hi, std::vector<double>* roots) {
  int size = static_cast<int>(p.size());
  while (size > 0 && p[size - 1] == 0.0) --size;
  if (size <= 1) return;  // constant: no isolated roots
  if (size == 2) {
    const double x = -p[0] / p[1];
    if (x > lo && x < hi) roots->push_back(x);
    return;
  }
  const std::vector<double> dp = Derivative(p.data(), size, 1);
  std::vector<double> breaks{lo};
  Roots(dp, lo, hi, &breaks);
  breaks.push_back(hi);
  for (std::size_t i = 0; i + 1 < breaks.size(); ++i) {
    double a = breaks[i], b = breaks[i + 1];
    double fa = Eval(p.data(), size, a), fb = Eval(p.data(), size, b);
    if (fa == 0.0) {
      if (a > lo && a < hi && (roots->empty() || roots->back() != a)) roots->push_back(a);
      continue;
    }
    if (fb == 0.0 || (fa < 0.0) == (fb < 0.0)) continue;  // a root at b is found from the right
    for (int it = 0; it < 200 && b - a > 1e-15 * std::max(1.0, std::abs(a)); ++it) {
      const double m = 0.5 * (a + b);
      const double fm = Eval(p.data(), size, m);
      if (fm == 0.0) { a = b = m; break; }
      if ((fm < 0.0) == (fa < 0.0)) { a = m; fa = fm; } else { b = m; }
    }
    roots->push_back(0.5 * (a + b));
  }
}

}  // namespace

double Eval(const double* c, int size, double x, int stride) {
  double value = 0.0;
  for (int i = size - 1; i >= 0; --i) value = value * x + c[i * stride];
  return value;
}

double EvalDerivative(const double* c, int size, int k, double x, int stride) {
  double value = 0.0;
  for (int i = size - 1; i >= k; --i) {
    double factor = 1.0;
    for (int j = 0; j < k; ++j) factor *= static_cast<double>(i - j);
    value = value * x + factor * c[i * stride];
  }
  return value;
}

double MaxAbsDerivative(const double* c, int size, int k, double length, double* where) {
  const std::vector<double> d = Derivative(c, size, k);
  double at = 0.0, best = 0.0;
  if (!d.empty()) {
    const int n = static_cast<int>(d.size());
    best = std::abs(d[0]);
    const double end = std::abs(Eval(d.data(), n, length));
    if (end > best) {
      best = end;
      at = length;
    }
    if (n >= 3 && length > 0.0) {
      std::vector<double> critical;
      Roots(Derivative(d.data(), n, 1), 0.0, length, &critical);
      for (double x : critical) {
        const double value = std::abs(Eval(d.data(), n, x));
        if (value > best) {
          best = value;
          at = x;
        }
      }
    }
  }
  if (where != nullptr) *where = at;
  return best;
}

void Range(const double* c, int size, double length, double* lo, double* hi) {
  *lo = *hi = size > 0 ? c[0] : 0.0;
  if (size == 0) return;
  const double end = Eval(c, size, length);
  *lo = std::min(*lo, end);
  *hi = std::max(*hi, end);
  if (size >= 3 && length > 0.0) {
    std::vector<double> critical;
    Roots(Derivative(c, size, 1), 0.0, length, &critical);
    for (double x : critical) {
      const double v = Eval(c, size, x);
      *lo = std::min(*lo, v);
      *hi = std::max(*hi, v);
    }
  }
}

}  // namespace poly

TimedTrajectory::TimedTrajectory(std::vector<Piece> pieces, Eigen::VectorXd end_position)
    : pieces_(std::move(pieces)), end_position_(std::move(end_position)) {
  if (pieces_.empty()) {
    if (end_position_.size() != 0) ThrowInvalid("a trajectory with no pieces cannot have an end position");
    return;
  }
  const Eigen::Index n = pieces_.front().coefficients.rows();
  for (std::size_t k = 0; k < pieces_.size(); ++k) {
    const Piece& piece = pieces_[k];
    if (piece.coefficients.rows() != n || piece.coefficients.cols() < 1) {
      ThrowInvalid("trajectory piece " + std::to_string(k) + " has a " + std::to_string(piece.coefficients.rows()) +
                   "×" + std::to_string(piece.coefficients.cols()) + " coefficient matrix, expected " +
                   std::to_string(n) + " rows and at least 1 column");
    }
  }
  if (end_position_.size() != 0 && end_position_.size() != n) {
    ThrowInvalid("trajectory end position has " + std::to_string(end_position_.size()) + " values, pieces have " +
                 std::to_string(n));
  }
}

double TimedTrajectory::duration() const {
  if (pieces_.empty()) return 0.0;
  return pieces_.back().t0 + pieces_.back().duration;
}

int TimedTrajectory::degree() const {
  int out = 0;
  for (const Piece& piece : pieces_) out = std::max(out, piece.degree());
  return out;
}

double TimedTrajectory::Piece::Derivative(int joint, int order, double tau) const {
  return poly::EvalDerivative(coefficients.data() + joint, static_cast<int>(coefficients.cols()), order, tau,
                              static_cast<int>(coefficients.rows()));
}

TrajectorySample TimedTrajectory::Piece::State(double tau) const {
  const Eigen::Index n = coefficients.rows();
  const int size = static_cast<int>(coefficients.cols());
  TrajectorySample out;
  out.t = t0 + tau;
  out.q.resize(n);
  out.qd.resize(n);
  out.qdd.resize(n);
  out.jerk.resize(n);
  // Each row in place: in the column-major matrix its coefficients are n apart.
  const double* const c = coefficients.data();
  const int stride = static_cast<int>(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double* row = c + i;
    out.q[i] = tau == 0.0 ? row[0] : poly::Eval(row, size, tau, stride);
    out.qd[i] = poly::EvalDerivative(row, size, 1, tau, stride);
    out.qdd[i] = poly::EvalDerivative(row, size, 2, tau, stride);
    out.jerk[i] = poly::EvalDerivative(row, size, 3, tau, stride);
  }
  return out;
}

double TimedTrajectory::Piece::MaxJointTravel() const {
  double travel = 0.0;
  for (Eigen::Index i = 0; i < coefficients.rows(); ++i) {
    const Eigen::VectorXd c = coefficients.row(i).transpose();
    travel = std::max(travel, poly::MaxAbsDerivative(c.data(), static_cast<int>(c.size()), 1, duration) * duration);
  }
  return travel;
}

TrajectorySample TimedTrajectory::Evaluate(double t) const {
  if (pieces_.empty()) {
    throw Error(ErrorCode::kFailedPrecondition, "cannot evaluate an empty trajectory");
  }
  const double end = duration();
  if (!(t > 0.0)) return pieces_.front().State(0.0);  // also catches NaN
  if (t >= end) {
    // The last piece of positive duration gives the end state (a zero-duration tail piece
    // would report its own, possibly zero, derivatives).
    auto last = pieces_.end() - 1;
    while (last != pieces_.begin() && !(last->duration > 0.0)) --last;
    TrajectorySample out = last->State(last->duration);
    out.t = end;
    if (end_position_.size() != 0) out.q = end_position_;
    return out;
  }
  // The last piece that starts at or before t (right limit at piece boundaries).
  auto it = std::upper_bound(pieces_.begin(), pieces_.end(), t,
                             [](double value, const Piece& piece) { return value < piece.t0; });
  const Piece& piece = (it == pieces_.begin()) ? pieces_.front() : *(it - 1);
  const double tau = std::min(std::max(0.0, t - piece.t0), piece.duration);
  TrajectorySample out = piece.State(tau);
  out.t = t;
  return out;
}

std::vector<TrajectorySample> TimedTrajectory::Sample(double period) const {
  if (!(period > 0.0) || !std::isfinite(period)) {
    ThrowInvalid("sample period = " + FormatNumber(period) + " must be finite and > 0");
  }
  std::vector<TrajectorySample> out;
  if (pieces_.empty()) return out;
  const double end = duration();
  constexpr double kMaxSamples = 1e8;
  if (end / period > kMaxSamples) {
    ThrowInvalid("sample period = " + FormatNumber(period) + " s gives more than 1e8 samples for a " +
                 FormatNumber(end) + " s trajectory");
  }
  const double guard = 1e-9 * period;
  out.push_back(Evaluate(0.0));
  for (long k = 1;; ++k) {
    const double t = static_cast<double>(k) * period;
    if (!(t < end - guard)) break;
    out.push_back(Evaluate(t));
  }
  if (end > 0.0) out.push_back(Evaluate(end));
  return out;
}

JointPath TimedTrajectory::Waypoints() const {
  JointPath out;
  if (pieces_.empty()) return out;
  out.reserve(pieces_.size() + 1);
  out.push_back(pieces_.front().coefficients.col(0));
  for (std::size_t k = 1; k < pieces_.size(); ++k) out.push_back(pieces_[k].coefficients.col(0));
  out.push_back(Evaluate(duration()).q);
  return out;
}

TimedTrajectory TimedTrajectory::TimeScaled(double factor) const {
  if (!std::isfinite(factor) || !(factor > 0.0)) {
    ThrowInvalid("time scale factor = " + FormatNumber(factor) + " must be finite and > 0");
  }
  std::vector<Piece> pieces = pieces_;
  for (Piece& piece : pieces) {
    piece.t0 *= factor;
    piece.duration *= factor;
    double scale = 1.0;
    for (Eigen::Index k = 1; k < piece.coefficients.cols(); ++k) {
      scale /= factor;
      piece.coefficients.col(k) *= scale;
    }
  }
  return TimedTrajectory(std::move(pieces), end_position_);
}

TimedTrajectory HoldTrajectory(const Eigen::VectorXd& q, double duration) {
  if (q.size() == 0 || !q.allFinite()) ThrowInvalid("hold position must be non-empty and finite");
  if (!std::isfinite(duration) || duration < 0.0) {
    ThrowInvalid("hold duration = " + FormatNumber(duration) + " s must be finite and >= 0");
  }
  TimedTrajectory::Piece piece;
  piece.duration = duration;
  piece.coefficients = q;
  return TimedTrajectory({std::move(piece)}, q);
}

TimedTrajectory ConcatenateTrajectories(const std::vector<TimedTrajectory>& parts) {
  std::vector<TimedTrajectory::Piece> pieces;
  Eigen::VectorXd end;
  double t = 0.0;
  int dofs = -1;
  for (std::size_t k = 0; k < parts.size(); ++k) {
    const TimedTrajectory& part = parts[k];
    if (part.empty()) continue;
    if (dofs >= 0 && part.num_dofs() != dofs) {
      ThrowInvalid("trajectory part " + std::to_string(k) + " has " + std::to_string(part.num_dofs()) +
                   " joints, the parts before it " + std::to_string(dofs));
    }
    dofs = part.num_dofs();
    for (const TimedTrajectory::Piece& piece : part.pieces()) {
      pieces.push_back(piece);
      pieces.back().t0 = t + piece.t0;
    }
    t += part.duration();
    end = part.Evaluate(part.duration()).q;
  }
  if (pieces.empty()) return TimedTrajectory();
  return TimedTrajectory(std::move(pieces), std::move(end));
}

TimedTrajectory DelayedTrajectory(const TimedTrajectory& trajectory, double delay) {
  if (!std::isfinite(delay) || delay < 0.0) ThrowInvalid("delay = " + FormatNumber(delay) + " s must be finite and >= 0");
  if (trajectory.empty() || delay == 0.0) return trajectory;
  return ConcatenateTrajectories({HoldTrajectory(trajectory.Evaluate(0.0).q, delay), trajectory});
}

TimedTrajectory TrajectoryRows(const TimedTrajectory& trajectory, int first, int count) {
  if (first < 0 || count < 1 || first + count > trajectory.num_dofs()) {
    ThrowInvalid("joints [" + std::to_string(first) + ", " + std::to_string(first + count) +
                 ") are outside the trajectory's " + std::to_string(trajectory.num_dofs()) + " joints");
  }
  std::vector<TimedTrajectory::Piece> pieces = trajectory.pieces();
  for (TimedTrajectory::Piece& piece : pieces) {
    piece.coefficients = Eigen::MatrixXd(piece.coefficients.middleRows(first, count));
  }
  Eigen::VectorXd end = trajectory.Evaluate(trajectory.duration()).q.segment(first, count);
  return TimedTrajectory(std::move(pieces), std::move(end));
}

TimedTrajectory::Piece LinePiece(double t0, double duration, const Eigen::VectorXd& origin,
                                 const Eigen::VectorXd& direction, double s0, double s1, double s2, double s3) {
  TimedTrajectory::Piece piece;
  piece.t0 = t0;
  piece.duration = duration;
  const int cols = s3 != 0.0 ? 4 : 3;
  piece.coefficients.resize(origin.size(), cols);
  piece.coefficients.col(0) = s0 == 0.0 ? origin : Eigen::VectorXd(origin + s0 * direction);
  piece.coefficients.col(1) = s1 * direction;
  piece.coefficients.col(2) = s2 * direction;
  if (cols == 4) piece.coefficients.col(3) = s3 * direction;
  return piece;
}

}  // namespace chasles
