#include "chasles/optimizers/collocation.h"

#include <algorithm>
#include <functional>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <IpIpoptApplication.hpp>
#include <IpSolveStatistics.hpp>

#include "chasles/collision/proximity.h"
#include "chasles/robot/dynamics.h"
#include "chasles/optimizers/verification.h"
#include "chasles/robot/error.h"
#include "collocation_nlp.h"

namespace chasles {
namespace {

using collocation::ClearancePair;
using collocation::CorridorRow;
using collocation::Instant;
using collocation::CollocationNlp;
using collocation::Layout;
using collocation::Transcription;
using Clock = std::chrono::steady_clock;
using Piece = TimedTrajectory::Piece;

constexpr int kMaxClearanceRounds = 8;       // solves in all: added clearance pairs, tightened corridor or position bounds
constexpr int kMaxEffortScalings = 20;       // growing slow-downs tried for torques
constexpr double kEffortStep = 0.005;        // [rad] torque recheck spacing (VerifyTrajectory's default)
constexpr double kCollisionStep = 0.005;     // [rad] contact search spacing (VerifyTrajectory's default)
constexpr double kClearanceTolerance = 1e-6;  // [m] below a requirement that still counts as met
constexpr double kSweepStep = 0.05;          // [rad] least joint motion allowed between clearance instants
constexpr double kMinIntervalFraction = 0.1;  // of an even split of the duration's lower bound
constexpr double kRegularization = 1e-3;      // ρ/T₀ of the tie-breaking terms (Transcription)
constexpr double kCorrectionTolerance = 1e-4;  // of the acceleration limit: largest knot correction (ExactChain)
constexpr double kCorridorMargin = 1e-4;     // relative: the knots' first corridor radius is δ(1 − this)
constexpr int kWaypointSamples = 32;         // per warm-start piece, to find where it passes a waypoint
constexpr double kWarmBarrier = 1e-4;        // Ipopt mu_init of a re-solve started from the last solution
constexpr double kWarmPush = 1e-6;           // Ipopt warm_start_*_push / _frac of such a re-solve

std::string StatusName(Ipopt::ApplicationReturnStatus status) {
  switch (status) {
    case Ipopt::Solve_Succeeded: return "Solve_Succeeded";
    case Ipopt::Solved_To_Acceptable_Level: return "Solved_To_Acceptable_Level";
    case Ipopt::Infeasible_Problem_Detected: return "Infeasible_Problem_Detected";
    case Ipopt::Search_Direction_Becomes_Too_Small: return "Search_Direction_Becomes_Too_Small";
    case Ipopt::Diverging_Iterates: return "Diverging_Iterates";
    case Ipopt::User_Requested_Stop: return "User_Requested_Stop";
    case Ipopt::Feasible_Point_Found: return "Feasible_Point_Found";
    case Ipopt::Maximum_Iterations_Exceeded: return "Maximum_Iterations_Exceeded";
    case Ipopt::Restoration_Failed: return "Restoration_Failed";
    case Ipopt::Error_In_Step_Computation: return "Error_In_Step_Computation";
    case Ipopt::Maximum_CpuTime_Exceeded: return "Maximum_CpuTime_Exceeded";
    case Ipopt::Not_Enough_Degrees_Of_Freedom: return "Not_Enough_Degrees_Of_Freedom";
    case Ipopt::Invalid_Problem_Definition: return "Invalid_Problem_Definition";
    case Ipopt::Invalid_Option: return "Invalid_Option";
    case Ipopt::Invalid_Number_Detected: return "Invalid_Number_Detected";
    case Ipopt::Unrecoverable_Exception: return "Unrecoverable_Exception";
    case Ipopt::NonIpopt_Exception_Thrown: return "NonIpopt_Exception_Thrown";
    case Ipopt::Insufficient_Memory: return "Insufficient_Memory";
    case Ipopt::Internal_Error: return "Internal_Error";
  }
  return "Ipopt status " + std::to_string(static_cast<int>(status));
}

/// The cubic pieces of a solution x with its defects closed exactly. Ipopt leaves the defects
/// open by up to its tolerance (~1e-8 rad), which would make positions jump at knots. Per joint,
/// the knot accelerations that are neither fixed nor on their bound get the least-norm
/// correction Δ (a linear problem: the end state of the chain is linear in them for fixed
/// durations) after which the chain integrated from (q₀, q̇₀) ends at (q_N, q̇_N); the pieces are
/// that chain, ending exactly at t.end_q. `correction` receives maxᵢ,ₖ |Δᵢₖ|/Aᵢ (+inf when a
/// joint has no free acceleration to correct with).
TimedTrajectory ExactChain(const Layout& L, const Eigen::VectorXd& x, const Transcription& t, double* correction) {
  const int N = L.intervals, n = L.n;
  Eigen::VectorXd h(N), until_end(N + 1);
  for (int k = 0; k < N; ++k) h[k] = x[L.h(k)];
  until_end[N] = 0.0;
  for (int k = N - 1; k >= 0; --k) until_end[k] = until_end[k + 1] + h[k];
  Eigen::MatrixXd a(N + 1, n), q(N + 1, n), v(N + 1, n);
  for (int k = 0; k <= N; ++k) {
    for (int i = 0; i < n; ++i) a(k, i) = x[L.a(k, i)];
  }
  const auto integrate = [&](int i) {
    q(0, i) = t.start_q[i];
    v(0, i) = t.start_v[i];
    for (int k = 0; k < N; ++k) {
      q(k + 1, i) = q(k, i) + v(k, i) * h[k] + (2 * a(k, i) + a(k + 1, i)) * h[k] * h[k] / 6;
      v(k + 1, i) = v(k, i) + (a(k, i) + a(k + 1, i)) * h[k] / 2;
    }
  };
  *correction = 0.0;
  for (int i = 0; i < n; ++i) {
    // ∂(q_N, q̇_N)/∂aⱼ: aⱼ enters steps j−1 and j directly and every later velocity. Accelerations
    // on their bound are left alone, unless too few others remain to correct with.
    Eigen::MatrixXd G;
    Eigen::Matrix2d GG;
    for (bool spare_bounds : {true, false}) {
      G = Eigen::MatrixXd::Zero(2, N + 1);
      for (int j = 0; j <= N; ++j) {
        const bool fixed = (j == 0 && t.start_at_rest_acceleration) || (j == N && t.end_at_rest_acceleration) ||
                           (spare_bounds && std::abs(a(j, i)) >= t.max_acceleration[i] * (1.0 - 1e-9));
        if (fixed) continue;
        const double before = j > 0 ? h[j - 1] : 0.0, after = j < N ? h[j] : 0.0;
        G(0, j) = before * before / 6 + after * after / 3 + before / 2 * until_end[j] +
                  (j < N ? after / 2 * until_end[j + 1] : 0.0);
        G(1, j) = (before + after) / 2;
      }
      GG = G * G.transpose();
      if (GG.determinant() > 1e-9 * GG(0, 0) * GG(1, 1)) break;
    }
    for (int round = 0; round < 2; ++round) {
      integrate(i);
      const Eigen::Vector2d r(t.end_q[i] - q(N, i), t.end_v[i] - v(N, i));
      if (r.isZero(0.0)) break;
      if (!(GG.determinant() > 1e-9 * GG(0, 0) * GG(1, 1))) {
        *correction = std::numeric_limits<double>::infinity();
        break;
      }
      const Eigen::VectorXd delta = G.transpose() * GG.ldlt().solve(r);
      a.col(i) += delta;
      *correction = std::max(*correction, delta.cwiseAbs().maxCoeff() / t.max_acceleration[i]);
    }
    integrate(i);
  }
  std::vector<Piece> pieces;
  double t0 = 0.0;
  for (int k = 0; k < N; ++k) {
    Piece piece;
    piece.t0 = t0;
    piece.duration = h[k];
    piece.coefficients.resize(n, 4);
    for (int i = 0; i < n; ++i) {
      piece.coefficients(i, 0) = q(k, i);
      piece.coefficients(i, 1) = v(k, i);
      piece.coefficients(i, 2) = a(k, i) / 2;
      piece.coefficients(i, 3) = (a(k + 1, i) - a(k, i)) / h[k] / 6;
    }
    t0 += h[k];
    pieces.push_back(std::move(piece));
  }
  return TimedTrajectory(std::move(pieces), t.end_q);
}

/// T + w Σ ‖q̈ₖ₊₁ − q̈ₖ‖²/hₖ (= T + w∫‖q⃛‖² dt) of a solution, without the regularisation.
double Objective(const Layout& L, const Eigen::VectorXd& x, double jerk_weight) {
  double total = 0.0;
  for (int k = 0; k < L.intervals; ++k) {
    double jerk = 0.0;
    for (int i = 0; i < L.n; ++i) jerk += std::pow(x[L.a(k + 1, i)] - x[L.a(k, i)], 2);
    total += x[L.h(k)] + jerk_weight * jerk / x[L.h(k)];
  }
  return total;
}

/// Where a piece of `chain` leaves [lower, upper] (exact ranges), adds twice the excess to that
/// joint's margin at both of the piece's knots (at most `most`, and a quarter of the joint's
/// range); returns the largest excess (0: inside everywhere).
double PullInPositionBounds(const TimedTrajectory& chain, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                            double most, Eigen::MatrixXd* margin) {
  const int n = chain.num_dofs();
  const int knots = static_cast<int>(chain.pieces().size()) + 1;
  double worst = 0.0;
  for (int k = 0; k + 1 < knots; ++k) {
    const Piece& piece = chain.pieces()[k];
    for (int i = 0; i < n; ++i) {
      const Eigen::VectorXd c = piece.coefficients.row(i).transpose();
      double lo, hi;
      poly::Range(c.data(), static_cast<int>(c.size()), piece.duration, &lo, &hi);
      // Rounding, 1e-12 of the limit, is not an excess.
      const double below = lower[i] - lo, above = hi - upper[i];
      const bool out = below > 1e-12 * std::max(1.0, std::abs(lower[i])) || above > 1e-12 * std::max(1.0, std::abs(upper[i]));
      if (!out) continue;
      const double excess = std::max(below, above);
      if (margin->size() == 0) *margin = Eigen::MatrixXd::Zero(knots, n);
      const double cap = std::min(most, (upper[i] - lower[i]) / 4);
      for (int knot : {k, k + 1}) (*margin)(knot, i) = std::min((*margin)(knot, i) + 2 * excess, cap);
      worst = std::max(worst, excess);
    }
  }
  return worst;
}

/// The path being followed: its distinct waypoints and, per interval, the segment it follows.
struct PathFollowing {
  JointPath waypoints;             ///< consecutive repeats removed
  std::vector<double> knot_times;  ///< in the warm start, K values from 0 to its duration
  std::vector<int> segment;        ///< per interval: j, following waypoints j → j+1
  std::vector<int> waypoint_knot;  ///< per interior waypoint j (index j − 1): its knot
};

/// Where `trajectory` passes waypoint w after time `after`: the first local minimum of the
/// distance once it is within `reach` (else the least distance), by samples and golden-section
/// refinement.
double PassingTime(const TimedTrajectory& trajectory, const Eigen::VectorXd& w, double after, double reach) {
  std::vector<double> times;
  for (const Piece& piece : trajectory.pieces()) {
    for (int s = 0; s <= kWaypointSamples; ++s) {
      const double time = piece.t0 + piece.duration * s / kWaypointSamples;
      if (time > after) times.push_back(time);
    }
  }
  if (times.empty()) return trajectory.duration();
  const auto distance = [&](double time) { return (trajectory.Evaluate(time).q - w).norm(); };
  std::size_t best = 0;
  double best_distance = distance(times[0]);
  bool within = best_distance <= reach;
  for (std::size_t s = 1; s < times.size(); ++s) {
    const double d = distance(times[s]);
    if (within && d > best_distance) break;  // past the first local minimum within reach
    if (d < best_distance) {
      best = s;
      best_distance = d;
    }
    within = within || d <= reach;
  }
  double lo = best > 0 ? times[best - 1] : std::max(after, 0.0), hi = best + 1 < times.size() ? times[best + 1] : times[best];
  const double ratio = (std::sqrt(5.0) - 1) / 2;
  for (int round = 0; round < 80 && hi - lo > 1e-12 * std::max(1.0, hi); ++round) {
    const double m1 = hi - ratio * (hi - lo), m2 = lo + ratio * (hi - lo);
    if (distance(m1) <= distance(m2)) {
      hi = m2;
    } else {
      lo = m1;
    }
  }
  const double refined = (lo + hi) / 2;
  return distance(refined) <= best_distance ? refined : times[best];
}

/// Knot times along the warm start: one where it passes each interior waypoint, the rest spread
/// evenly in time between them, at least two intervals per segment (`knots` raised if needed).
PathFollowing FollowPath(const TimedTrajectory& warm, const JointPath& path, double corridor, int* knots) {
  PathFollowing f;
  for (const Eigen::VectorXd& w : path) {
    if (f.waypoints.empty() || (w - f.waypoints.back()).norm() > 0.0) f.waypoints.push_back(w);
  }
  const int segments = static_cast<int>(f.waypoints.size()) - 1;
  *knots = std::max(*knots, 2 * segments + 1);
  const int intervals = *knots - 1;
  std::vector<double> anchor{0.0};
  for (int j = 1; j < segments; ++j) anchor.push_back(PassingTime(warm, f.waypoints[j], anchor.back(), corridor));
  anchor.push_back(warm.duration());
  // Intervals per segment: 2 each, the rest by duration (largest remainder).
  std::vector<int> count(segments, 2);
  const int spare = intervals - 2 * segments;
  std::vector<std::pair<double, int>> remainder;
  int given = 0;
  for (int j = 0; j < segments; ++j) {
    const double share = spare * (anchor[j + 1] - anchor[j]) / std::max(warm.duration(), 1e-300);
    count[j] += static_cast<int>(std::floor(share));
    given += static_cast<int>(std::floor(share));
    remainder.push_back({share - std::floor(share), j});
  }
  std::sort(remainder.begin(), remainder.end(), std::greater<>());
  for (int r = 0; given < spare; ++r, ++given) ++count[remainder[r % segments].second];
  for (int j = 0; j < segments; ++j) {
    if (j > 0) f.waypoint_knot.push_back(static_cast<int>(f.knot_times.size()));
    for (int s = 0; s < count[j]; ++s) {
      f.knot_times.push_back(anchor[j] + (anchor[j + 1] - anchor[j]) * s / count[j]);
      f.segment.push_back(j);
    }
  }
  f.knot_times.push_back(warm.duration());
  return f;
}

/// The corridor rows of knot k (1 … K−2): within `radius` of the segment of interval k, and
/// of its waypoint when the knot has one.
void AddCorridorRows(const PathFollowing& f, int k, double radius, std::vector<CorridorRow>* rows) {
  for (std::size_t w = 0; w < f.waypoint_knot.size(); ++w) {
    if (f.waypoint_knot[w] == k) rows->push_back({{k, 0.0}, f.waypoints[w + 1], Eigen::VectorXd(), 0.0, radius, 0.0});
  }
  const int j = f.segment[k];
  const Eigen::VectorXd ab = f.waypoints[j + 1] - f.waypoints[j];
  rows->push_back({{k, 0.0}, f.waypoints[j], ab / ab.norm(), ab.norm(), radius, 0.0});
}

/// An upper bound on the distance from the trajectory to the path (each piece to its segment,
/// each waypoint knot to its waypoint); `worst` receives the interval with the largest.
double CorridorBound(const TimedTrajectory& trajectory, const PathFollowing& f, std::vector<double>* per_interval) {
  per_interval->assign(trajectory.pieces().size(), 0.0);
  double bound = 0.0;
  for (std::size_t k = 0; k < trajectory.pieces().size(); ++k) {
    const Piece& piece = trajectory.pieces()[k];
    const int j = f.segment[k];
    double d = MaxDistanceToSegment(piece, f.waypoints[j], f.waypoints[j + 1]);
    for (std::size_t w = 0; w < f.waypoint_knot.size(); ++w) {
      if (f.waypoint_knot[w] == static_cast<int>(k)) {
        d = std::max(d, (piece.coefficients.col(0) - f.waypoints[w + 1]).norm());
      }
    }
    (*per_interval)[k] = d;
    bound = std::max(bound, d);
  }
  return bound;
}

/// max over pieces and joints of |q⁽ᵒʳᵈᵉʳ⁾ᵢ| / limitᵢ (exact).
double MaxRatio(const TimedTrajectory& trajectory, int order, const Eigen::VectorXd& limit) {
  double ratio = 0.0;
  for (const Piece& piece : trajectory.pieces()) {
    for (int i = 0; i < piece.coefficients.rows(); ++i) {
      const Eigen::VectorXd c = piece.coefficients.row(i).transpose();
      ratio = std::max(ratio, poly::MaxAbsDerivative(c.data(), static_cast<int>(c.size()), order, piece.duration) /
                                  limit[i]);
    }
  }
  return ratio;
}

/// Largest |τᵢ|/τmaxᵢ at the states VerifyTrajectory checks with its default joint step.
double MaxEffortRatio(const TimedTrajectory& trajectory, const RobotModel& robot, const KinematicLimits& limits,
                      double* where) {
  DynamicsOptions dynamics;
  dynamics.gravity = limits.gravity;
  const int n = trajectory.num_dofs();
  double worst = 0.0;
  for (const Piece& piece : trajectory.pieces()) {
    const int m = std::max(1, static_cast<int>(std::ceil(piece.MaxJointTravel() / kEffortStep)));
    for (int s = 0; s <= m; ++s) {
      const double tau = piece.duration * s / m;
      const TrajectorySample x = piece.State(tau);
      const Eigen::VectorXd effort = InverseDynamics(robot, x.q, x.qd, x.qdd, dynamics);
      for (int i = 0; i < n; ++i) {
        const double ratio = std::abs(effort[i]) / limits.max_effort[i];
        if (ratio > worst) {
          worst = ratio;
          *where = piece.t0 + tau;
        }
      }
    }
  }
  return worst;
}

/// The smallest slow-down s >= 1 (to 1e-6 relative) after which every torque is within its limit
/// at the states MaxEffortRatio checks; +inf when kMaxEffortScalings growing tries find none
/// (`ratio` and `where` then describe the last try). Slowing by s divides the inertial torques
/// by s² but leaves gravity and friction, so there may be none.
double EffortSlowDown(const TimedTrajectory& trajectory, const RobotModel& robot, const KinematicLimits& limits,
                      double* ratio, double* where) {
  const auto fits = [&](double s) {
    *ratio = MaxEffortRatio(s == 1.0 ? trajectory : trajectory.TimeScaled(s), robot, limits, where);
    return *ratio <= 1.0 + 1e-9;
  };
  if (fits(1.0)) return 1.0;
  double lo = 1.0, hi = *ratio;
  for (int round = 0; !fits(hi); ++round) {
    if (round + 1 >= kMaxEffortScalings) return std::numeric_limits<double>::infinity();
    lo = hi;
    hi *= std::max(*ratio, 1.01);
  }
  while (hi > lo * (1.0 + 1e-6)) {
    const double mid = std::sqrt(lo * hi);
    (fits(mid) ? hi : lo) = mid;
  }
  return hi;
}

/// What a check of a solution's clearance found.
struct ClearanceFindings {
  int added = 0;             ///< new (instant, link) pairs
  bool contact = false;      ///< a violated instant touches an obstacle (no distance gradient)
  double worst = std::numeric_limits<double>::infinity();  ///< smallest distance − requirement [m]
  Instant where;
  std::string link;          ///< the link at `where`
};

/// Clearance bookkeeping. Instants: every interior knot and every interval midpoint (where
/// the clearance is required), and between them states no more than kCollisionStep of joint
/// motion apart (where contact is looked for, as VerifyTrajectory does).
class ClearanceGuard {
 public:
  ClearanceGuard(const CollisionChecker& checker, const ObstacleProximity& proximity, const Layout& layout,
                 const Eigen::VectorXd& warm, double clearance, double activation)
      : checker_(checker),
        proximity_(proximity),
        layout_(layout),
        warm_(warm),
        clearance_(clearance),
        activation_(activation) {}

