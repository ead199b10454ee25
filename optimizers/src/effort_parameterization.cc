#include "effort_parameterization.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "chasles/robot/error.h"

namespace chasles::detail {
namespace {

using Piece = TimedTrajectory::Piece;
constexpr double kInf = std::numeric_limits<double>::infinity();
/// Backward/forward passes at most: margins and damping tangents are refined between them.
constexpr int kMaxSolves = 10;
/// Tangent point floor for the damping bound [(rad/s)²]: √x ≤ (x + x₀)/(2√x₀) for any x₀ > 0.
constexpr double kMinTangent = 1e-4;
/// Passes after which the damping tangents are no longer moved to the last profile's speeds:
/// one re-solve at the first profile's speeds (a third pass changed no bench ratio in its fourth
/// digit and cost 8 % of the instructions on the shelf path).
constexpr int kTangentSolves = 1;
/// Knots of the interpolant that bounds damping where it takes torque away.
constexpr int kDampingKnots = 6;
/// Share of each torque limit the passes use: the rest absorbs the tolerance of the exact 2-D
/// solutions, so the returned torques meet the limits themselves.
constexpr double kLimitShare = 1.0 - 1e-9;
/// Where the tangent of a section jumps by more than this, the motion stops there.
constexpr double kTangentJump = 1e-9;

/// a·u + b·x ≤ c.
struct Row {
  double a, b, c;
};

/// The path and its torque coefficients at grid nodes, one column per node: q, q′, q″ and the
/// rigid-body τ = a·u + b·x + c (no allocation per node).
class Nodes {
 public:
  Nodes(int dofs, int count) : q(dofs, count), d1(dofs, count), d2(dofs, count), a(dofs, count), b(dofs, count), c(dofs, count) {}

  /// Node `k` at parameter s of the section.
  void Set(int k, const PathSection& section, double s, const RobotModel& robot, const Eigen::Vector3d& gravity) {
    q.col(k) = section.p0 + s * section.p1 + (s * s) * section.p2;
    d1.col(k) = section.p1 + (2.0 * s) * section.p2;
    d2.col(k) = 2.0 * section.p2;
    column_q_ = q.col(k);
    column_d1_ = d1.col(k);
    column_d2_ = d2.col(k);
    PathTorqueCoefficients(robot, column_q_, column_d1_, column_d2_, gravity, &torque_);
    a.col(k) = torque_.a;
    b.col(k) = torque_.b;
    c.col(k) = torque_.c;
  }

  Eigen::MatrixXd q, d1, d2, a, b, c;

 private:
  Eigen::VectorXd column_q_, column_d1_, column_d2_;
  PathTorque torque_;
};

struct Interval {
  int section = 0;
  double s0 = 0.0, h = 0.0;  // local start and length on its section
  double at = 0.0;           // start along the whole path [rad of path]
  int n0 = 0, n1 = 0, mid = 0;  // nodes: start, end, midpoint
  double x_velocity = kInf;  // velocity limit on x over the interval
  double u_bound = 0.0;      // |u| allowed by the acceleration limits at x ≤ x_velocity
  bool straight = false;     // q″ = 0 at both ends: the acceleration limits are |u| ≤ u_bound
  Eigen::VectorXd coulomb_hi, coulomb_lo;  // Coulomb torque bounds over the interval
  Eigen::VectorXd margin;                  // per joint, taken off both torque limits [N·m]
};

int Sign(double v) { return v > 0.0 ? 1 : (v < 0.0 ? -1 : 0); }

/// The range [lo, hi] of x over the polygon {(u, x) : rows}; false when it is empty. Rows with
/// a = 0 bound x directly; the others give u ≤ U(x) (a > 0, concave) and u ≥ L(x) (a < 0,
/// convex), so the gap U − L is concave and piecewise linear, and its roots are found exactly by
/// Newton steps on its active pieces from the direct bounds inwards.
class XRange {
 public:
  /// Takes the rows (the line buffers are kept between calls).
  void Load(const std::vector<Row>& rows) {
    upper_.clear();
    lower_.clear();
    xlo_ = 0.0;
    xhi_ = kInf;
    empty_ = false;
    for (const Row& r : rows) {
      if (r.a > 0.0) {
        upper_.push_back({r.c / r.a, r.b / r.a});
      } else if (r.a < 0.0) {
        lower_.push_back({r.c / r.a, r.b / r.a});
      } else if (r.b > 0.0) {
        xhi_ = std::min(xhi_, r.c / r.b);
      } else if (r.b < 0.0) {
        xlo_ = std::max(xlo_, r.c / r.b);
      } else if (r.c < -Tolerance(r.c)) {
        empty_ = true;
      }
    }
  }

