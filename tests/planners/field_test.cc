// The field family. potential_field: pure descent on convex scenes (a point robot round a
// sphere and a box, a 2R arm in free space), a U-trap that is a local minimum (reported, never a
// wrong path), escapes by random walks, the 2R arm round a wall, terminations and budgets.
// wavefront: success exactly when an independent BFS over the same grid finds the goal reachable
// (random box scenes, the U-trap, a maze), walled-off goals, held coordinates, the refusal of
// more than 3 moving coordinates, the memory cap. Bad parameters for both.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <deque>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "chasles/collision/collision_checker.h"
#include "chasles/planners/registry.h"
#include "chasles/robot/error.h"
#include "two_link_arm.h"

namespace chasles {
namespace {

Eigen::Isometry3d At(double x, double y, double z = 0.0) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(x, y, z);
  return t;
}

/// A point robot: prismatic joints along x, y (and z) carrying a sphere of radius 0.05 m, each
/// joint within [-1, 1] m.
std::shared_ptr<const RobotModel> PointRobot(int dims) {
  const char* names[] = {"x", "y", "z", "w"};
  std::vector<Link> links(dims + 1);
  std::vector<Joint> joints(dims);
  links[0].name = "base";
  for (int i = 0; i < dims; ++i) {
    links[i + 1].name = std::string("carriage_") + names[i];
    links[i + 1].parent_joint = i;
    Joint& j = joints[i];
    j.name = names[i];
    j.type = JointType::kPrismatic;
    j.parent_link = i;
    j.child_link = i + 1;
    j.axis = i < 3 ? Eigen::Vector3d::Unit(i) : Eigen::Vector3d::UnitX();
    j.limits = {-1.0, 1.0, 1.0, 0.0};
    j.dof = i;
  }
  links[dims].collision.push_back(Shape::Sphere(0.05));
  return RobotModel::FromTree("point", links, joints);
}

using testing::kTwoLinkUrdf;  // the planar 2R arm of the planner contract test

void AddBox(Scene* scene, const std::string& name, double cx, double cy, double sx, double sy) {
  scene->AddObject({name, Shape::Box(Eigen::Vector3d(sx, sy, 0.5), At(cx, cy))});
}

/// A U open toward -x: bottom wall at x = 0.3, side walls at y = ±0.4 from x = -0.3.
void AddUTrap(Scene* scene) {
  AddBox(scene, "u_bottom", 0.3, 0.0, 0.1, 0.9);
  AddBox(scene, "u_left", 0.0, 0.4, 0.7, 0.1);
  AddBox(scene, "u_right", 0.0, -0.4, 0.7, 0.1);
}

class FieldPlannerTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    registry_ = new PlannerRegistry();
    RegisterFieldPlanners(registry_);
  }
  static void TearDownTestSuite() {
    delete registry_;
    registry_ = nullptr;
  }

  static PlanningProblem Problem(std::shared_ptr<const RobotModel> robot, std::shared_ptr<Scene> scene,
                                 const Eigen::VectorXd& start, const Eigen::VectorXd& goal, ParameterValues params = {},
                                 std::uint64_t seed = 1) {
    PlanningProblem p;
    p.checker = std::make_shared<const CollisionChecker>(std::move(robot), std::move(scene));
    p.start = start;
    p.goal = goal;
    p.goal_tolerance = 1e-3;
    p.max_step = 0.005;
    p.seed = seed;
    p.parameters = std::move(params);
    return p;
  }

  static PlannerResult Plan(const std::string& id, const PlanningProblem& p,
                            const Termination& termination = Termination::After(std::chrono::seconds(10))) {
    auto planner = registry_->Create(id);
    planner->Setup(p);
    return planner->Solve(termination);
  }

  /// Exact endpoints, every motion valid (discrete re-check at max_step), within the limits.
  static void ExpectValidPath(const PlannerResult& r, const PlanningProblem& p) {
    ASSERT_EQ(r.status, PlanStatus::kExactSolution) << r.message;
    ASSERT_GE(r.path.size(), 2u);
    EXPECT_EQ(r.path.front(), p.start);
    EXPECT_EQ(r.path.back(), p.goal);
    const RobotModel& robot = p.checker->robot();
    for (std::size_t i = 0; i < r.path.size(); ++i) {
      EXPECT_TRUE(r.path[i].allFinite());
      EXPECT_TRUE((r.path[i].array() >= robot.lower_limits().array()).all()) << "waypoint " << i;
      EXPECT_TRUE((r.path[i].array() <= robot.upper_limits().array()).all()) << "waypoint " << i;
      if (i + 1 < r.path.size()) {
        EXPECT_TRUE(p.checker->IsMotionValid(r.path[i], r.path[i + 1], p.max_step)) << "segment " << i;
      }
    }
    EXPECT_GT(r.state_checks, 0u);
  }

  /// Wavefront on a 2-D point robot problem succeeds (with a valid path) exactly when
  /// GridReachable says the grid connects start and goal.
  static void ExpectWavefrontMatchesBfs(const PlanningProblem& p, double r, const std::string& label);

  static PlannerRegistry* registry_;
};