  /// The requirement at an instant: min(clearance, the warm start's own distance there), so a
  /// warm start that passes closer (a start next to a shelf) stays feasible.
  double Minimum(Instant at) const {
    return std::min(clearance_, checker_.Clearance(collocation::PositionAt(layout_, warm_.data(), at)));
  }

  /// Pairs for every link that comes within clearance + activation of an obstacle somewhere
  /// along the warm start: that link at every knot and midpoint.
  std::vector<ClearancePair> Initial() const {
    std::vector<int> links;
    for (const Instant& at : Required()) {
      const Eigen::VectorXd q = collocation::PositionAt(layout_, warm_.data(), at);
      if (checker_.Clearance(q) >= clearance_ + activation_) continue;
      for (const LinkProximity& link : proximity_.Query(q, clearance_ + activation_)) {
        if (link.found()) links.push_back(link.link);
      }
    }
    std::vector<ClearancePair> pairs;
    AddLinks(&links, &pairs);
    return pairs;
  }

  /// Checks the solution x: the requirement at knots and midpoints, no contact in between.
  /// A violating link not yet constrained gets pairs at every knot and midpoint (re-timed, the
  /// next solve would otherwise pass the obstacle between other instants); a contact between
  /// them adds a pair at that instant. `pairs` stays sorted.
  ClearanceFindings Check(const Eigen::VectorXd& x, std::vector<ClearancePair>* pairs) const {
    ClearanceFindings found;
    std::vector<ClearancePair> added;
    std::vector<int> links;
    // required: the clearance requirement; otherwise contact only.
    const auto check = [&](Instant at, bool required) {
      const Eigen::VectorXd q = collocation::PositionAt(layout_, x.data(), at);
      double minimum = required ? Minimum(at) : 0.0;
      const double need = required ? minimum - kClearanceTolerance : 1e-12;
      if (checker_.Clearance(q) >= need) return;
      if (!required) minimum = Minimum(at);
      for (const LinkProximity& link : proximity_.Query(q, std::max(minimum, 1e-9))) {
        if (!link.found() || link.distance >= need) continue;
        if (link.distance - minimum < found.worst) {
          found.worst = link.distance - minimum;
          found.where = at;
          found.link = proximity_.robot().links()[link.link].name;
        }
        found.contact = found.contact || link.distance <= 0.0;
        links.push_back(link.link);
        if (!required) added.push_back({at, link.link, minimum});
      }
    };
    for (int k = 0; k < layout_.intervals; ++k) {
      if (k > 0) check({k, 0.0}, true);
      check({k, 0.5}, true);
      const int m = DenseSteps(x, k);
      for (int j = 1; j < m; ++j) {
        if (2 * j != m) check({k, static_cast<double>(j) / m}, false);
      }
    }
    AddLinks(&links, &added);
    for (const ClearancePair& pair : added) {
      const bool known = std::any_of(pairs->begin(), pairs->end(), [&](const ClearancePair& other) {
        return other.at == pair.at && other.link == pair.link;
      });
      if (!known) {
        pairs->push_back(pair);
        ++found.added;
      }
    }
    std::sort(pairs->begin(), pairs->end(), [](const ClearancePair& a, const ClearancePair& b) {
      return a.at == b.at ? a.link < b.link : a.at < b.at;
    });
    return found;
  }