  bool Solve(double* lo, double* hi) const {
    if (empty_ || !(xhi_ >= xlo_ - Tolerance(xhi_))) return false;
    const double top = std::max(xhi_, xlo_);
    if (!std::isfinite(top)) return false;  // callers always bound x from above
    return Root(top, -1, hi) && Root(xlo_, +1, lo);
  }

  /// u ∈ [L(x), U(x)] at x.
  void URange(double x, double* lower, double* upper) const {
    double slope;
    *upper = Upper(x, &slope);
    *lower = Lower(x, &slope);
  }

 private:
  struct Line {
    double p, q;  // u = p − q·x
  };
  static double Tolerance(double v) { return 1e-10 * (1.0 + std::abs(v)); }

  double Upper(double x, double* slope) const {
    double best = kInf;
    *slope = 0.0;
    for (const Line& l : upper_) {
      const double u = l.p - l.q * x;
      if (u < best) {
        best = u;
        *slope = -l.q;
      }
    }
    return best;
  }
  double Lower(double x, double* slope) const {
    double best = -kInf;
    *slope = 0.0;
    for (const Line& l : lower_) {
      const double u = l.p - l.q * x;
      if (u > best) {
        best = u;
        *slope = -l.q;
      }
    }
    return best;
  }

  /// From x = start, moving in `direction` (−1: down from the upper end, +1: up from the lower
  /// one), the first x where U(x) ≥ L(x), within the direct bounds.
  bool Root(double start, int direction, double* out) const {
    double x = start;
    for (int it = 0; it < 200; ++it) {
      double su, sl;
      const double upper = Upper(x, &su), lower = Lower(x, &sl);
      const double gap = upper - lower;
      if (!(gap < 0.0) || -gap <= Tolerance(std::max(std::abs(upper), std::abs(lower)))) {
        *out = x;
        return true;
      }
      const double slope = su - sl;  // of the active piece of the gap
      if (!(slope * direction > 0.0)) return false;  // it only falls further that way
      const double next = x - gap / slope;
      if (next < xlo_ - Tolerance(xlo_) || next > xhi_ + Tolerance(xhi_) || next == x) return false;
      x = std::min(std::max(next, xlo_), std::max(xhi_, xlo_));
    }
    return false;
  }