PlannerRegistry* FieldPlannerTest::registry_ = nullptr;

// ---------------------------------------------------------------------------------------------
// potential_field

TEST_F(FieldPlannerTest, PotentialFieldDescendsRoundASphere) {
  auto scene = std::make_shared<Scene>();
  scene->AddObject({"ball", Shape::Sphere(0.2, At(0.0, 0.0))});
  const PlanningProblem p = Problem(PointRobot(2), scene, Eigen::Vector2d(-0.8, 0.05), Eigen::Vector2d(0.8, 0.0),
                                    {{"random_walks", 0}});
  ASSERT_FALSE(p.checker->IsMotionValid(p.start, p.goal, p.max_step)) << "the straight line must collide";
  const PlannerResult r = Plan("potential_field", p);
  ExpectValidPath(r, p);
  EXPECT_EQ(r.message.find("random walks"), std::string::npos) << r.message;
}

TEST_F(FieldPlannerTest, PotentialFieldDescendsRoundABox) {
  auto scene = std::make_shared<Scene>();
  // The goal line crosses the box but not its face's normal through the goal: the descent slides
  // up the face and round the corner (a goal straight behind a face would be a local minimum).
  AddBox(scene.get(), "crate", 0.0, 0.1, 0.3, 0.4);
  const PlanningProblem p = Problem(PointRobot(2), scene, Eigen::Vector2d(-0.7, -0.1), Eigen::Vector2d(0.7, 0.5),
                                    {{"random_walks", 0}});
  ASSERT_FALSE(p.checker->IsMotionValid(p.start, p.goal, p.max_step));
  ExpectValidPath(Plan("potential_field", p), p);
}

TEST_F(FieldPlannerTest, PotentialFieldMovesATwoLinkArmInFreeSpaceStraight) {
  const PlanningProblem p = Problem(RobotModel::FromUrdf(kTwoLinkUrdf), std::make_shared<Scene>(),
                                    Eigen::Vector2d(1.2, 0.5), Eigen::Vector2d(-1.0, -0.7), {{"random_walks", 0}});
  const PlannerResult r = Plan("potential_field", p);
  ExpectValidPath(r, p);
  // No obstacle: the descent is the straight joint-space line, so every waypoint lies on it.
  const Eigen::Vector2d line = (p.goal - p.start).normalized();
  for (const Eigen::VectorXd& q : r.path) {
    const Eigen::Vector2d d = q - p.start;
    EXPECT_NEAR(d.x() * line.y() - d.y() * line.x(), 0.0, 1e-9) << q.transpose();
  }
}

