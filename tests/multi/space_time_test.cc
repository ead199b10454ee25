// BuildRoadmap and SearchSpaceTime on a disc robot in the plane: the roadmap's validity and
// determinism, waiting for and detouring around moving obstacles (synthetic ConflictFree
// functions), the goal held clear, merged moves, and named errors. Every found trajectory is
// re-checked here at 1 ms and 0.005 rad against the same moving obstacles and the static scene.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "chasles/multi/space_time.h"
#include "chasles/optimizers/verification.h"
#include "chasles/robot/error.h"
#include "disc_robots.h"

namespace chasles {
namespace {

using ::testing::HasSubstr;

KinematicLimits Limits() {
  KinematicLimits limits;
  limits.max_velocity = Eigen::Vector2d(1.0, 1.0);
  limits.max_acceleration = Eigen::Vector2d(2.0, 2.0);
  return limits;
}

std::shared_ptr<const CollisionChecker> Floor() {
  auto scene = std::make_shared<Scene>();
  test::AddWall(scene.get(), "pillar", 0.0, 1.2, 0.6, 0.6);
  return std::make_shared<CollisionChecker>(test::DiscRobot(), scene);
}

/// A disc obstacle of radius 0.3 m moving along `from` → `to` during [t0, t1], standing at its
/// ends outside; clear when the robot's centre is more than 0.6 m from it.
ConflictFree MovingDisc(Eigen::Vector2d from, Eigen::Vector2d to, double t0, double t1) {
  return [=](const Eigen::VectorXd& q, double t) {
    const double s = std::clamp((t - t0) / (t1 - t0), 0.0, 1.0);
    const Eigen::Vector2d at = from + s * (to - from);
    return (q.head<2>() - at).norm() > 0.6;
  };
}

int VertexOf(const Roadmap& roadmap, const Eigen::VectorXd& q) {
  for (int v = 0; v < static_cast<int>(roadmap.vertices.size()); ++v) {
    if ((roadmap.vertices[v] - q).cwiseAbs().maxCoeff() <= 1e-12) return v;
  }
  return -1;
}

/// The result starts and ends where it should, meets the limits and the scene (VerifyTrajectory)
/// and never meets the moving obstacle, at 1 ms and 0.005 rad.
void ExpectClear(const SpaceTimeResult& result, const CollisionChecker& checker, const Eigen::VectorXd& start,
                 const Eigen::VectorXd& goal, const ConflictFree& conflict_free, double hold_until) {
  ASSERT_TRUE(result.found) << result.message;
  const VerificationReport report = VerifyTrajectory(result.trajectory, start, goal, checker, Limits());
  EXPECT_TRUE(report.ok) << report.reason;
  const double end = std::max(result.trajectory.duration(), hold_until) + 1.0;
  for (double t = 0.0; t <= end; t += 1e-3) {
    const Eigen::VectorXd q = result.trajectory.Evaluate(t).q;
    ASSERT_TRUE(conflict_free(q, t)) << "meets the moving obstacle at t = " << t;
  }
  EXPECT_NEAR(result.arrival, result.trajectory.duration(), 1e-12);
  EXPECT_GE(result.wait_time + 1e-12, result.start_delay);
}

TEST(RoadmapTest, EdgesAreValidSeedPathsIncludedAndDeterministic) {
  const auto checker = Floor();
  const JointPath seed{Eigen::Vector2d(-3, 0), Eigen::Vector2d(3, 0)};
  RoadmapOptions options;
  options.prm_vertices = 60;
  options.seed = 5;
  const Roadmap a = BuildRoadmap(*checker, {seed}, options, Termination());
  const Roadmap b = BuildRoadmap(*checker, {seed}, options, Termination());
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  for (std::size_t v = 0; v < a.vertices.size(); ++v) {
    EXPECT_EQ(a.vertices[v], b.vertices[v]);
    EXPECT_EQ(a.neighbors[v], b.neighbors[v]);
  }
  EXPECT_EQ(a.lines, b.lines);
  EXPECT_EQ(VertexOf(a, seed.front()), 0);
  EXPECT_GE(VertexOf(a, seed.back()), 0);
  // 2 seed vertices + 60 PRM milestones, plus stations.
  EXPECT_GE(a.vertices.size(), 62u);
  int edges = 0;
  for (int v = 0; v < static_cast<int>(a.vertices.size()); ++v) {
    EXPECT_TRUE(checker->IsValid(a.vertices[v]));
    for (int w : a.neighbors[v]) {
      ++edges;
      EXPECT_NE(std::find(a.neighbors[w].begin(), a.neighbors[w].end(), v), a.neighbors[w].end());
      EXPECT_LE((a.vertices[w] - a.vertices[v]).cwiseAbs().maxCoeff(), options.station_spacing + 1e-12);
      EXPECT_TRUE(checker->IsMotionValid(a.vertices[v], a.vertices[w], 0.005));
    }
  }
  EXPECT_GT(edges, 0);
  // Without the PRM: just the path, cut into stations of at most 0.25.
  options.prm_vertices = 0;
  const Roadmap path = BuildRoadmap(*checker, {seed}, options, Termination());
  EXPECT_EQ(path.vertices.size(), 25u);  // 6 m in 24 stations
}

TEST(SpaceTimeTest, NoMovingObstaclesGivesTheFastestRouteWithoutWaiting) {
  const auto checker = Floor();
  const JointPath seed{Eigen::Vector2d(-3, 0), Eigen::Vector2d(3, 0)};
  RoadmapOptions roadmap_options;
  roadmap_options.prm_vertices = 0;
  const Roadmap roadmap = BuildRoadmap(*checker, {seed}, roadmap_options, Termination());
  const ConflictFree free = [](const Eigen::VectorXd&, double) { return true; };
  const SpaceTimeResult result =
      SearchSpaceTime(roadmap, 0, VertexOf(roadmap, seed.back()), Limits(), free, SpaceTimeOptions(), Termination());
  ExpectClear(result, *checker, seed.front(), seed.back(), free, 0.0);
  EXPECT_EQ(result.wait_time, 0.0);
  // The merged run is the time-optimal straight line: 6 m at 1 m/s, 2 m/s² → 6.5 s.
  EXPECT_NEAR(result.arrival, 6.5, 1e-9);
}

TEST(SpaceTimeTest, WaitsForACrossingObstacleAlongAFixedPath) {
  const auto checker = Floor();
  const JointPath seed{Eigen::Vector2d(-3, 0), Eigen::Vector2d(3, 0)};
  RoadmapOptions roadmap_options;
  roadmap_options.prm_vertices = 0;
  const Roadmap roadmap = BuildRoadmap(*checker, {seed}, roadmap_options, Termination());
  // Crosses the path at x = 0 around t = 3.25 s, when the robot would be there.
  const ConflictFree crossing = MovingDisc({0, -3}, {0, 3}, 0.25, 6.25);
  const SpaceTimeResult result =
      SearchSpaceTime(roadmap, 0, VertexOf(roadmap, seed.back()), Limits(), crossing, SpaceTimeOptions(), Termination());
  ExpectClear(result, *checker, seed.front(), seed.back(), crossing, 0.0);
  EXPECT_GT(result.arrival, 6.5);
  EXPECT_GT(result.wait_time, 0.0);
  EXPECT_GT(result.conflict_checks, 0u);
  // Deterministic: the same search gives the same schedule.
  const SpaceTimeResult again =
      SearchSpaceTime(roadmap, 0, VertexOf(roadmap, seed.back()), Limits(), crossing, SpaceTimeOptions(), Termination());
  ASSERT_TRUE(again.found);
  EXPECT_EQ(again.arrival, result.arrival);
  EXPECT_EQ(again.wait_time, result.wait_time);
  EXPECT_EQ(again.expansions, result.expansions);
  EXPECT_EQ(again.conflict_checks, result.conflict_checks);
  ASSERT_EQ(again.path.size(), result.path.size());
  for (std::size_t k = 0; k < result.path.size(); ++k) EXPECT_EQ(again.path[k], result.path[k]);
}

TEST(SpaceTimeTest, DetoursOnThePrmWhenThePathIsBlockedForLong) {
  const auto checker = Floor();
  const JointPath seed{Eigen::Vector2d(-3, 0), Eigen::Vector2d(3, 0)};
  RoadmapOptions roadmap_options;
  roadmap_options.prm_vertices = 150;
  roadmap_options.seed = 3;
  const Roadmap roadmap = BuildRoadmap(*checker, {seed}, roadmap_options, Termination());
  // An obstacle parked on the path at (1, 0) until t = 40 s.
  const ConflictFree parked = MovingDisc({1, 0}, {1, -4}, 40.0, 41.0);
  SpaceTimeOptions options;
  options.horizon = 30.0;  // waiting it out is not allowed
  const SpaceTimeResult result =
      SearchSpaceTime(roadmap, 0, VertexOf(roadmap, seed.back()), Limits(), parked, options, Termination());
  ExpectClear(result, *checker, seed.front(), seed.back(), parked, 0.0);
  EXPECT_LT(result.arrival, 30.0);
  bool left_the_line = false;
  for (const Eigen::VectorXd& q : result.path) left_the_line = left_the_line || std::abs(q[1]) > 0.1;
  EXPECT_TRUE(left_the_line);
  // Along the path alone it cannot get there within the horizon.
  roadmap_options.prm_vertices = 0;
  const Roadmap line = BuildRoadmap(*checker, {seed}, roadmap_options, Termination());
  const SpaceTimeResult stuck =
      SearchSpaceTime(line, 0, VertexOf(line, seed.back()), Limits(), parked, options, Termination());
  EXPECT_FALSE(stuck.found);
  EXPECT_THAT(stuck.message, HasSubstr("horizon"));
}

TEST(SpaceTimeTest, TheGoalMustStayClearUntilHoldUntil) {
  const auto checker = Floor();
  const JointPath seed{Eigen::Vector2d(-3, 0), Eigen::Vector2d(3, 0)};
  RoadmapOptions roadmap_options;
  roadmap_options.prm_vertices = 0;
  const Roadmap roadmap = BuildRoadmap(*checker, {seed}, roadmap_options, Termination());
  // Something arrives at the goal at t = 20 s and stays.
  const ConflictFree takes_goal = MovingDisc({3, -4}, {3, 0}, 16.0, 20.0);
  SpaceTimeOptions options;
  options.hold_until = 25.0;
  options.horizon = 40.0;
  const SpaceTimeResult result =
      SearchSpaceTime(roadmap, 0, VertexOf(roadmap, seed.back()), Limits(), takes_goal, options, Termination());
  EXPECT_FALSE(result.found);
  EXPECT_THAT(result.message, HasSubstr("goal is occupied by a moving obstacle at hold_until = 25 s"));
  EXPECT_EQ(result.expansions, 0);  // known before searching
  // Occupied between the horizon and hold_until: no arrival by the horizon can stay there.
  options.hold_until = 50.0;
  const SpaceTimeResult beyond =
      SearchSpaceTime(roadmap, 0, VertexOf(roadmap, seed.back()), Limits(), takes_goal, options, Termination());
  EXPECT_FALSE(beyond.found);
  EXPECT_THAT(beyond.message, HasSubstr("after the horizon 40 s and before hold_until = 50 s"));
  // Occupied at hold_until but free again later: the robot arrives after the obstacle leaves.
  options.hold_until = 25.0;
  const ConflictFree passes_goal = [](const Eigen::VectorXd& q, double t) {
    return t < 20.0 || t > 27.0 || (q.head<2>() - Eigen::Vector2d(3, 0)).norm() > 0.6;
  };
  const SpaceTimeResult after =
      SearchSpaceTime(roadmap, 0, VertexOf(roadmap, seed.back()), Limits(), passes_goal, options, Termination());
  ExpectClear(after, *checker, seed.front(), seed.back(), passes_goal, 0.0);
  EXPECT_GT(after.arrival, 27.0);
  // If the others are done by then, the goal is reachable (the obstacle has not come yet).
  options.hold_until = 10.0;
  const ConflictFree later = MovingDisc({3, -4}, {3, -1.0}, 16.0, 20.0);
  const SpaceTimeResult ok =
      SearchSpaceTime(roadmap, 0, VertexOf(roadmap, seed.back()), Limits(), later, options, Termination());
  ExpectClear(ok, *checker, seed.front(), seed.back(), later, options.hold_until);
}

TEST(SpaceTimeTest, MergingMovesNeverArrivesLater) {
  const auto checker = Floor();
  const JointPath seed{Eigen::Vector2d(-3, 0), Eigen::Vector2d(3, 0)};
  RoadmapOptions roadmap_options;
  roadmap_options.prm_vertices = 0;
  const Roadmap roadmap = BuildRoadmap(*checker, {seed}, roadmap_options, Termination());
  const ConflictFree crossing = MovingDisc({0, -3}, {0, 3}, 0.25, 6.25);
  SpaceTimeOptions options;
  const int goal = VertexOf(roadmap, seed.back());
  const SpaceTimeResult merged = SearchSpaceTime(roadmap, 0, goal, Limits(), crossing, options, Termination());
  options.merge_moves = false;
  const SpaceTimeResult stops = SearchSpaceTime(roadmap, 0, goal, Limits(), crossing, options, Termination());
  ExpectClear(merged, *checker, seed.front(), seed.back(), crossing, 0.0);
  ExpectClear(stops, *checker, seed.front(), seed.back(), crossing, 0.0);
  EXPECT_LE(merged.arrival, stops.arrival + 1e-9);
  EXPECT_LE(merged.trajectory.pieces().size(), stops.trajectory.pieces().size());
}

TEST(SpaceTimeTest, HandBuiltRoadmapMovesEdgeByEdgeAndMergingRunsThrough) {
  const auto checker = Floor();
  Roadmap roadmap;
  for (double x : {-3.0, -1.0, 1.0, 3.0}) roadmap.AddVertex(Eigen::Vector2d(x, 0.0));
  for (int v = 0; v + 1 < 4; ++v) roadmap.AddEdge(v, v + 1);
  roadmap.AddEdge(1, 0);  // a duplicate, either way round, is ignored
  roadmap.AddEdge(2, 2);  // so is a loop
  EXPECT_EQ(roadmap.neighbors[0], std::vector<int>({1}));
  EXPECT_EQ(roadmap.neighbors[1], std::vector<int>({0, 2}));
  EXPECT_EQ(roadmap.neighbors[2], std::vector<int>({1, 3}));
  EXPECT_THROW(roadmap.AddEdge(0, 4), Error);
  const ConflictFree free = [](const Eigen::VectorXd&, double) { return true; };
  SpaceTimeOptions options;
  options.merge_moves = false;
  const SpaceTimeResult stops = SearchSpaceTime(roadmap, 0, 3, Limits(), free, options, Termination());
  ExpectClear(stops, *checker, Eigen::Vector2d(-3, 0), Eigen::Vector2d(3, 0), free, 0.0);
  EXPECT_NEAR(stops.arrival, 7.5, 1e-9);  // three 2 m rest-to-rest moves of 2.5 s
  EXPECT_EQ(stops.path.size(), 4u);
  options.merge_moves = true;
  const SpaceTimeResult merged = SearchSpaceTime(roadmap, 0, 3, Limits(), free, options, Termination());
  ExpectClear(merged, *checker, Eigen::Vector2d(-3, 0), Eigen::Vector2d(3, 0), free, 0.0);
  EXPECT_NEAR(merged.arrival, 6.5, 1e-9);  // through the collinear stations without stopping
  EXPECT_EQ(merged.path.size(), 4u);
  // With an obstacle crossing at x = 0 the merged schedule still waits and stays clear.
  const ConflictFree crossing = MovingDisc({0, -3}, {0, 3}, 0.25, 6.25);
  options.merge_moves = false;
  const SpaceTimeResult slow = SearchSpaceTime(roadmap, 0, 3, Limits(), crossing, options, Termination());
  options.merge_moves = true;
  const SpaceTimeResult fast = SearchSpaceTime(roadmap, 0, 3, Limits(), crossing, options, Termination());
  ExpectClear(slow, *checker, Eigen::Vector2d(-3, 0), Eigen::Vector2d(3, 0), crossing, 0.0);
  ExpectClear(fast, *checker, Eigen::Vector2d(-3, 0), Eigen::Vector2d(3, 0), crossing, 0.0);
  EXPECT_LE(fast.arrival, slow.arrival + 1e-9);
}

TEST(SpaceTimeTest, StopsWithTheTerminationAndNamesBadInput) {
  const auto checker = Floor();
  const JointPath seed{Eigen::Vector2d(-3, 0), Eigen::Vector2d(3, 0)};
  RoadmapOptions roadmap_options;
  roadmap_options.prm_vertices = 0;
  const Roadmap roadmap = BuildRoadmap(*checker, {seed}, roadmap_options, Termination());
  const ConflictFree free = [](const Eigen::VectorXd&, double) { return true; };
  const SpaceTimeResult stopped =
      SearchSpaceTime(roadmap, 0, 1, Limits(), free, SpaceTimeOptions(), Termination::AlreadyStopped());
  EXPECT_FALSE(stopped.found);
  EXPECT_THAT(stopped.message, HasSubstr("stopped"));
  const auto expect_invalid = [&](int start, int goal, SpaceTimeOptions options, const std::string& text) {
    try {
      SearchSpaceTime(roadmap, start, goal, Limits(), free, options, Termination());
      ADD_FAILURE() << "no error; expected " << text;
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
      EXPECT_THAT(e.what(), HasSubstr(text));
    }
  };
  expect_invalid(-1, 1, SpaceTimeOptions(), "start_vertex = -1");
  expect_invalid(0, 999, SpaceTimeOptions(), "goal_vertex = 999");
  SpaceTimeOptions bad;
  bad.wait_step = 0.0;
  expect_invalid(0, 1, bad, "wait_step = 0 must be finite and > 0");
  KinematicLimits three;
  three.max_velocity = Eigen::Vector3d(1, 1, 1);
  three.max_acceleration = Eigen::Vector3d(1, 1, 1);
  EXPECT_THROW(SearchSpaceTime(roadmap, 0, 1, three, free, SpaceTimeOptions(), Termination()), Error);
  bad = SpaceTimeOptions();
  bad.time_step = -0.01;
  expect_invalid(0, 1, bad, "time_step = -0.01 must be finite and > 0");
  bad = SpaceTimeOptions();
  bad.max_joint_step = 0.0;
  expect_invalid(0, 1, bad, "max_joint_step = 0 must be finite and > 0");
  bad = SpaceTimeOptions();
  bad.hold_until = -1.0;
  expect_invalid(0, 1, bad, "hold_until = -1 must be finite and >= 0");
  roadmap_options.station_spacing = 0.0;
  EXPECT_THROW(BuildRoadmap(*checker, {seed}, roadmap_options, Termination()), Error);
  roadmap_options.station_spacing = 0.25;
  EXPECT_THROW(BuildRoadmap(*checker, {}, roadmap_options, Termination()), Error);
  EXPECT_THROW(BuildRoadmap(*checker, {{Eigen::Vector3d(0, 0, 0)}}, roadmap_options, Termination()), Error);
}

}  // namespace
}  // namespace chasles
