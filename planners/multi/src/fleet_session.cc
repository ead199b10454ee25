#include "chasles/multi/fleet_session.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <deque>
#include <queue>
#include <stdexcept>
#include <unordered_map>
#include <utility>

#include "chasles/robot/error.h"
#include "rest_to_rest.h"

namespace chasles {
namespace {

using fleet_internal::AlongLimit;
using fleet_internal::Profile;

constexpr double kInf = std::numeric_limits<double>::infinity();

struct Interval {
  double start = -kInf, end = kInf;  ///< [start, end)
};

const LatticeDirection kDirections[4] = {LatticeDirection::kEast, LatticeDirection::kNorth, LatticeDirection::kWest,
                                         LatticeDirection::kSouth};

Eigen::Vector3d Unit(LatticeDirection direction) {
  switch (direction) {
    case LatticeDirection::kEast: return {1.0, 0.0, 0.0};
    case LatticeDirection::kNorth: return {0.0, 1.0, 0.0};
    case LatticeDirection::kWest: return {-1.0, 0.0, 0.0};
    case LatticeDirection::kSouth: return {0.0, -1.0, 0.0};
  }
  return Eigen::Vector3d::Zero();
}

/// The nodes reachable from `from` along free edges, in breadth-first order (`from` first);
/// *depth (optional) gets every cell's lattice distance from `from` [edges], -1 when unreachable.
std::vector<GridCell> BreadthFirst(const FleetLattice& lattice, GridCell from, std::vector<int>* depth) {
  const LatticeGeometry& g = lattice.geometry();
  std::vector<int> local;
  std::vector<int>& distance = depth != nullptr ? *depth : local;
  distance.assign(static_cast<std::size_t>(g.num_cells()), -1);
  std::vector<GridCell> order{from};
  distance[static_cast<std::size_t>(from)] = 0;
  for (std::size_t head = 0; head < order.size(); ++head) {
    const GridCell c = order[head];
    for (LatticeDirection d : kDirections) {
      if (!lattice.edge_free(c, d)) continue;
      const GridCell next = g.Neighbour(c, d);
      if (distance[static_cast<std::size_t>(next)] >= 0) continue;
      distance[static_cast<std::size_t>(next)] = distance[static_cast<std::size_t>(c)] + 1;
      order.push_back(next);
    }
  }
  return order;
}

std::string RobotField(int robot) { return "robots[" + std::to_string(robot) + "]"; }

std::string PointText(const Eigen::Vector2d& p) { return "(" + FormatNumber(p.x()) + ", " + FormatNumber(p.y()) + ")"; }

void ValidateLimits(const Eigen::Vector3d& v, const std::string& field) {
  for (int k = 0; k < 3; ++k) {
    if (!(std::isfinite(v[k]) && v[k] > 0.0)) {
      ThrowInvalid(field + "[" + std::to_string(k) + "] = " + FormatNumber(v[k]) + " must be finite and > 0");
    }
  }
}

}  // namespace

/// A found motion: cells[0] the anchor; run r goes cells[r] -> cells[r+1] (edges[r] edges in
/// directions[r]) leaving at departs[r], taking durations[r].
struct FleetSession::SearchResult {
  bool found = false;
  bool stopped = false;
  std::vector<GridCell> cells;
  std::vector<double> departs, durations;
  std::vector<LatticeDirection> directions;  ///< of run r
  std::vector<int> edges;                    ///< lattice edges run r covers
  std::size_t expansions = 0;
};

/// SIPP for one robot against the others' occupancy (see the file comment of fleet_session.h),
/// less the parking of the robots marked in `ignored`.
class FleetSession::Search {
 public:
  Search(const FleetSession& session, int robot, const std::vector<char>& ignored, const Termination& termination)
      : session_(session), robot_(robot), ignored_(ignored), termination_(termination) {
    const LatticeGeometry& g = session.lattice_->geometry();
    const FleetSessionRobot& limits = session.robots_[static_cast<std::size_t>(robot)].limits;
    max_run_ = std::max(1, session.options_.max_run);
    for (int d = 0; d < 4; ++d) {
      const Eigen::Vector3d unit = Unit(kDirections[d]);
      const double v = AlongLimit(unit, limits.max_velocity), a = AlongLimit(unit, limits.max_acceleration);
      durations_[d].resize(static_cast<std::size_t>(max_run_) + 1, 0.0);
      for (int k = 1; k <= max_run_; ++k) durations_[d][static_cast<std::size_t>(k)] = Profile(k * g.spacing, v, a).duration;
    }
    fastest_v_ = std::max(limits.max_velocity.x(), limits.max_velocity.y());
    fastest_a_ = std::max(limits.max_acceleration.x(), limits.max_acceleration.y());
  }