TEST_F(FieldPlannerTest, PotentialFieldReportsTheUTrapAsALocalMinimumWithoutWalks) {
  auto scene = std::make_shared<Scene>();
  AddUTrap(scene.get());
  const PlanningProblem p = Problem(PointRobot(2), scene, Eigen::Vector2d(-0.6, 0.0), Eigen::Vector2d(0.7, 0.0),
                                    {{"random_walks", 0}});
  const PlannerResult r = Plan("potential_field", p);
  EXPECT_EQ(r.status, PlanStatus::kLocalMinimum) << r.message;
  EXPECT_TRUE(r.path.empty());
  // Named: where, how far, the gradient. Where: on y = 0 in front of the bottom wall (inner face
  // x = 0.25), at the balance of the pulls: ζ (0.7 − x) = η (1/d − 1/ρ0)/d², d = 0.2 − x, with the
  // defaults ζ = 1, η = 0.01, ρ0 = 0.2.
  double lo = 0.0, hi = 0.19;
  for (int i = 0; i < 60; ++i) {
    const double x = 0.5 * (lo + hi), d = 0.2 - x;
    ((0.7 - x) > 0.01 * (1 / d - 1 / 0.2) / (d * d) ? lo : hi) = x;
  }
  const std::string prefix = "local minimum at q = (";
  const std::size_t at = r.message.find(prefix);
  ASSERT_NE(at, std::string::npos) << r.message;
  std::size_t used = 0;
  const double x = std::stod(r.message.substr(at + prefix.size()), &used);
  EXPECT_NEAR(x, lo, 2e-3) << r.message;  // the descent stops when its step shrinks below step/64
  EXPECT_EQ(r.message.substr(at + prefix.size() + used, 4), ", 0)") << r.message;
  EXPECT_NE(r.message.find("rad from the goal, gradient norm"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("after 0 random walks"), std::string::npos) << r.message;
}

TEST_F(FieldPlannerTest, PotentialFieldWithWalksReachesTheGoalOrReportsALocalMinimum) {
  auto scene = std::make_shared<Scene>();
  AddUTrap(scene.get());
  int reached = 0;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    const PlanningProblem p = Problem(PointRobot(2), scene, Eigen::Vector2d(-0.6, 0.0), Eigen::Vector2d(0.7, 0.0),
                                      {{"random_walks", 30}}, seed);
    const PlannerResult r = Plan("potential_field", p);
    if (r.status == PlanStatus::kExactSolution) {
      ++reached;
      ExpectValidPath(r, p);
    } else {
      EXPECT_EQ(r.status, PlanStatus::kLocalMinimum) << "seed " << seed << ": " << r.message;
      EXPECT_TRUE(r.path.empty());
      EXPECT_NE(r.message.find("after 30 random walks"), std::string::npos) << r.message;
    }
  }
  std::printf("U-trap with 30 walks: %d of 6 seeds reached the goal\n", reached);
}

TEST_F(FieldPlannerTest, PotentialFieldWalksTheTwoLinkArmRoundTheWall) {
  // The contract test's problem: the straight joint-space line hits the wall; the descent stops
  // in front of it and the walks lead round.
  auto scene = std::make_shared<Scene>();
  scene->AddObject({"wall", Shape::Box(Eigen::Vector3d(0.2, 0.3, 0.5), At(1.4, 0.0))});
  int reached = 0;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    const PlanningProblem p = Problem(RobotModel::FromUrdf(kTwoLinkUrdf), scene, Eigen::Vector2d(1.2, 0.0),
                                      Eigen::Vector2d(-1.2, 0.0), {}, seed);
    const PlannerResult r = Plan("potential_field", p);
    if (r.status == PlanStatus::kExactSolution) {
      ++reached;
      ExpectValidPath(r, p);
      EXPECT_NE(r.message.find("random walks"), std::string::npos) << r.message;
    } else {
      EXPECT_EQ(r.status, PlanStatus::kLocalMinimum) << "seed " << seed << ": " << r.message;
      EXPECT_TRUE(r.path.empty());
    }
  }
  EXPECT_GE(reached, 9) << "default parameters should round the wall for nearly every seed";
}

