// Weighted A* over a C-space lattice (planners/search).
//
// Design notes
// * Lattice: q(k) = start + k ⊙ res (lattice.h), anchored at the start so the start is a node.
//   Each goal's cell k = round((goal − start) / res) (clamped to the cells within the limits: a
//   goal at a limit may round past it) is a goal node whose position is the exact goal, so the
//   path ends exactly there and the last edge is checked like every other. A goal
//   whose cell is the start's cell becomes an extra node joined to the start only. Goals that
//   round to a cell already taken by an earlier goal (problem.goal first) are dropped.
// * Moves: axis moves (±1 in one coordinate, 2n neighbours) or full (3^n − 1 neighbours, n <= 3).
//   Edge cost = ‖W(q_b − q_a)‖ (weighted Euclidean joint distance; W = all ones for now).
// * Heuristic (consistent, so admissible): the weighted Euclidean distance to the nearest goal.
//   With axis moves the free-space lattice cost is the weighted L1 distance, so h also takes
//   max(L2, L1 − δ_goal), where δ_goal = the largest L1 − L2 over the nodes with an edge into
//   the goal (its cell's neighbours, or the start): every lattice edge changes L1 by exactly its
//   cost, and the edge into the goal costs its L2 >= L1 − δ. This keeps 7-joint queries to about
//   the nodes near the path, where the Euclidean bound alone floods the lattice (it
//   underestimates an axis path by up to √n).
// * Weighted A*: f = g + ε·h. A node is closed the first time one of its open entries pops with
//   a valid edge and is never reopened; with a consistent h the cost is still at most ε × the
//   optimal lattice cost (Likhachev et al., ARA*, 2003), and exactly optimal for ε = 1.
// * Lazy validation: a node's validity (cached) and the edge from its parent are checked only
//   when an open entry pops. Every (parent, node) candidate gets its own entry, so an invalid
//   edge from one parent does not lose the node: the search closes the same nodes at the same
//   costs as an eager search over the valid edges.
// * Determinism: no randomness (the seed is unused); equal f pops the larger g first, then the
//   earlier insertion.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <queue>
#include <string>
#include <utility>
#include <vector>

#include "chasles/planners/registry.h"
#include "chasles/robot/error.h"
#include "lattice.h"

