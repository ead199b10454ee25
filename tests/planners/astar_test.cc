// astar: weighted A* over a C-space lattice. Known lattice costs on an empty plane (octile and
// Manhattan distances), equality with an independent eager Dijkstra over the same lattice on
// obstacle scenes, the ε bound, goals (exact endpoint, several goals, a goal in the start's
// cell), refusals and bad input, the memory cap and terminations, and a 7-joint query.

#include <algorithm>
#include <cmath>
#include <functional>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <queue>
#include <random>
#include <sstream>

#include <gtest/gtest.h>

#include "chasles/collision/collision_checker.h"
#include "chasles/planners/registry.h"
#include "chasles/robot/error.h"
#include "chasles/robot/mobile.h"

namespace chasles {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// A point-like robot: prismatic joints x, y (and z when dims = 3), limits [0, 10] m, carrying
/// a sphere of 0.05 m, so q is the sphere centre.
std::shared_ptr<const RobotModel> SlideRobot(int dims) {
  std::vector<Link> links(dims + 1);
  links[0].name = "base";
  for (int i = 1; i < dims; ++i) links[i].name = std::string("slide_") + "xyz"[i - 1];
  links[dims].name = "point";
  links[dims].collision.push_back(Shape::Sphere(0.05));
  std::vector<Joint> joints(dims);
  for (int i = 0; i < dims; ++i) {
    links[i + 1].parent_joint = i;
    joints[i].name = std::string(1, "xyz"[i]);
    joints[i].type = JointType::kPrismatic;
    joints[i].parent_link = i;
    joints[i].child_link = i + 1;
    joints[i].axis = Eigen::Vector3d::Unit(i);
    joints[i].limits = {0.0, 10.0, 1.0, 0.0};
    joints[i].dof = i;
  }
  return RobotModel::FromTree("point", links, joints);
}

/// An axis-aligned box in the plane from (x0, y0) to (x1, y1), 1 m tall.
SceneObject Wall(const std::string& name, double x0, double y0, double x1, double y1) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(0.5 * (x0 + x1), 0.5 * (y0 + y1), 0.0);
  return {name, Shape::Box(Eigen::Vector3d(x1 - x0, y1 - y0, 1.0), pose)};
}

std::shared_ptr<const CollisionChecker> PlaneChecker(const std::vector<SceneObject>& walls, bool force_fcl = false) {
  auto scene = std::make_shared<Scene>();
  for (const SceneObject& w : walls) scene->AddObject(w);
  CollisionOptions options;
  options.force_fcl = force_fcl;
  return std::make_shared<const CollisionChecker>(SlideRobot(2), scene, options);
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream out;
  out << in.rdbuf();
  return out.str();
}

std::shared_ptr<const CollisionChecker> PandaWithBox() {
  const std::string dir = std::string(CHASLES_SOURCE_DIR) + "/examples/robots/";
  auto robot = RobotModel::FromUrdf(ReadFile(dir + "panda.urdf"), ReadFile(dir + "panda.srdf"));
  auto scene = std::make_shared<Scene>();
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(0.55, 0.0, 0.3);
  scene->AddObject(SceneObject{"box", Shape::Box(Eigen::Vector3d(0.2, 0.6, 0.6), pose)});
  return std::make_shared<const CollisionChecker>(robot, scene);
}

PlanningProblem Problem(std::shared_ptr<const CollisionChecker> checker, const Eigen::VectorXd& start,
                        const Eigen::VectorXd& goal, ParameterValues parameters = {}) {
  PlanningProblem p;
  p.checker = std::move(checker);
  p.start = start;
  p.goal = goal;
  p.max_step = 0.01;
  p.parameters = std::move(parameters);
  return p;
}

std::unique_ptr<Planner> CreateAstar() {
  PlannerRegistry registry;
  RegisterSearchPlanners(&registry);
  return registry.Create("astar");
}

PlannerResult Plan(const PlanningProblem& p, const Termination& termination = Termination()) {
  auto planner = CreateAstar();
  planner->Setup(p);
  return planner->Solve(termination);
}

double PathCost(const JointPath& path) {
  double cost = 0.0;
  for (size_t i = 0; i + 1 < path.size(); ++i) cost += (path[i + 1] - path[i]).norm();
  return cost;
}

/// The edge test every lattice search must use.
bool EdgeValid(const CollisionChecker& checker, const Eigen::VectorXd& a, const Eigen::VectorXd& b, double max_step) {
  return checker.certifies_motion() ? checker.IsMotionCertified(a, b) : checker.IsMotionValid(a, b, max_step);
}

