// Grid MAPF: LaCAM* over joint configurations with PIBT as its successor generator, then large
// neighbourhood search, written from the papers (Okumura et al., "Priority inheritance with
// backtracking for iterative multi-agent path finding", AIJ 2022; Okumura, "LaCAM: search-based
// algorithm for quick multi-agent pathfinding", AAAI 2023; Okumura, "Improving LaCAM for
// scalable eventually optimal multi-agent pathfinding", IJCAI 2023; Li et al., "Anytime
// multi-agent path finding via large neighborhood search", IJCAI 2021), adapted to forbid
// rotation cycles (grid_mapf.h), with rules of our own for pockets (docs/architecture.md).
//
// Inside the solver a cell is a compact id over the free cells (a "vertex"); configurations are
// vectors of vertices, one per robot. CheckMapfPlan at the end of this file shares no code with
// the solver.

#include "chasles/multi/grid_mapf.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <deque>
#include <limits>
#include <memory>
#include <new>
#include <queue>
#include <random>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include "chasles/robot/error.h"

namespace chasles {
namespace {

using Clock = std::chrono::steady_clock;

constexpr int kMaxSide = 4096;
/// Distance-table entries (robots × free cells) the solver allocates at most: 256 MB.
constexpr std::int64_t kMaxDistanceEntries = std::int64_t{1} << 26;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// Uniform integer in [0, n), n >= 1, by rejection: the same stream on every standard library.
std::uint64_t Below(std::mt19937_64& rng, std::uint64_t n) {
  const std::uint64_t threshold = (0 - n) % n;  // 2^64 mod n
  for (;;) {
    const std::uint64_t r = rng();
    if (r >= threshold) return r % n;
  }
}

template <class T>
void Shuffle(std::vector<T>* values, std::mt19937_64& rng) {
  for (std::size_t i = values->size(); i > 1; --i) {
    std::swap((*values)[i - 1], (*values)[Below(rng, i)]);
  }
}

void ValidateMap(const GridMap& map) {
  if (map.width < 1 || map.width > kMaxSide || map.height < 1 || map.height > kMaxSide) {
    ThrowInvalid("map is " + std::to_string(map.width) + " × " + std::to_string(map.height) +
                 " cells; width and height must be within [1, " + std::to_string(kMaxSide) + "]");
  }
  const std::size_t cells = static_cast<std::size_t>(map.width) * static_cast<std::size_t>(map.height);
  if (map.blocked.size() != cells) {
    ThrowInvalid("map.blocked has " + std::to_string(map.blocked.size()) + " entries; width * height = " +
                 std::to_string(cells));
  }
}

void ValidateSide(const char* name, int value) {
  if (value < 1 || value > kMaxSide) {
    ThrowInvalid(std::string(name) + " = " + std::to_string(value) + " must be within [1, " +
                 std::to_string(kMaxSide) + "]");
  }
}

/// Cells of the largest 4-connected free component (ties: the one holding the lowest cell),
/// in increasing order.
std::vector<GridCell> LargestComponent(const GridMap& map) {
  const int cells = map.width * map.height;
  std::vector<int> label(cells, -1);
  std::vector<GridCell> best, current, queue;
  for (GridCell seed = 0; seed < cells; ++seed) {
    if (map.blocked[seed] || label[seed] >= 0) continue;
    current.clear();
    queue.assign(1, seed);
    label[seed] = seed;
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const GridCell c = queue[head];
      current.push_back(c);
      const int x = c % map.width, y = c / map.width;
      const GridCell around[4] = {x > 0 ? c - 1 : -1, x + 1 < map.width ? c + 1 : -1, y > 0 ? c - map.width : -1,
                                  y + 1 < map.height ? c + map.width : -1};
      for (GridCell n : around) {
        if (n >= 0 && !map.blocked[n] && label[n] < 0) {
          label[n] = seed;
          queue.push_back(n);
        }
      }
    }
    if (current.size() > best.size()) best = current;
  }
  std::sort(best.begin(), best.end());
  return best;
}

// ---------------------------------------------------------------------------------------------
// The free cells as a graph of compact vertex ids, and per-robot distances to the goal.

struct Graph {
  std::vector<GridCell> cell;           ///< vertex -> cell
  std::vector<int> vertex;              ///< cell -> vertex, -1 for blocked
  std::vector<std::array<int, 4>> neighbors;
  std::vector<std::uint8_t> degree;
  /// pocket[4 * v + k]: moving from v to its k-th neighbour u crosses a bridge (an edge whose
  /// removal splits the free cells) into the smaller side, the "pocket": c + 1 when the pocket is
  /// the depth-first subtree of c, -(c + 1) when it is everything else; 0 otherwise.
  std::vector<int> pocket;
  std::vector<int> preorder, subtree_end;  ///< depth-first numbering: subtree of c = [preorder[c], subtree_end[c])

  explicit Graph(const GridMap& map) : vertex(map.blocked.size(), -1) {
    for (GridCell c = 0; c < static_cast<GridCell>(map.blocked.size()); ++c) {
      if (map.blocked[c]) continue;
      vertex[c] = static_cast<int>(cell.size());
      cell.push_back(c);
    }
    neighbors.resize(cell.size());
    degree.assign(cell.size(), 0);
    for (int v = 0; v < static_cast<int>(cell.size()); ++v) {
      const GridCell c = cell[v];
      const int x = c % map.width, y = c / map.width;
      const GridCell around[4] = {x > 0 ? c - 1 : -1, x + 1 < map.width ? c + 1 : -1, y > 0 ? c - map.width : -1,
                                  y + 1 < map.height ? c + map.width : -1};
      for (GridCell n : around) {
        if (n >= 0 && vertex[n] >= 0) neighbors[v][degree[v]++] = vertex[n];
      }
    }
    FindPockets();
  }
  int size() const { return static_cast<int>(cell.size()); }

  /// Whether vertex g lies in the pocket entered from v by neighbour slot k (pocket != 0).
  bool InPocket(int v, int k, int g) const {
    const int code = pocket[4 * v + k];
    const int c = std::abs(code) - 1;
    const bool below = preorder[c] <= preorder[g] && preorder[g] < subtree_end[c];
    return code > 0 ? below : !below;
  }

 private:
  /// Bridges by Tarjan's low-link over an iterative depth-first search of each component.
  void FindPockets() {
    const int n = size();
    pocket.assign(4 * n, 0);
    preorder.assign(n, -1);
    subtree_end.assign(n, 0);
    std::vector<int> low(n, 0), parent(n, -1), component_of(n, 0), component_size;
    std::vector<std::pair<int, int>> stack;  // (vertex, next neighbour slot)
    int counter = 0;
    for (int root = 0; root < n; ++root) {
      if (preorder[root] >= 0) continue;
      const int first = counter;
      const int component = static_cast<int>(component_size.size());
      component_of[root] = component;
      preorder[root] = low[root] = counter++;
      stack.assign(1, {root, 0});
      while (!stack.empty()) {
        auto& [v, k] = stack.back();
        if (k < degree[v]) {
          const int u = neighbors[v][k++];
          if (preorder[u] < 0) {
            parent[u] = v;
            component_of[u] = component;
            preorder[u] = low[u] = counter++;
            stack.push_back({u, 0});
          } else if (u != parent[v]) {
            low[v] = std::min(low[v], preorder[u]);
          }
        } else {
          subtree_end[v] = counter;
          const int done = v;
          stack.pop_back();
          if (!stack.empty()) low[stack.back().first] = std::min(low[stack.back().first], low[done]);
        }
      }
      component_size.push_back(counter - first);
    }
    for (int v = 0; v < n; ++v) {
      for (int k = 0; k < degree[v]; ++k) {
        const int u = neighbors[v][k];
        const int child = parent[u] == v ? u : parent[v] == u ? v : -1;
        if (child < 0 || low[child] <= preorder[parent[child]]) continue;  // not a bridge
        const int below = subtree_end[child] - preorder[child];
        const int rest = component_size[component_of[child]] - below;
        if (u == child && below <= rest) pocket[4 * v + k] = child + 1;
        if (v == child && rest < below) pocket[4 * v + k] = -(child + 1);
      }
    }
  }