namespace chasles {
namespace {

constexpr char kId[] = "astar";
constexpr std::uint64_t kPopsPerStopCheck = 64;

/// Validated settings of one Setup.
struct AstarSettings {
  Eigen::VectorXd resolution;  ///< lattice spacing per joint [rad] or [m]
  Eigen::VectorXd weights;     ///< per-joint cost weights [-] (all 1)
  bool full = false;           ///< 3^n − 1 neighbours instead of 2n
  double epsilon = 1.0;
  std::uint64_t max_nodes = 0;
  std::uint64_t max_expansions = 0;  ///< 0 = unlimited
};

enum class Validity : std::uint8_t { kUnknown, kValid, kInvalid };

struct Node {
  double g = 0.0;  ///< cost from the start, once closed
  double h = 0.0;  ///< heuristic (before the ε weight)
  std::uint32_t parent = LatticeNodeTable::kNone;
  std::int32_t goal = -1;  ///< index into the goals, or -1: the node sits at its lattice position
  Validity validity = Validity::kUnknown;
  bool closed = false;
};

/// One candidate (parent → node) on the open list.
struct OpenEntry {
  double f;
  double g;
  std::uint32_t node;
  std::uint32_t parent;
  std::uint64_t order;  ///< insertion counter
};

/// std::priority_queue pops the greatest: an entry is "less" when it pops later.
struct PopsLater {
  bool operator()(const OpenEntry& a, const OpenEntry& b) const {
    if (a.f != b.f) return a.f > b.f;
    if (a.g != b.g) return a.g < b.g;  // equal f: the deeper entry (nearer the goal) first
    return a.order > b.order;
  }
};

std::string FormatShort(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.4g", value);
  return text;
}

std::string FormatResolution(const Eigen::VectorXd& res) {
  if ((res.array() == res[0]).all()) return FormatShort(res[0]);
  std::string out = "(";
  for (int i = 0; i < res.size(); ++i) out += (i == 0 ? "" : ", ") + FormatShort(res[i]);
  return out + ")";
}

/// "m" when every coordinate is a length (prismatic joints: a base's x, y), "rad" when every one
/// is an angle, else "m or rad" (per joint type).
std::string ResolutionUnit(const RobotModel& robot) {
  bool lengths = false, angles = false;
  for (int i = 0; i < robot.num_dofs(); ++i) {
    (robot.joints()[robot.dof_joint(i)].type == JointType::kPrismatic ? lengths : angles) = true;
  }
  return lengths && angles ? "m for prismatic coordinates, rad for revolute ones" : lengths ? "m" : "rad";
}

/// Why q is not a valid state: outside a joint limit, or the first contact found.
std::string DescribeInvalid(const CollisionChecker& checker, const Eigen::VectorXd& q) {
  const RobotModel& robot = checker.robot();
  for (int i = 0; i < robot.num_dofs(); ++i) {
    if (!(q[i] >= robot.lower_limits()[i] && q[i] <= robot.upper_limits()[i])) {
      return "is outside the joint limits: [" + std::to_string(i) + "] = " + FormatNumber(q[i]) + " is not within [" +
             FormatNumber(robot.lower_limits()[i]) + ", " + FormatNumber(robot.upper_limits()[i]) + "] (joint '" +
             robot.dof_names()[i] + "')";
    }
  }
  const CollisionResult contact = checker.Check(q);
  if (contact.in_collision) return "is in collision (link '" + contact.link_a + "' with '" + contact.other + "')";
  return "is invalid";
}

/// One Solve: the lattice, its nodes, the open list and the counters.
class LatticeSearch {
 public:
  LatticeSearch(const PlanningProblem& problem, const AstarSettings& settings, std::vector<Eigen::VectorXd> goals,
                CheckCounters* counters)
      : problem_(problem),
        settings_(settings),
        checker_(*problem.checker),
        goals_(std::move(goals)),
        lattice_(problem.start, settings.resolution, checker_.robot().lower_limits(),
                 checker_.robot().upper_limits()),
        table_(lattice_.key_words()),
        counters_(counters) {
    BuildMoves();
  }

  /// Runs to a goal or a stop; fills status, message, path, graph_states and the bound.
  void Run(const Termination& termination, PlannerResult* result) {
    const auto t0 = Termination::Clock::now();
    const auto seconds = [t0] { return std::chrono::duration<double>(Termination::Clock::now() - t0).count(); };
    std::uint64_t pops = 0;
    std::uint64_t expansions = 0;
    Eigen::VectorXd q, q_parent;
    bool within_cap = AddStartAndGoals();
    while (within_cap && !open_.empty()) {
      if (pops++ % kPopsPerStopCheck == 0 && termination.ShouldStop()) {
        Stopped(termination.Reason(), seconds(), expansions, result);
        return;
      }
      if (settings_.max_expansions > 0 && expansions >= settings_.max_expansions) {
        result->status = PlanStatus::kNoSolution;
        result->message = std::string(kId) + " stopped after max_expansions = " +
                          std::to_string(settings_.max_expansions) + " expansions without reaching the goal (" +
                          std::to_string(table_.size()) + " lattice nodes stored, " + std::to_string(seconds()) + " s)";
        result->graph_states = table_.size();
        return;
      }
      const OpenEntry entry = open_.top();
      open_.pop();
      Node& node = nodes_[entry.node];
      if (node.closed || node.validity == Validity::kInvalid) continue;
      Position(entry.node, &q);
      if (node.validity == Validity::kUnknown) {
        node.validity = checker_.IsValid(q, counters_) ? Validity::kValid : Validity::kInvalid;
        if (node.validity == Validity::kInvalid) continue;
      }
      Position(entry.parent, &q_parent);
      if (!EdgeValid(q_parent, q)) continue;
      node.closed = true;
      node.g = entry.g;
      node.parent = entry.parent;
      if (node.goal >= 0) {
        Succeed(entry.node, expansions, result);
        return;
      }
      within_cap = Expand(entry.node, q);
      if (within_cap) ++expansions;
    }
    if (!within_cap) {
      result->status = PlanStatus::kNoSolution;
      result->message = std::string(kId) + " hit its memory cap: max_nodes = " + std::to_string(settings_.max_nodes) +
                        " lattice nodes stored after " + std::to_string(expansions) + " expansions (" +
                        std::to_string(seconds()) + " s); raise max_nodes or use a coarser resolution";
      result->graph_states = table_.size();
      return;
    }
    result->status = PlanStatus::kLatticeExhausted;
    result->message = std::string(kId) + " found no path on the lattice at resolution " +
                      FormatResolution(settings_.resolution) + " [" + ResolutionUnit(checker_.robot()) + "] with " +
                      (settings_.full ? "full" : "axis") + " moves: all " + std::to_string(expansions) +
                      " reachable nodes were expanded; a finer resolution may find a way through";
    result->graph_states = table_.size();
  }