TEST_F(FieldPlannerTest, PotentialFieldSeededRunsRepeat) {
  auto scene = std::make_shared<Scene>();
  AddUTrap(scene.get());
  const PlanningProblem p = Problem(PointRobot(2), scene, Eigen::Vector2d(-0.6, 0.0), Eigen::Vector2d(0.7, 0.0),
                                    {{"random_walks", 30}}, 3);
  const PlannerResult a = Plan("potential_field", p);
  const PlannerResult b = Plan("potential_field", p);
  EXPECT_EQ(a.status, b.status);
  EXPECT_EQ(a.message, b.message);
  ASSERT_EQ(a.path.size(), b.path.size());
  for (std::size_t i = 0; i < a.path.size(); ++i) EXPECT_EQ(a.path[i], b.path[i]) << "waypoint " << i;
}

TEST_F(FieldPlannerTest, PotentialFieldTerminationsAndStepBudget) {
  const PlanningProblem p = Problem(PointRobot(2), std::make_shared<Scene>(), Eigen::Vector2d(-0.8, 0.0),
                                    Eigen::Vector2d(0.8, 0.0));
  const auto now = Termination::Clock::now();
  EXPECT_EQ(Plan("potential_field", p, Termination(now + std::chrono::hours(1), now - std::chrono::seconds(1))).status,
            PlanStatus::kDeadlineExceeded);
  const PlannerResult budget = Plan("potential_field", p, Termination::After(std::chrono::seconds(-1)));
  EXPECT_EQ(budget.status, PlanStatus::kNoSolution) << budget.message;
  EXPECT_TRUE(budget.path.empty());

  PlanningProblem few = p;
  few.parameters["max_steps"] = 3;  // 1.6 m at 0.05 m per step needs 32
  const PlannerResult r = Plan("potential_field", few);
  EXPECT_EQ(r.status, PlanStatus::kNoSolution) << r.message;
  EXPECT_TRUE(r.path.empty());
  EXPECT_NE(r.message.find("max_steps = 3"), std::string::npos) << r.message;
  EXPECT_EQ(r.graph_states, 3u);
}

TEST_F(FieldPlannerTest, PotentialFieldReportsInvalidEndpoints) {
  auto scene = std::make_shared<Scene>();
  scene->AddObject({"ball", Shape::Sphere(0.2, At(0.0, 0.0))});
  EXPECT_EQ(Plan("potential_field", Problem(PointRobot(2), scene, Eigen::Vector2d(0.1, 0.0), Eigen::Vector2d(0.8, 0.0)))
                .status,
            PlanStatus::kInvalidStart);
  EXPECT_EQ(Plan("potential_field", Problem(PointRobot(2), scene, Eigen::Vector2d(0.8, 0.0), Eigen::Vector2d(0.0, 0.1)))
                .status,
            PlanStatus::kInvalidGoal);
}

// ---------------------------------------------------------------------------------------------
// wavefront