 public:
};

/// A zero-filled array from calloc: large ones come as fresh zero pages the kernel maps only
/// when first touched (the search touches little of some, e.g. the refiner's visited marks).
template <class T>
class ZeroArray {
 public:
  ZeroArray() = default;
  explicit ZeroArray(std::size_t size) : data_(static_cast<T*>(std::calloc(size == 0 ? 1 : size, sizeof(T)))), size_(size) {
    if (data_ == nullptr) throw std::bad_alloc();
  }
  T& operator[](std::size_t i) { return data_.get()[i]; }
  const T& operator[](std::size_t i) const { return data_.get()[i]; }
  std::size_t size() const { return size_; }

 private:
  struct Free {
    void operator()(T* p) const { std::free(p); }
  };
  std::unique_ptr<T, Free> data_;
  std::size_t size_ = 0;
};

/// Per robot, the breadth-first distance of every vertex to its goal; -1 for a vertex in
/// another component. Stored as distance + 1 (0 = unreachable), in 16 bits when every distance
/// fits (fewer than 65535 vertices), else 32: the tables are the solver's largest memory.
class DistanceTable {
 public:
  DistanceTable(const Graph& graph, int robots)
      : v_(graph.size()), narrow_(graph.size() < 65535) {
    const std::size_t entries = static_cast<std::size_t>(robots) * v_;
    if (narrow_) {
      narrow_data_ = ZeroArray<std::uint16_t>(entries);
    } else {
      wide_data_ = ZeroArray<std::uint32_t>(entries);
    }
  }

  /// Fills robot's row by a breadth-first search from `goal`.
  void Compute(const Graph& graph, int robot, int goal, std::vector<int>* queue) {
    const std::size_t row = static_cast<std::size_t>(robot) * v_;
    Set(row + goal, 1);
    queue->assign(1, goal);
    for (std::size_t head = 0; head < queue->size(); ++head) {
      const int v = (*queue)[head];
      const std::uint32_t next = Get(row + v) + 1;
      for (int k = 0; k < graph.degree[v]; ++k) {
        const int u = graph.neighbors[v][k];
        if (Get(row + u) == 0) {
          Set(row + u, next);
          queue->push_back(u);
        }
      }
    }
  }

  std::int32_t operator()(int robot, int v) const {
    return static_cast<std::int32_t>(Get(static_cast<std::size_t>(robot) * v_ + v)) - 1;
  }

 private:
  std::uint32_t Get(std::size_t i) const { return narrow_ ? narrow_data_[i] : wide_data_[i]; }
  void Set(std::size_t i, std::uint32_t value) {
    if (narrow_) {
      narrow_data_[i] = static_cast<std::uint16_t>(value);
    } else {
      wide_data_[i] = value;
    }
  }

  std::size_t v_;
  bool narrow_;
  ZeroArray<std::uint16_t> narrow_data_;
  ZeroArray<std::uint32_t> wide_data_;
};

// ---------------------------------------------------------------------------------------------
// LaCAM*.

/// A constraint of the low-level search: robot `who` moves to vertex `where` at the next step,
/// together with every constraint on the chain to the root (depth 0, no constraint).
struct LowNode {
  int parent = -1;
  int who = -1;
  int where = -1;
  int depth = 0;
};

struct HighNode;

struct Edge {
  HighNode* to = nullptr;
  std::int64_t cost = 0;
};

/// A configuration of the high-level search.
struct HighNode {
  std::vector<int> config;      ///< vertex per robot
  std::vector<float> priority;  ///< PIBT priorities: + 1 per step away from the goal
  std::vector<int> order;       ///< robots by decreasing priority; filled when first needed
  std::vector<int> constrain;   ///< the order of the low-level search; filled when first needed
  HighNode* parent = nullptr;   ///< on the cheapest known way from the start
  std::vector<Edge> successors; ///< configurations generated from this one (LaCAM*)
  std::vector<int> pending;     ///< low-level nodes not yet tried (a queue from pending_head)
  std::size_t pending_head = 0;
  std::int64_t g = 0;           ///< cost from the start along parent links (sum of loss)
  std::int64_t h = 0;           ///< sum of the robots' distances to their goals
  int id = 0;                   ///< creation order
};

struct ConfigHash {
  int n = 0;
  std::size_t operator()(const int* config) const {
    std::uint64_t h = 0x9E3779B97F4A7C15ull;
    for (int i = 0; i < n; ++i) {
      h ^= static_cast<std::uint64_t>(static_cast<std::uint32_t>(config[i])) + 0x9E3779B97F4A7C15ull + (h << 6) + (h >> 2);
    }
    h ^= h >> 31;
    h *= 0xBF58476D1CE4E5B9ull;
    h ^= h >> 29;
    return static_cast<std::size_t>(h);
  }
};

struct ConfigEqual {
  int n = 0;
  bool operator()(const int* a, const int* b) const { return std::equal(a, a + n, b); }
};

class LacamSearch {
 public:
  LacamSearch(const Graph& graph, int width, const std::vector<int>& starts, const std::vector<int>& goals,
              const DistanceTable& distances, std::uint64_t seed)
      : graph_(graph),
        width_(width),
        n_(static_cast<int>(starts.size())),
        starts_(starts),
        goals_(goals),
        distances_(distances),
        rng_(seed),
        explored_(1024, ConfigHash{n_}, ConfigEqual{n_}),
        occupied_now_(graph.size(), -1),
        occupied_next_(graph.size(), -1),
        next_(n_, -1) {
    low_nodes_.push_back(LowNode{});  // the root: no constraint
    root_ = NewNode(starts_, nullptr);
    open_.push_back(root_);
  }

  enum class SearchEnd { kPlan, kExhausted, kStopped };

  /// LaCAM: searches until the first plan (kPlan), until every reachable configuration was
  /// explored without one (kExhausted: no plan exists), or until `termination` stops.
  SearchEnd FindPlan(const Termination& termination) {
    while (goal_ == nullptr) {
      if (open_.empty()) return SearchEnd::kExhausted;
      if (termination.ShouldStop()) return SearchEnd::kStopped;
      Step();
    }
    return SearchEnd::kPlan;
  }

  /// LaCAM*: after the first plan, goes on searching for cheaper ones (in the sum of loss) until
  /// `stop()`, or `max_configurations` more configurations were generated (0 = no limit), or the
  /// search is exhausted: then true, and the plan is optimal in the sum of loss.
  template <class Stop>
  bool Improve(const Stop& stop, std::uint64_t max_configurations) {
    const std::uint64_t limit = max_configurations == 0 ? std::numeric_limits<std::uint64_t>::max()
                                                        : generated_ + max_configurations;
    while (!open_.empty()) {
      if (generated_ >= limit || stop()) return false;
      Step();
    }
    return true;
  }

  /// The best plan found: per robot, its vertex at every step (all of one length).
  std::vector<std::vector<int>> Plan() const {
    std::vector<const HighNode*> chain;
    for (const HighNode* at = goal_; at != nullptr; at = at->parent) chain.push_back(at);
    std::reverse(chain.begin(), chain.end());
    std::vector<std::vector<int>> paths(n_, std::vector<int>(chain.size()));
    for (std::size_t t = 0; t < chain.size(); ++t) {
      for (int i = 0; i < n_; ++i) paths[i][t] = chain[t]->config[i];
    }
    return paths;
  }

  std::int64_t plan_cost() const { return goal_->g; }
  std::uint64_t generated() const { return generated_; }
  std::uint64_t created() const { return nodes_.size(); }

 private:
  /// One turn of LaCAM*'s loop on the top of OPEN (Okumura 2023, Algorithm 1 of LaCAM*).
  void Step() {
    HighNode* node = open_.back();
    if (goal_ == nullptr && node->h == 0) {
      ShortestCostsFromStart();
      goal_ = node;
      return;
    }
    // LaCAM*: nothing below this node can beat the plan found.
    if (goal_ != nullptr && goal_->g <= node->g + node->h) {
      open_.pop_back();
      return;
    }
    if (node->pending_head == node->pending.size()) {
      open_.pop_back();
      std::vector<int>().swap(node->pending);
      node->pending_head = 0;
      return;
    }
    const int low = node->pending[node->pending_head++];
    if (low_nodes_[low].depth < n_) Branch(node, low);
    if (!NextConfiguration(*node, low)) return;
    ++generated_;
    const auto known = explored_.find(next_config_.data());
    if (known != explored_.end()) {
      HighNode* other = known->second;
      AddSuccessor(node, other);
      open_.push_back(other);  // LaCAM: revisit the known configuration (depth first)
      if (goal_ != nullptr) Rewire(node);
    } else {
      HighNode* created = NewNode(next_config_, node);
      AddSuccessor(node, created);
      open_.push_back(created);
    }
  }