/// Independent reference: Dijkstra over the planar lattice q = start + k·res (4 or 8
/// neighbours, nodes inside the limits), with every node and edge checked eagerly; the cells
/// round((goal − start)/res), moved inside the limits, sit at the exact goals; a goal in the
/// start's cell is joined to the start only. Returns the cheapest cost to any goal, or +inf.
double EagerDijkstra(const PlanningProblem& p, const std::vector<Eigen::VectorXd>& goals, double res, bool full) {
  const CollisionChecker& checker = *p.checker;
  const Eigen::VectorXd lower = checker.robot().lower_limits();
  const Eigen::VectorXd upper = checker.robot().upper_limits();
  using Cell = std::pair<long, long>;
  std::map<Cell, Eigen::VectorXd> goal_at;
  double best = kInf;
  const auto goal_cell = [&](int i, double g) {
    long k = std::lround((g - p.start[i]) / res);
    while (p.start[i] + static_cast<double>(k) * res > upper[i]) --k;
    while (p.start[i] + static_cast<double>(k) * res < lower[i]) ++k;
    return k;
  };
  for (const Eigen::VectorXd& g : goals) {
    const Cell c{goal_cell(0, g[0]), goal_cell(1, g[1])};
    if (c == Cell{0, 0}) {
      if (EdgeValid(checker, p.start, g, p.max_step)) best = std::min(best, (g - p.start).norm());
    } else {
      goal_at.emplace(c, g);
    }
  }
  const auto position = [&](const Cell& c, Eigen::VectorXd* q) {
    const auto it = goal_at.find(c);
    if (it != goal_at.end()) {
      *q = it->second;
      return true;
    }
    *q = Eigen::Vector2d(p.start[0] + static_cast<double>(c.first) * res,
                         p.start[1] + static_cast<double>(c.second) * res);
    return (*q)[0] >= lower[0] && (*q)[0] <= upper[0] && (*q)[1] >= lower[1] && (*q)[1] <= upper[1] &&
           checker.IsValid(*q);
  };
  std::map<Cell, double> dist{{{0, 0}, 0.0}};
  std::map<Cell, bool> done;
  std::priority_queue<std::pair<double, Cell>, std::vector<std::pair<double, Cell>>, std::greater<>> queue;
  queue.push({0.0, {0, 0}});
  Eigen::VectorXd qa, qb;
  while (!queue.empty()) {
    const auto [d, a] = queue.top();
    queue.pop();
    if (done[a]) continue;
    done[a] = true;
    if (goal_at.count(a)) best = std::min(best, d);
    position(a, &qa);
    for (long dx = -1; dx <= 1; ++dx) {
      for (long dy = -1; dy <= 1; ++dy) {
        if ((dx == 0 && dy == 0) || (!full && dx != 0 && dy != 0)) continue;
        const Cell b{a.first + dx, a.second + dy};
        if (done[b] || !position(b, &qb) || !EdgeValid(checker, qa, qb, p.max_step)) continue;
        const double db = d + (qb - qa).norm();
        const auto it = dist.find(b);
        if (it == dist.end() || db < it->second) {
          dist[b] = db;
          queue.push({db, b});
        }
      }
    }
  }
  return best;
}

void ExpectValidPath(const PlannerResult& r, const PlanningProblem& p, const Eigen::VectorXd& goal) {
  ASSERT_EQ(r.status, PlanStatus::kExactSolution) << r.message;
  ASSERT_GE(r.path.size(), 2u);
  EXPECT_EQ(r.path.front(), p.start);
  EXPECT_EQ(r.path.back(), goal);
  const RobotModel& robot = p.checker->robot();
  for (size_t i = 0; i < r.path.size(); ++i) {
    EXPECT_TRUE((r.path[i].array() >= robot.lower_limits().array()).all()) << "waypoint " << i;
    EXPECT_TRUE((r.path[i].array() <= robot.upper_limits().array()).all()) << "waypoint " << i;
    if (i + 1 < r.path.size()) {
      EXPECT_TRUE(EdgeValid(*p.checker, r.path[i], r.path[i + 1], p.max_step)) << "segment " << i;
    }
  }
  EXPECT_GT(r.state_checks, 0u);
  EXPECT_GT(r.graph_states, 0u);
}

// ---------------------------------------------------------------------------------------------
// Known optimal lattice costs.