/// An independent reachability check over the wavefront's grid for the 2-D point robot: nodes
/// at goal + k·r per coordinate within the joint limits [-1, 1] (up to rounding, then on the
/// limit), the start on a node; breadth-first from the goal node over 8-connected valid nodes, an
/// edge usable when the motion from the new node to the one it is reached from is valid (the
/// planner's motion check: certified when the checker certifies).
bool GridReachable(const PlanningProblem& p, double r) {
  const CollisionChecker& checker = *p.checker;
  int kmin[2], count[2];
  for (int d = 0; d < 2; ++d) {
    kmin[d] = static_cast<int>(std::lround((-1.0 - p.goal[d]) / r));
    if (p.goal[d] + kmin[d] * r < -1.0 - 1e-9) ++kmin[d];
    int kmax = static_cast<int>(std::lround((1.0 - p.goal[d]) / r));
    if (p.goal[d] + kmax * r > 1.0 + 1e-9) --kmax;
    count[d] = kmax - kmin[d] + 1;
  }
  const auto node = [&](int i, int j) {
    return Eigen::Vector2d(std::clamp(p.goal[0] + (i + kmin[0]) * r, -1.0, 1.0),
                           std::clamp(p.goal[1] + (j + kmin[1]) * r, -1.0, 1.0));
  };
  const auto index = [&](const Eigen::VectorXd& q, int d) {
    return static_cast<int>(std::lround((q[d] - p.goal[d]) / r)) - kmin[d];
  };
  const auto motion = [&](const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
    return checker.certifies_motion() ? checker.IsMotionCertified(a, b) : checker.IsMotionValid(a, b, p.max_step);
  };
  std::vector<char> seen(count[0] * count[1], 0);
  const int gi = index(p.goal, 0), gj = index(p.goal, 1), si = index(p.start, 0), sj = index(p.start, 1);
  std::deque<std::pair<int, int>> open{{gi, gj}};
  seen[gi * count[1] + gj] = 1;
  while (!open.empty()) {
    const auto [i, j] = open.front();
    open.pop_front();
    if (i == si && j == sj) return true;
    for (int di = -1; di <= 1; ++di) {
      for (int dj = -1; dj <= 1; ++dj) {
        const int a = i + di, b = j + dj;
        if ((di == 0 && dj == 0) || a < 0 || b < 0 || a >= count[0] || b >= count[1] || seen[a * count[1] + b]) continue;
        if (!checker.IsValid(node(a, b)) || !motion(node(a, b), node(i, j))) continue;
        seen[a * count[1] + b] = 1;
        open.emplace_back(a, b);
      }
    }
  }
  return false;
}

/// Portable uniform draws for the scene generator.
double Uniform(std::mt19937_64& engine, double lo, double hi) {
  return lo + (hi - lo) * static_cast<double>(engine() >> 11) * 0x1.0p-53;
}

void FieldPlannerTest::ExpectWavefrontMatchesBfs(const PlanningProblem& p, double r, const std::string& label) {
  SCOPED_TRACE(label);
  const bool reachable = GridReachable(p, r);
  const PlannerResult result = Plan("wavefront", p);
  if (reachable) {
    ExpectValidPath(result, p);
  } else {
    EXPECT_EQ(result.status, PlanStatus::kLatticeExhausted) << result.message;
    EXPECT_TRUE(result.path.empty());
    EXPECT_NE(result.message.find("the start is not connected to the goal on the grid at resolution 0.1"),
              std::string::npos)
        << result.message;
  }
}

TEST_F(FieldPlannerTest, WavefrontReachesTheGoalExactlyWhenTheGridConnectsIt) {
  // Start (-0.8, -0.7) and goal (0.7, 0.6) on the nodes of the 0.1 m grid anchored at the goal.
  const Eigen::Vector2d start(-0.8, -0.7), goal(0.7, 0.6);
  int reachable = 0, scenes = 0;
  for (std::uint64_t seed = 1; seed <= 12; ++seed) {
    std::mt19937_64 engine(seed);
    auto scene = std::make_shared<Scene>();
    for (int k = 0; k < 12; ++k) {
      const double cx = Uniform(engine, -0.9, 0.9), cy = Uniform(engine, -0.9, 0.9);
      const double sx = Uniform(engine, 0.05, 0.9), sy = Uniform(engine, 0.05, 0.9);
      // Keep the endpoints free.
      if (std::abs(cx - start.x()) < sx / 2 + 0.1 && std::abs(cy - start.y()) < sy / 2 + 0.1) continue;
      if (std::abs(cx - goal.x()) < sx / 2 + 0.1 && std::abs(cy - goal.y()) < sy / 2 + 0.1) continue;
      AddBox(scene.get(), "box" + std::to_string(k), cx, cy, sx, sy);
    }
    const PlanningProblem p = Problem(PointRobot(2), scene, start, goal, {{"resolution", 0.1}});
    ++scenes;
    reachable += GridReachable(p, 0.1) ? 1 : 0;
    ExpectWavefrontMatchesBfs(p, 0.1, "seed " + std::to_string(seed));
  }
  // Both outcomes occur among the scenes, so both branches are exercised.
  std::printf("wavefront random scenes: %d of %d connected on the grid\n", reachable, scenes);
  EXPECT_GT(reachable, 0);
  EXPECT_LT(reachable, scenes);
}