  std::int32_t Distance(int robot, int v) const { return distances_(robot, v); }

  /// LaCAM*'s transition cost (sum of loss): robots not both at their goal before and after.
  std::int64_t Cost(const std::vector<int>& from, const std::vector<int>& to) const {
    std::int64_t cost = 0;
    for (int i = 0; i < n_; ++i) cost += !(from[i] == goals_[i] && to[i] == goals_[i]);
    return cost;
  }

  HighNode* NewNode(const std::vector<int>& config, HighNode* parent) {
    nodes_.emplace_back(std::make_unique<HighNode>());
    HighNode* node = nodes_.back().get();
    node->id = static_cast<int>(nodes_.size()) - 1;
    node->config = config;
    node->priority.resize(n_);
    node->parent = parent;
    for (int i = 0; i < n_; ++i) {
      const float d = static_cast<float>(Distance(i, config[i]));
      node->h += Distance(i, config[i]);
      if (parent == nullptr) {
        node->priority[i] = d / static_cast<float>(graph_.size() + 1);  // farther first, in [0, 1)
      } else if (config[i] != goals_[i]) {
        node->priority[i] = parent->priority[i] + 1.0f;
      } else {
        node->priority[i] = parent->priority[i] - std::floor(parent->priority[i]);
      }
    }
    if (parent != nullptr) node->g = parent->g + Cost(parent->config, config);
    node->pending.push_back(0);  // the root of the low-level search
    explored_.emplace(node->config.data(), node);
    return node;
  }

  void AddSuccessor(HighNode* from, HighNode* to) {
    const std::uint64_t key = static_cast<std::uint64_t>(from->id) << 32 | static_cast<std::uint32_t>(to->id);
    if (!edges_.insert(key).second) return;
    from->successors.push_back(Edge{to, Cost(from->config, to->config)});
  }

  /// Costs-to-come and parents by Dijkstra from the start over every edge found so far. Run once,
  /// when the first plan is found: until then the costs are not needed (LaCAM* keeps them
  /// current from the beginning by Rewire; the result is the same).
  void ShortestCostsFromStart() {
    for (const auto& node : nodes_) node->g = std::numeric_limits<std::int64_t>::max();
    root_->g = 0;
    root_->parent = nullptr;
    Rewire(root_);
  }

  /// LaCAM*: after a new edge out of `from`, lowers costs-to-come through it (Dijkstra), and
  /// sends back to the search every node that could now lead to a cheaper plan.
  void Rewire(HighNode* from) {
    using Entry = std::pair<std::int64_t, HighNode*>;
    const auto later = [](const Entry& a, const Entry& b) { return a.first > b.first; };
    std::priority_queue<Entry, std::vector<Entry>, decltype(later)> queue(later);
    queue.emplace(from->g, from);
    while (!queue.empty()) {
      const auto [g, node] = queue.top();
      queue.pop();
      if (g != node->g) continue;  // stale
      for (const Edge& e : node->successors) {
        HighNode* to = e.to;
        if (node->g + e.cost >= to->g) continue;
        to->g = node->g + e.cost;
        to->parent = node;
        queue.emplace(to->g, to);
        if (goal_ != nullptr && to != goal_ && to->g + to->h < goal_->g) open_.push_back(to);
      }
    }
  }

  void EnsureOrder(HighNode* node) {
    if (!node->order.empty() || n_ == 0) return;
    node->order.resize(n_);
    for (int i = 0; i < n_; ++i) node->order[i] = i;
    const std::vector<float>& p = node->priority;
    std::stable_sort(node->order.begin(), node->order.end(), [&](int a, int b) { return p[a] > p[b]; });
  }

  /// The order in which the low-level search constrains the robots of `node`: the robot of
  /// highest priority, then the others by grid (Manhattan) distance from it, nearest first
  /// (ties by priority). LaCAM constrains in priority order; any fixed order keeps it complete,
  /// and this one reaches the robots that hold up the most delayed one first: robots parked at
  /// their goals, of low priority, in the pocket it cannot get through.
  void EnsureConstraintOrder(HighNode* node) {
    if (!node->constrain.empty() || n_ == 0) return;
    EnsureOrder(node);
    const int width = width_;
    const GridCell at = graph_.cell[node->config[node->order[0]]];
    const auto distance = [&](int robot) {
      const GridCell c = graph_.cell[node->config[robot]];
      return std::abs(c % width - at % width) + std::abs(c / width - at / width);
    };
    node->constrain = node->order;
    std::stable_sort(node->constrain.begin(), node->constrain.end(),
                     [&](int a, int b) { return distance(a) < distance(b); });
  }

  /// Low-level search: the children of constraint node `low` fix the next robot in the node's
  /// constraint order to each of its moves (stay included), in a seeded random order.
  void Branch(HighNode* node, int low) {
    EnsureConstraintOrder(node);
    const LowNode parent = low_nodes_[low];
    const int robot = node->constrain[parent.depth];
    const int v = node->config[robot];
    std::vector<int>& moves = scratch_moves_;
    moves.assign(1, v);
    for (int k = 0; k < graph_.degree[v]; ++k) moves.push_back(graph_.neighbors[v][k]);
    Shuffle(&moves, rng_);
    for (int u : moves) {
      low_nodes_.push_back(LowNode{low, robot, u, parent.depth + 1});
      node->pending.push_back(static_cast<int>(low_nodes_.size()) - 1);
    }
  }

  /// Whether robot `robot`, moving into the vertex that robot `ahead` (decided to move) vacates,
  /// would close a cycle of robots each following the next: walks the chain of decided moves
  /// from `ahead`. A cycle of two is a swap. Every move into an occupied vertex is checked when
  /// it is decided, so the decided moves never hold a cycle and the walk ends.
  bool ClosesCycle(int robot, int ahead) const {
    int at = ahead;
    for (int steps = 0; steps <= n_; ++steps) {
      const int to = next_[at];
      if (to < 0 || to == current_[at]) return false;  // undecided, or stays
      const int occupant = occupied_now_[to];
      if (occupant < 0) return false;
      if (occupant == robot) return true;
      at = occupant;
    }
    return true;  // unreachable: the decided moves never form a cycle
  }

  void Reserve(int robot, int v) {
    next_[robot] = v;
    occupied_next_[v] = robot;
    reserved_.push_back(v);
  }

  /// Whether robot `robot` standing in v should keep out of the pocket behind its neighbour slot
  /// k (u) for robot `other`, whose goal is in that pocket: true unless `robot`'s goal lies in
  /// the pocket too and deeper than the goal of `other`. Depth = distance from u, the only way
  /// in; a robot that goes in first must be the one going deepest, or the other cannot pass it
  /// (no swaps, no rotations).
  bool ShouldKeepOut(int robot, int v, int k, int other) const {
    if (graph_.pocket[4 * v + k] == 0 || !graph_.InPocket(v, k, goals_[other])) return false;
    const int u = graph_.neighbors[v][k];
    return !(graph_.InPocket(v, k, goals_[robot]) && Distance(robot, u) > Distance(other, u));
  }

  /// One move of PIBT: reserves u for `robot` unless another robot has, or it would close a cycle
  /// of followers; a robot standing in u that has not decided yet must move away first (it
  /// inherits the priority). False, with nothing reserved for `robot`, when u cannot be had.
  bool TryMove(int robot, int u) {
    if (occupied_next_[u] >= 0) return false;
    const int occupant = occupied_now_[u];
    const bool follows = occupant >= 0 && occupant != robot && next_[occupant] >= 0;
    if (follows && ClosesCycle(robot, occupant)) return false;
    Reserve(robot, u);
    if (occupant < 0 || occupant == robot || follows) return true;
    if (Pibt(occupant, robot)) return true;
    next_[robot] = -1;  // the occupant stays in u (it took over the reservation)
    return false;
  }