TEST(AstarTest, EmptyPlaneEightConnectedCostIsTheOctileDistance) {
  const auto checker = PlaneChecker({});
  const Eigen::Vector2d start(1.0, 1.0);
  // Octile distance on a unit lattice: (max − min) straight moves + min diagonal moves.
  const std::vector<std::pair<Eigen::Vector2d, double>> cases = {
      {Eigen::Vector2d(7.0, 4.0), 3.0 + 3.0 * std::sqrt(2.0)},
      {Eigen::Vector2d(1.0, 9.0), 8.0},
      {Eigen::Vector2d(9.0, 9.0), 8.0 * std::sqrt(2.0)},
      {Eigen::Vector2d(0.0, 6.0), 4.0 + std::sqrt(2.0)},
  };
  for (const auto& [goal, octile] : cases) {
    const PlanningProblem p = Problem(checker, start, goal, {{"resolution", 1.0}});
    const PlannerResult r = Plan(p);
    ExpectValidPath(r, p, goal);
    EXPECT_NEAR(PathCost(r.path), octile, 1e-9) << goal.transpose();
    EXPECT_EQ(r.suboptimality_bound, 1.0);
  }
  // Collinear lattice steps are merged: a straight or diagonal run is one segment.
  for (const Eigen::Vector2d& goal : {Eigen::Vector2d(1.0, 9.0), Eigen::Vector2d(9.0, 9.0), Eigen::Vector2d(9.0, 5.0)}) {
    const PlanningProblem p = Problem(checker, Eigen::Vector2d(5.0, 5.0), goal, {{"resolution", 1.0}});
    const PlannerResult r = Plan(p);
    ExpectValidPath(r, p, goal);
    EXPECT_EQ(r.path.size(), 2u) << goal.transpose();
  }
}

TEST(AstarTest, EmptySpaceTwentySixConnectedCostIsKnown) {
  // Three joints: full connectivity by default. On a unit lattice, Δk sorted a >= b >= c costs
  // c·√3 + (b − c)·√2 + (a − b); axis moves cost a + b + c.
  const auto checker = std::make_shared<const CollisionChecker>(SlideRobot(3), std::make_shared<Scene>());
  const Eigen::Vector3d start(1.0, 1.0, 1.0);
  for (const Eigen::Vector3d& goal : {Eigen::Vector3d(8.0, 5.0, 3.0), Eigen::Vector3d(0.0, 9.0, 6.0)}) {
    Eigen::Vector3d d = (goal - start).cwiseAbs();
    std::sort(d.data(), d.data() + 3, std::greater<>());
    const double full = d[2] * std::sqrt(3.0) + (d[1] - d[2]) * std::sqrt(2.0) + (d[0] - d[1]);
    PlanningProblem p = Problem(checker, start, goal, {{"resolution", 1.0}});
    PlannerResult r = Plan(p);
    ExpectValidPath(r, p, goal);
    EXPECT_NEAR(PathCost(r.path), full, 1e-9) << goal.transpose();
    p.parameters["connectivity"] = 1;
    r = Plan(p);
    ExpectValidPath(r, p, goal);
    EXPECT_NEAR(PathCost(r.path), d.sum(), 1e-9) << goal.transpose();
  }
}

TEST(AstarTest, EmptyPlaneAxisMovesCostIsTheManhattanDistance) {
  const auto checker = PlaneChecker({});
  const Eigen::Vector2d start(1.0, 1.0);
  for (const Eigen::Vector2d& goal : {Eigen::Vector2d(4.0, 2.5), Eigen::Vector2d(0.5, 8.0), Eigen::Vector2d(9.5, 0.0)}) {
    const PlanningProblem p = Problem(checker, start, goal, {{"resolution", 0.5}, {"connectivity", 1}});
    const PlannerResult r = Plan(p);
    ExpectValidPath(r, p, goal);
    EXPECT_NEAR(PathCost(r.path), (goal - start).lpNorm<1>(), 1e-9) << goal.transpose();
    for (size_t i = 0; i + 1 < r.path.size(); ++i) {
      const Eigen::VectorXd step = r.path[i + 1] - r.path[i];
      EXPECT_TRUE(step[0] == 0.0 || step[1] == 0.0) << "segment " << i << " is not an axis move";
    }
  }
}

TEST(AstarTest, DefaultResolutionDividesTheWidestJointRangeIntoCellsPerJoint) {
  const auto checker = PlaneChecker({});
  // 10 m / 20 cells = 0.5 m; axis moves from (1, 1) to (4, 2.5): Manhattan distance on the lattice.
  const Eigen::Vector2d start(1.0, 1.0), goal(4.0, 2.5);
  const PlanningProblem p = Problem(checker, start, goal, {{"cells_per_joint", 20}, {"connectivity", 1}});
  const PlannerResult r = Plan(p);
  ExpectValidPath(r, p, goal);
  EXPECT_NEAR(PathCost(r.path), 4.5, 1e-9);
  EXPECT_NEAR(PathCost(r.path), EagerDijkstra(p, {goal}, 0.5, false), 1e-9);
}

// ---------------------------------------------------------------------------------------------
// Obstacle scenes: equal to an eager Dijkstra over the same lattice.