 private:
  /// The neighbour offsets: (coordinate, ±1) pairs per move, in a fixed order.
  void BuildMoves() {
    const int n = lattice_.num_dims();
    if (!settings_.full) {
      for (int i = 0; i < n; ++i) {
        moves_.push_back({{i, -1}});
        moves_.push_back({{i, +1}});
      }
      return;
    }
    int count = 1;
    for (int i = 0; i < n; ++i) count *= 3;
    for (int code = 0; code < count; ++code) {
      std::vector<std::pair<int, int>> move;
      for (int i = 0, c = code; i < n; ++i, c /= 3) {
        if (c % 3 != 1) move.push_back({i, c % 3 - 1});
      }
      if (!move.empty()) moves_.push_back(std::move(move));
    }
  }

  /// The start and the goal nodes (their slack is needed by every heuristic value); then the
  /// start is closed at cost 0 and expanded, and goals in its cell are joined to it directly.
  /// Returns false when the start's neighbours exceed max_nodes.
  bool AddStartAndGoals() {
    const int n = lattice_.num_dims();
    key_.resize(lattice_.key_words());
    const LatticeCoords origin(n, 0);
    lattice_.Pack(origin, key_.data());
    const std::uint32_t start = table_.Add(key_.data());
    nodes_.emplace_back();
    std::vector<std::uint32_t> start_cell_goals;
    for (int j = 0; j < static_cast<int>(goals_.size()); ++j) {
      const LatticeCoords cell = lattice_.Nearest(goals_[j]);
      lattice_.Pack(cell, key_.data());
      const bool in_start_cell = cell == origin;
      if (!in_start_cell && table_.Find(key_.data()) != LatticeNodeTable::kNone) continue;  // cell taken
      const std::uint32_t g = table_.Add(key_.data(), !in_start_cell);
      nodes_.emplace_back();
      nodes_[g].goal = j;
      nodes_[g].validity = Validity::kValid;  // checked by Solve
      kept_goals_.push_back(j);
      slack_.push_back(GoalSlack(goals_[j], cell, in_start_cell));
      if (in_start_cell) start_cell_goals.push_back(g);
    }
    Eigen::VectorXd q;
    for (std::uint32_t v = 0; v < nodes_.size(); ++v) {
      Position(v, &q);
      nodes_[v].h = Heuristic(q);
    }
    Node& s = nodes_[start];
    s.validity = Validity::kValid;
    s.closed = true;
    Position(start, &q);
    for (const std::uint32_t g : start_cell_goals) Push(start, g, WeightedNorm(goals_[nodes_[g].goal] - q));
    return Expand(start, q);
  }