  /// PIBT (priority inheritance with backtracking) for `robot`, pushed by `pusher` (-1 when not):
  /// the robot takes its best move that TryMove grants. Moves are ranked by distance to the goal,
  /// then vertices nobody stands on, then seeded random; ranked last are moves into a pocket
  /// (Graph::pocket) that does not hold the robot's goal, and for a pushed robot moves into a
  /// pocket its pusher must enter deeper (ShouldKeepOut: it would only be pushed in again).
  /// Pull (our pocket rule, after LaCAM*'s swap): when the best move enters a pocket whose
  /// entrance holds an undecided robot that should keep out, the robot backs off instead and
  /// that robot follows it out, one step at a time, until they can pass.
  /// A robot without any move stays: a pushed robot takes its vertex back from the pusher, which
  /// tries its next move; at the top level the vertex was reserved by a constrained robot, and
  /// the configuration fails.
  bool Pibt(int robot, int pusher) {
    const int v = current_[robot];
    std::array<int, 5> candidates, slot;
    std::array<std::int64_t, 5> key;
    int count = 0;
    candidates[count] = v;
    slot[count++] = -1;
    for (int k = 0; k < graph_.degree[v]; ++k) {
      candidates[count] = graph_.neighbors[v][k];
      slot[count++] = k;
    }
    for (int k = count; k > 1; --k) {
      const int r = static_cast<int>(Below(rng_, k));
      std::swap(candidates[k - 1], candidates[r]);
      std::swap(slot[k - 1], slot[r]);
    }
    constexpr std::int64_t kLast = std::int64_t{1} << 40;
    for (int k = 0; k < count; ++k) {
      const int u = candidates[k];
      const int occupant = occupied_now_[u];
      key[k] = 2 * static_cast<std::int64_t>(Distance(robot, u)) + (occupant >= 0 && occupant != robot ? 1 : 0);
      if (pusher >= 0 && slot[k] >= 0 && ShouldKeepOut(robot, v, slot[k], pusher)) key[k] += kLast;
      if (slot[k] >= 0 && graph_.pocket[4 * v + slot[k]] != 0 && !graph_.InPocket(v, slot[k], goals_[robot])) {
        key[k] += kLast;  // a pocket its goal is not in: it would have to come out again
      }
    }
    for (int a = 1; a < count; ++a) {  // stable insertion sort by key
      for (int b = a; b > 0 && key[b] < key[b - 1]; --b) {
        std::swap(key[b], key[b - 1]);
        std::swap(candidates[b], candidates[b - 1]);
        std::swap(slot[b], slot[b - 1]);
      }
    }
    const int best = candidates[0];
    const int blocker = occupied_now_[best];
    if (pusher < 0 && best != v && blocker >= 0 && next_[blocker] < 0 && occupied_next_[v] < 0 &&
        ShouldKeepOut(blocker, v, slot[0], robot)) {
      for (int k = 1; k < count; ++k) {
        if (candidates[k] == v || !TryMove(robot, candidates[k])) continue;
        if (next_[blocker] < 0 && occupied_next_[v] < 0 && !ClosesCycle(blocker, robot)) Reserve(blocker, v);
        return true;
      }
    }
    for (int k = 0; k < count; ++k) {
      if (TryMove(robot, candidates[k])) return true;
    }
    Reserve(robot, v);
    return false;
  }

  /// The configuration following `node` under the constraints of low-level node `low`, in
  /// next_config_: the constrained robots first, then PIBT for the others in the node's order.
  /// False when the constraints conflict or a robot cannot be placed.
  bool NextConfiguration(HighNode& node, int low) {
    EnsureOrder(&node);
    current_ = node.config.data();
    for (int i = 0; i < n_; ++i) occupied_now_[current_[i]] = i;
    bool ok = true;
    for (int k = low; ok && low_nodes_[k].depth > 0; k = low_nodes_[k].parent) {
      const LowNode& c = low_nodes_[k];
      const int occupant = occupied_now_[c.where];
      if (occupied_next_[c.where] >= 0) {
        ok = false;
      } else if (occupant >= 0 && occupant != c.who && next_[occupant] >= 0 && ClosesCycle(c.who, occupant)) {
        ok = false;
      } else {
        Reserve(c.who, c.where);
      }
    }
    for (int k = 0; ok && k < n_; ++k) {
      const int robot = node.order[k];
      if (next_[robot] < 0 && !Pibt(robot, -1)) ok = false;
    }
    if (ok) next_config_.assign(next_.begin(), next_.end());
    for (int v : reserved_) occupied_next_[v] = -1;
    reserved_.clear();
    for (int i = 0; i < n_; ++i) {
      occupied_now_[current_[i]] = -1;
      next_[i] = -1;
    }
    return ok;
  }

  const Graph& graph_;
  const int width_;  ///< of the map
  const int n_;
  const std::vector<int>& starts_;
  const std::vector<int>& goals_;
  const DistanceTable& distances_;
  std::mt19937_64 rng_;
  std::vector<std::unique_ptr<HighNode>> nodes_;
  std::deque<LowNode> low_nodes_;
  std::unordered_set<std::uint64_t> edges_;  ///< (from id, to id) of every successor edge
  std::unordered_map<const int*, HighNode*, ConfigHash, ConfigEqual> explored_;
  HighNode* root_ = nullptr;
  HighNode* goal_ = nullptr;     ///< the start of the best plan, backwards along parent links
  std::vector<HighNode*> open_;  ///< LaCAM's OPEN: a stack
  std::uint64_t generated_ = 0;  ///< configurations generated (new or known)
  // Scratch of NextConfiguration / Pibt.
  const int* current_ = nullptr;
  std::vector<int> occupied_now_;   ///< vertex -> robot in the current configuration
  std::vector<int> occupied_next_;  ///< vertex -> robot that reserved it for the next one
  std::vector<int> next_;           ///< robot -> reserved vertex, -1 while undecided
  std::vector<int> reserved_;       ///< vertices written to occupied_next_
  std::vector<int> next_config_;
  std::vector<int> scratch_moves_;
};

// ---------------------------------------------------------------------------------------------
// Refinement by large neighbourhood search.

/// Anytime improvement of the sum of costs of a valid plan by large neighbourhood search (after
/// Li et al., "Anytime multi-agent path finding via large neighborhood search", IJCAI 2021):
/// repeatedly takes a few robots out, replans them one after another (random order) by
/// space-time A* among the others' fixed paths under the same conflict rules, and keeps the new
/// paths when their sum of costs is lower. Neighbourhoods: the robot with the largest delay with
/// the robots found on its shortest path at the times it would pass, the robots that pass the
/// cells around a crossing, or random robots, chosen adaptively by how much each kind has
/// improved lately.
class NeighbourhoodRefiner {
 public:
  NeighbourhoodRefiner(const Graph& graph, const std::vector<int>& starts, const std::vector<int>& goals,
                       const DistanceTable& distances, const std::vector<std::vector<int>>& plan,
                       std::uint64_t seed)
      : graph_(graph),
        n_(static_cast<int>(starts.size())),
        v_(graph.size()),
        starts_(starts),
        goals_(goals),
        distances_(distances),
        rng_(seed ^ 0x5DEECE66Dull),
        paths_(plan),
        parked_(v_, -1) {
    for (auto& path : paths_) Trim(&path);
    Grow(static_cast<int>(plan.empty() ? 1 : plan[0].size()));
    for (int i = 0; i < n_; ++i) Insert(i);
    for (int i = 0; i < n_; ++i) cost_ += Cost(i);
  }

