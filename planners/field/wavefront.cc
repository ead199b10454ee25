// wavefront: a navigation function on a grid over at most 3 configuration coordinates
// (Barraquand & Latombe's wavefront expansion; Choset et al., Principles of Robot Motion, 4.5),
// with Euclidean step costs so it is a discrete distance-to-goal function.
//
// Coordinates: the grid spans the coordinates in which start and goal differ by more than
// 1e-9 — at most 3 (more is refused with kFailedPrecondition); the others are held at the goal's
// values (they differ from the start's by at most 1e-9, a difference the first motion absorbs).
// So a planar robot or a drone that keeps its heading plans over (x, y) or (x, y, z); an arm
// moving two joints plans over those two. When the start is not connected to the goal with the
// held coordinates fixed and fewer than 3 coordinates move, held coordinates are released (in
// configuration order, up to 3 grid coordinates) and the wavefront runs once more: the 2R arm
// of the planner contract, whose start and goal differ only in the shoulder, must fold its
// elbow round the wall. The result message names the released coordinates.
//
// Grid: per moving coordinate i a spacing r_i (`resolution`, or the joint range divided by
// `cells_per_coordinate`), anchored at the goal: cell k_i sits at goal_i + k_i·r_i, so the goal
// is a cell and the path ends exactly at it. Cells span the joint limits.
//
// Wavefront: Dijkstra from the goal cell over full connectivity (2 / 8 / 26 neighbours in 1 /
// 2 / 3 dimensions) with Euclidean step costs, over valid cells (IsValid, evaluated lazily)
// and edges validated lazily: the edge from a cell to the neighbour it would be reached from
// is checked (in path direction, certified when the checker certifies motions, else discrete at
// max_step) when the cell is finalised; if it fails, the cell's next-best finalised neighbour is
// tried. Each finalised cell stores its parent, so the descent (follow the parents from the
// start's cell) is steepest on the navigation function and never stuck, and every edge on it
// has been validated. The start connects by a validated motion to one of the cells around it
// (the 4 nearest per coordinate) — the one with the least connection + wavefront cost; the
// expansion stops once no unfinalised cell could give a cheaper start connection.
// Memory: about 10 bytes per cell (max_cells caps the grid) plus the queue.
// Goals: the grid is anchored at `goal`; additional goals are not used.

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <queue>
#include <string>
#include <tuple>
#include <unordered_map>
#include <utility>
#include <vector>

#include "chasles/robot/error.h"
#include "field.h"

namespace chasles::field {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kSameCoordinate = 1e-9;  // start and goal coordinates closer than this are held fixed
constexpr int kMaxMoving = 3;
constexpr double kLimitSlack = 1e-9;      // relative: a cell this far past a limit sits on it
constexpr std::uint8_t kKnown = 1, kValid = 2, kDone = 4, kCandidate = 8;

/// A grid over some configuration coordinates, anchored at the goal.
struct Grid {
  std::vector<int> coords;            // configuration indices of the grid's coordinates
  std::vector<double> spacing;        // r_i
  std::vector<double> lower, upper;   // joint limits of the grid's coordinates
  std::vector<std::int64_t> kmin;     // first cell index (<= 0)
  std::vector<std::int64_t> count;    // cells along each coordinate
  std::vector<std::int64_t> stride;   // linear index stride
  std::int64_t cells = 1;
  double total = 1.0;                 // cells, before any overflow
  std::string shape;                  // "64 × 58"

  std::int64_t Index(std::int64_t cell, std::size_t i) const { return (cell / stride[i]) % count[i]; }
  void Config(const Eigen::VectorXd& goal, std::int64_t cell, Eigen::VectorXd* q) const {
    *q = goal;
    for (std::size_t i = 0; i < coords.size(); ++i) {
      const double x = goal[coords[i]] + static_cast<double>(Index(cell, i) + kmin[i]) * spacing[i];
      (*q)[coords[i]] = std::clamp(x, lower[i], upper[i]);  // a limit cell off by rounding sits on it
    }
  }
  std::string Resolution() const {
    std::string s;
    for (std::size_t i = 0; i < coords.size(); ++i) s += (i == 0 ? "" : " × ") + FormatNumber(spacing[i]);
    return s;
  }
};

/// One neighbour direction: the index step per grid coordinate, the linear index step and the
/// Euclidean length.
struct Offset {
  std::array<int, kMaxMoving> step{};
  std::int64_t delta = 0;
  double cost = 0.0;
  int opposite = -1;
};

class WavefrontPlanner : public Planner {
 public:
  explicit WavefrontPlanner(PlannerSpec spec) : spec_(std::move(spec)) {}