  /// Largest L1 − L2 (weighted) from a node with an edge into the goal to the goal.
  double GoalSlack(const Eigen::VectorXd& goal, const LatticeCoords& cell, bool in_start_cell) const {
    if (settings_.full) return 0.0;  // the heuristic is L2 alone
    if (in_start_cell) return WeightedL1(goal - problem_.start) - WeightedNorm(goal - problem_.start);
    double slack = 0.0;
    Eigen::VectorXd q;
    lattice_.Position(cell, &q);
    for (int i = 0; i < lattice_.num_dims(); ++i) {
      for (const int step : {-1, +1}) {
        Eigen::VectorXd p = q;
        p[i] = lattice_.Position(i, cell[i] + step);
        slack = std::max(slack, WeightedL1(goal - p) - WeightedNorm(goal - p));
      }
    }
    return slack;
  }

  double WeightedNorm(const Eigen::VectorXd& d) const { return settings_.weights.cwiseProduct(d).norm(); }
  double WeightedL1(const Eigen::VectorXd& d) const { return settings_.weights.cwiseProduct(d).lpNorm<1>(); }

  double Heuristic(const Eigen::VectorXd& q) const {
    double h = std::numeric_limits<double>::infinity();
    for (size_t j = 0; j < kept_goals_.size(); ++j) {
      const Eigen::VectorXd d = goals_[kept_goals_[j]] - q;
      double hj = WeightedNorm(d);
      if (!settings_.full) hj = std::max(hj, WeightedL1(d) - slack_[j]);
      h = std::min(h, hj);
    }
    return h;
  }

  void Position(std::uint32_t node, Eigen::VectorXd* q) {
    if (nodes_[node].goal >= 0) {
      *q = goals_[nodes_[node].goal];
      return;
    }
    lattice_.Unpack(table_.key(node), &k_);
    lattice_.Position(k_, q);
  }

  bool EdgeValid(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
    return checker_.IsMotionFree(a, b, problem_.max_step, counters_);
  }

  void Push(std::uint32_t parent, std::uint32_t node, double edge_cost) {
    const double g = nodes_[parent].g + edge_cost;
    open_.push({g + settings_.epsilon * nodes_[node].h, g, node, parent, order_++});
  }

  /// Pushes an entry for every neighbour of closed node u at q_u that is not closed or known
  /// invalid. Returns false when a new node would exceed max_nodes.
  bool Expand(std::uint32_t u, const Eigen::VectorXd& q_u) {
    lattice_.Unpack(table_.key(u), &k_);
    const LatticeCoords k_u = k_;
    LatticeCoords k_v;
    Eigen::VectorXd q_v;
    for (const auto& move : moves_) {
      k_v = k_u;
      for (const auto& [i, step] : move) k_v[i] += step;
      if (!lattice_.InLimits(k_v)) continue;
      lattice_.Pack(k_v, key_.data());
      std::uint32_t v = table_.Find(key_.data());
      if (v == LatticeNodeTable::kNone) {
        if (table_.size() >= settings_.max_nodes) return false;
        q_v = q_u;
        for (const auto& [i, step] : move) q_v[i] = lattice_.Position(i, k_v[i]);
        v = table_.Add(key_.data());
        nodes_.emplace_back();
        nodes_[v].h = Heuristic(q_v);
      } else {
        if (nodes_[v].closed || nodes_[v].validity == Validity::kInvalid) continue;
        if (nodes_[v].goal >= 0) {
          q_v = goals_[nodes_[v].goal];
        } else {
          q_v = q_u;
          for (const auto& [i, step] : move) q_v[i] = lattice_.Position(i, k_v[i]);
        }
      }
      Push(u, v, WeightedNorm(q_v - q_u));
    }
    return true;
  }

