#include "chasles/optimizers/spline_smoothing.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/QR>
#include <nlopt.hpp>

#include "chasles/collision/proximity.h"
#include "chasles/optimizers/verification.h"
#include "chasles/robot/dynamics.h"
#include "chasles/robot/error.h"
#include "spline_curve.h"
#include "spline_problem.h"

namespace chasles {
namespace {

using spline::ClearanceSample;
using spline::JointSpline;
using spline::Layout;
using spline::Problem;

constexpr int kMaxControlPoints = 500;
/// NLopt's tolerance on the constraints (dimensionless limit rows, clearance rows in units of
/// 0.05 m).
constexpr double kConstraintTolerance = 1e-8;
/// Largest time scaling accepted for a solver's tolerance on the limits: beyond, it did not
/// meet them. With a moving end much less, as slowing down changes its velocity.
constexpr double kMaxRoundingScale = 1.0 + 1e-3;
constexpr double kMaxMovingEndScale = 1.0 + 1e-9;
/// [m] below a sample's required clearance still accepted (rounding of the distances).
constexpr double kClearanceTolerance = 1e-9;
/// NLopt's relative tolerance on x.
constexpr double kRelativeTolerance = 1e-7;
constexpr int kFitSamplesPerSpan = 8;
constexpr double kSampleStep = 0.05;     ///< [rad] of joint travel between clearance samples
constexpr int kMaxSamplesPerSpan = 12;
constexpr double kCheckStep = 0.002;     ///< [rad] of joint travel between dense clearance checks
constexpr double kCheckPeriod = 0.001;   ///< [s] between dense clearance checks
constexpr int kMaxClearanceRounds = 4;   ///< solves with refined clearance samples
/// [m] asked for beyond the required clearance at the samples (at most 10 % more), for the
/// dips between them.
constexpr double kClearanceMargin = 0.005;

using Clock = std::chrono::steady_clock;

double Seconds(Clock::time_point since) { return std::chrono::duration<double>(Clock::now() - since).count(); }

void ValidateOptions(const SplineOptions& options) {
  if (options.degree != 3 && options.degree != 5) {
    ThrowInvalid("spline degree = " + std::to_string(options.degree) + " must be 3 or 5");
  }
  if (options.control_points != 0 &&
      (options.control_points < options.degree + 1 || options.control_points > kMaxControlPoints)) {
    ThrowInvalid("spline control_points = " + std::to_string(options.control_points) + " must be 0 (chosen from " +
                 "the path) or within [degree + 1 = " + std::to_string(options.degree + 1) + ", " +
                 std::to_string(kMaxControlPoints) + "]");
  }
  if (!std::isfinite(options.jerk_weight) || !(options.jerk_weight >= 0.0)) {
    ThrowInvalid("spline jerk_weight = " + FormatNumber(options.jerk_weight) + " must be finite and >= 0");
  }
  if (!std::isfinite(options.clearance) || !(options.clearance >= 0.0)) {
    ThrowInvalid("spline clearance = " + FormatNumber(options.clearance) + " must be finite and >= 0");
  }
  if (!std::isfinite(options.max_deviation) || !(options.max_deviation > 0.0)) {
    ThrowInvalid("spline max_deviation = " + FormatNumber(options.max_deviation) + " must be finite and > 0");
  }
  if (options.algorithm != "slsqp" && options.algorithm != "mma") {
    ThrowInvalid("spline algorithm = '" + options.algorithm + "' must be 'slsqp' or 'mma'");
  }
  if (options.max_evaluations < 1) {
    ThrowInvalid("spline max_evaluations = " + std::to_string(options.max_evaluations) + " must be >= 1");
  }
  if (!std::isfinite(options.time_budget) || !(options.time_budget > 0.0)) {
    ThrowInvalid("spline time_budget = " + FormatNumber(options.time_budget) + " must be finite and > 0");
  }
}

/// One span per piece of positive duration of the warm start (whose pieces are its phases:
/// accelerate, cruise, blend, brake), within [8, 30], plus the degree.
int DefaultControlPoints(const TimedTrajectory& initial, int degree) {
  int pieces = 0;
  for (const TimedTrajectory::Piece& piece : initial.pieces()) pieces += piece.duration > 0.0 ? 1 : 0;
  return std::max(std::min(pieces, 30), 8) + degree;
}

/// Least-squares fit of the free control points to samples of `initial` at the knots of
/// `delta` (kFitSamplesPerSpan per span); the fixed and derived ones as the layout says.
Eigen::MatrixXd FitControlPoints(const Layout& layout, const TimedTrajectory& initial, const Eigen::VectorXd& delta) {
  const int n = layout.num_dofs, k = layout.num_control_points, m = layout.num_spans(), p = layout.degree;
  std::vector<double> x(layout.num_variables(), 0.0);
  for (int j = 0; j < m; ++j) x[layout.SpanVariable(j)] = delta[j];
  Eigen::MatrixXd control;
  Eigen::VectorXd unused;
  layout.Unpack(x.data(), &control, &unused);
  const int free = layout.free_per_joint();
  if (free <= 0) return control;
  const Eigen::VectorXd knots = spline::ClampedKnots(p, delta);
  const int rows = m * kFitSamplesPerSpan;
  Eigen::MatrixXd basis(rows, k), target(rows, n);
  Eigen::VectorXd values(k);
  for (int j = 0; j < m; ++j) {
    for (int s = 0; s < kFitSamplesPerSpan; ++s) {
      const int r = j * kFitSamplesPerSpan + s;
      const double t = knots[p + j] + (s + 0.5) / kFitSamplesPerSpan * delta[j];
      spline::BasisFunctions(p, knots, t, values.data());
      basis.row(r) = values.transpose();
      target.row(r) = initial.Evaluate(t).q.transpose();
    }
  }
  const int first = layout.first_free();
  Eigen::MatrixXd fixed_control = control;
  fixed_control.middleCols(first, free).setZero();
  const Eigen::MatrixXd rhs = target - basis * fixed_control.transpose();
  const Eigen::MatrixXd solution = basis.middleCols(first, free).colPivHouseholderQr().solve(rhs);  // free × n
  control.middleCols(first, free) = solution.transpose();
  return control;
}

/// max over the limited orders r of (maxᵢ |C⁽ʳ⁾ᵢ|/limit)^(1/r): the factor by which scaling every
/// span duration puts the derivative control points exactly on their limits.
double HodographScale(const Layout& layout, const KinematicLimits& limits, const Eigen::MatrixXd& control,
                      const Eigen::VectorXd& delta) {
  const int k = layout.num_control_points;
  JointSpline spline(layout.degree, k, 0);
  const spline::RowMajorMatrix no_seeds;
  double scale = 0.0;
  Eigen::VectorXd row(k);
  for (int d = 0; d < layout.num_dofs; ++d) {
    row = control.row(d).transpose();
    spline.Compute(row.data(), no_seeds, delta, 0);
    const int max_order = limits.max_jerk.size() != 0 ? 3 : 2;
    for (int r = 1; r <= max_order; ++r) {
      const double limit = r == 1 ? limits.max_velocity[d] : (r == 2 ? limits.max_acceleration[d] : limits.max_jerk[d]);
      const Eigen::VectorXd& points = spline.hodograph(r);
      for (int i = 0; i < points.size(); ++i) {
        // A moving end's own velocity does not scale (and is the caller's to keep in limits).
        if (r == 1 && ((i == 0 && !layout.start_at_rest) || (i == k - 2 && !layout.end_at_rest))) continue;
        scale = std::max(scale, std::pow(std::abs(points[i]) / limit, 1.0 / r));
      }
    }
  }
  return scale;
}

/// Exact max |q⁽ʳ⁾ᵢ|/limitᵢ over the pieces, as the time scale that brings it to 1 (>= 1).
double RequiredTimeScale(const TimedTrajectory& trajectory, const KinematicLimits& limits, std::string* worst) {
  double scale = 1.0;
  const char* names[4] = {"", "velocity", "acceleration", "jerk"};
  for (const TimedTrajectory::Piece& piece : trajectory.pieces()) {
    for (int i = 0; i < piece.coefficients.rows(); ++i) {
      const Eigen::VectorXd c = piece.coefficients.row(i).transpose();
      const int max_order = limits.max_jerk.size() != 0 ? 3 : 2;
      for (int r = 1; r <= max_order; ++r) {
        const double limit = r == 1 ? limits.max_velocity[i] : (r == 2 ? limits.max_acceleration[i] : limits.max_jerk[i]);
        const double ratio = poly::MaxAbsDerivative(c.data(), static_cast<int>(c.size()), r, piece.duration) / limit;
        const double needed = std::pow(ratio, 1.0 / r);
        if (needed > scale) {
          scale = needed;
          *worst = "joint " + std::to_string(i) + " " + names[r] + " at " + FormatNumber(ratio) + " of its limit";
        }
      }
    }
  }
  return scale;
}

/// The clearance the result must keep at span j, fraction f: options.clearance, or less where
/// the warm start itself comes closer within one span (of the fit's uniform spans over its
/// duration T₀) of the corresponding time (j + f)·T₀/m — a start next to an obstacle does not
/// make the problem infeasible, and the spline may run a little ahead of or behind the warm
/// start.
class ClearanceRule {
 public:
  ClearanceRule(const CollisionChecker& checker, const TimedTrajectory& initial, int num_spans, double clearance)
      : clearance_(clearance) {
    const int points = kRuleGrid * num_spans;
    grid_.resize(points + 1);
    for (int g = 0; g <= points; ++g) {
      grid_[g] = checker.Clearance(initial.Evaluate(initial.duration() * g / points).q);
    }
  }