  /// Improves until `stop()` or after `max_iterations` neighbourhoods (0 = no limit).
  template <class Stop>
  void Run(const Stop& stop, std::uint64_t max_iterations) {
    if (n_ == 0) return;
    const int size = std::min(8, std::max(2, n_ / 2));
    std::vector<int> group, order;
    std::vector<std::vector<int>> old_paths;
    while ((max_iterations == 0 || iterations_ < max_iterations) && !stop()) {
      ++iterations_;
      double total = 0.0;
      for (double w : weights_) total += w;
      double draw = static_cast<double>(Below(rng_, 1u << 30)) / (1u << 30) * total;
      int kind = 0;
      while (kind < 2 && draw >= weights_[kind]) draw -= weights_[kind++];
      if (kind == 0) {
        DelayedNeighbourhood(size, &group);
      } else if (kind == 1) {
        AreaNeighbourhood(size, &group);
      } else {
        RandomNeighbourhood(size, &group);
      }
      std::int64_t old_cost = 0;
      old_paths.clear();
      for (int i : group) {
        old_cost += Cost(i);
        old_paths.push_back(paths_[i]);
        Remove(i);
      }
      order = group;
      Shuffle(&order, rng_);
      // The robots still to place cost at least their distances: a robot's arrival must leave
      // room for them under old_cost, else the neighbourhood cannot improve (A* stops there).
      std::int64_t still = 0;
      for (int i : order) still += Distance(i, starts_[i]);
      std::int64_t new_cost = 0;
      std::size_t placed = 0;
      for (; placed < order.size(); ++placed) {
        const int i = order[placed];
        still -= Distance(i, starts_[i]);
        if (!PlanAlone(i, old_cost - 1 - new_cost - still, stop, &paths_[i])) break;
        Insert(i);
        new_cost += Cost(i);
      }
      const bool better = placed == order.size() && new_cost < old_cost;
      if (!better) {
        for (std::size_t k = 0; k < placed; ++k) Remove(order[k]);
        for (std::size_t k = 0; k < group.size(); ++k) {
          paths_[group[k]] = old_paths[k];
          Insert(group[k]);
        }
      } else {
        cost_ += new_cost - old_cost;
        ++improvements_;
      }
      const double gain = better ? static_cast<double>(old_cost - new_cost) : 0.0;
      weights_[kind] = std::max(0.01, 0.9 * weights_[kind] + 0.1 * gain);
    }
  }

  /// The plan: per robot its vertex at every step, all of one length.
  std::vector<std::vector<int>> Plan() const {
    std::size_t length = 1;
    for (const auto& path : paths_) length = std::max(length, path.size());
    std::vector<std::vector<int>> plan = paths_;
    for (auto& path : plan) path.resize(length, path.back());
    return plan;
  }

  std::int64_t cost() const { return cost_; }
  std::uint64_t iterations() const { return iterations_; }
  std::uint64_t improvements() const { return improvements_; }

 private:
  std::int32_t Distance(int robot, int v) const { return distances_(robot, v); }
  /// Sum-of-costs term of robot i: the step from which it stays at its goal.
  std::int64_t Cost(int i) const { return static_cast<std::int64_t>(paths_[i].size()) - 1; }

  /// Cuts the path after the step from which it stays at its goal.
  void Trim(std::vector<int>* path) const {
    std::size_t end = path->size();
    while (end > 1 && (*path)[end - 2] == path->back()) --end;
    path->resize(end);
  }

  int Position(int robot, int t) const {
    const std::vector<int>& path = paths_[robot];
    return path[std::min<std::size_t>(t, path.size() - 1)];
  }

  /// The robot at vertex v at step t (among the placed ones), -1 for none. From step horizon_ on
  /// every placed robot stands at its goal.
  int At(int t, int v) const { return t < horizon_ ? occupancy_[static_cast<std::size_t>(t) * v_ + v] : parked_[v]; }

  void Grow(int horizon) {
    if (horizon <= horizon_) return;
    occupancy_.resize(static_cast<std::size_t>(horizon) * v_, -1);
    for (int t = horizon_; t < horizon; ++t) {
      for (int v = 0; v < v_; ++v) occupancy_[static_cast<std::size_t>(t) * v_ + v] = parked_[v];
    }
    horizon_ = horizon;
  }

  void Insert(int robot) {
    Grow(static_cast<int>(paths_[robot].size()));
    for (int t = 0; t < horizon_; ++t) occupancy_[static_cast<std::size_t>(t) * v_ + Position(robot, t)] = robot;
    parked_[goals_[robot]] = robot;
  }

  void Remove(int robot) {
    for (int t = 0; t < horizon_; ++t) {
      int& at = occupancy_[static_cast<std::size_t>(t) * v_ + Position(robot, t)];
      if (at == robot) at = -1;
    }
    parked_[goals_[robot]] = -1;
  }

  /// Whether a robot leaving v at step t into the vertex of `ahead` (which leaves it) closes a
  /// cycle of followers: walks the placed robots' moves at t from `ahead`. (The robot itself is
  /// not placed: the chain closes when it reaches a robot entering v.)
  bool ClosesCycle(int t, int ahead, int v) const {
    int at = ahead;
    for (int steps = 0; steps <= n_; ++steps) {
      const int to = Position(at, t + 1);
      if (to == v) return true;
      const int next = At(t, to);
      if (next < 0 || next == at) return false;
      at = next;
    }
    return true;
  }

  /// The agent with the largest delay (cost over its distance) not tried lately, and the robots
  /// on one of its shortest paths at the steps it would pass there (or one later).
  void DelayedNeighbourhood(int size, std::vector<int>* group) {
    int chosen = -1;
    std::int64_t worst = 0;
    for (int pass = 0; pass < 2 && chosen < 0; ++pass) {
      for (int i = 0; i < n_; ++i) {
        const std::int64_t delay = Cost(i) - Distance(i, starts_[i]);
        if (delay > worst && tabu_.count(i) == 0) {
          worst = delay;
          chosen = i;
        }
      }
      if (chosen < 0) tabu_.clear();
    }
    if (chosen < 0) {
      RandomNeighbourhood(size, group);
      return;
    }
    tabu_.insert(chosen);
    group->assign(1, chosen);
    std::vector<int> found;
    int v = starts_[chosen];
    for (int t = 0;; ++t) {
      for (int dt = 0; dt <= 1; ++dt) {
        const int robot = At(t + dt, v);
        if (robot >= 0 && robot != chosen && std::find(found.begin(), found.end(), robot) == found.end()) {
          found.push_back(robot);
        }
      }
      if (v == goals_[chosen]) break;
      int options[4], count = 0;
      for (int k = 0; k < graph_.degree[v]; ++k) {
        const int u = graph_.neighbors[v][k];
        if (Distance(chosen, u) < Distance(chosen, v)) options[count++] = u;
      }
      v = options[Below(rng_, count)];
    }
    Shuffle(&found, rng_);
    for (int robot : found) {
      if (static_cast<int>(group->size()) >= size) break;
      group->push_back(robot);
    }
    while (static_cast<int>(group->size()) < size) {
      const int robot = static_cast<int>(Below(rng_, n_));
      if (std::find(group->begin(), group->end(), robot) == group->end()) group->push_back(robot);
    }
  }

  /// The robots that pass the cells nearest (breadth first) a random crossing (a cell with 3 or
  /// 4 neighbours), at any step: where robots wait for each other (after the map-based
  /// neighbourhoods of Li et al.).
  void AreaNeighbourhood(int size, std::vector<int>* group) {
    if (crossings_.empty()) {
      for (int v = 0; v < v_; ++v) {
        if (graph_.degree[v] >= 3) crossings_.push_back(v);
      }
      if (crossings_.empty()) crossings_.push_back(0);
    }
    group->clear();
    area_queue_.assign(1, crossings_[Below(rng_, crossings_.size())]);
    area_seen_.insert(area_queue_[0]);
    for (std::size_t head = 0; head < area_queue_.size() && static_cast<int>(group->size()) < size; ++head) {
      const int v = area_queue_[head];
      for (int t = 0; t < horizon_ && static_cast<int>(group->size()) < size; ++t) {
        const int robot = occupancy_[static_cast<std::size_t>(t) * v_ + v];
        if (robot >= 0 && std::find(group->begin(), group->end(), robot) == group->end()) group->push_back(robot);
      }
      for (int k = 0; k < graph_.degree[v]; ++k) {
        if (area_seen_.insert(graph_.neighbors[v][k]).second) area_queue_.push_back(graph_.neighbors[v][k]);
      }
    }
    area_seen_.clear();
    while (static_cast<int>(group->size()) < size) {
      const int robot = static_cast<int>(Below(rng_, n_));
      if (std::find(group->begin(), group->end(), robot) == group->end()) group->push_back(robot);
    }
  }

