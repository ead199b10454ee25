// Coordinate's FLEET method on generated maps: 120 planar bases on a 32 x 32 map with 20 % of
// its 1 m cells blocked (boxes), as the MAPF benchmarks pose them. Every answer is re-checked
// here, independently of the planner: each trajectory's pieces are walked at 1 ms, and between
// samples a robot moves at most its speed bound times half a millisecond, so no pair of discs
// and no disc and box come closer than allowed anywhere — not only at the samples.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <unordered_map>

#include "chasles/multi/coordinator.h"
#include "chasles/multi/grid_mapf.h"
#include "chasles/robot/error.h"
#include "chasles/robot/mobile.h"

namespace chasles {
namespace {

using ::testing::HasSubstr;

constexpr double kRadius = 0.4;  // disc robots 0.8 m across on 1 m cells

PlannerRegistry& Registry() {
  static PlannerRegistry* registry = [] {
    auto* r = new PlannerRegistry();
    RegisterDefaultPlanners(r);
    return r;
  }();
  return *registry;
}

std::shared_ptr<const RobotModel> DiscBase(double speed) {
  MobileDescription mobile;
  mobile.name = "disc_base";
  mobile.kind = RobotKind::kPlanar;
  mobile.workspace_min = Eigen::Vector3d(0, 0, 0);
  mobile.workspace_max = Eigen::Vector3d(32, 32, 0);
  mobile.linear_velocity = speed;
  mobile.angular_velocity = 1.0;
  mobile.body.collision.push_back(Shape::Sphere(kRadius, Eigen::Isometry3d(Eigen::Translation3d(0, 0, 0.4))));
  return RobotFromMobile(mobile);
}

/// Blocked cell (x, y) is the box [x, x+1] × [y, y+1] × [0, 1].
std::shared_ptr<Scene> SceneOf(const GridMap& map) {
  auto scene = std::make_shared<Scene>();
  for (int y = 0; y < map.height; ++y) {
    for (int x = 0; x < map.width; ++x) {
      if (!map.blocked[static_cast<std::size_t>(y * map.width + x)]) continue;
      scene->AddObject(SceneObject{"cell_" + std::to_string(x) + "_" + std::to_string(y),
                                   Shape::Box(Eigen::Vector3d(1, 1, 1), Eigen::Isometry3d(Eigen::Translation3d(x + 0.5, y + 0.5, 0.5)))});
    }
  }
  return scene;
}

/// The query: robots at cell centres, headings 0 at the start and seeded at the goal; two speeds.
CoordinationQuery FleetQuery(const GridMap& map, int robots, std::uint64_t seed) {
  std::vector<GridCell> starts, goals;
  RandomScenario(map, robots, seed, &starts, &goals);
  CoordinationQuery query;
  query.scene = SceneOf(map);
  query.fleet_resolution = 1.0;
  query.time_budget = 30.0;
  query.seed = seed;
  query.knots_replace_samples = true;
  const auto fast = DiscBase(1.0), slow = DiscBase(0.6);
  for (int k = 0; k < robots; ++k) {
    TeamRobotSpec spec;
    spec.placement.name = "r" + std::to_string(k);
    spec.placement.model = k % 3 == 0 ? slow : fast;
    const GridCell s = starts[static_cast<std::size_t>(k)], g = goals[static_cast<std::size_t>(k)];
    spec.start = Eigen::Vector3d(s % map.width + 0.5, s / map.width + 0.5, 0.0);
    spec.goal = Eigen::Vector3d(g % map.width + 0.5, g / map.width + 0.5, (k % 4) * 0.5);
    query.robots.push_back(spec);
  }
  return query;
}

/// Distance in the plane from p to the box [x, x+1] × [y, y+1].
double ToCell(const Eigen::Vector2d& p, int x, int y) {
  const double dx = std::max({x - p.x(), 0.0, p.x() - (x + 1.0)});
  const double dy = std::max({y - p.y(), 0.0, p.y() - (y + 1.0)});
  return std::hypot(dx, dy);
}

/// The independent check. Walks each robot's pieces (not TimedTrajectory::Evaluate) at 1 ms.
/// Between two samples dt apart a robot is within v·dt/2 of one of them (v: its planar speed
/// bound), so a sampled clearance above `allowed + v_i·dt/2 + v_j·dt/2` holds for all times.
void ExpectNoContactAnywhere(const CoordinationQuery& query, const CoordinationOutcome& outcome, const GridMap& map,
                             double padding) {
  ASSERT_EQ(outcome.code, CoordinationCode::kSuccess) << outcome.message;
  const std::size_t n = query.robots.size();
  ASSERT_EQ(outcome.robots.size(), n);
  const double dt = 1e-3;
  std::vector<double> slack(n);  // v·dt/2 per robot
  std::vector<std::size_t> cursor(n, 0);
  for (std::size_t k = 0; k < n; ++k) {
    const double v = query.robots[k].placement.model->velocity_limits()[0];
    slack[k] = std::sqrt(2.0) * v * dt / 2.0;  // x and y each at most v
    const TimedTrajectory& trajectory = outcome.robots[k].trajectory;
    // Ends: the robot starts at its start and rests at its goal.
    EXPECT_LT((trajectory.pieces().front().coefficients.col(0) - query.robots[k].start).norm(), 1e-9);
    EXPECT_LT((trajectory.Evaluate(trajectory.duration()).q - query.robots[k].goal).norm(), 1e-9);
  }
  const double makespan = outcome.makespan;
  std::vector<Eigen::Vector2d> at(n);
  std::unordered_map<std::int64_t, std::vector<std::size_t>> grid;
  double nearest_pair = std::numeric_limits<double>::infinity(), nearest_box = nearest_pair;
  const auto key = [](int x, int y) {
    return static_cast<std::int64_t>((static_cast<std::uint64_t>(static_cast<std::uint32_t>(x)) << 32) |
                                     static_cast<std::uint32_t>(y));
  };
  const int samples = static_cast<int>(std::ceil(makespan / dt));
  for (int s = 0; s <= samples; ++s) {
    const double t = std::min(makespan, s * dt);
    grid.clear();
    for (std::size_t k = 0; k < n; ++k) {
      const auto& pieces = outcome.robots[k].trajectory.pieces();
      while (cursor[k] + 1 < pieces.size() && pieces[cursor[k] + 1].t0 <= t) ++cursor[k];
      const TimedTrajectory::Piece& piece = pieces[cursor[k]];
      const double tau = std::min(std::max(t - piece.t0, 0.0), piece.duration);
      Eigen::Vector2d p = Eigen::Vector2d::Zero();
      for (int c = static_cast<int>(piece.coefficients.cols()) - 1; c >= 0; --c) p = p * tau + piece.coefficients.col(c).head<2>();
      at[k] = p;
      grid[key(static_cast<int>(std::floor(p.x())), static_cast<int>(std::floor(p.y())))].push_back(k);
      // Obstacles: the blocked cells around it.
      const int cx = static_cast<int>(std::floor(p.x())), cy = static_cast<int>(std::floor(p.y()));
      for (int y = cy - 1; y <= cy + 1; ++y) {
        for (int x = cx - 1; x <= cx + 1; ++x) {
          if (x < 0 || y < 0 || x >= map.width || y >= map.height) continue;  // no boxes off the map
          if (map.blocked[static_cast<std::size_t>(y * map.width + x)] == 0) continue;
          const double clearance = ToCell(p, x, y) - kRadius - slack[k];
          nearest_box = std::min(nearest_box, clearance);
          ASSERT_GT(clearance, 0.0) << "robot " << k << " reaches the box of cell (" << x << ", " << y << ") at t = " << t;
        }
      }
    }
    for (std::size_t k = 0; k < n; ++k) {
      const int cx = static_cast<int>(std::floor(at[k].x())), cy = static_cast<int>(std::floor(at[k].y()));
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const auto it = grid.find(key(cx + dx, cy + dy));
          if (it == grid.end()) continue;
          for (std::size_t j : it->second) {
            if (j <= k) continue;
            const double gap = (at[k] - at[j]).norm() - 2.0 * kRadius - padding - slack[k] - slack[j];
            nearest_pair = std::min(nearest_pair, gap);
            ASSERT_GT(gap, 0.0) << "robots " << k << " and " << j << " at t = " << t;
          }
        }
      }
    }
  }
  std::printf("%zu robots, makespan %.2f s: nearest pair %.4f m and box %.4f m beyond what is allowed (sampled "
              "bound)\n", n, makespan, nearest_pair, nearest_box);
}

