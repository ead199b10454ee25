#include "chasles/optimizers/collocation.h"

#include <algorithm>
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
using collocation::Instant;
using collocation::CollocationNlp;
using collocation::Layout;
using collocation::Transcription;
using Clock = std::chrono::steady_clock;
using Piece = TimedTrajectory::Piece;

constexpr int kMaxClearanceRounds = 5;       // solves with added clearance pairs
constexpr int kMaxEffortScalings = 20;       // growing slow-downs tried for torques
constexpr double kEffortStep = 0.005;        // [rad] torque recheck spacing (VerifyTrajectory's default)
constexpr double kCollisionStep = 0.005;     // [rad] contact search spacing (VerifyTrajectory's default)
constexpr double kClearanceTolerance = 1e-6;  // [m] below a requirement that still counts as met
constexpr double kSweepStep = 0.05;          // [rad] least joint motion allowed between clearance instants
constexpr double kMinIntervalFraction = 0.1;  // of an even split of the duration's lower bound
constexpr double kRegularization = 1e-3;      // ρ/T₀ of the tie-breaking terms (Transcription)
constexpr double kJumpTolerance = 1e-7;      // [rad], [rad/s]: largest defect left between pieces

void ValidateOptions(const CollocationOptions& options) {
  if (options.knots < 2) ThrowInvalid("collocation knots = " + std::to_string(options.knots) + " must be >= 2");
  const auto finite_nonnegative = [](double value, const char* name) {
    if (!std::isfinite(value) || !(value >= 0.0)) {
      ThrowInvalid(std::string("collocation ") + name + " = " + FormatNumber(value) + " must be finite and >= 0");
    }
  };
  finite_nonnegative(options.jerk_weight, "jerk_weight");
  finite_nonnegative(options.clearance, "clearance");
  finite_nonnegative(options.activation_distance, "activation_distance");
  if (options.max_iterations < 1) {
    ThrowInvalid("collocation max_iterations = " + std::to_string(options.max_iterations) + " must be >= 1");
  }
  if (!std::isfinite(options.tolerance) || !(options.tolerance > 0.0)) {
    ThrowInvalid("collocation tolerance = " + FormatNumber(options.tolerance) + " must be finite and > 0");
  }
  if (!(options.time_budget > 0.0)) {
    ThrowInvalid("collocation time_budget = " + FormatNumber(options.time_budget) + " must be > 0");
  }
}

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