  void RandomNeighbourhood(int size, std::vector<int>* group) {
    group->clear();
    while (static_cast<int>(group->size()) < size) {
      const int robot = static_cast<int>(Below(rng_, n_));
      if (std::find(group->begin(), group->end(), robot) == group->end()) group->push_back(robot);
    }
  }

  /// Space-time A* for `robot` among the placed robots: the earliest arrival at its goal after
  /// which no placed robot enters the goal, if it is at most `bound`. States past the horizon (a
  /// static world) are merged per vertex. The open list is a bucket queue on f, last in first
  /// out within a bucket (deeper states first). False when there is no such arrival, past the
  /// expansion cap, or when `stop()`.
  template <class Stop>
  bool PlanAlone(int robot, std::int64_t bound, const Stop& stop, std::vector<int>* path) {
    const int goal = goals_[robot];
    int last_busy = -1;  // the last step a placed robot is at the goal
    for (int t = 0; t < horizon_; ++t) {
      if (occupancy_[static_cast<std::size_t>(t) * v_ + goal] >= 0) last_busy = t;
    }
    // Admissible and consistent: the robot cannot finish before its goal is clear for good.
    const auto f_of = [&](int v, int t) {
      return std::max<std::int64_t>(t + static_cast<std::int64_t>(Distance(robot, v)), last_busy + 1);
    };
    const std::int64_t f0 = f_of(starts_[robot], 0);
    bound = std::min<std::int64_t>(bound, f0 + 4 * static_cast<std::int64_t>(v_));
    if (f0 > bound) return false;
    const std::size_t slots = static_cast<std::size_t>(horizon_ + 1) * v_;
    if (seen_.size() < slots || ++stamp_ == 0) {
      seen_ = ZeroArray<std::uint32_t>(std::max(slots, seen_.size()) + seen_.size() / 2);
      stamp_ = 1;
    }
    states_.clear();
    const std::size_t buckets = static_cast<std::size_t>(bound - f0 + 1);
    if (buckets_.size() < buckets) buckets_.resize(buckets);
    for (std::size_t b = 0; b < buckets; ++b) buckets_[b].clear();
    std::size_t current = 0, queued = 0;
    const auto push = [&](int v, int t, int parent) {
      const std::int64_t f = f_of(v, t);
      if (f > bound) return;
      std::uint32_t& mark = seen_[static_cast<std::size_t>(std::min(t, horizon_)) * v_ + v];
      if (mark == stamp_) return;
      mark = stamp_;
      states_.push_back({v, t, parent});
      buckets_[static_cast<std::size_t>(f - f0)].push_back(static_cast<int>(states_.size()) - 1);
      ++queued;
    };
    push(starts_[robot], 0, -1);
    const std::size_t cap = 64 * static_cast<std::size_t>(v_) + 100000;
    while (queued > 0) {
      if (states_.size() > cap || ((states_.size() & 1023) == 0 && stop())) return false;
      while (buckets_[current].empty()) ++current;
      const int index = buckets_[current].back();
      buckets_[current].pop_back();
      --queued;
      const State state = states_[index];
      if (state.v == goal && state.t > last_busy) {
        path->clear();
        for (int k = index; k >= 0; k = states_[k].parent) path->push_back(states_[k].v);
        std::reverse(path->begin(), path->end());
        Trim(path);
        return true;
      }
      const int t = state.t;
      for (int k = -1; k < graph_.degree[state.v]; ++k) {
        const int u = k < 0 ? state.v : graph_.neighbors[state.v][k];
        if (At(t + 1, u) >= 0) continue;
        if (u != state.v) {
          const int ahead = At(t, u);
          if (ahead >= 0 && ClosesCycle(t, ahead, state.v)) continue;
        }
        push(u, t + 1, index);
      }
    }
    return false;
  }

  struct State {
    int v, t, parent;
  };

  const Graph& graph_;
  const int n_;
  const int v_;
  const std::vector<int>& starts_;
  const std::vector<int>& goals_;
  const DistanceTable& distances_;
  std::mt19937_64 rng_;
  std::vector<std::vector<int>> paths_;  ///< trimmed: each ends where its robot stays for good
  std::vector<int> parked_;              ///< vertex -> placed robot whose goal it is
  std::vector<int> occupancy_;           ///< [t * |V| + v] -> placed robot, for t < horizon_
  int horizon_ = 0;
  std::int64_t cost_ = 0;
  std::uint64_t iterations_ = 0, improvements_ = 0;
  double weights_[3] = {1.0, 1.0, 1.0};  ///< delayed, area, random
  std::unordered_set<int> tabu_;
  std::vector<int> crossings_, area_queue_;
  std::unordered_set<int> area_seen_;
  ZeroArray<std::uint32_t> seen_;          ///< A*'s visited marks, [min(t, horizon_) * |V| + v]
  std::uint32_t stamp_ = 0;
  std::vector<State> states_;               ///< of the running A*
  std::vector<std::vector<int>> buckets_;   ///< its open list, by f - f0
};

/// The sum of costs of a plan of vertex paths of one length.
std::int64_t SumOfCosts(const std::vector<std::vector<int>>& plan, const std::vector<int>& goals) {
  std::int64_t sum = 0;
  for (std::size_t i = 0; i < plan.size(); ++i) {
    std::size_t end = plan[i].size();
    while (end > 0 && plan[i][end - 1] == goals[i]) --end;
    sum += static_cast<std::int64_t>(end);
  }
  return sum;
}

void ValidateRobots(const GridMap& map, const std::vector<GridCell>& cells, const char* field) {
  const GridCell count = static_cast<GridCell>(map.blocked.size());
  std::unordered_map<GridCell, std::size_t> seen;
  for (std::size_t i = 0; i < cells.size(); ++i) {
    const std::string name = std::string(field) + "[" + std::to_string(i) + "]";
    const GridCell c = cells[i];
    if (c < 0 || c >= count) {
      ThrowInvalid(name + " = cell " + std::to_string(c) + " is outside the map (cells 0 to " + std::to_string(count - 1) +
                   ")");
    }
    if (map.blocked[c]) ThrowInvalid(name + " = " + DescribeCell(map, c) + " is blocked");
    const auto [at, inserted] = seen.emplace(c, i);
    if (!inserted) {
      ThrowInvalid(name + " = " + DescribeCell(map, c) + " is also " + field + "[" + std::to_string(at->second) +
                   "]; " + field + " must be distinct");
    }
  }
}

}  // namespace

std::string DescribeCell(const GridMap& map, GridCell cell) {
  if (map.width <= 0) return "cell " + std::to_string(cell);
  return "cell " + std::to_string(cell) + " (x=" + std::to_string(cell % map.width) +
         ", y=" + std::to_string(cell / map.width) + ")";
}