  /// The robot's safe intervals at `cell`, sorted (cached).
  const std::vector<Interval>& Safe(GridCell cell) {
    auto [it, inserted] = safe_.try_emplace(cell);
    if (!inserted) return it->second;
    std::vector<Interval> busy;
    for (const Occupancy& o : session_.occupancy_[static_cast<std::size_t>(cell)]) {
      if (o.robot == robot_ || (o.leave == kInf && ignored_[static_cast<std::size_t>(o.robot)])) continue;
      busy.push_back({o.enter - kGuard, o.leave + kGuard});
    }
    std::sort(busy.begin(), busy.end(), [](const Interval& a, const Interval& b) { return a.start < b.start; });
    std::vector<Interval>& safe = it->second;
    double from = -kInf;
    for (const Interval& b : busy) {
      if (b.start > from) safe.push_back({from, b.start});
      from = std::max(from, b.end);
    }
    if (from < kInf) safe.push_back({from, kInf});
    return safe;
  }

  /// Index of the safe interval of `cell` holding t, or -1.
  int IntervalAt(GridCell cell, double t) {
    const std::vector<Interval>& safe = Safe(cell);
    for (std::size_t i = 0; i < safe.size(); ++i) {
      if (safe[i].start <= t && t < safe[i].end) return static_cast<int>(i);
    }
    return -1;
  }

  SearchResult Run(GridCell start, double t0, GridCell goal) {
    SearchResult result;
    const LatticeGeometry& g = session_.lattice_->geometry();
    std::vector<int> distance;
    BreadthFirst(*session_.lattice_, goal, &distance);
    if (distance[static_cast<std::size_t>(start)] < 0) return result;
    const int first = IntervalAt(start, t0);
    if (first < 0) return result;  // someone else holds the start (cannot happen for a consistent session)

    struct Node {
      GridCell cell;
      int interval;
      double arrival;
      int parent;
      double depart, duration;
      LatticeDirection direction;
      int edges;
    };
    std::vector<Node> nodes;
    std::unordered_map<std::uint64_t, int> index;
    using Entry = std::pair<double, int>;  // f, node
    std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> open;
    const auto key = [](GridCell c, int i) { return (static_cast<std::uint64_t>(c) << 20) | static_cast<std::uint64_t>(i); };
    const auto heuristic = [&](GridCell c) {
      return Profile(distance[static_cast<std::size_t>(c)] * g.spacing, fastest_v_, fastest_a_).duration;
    };
    nodes.push_back({start, first, t0, -1, 0.0, 0.0, LatticeDirection::kEast, 0});
    index[key(start, first)] = 0;
    open.push({t0 + heuristic(start), 0});
    while (!open.empty()) {
      const int n = open.top().second;
      open.pop();
      const Node node = nodes[static_cast<std::size_t>(n)];
      if (index[key(node.cell, node.interval)] != n) continue;  // reached sooner since it was queued
      if (++result.expansions % 256 == 0 && termination_.ShouldStop()) {
        result.stopped = true;
        return result;
      }
      if (result.expansions > session_.options_.max_expansions) return result;
      const Interval here = Safe(node.cell)[static_cast<std::size_t>(node.interval)];
      if (node.cell == goal && here.end == kInf) {
        std::vector<int> chain;
        for (int k = n; k >= 0; k = nodes[static_cast<std::size_t>(k)].parent) chain.push_back(k);
        std::reverse(chain.begin(), chain.end());
        for (std::size_t k = 0; k < chain.size(); ++k) {
          const Node& c = nodes[static_cast<std::size_t>(chain[k])];
          result.cells.push_back(c.cell);
          if (k > 0) {
            result.departs.push_back(c.depart);
            result.durations.push_back(c.duration);
            result.directions.push_back(c.direction);
            result.edges.push_back(c.edges);
          }
        }
        result.found = true;
        return result;
      }
      for (int d = 0; d < 4; ++d) {
        GridCell at = node.cell;
        std::vector<GridCell> along;
        for (int k = 1; k <= max_run_; ++k) {
          if (!session_.lattice_->edge_free(at, kDirections[d])) break;
          at = g.Neighbour(at, kDirections[d]);
          along.push_back(at);
          const double duration = durations_[d][static_cast<std::size_t>(k)];
          if (node.arrival + duration > here.end) break;  // cannot even leave now and arrive in time
          Relax(node, n, here, kDirections[d], along, duration, &nodes, &index, &open, key, heuristic);
        }
      }
    }
    return result;
  }