TEST(FleetCoordinate, HundredsOfBasesOnARandomMapNeverComeCloserThanAllowed) {
  const GridMap map = RandomGridMap(32, 32, 0.2, 7);
  CoordinationQuery query = FleetQuery(map, 120, 7);
  query.robot_padding = 0.1;
  const CoordinationOutcome outcome = Coordinate(query, Registry(), Termination());
  ASSERT_EQ(outcome.method, CoordinationMethod::kFleet) << outcome.message;
  ExpectNoContactAnywhere(query, outcome, map, query.robot_padding);
  ASSERT_TRUE(outcome.fleet.has_value());
  EXPECT_EQ(outcome.fleet->width, 32);
  EXPECT_GE(outcome.fleet->sum_of_costs, outcome.fleet->sum_of_lower_bounds);
  EXPECT_FALSE(outcome.fleet->dependencies.empty());
  EXPECT_GE(outcome.verification.min_robot_distance, query.robot_padding);
  // No samples were asked for; the trajectories are the answer.
  for (const RobotPlan& plan : outcome.robots) EXPECT_TRUE(plan.samples.empty());
}

TEST(FleetCoordinate, DependenciesPointAtNodesOfBothRobotsPaths) {
  const GridMap map = RandomGridMap(16, 16, 0.2, 3);
  const CoordinationQuery query = FleetQuery(map, 30, 3);
  const CoordinationOutcome outcome = Coordinate(query, Registry(), Termination());
  ExpectNoContactAnywhere(query, outcome, map, 0.0);
  ASSERT_TRUE(outcome.fleet.has_value());
  for (const FleetWait& wait : outcome.fleet->dependencies) {
    const JointPath& mine = outcome.robots[static_cast<std::size_t>(wait.robot)].path;
    const JointPath& theirs = outcome.robots[static_cast<std::size_t>(wait.waits_for)].path;
    ASSERT_LT(static_cast<std::size_t>(wait.leave_index + 1), mine.size());
    ASSERT_LT(static_cast<std::size_t>(wait.arrival_index), theirs.size());
    // The node it enters next is the node the other robot has left when it reaches arrival_index.
    EXPECT_LT((mine[wait.leave_index + 1].head<2>() - Eigen::Vector2d(wait.x, wait.y)).norm(), 1e-9);
    EXPECT_LT((theirs[wait.arrival_index - 1].head<2>() - Eigen::Vector2d(wait.x, wait.y)).norm(), 1e-9);
  }
}

TEST(FleetCoordinate, ArmsAndOffLatticeBasesAreNotFleets) {
  const GridMap map = RandomGridMap(16, 16, 0.2, 3);
  CoordinationQuery query = FleetQuery(map, 4, 3);
  query.robots[2].start.x() += 0.3;  // between nodes
  query.method = CoordinationMethod::kFleet;
  try {
    Coordinate(query, Registry(), Termination());
    ADD_FAILURE() << "an off-lattice start was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_THAT(e.what(), HasSubstr("robots[2].start"));
    EXPECT_THAT(e.what(), HasSubstr("is not on a lattice node"));
  }
  query.fleet_resolution = 0.5;  // below 2 × 0.4 m
  query.robots[2].start.x() -= 0.3;
  try {
    Coordinate(query, Registry(), Termination());
    ADD_FAILURE() << "a lattice finer than the footprints was accepted";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("fleet_resolution = 0.5 m is below the smallest spacing that keeps these robots apart, 0.8 m"));
  }
}

}  // namespace
}  // namespace chasles