MapfResult SolveMapf(const GridMap& map, const std::vector<GridCell>& starts, const std::vector<GridCell>& goals,
                     const MapfOptions& options, const Termination& termination) {
  const Clock::time_point began = Clock::now();
  ValidateMap(map);
  if (starts.size() != goals.size()) {
    ThrowInvalid("starts has " + std::to_string(starts.size()) + " entries and goals " +
                 std::to_string(goals.size()) + "; there must be one of each per robot");
  }
  ValidateRobots(map, starts, "starts");
  ValidateRobots(map, goals, "goals");
  if (!(options.refine_budget >= 0.0)) {
    ThrowInvalid("options.refine_budget = " + FormatNumber(options.refine_budget) + " must be >= 0");
  }
  MapfResult result;
  const int n = static_cast<int>(starts.size());
  if (n == 0) {
    result.solved = true;
    result.proven_optimal = true;
    result.message = "no robots";
    result.seconds = SecondsSince(began);
    return result;
  }
  const Graph graph(map);
  if (static_cast<std::int64_t>(n) * graph.size() > kMaxDistanceEntries) {
    ThrowResourceExhausted(std::to_string(n) + " robots × " + std::to_string(graph.size()) +
                           " free cells = " + std::to_string(static_cast<std::int64_t>(n) * graph.size()) +
                           " distance-table entries; at most " + std::to_string(kMaxDistanceEntries) +
                           " (fewer robots or a smaller map)");
  }
  std::vector<int> start_vertex(n), goal_vertex(n);
  for (int i = 0; i < n; ++i) {
    start_vertex[i] = graph.vertex[starts[i]];
    goal_vertex[i] = graph.vertex[goals[i]];
  }
  DistanceTable distances(graph, n);
  std::vector<int> queue;
  std::vector<int> unreachable;
  for (int i = 0; i < n; ++i) {
    if (termination.ShouldStop()) {
      result.message = "no plan within the budget: stopped while computing the robots' distances";
      result.seconds = SecondsSince(began);
      return result;
    }
    distances.Compute(graph, i, goal_vertex[i], &queue);
    const std::int32_t d = distances(i, start_vertex[i]);
    if (d < 0) {
      unreachable.push_back(i);
    } else {
      result.sum_of_lower_bounds += d;
    }
  }
  if (!unreachable.empty()) {
    result.sum_of_lower_bounds = 0;
    std::string message = "no plan exists: ";
    for (std::size_t k = 0; k < unreachable.size() && k < 5; ++k) {
      const int i = unreachable[k];
      if (k > 0) message += "; ";
      message += "robots[" + std::to_string(i) + "]: goal " + DescribeCell(map, goals[i]) +
                 " is not reachable from its start " + DescribeCell(map, starts[i]);
    }
    if (unreachable.size() > 5) message += "; and " + std::to_string(unreachable.size() - 5) + " more robots";
    result.message = message + " (another connected component)";
    result.seconds = SecondsSince(began);
    return result;
  }

  LacamSearch search(graph, map.width, start_vertex, goal_vertex, distances, options.seed);
  const LacamSearch::SearchEnd end = search.FindPlan(termination);
  result.nodes_expanded = search.generated();
  result.nodes_created = search.created();
  if (end != LacamSearch::SearchEnd::kPlan) {
    if (end == LacamSearch::SearchEnd::kStopped) {
      const StopReason reason = termination.Reason();
      result.message = std::string("no plan within the budget: the search stopped (") +
                       (reason == StopReason::kCancelled  ? "cancelled"
                        : reason == StopReason::kDeadline ? "deadline"
                                                          : "time budget") +
                       ") after " + std::to_string(search.created()) + " configurations in " +
                       FormatNumber(std::round(SecondsSince(began) * 1e3) / 1e3) + " s";
    } else {
      result.message = "no plan exists under the conflict rules (no swaps, no rotation cycles): all " +
                       std::to_string(search.created()) + " reachable configurations were explored";
    }
    result.seconds = SecondsSince(began);
    return result;
  }
  result.solved = true;
  result.first_solution_seconds = SecondsSince(began);
  std::vector<std::vector<int>> plan = search.Plan();
  if (!options.refine) {
    result.message = "first plan (refinement off)";
  } else {
    // LaCAM* goes on for at most a tenth of the refinement budget (it is exhausted quickly on
    // small instances, proving its plan optimal in the sum of loss, and makes little progress on
    // large ones), then large neighbourhood search takes the rest. The minimum sum of loss is a
    // lower bound on every plan's sum of costs: a plan that meets it is optimal.
    const Clock::time_point refine_began = Clock::now();
    const auto after = [&](double seconds) {
      return refine_began + std::chrono::duration_cast<Clock::duration>(
                                std::chrono::duration<double>(std::min(seconds, 1e7)));
    };
    const Clock::time_point lacam_end = after(0.1 * options.refine_budget);
    const Clock::time_point refine_end = after(options.refine_budget);
    const bool exhausted = search.Improve(
        [&] { return termination.ShouldStop() || Clock::now() >= lacam_end; }, options.refine_iterations);
    result.nodes_expanded = search.generated();
    result.nodes_created = search.created();
    // LaCAM* lowers the sum of loss; keep its plan unless the sum of costs went up.
    std::vector<std::vector<int>> improved = search.Plan();
    if (SumOfCosts(improved, goal_vertex) <= SumOfCosts(plan, goal_vertex)) plan = std::move(improved);
    const auto proven = [&] { return exhausted && SumOfCosts(plan, goal_vertex) == search.plan_cost(); };
    std::string lacam = "LaCAM* generated " + std::to_string(search.generated()) + " configurations" +
                        (exhausted ? " and was exhausted (minimum sum of loss " +
                                         std::to_string(search.plan_cost()) + ")"
                                   : "");
    if (proven()) {
      result.message = "plan proven optimal: " + lacam + ", which the sum of costs meets";
    } else {
      NeighbourhoodRefiner refiner(graph, start_vertex, goal_vertex, distances, plan, options.seed);
      const std::int64_t floor = exhausted ? search.plan_cost() : result.sum_of_lower_bounds;
      refiner.Run([&] { return refiner.cost() <= floor || termination.ShouldStop() || Clock::now() >= refine_end; },
                  options.refine_iterations);
      plan = refiner.Plan();
      result.refine_iterations = refiner.iterations();
      result.message = std::string(proven() ? "plan proven optimal: " : "refined: ") + lacam + ", then " +
                       std::to_string(refiner.iterations()) + " neighbourhoods were replanned (" +
                       std::to_string(refiner.improvements()) + " improved the plan)";
    }
    result.proven_optimal = proven();
  }
  const int steps = static_cast<int>(plan[0].size());
  result.makespan = steps - 1;
  result.paths.assign(n, std::vector<GridCell>(steps));
  for (int i = 0; i < n; ++i) {
    for (int t = 0; t < steps; ++t) result.paths[i][t] = graph.cell[plan[i][t]];
    int last_away = -1;
    for (int t = steps - 1; t >= 0; --t) {
      if (result.paths[i][t] != goals[i]) {
        last_away = t;
        break;
      }
    }
    result.sum_of_costs += last_away + 1;
    for (int t = 0; t + 1 < steps; ++t) {
      result.sum_of_loss += !(result.paths[i][t] == goals[i] && result.paths[i][t + 1] == goals[i]);
    }
  }
  result.seconds = SecondsSince(began);
  return result;
}

// ---------------------------------------------------------------------------------------------
// Maps and scenarios.

GridMap RandomGridMap(int width, int height, double blocked_fraction, std::uint64_t seed) {
  ValidateSide("width", width);
  ValidateSide("height", height);
  if (!(blocked_fraction >= 0.0 && blocked_fraction < 1.0)) {
    ThrowInvalid("blocked_fraction = " + FormatNumber(blocked_fraction) + " must be within [0, 1)");
  }
  GridMap map;
  map.width = width;
  map.height = height;
  const int cells = width * height;
  map.blocked.assign(cells, 0);
  std::vector<GridCell> order(cells);
  for (GridCell c = 0; c < cells; ++c) order[c] = c;
  std::mt19937_64 rng(seed);
  Shuffle(&order, rng);
  const int count = static_cast<int>(std::lround(blocked_fraction * cells));
  for (int k = 0; k < count; ++k) map.blocked[order[k]] = 1;
  const std::vector<GridCell> keep = LargestComponent(map);
  std::fill(map.blocked.begin(), map.blocked.end(), 1);
  for (GridCell c : keep) map.blocked[c] = 0;
  return map;
}

GridMap RoomsGridMap(int width, int height, int room_size, std::uint64_t seed) {
  ValidateSide("width", width);
  ValidateSide("height", height);
  if (room_size < 1) ThrowInvalid("room_size = " + std::to_string(room_size) + " must be >= 1");
  GridMap map;
  map.width = width;
  map.height = height;
  map.blocked.assign(width * height, 1);
  const int period = room_size + 1;
  const int rooms_x = width >= room_size ? (width - room_size) / period + 1 : 0;
  const int rooms_y = height >= room_size ? (height - room_size) / period + 1 : 0;
  const auto open = [&](int x, int y) { map.blocked[y * width + x] = 0; };
  for (int ry = 0; ry < rooms_y; ++ry) {
    for (int rx = 0; rx < rooms_x; ++rx) {
      for (int y = 0; y < room_size; ++y) {
        for (int x = 0; x < room_size; ++x) open(rx * period + x, ry * period + y);
      }
    }
  }
  std::mt19937_64 rng(seed);
  for (int ry = 0; ry < rooms_y; ++ry) {
    for (int rx = 0; rx < rooms_x; ++rx) {
      if (rx + 1 < rooms_x) open(rx * period + room_size, ry * period + static_cast<int>(Below(rng, room_size)));
      if (ry + 1 < rooms_y) open(rx * period + static_cast<int>(Below(rng, room_size)), ry * period + room_size);
    }
  }
  return map;
}