/// Seeded planar scenes of random walls between start (0.7, 0.9) and goal (9.2, 8.6).
std::vector<std::vector<SceneObject>> RandomWallScenes(int count) {
  std::mt19937 rng(20240601);
  std::uniform_real_distribution<double> centre(2.0, 8.0), half(0.2, 1.8);
  std::vector<std::vector<SceneObject>> scenes;
  for (int s = 0; s < count; ++s) {
    std::vector<SceneObject> walls;
    for (int w = 0; w < 6; ++w) {
      const double cx = centre(rng), cy = centre(rng);
      const bool horizontal = w % 2 == 0;
      const double hx = horizontal ? half(rng) : 0.15, hy = horizontal ? 0.15 : half(rng);
      walls.push_back(Wall("wall" + std::to_string(w), cx - hx, cy - hy, cx + hx, cy + hy));
    }
    scenes.push_back(walls);
  }
  // A fixed maze-like scene: two long walls with gaps at opposite ends.
  scenes.push_back({Wall("lower", 0.0, 3.0, 8.0, 3.4), Wall("upper", 2.0, 6.0, 10.0, 6.4)});
  return scenes;
}

TEST(AstarTest, CostEqualsAnEagerDijkstraOnObstacleScenes) {
  const Eigen::Vector2d start(0.7, 0.9), goal(9.2, 8.6);  // goal off the lattice
  int detours = 0;
  for (const auto& walls : RandomWallScenes(5)) {
    const auto checker = PlaneChecker(walls);
    ASSERT_TRUE(checker->certifies_motion());
    for (const int connectivity : {1, 2}) {
      for (const double res : {0.5, 0.3}) {
        SCOPED_TRACE("connectivity " + std::to_string(connectivity) + ", resolution " + std::to_string(res));
        const PlanningProblem p =
            Problem(checker, start, goal, {{"resolution", res}, {"connectivity", connectivity}});
        const double optimal = EagerDijkstra(p, {goal}, res, connectivity == 2);
        const PlannerResult r = Plan(p);
        if (optimal == kInf) {  // the independent Dijkstra proves the lattice disconnected
          EXPECT_EQ(r.status, PlanStatus::kLatticeExhausted) << r.message;
          continue;
        }
        ExpectValidPath(r, p, goal);
        EXPECT_NEAR(PathCost(r.path), optimal, 1e-9);
        if (!checker->IsMotionCertified(start, goal)) ++detours;
      }
    }
  }
  EXPECT_GE(detours, 8) << "the scenes should block the straight line";
}

TEST(AstarTest, CostEqualsAnEagerDijkstraForRandomQueries) {
  // Random starts and off-lattice goals: the goal's edge and the axis-move heuristic's slack
  // change with where the goal sits in its cell.
  std::mt19937 rng(977);
  std::uniform_real_distribution<double> coordinate(0.0, 10.0);
  const auto scenes = RandomWallScenes(2);
  int solved = 0;
  for (const auto& walls : {scenes[0], scenes.back()}) {
    const auto checker = PlaneChecker(walls);
    for (int query = 0; query < 12; ++query) {
      Eigen::Vector2d start, goal;
      do {
        start = Eigen::Vector2d(coordinate(rng), coordinate(rng));
        goal = Eigen::Vector2d(coordinate(rng), coordinate(rng));
      } while (!checker->IsValid(start) || !checker->IsValid(goal));
      for (const int connectivity : {1, 2}) {
        SCOPED_TRACE("query " + std::to_string(query) + ", connectivity " + std::to_string(connectivity));
        const PlanningProblem p = Problem(checker, start, goal, {{"resolution", 0.45}, {"connectivity", connectivity}});
        const double optimal = EagerDijkstra(p, {goal}, 0.45, connectivity == 2);
        const PlannerResult r = Plan(p);
        if (optimal == kInf) {  // the independent Dijkstra proves the lattice disconnected
          EXPECT_EQ(r.status, PlanStatus::kLatticeExhausted) << r.message;
          continue;
        }
        ExpectValidPath(r, p, goal);
        EXPECT_NEAR(PathCost(r.path), optimal, 1e-9);
        ++solved;
      }
    }
  }
  EXPECT_GE(solved, 40);
}

TEST(AstarTest, DiscreteMotionChecksWithoutCertificationAlsoMatchDijkstra) {
  // FCL path: IsMotionCertified is not certified, so edges use IsMotionValid(max_step).
  const auto checker = PlaneChecker(RandomWallScenes(1).back(), /*force_fcl=*/true);
  ASSERT_FALSE(checker->certifies_motion());
  const Eigen::Vector2d start(0.7, 0.9), goal(9.2, 8.6);
  const PlanningProblem p = Problem(checker, start, goal, {{"resolution", 0.5}});
  const PlannerResult r = Plan(p);
  ExpectValidPath(r, p, goal);
  EXPECT_NEAR(PathCost(r.path), EagerDijkstra(p, {goal}, 0.5, true), 1e-9);
}

