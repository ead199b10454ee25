// The CartesianPath RPC over loopback gRPC: the shipped example drawn along its lines (checked by a
// projection formula written here, on the states and on the timed samples), a wall on the line
// (the path stops before it; ignored, the timing refuses the colliding path), and named errors.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "chasles/collision/collision_checker.h"
#include "chasles/server/convert.h"
#include "server_fixture.h"

namespace chasles::testing {
namespace {

v1::CartesianPathRequest Example() {
  v1::CartesianPathRequest request;
  const std::string text = ReadText(ExamplePath("requests/cartesian_panda_table.json"));
  EXPECT_TRUE(google::protobuf::util::JsonStringToMessage(text, &request).ok());
  return request;
}

std::shared_ptr<const RobotModel> Panda() {
  return RobotModel::FromUrdf(ReadText(ExamplePath("robots/panda.urdf")), ReadText(ExamplePath("robots/panda.srdf")));
}

Eigen::VectorXd ToVector(const google::protobuf::RepeatedField<double>& values) {
  Eigen::VectorXd q(values.size());
  for (int i = 0; i < values.size(); ++i) q[i] = values[i];
  return q;
}

Eigen::Vector3d Tcp(const RobotModel& robot, const Eigen::VectorXd& q) {
  std::vector<Eigen::Isometry3d> poses;
  robot.ForwardKinematics(q, &poses);
  return poses[static_cast<std::size_t>(robot.FindLink("panda_tcp"))].translation();
}

/// The distance from p to the polyline through `corners` (projection onto each segment).
double PolylineDistance(const Eigen::Vector3d& p, const std::vector<Eigen::Vector3d>& corners) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i + 1 < corners.size(); ++i) {
    const Eigen::Vector3d d = corners[i + 1] - corners[i];
    const double u = std::clamp((p - corners[i]).dot(d) / d.squaredNorm(), 0.0, 1.0);
    best = std::min(best, (p - corners[i] - u * d).norm());
  }
  return best;
}

class CartesianPath : public SharedServerTest<> {
 protected:
  void TearDown() override {
    v1::ListPlannersResponse planners;  // the server survives every request
    EXPECT_TRUE(server_->ListPlanners(&planners).ok());
  }
  static grpc::Status Call(const v1::CartesianPathRequest& request, v1::CartesianPathResponse* response) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
    return server_->stub().CartesianPath(&context, request, response);
  }
  static void ExpectError(const v1::CartesianPathRequest& request, std::initializer_list<const char*> fragments) {
    v1::CartesianPathResponse response;
    const grpc::Status status = Call(request, &response);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();
    for (const char* fragment : fragments) {
      EXPECT_NE(status.error_message().find(fragment), std::string::npos)
          << "'" << fragment << "' not in: " << status.error_message();
    }
  }
  /// The commanded corners: the start's TCP position, then every waypoint's.
  static std::vector<Eigen::Vector3d> Corners(const RobotModel& robot, const v1::CartesianPathRequest& request) {
    std::vector<Eigen::Vector3d> corners{Tcp(robot, ToVector(request.start().positions()))};
    for (const v1::Pose& w : request.waypoints()) corners.emplace_back(w.position().x(), w.position().y(), w.position().z());
    return corners;
  }
  /// A wall across the example's first line, three quarters along it (clear of the hand at the start).
  static v1::Scene WallScene(const RobotModel& robot, const v1::CartesianPathRequest& request) {
    const std::vector<Eigen::Vector3d> corners = Corners(robot, request);
    const Eigen::Vector3d middle = 0.25 * corners[0] + 0.75 * corners[1];
    v1::Scene scene;
    v1::Box* box = scene.add_boxes();
    box->set_name("wall");
    box->mutable_size()->set_x(0.3);
    box->mutable_size()->set_y(0.02);
    box->mutable_size()->set_z(0.3);
    box->mutable_pose()->mutable_position()->set_x(middle.x());
    box->mutable_pose()->mutable_position()->set_y(middle.y());
    box->mutable_pose()->mutable_position()->set_z(middle.z());
    return scene;
  }
};