GridMap WarehouseGridMap(int width, int height, int shelf_length, int aisle_width, int dock_width) {
  ValidateSide("width", width);
  ValidateSide("height", height);
  if (shelf_length < 1) ThrowInvalid("shelf_length = " + std::to_string(shelf_length) + " must be >= 1");
  if (aisle_width < 1) ThrowInvalid("aisle_width = " + std::to_string(aisle_width) + " must be >= 1");
  if (dock_width < 0) ThrowInvalid("dock_width = " + std::to_string(dock_width) + " must be >= 0");
  GridMap map;
  map.width = width;
  map.height = height;
  map.blocked.assign(width * height, 0);
  const int inner_width = width - 2 * dock_width;
  const int inner_height = height - 2 * aisle_width;
  // k shelves and k - 1 aisles between them must fit.
  const int columns = inner_width >= shelf_length ? (inner_width + aisle_width) / (shelf_length + aisle_width) : 0;
  const int rows = inner_height >= 1 ? (inner_height + aisle_width) / (1 + aisle_width) : 0;
  if (columns == 0 || rows == 0) return map;
  const int x0 = dock_width + (inner_width - (columns * (shelf_length + aisle_width) - aisle_width)) / 2;
  const int y0 = aisle_width + (inner_height - (rows * (1 + aisle_width) - aisle_width)) / 2;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < columns; ++c) {
      const int y = y0 + r * (1 + aisle_width);
      for (int x = x0 + c * (shelf_length + aisle_width); x < x0 + c * (shelf_length + aisle_width) + shelf_length;
           ++x) {
        map.blocked[y * width + x] = 1;
      }
    }
  }
  return map;
}

void RandomScenario(const GridMap& map, int robots, std::uint64_t seed, std::vector<GridCell>* starts,
                    std::vector<GridCell>* goals) {
  ValidateMap(map);
  if (robots < 0) ThrowInvalid("robots = " + std::to_string(robots) + " must be >= 0");
  std::vector<GridCell> component = LargestComponent(map);
  if (static_cast<int>(component.size()) < robots) {
    ThrowInvalid("robots = " + std::to_string(robots) + " exceeds the " + std::to_string(component.size()) +
                 " cells of the map's largest connected component");
  }
  std::mt19937_64 rng(seed);
  std::vector<GridCell> goal_cells = component;
  Shuffle(&component, rng);
  Shuffle(&goal_cells, rng);
  starts->assign(component.begin(), component.begin() + robots);
  goals->assign(goal_cells.begin(), goal_cells.begin() + robots);
}

// ---------------------------------------------------------------------------------------------
// The independent plan check: written apart from the solver on purpose (no shared conflict code).

std::string CheckMapfPlan(const GridMap& map, const std::vector<GridCell>& starts, const std::vector<GridCell>& goals,
                          const std::vector<std::vector<GridCell>>& paths) {
  if (map.width < 1 || map.height < 1 ||
      map.blocked.size() != static_cast<std::size_t>(map.width) * static_cast<std::size_t>(map.height)) {
    return "the map is malformed (" + std::to_string(map.width) + " × " + std::to_string(map.height) + ", " +
           std::to_string(map.blocked.size()) + " blocked entries)";
  }
  const std::size_t robots = starts.size();
  if (goals.size() != robots) {
    return std::to_string(robots) + " starts but " + std::to_string(goals.size()) + " goals";
  }
  if (paths.size() != robots) {
    return std::to_string(paths.size()) + " paths for " + std::to_string(robots) + " robots";
  }
  if (robots == 0) return "";
  const std::size_t length = paths[0].size();
  for (std::size_t i = 0; i < robots; ++i) {
    if (paths[i].empty()) return "robot " + std::to_string(i) + ": empty path";
    if (paths[i].size() != length) {
      return "robot " + std::to_string(i) + ": path of " + std::to_string(paths[i].size()) +
             " steps, robot 0's has " + std::to_string(length) + " (paths must have one length)";
    }
  }
  const long long cells = static_cast<long long>(map.blocked.size());
  const auto where = [&](GridCell c) {
    return "cell " + std::to_string(c) + " (x=" + std::to_string(c % map.width) + ", y=" + std::to_string(c / map.width) +
           ")";
  };
  for (std::size_t i = 0; i < robots; ++i) {
    if (paths[i].front() != starts[i]) {
      return "robot " + std::to_string(i) + " begins at cell " + std::to_string(paths[i].front()) +
             ", its start is cell " + std::to_string(starts[i]);
    }
    if (paths[i].back() != goals[i]) {
      return "robot " + std::to_string(i) + " ends at cell " + std::to_string(paths[i].back()) +
             ", its goal is cell " + std::to_string(goals[i]);
    }
  }
  std::vector<int> holder(cells, -1);  // cell -> robot at the step being checked
  std::vector<int> ahead(robots);      // robot -> the robot whose cell it enters, or -1
  std::vector<int> mark(robots);
  for (std::size_t t = 0; t < length; ++t) {
    for (std::size_t i = 0; i < robots; ++i) {
      const GridCell c = paths[i][t];
      const std::string who = "robot " + std::to_string(i) + " at step " + std::to_string(t);
      if (c < 0 || c >= cells) return who + " is at cell " + std::to_string(c) + ", outside the map";
      if (map.blocked[c]) return who + " is in blocked " + where(c);
      if (holder[c] >= 0) {
        return "vertex conflict at step " + std::to_string(t) + ": robots " + std::to_string(holder[c]) + " and " +
               std::to_string(i) + " both in " + where(c);
      }
      holder[c] = static_cast<int>(i);
    }
    if (t + 1 < length) {
      for (std::size_t i = 0; i < robots; ++i) {
        const GridCell a = paths[i][t], b = paths[i][t + 1];
        ahead[i] = -1;
        if (a == b) continue;
        const std::string move = "robot " + std::to_string(i) + " at step " + std::to_string(t) + " -> " +
                                 std::to_string(t + 1);
        if (b < 0 || b >= cells) return move + " moves to cell " + std::to_string(b) + ", outside the map";
        const int dx = std::abs(a % map.width - b % map.width), dy = std::abs(a / map.width - b / map.width);
        if (dx + dy != 1) return move + " jumps from " + where(a) + " to " + where(b) + ", not a neighbouring cell";
        ahead[i] = holder[b];
      }
      for (std::size_t i = 0; i < robots; ++i) {
        const int j = ahead[i];
        if (j >= 0 && ahead[j] == static_cast<int>(i)) {
          return "swap at step " + std::to_string(t) + " -> " + std::to_string(t + 1) + ": robots " +
                 std::to_string(std::min<std::size_t>(i, j)) + " and " + std::to_string(std::max<std::size_t>(i, j)) +
                 " exchange " + where(paths[i][t]) + " and " + where(paths[j][t]);
        }
      }
      // Rotation cycles: a cycle in robot -> ahead (every robot has at most one `ahead`).
      std::fill(mark.begin(), mark.end(), 0);  // 0 unseen, 1 on the current walk, 2 done
      for (std::size_t i = 0; i < robots; ++i) {
        int r = static_cast<int>(i);
        while (r >= 0 && mark[r] == 0) {
          mark[r] = 1;
          r = ahead[r];
        }
        if (r >= 0 && mark[r] == 1) {
          std::string cycle;
          int k = r;
          do {
            cycle += "robot " + std::to_string(k) + " " + where(paths[k][t]) + " -> ";
            k = ahead[k];
          } while (k != r);
          return "rotation cycle at step " + std::to_string(t) + " -> " + std::to_string(t + 1) + ": " + cycle +
                 "robot " + std::to_string(r) + ", each moving into the cell the next vacates";
        }
        for (r = static_cast<int>(i); r >= 0 && mark[r] == 1; r = ahead[r]) mark[r] = 2;
      }
    }
    for (std::size_t i = 0; i < robots; ++i) holder[paths[i][t]] = -1;
  }
  return "";
}

}  // namespace chasles