  std::vector<Line> upper_, lower_;
  double xlo_ = 0.0, xhi_ = kInf;
  bool empty_ = false;
};

}  // namespace

TimedTrajectory RetimeUnderEffort(const std::vector<PathSection>& sections, const KinematicLimits& limits,
                                  const RobotModel& robot, const DynamicsOptions& dynamics, double start_speed,
                                  double end_speed, double grid_step, EffortRetimeReport* report) {
  const int n = robot.num_dofs();
  EffortRetimeReport local;
  EffortRetimeReport& out = report != nullptr ? *report : local;
  out = EffortRetimeReport();
  std::vector<JointFriction> friction(n);
  if (dynamics.include_friction) {
    for (int j = 0; j < n; ++j) friction[j] = DofFriction(robot, j);
  }

  // The grid: intervals of at most grid_step along each section, nodes at their ends and
  // midpoints (a section's intervals share their end nodes).
  const auto intervals_on = [&](const PathSection& section) {
    return std::max(1, static_cast<int>(std::ceil(section.length / grid_step)));
  };
  int count = 0;
  for (const PathSection& section : sections) {
    if (section.length > 0.0) count += 1 + 2 * intervals_on(section);
  }
  Nodes nodes(n, count);
  std::vector<Interval> intervals;
  std::vector<int> stops;  // intervals whose start must be at rest (the tangent jumps there)
  double along = 0.0;
  int next_node = 0;
  for (std::size_t k = 0; k < sections.size(); ++k) {
    const PathSection& section = sections[k];
    if (!(section.length > 0.0)) continue;
    const int m = intervals_on(section);
    if (!intervals.empty()) {
      const double jump = (nodes.d1.col(intervals.back().n1) - section.p1).norm();
      if (jump > kTangentJump * std::max(1.0, section.p1.norm())) stops.push_back(static_cast<int>(intervals.size()));
    }
    nodes.Set(next_node++, section, 0.0, robot, dynamics.gravity);
    for (int i = 0; i < m; ++i) {
      Interval iv;
      iv.section = static_cast<int>(k);
      iv.s0 = section.length * i / m;
      const double s1 = i + 1 == m ? section.length : section.length * (i + 1) / m;
      iv.h = s1 - iv.s0;
      iv.at = along + iv.s0;
      iv.n0 = next_node - 1;
      iv.mid = next_node;
      nodes.Set(next_node++, section, iv.s0 + 0.5 * iv.h, robot, dynamics.gravity);
      iv.n1 = next_node;
      nodes.Set(next_node++, section, s1, robot, dynamics.gravity);
      intervals.push_back(std::move(iv));
    }
    along += section.length;
  }
  const int N = static_cast<int>(intervals.size());
  out.grid_intervals = N;
  if (N == 0) ThrowInvalid("the path to retime has no length");
  std::vector<char> stop(N + 1, 0);  // per grid point: must be at rest
  for (int i : stops) stop[i] = 1;
  std::vector<char> rest = stop;  // per grid point: may be at rest
  rest[0] = start_speed == 0.0;
  rest[N] = end_speed == 0.0;

  // Holding still must be possible everywhere.
  for (const Interval& iv : intervals) {
    for (int e : {iv.n0, iv.mid, iv.n1}) {
      for (int j = 0; j < n; ++j) {
        const double hold = nodes.c(j, e);
        if (std::abs(hold) > limits.max_effort[j]) {
          const double s = e == iv.n0 ? iv.at : (e == iv.n1 ? iv.at + iv.h : iv.at + 0.5 * iv.h);
          throw Error(ErrorCode::kFailedPrecondition,
                      "max_effort cannot be met: joint " + std::to_string(j) + " '" + robot.dof_names()[j] +
                          "' needs " + FormatNumber(hold) + " N·m to hold the robot still at s = " + FormatNumber(s) +
                          " rad along the path, above its limit " + FormatNumber(limits.max_effort[j]));
        }
      }
    }
  }
  // Per interval: the velocity limit (|q′ᵢ| is largest at an end: linear in s), the Coulomb
  // torque's bounds, the acceleration bound on u and the a-priori margin.
  for (int i = 0; i < N; ++i) {
    Interval& iv = intervals[i];
    const int A = iv.n0, B = iv.n1, M = iv.mid;
    iv.coulomb_hi = Eigen::VectorXd::Zero(n);
    iv.coulomb_lo = Eigen::VectorXd::Zero(n);
    iv.margin = Eigen::VectorXd::Zero(n);
    for (int j = 0; j < n; ++j) {
      const double speed = std::max(std::abs(nodes.d1(j, A)), std::abs(nodes.d1(j, B)));
      if (speed > 0.0) {
        iv.x_velocity = std::min(iv.x_velocity, limits.max_velocity[j] * limits.max_velocity[j] / (speed * speed));
      }
      const double f = friction[j].friction;
      const int sa = Sign(nodes.d1(j, A)), sb = Sign(nodes.d1(j, B));
      if (sa == sb && sa != 0) {
        // At rest (an end of the interval) InverseDynamics has no Coulomb torque.
        const bool still = rest[i] || rest[i + 1];
        iv.coulomb_hi[j] = still ? std::max(0.0, f * sa) : f * sa;
        iv.coulomb_lo[j] = still ? std::min(0.0, f * sa) : f * sa;
      } else {
        iv.coulomb_hi[j] = f;
        iv.coulomb_lo[j] = -f;
      }
    }
    if (!std::isfinite(iv.x_velocity)) iv.x_velocity = 1e12;
    // The margin: twice the largest gap between the rigid torque at the midpoint and its ends'
    // mean that any (u, x) within the limits could give (|u| by the acceleration limits at
    // x ≤ the velocity limit): with x linear in s, the gap is
    // (a_m − ā)u + (b_m − b̄)x_m − (b₁ − b₀)(x₁ − x₀)/4 + (c_m − c̄), |x₁ − x₀| = 2h|u|.
    double u_bound = kInf;
    for (int node : {A, B}) {
      double at = kInf;
      for (int j = 0; j < n; ++j) {
        const double d1 = nodes.d1(j, node);
        if (d1 != 0.0) at = std::min(at, (limits.max_acceleration[j] + std::abs(nodes.d2(j, node)) * iv.x_velocity) / std::abs(d1));
      }
      u_bound = std::min(u_bound, at);
    }
    if (!std::isfinite(u_bound)) u_bound = 0.0;
    iv.u_bound = u_bound;
    iv.straight = nodes.d2.col(A).isZero(0.0) && nodes.d2.col(B).isZero(0.0);
    for (int j = 0; j < n; ++j) {
      const double gap = std::abs(nodes.a(j, M) - 0.5 * (nodes.a(j, A) + nodes.a(j, B))) * u_bound +
                         std::abs(nodes.b(j, M) - 0.5 * (nodes.b(j, A) + nodes.b(j, B))) * iv.x_velocity +
                         0.5 * std::abs(nodes.b(j, B) - nodes.b(j, A)) * iv.h * u_bound +
                         std::abs(nodes.c(j, M) - 0.5 * (nodes.c(j, A) + nodes.c(j, B)));
      iv.margin[j] = 2.0 * gap;
    }
  }

  // Tangent points of the damping bound, one per interval, so that on a straight interval the
  // bound — linear in x, and x linear in s — holds between its ends too (start: a quarter of
  // the velocity limit; then the interval's mean x of the last pass).
  std::vector<double> tangent(intervals.size());
  for (std::size_t i = 0; i < intervals.size(); ++i) tangent[i] = std::max(kMinTangent, 0.25 * intervals[i].x_velocity);

  std::vector<Row> rows;
  std::vector<XRange> ranges(intervals.size());  // per interval, its last rows
  // The rows of interval i in (u, x_i), with x_{i+1} = x_i + 2h·u in [klo, khi].
  const auto build_rows = [&](int i, double klo, double khi) {
    const Interval& iv = intervals[i];
    rows.clear();
    const double h2 = 2.0 * iv.h;
    rows.push_back({0.0, -1.0, 0.0});
    rows.push_back({-h2, -1.0, 0.0});
    rows.push_back({0.0, 1.0, iv.x_velocity});
    rows.push_back({h2, 1.0, iv.x_velocity});
    rows.push_back({h2, 1.0, khi});
    rows.push_back({-h2, -1.0, -klo});
    if (iv.straight) {  // q̈ = q′u at both ends
      rows.push_back({1.0, 0.0, iv.u_bound});
      rows.push_back({-1.0, 0.0, iv.u_bound});
    }
    // A torque row no (u, x) within |u| ≤ u_bound, 0 ≤ x ≤ x_velocity can violate is left out.
    const auto binding = [&](double a, double b, double c) {
      return std::abs(a) * iv.u_bound + std::max(b, 0.0) * iv.x_velocity > c;
    };
    for (int e = 0; e < 2; ++e) {
      const int node = e == 0 ? iv.n0 : iv.n1;
      const double shift = e == 0 ? 0.0 : h2;  // x_e = x + shift·u
      for (int j = 0; j < n; ++j) {
        // Acceleration q′u + q″x_e.
        const double aa = nodes.d1(j, node) + shift * nodes.d2(j, node), ab = nodes.d2(j, node);
        if (!iv.straight && (aa != 0.0 || ab != 0.0)) {
          rows.push_back({aa, ab, limits.max_acceleration[j]});
          rows.push_back({-aa, -ab, limits.max_acceleration[j]});
        }
        // Torque ±(a u + b x_e + c + Coulomb + k√x_e) ≤ τmax − margin, k = damping·q′.
        const double k = friction[j].damping * nodes.d1(j, node);
        const double ta = nodes.a(j, node), tb = nodes.b(j, node), tc = nodes.c(j, node);
        const double x0 = tangent[i];
        for (int side : {+1, -1}) {
          const double ks = side * k;
          const double coulomb = side > 0 ? iv.coulomb_hi[j] : -iv.coulomb_lo[j];
          const double room = kLimitShare * limits.max_effort[j] - iv.margin[j] - side * tc - coulomb;
          // ks·√x_e ≤ slope·x_e + offset on every row pushed.
          const auto push = [&](double slope, double offset) {
            const double bx = side * tb + slope;
            const Row row{side * ta + shift * bx, bx, room - offset};
            if (binding(row.a, row.b, row.c)) rows.push_back(row);
          };
          if (ks > 0.0) {  // √x below its tangent at x0
            push(ks / (2.0 * std::sqrt(x0)), 0.5 * ks * std::sqrt(x0));
          } else if (ks < 0.0) {
            // ks·√x is convex: below its interpolant through ṡ = 0, ½v₀, 0.9v₀, v₀, 1.1v₀ and the
            // velocity limit (v₀² the tangent point: the last pass's speed there), which is the
            // largest of its pieces' lines — narrow where the profile runs.
            const double top = std::sqrt(iv.x_velocity), v0 = std::sqrt(x0);
            double knots[kDampingKnots] = {0.0, 0.5 * v0, 0.9 * v0, v0, 1.1 * v0, top};
            double va = 0.0;
            for (int k = 1; k < kDampingKnots; ++k) {
              const double vb = std::min(knots[k], top);
              if (!(vb > va)) continue;
              const double slope = ks / (va + vb);  // through (va², ks·va) and (vb², ks·vb)
              push(slope, ks * va - slope * va * va);
              va = vb;
            }
          } else {
            push(0.0, 0.0);
          }
        }
      }
    }
  };

  // Exact torque of joint j at node k at x, u (friction included).
  const auto torque = [&](int k, int j, double x, double u) {
    const double qd = nodes.d1(j, k) * std::sqrt(std::max(0.0, x));
    return nodes.a(j, k) * u + nodes.b(j, k) * x + nodes.c(j, k) + friction[j].damping * qd +
           friction[j].friction * Sign(qd);
  };

  const bool damping =
      std::any_of(friction.begin(), friction.end(), [](const JointFriction& f) { return f.damping != 0.0; });
  std::vector<double> klo(N + 1), khi(N + 1), x(N + 1), u(N);
  const double x_start = start_speed * start_speed, x_end = end_speed * end_speed;
  for (int solve = 0;; ++solve) {
    ++out.solves;
    // Controllable sets, backwards.
    klo[N] = khi[N] = x_end;
    for (int i = N - 1; i >= 0; --i) {
      build_rows(i, klo[i + 1], khi[i + 1]);
      double lo, hi;
      ranges[i].Load(rows);
      const bool ok = ranges[i].Solve(&lo, &hi);
      if (!ok || (stop[i] && lo > 1e-12)) {
        throw Error(ErrorCode::kFailedPrecondition,
                    "max_effort cannot be met: no speed along the path at s = " + FormatNumber(intervals[i].at) +
                        " rad reaches the end within the torque, velocity and acceleration limits");
      }
      if (stop[i]) lo = hi = 0.0;
      klo[i] = lo;
      khi[i] = hi;
    }
    if (x_start > khi[0] * (1.0 + 1e-9) + 1e-12 || x_start < klo[0] * (1.0 - 1e-9) - 1e-12) {
      throw Error(ErrorCode::kFailedPrecondition,
                  "max_effort cannot be met: from the start speed " + FormatNumber(start_speed) +
                      " rad/s no motion along the path stays within the torque, velocity and acceleration limits");
    }
    // Greedy forward pass: the largest u that stays controllable.
    x[0] = std::min(std::max(x_start, klo[0]), khi[0]);
    for (int i = 0; i < N; ++i) {
      const Interval& iv = intervals[i];
      double lower, upper;
      ranges[i].URange(x[i], &lower, &upper);  // the backward pass's rows: the same K_{i+1}
      double next = x[i] + 2.0 * iv.h * std::max(lower, upper);
      next = std::min(std::max(next, klo[i + 1]), khi[i + 1]);
      if (stop[i + 1]) next = 0.0;
      x[i + 1] = std::max(0.0, next);
      u[i] = (x[i + 1] - x[i]) / (2.0 * iv.h);
    }
    // Check every interval's ends and midpoint with the exact torque; the midpoint's distance
    // from its ends' mean sets the margin for the curvature between grid points.
    bool ok = true;
    bool margins_grew = false;
    out.worst_effort = 0.0;
    for (int i = 0; i < N; ++i) {
      Interval& iv = intervals[i];
      const double xm = 0.5 * (x[i] + x[i + 1]);
      for (int j = 0; j < n; ++j) {
        const double limit = limits.max_effort[j];
        const double worst = std::max({std::abs(torque(iv.n0, j, x[i], u[i])), std::abs(torque(iv.n1, j, x[i + 1], u[i])),
                                       std::abs(torque(iv.mid, j, xm, u[i]))});
        out.worst_effort = std::max(out.worst_effort, worst / limit);
        const double rigid_gap = (nodes.a(j, iv.mid) - 0.5 * (nodes.a(j, iv.n0) + nodes.a(j, iv.n1))) * u[i] +
                                 nodes.b(j, iv.mid) * xm - 0.5 * (nodes.b(j, iv.n0) * x[i] + nodes.b(j, iv.n1) * x[i + 1]) +
                                 nodes.c(j, iv.mid) - 0.5 * (nodes.c(j, iv.n0) + nodes.c(j, iv.n1));
        // Covered while the margin holds the gap; else twice the gap.
        const double gap = std::abs(rigid_gap);
        if (gap > iv.margin[j]) {
          iv.margin[j] = 2.0 * gap;
          margins_grew = true;
        }
        if (worst > limit * (1.0 + 1e-12)) {
          ok = false;
          iv.margin[j] += 2.0 * (worst - limit);  // twice: the profile moves with the margin
          margins_grew = true;
        }
      }
    }
    // The damping tangents at this profile's speeds.
    bool tangents_moved = false;
    for (int i = 0; i < N; ++i) {
      const double want = std::max(kMinTangent, 0.5 * (x[i] + x[i + 1]));
      if (std::abs(want - tangent[i]) > 1e-3 * want) tangents_moved = true;
      tangent[i] = want;
    }
    if (ok && !margins_grew && (!damping || !tangents_moved || solve >= kTangentSolves)) break;
    if (solve + 1 >= kMaxSolves) {
      if (ok) break;
      throw Error(ErrorCode::kFailedPrecondition,
                  "max_effort cannot be met: after " + std::to_string(kMaxSolves) +
                      " passes a torque between grid points still exceeds its limit by a factor " +
                      FormatNumber(out.worst_effort));
    }
  }

  // One piece per interval: σ(t) = s0 + ṡ₀t + (u/2)t² on its section.
  std::vector<Piece> pieces;
  pieces.reserve(N);
  double t = 0.0;
  for (int i = 0; i < N; ++i) {
    const Interval& iv = intervals[i];
    const PathSection& section = sections[iv.section];
    const double v0 = std::sqrt(x[i]), v1 = std::sqrt(x[i + 1]);
    if (!(v0 + v1 > 0.0)) {
      throw Error(ErrorCode::kFailedPrecondition, "max_effort cannot be met: the motion stalls at s = " +
                                                      FormatNumber(iv.at) + " rad along the path");
    }
    // A piece that comes to rest ends a hair early (1e-12 of it), so its last velocity points
    // along the motion by about 1e-12 of its start speed instead of either way by rounding: a
    // reversed sign would turn the Coulomb friction against the motion there.
    const double duration = 2.0 * iv.h / (v0 + v1) * (x[i + 1] == 0.0 ? 1.0 - 1e-12 : 1.0);
    const double A = iv.s0, B = v0, C = 0.5 * u[i];
    Piece piece;
    piece.t0 = t;
    piece.duration = duration;
    const bool straight = section.p2.isZero(0.0);
    piece.coefficients.resize(n, straight ? 3 : 5);
    piece.coefficients.col(0) = section.p0 + A * section.p1 + (A * A) * section.p2;
    piece.coefficients.col(1) = B * section.p1 + (2.0 * A * B) * section.p2;
    piece.coefficients.col(2) = C * section.p1 + (B * B + 2.0 * A * C) * section.p2;
    if (!straight) {
      piece.coefficients.col(3) = (2.0 * B * C) * section.p2;
      piece.coefficients.col(4) = (C * C) * section.p2;
    }
    t += duration;
    pieces.push_back(std::move(piece));
  }
  const PathSection& last = sections[intervals.back().section];
  const Eigen::VectorXd end = last.p0 + last.length * last.p1 + (last.length * last.length) * last.p2;
  return TimedTrajectory(std::move(pieces), end);
}

}  // namespace chasles::detail