TEST_F(FieldPlannerTest, WavefrontLeavesTheUTrapAndSolvesAMaze) {
  auto trap = std::make_shared<Scene>();
  AddUTrap(trap.get());
  const PlanningProblem p = Problem(PointRobot(2), trap, Eigen::Vector2d(0.1, 0.1), Eigen::Vector2d(0.7, -0.2),
                                    {{"resolution", 0.1}});
  ASSERT_TRUE(GridReachable(p, 0.1));
  ExpectWavefrontMatchesBfs(p, 0.1, "u-trap");

  // A maze: three walls with gaps at alternating ends.
  auto maze = std::make_shared<Scene>();
  AddBox(maze.get(), "wall1", -0.45, -0.25, 0.06, 1.5);  // gap at the top
  AddBox(maze.get(), "wall2", 0.0, 0.25, 0.06, 1.5);     // gap at the bottom
  AddBox(maze.get(), "wall3", 0.45, -0.25, 0.06, 1.5);   // gap at the top
  const PlanningProblem m = Problem(PointRobot(2), maze, Eigen::Vector2d(-0.8, -0.7), Eigen::Vector2d(0.8, -0.7),
                                    {{"resolution", 0.1}});
  ASSERT_TRUE(GridReachable(m, 0.1));
  const PlannerResult r = Plan("wavefront", m);
  ExpectValidPath(r, m);
  // It winds: up past wall1, down past wall2, up past wall3.
  double top = -1, bottom = 1;
  for (const Eigen::VectorXd& q : r.path) {
    if (q[0] > -0.45 && q[0] < 0.0) top = std::max(top, q[1]);
    if (q[0] > 0.0 && q[0] < 0.45) bottom = std::min(bottom, q[1]);
  }
  EXPECT_GT(top, 0.5);
  EXPECT_LT(bottom, -0.5);
}

TEST_F(FieldPlannerTest, WavefrontReportsAWalledOffGoal) {
  auto scene = std::make_shared<Scene>();
  // A closed ring of walls round the goal (0.5, 0.5).
  AddBox(scene.get(), "north", 0.5, 0.8, 0.7, 0.06);
  AddBox(scene.get(), "south", 0.5, 0.2, 0.7, 0.06);
  AddBox(scene.get(), "east", 0.8, 0.5, 0.06, 0.7);
  AddBox(scene.get(), "west", 0.2, 0.5, 0.06, 0.7);
  const PlanningProblem p = Problem(PointRobot(2), scene, Eigen::Vector2d(-0.5, -0.5), Eigen::Vector2d(0.5, 0.5),
                                    {{"resolution", 0.1}});
  ASSERT_FALSE(GridReachable(p, 0.1));
  ExpectWavefrontMatchesBfs(p, 0.1, "walled off");
  const PlannerResult r = Plan("wavefront", p);
  EXPECT_NE(r.message.find("(21 × 21 cells)"), std::string::npos) << r.message;
}

TEST_F(FieldPlannerTest, WavefrontHoldsEqualCoordinatesFixedAndPlansOverThree) {
  // A 3-D point robot: z equal at start and goal, so it plans over (x, y) at z = 0.3.
  auto scene = std::make_shared<Scene>();
  scene->AddObject({"pillar", Shape::Box(Eigen::Vector3d(0.4, 0.4, 2.0), At(0.0, 0.0))});
  const PlanningProblem flat = Problem(PointRobot(3), scene, Eigen::Vector3d(-0.7, -0.1, 0.3),
                                       Eigen::Vector3d(0.7, 0.2, 0.3));
  const PlannerResult r = Plan("wavefront", flat);
  ExpectValidPath(r, flat);
  for (const Eigen::VectorXd& q : r.path) EXPECT_EQ(q[2], 0.3) << q.transpose();
  EXPECT_EQ(r.message.find("released"), std::string::npos) << r.message;

  // All three move: a 3-D grid, round a box that spans the whole height but not the width.
  const PlanningProblem full = Problem(PointRobot(3), scene, Eigen::Vector3d(-0.7, -0.1, -0.5),
                                       Eigen::Vector3d(0.7, 0.2, 0.4), {{"cells_per_coordinate", 20}});
  ExpectValidPath(Plan("wavefront", full), full);
}