/// The cubic pieces of a solution x (one per interval), ending exactly at `end`.
TimedTrajectory BuildTrajectory(const Layout& L, const Eigen::VectorXd& x, const Eigen::VectorXd& end) {
  std::vector<Piece> pieces;
  double t0 = 0.0;
  for (int k = 0; k < L.intervals; ++k) {
    Piece piece;
    piece.t0 = t0;
    piece.duration = x[L.h(k)];
    piece.coefficients.resize(L.n, 4);
    for (int i = 0; i < L.n; ++i) {
      const double a0 = x[L.a(k, i)];
      piece.coefficients(i, 0) = x[L.q(k, i)];
      piece.coefficients(i, 1) = x[L.v(k, i)];
      piece.coefficients(i, 2) = a0 / 2;
      piece.coefficients(i, 3) = (x[L.a(k + 1, i)] - a0) / piece.duration / 6;
    }
    t0 += piece.duration;
    pieces.push_back(std::move(piece));
  }
  return TimedTrajectory(std::move(pieces), end);
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

/// Largest |piece k's end − knot k+1| over positions and velocities (the defects left open).
void DefectJumps(const Layout& L, const Eigen::VectorXd& x, const TimedTrajectory& trajectory, double* position,
                 double* velocity) {
  *position = *velocity = 0.0;
  for (int k = 0; k < L.intervals; ++k) {
    const Piece& piece = trajectory.pieces()[k];
    for (int i = 0; i < L.n; ++i) {
      const Eigen::VectorXd c = piece.coefficients.row(i).transpose();
      *position = std::max(*position, std::abs(poly::Eval(c.data(), 4, piece.duration) - x[L.q(k + 1, i)]));
      *velocity = std::max(*velocity, std::abs(poly::EvalDerivative(c.data(), 4, 1, piece.duration) - x[L.v(k + 1, i)]));
    }
  }
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

CollocationResult OptimizeByCollocation(const TimedTrajectory& warm_start, const KinematicLimits& limits,
                                        const CollocationOptions& options, const CollisionChecker* checker) {
  const Clock::time_point started = Clock::now();
  ValidateOptions(options);
  if (warm_start.empty()) ThrowInvalid("collocation warm_start is empty");
  const int n = warm_start.num_dofs();
  limits.Validate(n);
  if (checker != nullptr && checker->robot().num_dofs() != n) {
    ThrowInvalid("collocation warm_start has " + std::to_string(n) + " joints, robot has " +
                 std::to_string(checker->robot().num_dofs()));
  }
  const bool effort = limits.max_effort.size() != 0;
  if (effort && (checker == nullptr || !HasInertia(checker->robot()))) {
    ThrowInvalid("max_effort needs a robot with inertia on every moving link (pass its checker to collocation)");
  }
  const double total = warm_start.duration();
  const TrajectorySample first = warm_start.Evaluate(0.0);
  const TrajectorySample last = warm_start.Evaluate(total);
  if (!std::isfinite(total) || !first.q.allFinite() || !first.qd.allFinite() || !last.q.allFinite() ||
      !last.qd.allFinite()) {
    ThrowInvalid("collocation warm_start has a non-finite duration or end state");
  }

  CollocationResult result;
  OptimizerReport& report = result.report;
  const auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - started).count(); };
  if (!(total > 0.0)) {
    Piece rest;
    rest.coefficients = Eigen::MatrixXd::Zero(n, 4);
    rest.coefficients.col(0) = first.q;
    result.trajectory = TimedTrajectory({rest}, last.q);
    report.ok = true;
    report.message = "the warm start does not move: nothing to optimise";
    report.solve_seconds = elapsed();
    return result;
  }

  // The transcription.
  Transcription t;
  t.num_dofs = n;
  t.knots = options.knots;
  t.jerk_weight = options.jerk_weight;
  const double inf = std::numeric_limits<double>::infinity();
  t.position_lower = checker != nullptr ? checker->robot().lower_limits() : Eigen::VectorXd::Constant(n, -inf);
  t.position_upper = checker != nullptr ? checker->robot().upper_limits() : Eigen::VectorXd::Constant(n, inf);
  t.max_velocity = limits.max_velocity;
  t.max_acceleration = limits.max_acceleration;
  t.max_jerk = limits.max_jerk;
  t.max_effort = limits.max_effort;
  const double rest_tolerance = 1e-9 * std::max(1.0, limits.max_velocity.maxCoeff());
  const bool start_rest = first.qd.cwiseAbs().maxCoeff() <= rest_tolerance;
  const bool end_rest = last.qd.cwiseAbs().maxCoeff() <= rest_tolerance;
  t.start_q = first.q;
  t.end_q = last.q;
  t.start_v = start_rest ? Eigen::VectorXd::Zero(n) : first.qd;
  t.end_v = end_rest ? Eigen::VectorXd::Zero(n) : last.qd;
  const bool jerk_limited = limits.max_jerk.size() != 0;
  t.start_at_rest_acceleration = jerk_limited && start_rest;
  t.end_at_rest_acceleration = jerk_limited && end_rest;
  const Layout layout{n, options.knots - 1};
  // hₖ >= a tenth of an even split of a lower bound on the duration (no joint can beat
  // |Δqᵢ|/vᵢ), and never below a thousandth of the warm start's interval.
  double lower_bound = 0.0;
  for (int i = 0; i < n; ++i) lower_bound = std::max(lower_bound, std::abs(last.q[i] - first.q[i]) / limits.max_velocity[i]);
  t.min_interval = kMinIntervalFraction * std::max(lower_bound, 0.01 * total) / layout.intervals;
  if (effort) {
    t.robot = &checker->robot();
    t.dynamics.gravity = limits.gravity;
  }
  const double deadline = std::isfinite(options.time_budget) ? options.time_budget : 1e300;
  t.stop = [&] { return (options.stop && options.stop()) || elapsed() > deadline; };

  // The warm start, sampled at K evenly spaced times; with max_effort and both ends at rest,
  // first slowed down until its torques are within their limits (when a slow-down can).
  TimedTrajectory slowed;
  const TimedTrajectory* initial = &warm_start;
  if (effort && start_rest && end_rest) {
    double ratio = 0.0, where = 0.0;
    const double slow = EffortSlowDown(warm_start, checker->robot(), limits, &ratio, &where);
    if (std::isfinite(slow) && slow > 1.0) {
      slowed = warm_start.TimeScaled(slow);
      initial = &slowed;
    }
  }
  const double span = initial->duration();
  t.nominal_interval = span / layout.intervals;
  t.regularization = kRegularization * span;
  Eigen::VectorXd warm(layout.size());
  for (int k = 0; k <= layout.intervals; ++k) {
    const TrajectorySample s = k == layout.intervals ? initial->Evaluate(span) : initial->Evaluate(span * k / layout.intervals);
    for (int i = 0; i < n; ++i) {
      warm[layout.q(k, i)] = s.q[i];
      warm[layout.v(k, i)] = std::clamp(s.qd[i], -limits.max_velocity[i], limits.max_velocity[i]);
      warm[layout.a(k, i)] = std::clamp(s.qdd[i], -limits.max_acceleration[i], limits.max_acceleration[i]);
    }
    if (k < layout.intervals) warm[layout.h(k)] = t.nominal_interval;
  }
  for (int i = 0; i < n; ++i) {
    warm[layout.v(0, i)] = t.start_v[i];
    warm[layout.v(layout.intervals, i)] = t.end_v[i];
    if (t.start_at_rest_acceleration) warm[layout.a(0, i)] = 0.0;
    if (t.end_at_rest_acceleration) warm[layout.a(layout.intervals, i)] = 0.0;
  }

  // Clearance: only with obstacles.
  std::unique_ptr<ObstacleProximity> proximity;
  std::unique_ptr<ClearanceGuard> guard;
  if (checker != nullptr && !checker->scene().empty()) {
    // Non-owning: the proximity object lives only during this call.
    proximity = std::make_unique<ObstacleProximity>(std::shared_ptr<const CollisionChecker>(
        std::shared_ptr<const CollisionChecker>(), checker));
    t.proximity = proximity.get();
    guard = std::make_unique<ClearanceGuard>(*checker, *proximity, layout, warm, options.clearance,
                                             options.activation_distance);
    t.pairs = guard->Initial();
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

  // The solves: one, plus one per round of clearance pairs added after a violation. Only one
  // thread of the process may use Ipopt at a time (IpoptLock).
  Eigen::VectorXd start = warm;
  Eigen::VectorXd x;
  bool solved = false;
  int rounds = 0;
  std::string failure;
  std::unique_lock<std::timed_mutex> lock(IpoptLock(), std::defer_lock);
  while (!lock.try_lock_for(std::chrono::milliseconds(10))) {
    if (t.stop()) {
      report.status = "User_Requested_Stop";
      report.message = options.stop && options.stop() ? "stopped by the caller while waiting for another solve"
                                                      : "time budget of " + FormatNumber(options.time_budget) +
                                                            " s exceeded while waiting for another solve";
      report.solve_seconds = elapsed();
      return result;
    }
  }
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app = MakeIpopt(options);
  for (;; ++rounds) {
    const double remaining = options.time_budget - elapsed();
    app->Options()->SetNumericValue("max_cpu_time", std::max(1e-3, std::min(remaining, 1e6)));
    Ipopt::SmartPtr<CollocationNlp> nlp = new CollocationNlp(t, start);
    const Ipopt::ApplicationReturnStatus status = app->OptimizeTNLP(Ipopt::GetRawPtr(nlp));
    report.status = StatusName(status);
    Ipopt::SmartPtr<Ipopt::SolveStatistics> stats = app->Statistics();
    if (Ipopt::IsValid(stats)) {
      report.iterations += stats->IterationCount();
      double dual, primal, complementarity, kkt;
      stats->Infeasibilities(dual, primal, complementarity, kkt);
      report.constraint_violation = primal;
    } else {
      report.constraint_violation = nlp->violation();
    }
    if (status != Ipopt::Solve_Succeeded && status != Ipopt::Solved_To_Acceptable_Level) {
      if (nlp->stopped() && options.stop && options.stop()) {
        failure = "stopped by the caller";
      } else if (nlp->stopped() || status == Ipopt::Maximum_CpuTime_Exceeded) {
        failure = "time budget of " + FormatNumber(options.time_budget) + " s exceeded";
      } else {
        failure = "Ipopt ended with " + report.status;
      }
      failure += " after " + std::to_string(report.iterations) + " iterations";
      break;
    }
    x = nlp->solution();
    report.objective = Objective(layout, x, options.jerk_weight);
    if (guard == nullptr) {
      solved = true;
      break;
    }
    const ClearanceFindings found = guard->Check(x, &t.pairs);
    if (std::isinf(found.worst)) {
      solved = true;
      break;
    }
    if (found.added == 0 || rounds + 1 >= kMaxClearanceRounds) {
      failure = "clearance of link '" + found.link + "' is " + FormatNumber(-found.worst) + " m short in interval " +
                std::to_string(found.where.interval) + " at " + FormatNumber(found.where.fraction) +
                " of its duration after " + std::to_string(rounds + 1) + " solves";
      break;
    }
    // Continue from the solution, unless it touches an obstacle (no distance gradient there).
    t.bounded_motion = true;
    start = found.contact ? warm : x;
  }
  app = nullptr;  // MUMPS' instance ends with the application, still under the lock
  lock.unlock();
  report.message = failure;
  if (!solved) {
    report.solve_seconds = elapsed();
    return result;
  }

  // The trajectory, its continuity and its exact limits between knots.
  TimedTrajectory trajectory = BuildTrajectory(layout, x, t.end_q);
  double position_jump, velocity_jump;
  DefectJumps(layout, x, trajectory, &position_jump, &velocity_jump);
  const double velocity_tolerance = kJumpTolerance * std::max(1.0, limits.max_velocity.maxCoeff());
  std::string problem;
  if (!(position_jump <= kJumpTolerance) || !(velocity_jump <= velocity_tolerance)) {
    problem = "the collocation defects are not closed: positions jump " + FormatNumber(position_jump) +
              " rad and velocities " + FormatNumber(velocity_jump) + " rad/s between intervals";
  }
  if (problem.empty() && checker != nullptr) {
    const Eigen::VectorXd& lower = checker->robot().lower_limits();
    const Eigen::VectorXd& upper = checker->robot().upper_limits();
    for (const Piece& piece : trajectory.pieces()) {
      for (int i = 0; i < n && problem.empty(); ++i) {
        const Eigen::VectorXd c = piece.coefficients.row(i).transpose();
        double lo, hi;
        poly::Range(c.data(), 4, piece.duration, &lo, &hi);
        if (lo < lower[i] - 1e-12 * std::max(1.0, std::abs(lower[i])) ||
            hi > upper[i] + 1e-12 * std::max(1.0, std::abs(upper[i]))) {
          problem = "joint " + std::to_string(i) + " leaves its position limits between knots (t = " +
                    FormatNumber(piece.t0) + " s … " + FormatNumber(piece.t0 + piece.duration) + " s)";
        }
      }
    }
  }
  double scale = std::max(MaxRatio(trajectory, 1, limits.max_velocity),
                          std::sqrt(MaxRatio(trajectory, 2, limits.max_acceleration)));
  if (jerk_limited) scale = std::max(scale, std::cbrt(MaxRatio(trajectory, 3, limits.max_jerk)));
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
  if (problem.empty() && effort) {
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
  report.solve_seconds = elapsed();
  if (!problem.empty()) {
    report.message = problem;
    return result;
  }
  result.trajectory = std::move(trajectory);
  report.ok = true;
  report.message = std::to_string(options.knots) + " knots, " + std::to_string(report.iterations) +
                   " Ipopt iterations in " + std::to_string(rounds + 1) + " solve" + (rounds > 0 ? "s" : "") +
                   (t.pairs.empty() ? "" : ", " + std::to_string(t.pairs.size()) + " clearance constraints") +
                   ", duration " + FormatNumber(result.trajectory.duration()) + " s" +
                   (report.time_scale > 1.0 ? ", slowed by " + FormatNumber(report.time_scale) : "");
  return result;
}

}  // namespace chasles