  void Succeed(std::uint32_t goal, std::uint64_t expansions, PlannerResult* result) {
    std::vector<std::uint32_t> chain;
    for (std::uint32_t v = goal; v != LatticeNodeTable::kNone; v = nodes_[v].parent) chain.push_back(v);
    std::reverse(chain.begin(), chain.end());
    // Drop a waypoint between two equal lattice steps: it lies on the straight segment joining
    // its neighbours, which is then the same motion, already validated. The goal counts as a
    // lattice point only when it sits exactly at its cell's position.
    std::vector<LatticeCoords> k(chain.size());
    for (size_t i = 0; i < chain.size(); ++i) lattice_.Unpack(table_.key(chain[i]), &k[i]);
    Eigen::VectorXd q;
    lattice_.Position(k.back(), &q);
    const bool goal_on_lattice = q == goals_[nodes_[goal].goal];
    result->path.clear();
    result->path.push_back(problem_.start);  // bit-exact start
    for (size_t i = 1; i < chain.size(); ++i) {
      const bool last = i + 1 == chain.size();
      if (!last && (i + 2 < chain.size() || goal_on_lattice)) {
        bool straight = true;
        for (size_t d = 0; d < k[i].size() && straight; ++d) straight = k[i][d] - k[i - 1][d] == k[i + 1][d] - k[i][d];
        if (straight) continue;
      }
      Position(chain[i], &q);
      result->path.push_back(q);
    }
    result->status = PlanStatus::kExactSolution;
    result->suboptimality_bound = settings_.epsilon;
    result->graph_states = table_.size();
    result->message = std::string(kId) + " found a path of cost " + FormatShort(nodes_[goal].g) + " with " +
                      std::to_string(result->path.size()) + " waypoints (" + std::to_string(table_.size()) +
                      " lattice nodes stored, " + std::to_string(expansions) + " expanded)";
  }

  void Stopped(StopReason reason, double seconds, std::uint64_t expansions, PlannerResult* result) const {
    result->graph_states = table_.size();
    switch (reason) {
      case StopReason::kCancelled:
        result->status = PlanStatus::kCancelled;
        result->message = "cancelled by the client";
        return;
      case StopReason::kDeadline:
        result->status = PlanStatus::kDeadlineExceeded;
        result->message = std::string("the gRPC deadline passed before ") + kId + " found a path";
        return;
      default:
        result->status = PlanStatus::kNoSolution;
        result->message = std::string(kId) + " found no path within the budget (" + std::to_string(seconds) + " s, " +
                          std::to_string(table_.size()) + " lattice nodes stored, " + std::to_string(expansions) +
                          " expanded)";
    }
  }

  const PlanningProblem& problem_;
  const AstarSettings& settings_;
  const CollisionChecker& checker_;
  std::vector<Eigen::VectorXd> goals_;  ///< valid goals, problem.goal first when valid
  CSpaceLattice lattice_;
  LatticeNodeTable table_;
  CheckCounters* counters_;
  std::vector<Node> nodes_;
  std::vector<int> kept_goals_;  ///< goals with a node, in goals_
  std::vector<double> slack_;    ///< δ per kept goal
  std::vector<std::vector<std::pair<int, int>>> moves_;
  std::priority_queue<OpenEntry, std::vector<OpenEntry>, PopsLater> open_;
  std::uint64_t order_ = 0;
  std::vector<std::uint64_t> key_;  ///< scratch key
  LatticeCoords k_;                 ///< scratch coordinates
};

class AstarPlanner : public Planner {
 public:
  explicit AstarPlanner(PlannerSpec spec) : spec_(std::move(spec)) {}

  const PlannerSpec& spec() const override { return spec_; }

