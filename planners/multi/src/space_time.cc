#include "chasles/multi/space_time.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include "chasles/robot/error.h"

namespace chasles {
namespace {

/// Exact rest-to-rest moves along roadmap edges, computed once per directed edge.
class Moves {
 public:
  Moves(const Roadmap& roadmap, const KinematicLimits& limits) : roadmap_(roadmap), limits_(limits) {}
  const TimedTrajectory& Get(int a, int b) {
    const std::uint64_t key = (static_cast<std::uint64_t>(a) << 32) | static_cast<std::uint32_t>(b);
    auto it = cache_.find(key);
    if (it == cache_.end()) {
      it = cache_.emplace(key, ParameterizeRestToRest({roadmap_.vertices[a], roadmap_.vertices[b]}, limits_)).first;
    }
    return it->second;
  }

 private:
  const Roadmap& roadmap_;
  const KinematicLimits& limits_;
  std::unordered_map<std::uint64_t, TimedTrajectory> cache_;
};

/// Checks a motion (or a stand) against the moving obstacles at the search's density.
class Checker {
 public:
  Checker(const ConflictFree& conflict_free, const SpaceTimeOptions& options, std::uint64_t* counter)
      : conflict_free_(conflict_free), options_(options), counter_(counter) {}
  /// `trajectory` started at time t0; its first state is taken as already checked. The end
  /// state is checked first, then the others coarse to fine (a conflict shows up early).
  bool Motion(const TimedTrajectory& trajectory, double t0) const {
    const double duration = trajectory.duration();
    double travel = 0.0;
    for (const TimedTrajectory::Piece& piece : trajectory.pieces()) travel += piece.MaxJointTravel();
    const double steps = std::max(std::ceil(duration / options_.time_step), std::ceil(travel / options_.max_joint_step));
    const long m = std::max(1L, static_cast<long>(steps));
    const auto clear = [&](long i) {
      const double tau = duration * static_cast<double>(i) / static_cast<double>(m);
      ++*counter_;
      return conflict_free_(trajectory.Evaluate(tau).q, t0 + tau);
    };
    if (!clear(m)) return false;
    long stride = 1;
    while (stride * 2 < m) stride *= 2;
    for (; stride >= 1; stride /= 2) {  // i = stride · odd: every index in [1, m) once
      for (long i = stride; i < m; i += 2 * stride) {
        if (!clear(i)) return false;
      }
    }
    return true;
  }
  /// Standing at q over [t0, t1] (t0 itself included).
  bool Stand(const Eigen::VectorXd& q, double t0, double t1) const {
    const long m = std::max(1L, static_cast<long>(std::ceil((t1 - t0) / options_.time_step)));
    for (long i = 0; i <= m; ++i) {
      ++*counter_;
      if (!conflict_free_(q, t0 + (t1 - t0) * static_cast<double>(i) / static_cast<double>(m))) return false;
    }
    return true;
  }