  const PlannerSpec& spec() const override { return spec_; }

  void Setup(const PlanningProblem& problem) override;
  PlannerResult Solve(const Termination& termination) override;
  void Clear() override {
    set_up_ = false;
    problem_ = PlanningProblem();
    grid_ = Grid();
    held_.clear();
  }

 private:
  enum class Outcome { kFound, kNotConnected, kStopped };
  Grid MakeGrid(const std::vector<int>& coords) const;
  /// The wavefront over `grid` and the descent from the start; fills result->path when found.
  Outcome Run(const Grid& grid, const Termination& termination, PlannerResult* result, std::uint64_t* checks,
              std::uint64_t* finalised) const;

  PlannerSpec spec_;
  PlanningProblem problem_;
  bool set_up_ = false;
  double resolution_ = 0.0, per_coordinate_ = 64.0, max_cells_ = 0.0;
  Grid grid_;              // over the moving coordinates
  std::vector<int> held_;  // the other coordinates, in configuration order
};

Grid WavefrontPlanner::MakeGrid(const std::vector<int>& coords) const {
  const RobotModel& robot = problem_.checker->robot();
  Grid grid;
  grid.coords = coords;
  for (const int d : coords) {
    const double lo = robot.lower_limits()[d], hi = robot.upper_limits()[d], g = problem_.goal[d];
    double r = resolution_ > 0.0 ? resolution_ : (hi - lo) / per_coordinate_;
    // A zero range means an endpoint is outside the limits (Solve reports it); any r will do.
    if (!(r > 0.0)) r = std::max(std::abs(problem_.start[d] - g), 1e-3);
    // Cells within the limits, up to rounding (kLimitSlack): 0.5 - 15·0.1 is -1.0000000000000002.
    const double slack = kLimitSlack * std::max(1.0, hi - lo);
    std::int64_t kmin = static_cast<std::int64_t>(std::ceil((lo - g) / r));
    while (g + static_cast<double>(kmin - 1) * r >= lo - slack) --kmin;
    while (g + static_cast<double>(kmin) * r < lo - slack) ++kmin;
    std::int64_t kmax = static_cast<std::int64_t>(std::floor((hi - g) / r));
    while (g + static_cast<double>(kmax + 1) * r <= hi + slack) ++kmax;
    while (g + static_cast<double>(kmax) * r > hi + slack) --kmax;
    kmin = std::min<std::int64_t>(kmin, 0);  // the goal is a cell even when outside the limits
    kmax = std::max<std::int64_t>(kmax, 0);
    grid.spacing.push_back(r);
    grid.lower.push_back(lo);
    grid.upper.push_back(hi);
    grid.kmin.push_back(kmin);
    grid.count.push_back(kmax - kmin + 1);
    grid.total *= static_cast<double>(kmax - kmin + 1);
    grid.shape += (grid.shape.empty() ? "" : " × ") + std::to_string(kmax - kmin + 1);
  }
  if (grid.total <= max_cells_) {
    for (const std::int64_t c : grid.count) {
      grid.stride.push_back(grid.cells);
      grid.cells *= c;
    }
  }
  return grid;
}

void WavefrontPlanner::Setup(const PlanningProblem& problem) {
  Clear();
  const ParameterValues params = ResolveParameters(spec_, problem.parameters);
  const RobotModel& robot = problem.checker->robot();
  std::vector<int> moving;
  for (int i = 0; i < robot.num_dofs(); ++i) {
    (std::abs(problem.start[i] - problem.goal[i]) > kSameCoordinate ? moving : held_).push_back(i);
  }
  if (moving.size() > static_cast<std::size_t>(kMaxMoving)) {
    std::string names;
    for (std::size_t i = 0; i < moving.size(); ++i) names += (i == 0 ? "" : ", ") + robot.dof_names()[moving[i]];
    throw Error(ErrorCode::kFailedPrecondition,
                "wavefront plans over at most 3 moving coordinates; this query moves " + std::to_string(moving.size()) +
                    " (" + names + ") — use astar or a sampling planner");
  }
  resolution_ = params.at("resolution");
  per_coordinate_ = params.at("cells_per_coordinate");
  max_cells_ = params.at("max_cells");
  problem_ = problem;
  grid_ = MakeGrid(moving);
  if (grid_.total > max_cells_) {
    ThrowInvalid("planner.parameters['max_cells'] = " + FormatNumber(max_cells_) + " is below the " +
                 FormatNumber(grid_.total) + " cells (" + grid_.shape + ") of the wavefront grid at resolution " +
                 grid_.Resolution() + " (planner 'wavefront'); raise max_cells or coarsen resolution");
  }
  set_up_ = true;
}

WavefrontPlanner::Outcome WavefrontPlanner::Run(const Grid& grid, const Termination& termination,
                                                PlannerResult* result, std::uint64_t* checks,
                                                std::uint64_t* finalised) const {
  const CollisionChecker& checker = *problem_.checker;
  const Eigen::VectorXd& start = problem_.start;
  const Eigen::VectorXd& goal = problem_.goal;
  const int m = static_cast<int>(grid.coords.size());

  // Neighbour directions: every step in {-1, 0, 1}^m but zero.
  std::vector<Offset> offsets;
  const int combos = m == 1 ? 3 : m == 2 ? 9 : 27;
  for (int c = 0; c < combos; ++c) {
    Offset o;
    int rest = c;
    bool zero = true;
    double cost2 = 0.0;
    for (int i = 0; i < m; ++i) {
      o.step[i] = rest % 3 - 1;
      rest /= 3;
      zero = zero && o.step[i] == 0;
      o.delta += o.step[i] * grid.stride[i];
      cost2 += std::pow(o.step[i] * grid.spacing[i], 2);
    }
    if (zero) continue;
    o.cost = std::sqrt(cost2);
    offsets.push_back(o);
  }
  for (Offset& a : offsets) {
    for (std::size_t b = 0; b < offsets.size(); ++b) {
      if (offsets[b].delta == -a.delta) a.opposite = static_cast<int>(b);
    }
  }
  const auto neighbour = [&](std::int64_t cell, const Offset& o) -> std::int64_t {
    for (int i = 0; i < m; ++i) {
      const std::int64_t k = grid.Index(cell, i) + o.step[i];
      if (k < 0 || k >= grid.count[i]) return -1;
    }
    return cell + o.delta;
  };

  const auto n = static_cast<std::size_t>(grid.cells);
  std::vector<double> value(n, kInf);
  std::vector<std::uint8_t> flags(n, 0);
  std::vector<std::uint8_t> parent(n, 0);                   // offset index toward the goal
  std::unordered_map<std::int64_t, std::uint32_t> failed;  // cell -> offsets whose edge is blocked
  Eigen::VectorXd qa(start.size()), qb(start.size());
  const auto cell_valid = [&](std::int64_t c) {
    if (!(flags[c] & kKnown)) {
      grid.Config(goal, c, &qa);
      flags[c] |= kKnown | (StateValid(checker, qa, checks) ? kValid : 0);
    }
    return (flags[c] & kValid) != 0;
  };
  const auto blocked = [&](std::int64_t c, int dir) {
    const auto it = failed.find(c);
    return it != failed.end() && (it->second & (1u << dir)) != 0;
  };

  std::int64_t goal_cell = 0;
  for (int i = 0; i < m; ++i) goal_cell += -grid.kmin[i] * grid.stride[i];
  // The start's candidate cells: per coordinate the 4 nearest indices (2 on either side).
  {
    std::vector<std::vector<std::int64_t>> per(m);
    for (int i = 0; i < m; ++i) {
      const int d = grid.coords[i];
      const auto f = static_cast<std::int64_t>(std::floor((start[d] - goal[d]) / grid.spacing[i]));
      for (int dk = -1; dk <= 2; ++dk) {
        const std::int64_t k = std::clamp<std::int64_t>(f + dk - grid.kmin[i], 0, grid.count[i] - 1);
        if (std::find(per[i].begin(), per[i].end(), k) == per[i].end()) per[i].push_back(k);
      }
    }
    std::function<void(int, std::int64_t)> mark = [&](int i, std::int64_t base) {
      if (i == m) {
        flags[base] |= kCandidate;
        return;
      }
      for (const std::int64_t k : per[i]) mark(i + 1, base + k * grid.stride[i]);
    };
    mark(0, 0);
  }

  // Queue entries: (key, cell, offset index from the cell to the neighbour it is reached from).
  using Entry = std::tuple<double, std::int64_t, int>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
  value[goal_cell] = 0.0;
  flags[goal_cell] |= kKnown | kValid;
  queue.emplace(0.0, goal_cell, -1);
  double best_total = kInf;
  std::int64_t best_cell = -1;
  std::uint64_t pops = 0;
  while (!queue.empty()) {
    if ((++pops & 15) == 0 && termination.ShouldStop()) return Outcome::kStopped;
    const auto [key, v, dir] = queue.top();
    if (key >= best_total) break;  // no cell left can give a cheaper start connection
    queue.pop();
    if ((flags[v] & kDone) || key > value[v]) continue;  // finalised, or a stale entry
    if (dir >= 0) {
      if (blocked(v, dir)) continue;
      grid.Config(goal, v, &qa);
      grid.Config(goal, v + offsets[dir].delta, &qb);
      if (!MotionValid(checker, qa, qb, problem_.max_step, checks)) {
        // This edge is blocked: reach v from its next-best finalised neighbour instead.
        failed[v] |= 1u << dir;
        double next = kInf;
        int next_dir = -1;
        for (std::size_t k = 0; k < offsets.size(); ++k) {
          const std::int64_t w = neighbour(v, offsets[k]);
          if (w < 0 || !(flags[w] & kDone) || blocked(v, static_cast<int>(k))) continue;
          if (value[w] + offsets[k].cost < next) {
            next = value[w] + offsets[k].cost;
            next_dir = static_cast<int>(k);
          }
        }
        value[v] = next;
        if (next_dir >= 0) queue.emplace(next, v, next_dir);
        continue;
      }
      parent[v] = static_cast<std::uint8_t>(dir);
    }
    flags[v] |= kDone;
    ++*finalised;
    if (flags[v] & kCandidate) {
      grid.Config(goal, v, &qa);
      const double total = key + (qa - start).norm();
      if (total < best_total && MotionValid(checker, start, qa, problem_.max_step, checks)) {
        best_total = total;
        best_cell = v;
      }
    }
    for (std::size_t k = 0; k < offsets.size(); ++k) {
      const std::int64_t w = neighbour(v, offsets[k]);
      if (w < 0 || (flags[w] & kDone)) continue;
      const int back = offsets[k].opposite;  // from w toward v
      if (blocked(w, back) || !cell_valid(w)) continue;
      const double candidate = key + offsets[k].cost;
      if (candidate < value[w]) {
        value[w] = candidate;
        queue.emplace(candidate, w, back);
      }
    }
  }
  if (best_cell < 0) return Outcome::kNotConnected;

  // Descend: follow the parents from the start's cell; keep only the cells where the direction
  // changes (a straight run of validated edges is one straight motion).
  std::vector<std::int64_t> chain{best_cell};
  while (chain.back() != goal_cell) chain.push_back(chain.back() + offsets[parent[chain.back()]].delta);
  result->path.assign(1, start);
  for (std::size_t j = 0; j < chain.size(); ++j) {
    const bool corner = j == 0 || j + 1 == chain.size() || parent[chain[j]] != parent[chain[j - 1]];
    if (!corner) continue;
    grid.Config(goal, chain[j], &qa);
    result->path.push_back(qa);
  }
  result->path.back() = goal;
  // A start sitting on its cell: drop the cell when the start joins the next waypoint directly.
  if (result->path.size() > 2 && (result->path[1] - start).cwiseAbs().maxCoeff() <= kSameCoordinate &&
      MotionValid(checker, start, result->path[2], problem_.max_step, checks)) {
    result->path.erase(result->path.begin() + 1);
  }
  result->message = spec_.id + " descended " + std::to_string(chain.size() - 1) + " grid steps at resolution " +
                    grid.Resolution() + "; " + std::to_string(result->path.size()) + " waypoints";
  return Outcome::kFound;
}

PlannerResult WavefrontPlanner::Solve(const Termination& termination) {
  if (!set_up_) ThrowInvalid("planner '" + spec_.id + "': Solve() called before Setup()");
  const auto t0 = Termination::Clock::now();
  PlannerResult result;
  std::uint64_t checks = 0, finalised = 0;
  const auto finish = [&](PlannerResult r) {
    r.state_checks = checks;
    r.graph_states = finalised;
    r.solve_seconds = std::chrono::duration<double>(Termination::Clock::now() - t0).count();
    return r;
  };
  if (StoppedByClient(termination, spec_.id, &result)) return finish(result);
  if (!EndpointsValid(problem_, problem_.goal, spec_.id, &result, &checks)) return finish(result);
  if (grid_.coords.empty()) {  // start == goal up to 1e-9 per coordinate
    if (MotionValid(*problem_.checker, problem_.start, problem_.goal, problem_.max_step, &checks)) {
      result.path = {problem_.start, problem_.goal};
      result.status = PlanStatus::kExactSolution;
      result.message = spec_.id + ": the start is the goal";
    } else {
      result.status = PlanStatus::kNoSolution;
      result.message = spec_.id + ": the start is within 1e-9 of the goal but the motion between them collides";
    }
    return finish(result);
  }

  Outcome outcome = Run(grid_, termination, &result, &checks, &finalised);
  std::string widened;
  if (outcome == Outcome::kNotConnected && grid_.coords.size() < static_cast<std::size_t>(kMaxMoving) &&
      !held_.empty()) {
    // Blocked with the held coordinates fixed: release some (in configuration order) and retry.
    std::vector<int> coords = grid_.coords;
    for (std::size_t i = 0; i < held_.size() && coords.size() < static_cast<std::size_t>(kMaxMoving); ++i) {
      coords.push_back(held_[i]);
      widened += (widened.empty() ? "" : ", ") + problem_.checker->robot().dof_names()[held_[i]];
    }
    std::sort(coords.begin(), coords.end());
    const Grid wide = MakeGrid(coords);
    if (wide.total <= max_cells_) {
      outcome = Run(wide, termination, &result, &checks, &finalised);
    } else {
      widened += " not released: " + FormatNumber(wide.total) + " cells > max_cells";
    }
  }
  switch (outcome) {
    case Outcome::kFound:
      result.status = PlanStatus::kExactSolution;
      if (!widened.empty()) result.message += " (held coordinates released: " + widened + ")";
      break;
    case Outcome::kStopped:
      if (StoppedByClient(termination, spec_.id, &result)) break;
      result.status = PlanStatus::kNoSolution;
      result.message = spec_.id + " stopped by the time budget after finalising " + std::to_string(finalised) +
                       " grid cells";
      break;
    case Outcome::kNotConnected:
      result.status = PlanStatus::kLatticeExhausted;
      result.message = spec_.id + ": the start is not connected to the goal on the grid at resolution " +
                       grid_.Resolution() + " (" + grid_.shape + " cells" +
                       (widened.empty() ? std::string() : "; also with " + widened + " released") +
                       "); try a finer resolution";
      break;
  }
  return finish(result);
}

}  // namespace