  void Setup(const PlanningProblem& problem) override {
    Clear();
    const ParameterValues params = ResolveParameters(spec_, problem.parameters);
    if (!problem.checker) ThrowInvalid("planner '" + spec_.id + "': the problem has no collision checker");
    const RobotModel& robot = problem.checker->robot();
    CheckRobotKind(spec_, robot);
    const int n = robot.num_dofs();
    const auto check_size = [&](const Eigen::VectorXd& q, const std::string& field) {
      if (q.size() != n) {
        ThrowInvalid(field + " has " + std::to_string(q.size()) + " values, robot '" + robot.name() + "' has " +
                     std::to_string(n) + " joints");
      }
    };
    check_size(problem.start, "start");
    check_size(problem.goal, "goal");
    for (size_t i = 0; i < problem.additional_goals.size(); ++i) {
      check_size(problem.additional_goals[i], "additional_goals[" + std::to_string(i) + "]");
    }
    if (!(problem.max_step > 0.0)) ThrowInvalid("max_step = " + FormatNumber(problem.max_step) + " must be > 0");

    const int connectivity = static_cast<int>(params.at("connectivity"));
    if (connectivity == 2 && n > 3) {
      throw Error(ErrorCode::kFailedPrecondition,
                  "planner.parameters['connectivity'] = 2: full connectivity (all 3^n - 1 neighbours) needs at most "
                  "3 joints; robot '" + robot.name() + "' has " + std::to_string(n) +
                  " — use connectivity = 1 (axis moves) (planner '" + spec_.id + "')");
    }
    settings_.full = connectivity == 2 || (connectivity == 0 && n <= 3);

    const double resolution = params.at("resolution");
    const double cells = params.at("cells_per_joint");
    settings_.resolution.resize(n);
    // Default: one spacing for every coordinate, from the widest range. Per-joint spacings would
    // cut a narrow coordinate (a drone's ±0.35 rad tilt) into steps so cheap that the search
    // floods them.
    const double widest = (robot.upper_limits() - robot.lower_limits()).maxCoeff();
    // Per-joint overrides `resolution[i]` (ResolveParameters checked their values).
    for (const auto& [name, value] : params) {
      if (name.rfind("resolution[", 0) != 0) continue;
      const long index = std::stol(name.substr(11, name.size() - 12));
      if (index >= n) {
        ThrowInvalid("planner.parameters['" + name + "']: robot '" + robot.name() + "' has " + std::to_string(n) +
                     " joints (indices 0.." + std::to_string(n - 1) + ") (planner '" + spec_.id + "')");
      }
    }
    for (int i = 0; i < n; ++i) {
      const double range = robot.upper_limits()[i] - robot.lower_limits()[i];
      const std::string key = "resolution[" + std::to_string(i) + "]";
      const auto own = params.find(key);
      const double requested = own != params.end() && own->second > 0.0 ? own->second : resolution;
      const std::string field = own != params.end() && own->second > 0.0 ? key : std::string("resolution");
      double res = requested > 0.0 ? requested : widest / cells;
      if (!(res > 0.0)) res = 1.0;  // a joint without range: only the start's coordinate
      if (range / res > CSpaceLattice::kMaxCellsPerJoint) {
        ThrowInvalid("planner.parameters['" + field + "'] = " + FormatNumber(requested) + " gives " +
                     FormatShort(range / res) + " lattice steps across joint '" + robot.dof_names()[i] + "' ([" +
                     FormatNumber(robot.lower_limits()[i]) + ", " + FormatNumber(robot.upper_limits()[i]) +
                     "]); at most 2^30 (planner '" + spec_.id + "')");
      }
      settings_.resolution[i] = res;
    }
    settings_.weights = Eigen::VectorXd::Ones(n);
    settings_.epsilon = params.at("epsilon");
    settings_.max_nodes = static_cast<std::uint64_t>(params.at("max_nodes"));
    settings_.max_expansions = static_cast<std::uint64_t>(params.at("max_expansions"));
    problem_ = problem;
    ready_ = true;
  }