 private:
  template <typename Nodes, typename Index, typename Open, typename Key, typename Heuristic>
  void Relax(const typename Nodes::value_type& node, int n, const Interval& here, LatticeDirection direction,
             const std::vector<GridCell>& along, double duration, Nodes* nodes, Index* index, Open* open,
             const Key& key, const Heuristic& heuristic) {
    const GridCell target = along.back();
    const std::vector<Interval>& arrive = Safe(target);
    for (std::size_t j = 0; j < arrive.size(); ++j) {
      const Interval& J = arrive[j];
      if (J.end <= node.arrival + duration) continue;
      double depart = std::max(node.arrival, J.start);
      bool found = false;
      while (depart + duration <= here.end && depart + duration < J.end) {
        bool moved = false;
        for (std::size_t m = 0; m + 1 < along.size(); ++m) {
          const double later = LatestConflictFree(along[m], depart, duration);
          if (later != depart) {
            depart = later;
            moved = true;
            break;
          }
        }
        if (!moved) {
          found = true;
          break;
        }
      }
      if (!found) {
        if (depart + duration > here.end) return;  // later intervals only leave later
        continue;
      }
      const double arrival = depart + duration;
      const std::uint64_t k = key(target, static_cast<int>(j));
      const auto it = index->find(k);
      if (it != index->end() && (*nodes)[static_cast<std::size_t>(it->second)].arrival <= arrival) continue;
      const int id = static_cast<int>(nodes->size());
      nodes->push_back({target, static_cast<int>(j), arrival, n, depart, duration, direction,
                        static_cast<int>(along.size())});
      (*index)[k] = id;
      open->push({arrival + heuristic(target), id});
    }
  }

  /// `depart` when the cell is safe over [depart, depart + duration); else the start of the next
  /// safe interval that could hold it (or +inf).
  double LatestConflictFree(GridCell cell, double depart, double duration) {
    for (const Interval& s : Safe(cell)) {
      if (s.end < depart + duration) continue;
      return std::max(depart, s.start);
    }
    return kInf;
  }