PlannerSpec WavefrontSpec() {
  PlannerSpec spec;
  spec.id = "wavefront";
  spec.description =
      "Wavefront navigation function: Dijkstra from the goal over a grid of the (at most 3) coordinates in which start "
      "and goal differ, with lazily validated cells and edges, then steepest descent from the start. The other "
      "coordinates are held fixed (a planar robot or drone keeping its heading plans over x, y(, z)) unless the start "
      "is cut off with them fixed; then some are released, up to 3 grid coordinates";
  spec.optimizing = false;
  spec.parameters = {
      {"resolution", "grid spacing for every moving coordinate [rad or m]; 0 = each joint range / cells_per_coordinate",
       ParameterType::kDouble, 0.0, 0.0, 10.0},
      {"cells_per_coordinate", "cells across a moving coordinate's joint range when resolution = 0 [-]",
       ParameterType::kInt, 64.0, 2.0, 100000.0},
      {"max_cells", "largest grid accepted [-] (about 10 bytes per cell)", ParameterType::kInt, 4194304.0, 1.0,
       1e8},
  };
  return spec;
}

std::unique_ptr<Planner> MakeWavefrontPlanner(const PlannerSpec& spec) {
  return std::make_unique<WavefrontPlanner>(spec);
}

}  // namespace chasles::field
