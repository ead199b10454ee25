// The coordination examples (examples/requests/coordinate_*.json, written by
// examples/requests/make_coordination.py) pose the problems they claim to: every start and goal is
// collision-free against the scene and the robot itself, the starts (and the goals, but for the
// overlapping-goals example) keep the robots apart, each robot alone can move on its straight
// joint-space line, and the naive plan — every robot on that line at once, at the same normalised
// progress — makes robots collide, so the examples need coordination. In the overlapping-goals
// example the goals themselves collide (the server must answer GOALS_IN_CONFLICT).

#include <algorithm>
#include <cmath>
#include <fstream>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <google/protobuf/util/json_util.h>
#include <gtest/gtest.h>

#include "chasles/collision/collision_checker.h"
#include "chasles/multi/team.h"
#include "chasles/server/convert.h"
#include "chasles/v1/chasles.pb.h"

namespace chasles {
namespace {

/// Largest joint step between the checked states of the naive plan [rad] or [m] (the proto's
/// default collision_resolution).
constexpr double kJointStep = 0.005;

/// An example request with its scene, robots (placed by their base poses), starts and goals.
struct Example {
  v1::CoordinateRequest request;
  std::shared_ptr<const Scene> scene;
  std::vector<PlacedRobot> robots;
  std::vector<Eigen::VectorXd> starts;
  std::vector<Eigen::VectorXd> goals;
};

Eigen::VectorXd Positions(const google::protobuf::RepeatedField<double>& values) {
  return Eigen::Map<const Eigen::VectorXd>(values.data(), values.size());
}

/// Loads examples/requests/<file>; joint counts are checked here, limits by the checkers' IsValid.
Example LoadExample(const std::string& file) {
  const std::string path = std::string(CHASLES_SOURCE_DIR) + "/examples/requests/" + file;
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << path;
  std::stringstream text;
  text << in.rdbuf();
  Example example;
  const auto status = google::protobuf::util::JsonStringToMessage(text.str(), &example.request);
  EXPECT_TRUE(status.ok()) << path << ": " << status.ToString();
  EXPECT_TRUE(example.request.has_scene()) << path;
  example.scene = SceneFromProto(example.request.scene(), "scene");
  for (int i = 0; i < example.request.robots_size(); ++i) {
    const v1::TeamRobot& team_robot = example.request.robots(i);
    const std::string field = "robots[" + std::to_string(i) + "]";
    EXPECT_TRUE(team_robot.has_robot()) << field << " is not inline";
    EXPECT_TRUE(team_robot.has_goal()) << field << " has no joint goal";
    PlacedRobot placed;
    placed.name = team_robot.name();
    placed.model = RobotFromProto(team_robot.robot(), field + ".robot");
    placed.base_pose = PoseFromProto(team_robot.base_pose(), field + ".base_pose");
    example.starts.push_back(Positions(team_robot.start().positions()));
    example.goals.push_back(Positions(team_robot.goal().positions()));
    EXPECT_EQ(example.starts.back().size(), placed.model->num_dofs()) << field << ".start";
    EXPECT_EQ(example.goals.back().size(), placed.model->num_dofs()) << field << ".goal";
    example.robots.push_back(std::move(placed));
  }
  return example;
}

Eigen::VectorXd Concatenate(const std::vector<Eigen::VectorXd>& parts) {
  Eigen::Index size = 0;
  for (const Eigen::VectorXd& part : parts) size += part.size();
  Eigen::VectorXd all(size);
  Eigen::Index offset = 0;
  for (const Eigen::VectorXd& part : parts) {
    all.segment(offset, part.size()) = part;
    offset += part.size();
  }
  return all;
}

std::string Describe(const CollisionResult& contact) {
  return contact.in_collision ? contact.link_a + " touches " + contact.other : "free";
}

/// The robot name of a composite link "<robot>/<link>".
std::string RobotOf(const std::string& link) { return link.substr(0, link.find('/')); }

/// A checker of robot against robot only: the team without each robot's self-collisions, in an
/// empty scene.
std::unique_ptr<CollisionChecker> RobotPairChecker(const Example& example) {
  CompositionOptions options;
  options.self_collisions = false;
  return std::make_unique<CollisionChecker>(ComposeRobots(example.robots, options), std::make_shared<const Scene>());
}

/// The request's own settings: distinct names, a seed, the 30 s budget.
void ExpectRequestSettings(const Example& example) {
  std::set<std::string> names;
  for (const v1::TeamRobot& robot : example.request.robots()) {
    EXPECT_FALSE(robot.name().empty());
    EXPECT_TRUE(names.insert(robot.name()).second) << "duplicate robot name " << robot.name();
  }
  EXPECT_NE(example.request.seed(), 0u);
  EXPECT_EQ(example.request.time_budget(), 30.0);
  EXPECT_FALSE(example.request.request_id().empty());
}

/// Each robot alone, placed at its base pose in the scene: start and goal valid (limits, scene,
/// itself) and, with `straight_line`, its straight joint-space line from start to goal valid.
void ExpectEachRobotAloneFree(const Example& example, bool straight_line) {
  for (std::size_t i = 0; i < example.robots.size(); ++i) {
    SCOPED_TRACE("robot " + example.robots[i].name);
    const CollisionChecker alone(ComposeRobots({example.robots[i]}), example.scene);
    EXPECT_TRUE(alone.IsValid(example.starts[i])) << "start: " << Describe(alone.Check(example.starts[i]));
    EXPECT_TRUE(alone.IsValid(example.goals[i])) << "goal: " << Describe(alone.Check(example.goals[i]));
    if (straight_line) {
      EXPECT_TRUE(alone.IsMotionValid(example.starts[i], example.goals[i], kJointStep))
          << "its straight line from start to goal collides with the scene or itself";
    }
  }
}

/// The first state of the naive plan (all robots on their straight lines, same progress s) where
/// two robots touch: s in [0, 1], or -1 when none does. `contact` gets the contact.
double FirstNaiveConflict(const Example& example, const CollisionChecker& pairs, CollisionResult* contact) {
  const Eigen::VectorXd start = Concatenate(example.starts);
  const Eigen::VectorXd goal = Concatenate(example.goals);
  const int steps = std::max(1, static_cast<int>(std::ceil((goal - start).cwiseAbs().maxCoeff() / kJointStep)));
  for (int k = 0; k <= steps; ++k) {
    const double s = static_cast<double>(k) / steps;
    const CollisionResult result = pairs.Check(start + s * (goal - start));
    if (result.in_collision) {
      *contact = result;
      return s;
    }
  }
  return -1.0;
}

/// Examples a–c: starts and goals apart, each robot alone free, the naive plan colliding robot
/// against robot (strictly between start and goal).
void ExpectNeedsCoordination(const std::string& file, std::size_t robots) {
  SCOPED_TRACE(file);
  const Example example = LoadExample(file);
  ASSERT_EQ(example.robots.size(), robots);
  ExpectRequestSettings(example);
  ExpectEachRobotAloneFree(example, /*straight_line=*/true);

  const auto pairs = RobotPairChecker(example);
  const Eigen::VectorXd starts = Concatenate(example.starts);
  const Eigen::VectorXd goals = Concatenate(example.goals);
  EXPECT_TRUE(pairs->IsValid(starts)) << "starts: " << Describe(pairs->Check(starts));
  EXPECT_TRUE(pairs->IsValid(goals)) << "goals: " << Describe(pairs->Check(goals));

  CollisionResult contact;
  const double s = FirstNaiveConflict(example, *pairs, &contact);
  EXPECT_GT(s, 0.0) << "the naive plan never makes two robots touch (or they touch at the start)";
  EXPECT_LT(s, 1.0);
  if (s > 0.0) {
    EXPECT_NE(RobotOf(contact.link_a), RobotOf(contact.other)) << Describe(contact);
  }
  // The same naive plan is the straight line of the whole team in its composite configuration space.
  EXPECT_FALSE(pairs->IsMotionValid(starts, goals, kJointStep));
}

TEST(CoordinationExamples, CrossingArmsNeedCoordination) {
  ExpectNeedsCoordination("coordinate_crossing_arms.json", 2);
}

TEST(CoordinationExamples, SwapBasesNeedCoordination) { ExpectNeedsCoordination("coordinate_swap_bases.json", 4); }

TEST(CoordinationExamples, CorridorNeedsCoordination) { ExpectNeedsCoordination("coordinate_corridor.json", 2); }

TEST(CoordinationExamples, OverlappingGoalsCollideAtTheGoals) {
  const Example example = LoadExample("coordinate_goals_overlap.json");
  ASSERT_EQ(example.robots.size(), 2u);
  ExpectRequestSettings(example);
  // Into the bay the straight lines cut its corner: only the endpoints are checked alone.
  ExpectEachRobotAloneFree(example, /*straight_line=*/false);
  const auto pairs = RobotPairChecker(example);
  const Eigen::VectorXd starts = Concatenate(example.starts);
  const Eigen::VectorXd goals = Concatenate(example.goals);
  EXPECT_TRUE(pairs->IsValid(starts)) << "starts: " << Describe(pairs->Check(starts));
  const CollisionResult contact = pairs->Check(goals);
  ASSERT_TRUE(contact.in_collision) << "the goals do not overlap";
  EXPECT_NE(RobotOf(contact.link_a), RobotOf(contact.other)) << Describe(contact);
}

/// The arms stand where the generator says: "right" 1.1 m from "left", turned by π, and both use
/// the same joint values (the layout is point-symmetric about the table centre).
TEST(CoordinationExamples, CrossingArmsFaceEachOther) {
  const Example example = LoadExample("coordinate_crossing_arms.json");
  ASSERT_EQ(example.robots.size(), 2u);
  const Eigen::Isometry3d relative = example.robots[0].base_pose.inverse() * example.robots[1].base_pose;
  EXPECT_NEAR(relative.translation().x(), 1.1, 1e-9);
  EXPECT_NEAR(relative.translation().y(), 0.0, 1e-9);
  EXPECT_NEAR(relative.linear()(0, 0), -1.0, 1e-9);
  EXPECT_EQ(example.starts[0], example.starts[1]);
  EXPECT_EQ(example.goals[0], example.goals[1]);
  EXPECT_EQ(example.robots[0].model->num_dofs(), 7);
}

}  // namespace
}  // namespace chasles