TEST_F(FieldPlannerTest, WavefrontReleasesHeldCoordinatesWhenBlockedWithThemFixed) {
  // y is equal at start and goal, and the line y = 0 is walled: the 1-D grid over x fails, so
  // y is released (the 2R arm of the contract test is the same case).
  auto scene = std::make_shared<Scene>();
  AddBox(scene.get(), "wall", 0.0, 0.0, 0.1, 0.6);
  const PlanningProblem p = Problem(PointRobot(2), scene, Eigen::Vector2d(-0.8, 0.0), Eigen::Vector2d(0.8, 0.0));
  const PlannerResult r = Plan("wavefront", p);
  ExpectValidPath(r, p);
  EXPECT_NE(r.message.find("(held coordinates released: y)"), std::string::npos) << r.message;
}

TEST_F(FieldPlannerTest, WavefrontRefusesMoreThanThreeMovingCoordinates) {
  auto planner = registry_->Create("wavefront");
  const Eigen::Vector4d start(-0.5, -0.5, -0.5, -0.5), goal(0.5, 0.5, 0.5, 0.5);
  try {
    planner->Setup(Problem(PointRobot(4), std::make_shared<Scene>(), start, goal));
    FAIL() << "expected Error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kFailedPrecondition);
    EXPECT_EQ(std::string(e.what()),
              "wavefront plans over at most 3 moving coordinates; this query moves 4 (x, y, z, w) — use astar or a "
              "sampling planner");
  }
  // Three of the four moving is fine; the fourth is held.
  const Eigen::Vector4d goal3(0.5, 0.5, 0.5, -0.5);
  const PlanningProblem p = Problem(PointRobot(4), std::make_shared<Scene>(), start, goal3, {{"cells_per_coordinate", 8}});
  const PlannerResult r = Plan("wavefront", p);
  ExpectValidPath(r, p);
  for (const Eigen::VectorXd& q : r.path) EXPECT_EQ(q[3], -0.5);
}

TEST_F(FieldPlannerTest, WavefrontMemoryCapAndTerminations) {
  auto planner = registry_->Create("wavefront");
  try {
    planner->Setup(Problem(PointRobot(2), std::make_shared<Scene>(), Eigen::Vector2d(-0.5, -0.5),
                           Eigen::Vector2d(0.5, 0.5), {{"resolution", 0.001}, {"max_cells", 1000000}}));
    FAIL() << "expected Error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_EQ(std::string(e.what()),
              "planner.parameters['max_cells'] = 1000000 is below the 4004001 cells (2001 × 2001) of the wavefront "
              "grid at resolution 0.001 × 0.001 (planner 'wavefront'); raise max_cells or coarsen resolution");
  }
  const PlanningProblem p = Problem(PointRobot(2), std::make_shared<Scene>(), Eigen::Vector2d(-0.5, -0.5),
                                    Eigen::Vector2d(0.5, 0.5));
  EXPECT_EQ(Plan("wavefront", p, Termination::AlreadyStopped()).status, PlanStatus::kCancelled);
  const PlannerResult budget = Plan("wavefront", p, Termination::After(std::chrono::seconds(-1)));
  EXPECT_EQ(budget.status, PlanStatus::kNoSolution) << budget.message;
  EXPECT_NE(budget.message.find("stopped by the time budget"), std::string::npos) << budget.message;
}

// ---------------------------------------------------------------------------------------------
// both