  double Required(int span, double fraction) const {
    const double u = (span + fraction) * kRuleGrid;
    const int last = static_cast<int>(grid_.size()) - 1;
    const int lo = std::max(0, static_cast<int>(std::floor(u)) - kRuleGrid);
    const int hi = std::min(last, static_cast<int>(std::ceil(u)) + kRuleGrid);
    double nearest = clearance_;
    for (int g = lo; g <= hi; ++g) nearest = std::min(nearest, grid_[g]);
    return nearest;
  }

 private:
  static constexpr int kRuleGrid = 16;  // warm-start states per span
  double clearance_;
  std::vector<double> grid_;
};

/// The worst clearance shortfall per span of `trajectory` (one piece per span), at states no
/// more than kCheckStep of joint travel and kCheckPeriod apart. Returns the number of spans
/// with a state closer than required; `worst` gets (span, fraction) of each one's closest
/// shortfall, `summary` the overall worst.
int CheckClearance(const TimedTrajectory& trajectory, const CollisionChecker& checker, const ClearanceRule& rule,
                   std::vector<ClearanceSample>* worst, std::string* summary) {
  int spans = 0;
  double worst_gap = 0.0;
  const auto& pieces = trajectory.pieces();
  for (std::size_t j = 0; j < pieces.size(); ++j) {
    const TimedTrajectory::Piece& piece = pieces[j];
    const int states =
        std::max(1, static_cast<int>(std::ceil(std::max(piece.MaxJointTravel() / kCheckStep, piece.duration / kCheckPeriod))));
    double span_gap = 0.0, span_fraction = 0.0;
    Eigen::VectorXd q(piece.coefficients.rows());
    for (int s = 0; s <= states; ++s) {
      const double fraction = static_cast<double>(s) / states;
      const double tau = fraction * piece.duration;
      for (int i = 0; i < q.size(); ++i) {
        const Eigen::VectorXd c = piece.coefficients.row(i).transpose();
        q[i] = poly::Eval(c.data(), static_cast<int>(c.size()), tau);
      }
      const double required = rule.Required(static_cast<int>(j), fraction);
      const double have = checker.Clearance(q);
      const double gap = required - have;
      if (gap > span_gap) {
        span_gap = gap;
        span_fraction = fraction;
      }
      if (gap > worst_gap) {
        worst_gap = gap;
        *summary = "clearance " + FormatNumber(have) + " m is below the required " + FormatNumber(required) +
                   " m at t = " + FormatNumber(piece.t0 + tau) + " s";
      }
    }
    if (span_gap > 0.0) {
      ++spans;
      worst->push_back(ClearanceSample{static_cast<int>(j), span_fraction, 0.0, 0.0});
    }
  }
  return spans;
}

/// A point the result can be made of: its limits met after slowing it by `scale` (at most
/// kMaxRoundingScale) and every clearance sample at its required distance.
struct Candidate {
  std::vector<double> x;
  double scale = 1.0;
  double objective = std::numeric_limits<double>::infinity();  ///< after the scaling
  bool found() const { return !x.empty(); }
};

/// What the NLopt callbacks share: the problem, a one-point cache (NLopt asks for the
/// objective and the constraints at the same x one after the other), the best candidate
/// seen, the evaluation count and the stop request.
struct SolveContext {
  Problem* problem = nullptr;
  const std::function<bool()>* stop = nullptr;
  double max_scale = kMaxRoundingScale;  ///< the largest slow-down a candidate may need
  int evaluations = 0;
  bool stopped = false;