 private:
  const ConflictFree& conflict_free_;
  const SpaceTimeOptions& options_;
  std::uint64_t* counter_;
};

/// The exact rest-to-rest duration of the straight move a → b (ParameterizeRestToRest's profile):
/// 1/V + V/A when V² <= A, else 2/√A, with V = minᵢ vᵢ/|Δᵢ| and A = minᵢ aᵢ/|Δᵢ|.
double RestToRestDuration(const Eigen::VectorXd& a, const Eigen::VectorXd& b, const KinematicLimits& limits) {
  double V = std::numeric_limits<double>::infinity(), A = V;
  for (Eigen::Index i = 0; i < a.size(); ++i) {
    const double d = std::abs(b[i] - a[i]);
    if (d == 0.0) continue;
    V = std::min(V, limits.max_velocity[i] / d);
    A = std::min(A, limits.max_acceleration[i] / d);
  }
  if (!std::isfinite(V)) return 0.0;
  return V * V <= A ? 1.0 / V + V / A : 2.0 / std::sqrt(A);
}

struct Node {
  int vertex = 0;
  double t = 0.0;
  int parent = -1;  ///< index into the node list; -1 for the start
  bool wait = false;  ///< reached from the parent by waiting (else by moving along an edge)
};

/// One step of the plan: a move along an edge or a wait at a vertex.
struct Step {
  int from = 0, to = 0;  ///< equal for a wait
  double t0 = 0.0, duration = 0.0;
};

void ValidateOptions(const Roadmap& roadmap, int start_vertex, int goal_vertex, const KinematicLimits& limits,
                     const SpaceTimeOptions& options) {
  const int n = static_cast<int>(roadmap.vertices.size());
  if (n == 0 || roadmap.neighbors.size() != roadmap.vertices.size()) ThrowInvalid("roadmap is empty or malformed");
  if (start_vertex < 0 || start_vertex >= n) ThrowInvalid("start_vertex = " + std::to_string(start_vertex) + " is not a roadmap vertex");
  if (goal_vertex < 0 || goal_vertex >= n) ThrowInvalid("goal_vertex = " + std::to_string(goal_vertex) + " is not a roadmap vertex");
  limits.Validate(static_cast<int>(roadmap.vertices.front().size()));
  const auto positive = [](double v, const char* name) {
    if (!std::isfinite(v) || !(v > 0.0)) ThrowInvalid(std::string("space-time ") + name + " = " + FormatNumber(v) + " must be finite and > 0");
  };
  positive(options.wait_step, "wait_step");
  positive(options.horizon, "horizon");
  positive(options.time_step, "time_step");
  positive(options.max_joint_step, "max_joint_step");
  positive(options.time_resolution, "time_resolution");
  if (!std::isfinite(options.hold_until) || options.hold_until < 0.0) {
    ThrowInvalid("space-time hold_until = " + FormatNumber(options.hold_until) + " must be finite and >= 0");
  }
  if (options.max_expansions < 1) ThrowInvalid("space-time max_expansions must be >= 1");
}

}  // namespace

SpaceTimeResult SearchSpaceTime(const Roadmap& roadmap, int start_vertex, int goal_vertex, const KinematicLimits& limits,
                                const ConflictFree& conflict_free, const SpaceTimeOptions& options,
                                const Termination& termination) {
  ValidateOptions(roadmap, start_vertex, goal_vertex, limits, options);
  SpaceTimeResult result;
  Moves moves(roadmap, limits);
  const Checker check(conflict_free, options, &result.conflict_checks);
  const int n = static_cast<int>(roadmap.vertices.size());

  // The moves from each vertex: to every other station of its lines, or along its edges.
  std::vector<std::vector<int>> targets(n);
  if (roadmap.lines.empty()) {
    targets = roadmap.neighbors;
  } else {
    for (const std::vector<int>& line : roadmap.lines) {
      for (int a : line) {
        for (int b : line) {
          if (a != b) targets[a].push_back(b);
        }
      }
    }
    for (std::vector<int>& list : targets) {
      std::sort(list.begin(), list.end());
      list.erase(std::unique(list.begin(), list.end()), list.end());
    }
  }
  // Heuristic: the fastest time to the goal over these moves, ignoring moving obstacles.
  std::vector<double> h(n, std::numeric_limits<double>::infinity());
  {
    using Entry = std::pair<double, int>;
    std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> open;
    h[goal_vertex] = 0.0;
    open.emplace(0.0, goal_vertex);
    while (!open.empty()) {
      const auto [d, v] = open.top();
      open.pop();
      if (d > h[v]) continue;
      for (int w : targets[v]) {
        const double nd = d + RestToRestDuration(roadmap.vertices[w], roadmap.vertices[v], limits);
        if (nd < h[w]) {
          h[w] = nd;
          open.emplace(nd, w);
        }
      }
    }
  }
  if (!std::isfinite(h[start_vertex])) {
    result.message = "the roadmap does not connect the start to the goal";
    return result;
  }

  if (!check.Stand(roadmap.vertices[start_vertex], 0.0, 0.0)) {
    result.message = "the start is occupied by a moving obstacle at t = 0";
    return result;
  }
  // The goal first: occupied at a time no arrival within the horizon can avoid (the robot must
  // stay there until hold_until) means there is nothing to search.
  {
    const Eigen::VectorXd& goal = roadmap.vertices[goal_vertex];
    const double hold = options.hold_until;
    // The first of the samples of [t0, t1] (at most time_step apart, both ends) where
    // conflict_free gives `value`; -1 when none does.
    const auto scan = [&](double t0, double t1, bool value) {
      const long m = std::max(1L, static_cast<long>(std::ceil((t1 - t0) / options.time_step)));
      for (long i = 0; i <= m; ++i) {
        const double t = i == m ? t1 : t0 + (t1 - t0) * static_cast<double>(i) / static_cast<double>(m);
        ++result.conflict_checks;
        if (conflict_free(goal, t) == value) return t;
      }
      return -1.0;
    };
    if (hold > options.horizon) {
      const double t = scan(options.horizon, hold, false);
      if (t >= 0.0) {
        result.message = "the goal is occupied by a moving obstacle at t = " + FormatNumber(t) +
                         " s, after the horizon " + FormatNumber(options.horizon) + " s and before hold_until = " +
                         FormatNumber(hold) + " s (the robot must stay there until then)";
        return result;
      }
    } else if (scan(hold, options.horizon, true) < 0.0) {
      result.message = "the goal is occupied by a moving obstacle at hold_until = " + FormatNumber(hold) +
                       " s (when the others' motions end) and at every checked time up to the horizon " +
                       FormatNumber(options.horizon) + " s";
      return result;
    }
  }

  // A* over (vertex, time), earliest arrival first. Successors are checked lazily, when they
  // come out of the queue: a (vertex, time bucket) is closed by the first one whose motion or
  // wait from its parent is clear. States that cannot reach the goal by the horizon even
  // unhindered (t + h > horizon) are never generated.
  std::vector<Node> nodes;
  using Entry = std::pair<double, int>;  // (f = t + h, node); ties by node index: deterministic
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> open;
  std::unordered_set<std::uint64_t> closed;
  const auto bucket_key = [&options](int v, double t) {
    return (static_cast<std::uint64_t>(v) << 32) |
           static_cast<std::uint32_t>(std::llround(t / options.time_resolution));
  };
  const double latest = options.horizon * (1.0 + 1e-12) + 1e-9;  // rounding slack for t + h only
  nodes.push_back(Node{start_vertex, 0.0, -1, false});
  open.emplace(h[start_vertex], 0);
  int found = -1;
  bool reached_goal = false;
  while (!open.empty()) {
    if (termination.ShouldStop()) {
      const StopReason reason = termination.Reason();
      result.message = std::string("stopped: ") +
                       (reason == StopReason::kCancelled  ? "cancelled"
                        : reason == StopReason::kDeadline ? "deadline"
                                                          : "time budget") +
                       ", after " + std::to_string(result.expansions) + " expansions";
      return result;
    }
    if (result.expansions >= options.max_expansions) {
      result.message = "no route within " + std::to_string(options.max_expansions) + " expansions";
      return result;
    }
    const int index = open.top().second;
    open.pop();
    const Node node = nodes[index];
    const std::uint64_t key = bucket_key(node.vertex, node.t);
    if (closed.count(key)) continue;
    if (node.parent >= 0) {
      const Node& from = nodes[node.parent];
      const bool clear = node.wait ? check.Stand(roadmap.vertices[node.vertex], from.t, node.t)
                                   : check.Motion(moves.Get(from.vertex, node.vertex), from.t);
      if (!clear) continue;
    }
    closed.insert(key);
    ++result.expansions;
    if (node.vertex == goal_vertex) {
      reached_goal = true;
      if (check.Stand(roadmap.vertices[goal_vertex], node.t, std::max(node.t, options.hold_until))) {
        found = index;
        break;
      }
    }
    // Wait here.
    const double t_wait = node.t + options.wait_step;
    if (t_wait <= options.horizon && t_wait + h[node.vertex] <= latest && !closed.count(bucket_key(node.vertex, t_wait))) {
      nodes.push_back(Node{node.vertex, t_wait, index, true});
      open.emplace(t_wait + h[node.vertex], static_cast<int>(nodes.size()) - 1);
    }
    // Move to another station.
    for (int w : targets[node.vertex]) {
      const double t_arrive = node.t + moves.Get(node.vertex, w).duration();
      if (t_arrive > options.horizon || !(t_arrive + h[w] <= latest) || closed.count(bucket_key(w, t_arrive))) continue;
      nodes.push_back(Node{w, t_arrive, index, false});
      open.emplace(t_arrive + h[w], static_cast<int>(nodes.size()) - 1);
    }
  }
  if (found < 0) {
    result.message = reached_goal ? "the goal is reached but does not stay clear until hold_until = " +
                                        FormatNumber(options.hold_until) + " s at any arrival before the horizon " +
                                        FormatNumber(options.horizon) + " s"
                                  : "no route reaches the goal before the horizon " + FormatNumber(options.horizon) + " s";
    return result;
  }

  // The plan as steps, start to goal.
  std::vector<Step> steps;
  for (int i = found; nodes[i].parent >= 0; i = nodes[i].parent) {
    const Node& to = nodes[i];
    const Node& from = nodes[to.parent];
    steps.push_back(Step{from.vertex, to.vertex, from.t, to.t - from.t});
  }
  std::reverse(steps.begin(), steps.end());

  // Trajectory parts; runs of moves without a wait between them are retimed through their
  // stations when that stays clear, the time saved spent waiting at the run's end.
  std::vector<TimedTrajectory> parts;
  result.path.push_back(roadmap.vertices[start_vertex]);
  for (std::size_t i = 0; i < steps.size();) {
    const Step& step = steps[i];
    if (step.from == step.to) {
      parts.push_back(HoldTrajectory(roadmap.vertices[step.from], step.duration));
      result.wait_time += step.duration;
      if (result.path.size() == 1) result.start_delay += step.duration;
      ++i;
      continue;
    }
    std::size_t end = i;
    while (end < steps.size() && steps[end].from != steps[end].to) ++end;
    JointPath run{roadmap.vertices[steps[i].from]};
    for (std::size_t k = i; k < end; ++k) run.push_back(roadmap.vertices[steps[k].to]);
    // Greedy: from each station, the longest stretch (the whole run, then halves) whose
    // time-optimal retiming stays clear, followed by a wait until the original schedule.
    for (std::size_t a = i; a < end;) {
      std::size_t next = a + 1;
      if (options.merge_moves) {
        for (std::size_t b = end; b > a + 1; b = a + (b - a) / 2) {
          const JointPath stretch(run.begin() + static_cast<std::ptrdiff_t>(a - i),
                                  run.begin() + static_cast<std::ptrdiff_t>(b - i) + 1);
          const double t_start = steps[a].t0;
          const double t_end = steps[b - 1].t0 + steps[b - 1].duration;
          TimeOptimalOptions topp;
          topp.max_deviation = 0.0;  // stays on the roadmap's edges: through straight stations, stops at corners
          const TimedTrajectory fast = ParameterizeTimeOptimal(stretch, limits, topp);
          const double saved = (t_end - t_start) - fast.duration();
          if (saved > 1e-9 && check.Motion(fast, t_start) && check.Stand(stretch.back(), t_start + fast.duration(), t_end)) {
            parts.push_back(fast);
            if (b < steps.size()) {  // at the goal the robot simply arrives earlier (its hold was checked)
              parts.push_back(HoldTrajectory(stretch.back(), saved));
              result.wait_time += saved;
            }
            next = b;
            break;
          }
        }
      }
      if (next == a + 1) parts.push_back(moves.Get(steps[a].from, steps[a].to));
      a = next;
    }
    for (std::size_t k = 1; k < run.size(); ++k) result.path.push_back(run[k]);
    i = end;
  }
  if (parts.empty()) parts.push_back(HoldTrajectory(roadmap.vertices[start_vertex], 0.0));
  result.trajectory = ConcatenateTrajectories(parts);
  result.arrival = result.trajectory.duration();
  result.found = true;
  result.message = "arrives at " + FormatNumber(result.arrival) + " s after waiting " + FormatNumber(result.wait_time) +
                   " s; " + std::to_string(result.expansions) + " expansions";
  return result;
}

}  // namespace chasles