TEST_F(FieldPlannerTest, CancelFromAnotherThreadStopsBoth) {
  // Goals walled off, so neither planner would stop soon by itself: potential_field keeps
  // walking (100000 walks) and wavefront floods a 4-million-cell grid.
  auto scene = std::make_shared<Scene>();
  AddBox(scene.get(), "north", 0.5, 0.8, 0.7, 0.06);
  AddBox(scene.get(), "south", 0.5, 0.2, 0.7, 0.06);
  AddBox(scene.get(), "east", 0.8, 0.5, 0.06, 0.7);
  AddBox(scene.get(), "west", 0.2, 0.5, 0.06, 0.7);
  const std::vector<std::pair<std::string, ParameterValues>> runs = {
      {"potential_field", {{"random_walks", 100000}}},
      {"wavefront", {{"resolution", 0.001}, {"max_cells", 5000000}}}};
  for (const auto& [id, params] : runs) {
    auto planner = registry_->Create(id);
    planner->Setup(Problem(PointRobot(2), scene, Eigen::Vector2d(-0.5, -0.5), Eigen::Vector2d(0.5, 0.5), params));
    Termination termination;  // no budget: only Cancel() ends it
    std::thread canceller([termination] {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      termination.Cancel();
    });
    const PlannerResult r = planner->Solve(termination);
    canceller.join();
    EXPECT_EQ(r.status, PlanStatus::kCancelled) << id << ": " << r.message;
    EXPECT_TRUE(r.path.empty()) << id;
  }
}

TEST_F(FieldPlannerTest, BadParametersAreRejectedByName) {
  const auto message = [](const std::string& id, const ParameterValues& values) {
    auto planner = registry_->Create(id);
    try {
      planner->Setup(Problem(PointRobot(2), std::make_shared<Scene>(), Eigen::Vector2d(-0.5, -0.5),
                             Eigen::Vector2d(0.5, 0.5), values));
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message("potential_field", {{"step", 0}}),
            "planner.parameters['step'] = 0 must be within [0.0001, 1] (planner 'potential_field')");
  EXPECT_EQ(message("potential_field", {{"step", -0.1}}),
            "planner.parameters['step'] = -0.1 must be within [0.0001, 1] (planner 'potential_field')");
  EXPECT_EQ(message("potential_field", {{"random_walks", 2.5}}),
            "planner.parameters['random_walks'] = 2.5 must be an integer");
  EXPECT_EQ(message("potential_field", {{"influence_distance", 0}}),
            "planner.parameters['influence_distance'] = 0 must be within [0.0001, 10] (planner 'potential_field')");
  EXPECT_EQ(message("wavefront", {{"resolution", -1}}),
            "planner.parameters['resolution'] = -1 must be within [0, 10] (planner 'wavefront')");
  EXPECT_EQ(message("wavefront", {{"cells_per_coordinate", 1}}),
            "planner.parameters['cells_per_coordinate'] = 1 must be within [2, 100000] (planner 'wavefront')");
}

TEST_F(FieldPlannerTest, SpecsListTypedRangedParameters) {
  const PlannerSpec& pf = registry_->Spec("potential_field");
  EXPECT_FALSE(pf.optimizing);
  for (const char* name : {"attractive_gain", "attractive_radius", "repulsive_gain", "influence_distance", "step",
                           "random_walks", "walk_length", "max_steps"}) {
    const ParameterSpec* spec = pf.Find(name);
    ASSERT_NE(spec, nullptr) << name;
    EXPECT_LE(spec->min, spec->default_value) << name;
    EXPECT_LE(spec->default_value, spec->max) << name;
    EXPECT_NE(spec->description.find('['), std::string::npos) << name << ": unit in the description";
  }
  EXPECT_EQ(pf.Find("random_walks")->type, ParameterType::kInt);
  const PlannerSpec& wf = registry_->Spec("wavefront");
  EXPECT_FALSE(wf.optimizing);
  for (const char* name : {"resolution", "cells_per_coordinate", "max_cells"}) EXPECT_NE(wf.Find(name), nullptr) << name;
  EXPECT_FALSE(pf.Supports(RobotKind::kDubinsCar));
  EXPECT_TRUE(wf.Supports(RobotKind::kPlanar));
}

}  // namespace
}  // namespace chasles