  std::vector<double> x;
  bool has_gradient = false;
  double objective = 0.0;
  std::vector<double> gradient, constraints, jacobian;

  Candidate best;

  void At(const double* point, bool need_gradient) {
    if (*stop && (*stop)()) {
      stopped = true;
      throw nlopt::forced_stop();
    }
    const int n = problem->num_variables(), m = problem->num_constraints();
    if (!x.empty() && std::equal(x.begin(), x.end(), point) && (has_gradient || !need_gradient)) return;
    x.assign(point, point + n);
    constraints.resize(m);
    gradient.resize(n);
    jacobian.resize(static_cast<std::size_t>(m) * n);
    objective = problem->Evaluate(point, constraints.data(), need_gradient ? gradient.data() : nullptr,
                                  need_gradient ? jacobian.data() : nullptr);
    has_gradient = need_gradient;
    // SLSQP and MMA end on a point that meets the constraints only to their own tolerance;
    // a slight excess over the limits is removed by slowing down, which changes no clearance.
    const Problem::Figures& figures = problem->figures();
    const double scale = std::max(1.0, figures.hull_scale);
    if (scale <= max_scale && figures.clearance_shortfall <= kClearanceTolerance) {
      const double scaled = problem->ScaledObjective(scale);
      if (scaled < best.objective) best = Candidate{x, scale, scaled};
    }
  }
};

double ObjectiveCallback(unsigned n, const double* x, double* grad, void* data) {
  auto* context = static_cast<SolveContext*>(data);
  ++context->evaluations;
  context->At(x, grad != nullptr);
  if (grad != nullptr) std::copy(context->gradient.begin(), context->gradient.begin() + n, grad);
  return context->objective;
}

void ConstraintCallback(unsigned m, double* result, unsigned n, const double* x, double* grad, void* data) {
  auto* context = static_cast<SolveContext*>(data);
  context->At(x, grad != nullptr);
  std::copy(context->constraints.begin(), context->constraints.begin() + m, result);
  if (grad != nullptr) {
    std::copy(context->jacobian.begin(), context->jacobian.begin() + static_cast<std::size_t>(m) * n, grad);
  }
}

std::string ResultName(nlopt::result result) {
  return std::string("NLOPT_") + nlopt_result_to_string(static_cast<nlopt_result>(result));
}

}  // namespace

SplineResult SmoothWithBSpline(const TimedTrajectory& initial, const KinematicLimits& limits,
                               const SplineOptions& options, const CollisionChecker* checker) {
  ValidateOptions(options);
  if (initial.empty()) ThrowInvalid("spline initial trajectory is empty");
  const int n = initial.num_dofs();
  limits.Validate(n);
  if (checker != nullptr && checker->robot().num_dofs() != n) {
    ThrowInvalid("spline initial trajectory has " + std::to_string(n) + " joints, the checker's robot has " +
                 std::to_string(checker->robot().num_dofs()));
  }
  if (options.control_points != 0 && options.control_points < 6 && limits.max_jerk.size() != 0) {
    ThrowInvalid("spline control_points = " + std::to_string(options.control_points) +
                 " must be >= 6 with max_jerk set (three control points at each end at rest, for a zero "
                 "acceleration there)");
  }
  if (checker != nullptr && limits.max_effort.size() != 0 && !HasInertia(checker->robot())) {
    ThrowInvalid("max_effort needs a robot with inertia on every moving link");  // as VerifyTrajectory
  }
  for (std::size_t k = 0; k < initial.pieces().size(); ++k) {
    const TimedTrajectory::Piece& piece = initial.pieces()[k];
    if (!piece.coefficients.allFinite() || !std::isfinite(piece.duration) || !(piece.duration >= 0.0)) {
      ThrowInvalid("spline initial trajectory piece " + std::to_string(k) +
                   " has a non-finite coefficient or an invalid duration");
    }
  }

  const Clock::time_point started = Clock::now();
  SplineResult result;
  OptimizerReport& report = result.report;
  const double initial_duration = initial.duration();
  const TrajectorySample first = initial.Evaluate(0.0);
  const TrajectorySample last = initial.Evaluate(initial_duration);
  if (!(initial_duration > 0.0)) {
    result.trajectory = initial;
    report.ok = true;
    report.status = "NO_MOTION";
    report.message = "the initial trajectory does not move: returned as it is";
    return result;
  }

  // Layout: start and end states of the warm start; an end at rest also gets zero acceleration
  // when K >= 6.
  Layout layout;
  layout.num_dofs = n;
  layout.degree = options.degree;
  layout.num_control_points =
      options.control_points != 0 ? options.control_points : DefaultControlPoints(initial, options.degree);
  layout.start = first.q;
  layout.goal = last.q;
  const double rest = 1e-12 * std::max(1.0, limits.max_velocity.maxCoeff());
  layout.start_at_rest = first.qd.cwiseAbs().maxCoeff() <= rest;
  layout.end_at_rest = last.qd.cwiseAbs().maxCoeff() <= rest;
  layout.start_velocity = layout.start_at_rest ? Eigen::VectorXd::Zero(n) : first.qd;
  layout.end_velocity = layout.end_at_rest ? Eigen::VectorXd::Zero(n) : last.qd;
  layout.zero_rest_acceleration = layout.num_control_points >= 6;
  const int m = layout.num_spans();

  // Warm start: least squares on uniform spans over the initial duration, then every span
  // scaled so the derivative control points sit on their limits (exact at once with the ends
  // at rest; a moving end's velocity does not scale, so repeat).
  Eigen::VectorXd delta = Eigen::VectorXd::Constant(m, initial_duration / m);
  Eigen::MatrixXd control = FitControlPoints(layout, initial, delta);
  for (int pass = 0; pass < 100; ++pass) {
    const double scale = HodographScale(layout, limits, control, delta) / (1.0 - spline::kLimitMargin);
    if (!(scale > 0.0) || !std::isfinite(scale) || std::abs(scale - 1.0) <= 1e-12) break;
    delta *= scale;
    std::vector<double> x = layout.Pack(control, delta);
    Eigen::VectorXd unused;
    layout.Unpack(x.data(), &control, &unused);
  }
  const double warm_duration = delta.sum();

  // Bounds: control points within max_deviation of the fit and within the joint limits;
  // spans between 1e-3 of their warm value and the whole warm duration.
  const int num_variables = layout.num_variables();
  std::vector<double> lower(num_variables), upper(num_variables);
  for (int d = 0; d < n; ++d) {
    const double lo_limit = checker != nullptr ? checker->robot().lower_limits()[d] : -std::numeric_limits<double>::infinity();
    const double hi_limit = checker != nullptr ? checker->robot().upper_limits()[d] : std::numeric_limits<double>::infinity();
    for (int i = layout.first_free(); i <= layout.last_free(); ++i) {
      const int v = layout.ControlVariable(d, i);
      const double fit = std::min(std::max(control(d, i), lo_limit), hi_limit);
      control(d, i) = fit;
      lower[v] = std::max(fit - options.max_deviation, lo_limit);
      upper[v] = std::min(fit + options.max_deviation, hi_limit);
    }
  }
  for (int j = 0; j < m; ++j) {
    lower[layout.SpanVariable(j)] = 1e-3 * delta[j];
    upper[layout.SpanVariable(j)] = warm_duration;
  }
  std::vector<double> x = layout.Pack(control, delta);

  // Clearance: only with obstacles. Samples every kSampleStep of the warm start's joint travel.
  const bool obstacles =
      checker != nullptr && (!checker->scene().objects().empty() || !checker->scene().occupancy_maps().empty());
  std::unique_ptr<ObstacleProximity> proximity;
  std::unique_ptr<ClearanceRule> rule;
  spline::ClearanceSetup clearance;
  if (obstacles) {
    proximity = std::make_unique<ObstacleProximity>(
        checker->robot_ptr(), std::shared_ptr<const Scene>(std::shared_ptr<const Scene>(), &checker->scene()));
    rule = std::make_unique<ClearanceRule>(*checker, initial, m, options.clearance);
    clearance.proximity = proximity.get();
    clearance.query_range = options.clearance + 0.5;
    // The checker's padding: its clearance is the proximity distance minus this offset.
    const std::vector<LinkProximity> near = proximity->Query(layout.start, clearance.query_range);
    double nearest = std::numeric_limits<double>::infinity();
    for (const LinkProximity& link : near) nearest = std::min(nearest, link.distance);
    const double checker_clearance = checker->Clearance(layout.start);
    if (std::isfinite(nearest) && std::isfinite(checker_clearance)) clearance.offset = nearest - checker_clearance;
    const TimedTrajectory warm = Problem(layout, limits, 0.0, {}).Trajectory(x.data());
    for (int j = 0; j < m; ++j) {
      const int count = std::min(kMaxSamplesPerSpan,
                                 std::max(2, static_cast<int>(std::ceil(warm.pieces()[j].MaxJointTravel() / kSampleStep))));
      for (int s = 0; s < count; ++s) clearance.samples.push_back(ClearanceSample{j, (s + 0.5) / count, 0.0, 0.0});
    }
  }
  auto set_targets = [&](std::vector<ClearanceSample>* samples) {
    for (ClearanceSample& sample : *samples) {
      sample.required = rule->Required(sample.span, sample.fraction);
      sample.target = sample.required + std::min(kClearanceMargin, 0.1 * sample.required);
    }
  };
  if (obstacles) set_targets(&clearance.samples);

  // Solve; with obstacles, check the chosen point's clearance densely and solve again from it
  // with the worst state of every short span added as a sample.
  nlopt::result outcome = nlopt::FAILURE;
  std::string failure;
  int evaluations = 0;
  bool stopped = false;
  Candidate chosen;                  // the best candidate of the latest round that found one
  std::unique_ptr<Problem> problem;  // of the latest round
  std::string clearance_summary;     // non-empty when `chosen` comes too close somewhere
  for (int round = 0; round < kMaxClearanceRounds; ++round) {
    problem = std::make_unique<Problem>(layout, limits, options.jerk_weight, clearance);
    SolveContext context;
    context.problem = problem.get();
    context.stop = &options.stop;
    context.max_scale = layout.start_at_rest && layout.end_at_rest ? kMaxRoundingScale : kMaxMovingEndScale;
    nlopt::opt opt(options.algorithm == "mma" ? nlopt::LD_MMA : nlopt::LD_SLSQP, static_cast<unsigned>(num_variables));
    opt.set_lower_bounds(lower);
    opt.set_upper_bounds(upper);
    opt.set_min_objective(ObjectiveCallback, &context);
    const int num_constraints = problem->num_constraints();
    if (num_constraints > 0) {
      opt.add_inequality_mconstraint(ConstraintCallback, &context,
                                     std::vector<double>(num_constraints, kConstraintTolerance));
    }
    if (options.algorithm == "mma") {
      // NLopt's MMA solves a dual over the constraints (hundreds here) to 1e-14 by default.
      opt.set_param("dual_ftol_rel", 1e-8);
      opt.set_param("dual_maxeval", 1000);
      opt.set_param("inner_maxeval", 20);
    }
    // No ftol: steps that move only control points leave ΣΔ unchanged, which NLopt's SLSQP
    // would take for convergence.
    opt.set_xtol_rel(kRelativeTolerance);
    opt.set_maxeval(std::max(1, options.max_evaluations - evaluations));
    opt.set_maxtime(std::max(1e-3, options.time_budget - Seconds(started)));
    double value = 0.0;
    try {
      outcome = opt.optimize(x, value);
    } catch (const nlopt::forced_stop&) {
      outcome = nlopt::FORCED_STOP;
    } catch (const nlopt::roundoff_limited&) {
      outcome = nlopt::ROUNDOFF_LIMITED;  // the best point so far is usually fine
    } catch (const std::invalid_argument& e) {
      outcome = nlopt::INVALID_ARGS;
      failure = e.what();
    } catch (const std::bad_alloc&) {
      outcome = nlopt::OUT_OF_MEMORY;
    } catch (const std::runtime_error& e) {
      outcome = nlopt::FAILURE;
      failure = e.what();
    }
    evaluations += context.evaluations;
    stopped = context.stopped;
    if (stopped || (outcome < 0 && outcome != nlopt::ROUNDOFF_LIMITED) || !context.best.found()) break;
    chosen = std::move(context.best);
    clearance_summary.clear();
    if (!obstacles) break;
    std::vector<ClearanceSample> worst;
    if (CheckClearance(problem->Trajectory(chosen.x.data()), *checker, *rule, &worst, &clearance_summary) == 0) break;
    if (evaluations >= options.max_evaluations || Seconds(started) >= options.time_budget) break;
    set_targets(&worst);
    clearance.samples.insert(clearance.samples.end(), worst.begin(), worst.end());
    x = chosen.x;
  }

  report.status = stopped ? "NLOPT_FORCED_STOP" : ResultName(outcome);
  report.iterations = evaluations;
  auto finish = [&](bool ok, const std::string& message) {
    report.ok = ok;
    report.message = message;
    report.solve_seconds = Seconds(started);
    if (!ok) result.trajectory = TimedTrajectory();
    return result;
  };
  if (stopped) return finish(false, "stopped on request after " + std::to_string(evaluations) + " evaluations");
  if (outcome < 0 && outcome != nlopt::ROUNDOFF_LIMITED) {
    return finish(false, "NLopt failed (" + report.status + (failure.empty() ? "" : ": " + failure) + ")");
  }
  {
    const std::vector<double>& at = chosen.found() ? chosen.x : x;
    std::vector<double> constraints(problem->num_constraints());
    report.objective = problem->Evaluate(at.data(), constraints.data(), nullptr, nullptr);
    report.constraint_violation =
        constraints.empty() ? 0.0 : std::max(0.0, *std::max_element(constraints.begin(), constraints.end()));
  }
  if (!chosen.found()) {
    return finish(false, "no point within the limits and the clearance found in " + std::to_string(evaluations) +
                             " evaluations (largest constraint violation " +
                             FormatNumber(report.constraint_violation) + ")");
  }
  if (!clearance_summary.empty()) return finish(false, clearance_summary);
  report.objective = chosen.objective;

  // Exact limits of the pieces: the hull bounds them by chosen.scale, usually with room.
  TimedTrajectory trajectory = problem->Trajectory(chosen.x.data());
  std::string worst;
  const double scale = RequiredTimeScale(trajectory, limits, &worst);
  if (scale > kMaxRoundingScale) return finish(false, "the spline exceeds the limits (" + worst + ")");
  // (With a moving end chosen.scale <= kMaxMovingEndScale, and scale <= chosen.scale.)
  if (scale > 1.0) {
    trajectory = trajectory.TimeScaled(scale);
    report.time_scale = scale;
  }
  if (checker != nullptr) {
    VerificationOptions verification;
    if (!layout.start_at_rest) verification.start_velocity = layout.start_velocity;
    if (!layout.end_at_rest) verification.end_velocity = layout.end_velocity;
    const VerificationReport verified =
        VerifyTrajectory(trajectory, layout.start, layout.goal, *checker, limits, verification);
    if (!verified.ok) return finish(false, "the spline fails verification: " + verified.reason);
  }
  result.trajectory = std::move(trajectory);
  return finish(true, "B-spline of degree " + std::to_string(options.degree) + " with " +
                          std::to_string(layout.num_control_points) + " control points: " +
                          FormatNumber(result.trajectory.duration()) + " s (warm start " +
                          FormatNumber(initial_duration) + " s) after " + std::to_string(evaluations) +
                          " evaluations");
}

}  // namespace chasles