 private:
  /// Knots 1 … K−2 and all midpoints, in time order.
  std::vector<Instant> Required() const {
    std::vector<Instant> out;
    for (int k = 0; k < layout_.intervals; ++k) {
      if (k > 0) out.push_back({k, 0.0});
      out.push_back({k, 0.5});
    }
    return out;
  }

  /// Appends pairs for each of `links` (deduplicated) at every knot and midpoint.
  void AddLinks(std::vector<int>* links, std::vector<ClearancePair>* pairs) const {
    std::sort(links->begin(), links->end());
    links->erase(std::unique(links->begin(), links->end()), links->end());
    if (links->empty()) return;
    for (const Instant& at : Required()) {
      const double minimum = Minimum(at);
      for (int link : *links) pairs->push_back({at, link, minimum});
    }
  }

  /// Substeps of interval k so that no joint moves more than kCollisionStep between them (a
  /// bound from |q̇| <= |q̇ₖ| + |q̈ₖ|h + |u|h²/2).
  int DenseSteps(const Eigen::VectorXd& x, int k) const {
    const double h = x[layout_.h(k)];
    double travel = 0.0;
    for (int i = 0; i < layout_.n; ++i) {
      const double a0 = x[layout_.a(k, i)], a1 = x[layout_.a(k + 1, i)];
      travel = std::max(travel, (std::abs(x[layout_.v(k, i)]) + std::max(std::abs(a0), std::abs(a1)) * h) * h);
    }
    return std::max(2, static_cast<int>(std::ceil(travel / kCollisionStep)));
  }