  PlannerResult Solve(const Termination& termination) override {
    if (!ready_) ThrowInvalid("planner '" + spec_.id + "': Solve() called before Setup()");
    const auto t0 = Termination::Clock::now();
    PlannerResult result;
    CheckCounters counters;
    const CollisionChecker& checker = *problem_.checker;
    std::vector<Eigen::VectorXd> goals;
    std::string invalid_goals;
    if (!checker.IsValid(problem_.start, &counters)) {
      result.status = PlanStatus::kInvalidStart;
      result.message = "start " + DescribeInvalid(checker, problem_.start);
    } else {
      for (size_t j = 0; j <= problem_.additional_goals.size(); ++j) {
        const Eigen::VectorXd& goal = j == 0 ? problem_.goal : problem_.additional_goals[j - 1];
        if (checker.IsValid(goal, &counters)) {
          goals.push_back(goal);
        } else {
          const std::string field = j == 0 ? "goal" : "additional_goals[" + std::to_string(j - 1) + "]";
          invalid_goals += (invalid_goals.empty() ? "" : "; ") + field + " " + DescribeInvalid(checker, goal);
        }
      }
      if (goals.empty()) {
        result.status = PlanStatus::kInvalidGoal;
        result.message = invalid_goals;
      } else if (termination.ShouldStop()) {
        result.status = termination.Reason() == StopReason::kCancelled   ? PlanStatus::kCancelled
                        : termination.Reason() == StopReason::kDeadline ? PlanStatus::kDeadlineExceeded
                                                                        : PlanStatus::kNoSolution;
        result.message = result.status == PlanStatus::kCancelled ? "cancelled by the client"
                         : result.status == PlanStatus::kDeadlineExceeded
                             ? "the gRPC deadline passed before " + spec_.id + " started"
                             : spec_.id + " found no path within the budget (it ended before the search started)";
      } else {
        LatticeSearch search(problem_, settings_, std::move(goals), &counters);
        search.Run(termination, &result);
      }
    }
    result.state_checks = counters.state_checks;
    result.solve_seconds = std::chrono::duration<double>(Termination::Clock::now() - t0).count();
    return result;
  }

  void Clear() override {
    ready_ = false;
    problem_ = PlanningProblem();
    settings_ = AstarSettings();
  }

 private:
  PlannerSpec spec_;
  PlanningProblem problem_;
  AstarSettings settings_;
  bool ready_ = false;
};

PlannerSpec AstarSpec() {
  PlannerSpec spec;
  spec.id = kId;
  spec.description =
      "A* (weighted) over a C-space lattice anchored at the start: axis moves for arms, 8/26-connected grids for "
      "2-3 joints; lazy edge checks; optimal on the lattice for epsilon = 1, at most epsilon times optimal otherwise";
  spec.optimizing = false;
  spec.parameters = {
      {"resolution",
       "lattice spacing of every joint [rad] or [m]; 0 = the widest joint range / cells_per_joint; "
       "resolution[i] sets joint i's own spacing (0 = as the others)",
       ParameterType::kDouble, 0.0, 0.0, 100.0, true},
      {"cells_per_joint", "lattice steps across the widest joint range when resolution = 0 [-]", ParameterType::kInt,
       32.0, 2.0, 1e6},
      {"connectivity",
       "neighbours: 0 = automatic (full for at most 3 joints, axis moves otherwise), 1 = axis moves (2n), "
       "2 = full (3^n - 1, at most 3 joints) [-]",
       ParameterType::kInt, 0.0, 0.0, 2.0},
      {"epsilon", "heuristic weight of weighted A* (f = g + epsilon h): the path costs at most epsilon times the "
                  "optimal lattice path [-]",
       ParameterType::kDouble, 1.0, 1.0, 100.0},
      {"max_nodes", "memory cap: lattice nodes stored (open and closed) before the search gives up [-]",
       ParameterType::kInt, 2e6, 100.0, 1e9},
      {"max_expansions", "stop after this many node expansions; 0 = until the time budget [-]", ParameterType::kInt,
       0.0, 0.0, 1e12},
  };
  spec.refusal_reason = "its lattice moves ignore a car's minimum turning radius";
  return spec;
}

}  // namespace

void RegisterSearchPlanners(PlannerRegistry* registry) {
  PlannerSpec spec = AstarSpec();
  PlannerSpec copy = spec;
  registry->Register(std::move(spec), [copy] { return std::make_unique<AstarPlanner>(copy); });
}

}  // namespace chasles
