// Carried objects (attached_objects) over loopback gRPC: a 40 cm rod held in the Panda's gripper,
// pointing down, above a block on the floor. With the rod the start collides, a plan goes around
// the block, and the straight path and the Cartesian line through it are refused; without it all
// of them pass. Every returned trajectory is re-checked densely on a checker built here with the
// rod's exact box (the generic FCL path), independent of the spheres the server covers it with.

#include <chrono>
#include <cmath>
#include <initializer_list>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "chasles/collision/collision_checker.h"
#include "chasles/robot/attached_objects.h"
#include "chasles/server/convert.h"
#include "server_fixture.h"

namespace chasles::testing {
namespace {

constexpr double kReady[7] = {0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785};

v1::JointState Ready(double joint1) {
  v1::JointState state;
  for (int i = 0; i < 7; ++i) state.add_positions(i == 0 ? joint1 : kReady[i]);
  return state;
}

/// A 10 cm block on the floor under the gripper at the ready pose (TCP at x ≈ 0.307 m).
v1::Scene Block() {
  v1::Scene scene;
  v1::Box* block = scene.add_boxes();
  block->set_name("block");
  block->mutable_size()->set_x(0.1);
  block->mutable_size()->set_y(0.1);
  block->mutable_size()->set_z(0.1);
  block->mutable_pose()->mutable_position()->set_x(0.307);
  block->mutable_pose()->mutable_position()->set_z(0.05);
  return scene;
}

/// The rod: 4 × 4 × 40 cm along the TCP's z axis (down at the ready pose), its bottom at z ≈ 0.087 m.
v1::AttachedObject Rod() {
  v1::AttachedObject rod;
  rod.set_name("rod");
  rod.set_link("panda_tcp");
  v1::Box* box = rod.add_boxes();
  box->mutable_size()->set_x(0.04);
  box->mutable_size()->set_y(0.04);
  box->mutable_size()->set_z(0.4);
  box->mutable_pose()->mutable_position()->set_z(0.2);
  rod.add_touch_links("panda_hand");
  return rod;
}

std::shared_ptr<const RobotModel> Panda() {
  return RobotModel::FromUrdf(ReadText(ExamplePath("robots/panda.urdf")), ReadText(ExamplePath("robots/panda.srdf")));
}

/// The checker a careful user would build: the robot carrying the rod's exact box, on FCL.
std::shared_ptr<const CollisionChecker> ExactRodChecker() {
  const auto panda = Panda();
  v1::Scene scene = Block();
  google::protobuf::RepeatedPtrField<v1::AttachedObject> rods;
  *rods.Add() = Rod();
  const auto carrying = AttachObjects(*panda, AttachedObjectsFromProto(rods, *panda, "attached_objects"));
  CollisionOptions fcl;
  fcl.force_fcl = true;
  return std::make_shared<const CollisionChecker>(carrying, SceneFromProto(scene), fcl);
}

Eigen::VectorXd ToVector(const google::protobuf::RepeatedField<double>& values) {
  Eigen::VectorXd q(values.size());
  for (int i = 0; i < values.size(); ++i) q[i] = values[i];
  return q;
}

/// Colliding states of the trajectory on `checker`: every pair of consecutive samples joined by
/// states at most 0.002 rad apart.
int DenseCollisions(const v1::JointTrajectory& trajectory, const CollisionChecker& checker) {
  int colliding = 0;
  for (int s = 0; s + 1 < trajectory.points_size(); ++s) {
    const Eigen::VectorXd a = ToVector(trajectory.points(s).positions());
    const Eigen::VectorXd b = ToVector(trajectory.points(s + 1).positions());
    const int n = std::max(1, static_cast<int>(std::ceil((b - a).cwiseAbs().maxCoeff() / 0.002)));
    for (int i = 0; i < n; ++i) colliding += checker.Check(a + (b - a) * (static_cast<double>(i) / n)).in_collision;
  }
  return colliding;
}

class Attached : public SharedServerTest<> {
 protected:
  void TearDown() override {
    v1::ListPlannersResponse planners;  // the server survives every request
    EXPECT_TRUE(server_->ListPlanners(&planners).ok());
  }
  static v1::PlanRequest PlanAcross(double from, double to, bool carrying) {
    v1::PlanRequest request;
    *request.mutable_scene() = Block();
    *request.mutable_start() = Ready(from);
    const v1::JointState goal = Ready(to);
    *request.mutable_goal()->mutable_positions() = goal.positions();
    request.mutable_planner()->set_planner_id("rrt_connect");
    request.set_seed(7);
    request.set_time_budget(10.0);
    if (carrying) *request.add_attached_objects() = Rod();
    return request;
  }
};

TEST_F(Attached, TheRodMakesTheStartCollideAndNamesItself) {
  v1::PlanResponse bare, carrying;
  const grpc::Status first = server_->Plan(PlanAcross(0.0, 0.6, false), &bare);
  ASSERT_TRUE(first.ok()) << first.error_message();
  EXPECT_EQ(bare.outcome(), v1::SUCCESS) << bare.message();
  ASSERT_TRUE(server_->Plan(PlanAcross(0.0, 0.6, true), &carrying).ok());
  EXPECT_EQ(carrying.outcome(), v1::START_IN_COLLISION) << carrying.message();
  EXPECT_NE(carrying.message().find("rod"), std::string::npos) << carrying.message();
  EXPECT_NE(carrying.message().find("block"), std::string::npos) << carrying.message();
}

TEST_F(Attached, APlanCarryingTheRodGoesAroundTheBlock) {
  const auto exact = ExactRodChecker();
  // Without the rod the arm sweeps straight over the block, and the rod would go through it.
  v1::PlanResponse bare;
  ASSERT_TRUE(server_->Plan(PlanAcross(0.6, -0.6, false), &bare).ok());
  ASSERT_EQ(bare.outcome(), v1::SUCCESS) << bare.message();
  EXPECT_GT(DenseCollisions(bare.trajectory(), *exact), 0) << "the scenario should need the rod";
  // With it: planned around, certified, and free on the exact rod.
  v1::PlanResponse carrying;
  ASSERT_TRUE(server_->Plan(PlanAcross(0.6, -0.6, true), &carrying).ok());
  ASSERT_EQ(carrying.outcome(), v1::SUCCESS) << carrying.message();
  EXPECT_EQ(carrying.verification().collision_guarantee(), "certified");
  EXPECT_EQ(DenseCollisions(carrying.trajectory(), *exact), 0);
  // The spheres that stand for the rod say how far they reach outside it.
  bool said = false;
  for (const std::string& w : carrying.warnings()) said = said || w.find("attached_objects[0] ('rod'): covered by") == 0;
  EXPECT_TRUE(said);
  EXPECT_EQ(carrying.robot_id(), bare.robot_id());  // the robot as described
}

TEST_F(Attached, OptimizeAndCartesianPathsCarryItToo) {
  // The straight path over the block: fine bare, refused with the rod.
  v1::OptimizeRequest optimize;
  *optimize.mutable_scene() = Block();
  *optimize.add_path() = Ready(0.6);
  *optimize.add_path() = Ready(-0.6);
  v1::OptimizeResponse bare, carrying;
  grpc::ClientContext a, b;
  ASSERT_TRUE(server_->stub().Optimize(&a, optimize, &bare).ok());
  EXPECT_EQ(bare.outcome(), v1::SUCCESS) << bare.message();
  *optimize.add_attached_objects() = Rod();
  ASSERT_TRUE(server_->stub().Optimize(&b, optimize, &carrying).ok());
  EXPECT_EQ(carrying.outcome(), v1::VERIFICATION_FAILED) << carrying.message();
  EXPECT_NE(carrying.message().find("rod"), std::string::npos) << carrying.message();
  // A Cartesian line over the block: whole bare, stopped with the rod.
  const auto panda = Panda();
  std::vector<Eigen::Isometry3d> poses;
  panda->ForwardKinematics(ToVector(Ready(0.6).positions()), &poses);
  const Eigen::Isometry3d tcp = poses[static_cast<std::size_t>(panda->FindLink("panda_tcp"))];
  v1::CartesianPathRequest line;
  *line.mutable_scene() = Block();
  *line.mutable_start() = Ready(0.6);
  line.set_link("panda_tcp");
  v1::Pose* goal = line.add_waypoints();
  goal->mutable_position()->set_x(tcp.translation().x());
  goal->mutable_position()->set_y(-tcp.translation().y());
  goal->mutable_position()->set_z(tcp.translation().z());
  const Eigen::Quaterniond q(tcp.linear());
  goal->mutable_orientation()->set_x(q.x());
  goal->mutable_orientation()->set_y(q.y());
  goal->mutable_orientation()->set_z(q.z());
  goal->mutable_orientation()->set_w(q.w());
  v1::CartesianPathResponse whole, stopped;
  grpc::ClientContext c, d;
  ASSERT_TRUE(server_->stub().CartesianPath(&c, line, &whole).ok());
  EXPECT_EQ(whole.stop(), v1::CartesianPathResponse::COMPLETE) << whole.message();
  *line.add_attached_objects() = Rod();
  ASSERT_TRUE(server_->stub().CartesianPath(&d, line, &stopped).ok());
  EXPECT_EQ(stopped.stop(), v1::CartesianPathResponse::COLLISION) << stopped.message();
  EXPECT_LT(stopped.fraction(), 0.7);
  EXPECT_EQ(DenseCollisions(stopped.timed().trajectory(), *ExactRodChecker()), 0);
}

TEST_F(Attached, ACoordinatedRobotCarriesItToo) {
  const auto team = [](bool carrying) {
    v1::CoordinateRequest request;
    *request.mutable_scene() = Block();
    v1::TeamRobot* arm = request.add_robots();
    arm->set_name("arm");
    *arm->mutable_robot() = v1::RobotModel();
    arm->mutable_robot()->mutable_urdf()->set_urdf(ReadText(ExamplePath("robots/panda.urdf")));
    arm->mutable_robot()->mutable_urdf()->set_srdf(ReadText(ExamplePath("robots/panda.srdf")));
    *arm->mutable_start() = Ready(0.6);
    const v1::JointState goal = Ready(-0.6);
    *arm->mutable_goal()->mutable_positions() = goal.positions();
    if (carrying) *arm->add_attached_objects() = Rod();
    request.set_seed(3);
    request.set_time_budget(20.0);
    return request;
  };
  const auto exact = ExactRodChecker();
  for (const bool carrying : {false, true}) {
    v1::CoordinateResponse response;
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
    const grpc::Status status = server_->stub().Coordinate(&context, team(carrying), &response);
    ASSERT_TRUE(status.ok()) << status.error_message();
    ASSERT_EQ(response.outcome(), v1::SUCCESS) << response.message();
    ASSERT_EQ(response.robots_size(), 1);
    const int through = DenseCollisions(response.robots(0).trajectory(), *exact);
    if (carrying) {
      EXPECT_EQ(through, 0) << "the carried rod goes through the block";
    } else {
      EXPECT_GT(through, 0) << "the scenario should need the rod";
    }
  }
}

TEST_F(Attached, ABadObjectIsANamedError) {
  const auto expect = [](v1::PlanRequest request, const char* fragment) {
    v1::PlanResponse response;
    const grpc::Status status = server_->Plan(request, &response);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();
    EXPECT_NE(status.error_message().find(fragment), std::string::npos) << status.error_message();
  };
  v1::PlanRequest request = PlanAcross(0.6, -0.6, true);
  request.mutable_attached_objects(0)->set_link("nope");
  expect(request, "attached_objects[0].link = 'nope' is not a link of robot 'panda'");
  request = PlanAcross(0.6, -0.6, true);
  request.mutable_attached_objects(0)->mutable_boxes(0)->mutable_size()->set_z(-1.0);
  expect(request, "attached_objects[0].boxes[0].size.z = -1");
  request = PlanAcross(0.6, -0.6, true);
  request.mutable_attached_objects(0)->set_name("panda_hand");
  expect(request, "attached_objects[0].name = 'panda_hand' is a link of robot 'panda'");
  request = PlanAcross(0.6, -0.6, true);
  request.mutable_attached_objects(0)->add_touch_links("gripper");
  expect(request, "attached_objects[0].touch_links[1] = 'gripper' is not a link of robot 'panda'");
  request = PlanAcross(0.6, -0.6, true);
  request.mutable_attached_objects(0)->clear_boxes();
  expect(request, "attached_objects[0] has no shapes");
  request = PlanAcross(0.6, -0.6, true);
  request.mutable_attached_objects(0)->set_mass(-1.0);
  expect(request, "attached_objects[0].mass = -1 must be finite and >= 0 [kg]");
  // A workcell commit reads them as well.
  v1::CommitTrajectoryRequest commit;
  commit.set_workcell("cell");
  commit.set_robot_name("arm");
  for (const double t : {0.0, 1.0}) {
    v1::TrajectoryPoint* point = commit.mutable_trajectory()->add_points();
    point->set_time_from_start(t);
    *point->mutable_positions() = Ready(0.6).positions();
    for (int i = 0; i < 7; ++i) point->add_velocities(0.0);
  }
  *commit.add_attached_objects() = Rod();
  commit.mutable_attached_objects(0)->set_link("nope");
  v1::CommitTrajectoryResponse committed;
  grpc::ClientContext context;
  const grpc::Status status = server_->stub().CommitTrajectory(&context, commit, &committed);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();
  EXPECT_NE(status.error_message().find("attached_objects[0].link = 'nope'"), std::string::npos)
      << status.error_message();
}

}  // namespace
}  // namespace chasles::testing