  const CollisionChecker& checker_;
  const ObstacleProximity& proximity_;
  const Layout& layout_;
  const Eigen::VectorXd& warm_;
  double clearance_, activation_;
};

/// Serialises Ipopt in this process: Debian's sequential MUMPS keeps state in Fortran module
/// variables, and two solves in two threads abort it ("PB allocation in DMUMPS_LOAD_INIT",
/// reproduced with 4 threads). Held from the application's creation to its destruction.
std::timed_mutex& IpoptLock() {
  static std::timed_mutex mutex;
  return mutex;
}

/// Sets the Ipopt options every solve shares.
Ipopt::SmartPtr<Ipopt::IpoptApplication> MakeIpopt(const CollocationOptions& options) {
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app = IpoptApplicationFactory();
  Ipopt::SmartPtr<Ipopt::OptionsList> o = app->Options();
  o->SetIntegerValue("print_level", 0);
  o->SetStringValue("sb", "yes");
  o->SetStringValue("linear_solver", "mumps");
  o->SetStringValue("nlp_scaling_method", "user-scaling");
  o->SetStringValue("hessian_approximation", "exact");
  o->SetStringValue("mu_strategy", "adaptive");
  o->SetNumericValue("tol", options.tolerance);
  o->SetIntegerValue("max_iter", options.max_iterations);
  // Never read a stray ./ipopt.opt: every option is set here.
  if (app->Initialize("") != Ipopt::Solve_Succeeded) {
    throw Error(ErrorCode::kFailedPrecondition, "collocation: Ipopt failed to initialise");
  }
  return app;
}

}  // namespace

void CollocationOptions::Validate(const std::string& field_prefix) const {
  const auto field = [&](const char* name) { return field_prefix + name; };
  if (knots < 2 || knots > kMaxKnots) {
    ThrowInvalid(field("knots") + " = " + std::to_string(knots) +
                 (knots < 2 ? " must be >= 2" : " must be at most " + std::to_string(kMaxKnots)));
  }
  const auto finite_nonnegative = [&](double value, const char* name) {
    if (!std::isfinite(value) || !(value >= 0.0)) {
      ThrowInvalid(field(name) + " = " + FormatNumber(value) + " must be finite and >= 0");
    }
  };
  finite_nonnegative(jerk_weight, "jerk_weight");
  finite_nonnegative(clearance, "clearance");
  finite_nonnegative(activation_distance, "activation_distance");
  if (!std::isfinite(corridor) || !(corridor > 0.0) || corridor > 1.0) {
    ThrowInvalid(field("corridor") + " = " + FormatNumber(corridor) + " must be in (0, 1] rad");
  }
  if (max_iterations < 1) ThrowInvalid(field("max_iterations") + " = " + std::to_string(max_iterations) + " must be >= 1");
  if (!std::isfinite(tolerance) || !(tolerance > 0.0)) {
    ThrowInvalid(field("tolerance") + " = " + FormatNumber(tolerance) + " must be finite and > 0");
  }
  if (!(time_budget > 0.0)) ThrowInvalid(field("time_budget") + " = " + FormatNumber(time_budget) + " must be > 0");
}

namespace {

/// Phase 1 of OptimizeByCollocation: the inputs, checked.
struct CheckedInputs {
  int n = 0;
  double total = 0.0;
  TrajectorySample first, last;  // the warm start's ends
  bool along = false;            // a path with at least one move to follow
  bool effort = false;           // torque limits
};

CheckedInputs CheckInputs(const TimedTrajectory& warm_start, const KinematicLimits& limits,
                          const CollocationOptions& options, const CollisionChecker* checker, const JointPath* path) {
  options.Validate();
  if (warm_start.empty()) ThrowInvalid("collocation warm_start is empty");
  CheckedInputs in;
  const int n = in.n = warm_start.num_dofs();
  limits.Validate(n);
  if (checker != nullptr && checker->robot().num_dofs() != n) {
    ThrowInvalid("collocation warm_start has " + std::to_string(n) + " joints, robot has " +
                 std::to_string(checker->robot().num_dofs()));
  }
  in.effort = limits.max_effort.size() != 0;
  if (in.effort && (checker == nullptr || !HasInertia(checker->robot()))) {
    ThrowInvalid("max_effort needs a robot with inertia on every moving link (pass its checker to collocation)");
  }
  const double total = in.total = warm_start.duration();
  const TrajectorySample& first = in.first = warm_start.Evaluate(0.0);
  const TrajectorySample& last = in.last = warm_start.Evaluate(total);
  if (!std::isfinite(total) || !first.q.allFinite() || !first.qd.allFinite() || !last.q.allFinite() ||
      !last.qd.allFinite()) {
    ThrowInvalid("collocation warm_start has a non-finite duration or end state");
  }

  bool& along = in.along;
  if (path != nullptr && !path->empty()) {
    for (std::size_t k = 0; k < path->size(); ++k) {
      const Eigen::VectorXd& w = (*path)[k];
      if (w.size() != n || !w.allFinite()) {
        ThrowInvalid("collocation path[" + std::to_string(k) + "] has " + std::to_string(w.size()) +
                     " values (must be " + std::to_string(n) + " finite joint positions)");
      }
    }
    const auto same = [](const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
      return (a - b).cwiseAbs().maxCoeff() <= 1e-9 * std::max(1.0, b.cwiseAbs().maxCoeff());
    };
    if (!same(path->front(), first.q) || !same(path->back(), last.q)) {
      ThrowInvalid("collocation path runs from path[0] to path[" + std::to_string(path->size() - 1) +
                   "], which are not the warm start's start and end");
    }
    for (std::size_t k = 1; k < path->size() && !along; ++k) along = (*path)[k] != (*path)[k - 1];
  }
  return in;
}

/// Phase 2: the problem around the warm start — knots (along a path, at its waypoints), the
/// transcription, the initial variables and the clearance pairs. Built in place: the clearance
/// guard keeps references to the layout and the proximity object.
struct Problem {
  bool start_rest = false, end_rest = false, jerk_limited = false;
  int knots = 0;
  PathFollowing following;
  Transcription t;
  Layout layout;
  Eigen::VectorXd warm;
  std::unique_ptr<ObstacleProximity> proximity;
  std::unique_ptr<ClearanceGuard> guard;
};

void BuildProblem(const CheckedInputs& in, const TimedTrajectory& warm_start, const KinematicLimits& limits,
                  const CollocationOptions& options, const CollisionChecker* checker, const JointPath* path,
                  Problem* p) {
  // The warm start; with max_effort and both ends at rest, first slowed down until its torques
  // are within their limits (when a slow-down can).
  const int n = in.n;
  const TrajectorySample& first = in.first;
  const TrajectorySample& last = in.last;
  const double total = in.total;
  const bool start_rest = p->start_rest, end_rest = p->end_rest;
  TimedTrajectory slowed;
  const TimedTrajectory* initial = &warm_start;
  if (in.effort && start_rest && end_rest) {
    double ratio = 0.0, where = 0.0;
    const double slow = EffortSlowDown(warm_start, checker->robot(), limits, &ratio, &where);
    if (std::isfinite(slow) && slow > 1.0) {
      slowed = warm_start.TimeScaled(slow);
      initial = &slowed;
    }
  }
  const double span = initial->duration();
  // The knot times: along a path, one where the warm start passes each interior waypoint;
  // otherwise evenly spread.
  int& knots = p->knots = options.knots;
  PathFollowing& following = p->following;
  if (in.along) following = FollowPath(*initial, *path, options.corridor, &knots);
  std::vector<double> knot_times = following.knot_times;
  if (!in.along) {
    for (int k = 0; k < knots; ++k) knot_times.push_back(k + 1 == knots ? span : span * k / (knots - 1));
  }

  // The transcription.
  Transcription& t = p->t;
  t.num_dofs = n;
  t.knots = knots;
  t.jerk_weight = options.jerk_weight;
  const double inf = std::numeric_limits<double>::infinity();
  t.position_lower = checker != nullptr ? checker->robot().lower_limits() : Eigen::VectorXd::Constant(n, -inf);
  t.position_upper = checker != nullptr ? checker->robot().upper_limits() : Eigen::VectorXd::Constant(n, inf);
  t.max_velocity = limits.max_velocity;
  t.max_acceleration = limits.max_acceleration;
  t.max_jerk = limits.max_jerk;
  t.max_effort = limits.max_effort;
  t.start_q = first.q;
  t.end_q = last.q;
  t.start_v = start_rest ? Eigen::VectorXd::Zero(n) : first.qd;
  t.end_v = end_rest ? Eigen::VectorXd::Zero(n) : last.qd;
  const bool jerk_limited = p->jerk_limited = limits.max_jerk.size() != 0;
  t.start_at_rest_acceleration = jerk_limited && start_rest;
  t.end_at_rest_acceleration = jerk_limited && end_rest;
  p->layout = Layout{n, knots - 1};
  const Layout& layout = p->layout;
  // hₖ >= a tenth of an even split of a lower bound on the duration (no joint can beat
  // |Δqᵢ|/vᵢ), and never below a thousandth of the warm start's interval.
  double lower_bound = 0.0;
  for (int i = 0; i < n; ++i) lower_bound = std::max(lower_bound, std::abs(last.q[i] - first.q[i]) / limits.max_velocity[i]);
  t.min_interval = kMinIntervalFraction * std::max(lower_bound, 0.01 * total) / layout.intervals;
  if (in.effort) {
    t.robot = &checker->robot();
    t.dynamics.gravity = limits.gravity;
  }
  t.nominal_interval = span / layout.intervals;
  t.regularization = kRegularization * span;
  Eigen::VectorXd& warm = p->warm;
  warm.resize(layout.size());
  for (int k = 0; k <= layout.intervals; ++k) {
    const TrajectorySample s = initial->Evaluate(knot_times[k]);
    for (int i = 0; i < n; ++i) {
      warm[layout.q(k, i)] = s.q[i];
      warm[layout.v(k, i)] = std::clamp(s.qd[i], -limits.max_velocity[i], limits.max_velocity[i]);
      warm[layout.a(k, i)] = std::clamp(s.qdd[i], -limits.max_acceleration[i], limits.max_acceleration[i]);
    }
    if (k < layout.intervals) {
      warm[layout.h(k)] = knot_times[k + 1] - knot_times[k];
      t.min_interval = std::min(t.min_interval, std::max(0.5 * warm[layout.h(k)], 1e-3 * t.min_interval));
    }
  }
  if (in.along) {
    for (int k = 1; k < layout.intervals; ++k) {
      AddCorridorRows(following, k, options.corridor * (1.0 - kCorridorMargin), &t.corridor);
    }
  }
  for (int i = 0; i < n; ++i) {
    warm[layout.v(0, i)] = t.start_v[i];
    warm[layout.v(layout.intervals, i)] = t.end_v[i];
    if (t.start_at_rest_acceleration) warm[layout.a(0, i)] = 0.0;
    if (t.end_at_rest_acceleration) warm[layout.a(layout.intervals, i)] = 0.0;
  }

  // Clearance: only with obstacles.
  if (checker != nullptr && !checker->scene().empty()) {
    // Non-owning: the proximity object lives only during this call.
    p->proximity = std::make_unique<ObstacleProximity>(std::shared_ptr<const CollisionChecker>(
        std::shared_ptr<const CollisionChecker>(), checker));
    t.proximity = p->proximity.get();
    p->guard = std::make_unique<ClearanceGuard>(*checker, *p->proximity, layout, warm, options.clearance,
                                                options.activation_distance);
    t.pairs = p->guard->Initial();
  }

  // With clearance pairs, no interval may carry the robot far between the instants checked
  // (else a long interval could pass a link through an obstacle between its knots and midpoint):
  // the joint-space motion over each half interval is at most max_step = max(kSweepStep, twice
  // the warm start's average).
  double length = 0.0;
  for (int k = 0; k < layout.intervals; ++k) {
    length += (warm.segment(layout.q(k + 1, 0), n) - warm.segment(layout.q(k, 0), n)).norm();
  }
  t.max_step = std::max(kSweepStep, length / layout.intervals);
  t.bounded_motion = !t.pairs.empty();
}

/// Phase 3: the solves — one, plus one per round of rows tightened or clearance pairs added
/// after a violation. False when stopped while waiting for another solve (the report says so).
struct Solves {
  bool solved = false;
  TimedTrajectory chain;    // the last solution's pieces with the defects closed (ExactChain)
  double correction = 0.0;  // ExactChain's largest knot correction for it
  int rounds = 0;
};

bool SolveRounds(Problem& p, bool along, const CollocationOptions& options, const CollisionChecker* checker,
                 const std::function<double()>& elapsed, OptimizerReport* report, Solves* out) {
  // Only one thread of the process may use Ipopt at a time (IpoptLock).
  Transcription& t = p.t;
  const Layout& layout = p.layout;
  const PathFollowing& following = p.following;
  Eigen::VectorXd start = p.warm;
  Eigen::VectorXd x;
  TimedTrajectory& chain = out->chain;
  double& correction = out->correction;
  int& rounds = out->rounds;
  std::string failure;
  std::unique_lock<std::timed_mutex> lock(IpoptLock(), std::defer_lock);
  while (!lock.try_lock_for(std::chrono::milliseconds(10))) {
    if (t.stop()) {
      report->status = "User_Requested_Stop";
      report->message = options.stop && options.stop() ? "stopped by the caller while waiting for another solve"
                                                       : "time budget of " + FormatNumber(options.time_budget) +
                                                             " s exceeded while waiting for another solve";
      return false;
    }
  }
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app = MakeIpopt(options);
  collocation::Multipliers duals;  // of the last solve, when the next has the same rows
  for (;; ++rounds) {
    const double remaining = options.time_budget - elapsed();
    app->Options()->SetNumericValue("max_cpu_time", std::max(1e-3, std::min(remaining, 1e6)));
    // A re-solve whose rows are those of the last solve (bounds tightened) starts from its
    // primal and dual solution with a small barrier parameter instead of from scratch.
    const bool warm_duals = duals.rows.size() != 0;
    app->Options()->SetStringValue("warm_start_init_point", warm_duals ? "yes" : "no");
    if (warm_duals) {
      app->Options()->SetNumericValue("mu_init", kWarmBarrier);
      for (const char* push : {"warm_start_bound_push", "warm_start_bound_frac", "warm_start_mult_bound_push",
                               "warm_start_slack_bound_push", "warm_start_slack_bound_frac"}) {
        app->Options()->SetNumericValue(push, kWarmPush);
      }
    }
    Ipopt::SmartPtr<CollocationNlp> nlp = new CollocationNlp(t, start, warm_duals ? duals : collocation::Multipliers{});
    const Ipopt::ApplicationReturnStatus status = app->OptimizeTNLP(Ipopt::GetRawPtr(nlp));
    report->status = StatusName(status);
    Ipopt::SmartPtr<Ipopt::SolveStatistics> stats = app->Statistics();
    if (Ipopt::IsValid(stats)) {
      report->iterations += stats->IterationCount();
      double dual, primal, complementarity, kkt;
      stats->Infeasibilities(dual, primal, complementarity, kkt);
      report->constraint_violation = primal;
    } else {
      report->constraint_violation = nlp->violation();
    }
    if (status != Ipopt::Solve_Succeeded && status != Ipopt::Solved_To_Acceptable_Level) {
      if (nlp->stopped() && options.stop && options.stop()) {
        failure = "stopped by the caller";
      } else if (nlp->stopped() || status == Ipopt::Maximum_CpuTime_Exceeded) {
        failure = "time budget of " + FormatNumber(options.time_budget) + " s exceeded";
      } else {
        failure = "Ipopt ended with " + report->status;
      }
      failure += " after " + std::to_string(report->iterations) + " iterations";
      break;
    }
    x = nlp->solution();
    report->objective = Objective(layout, x, options.jerk_weight);
    chain = ExactChain(layout, x, t, &correction);
    bool again = false, contact = false;
    const std::size_t pairs_before = t.pairs.size();
    if (along) {
      // The exact bound of the solution's distance to the path. Rows sit at knots only (their
      // curvature is exact there); an interval that bulges beyond the corridor between them
      // tightens its two knots' segment rows by twice the excess for the next solve.
      std::vector<double> per_interval;
      const double bound = CorridorBound(chain, following, &per_interval);
      report->path_deviation = bound;
      if (bound > options.corridor) {
        const int worst = static_cast<int>(std::max_element(per_interval.begin(), per_interval.end()) - per_interval.begin());
        if (rounds + 1 >= kMaxClearanceRounds) {
          failure = "the trajectory leaves the path's corridor of " + FormatNumber(options.corridor) + " rad by " +
                    FormatNumber(bound - options.corridor) + " rad in interval " + std::to_string(worst) + " after " +
                    std::to_string(rounds + 1) + " solves";
          break;
        }
        for (int k = 0; k < layout.intervals; ++k) {
          if (per_interval[k] <= options.corridor) continue;
          const double excess = per_interval[k] - options.corridor * (1.0 - kCorridorMargin);
          for (CorridorRow& row : t.corridor) {
            if (row.direction.size() == 0 || (row.at.interval != k && row.at.interval != k + 1)) continue;
            row.radius = std::max(row.radius - 2 * excess, 0.1 * options.corridor);
            row.inset = std::min(row.inset + 2 * excess, row.length / 4);
          }
        }
        again = true;
      }
    }
    if (checker != nullptr) {
      // Position limits hold at the knots (variable bounds); a cubic that bulges past one
      // between them pulls that joint's bounds at both knots in by twice the excess.
      // Along a path at most half the corridor, so that a waypoint on a limit stays within reach.
      const double most = along ? options.corridor / 2 : std::numeric_limits<double>::infinity();
      const double excess = PullInPositionBounds(chain, t.position_lower, t.position_upper, most, &t.position_margin);
      if (excess > 0.0) {
        if (rounds + 1 >= kMaxClearanceRounds) {
          failure = "a joint leaves its position limits between knots by " + FormatNumber(excess) + " rad after " +
                    std::to_string(rounds + 1) + " solves";
          break;
        }
        again = true;
      }
    }
    if (p.guard != nullptr) {
      const ClearanceFindings found = p.guard->Check(x, &t.pairs);
      if (!std::isinf(found.worst)) {
        if (found.added == 0 || rounds + 1 >= kMaxClearanceRounds) {
          failure = "clearance of link '" + found.link + "' is " + FormatNumber(-found.worst) +
                    " m short in interval " + std::to_string(found.where.interval) + " at " +
                    FormatNumber(found.where.fraction) + " of its duration after " + std::to_string(rounds + 1) +
                    " solves";
          break;
        }
        t.bounded_motion = true;
        contact = found.contact;
        again = true;
      }
    }
    if (!again) {
      out->solved = true;
      break;
    }
    // Continue from the solution, unless it touches an obstacle (no distance gradient there).
    start = contact ? p.warm : x;
    duals = !contact && t.pairs.size() == pairs_before ? nlp->multipliers() : collocation::Multipliers{};
  }
  app = nullptr;  // MUMPS' instance ends with the application, still under the lock
  lock.unlock();
  report->message = failure;
  return true;
}

/// Phase 4: the last chain's exact limits (slowed down within them when both ends are at rest),
/// torques and the whole contract; the report's message.
void Finish(const CheckedInputs& in, Problem& p, Solves& s, const KinematicLimits& limits,
            const CollocationOptions& options, const CollisionChecker* checker, CollocationResult* result) {
  // The trajectory: the last solve's chain, which the loop found inside the corridor and the
  // position limits between knots (exactly; time scaling below keeps both); its exact limits.
  OptimizerReport& report = result->report;
  const Transcription& t = p.t;
  const bool start_rest = p.start_rest, end_rest = p.end_rest;
  TimedTrajectory trajectory = std::move(s.chain);
  const double correction = s.correction;
  std::string problem;
  if (!(correction <= kCorrectionTolerance)) {
    problem = "the collocation defects are not closed: closing them changes a knot acceleration by " +
              FormatNumber(correction) + " of its limit (at most " + FormatNumber(kCorrectionTolerance) + ")";
  }
  double scale = std::max(MaxRatio(trajectory, 1, limits.max_velocity),
                          std::sqrt(MaxRatio(trajectory, 2, limits.max_acceleration)));
  if (p.jerk_limited) scale = std::max(scale, std::cbrt(MaxRatio(trajectory, 3, limits.max_jerk)));
  const bool moving_ends = !start_rest || !end_rest;
  const auto rescale = [&](double factor) {
    if (moving_ends) {
      problem = "the trajectory would need slowing by a factor " + FormatNumber(factor) +
                " to meet the limits between knots, which would change its end velocities";
      return;
    }
    report.time_scale *= factor;
    trajectory = trajectory.TimeScaled(factor);
  };
  if (problem.empty() && scale > 1.0) rescale(scale);
  if (problem.empty() && in.effort) {
    // Torques between the checked points: the smallest further slow-down that meets them at the
    // states VerifyTrajectory checks.
    double ratio = 0.0, where = 0.0;
    const double slow = EffortSlowDown(trajectory, checker->robot(), limits, &ratio, &where);
    if (std::isinf(slow)) {
      problem = "a torque exceeds its limit by a factor " + FormatNumber(ratio) + " at t = " + FormatNumber(where) +
                " s (of the trajectory slowed down " + std::to_string(kMaxEffortScalings) + " times)";
    } else if (slow > 1.0) {
      rescale(slow);
    }
  }
  if (problem.empty() && checker != nullptr) {
    // The whole contract, self-collision included (not constrained above), as the caller will see it.
    VerificationOptions verification;
    if (!start_rest) verification.start_velocity = t.start_v;
    if (!end_rest) verification.end_velocity = t.end_v;
    const VerificationReport verified = VerifyTrajectory(trajectory, t.start_q, t.end_q, *checker, limits, verification);
    if (!verified.ok) problem = "the solution fails verification: " + verified.reason;
  }
  if (!problem.empty()) {
    report.message = problem;
    return;
  }
  result->trajectory = std::move(trajectory);
  report.ok = true;
  report.message = std::string(in.along ? "along the path within " + FormatNumber(report.path_deviation) + " rad (corridor " +
                                           FormatNumber(options.corridor) + "), "
                                     : "free of the path, ") +
                   std::to_string(p.knots) + " knots, " + std::to_string(report.iterations) +
                   " Ipopt iterations in " + std::to_string(s.rounds + 1) + " solve" + (s.rounds > 0 ? "s" : "") +
                   (t.pairs.empty() ? "" : ", " + std::to_string(t.pairs.size()) + " clearance constraints") +
                   ", duration " + FormatNumber(result->trajectory.duration()) + " s" +
                   (report.time_scale > 1.0 ? ", slowed by " + FormatNumber(report.time_scale) : "");
}

}  // namespace

CollocationResult OptimizeByCollocation(const TimedTrajectory& warm_start, const KinematicLimits& limits,
                                        const CollocationOptions& options, const CollisionChecker* checker,
                                        const JointPath* path) {
  const Clock::time_point started = Clock::now();
  const std::function<double()> elapsed = [&] { return std::chrono::duration<double>(Clock::now() - started).count(); };
  const CheckedInputs in = CheckInputs(warm_start, limits, options, checker, path);
  const int n = in.n;
  const TrajectorySample& first = in.first;
  const TrajectorySample& last = in.last;
  CollocationResult result;
  OptimizerReport& report = result.report;
  if (!(in.total > 0.0)) {
    Piece rest;
    rest.coefficients = Eigen::MatrixXd::Zero(n, 4);
    rest.coefficients.col(0) = first.q;
    result.trajectory = TimedTrajectory({rest}, last.q);
    report.ok = true;
    report.message = "the warm start does not move: nothing to optimise";
    report.solve_seconds = elapsed();
    return result;
  }

  const double rest_tolerance = 1e-9 * std::max(1.0, limits.max_velocity.maxCoeff());
  const bool start_rest = first.qd.cwiseAbs().maxCoeff() <= rest_tolerance;
  const bool end_rest = last.qd.cwiseAbs().maxCoeff() <= rest_tolerance;
  if (!in.along && start_rest && end_rest && first.q == last.q) {
    report.message = "free collocation (no path to follow) of a warm start that returns to its start at rest: the "
                     "minimum-time trajectory between equal ends does not move; follow the path instead";
    report.solve_seconds = elapsed();
    return result;
  }

  Problem problem;
  problem.start_rest = start_rest;
  problem.end_rest = end_rest;
  BuildProblem(in, warm_start, limits, options, checker, path, &problem);
  const double deadline = std::isfinite(options.time_budget) ? options.time_budget : 1e300;
  problem.t.stop = [&] { return (options.stop && options.stop()) || elapsed() > deadline; };
  Solves solves;
  const bool ran = SolveRounds(problem, in.along, options, checker, elapsed, &report, &solves);
  if (ran && solves.solved) Finish(in, problem, solves, limits, options, checker, &result);
  report.solve_seconds = elapsed();
  return result;
}

}  // namespace chasles