TEST(AstarTest, WeightedSearchCostsAtMostEpsilonTimesTheOptimum) {
  const Eigen::Vector2d start(0.7, 0.9), goal(9.2, 8.6);
  for (const auto& walls : RandomWallScenes(3)) {
    const auto checker = PlaneChecker(walls);
    for (const int connectivity : {1, 2}) {
      const double optimal = EagerDijkstra(Problem(checker, start, goal), {goal}, 0.3, connectivity == 2);
      if (optimal == kInf) continue;
      for (const double epsilon : {1.5, 3.0}) {
        SCOPED_TRACE("connectivity " + std::to_string(connectivity) + ", epsilon " + std::to_string(epsilon));
        const PlanningProblem p = Problem(checker, start, goal,
                                          {{"resolution", 0.3}, {"connectivity", connectivity}, {"epsilon", epsilon}});
        const PlannerResult r = Plan(p);
        ExpectValidPath(r, p, goal);
        EXPECT_EQ(r.suboptimality_bound, epsilon);
        EXPECT_LE(PathCost(r.path), epsilon * optimal + 1e-9);
        EXPECT_GE(PathCost(r.path), optimal - 1e-9);
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Goals.

/// A closed square room around (8, 8): its inside is unreachable from outside.
std::vector<SceneObject> Room() {
  return {Wall("south", 6.5, 6.5, 9.5, 6.8), Wall("north", 6.5, 9.2, 9.5, 9.5), Wall("west", 6.5, 6.5, 6.8, 9.5),
          Wall("east", 9.2, 6.5, 9.5, 9.5)};
}

TEST(AstarTest, WalledOffGoalExhaustsTheLattice) {
  const auto checker = PlaneChecker(Room());
  const Eigen::Vector2d start(1.0, 1.0), goal(8.0, 8.1);
  ASSERT_TRUE(checker->IsValid(goal));
  const PlannerResult r = Plan(Problem(checker, start, goal, {{"resolution", 0.5}}));
  // Not "out of time": every reachable node was expanded.
  EXPECT_EQ(r.status, PlanStatus::kLatticeExhausted);
  EXPECT_NE(r.message.find("reachable nodes were expanded"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("no path on the lattice at resolution 0.5"), std::string::npos) << r.message;
  EXPECT_TRUE(r.path.empty());
}

TEST(AstarTest, SeveralGoalsEndsAtAReachableOne) {
  const auto checker = PlaneChecker(Room());
  const Eigen::Vector2d start(1.0, 1.0), walled(8.0, 8.1), open(3.3, 8.7);
  PlanningProblem p = Problem(checker, start, walled, {{"resolution", 0.5}});
  p.additional_goals = {open};
  const PlannerResult r = Plan(p);
  ExpectValidPath(r, p, open);
  EXPECT_NEAR(PathCost(r.path), EagerDijkstra(p, {walled, open}, 0.5, true), 1e-9);
}

TEST(AstarTest, SeveralReachableGoalsEndsAtTheCheapest) {
  const auto checker = PlaneChecker(RandomWallScenes(1).back());
  const Eigen::Vector2d start(0.7, 0.9);
  const std::vector<Eigen::VectorXd> goals = {Eigen::Vector2d(9.2, 8.6), Eigen::Vector2d(1.1, 8.3),
                                              Eigen::Vector2d(9.4, 1.2)};
  for (const int connectivity : {1, 2}) {
    PlanningProblem p = Problem(checker, start, goals[0], {{"resolution", 0.5}, {"connectivity", connectivity}});
    p.additional_goals = {goals[1], goals[2]};
    const PlannerResult r = Plan(p);
    ASSERT_EQ(r.status, PlanStatus::kExactSolution) << r.message;
    EXPECT_EQ(r.path.back(), goals[2]) << "(9.4, 1.2) is on the start's side of the lower wall";
    ExpectValidPath(r, p, goals[2]);
    EXPECT_NEAR(PathCost(r.path), EagerDijkstra(p, goals, 0.5, connectivity == 2), 1e-9);
  }
}

TEST(AstarTest, GoalInTheStartsCellIsJoinedDirectly) {
  const auto checker = PlaneChecker({});
  const Eigen::Vector2d start(1.0, 1.0), goal(1.2, 0.9);
  const PlanningProblem p = Problem(checker, start, goal, {{"resolution", 1.0}});
  const PlannerResult r = Plan(p);
  ExpectValidPath(r, p, goal);
  ASSERT_EQ(r.path.size(), 2u);
  EXPECT_NEAR(PathCost(r.path), (goal - start).norm(), 1e-12);

  const PlanningProblem same = Problem(checker, start, start, {{"resolution", 1.0}});
  const PlannerResult r2 = Plan(same);
  ExpectValidPath(r2, same, start);
  EXPECT_EQ(PathCost(r2.path), 0.0);
}

TEST(AstarTest, GoalAtTheJointLimitIsReached) {
  // The goal's cell rounds past the limits' lattice range (10 − 0.7 = 9.3 = 18.6 steps of 0.5).
  const auto checker = PlaneChecker({});
  const Eigen::Vector2d start(0.7, 0.7), goal(10.0, 10.0);
  for (const int connectivity : {1, 2}) {
    const PlanningProblem p = Problem(checker, start, goal, {{"resolution", 0.5}, {"connectivity", connectivity}});
    const PlannerResult r = Plan(p);
    ExpectValidPath(r, p, goal);
    EXPECT_NEAR(PathCost(r.path), EagerDijkstra(p, {goal}, 0.5, connectivity == 2), 1e-9);
  }
}

TEST(AstarTest, InvalidStartAndGoalAreReported) {
  const auto checker = PlaneChecker({Wall("block", 4.0, 4.0, 6.0, 6.0)});
  const Eigen::Vector2d free(1.0, 1.0), blocked(5.0, 5.0);
  PlannerResult r = Plan(Problem(checker, blocked, free));
  EXPECT_EQ(r.status, PlanStatus::kInvalidStart);
  EXPECT_EQ(r.message, "start is in collision (link 'point' with 'block')");
  r = Plan(Problem(checker, free, blocked));
  EXPECT_EQ(r.status, PlanStatus::kInvalidGoal);
  EXPECT_EQ(r.message, "goal is in collision (link 'point' with 'block')");

  // An invalid goal among several is skipped.
  PlanningProblem p = Problem(checker, free, blocked, {{"resolution", 0.5}});
  p.additional_goals = {Eigen::Vector2d(8.0, 2.0)};
  r = Plan(p);
  ExpectValidPath(r, p, p.additional_goals[0]);
}

// ---------------------------------------------------------------------------------------------
// Parameters and refusals.

std::string SetupError(const PlanningProblem& p, ErrorCode code) {
  try {
    CreateAstar()->Setup(p);
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), code) << e.what();
    return e.what();
  }
  return "no error";
}

TEST(AstarTest, SpecIsRegisteredWithRangedParameters) {
  PlannerRegistry registry;
  RegisterSearchPlanners(&registry);
  EXPECT_EQ(registry.Ids(), std::vector<std::string>{"astar"});
  const PlannerSpec& spec = registry.Spec("astar");
  EXPECT_FALSE(spec.optimizing);
  EXPECT_TRUE(spec.Supports(RobotKind::kArm));
  EXPECT_TRUE(spec.Supports(RobotKind::kPlanar));
  EXPECT_TRUE(spec.Supports(RobotKind::kFreeFlyer));
  EXPECT_FALSE(spec.Supports(RobotKind::kDubinsCar));
  EXPECT_FALSE(spec.Supports(RobotKind::kReedsSheppCar));
  const ParameterValues defaults = ResolveParameters(spec, {});
  EXPECT_EQ(defaults.at("epsilon"), 1.0);
  EXPECT_EQ(defaults.at("resolution"), 0.0);
  EXPECT_EQ(defaults.at("connectivity"), 0.0);
  EXPECT_GE(defaults.at("max_nodes"), 100.0);
}

TEST(AstarTest, OutOfRangeParametersAreInvalidArguments) {
  const auto checker = PlaneChecker({});
  const Eigen::Vector2d start(1.0, 1.0), goal(2.0, 2.0);
  EXPECT_EQ(SetupError(Problem(checker, start, goal, {{"epsilon", 0.5}}), ErrorCode::kInvalidArgument),
            "planner.parameters['epsilon'] = 0.5 must be within [1, 100] (planner 'astar')");
  EXPECT_EQ(SetupError(Problem(checker, start, goal, {{"resolution", -0.1}}), ErrorCode::kInvalidArgument),
            "planner.parameters['resolution'] = -0.1 must be within [0, 100] (planner 'astar')");
  EXPECT_EQ(SetupError(Problem(checker, start, goal, {{"connectivity", 3}}), ErrorCode::kInvalidArgument),
            "planner.parameters['connectivity'] = 3 must be within [0, 2] (planner 'astar')");
  EXPECT_EQ(SetupError(Problem(checker, start, goal, {{"max_nodes", 10}}), ErrorCode::kInvalidArgument),
            "planner.parameters['max_nodes'] = 10 must be within [100, 1000000000] (planner 'astar')");
  // A positive resolution so fine that one joint spans more than 2^30 lattice steps.
  EXPECT_EQ(SetupError(Problem(checker, start, goal, {{"resolution", 1e-9}}), ErrorCode::kInvalidArgument),
            "planner.parameters['resolution'] = 1e-09 gives 1e+10 lattice steps across joint 'x' ([0, 10]); at "
            "most 2^30 (planner 'astar')");
}

TEST(AstarTest, PerJointResolutionSetsEachJointsSpacing) {
  const auto checker = PlaneChecker({});
  // x every 0.5 m, y every 0.25 m (resolution[1] overrides resolution for joint 1), 8-connected:
  // (1, 1) → (2.5, 2.5) is 3 diagonal steps (0.5, 0.25) and 3 steps of 0.25 in y. A uniform
  // 0.5 m lattice would take 3 diagonals of 0.5·√2 (2.12) instead.
  const Eigen::Vector2d start(1.0, 1.0), goal(2.5, 2.5);
  const PlanningProblem p =
      Problem(checker, start, goal, {{"resolution", 0.5}, {"resolution[1]", 0.25}, {"connectivity", 2}});
  const PlannerResult r = Plan(p);
  ExpectValidPath(r, p, goal);
  EXPECT_NEAR(PathCost(r.path), 3 * std::sqrt(0.5 * 0.5 + 0.25 * 0.25) + 0.75, 1e-9);
  for (const Eigen::VectorXd& q : r.path) {
    const double kx = (q[0] - 1.0) / 0.5, ky = (q[1] - 1.0) / 0.25;
    EXPECT_NEAR(kx, std::round(kx), 1e-9) << q.transpose();
    EXPECT_NEAR(ky, std::round(ky), 1e-9) << q.transpose();
  }
}

TEST(AstarTest, PerJointResolutionErrorsNameTheIndexedParameter) {
  const auto checker = PlaneChecker({});
  const Eigen::Vector2d start(1.0, 1.0), goal(2.0, 2.0);
  EXPECT_EQ(SetupError(Problem(checker, start, goal, {{"resolution[2]", 0.1}}), ErrorCode::kInvalidArgument),
            "planner.parameters['resolution[2]']: robot 'point' has 2 joints (indices 0..1) (planner 'astar')");
  EXPECT_EQ(SetupError(Problem(checker, start, goal, {{"resolution[1]", -1}}), ErrorCode::kInvalidArgument),
            "planner.parameters['resolution[1]'] = -1 must be within [0, 100] (planner 'astar')");
  EXPECT_EQ(SetupError(Problem(checker, start, goal, {{"epsilon[1]", 2}}), ErrorCode::kInvalidArgument),
            "planner.parameters['epsilon[1]'] is not a parameter of planner 'astar' (known: resolution, "
            "cells_per_joint, connectivity, epsilon, max_nodes, max_expansions)");
  EXPECT_EQ(SetupError(Problem(checker, start, goal, {{"resolution[1]", 1e-9}}), ErrorCode::kInvalidArgument),
            "planner.parameters['resolution[1]'] = 1e-09 gives 1e+10 lattice steps across joint 'y' ([0, 10]); at "
            "most 2^30 (planner 'astar')");
}

TEST(AstarTest, FullConnectivityWithSevenJointsIsAFailedPrecondition) {
  const auto checker = PandaWithBox();
  const Eigen::VectorXd q = Eigen::VectorXd::Zero(7);
  EXPECT_EQ(SetupError(Problem(checker, q, q, {{"connectivity", 2}}), ErrorCode::kFailedPrecondition),
            "planner.parameters['connectivity'] = 2: full connectivity (all 3^n - 1 neighbours) needs at most 3 "
            "joints; robot 'panda' has 7 — use connectivity = 1 (axis moves) (planner 'astar')");
}

TEST(AstarTest, CarsAreRefused) {
  MobileDescription car;
  car.kind = RobotKind::kDubinsCar;
  car.workspace_min = Eigen::Vector3d(0.0, 0.0, 0.0);
  car.workspace_max = Eigen::Vector3d(10.0, 10.0, 0.0);
  car.body.collision.push_back(Shape::Sphere(0.2));
  auto checker = std::make_shared<const CollisionChecker>(RobotFromMobile(car), std::make_shared<Scene>());
  const Eigen::VectorXd q = Eigen::Vector3d(1.0, 1.0, 0.0);
  const std::string message = SetupError(Problem(checker, q, q), ErrorCode::kFailedPrecondition);
  EXPECT_NE(message.find("its lattice moves ignore a car's minimum turning radius"), std::string::npos) << message;
}

// ---------------------------------------------------------------------------------------------
// Budgets and terminations.

TEST(AstarTest, MemoryCapEndsTheSearchWithNoSolution) {
  const auto checker = PlaneChecker({});
  const Eigen::Vector2d start(1.0, 1.0), goal(9.0, 9.0);
  const PlannerResult r = Plan(Problem(checker, start, goal, {{"resolution", 0.05}, {"max_nodes", 100}}));
  EXPECT_EQ(r.status, PlanStatus::kNoSolution);
  EXPECT_NE(r.message.find("hit its memory cap: max_nodes = 100 lattice nodes stored"), std::string::npos)
      << r.message;
  EXPECT_LE(r.graph_states, 100u);
  EXPECT_TRUE(r.path.empty());
}

TEST(AstarTest, MaxExpansionsEndsTheSearchWithNoSolution) {
  const auto checker = PlaneChecker({});
  const PlannerResult r = Plan(Problem(checker, Eigen::Vector2d(1.0, 1.0), Eigen::Vector2d(9.0, 9.0),
                                       {{"resolution", 0.5}, {"max_expansions", 5}}));
  EXPECT_EQ(r.status, PlanStatus::kNoSolution);
  EXPECT_NE(r.message.find("stopped after max_expansions = 5 expansions"), std::string::npos) << r.message;
}

TEST(AstarTest, TerminationsMapToStatuses) {
  const auto checker = PlaneChecker({});
  const PlanningProblem p = Problem(checker, Eigen::Vector2d(1.0, 1.0), Eigen::Vector2d(9.0, 9.0));
  PlannerResult r = Plan(p, Termination::AlreadyStopped());
  EXPECT_EQ(r.status, PlanStatus::kCancelled);
  EXPECT_EQ(r.message, "cancelled by the client");
  EXPECT_TRUE(r.path.empty());

  r = Plan(p, Termination::After(std::chrono::seconds(-1)));
  EXPECT_EQ(r.status, PlanStatus::kNoSolution);
  EXPECT_NE(r.message.find("within the budget"), std::string::npos) << r.message;

  const auto now = Termination::Clock::now();
  r = Plan(p, Termination(now + std::chrono::hours(1), now - std::chrono::seconds(1)));
  EXPECT_EQ(r.status, PlanStatus::kDeadlineExceeded);
}

TEST(AstarTest, SolveBeforeSetupThrows) {
  auto planner = CreateAstar();
  EXPECT_THROW(planner->Solve(Termination()), Error);
}

TEST(AstarTest, RunsRepeatExactly) {
  const auto checker = PlaneChecker(RandomWallScenes(2)[1]);
  PlanningProblem p = Problem(checker, Eigen::Vector2d(0.7, 0.9), Eigen::Vector2d(9.2, 8.6),
                              {{"resolution", 0.25}, {"connectivity", 1}});
  const PlannerResult a = Plan(p);
  p.seed = 12345;  // unused: the search has no randomness
  auto planner = CreateAstar();
  planner->Setup(p);
  planner->Solve(Termination());
  const PlannerResult b = planner->Solve(Termination());  // a second Solve starts afresh
  ASSERT_EQ(a.status, PlanStatus::kExactSolution) << a.message;
  ASSERT_EQ(b.status, PlanStatus::kExactSolution) << b.message;
  EXPECT_EQ(a.path, b.path);
  EXPECT_EQ(a.graph_states, b.graph_states);
  EXPECT_EQ(a.state_checks, b.state_checks);
  EXPECT_EQ(a.message, b.message);
}

// ---------------------------------------------------------------------------------------------
// A 7-joint arm.

TEST(AstarTest, PandaQueryAroundABoxFinishes) {
  const auto checker = PandaWithBox();
  Eigen::VectorXd start(7), goal(7);
  start << -1.2, -0.3, 0.0, -2.2, 0.0, 1.9, 0.8;
  goal << 1.2, -0.3, 0.0, -2.2, 0.0, 1.9, 0.8;
  ASSERT_TRUE(checker->IsValid(start));
  ASSERT_TRUE(checker->IsValid(goal));
  ASSERT_FALSE(checker->IsMotionCertified(start, goal)) << "the box must block the straight swing";
  const PlanningProblem p = Problem(checker, start, goal);
  const PlannerResult r = Plan(p, Termination::After(std::chrono::seconds(30)));
  ExpectValidPath(r, p, goal);
  EXPECT_EQ(r.suboptimality_bound, 1.0);
  std::cout << "[ panda ] " << r.message << "; " << r.state_checks << " state checks, " << r.solve_seconds
            << " s\n";
}

}  // namespace
}  // namespace chasles