TEST_F(CartesianPath, TheExampleDrawsItsRectangleAndIsTimed) {
  const v1::CartesianPathRequest request = Example();
  v1::CartesianPathResponse response;
  const grpc::Status status = Call(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(response.stop(), v1::CartesianPathResponse::COMPLETE) << response.message();
  EXPECT_EQ(response.fraction(), 1.0);
  EXPECT_EQ(response.waypoints_reached(), static_cast<unsigned>(request.waypoints_size()));
  EXPECT_EQ(response.path_size(), static_cast<int>(response.steps()) + 1);
  const auto robot = Panda();
  const std::vector<Eigen::Vector3d> corners = Corners(*robot, request);
  for (const v1::JointState& state : response.path()) {
    EXPECT_LE(PolylineDistance(Tcp(*robot, ToVector(state.positions())), corners), 1e-4 + 1e-9);
  }
  // The timed trajectory: verified, and its samples near the lines.
  const v1::OptimizeResponse& timed = response.timed();
  ASSERT_EQ(timed.outcome(), v1::SUCCESS) << timed.message();
  ASSERT_GT(timed.trajectory().points_size(), 10);
  EXPECT_EQ(timed.verification().collision_guarantee(), "certified");
  EXPECT_LE(timed.verification().max_velocity_ratio(), 1.0 + 1e-9);
  EXPECT_LE(timed.verification().max_acceleration_ratio(), 1.0 + 1e-9);
  double farthest = 0.0;
  for (const v1::TrajectoryPoint& point : timed.trajectory().points()) {
    farthest = std::max(farthest, PolylineDistance(Tcp(*robot, ToVector(point.positions())), corners));
  }
  EXPECT_LT(farthest, 2e-3) << "the timed trajectory leaves the lines";
  EXPECT_GE(response.trajectory_line_deviation(), farthest - 1e-4);
  // It ends where the path does (the last waypoint).
  const v1::TrajectoryPoint& last = timed.trajectory().points(timed.trajectory().points_size() - 1);
  EXPECT_LE((Tcp(*robot, ToVector(last.positions())) - corners.back()).norm(), 1e-4 + 1e-9);
}

TEST_F(CartesianPath, AWallOnTheLineEndsThePathAndIgnoringItIsRefusedByTheTiming) {
  v1::CartesianPathRequest request = Example();
  const auto robot = Panda();
  *request.mutable_scene() = WallScene(*robot, request);
  v1::CartesianPathResponse response;
  ASSERT_TRUE(Call(request, &response).ok());
  EXPECT_EQ(response.stop(), v1::CartesianPathResponse::COLLISION) << response.message();
  EXPECT_GT(response.fraction(), 0.0);
  EXPECT_LT(response.fraction(), 0.2);  // the wall is on the first of five lines (20 of 113 steps)
  EXPECT_EQ(response.waypoints_reached(), 0u);
  EXPECT_NE(response.message().find("waypoints[0]"), std::string::npos) << response.message();
  // What was achieved is timed, and its samples are free on the FCL checker.
  ASSERT_EQ(response.timed().outcome(), v1::SUCCESS) << response.timed().message();
  CollisionOptions fcl;
  fcl.force_fcl = true;
  const CollisionChecker checker(robot, SceneFromProto(request.scene()), fcl);
  for (const v1::TrajectoryPoint& point : response.timed().trajectory().points()) {
    EXPECT_FALSE(checker.Check(ToVector(point.positions())).in_collision);
  }
  // Told to ignore collisions, the path goes through the wall, and the timing refuses it.
  request.set_ignore_collisions(true);
  v1::CartesianPathResponse blind;
  ASSERT_TRUE(Call(request, &blind).ok());
  EXPECT_EQ(blind.stop(), v1::CartesianPathResponse::COMPLETE) << blind.message();
  EXPECT_EQ(blind.timed().outcome(), v1::VERIFICATION_FAILED) << blind.timed().message();
  EXPECT_EQ(blind.timed().trajectory().points_size(), 0);
}

TEST_F(CartesianPath, AStartInCollisionIsAnOutcomeWithNothingToTime) {
  v1::CartesianPathRequest request = Example();
  const auto robot = Panda();
  v1::Scene scene;
  v1::Sphere* block = scene.add_spheres();
  block->set_name("block");
  const Eigen::Vector3d tcp = Tcp(*robot, ToVector(request.start().positions()));
  block->set_radius(0.05);
  block->mutable_pose()->mutable_position()->set_x(tcp.x());
  block->mutable_pose()->mutable_position()->set_y(tcp.y());
  block->mutable_pose()->mutable_position()->set_z(tcp.z());
  *request.mutable_scene() = scene;
  v1::CartesianPathResponse response;
  ASSERT_TRUE(Call(request, &response).ok());
  EXPECT_EQ(response.stop(), v1::CartesianPathResponse::START_INVALID);
  EXPECT_EQ(response.fraction(), 0.0);
  EXPECT_EQ(response.path_size(), 1);
  EXPECT_NE(response.message().find("block"), std::string::npos) << response.message();
  EXPECT_FALSE(response.has_timed());
}

TEST_F(CartesianPath, BadInputNamesTheField) {
  v1::CartesianPathRequest request = Example();
  request.set_max_step(-1.0);
  ExpectError(request, {"max_step = -1 must be within [0.0001, 0.5]"});
  request = Example();
  request.mutable_waypoints(1)->mutable_position()->set_z(std::nan(""));
  ExpectError(request, {"waypoints[1].position.z"});
  request = Example();
  request.mutable_waypoints(2)->mutable_orientation()->set_w(0.5);
  ExpectError(request, {"waypoints[2].orientation has norm"});
  request = Example();
  request.clear_waypoints();
  ExpectError(request, {"waypoints: a Cartesian move needs at least one waypoint"});
  request = Example();
  request.set_link("no_such_link");
  ExpectError(request, {"link = 'no_such_link'"});
  request = Example();
  request.mutable_start()->mutable_positions()->RemoveLast();
  ExpectError(request, {"start.positions"});
  request = Example();
  request.set_jump_threshold(0.5);
  ExpectError(request, {"jump_threshold = 0.5"});
  request = Example();
  request.set_max_joint_jump(7.0);
  ExpectError(request, {"max_joint_jump = 7"});
  request = Example();
  request.set_padding(-0.1);
  ExpectError(request, {"padding = -0.1"});
}

}  // namespace
}  // namespace chasles::testing