  const FleetSession& session_;
  int robot_;
  const std::vector<char>& ignored_;
  const Termination& termination_;
  int max_run_ = 1;
  std::vector<double> durations_[4];
  double fastest_v_ = 1.0, fastest_a_ = 1.0;
  std::unordered_map<GridCell, std::vector<Interval>> safe_;
};

FleetSession::FleetSession(std::shared_ptr<const FleetLattice> lattice, std::vector<FleetSessionRobot> robots,
                           double start_time, FleetSessionOptions options)
    : lattice_(std::move(lattice)),
      options_(options),
      start_time_(start_time),
      forgotten_(start_time),
      latest_now_(start_time) {
  if (lattice_ == nullptr) ThrowInvalid("lattice is null");
  if (!std::isfinite(start_time)) ThrowInvalid("start_time = " + FormatNumber(start_time) + " must be finite");
  const LatticeGeometry& g = lattice_->geometry();
  occupancy_.resize(static_cast<std::size_t>(g.num_cells()));
  std::vector<int> holder(static_cast<std::size_t>(g.num_cells()), -1);
  robots_.resize(robots.size());
  for (std::size_t i = 0; i < robots.size(); ++i) {
    const std::string field = RobotField(static_cast<int>(i));
    ValidateLimits(robots[i].max_velocity, field + ".max_velocity");
    ValidateLimits(robots[i].max_acceleration, field + ".max_acceleration");
    if (!std::isfinite(robots[i].pose.z())) ThrowInvalid(field + ".pose heading must be finite");
    const GridCell cell = g.NodeAt(robots[i].pose.head<2>(), field + ".pose");
    if (!lattice_->node_free(cell)) {
      ThrowInvalid(field + ".pose = " + PointText(robots[i].pose.head<2>()) + " is on a blocked lattice node (cell " +
                   std::to_string(cell) + "): its footprint there touches the scene");
    }
    if (holder[static_cast<std::size_t>(cell)] >= 0) {
      ThrowInvalid(field + ".pose = " + PointText(robots[i].pose.head<2>()) + " is on the node of " +
                   RobotField(holder[static_cast<std::size_t>(cell)]) + " (cell " + std::to_string(cell) + ")");
    }
    holder[static_cast<std::size_t>(cell)] = static_cast<int>(i);
    RobotState& state = robots_[i];
    state.limits = robots[i];
    state.heading = robots[i].pose.z();
    Eigen::VectorXd at(3);
    at << g.Position(cell).x(), g.Position(cell).y(), robots[i].pose.z();
    state.plan.start_time = start_time;
    state.plan.arrival_time = start_time;
    state.plan.finish_time = start_time;
    state.plan.trajectory = TimedTrajectory({LinePiece(0.0, 0.0, at, Eigen::VectorXd::Zero(3), 0.0, 0.0, 0.0)}, at);
    state.visits.push_back({cell, start_time, kInf});
    Index(static_cast<int>(i));
  }
}

const FleetSessionPlan& FleetSession::plan(int robot) const {
  if (robot < 0 || robot >= num_robots()) ThrowInvalid("robot = " + std::to_string(robot) + " is out of range");
  return robots_[static_cast<std::size_t>(robot)].plan;
}

Eigen::Vector3d FleetSession::PoseAt(int robot, double t) const {
  const FleetSessionPlan& p = plan(robot);
  return p.trajectory.Evaluate(t - p.start_time).q.head<3>();
}

std::size_t FleetSession::occupancy_size() const {
  std::size_t n = 0;
  for (const auto& cell : occupancy_) n += cell.size();
  return n;
}

void FleetSession::Index(int robot) {
  for (const Visit& v : robots_[static_cast<std::size_t>(robot)].visits) {
    occupancy_[static_cast<std::size_t>(v.cell)].push_back({v.enter, v.leave, robot});
  }
}

void FleetSession::Unindex(int robot) {
  for (const Visit& v : robots_[static_cast<std::size_t>(robot)].visits) {
    auto& cell = occupancy_[static_cast<std::size_t>(v.cell)];
    cell.erase(std::remove_if(cell.begin(), cell.end(), [&](const Occupancy& o) { return o.robot == robot; }),
               cell.end());
  }
}

void FleetSession::Forget(double before) {
  if (before <= forgotten_) return;
  forgotten_ = before;
  for (auto& cell : occupancy_) {
    cell.erase(std::remove_if(cell.begin(), cell.end(), [&](const Occupancy& o) { return o.leave + kGuard < before; }),
               cell.end());
  }
  for (RobotState& state : robots_) {
    auto& visits = state.visits;
    const auto keep = std::find_if(visits.begin(), visits.end(), [&](const Visit& v) { return v.leave + kGuard >= before; });
    visits.erase(visits.begin(), keep);
  }
}

bool FleetSession::Idle(int robot, double now) const {
  return robots_[static_cast<std::size_t>(robot)].plan.finish_time <= now;
}

FleetSession::Visit FleetSession::Anchor(int robot, double now) const {
  const RobotState& state = robots_[static_cast<std::size_t>(robot)];
  const FleetSessionPlan& p = state.plan;
  const LatticeGeometry& g = lattice_->geometry();
  if (now >= p.arrival_time) {
    // Parked at its last node (perhaps still turning: the new plan starts when the turn ends).
    return {state.visits.back().cell, std::max(now, p.finish_time), 0.0};
  }
  GridCell cell = g.NodeAt(p.trajectory.Evaluate(0.0).q.head<2>(), "plan start");
  // A plan that has not started yet: the robot still finishes the run it was on.
  if (now < p.start_time) return {cell, p.start_time, 0.0};
  for (const FleetRun& run : p.runs) {
    if (run.start_time > now) break;
    cell = run.to;
    if (now < run.end_time) return {run.to, run.end_time, 0.0};  // on this run: it ends first
  }
  return {cell, now, 0.0};
}

FleetSession::RobotState FleetSession::Replanned(int robot, const Visit& anchor, const SearchResult& result,
                                                 double goal_heading) const {
  const RobotState& old = robots_[static_cast<std::size_t>(robot)];
  const LatticeGeometry& g = lattice_->geometry();
  RobotState state;
  state.limits = old.limits;
  const double t0 = anchor.enter;
  // Visits done by t0 stay (they are history, or the run the robot finishes first); the visit of
  // the anchor node keeps its start.
  double anchor_enter = t0;
  for (const Visit& v : old.visits) {
    if (v.cell == anchor.cell && v.enter <= t0 && t0 < v.leave) {
      anchor_enter = v.enter;
    } else if (v.leave <= t0) {
      state.visits.push_back(v);
    }
  }
  const std::size_t runs = result.departs.size();
  state.visits.push_back({anchor.cell, anchor_enter, runs == 0 ? kInf : result.departs[0] + result.durations[0]});
  // The heading the robot has at t0.
  double heading = old.heading;
  if (t0 < old.plan.finish_time) heading = old.plan.trajectory.Evaluate(t0 - old.plan.start_time).q[2];

  std::vector<TimedTrajectory::Piece> pieces;
  Eigen::VectorXd at(3);
  at << g.Position(anchor.cell).x(), g.Position(anchor.cell).y(), heading;
  double t = 0.0;  // trajectory time
  for (std::size_t r = 0; r < runs; ++r) {
    const GridCell from = result.cells[r], to = result.cells[r + 1];
    const double depart = result.departs[r], duration = result.durations[r];
    const double end = depart + duration;
    // Cells along the run, the end node until it leaves again.
    GridCell cell = from;
    for (int k = 1; k < result.edges[r]; ++k) {
      cell = g.Neighbour(cell, result.directions[r]);
      state.visits.push_back({cell, depart, end});
    }
    const double leave = r + 1 < runs ? result.departs[r + 1] + result.durations[r + 1] : kInf;
    state.visits.push_back({to, depart, leave});

    if (depart - t0 > t) pieces.push_back(LinePiece(t, depart - t0 - t, at, Eigen::VectorXd::Zero(3), 0.0, 0.0, 0.0));
    t = depart - t0;
    // The run the search timed: edges × spacing along its direction, at the robot's limits.
    const Eigen::Vector3d unit = Unit(result.directions[r]);
    const Profile profile(result.edges[r] * g.spacing, AlongLimit(unit, state.limits.max_velocity),
                          AlongLimit(unit, state.limits.max_acceleration));
    profile.AppendPieces(t, at, Eigen::VectorXd(unit), &pieces);
    t += profile.duration;
    at << g.Position(to).x(), g.Position(to).y(), heading;
    state.plan.runs.push_back({static_cast<int>(r), static_cast<int>(r), from, to, depart, t0 + t});
  }
  state.plan.start_time = t0;
  state.plan.arrival_time = t0 + t;
  const double turn = goal_heading - heading;
  if (turn != 0.0) {
    const Profile profile(std::abs(turn), state.limits.max_velocity.z(), state.limits.max_acceleration.z());
    Eigen::VectorXd axis = Eigen::VectorXd::Zero(3);
    axis[2] = turn > 0.0 ? 1.0 : -1.0;
    profile.AppendPieces(t, at, axis, &pieces);
    t += profile.duration;
    at[2] = goal_heading;
  }
  if (pieces.empty()) pieces.push_back(LinePiece(0.0, 0.0, at, Eigen::VectorXd::Zero(3), 0.0, 0.0, 0.0));
  state.plan.finish_time = t0 + t;
  state.plan.trajectory = TimedTrajectory(std::move(pieces), at);
  state.heading = goal_heading;
  return state;
}

std::string FleetSession::Name(int robot) const {
  const std::string& name = robots_[static_cast<std::size_t>(robot)].limits.name;
  return name.empty() ? "robot " + std::to_string(robot) : "robot '" + name + "'";
}

GridCell FleetSession::Refuge(int robot, const std::vector<char>& avoid, GridCell goal, double now) const {
  const GridCell from = robots_[static_cast<std::size_t>(robot)].visits.back().cell;
  for (const GridCell c : BreadthFirst(*lattice_, from, nullptr)) {
    const auto& here = occupancy_[static_cast<std::size_t>(c)];
    const bool untouched =
        std::none_of(here.begin(), here.end(), [&](const Occupancy& o) { return o.robot != robot && o.leave > now; });
    if (c != goal && !avoid[static_cast<std::size_t>(c)] && untouched) return c;
  }
  return -1;
}

void FleetSession::Shift(int robot, double from, double delta) {
  RobotState& state = robots_[static_cast<std::size_t>(robot)];
  Unindex(robot);
  for (Visit& v : state.visits) {
    if (v.enter >= from) v.enter += delta;
    if (v.leave > from) v.leave += delta;  // +inf stays
  }
  Index(robot);
  FleetSessionPlan& p = state.plan;
  for (FleetRun& run : p.runs) {
    if (run.start_time >= from) {
      run.start_time += delta;
      run.end_time += delta;
    }
  }
  if (p.arrival_time >= from) p.arrival_time += delta;
  if (p.finish_time >= from) p.finish_time += delta;
  // The trajectory: at rest where it stands at `from` for delta, every later piece delta later.
  // `from` is a piece boundary (a run starts there, at rest), up to the rounding of times
  // shifted before: the boundary nearest it is taken.
  const double local = std::max(0.0, from - p.start_time);
  const auto& old = p.trajectory.pieces();
  std::size_t split = old.size();
  for (std::size_t i = 0; i < old.size(); ++i) {
    if (old[i].t0 >= local - 1e-9 * std::max(1.0, std::abs(local))) {
      split = i;
      break;
    }
  }
  const double at = split < old.size() ? old[split].t0 : p.trajectory.duration();
  std::vector<TimedTrajectory::Piece> pieces(old.begin(), old.begin() + static_cast<std::ptrdiff_t>(split));
  pieces.push_back(LinePiece(at, delta, p.trajectory.Evaluate(at).q, Eigen::VectorXd::Zero(3), 0.0, 0.0, 0.0));
  for (std::size_t i = split; i < old.size(); ++i) {
    pieces.push_back(old[i]);
    pieces.back().t0 = at + delta + (old[i].t0 - at);
  }
  const Eigen::VectorXd end = p.trajectory.Evaluate(p.trajectory.duration()).q;
  p.trajectory = TimedTrajectory(std::move(pieces), end);
}

std::vector<int> FleetSession::Delay(int robot, double from, double delta) {
  // Robot by robot: wherever a delayed robot now overlaps another at a node, the later of the
  // two in the node's planned order waits until the earlier has left, until no two occupy a node
  // at once. Each conflict is measured on the plans as they are then, and delays only grow, so
  // it ends.
  std::vector<int> robots;
  std::vector<char> delayed(robots_.size(), 0);
  // The order at each node is the plans' before any delay: each visit's entry then, per robot
  // (visits keep their indices while delays shift them).
  std::vector<std::vector<double>> entered(robots_.size());
  const auto original_entry = [&](int r, GridCell cell, double enter) {
    const auto& visits = robots_[static_cast<std::size_t>(r)].visits;
    for (std::size_t i = 0; i < visits.size(); ++i) {
      if (visits[i].cell == cell && visits[i].enter == enter) {
        return delayed[static_cast<std::size_t>(r)] ? entered[static_cast<std::size_t>(r)][i] : enter;
      }
    }
    return enter;  // (not reached: every occupancy is a visit)
  };
  const auto delay = [&](int r, double at, double by) {
    if (!(by > 0.0) || !std::isfinite(by)) {
      throw std::logic_error("FleetSession::Delay: a delay of " + FormatNumber(by) + " s");
    }
    if (!delayed[static_cast<std::size_t>(r)]) {
      delayed[static_cast<std::size_t>(r)] = 1;
      for (const Visit& v : robots_[static_cast<std::size_t>(r)].visits) entered[static_cast<std::size_t>(r)].push_back(v.enter);
      robots.push_back(r);
    }
    Shift(r, at, by);
  };
  delay(robot, from, delta);
  std::deque<int> queue{robot};
  constexpr std::size_t kMaxShifts = 1000000;
  std::size_t shifts = 0;
  while (!queue.empty()) {
    const int r = queue.front();
    queue.pop_front();
    for (;;) {
      // Of the nodes where a delayed robot now overlaps another, the earliest: whichever of the
      // two came second there waits until the first has left.
      int later = -1;
      double at = kInf, by = 0.0;
      for (const Visit& v : robots_[static_cast<std::size_t>(r)].visits) {
        for (const Occupancy& o : occupancy_[static_cast<std::size_t>(v.cell)]) {
          if (o.robot == r || o.leave + kGuard <= v.enter || v.leave + kGuard <= o.enter) continue;
          const bool other_later = original_entry(o.robot, v.cell, o.enter) > original_entry(r, v.cell, v.enter);
          const double enter = other_later ? o.enter : v.enter;
          if (enter < at) {
            later = other_later ? o.robot : r;
            at = enter;
            by = (other_later ? v.leave : o.leave) + kGuard - enter;
          }
        }
      }
      if (later < 0) break;
      if (++shifts > kMaxShifts) throw std::logic_error("FleetSession::Delay: delay propagation did not settle");
      delay(later, at, by);  // (Shift changes occupancy_: the scan starts over)
      queue.push_back(later);
    }
  }
  return robots;
}

FleetStateOutcome FleetSession::Report(int robot, const Eigen::Vector2d& position, double time, double tolerance) {
  if (robot < 0 || robot >= num_robots()) {
    ThrowInvalid("robot = " + std::to_string(robot) + " must be in [0, " + std::to_string(num_robots()) + ")");
  }
  if (!position.allFinite()) ThrowInvalid("position = " + PointText(position) + " must be finite");
  if (!std::isfinite(tolerance) || !(tolerance > 0.0)) {
    ThrowInvalid("tolerance = " + FormatNumber(tolerance) + " must be finite and > 0");
  }
  CheckNow(time);
  time = std::max(time, latest_now_);
  Advance(time);
  FleetStateOutcome out;
  const RobotState& state = robots_[static_cast<std::size_t>(robot)];
  const FleetSessionPlan& p = state.plan;
  out.planned = PoseAt(robot, time);
  out.deviation = (position - out.planned.head<2>()).norm();
  if (out.deviation <= tolerance) {
    out.message = Name(robot) + " is on its plan (" + FormatNumber(out.deviation) + " m from it)";
    return out;
  }
  // The runs the point lies on (within the tolerance), and the plan's time there: the run is
  // straight and rest to rest, so its progress along the run grows with time (bisection).
  const LatticeGeometry& g = lattice_->geometry();
  const FleetRun* on = nullptr;
  double at_time = 0.0;
  for (const FleetRun& run : p.runs) {
    const Eigen::Vector2d a = g.Position(run.from), b = g.Position(run.to);
    const Eigen::Vector2d ab = b - a;
    const double u = std::clamp((position - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
    if ((a + u * ab - position).norm() > tolerance) continue;
    const auto progress = [&](double t) {
      return (p.trajectory.Evaluate(t - p.start_time).q.head<2>() - a).dot(ab) / ab.squaredNorm();
    };
    double lo = run.start_time, hi = run.end_time;
    if (u <= 0.0) {
      hi = lo;
    } else {
      for (int k = 0; k < 60; ++k) {
        const double mid = 0.5 * (lo + hi);
        (progress(mid) < u ? lo : hi) = mid;
      }
    }
    // Of several runs through the point (a path crossing itself), the one nearest in time.
    if (on == nullptr || std::abs(time - hi) < std::abs(time - at_time)) {
      on = &run;
      at_time = hi;
    }
  }
  if (on == nullptr) {
    out.status = FleetStateStatus::kOffPlan;
    out.message = Name(robot) + " is at " + PointText(position) + ", " + FormatNumber(out.deviation) +
                  " m from its planned position " + PointText(out.planned.head<2>()) +
                  " and off every run of its plan: nothing changed";
    return out;
  }
  out.delay = time - at_time;
  if (out.delay <= 0.0) {
    out.status = FleetStateStatus::kAhead;
    out.message = Name(robot) + " is " + FormatNumber(-out.delay) + " s ahead of its plan: nothing changed";
    return out;
  }
  out.status = FleetStateStatus::kLate;
  out.robots = Delay(robot, on->start_time, out.delay);
  out.orders = OrdersOf(out.robots, time);
  out.message = Name(robot) + " is " + FormatNumber(out.delay) + " s behind its plan: delayed, with " +
                std::to_string(out.robots.size() - 1) + " robots ordered after it";
  return out;
}

std::vector<FleetSessionOrder> FleetSession::OrdersOf(const std::vector<int>& robots, double from) const {
  std::vector<FleetSessionOrder> orders;
  for (int r : robots) {
    std::vector<FleetSessionOrder> of = OrdersOf(r, from);
    orders.insert(orders.end(), of.begin(), of.end());
  }
  return orders;
}

std::vector<FleetSessionOrder> FleetSession::OrdersOf(int robot, double from) const {
  std::vector<FleetSessionOrder> orders;
  const LatticeGeometry& g = lattice_->geometry();
  for (const Visit& v : robots_[static_cast<std::size_t>(robot)].visits) {
    if (v.leave <= from) continue;
    const Occupancy* before = nullptr;
    const Occupancy* after = nullptr;
    for (const Occupancy& o : occupancy_[static_cast<std::size_t>(v.cell)]) {
      if (o.robot == robot) continue;
      if (o.leave <= v.enter + kGuard && (before == nullptr || o.leave > before->leave)) before = &o;
      if (o.enter >= v.leave - kGuard && (after == nullptr || o.enter < after->enter)) after = &o;
    }
    const Eigen::Vector2d p = g.Position(v.cell);
    if (before != nullptr && before->leave > from) {
      orders.push_back({before->robot, robot, v.cell, p.x(), p.y(), before->leave, v.enter});
    }
    if (after != nullptr) orders.push_back({robot, after->robot, v.cell, p.x(), p.y(), v.leave, after->enter});
  }
  return orders;
}

GridCell FleetSession::GoalCell(const Eigen::Vector3d& goal, const std::string& field) const {
  if (!std::isfinite(goal.z())) ThrowInvalid(field + " heading must be finite");
  const GridCell cell = lattice_->geometry().NodeAt(goal.head<2>(), field);
  if (!lattice_->node_free(cell)) {
    ThrowInvalid(field + " = " + PointText(goal.head<2>()) + " is on a blocked lattice node (cell " +
                 std::to_string(cell) + "): the footprint there touches the scene");
  }
  return cell;
}

void FleetSession::CheckNow(double now) const {
  if (!std::isfinite(now) || now < start_time_) {
    ThrowInvalid("now = " + FormatNumber(now) + " must be finite and not before the session's start " +
                 FormatNumber(start_time_));
  }
}

void FleetSession::Advance(double now) {
  latest_now_ = std::max(latest_now_, now);
  if (++assigns_ % 32 == 0) Forget(now - 1.0);
}

void FleetSession::Skip(double now) {
  CheckNow(now);
  Advance(now);
}

FleetGoalOutcome FleetSession::Assign(int robot, const Eigen::Vector3d& goal, double now,
                                      const Termination& termination) {
  const auto started = std::chrono::steady_clock::now();
  if (robot < 0 || robot >= num_robots()) {
    ThrowInvalid("robot = " + std::to_string(robot) + " must be in [0, " + std::to_string(num_robots()) + ")");
  }
  CheckNow(now);
  now = std::max(now, latest_now_);  // the session's clock never goes back
  const LatticeGeometry& g = lattice_->geometry();
  const GridCell goal_cell = GoalCell(goal, "goal");
  Advance(now);

  FleetGoalOutcome outcome;
  std::vector<std::pair<int, RobotState>> saved;  // for rollback, first change of each robot
  const auto commit = [&](int r, RobotState state) {
    if (std::none_of(saved.begin(), saved.end(), [&](const auto& s) { return s.first == r; })) {
      saved.emplace_back(r, robots_[static_cast<std::size_t>(r)]);
    }
    Unindex(r);
    robots_[static_cast<std::size_t>(r)] = std::move(state);
    Index(r);
  };
  const auto finish = [&](FleetGoalCode code, std::string message) {
    outcome.code = code;
    outcome.message = std::move(message);
    if (code != FleetGoalCode::kSuccess) {
      for (auto it = saved.rbegin(); it != saved.rend(); ++it) {
        Unindex(it->first);
        robots_[static_cast<std::size_t>(it->first)] = std::move(it->second);
        Index(it->first);
      }
      outcome.robots.clear();
    } else {
      outcome.orders = OrdersOf(outcome.robots, now);
    }
    outcome.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    return outcome;
  };
  const auto search = [&](int r, const std::vector<char>& ignored, GridCell to) {
    const Visit anchor = Anchor(r, now);
    Search s(*this, r, ignored, termination);
    SearchResult result = s.Run(anchor.cell, anchor.enter, to);
    outcome.expansions += result.expansions;
    ++outcome.searches;
    return std::make_pair(anchor, std::move(result));
  };
  // Another robot parks on the goal for good while still on its way there: nothing to move aside.
  for (const Occupancy& o : occupancy_[static_cast<std::size_t>(goal_cell)]) {
    if (o.robot != robot && o.leave == kInf && !Idle(o.robot, now)) {
      return finish(FleetGoalCode::kNoPath, "the goal node " + PointText(g.Position(goal_cell)) + " (cell " +
                                                std::to_string(goal_cell) + ") is where " + Name(o.robot) +
                                                " is going to park");
    }
  }
  const std::vector<char> none(robots_.size(), 0);
  int moved = 0;
  for (int round = 0; round <= options_.evasion_rounds; ++round) {
    auto [anchor, result] = search(robot, none, goal_cell);
    if (result.stopped) return finish(FleetGoalCode::kStopped, "stopped before a plan was found");
    if (result.found) {
      commit(robot, Replanned(robot, anchor, result, goal.z()));
      outcome.robots.insert(outcome.robots.begin(), robot);
      return finish(FleetGoalCode::kSuccess, "");
    }
    if (round == options_.evasion_rounds) break;
    // The window: plan through parked robots, then move the idle ones on the way aside (a robot
    // still on its way to park there is named instead).
    std::vector<char> parked(robots_.size(), 1);
    auto [through_anchor, through] = search(robot, parked, goal_cell);
    if (through.stopped) return finish(FleetGoalCode::kStopped, "stopped before a plan was found");
    if (!through.found) break;
    const RobotState probe = Replanned(robot, through_anchor, through, goal.z());
    std::vector<char> on_path(static_cast<std::size_t>(g.num_cells()), 0);
    for (const Visit& v : probe.visits) {
      if (v.leave > now) on_path[static_cast<std::size_t>(v.cell)] = 1;
    }
    std::vector<int> in_the_way;
    for (int r = 0; r < num_robots(); ++r) {
      const RobotState& other = robots_[static_cast<std::size_t>(r)];
      if (r == robot || !on_path[static_cast<std::size_t>(other.visits.back().cell)]) continue;
      if (!Idle(r, now)) {
        const Eigen::Vector2d p = g.Position(other.visits.back().cell);
        return finish(FleetGoalCode::kNoPath,
                      Name(r) + " is going to park at " + PointText(p) + " (cell " +
                          std::to_string(other.visits.back().cell) + ") on the way, idle from t = " +
                          FormatNumber(other.plan.finish_time) + " s: send it on first, or this goal after then");
      }
      in_the_way.push_back(r);
    }
    if (in_the_way.empty()) break;
    for (int j : in_the_way) {
      if (++moved > options_.max_evasions) {
        return finish(FleetGoalCode::kNoPath, "more than " + std::to_string(options_.max_evasions) +
                                                  " idle robots stand in the way");
      }
      const GridCell refuge = Refuge(j, on_path, goal_cell, now);
      if (refuge < 0) return finish(FleetGoalCode::kNoPath, "idle " + Name(j) + " has nowhere to go");
      auto [j_anchor, aside] = search(j, none, refuge);
      if (aside.stopped) return finish(FleetGoalCode::kStopped, "stopped before a plan was found");
      if (!aside.found) {
        return finish(FleetGoalCode::kNoPath, "idle " + Name(j) + " cannot move out of the way");
      }
      commit(j, Replanned(j, j_anchor, aside, robots_[static_cast<std::size_t>(j)].heading));
      outcome.robots.push_back(j);
    }
  }
  return finish(FleetGoalCode::kNoPath, "no path to the goal among the other robots' trajectories");
}

}  // namespace chasles
