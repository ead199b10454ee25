// Mobile robots over gRPC: a car's plan comes back verified and ends at the goal pose (heading
// modulo 2π); planners that do not plan for a robot's kind refuse with FAILED_PRECONDITION and
// the reason; malformed mobile descriptions get INVALID_ARGUMENT naming the field.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "server_fixture.h"

namespace chasles::testing {
namespace {

constexpr double kPi = 3.14159265358979323846;

v1::RobotModel LoadMobile(const std::string& name) {
  v1::RobotModel robot;
  const auto status =
      google::protobuf::util::JsonStringToMessage(ReadText(ExamplePath("robots/" + name + ".json")), robot.mutable_mobile());
  EXPECT_TRUE(status.ok()) << name << ": " << status.ToString();
  return robot;
}

/// The example car in an open yard with one wall between start and goal.
v1::PlanRequest CarRequest(v1::MobileRobot::Kind kind) {
  v1::PlanRequest request;
  *request.mutable_robot() = LoadMobile("car");
  request.mutable_robot()->mutable_mobile()->set_kind(kind);
  v1::Box* wall = request.mutable_scene()->add_boxes();
  wall->set_name("wall");
  wall->mutable_size()->set_x(0.4);
  wall->mutable_size()->set_y(5.0);
  wall->mutable_size()->set_z(1.0);
  wall->mutable_pose()->mutable_position()->set_x(6.0);
  wall->mutable_pose()->mutable_position()->set_y(2.5);
  wall->mutable_pose()->mutable_position()->set_z(0.5);
  for (double q : {2.0, 2.0, kPi / 2}) request.mutable_start()->add_positions(q);
  for (double q : {10.0, 2.0, -kPi / 2}) request.mutable_goal()->add_positions(q);
  request.mutable_planner()->set_planner_id("rrt_connect");
  request.set_time_budget(10.0);
  request.set_seed(5);
  return request;
}

class MobileRobots : public SharedServerTest<> {};

TEST_F(MobileRobots, CarTrajectoryIsVerifiedAndEndsAtTheGoalPose) {
  for (auto kind : {v1::MobileRobot::DUBINS_CAR, v1::MobileRobot::REEDS_SHEPP_CAR}) {
    const v1::PlanRequest request = CarRequest(kind);
    v1::PlanResponse response;
    const grpc::Status status = server_->Plan(request, &response);
    ASSERT_TRUE(status.ok()) << status.error_message();
    ASSERT_EQ(response.outcome(), v1::SUCCESS) << response.message();
    const v1::JointTrajectory& trajectory = response.trajectory();
    ASSERT_EQ(trajectory.joint_names_size(), 3);
    EXPECT_EQ(trajectory.joint_names(2), "theta");
    const v1::TrajectoryPoint& first = trajectory.points(0);
    const v1::TrajectoryPoint& last = trajectory.points(trajectory.points_size() - 1);
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(first.positions(j), request.start().positions(j), 1e-9);
    EXPECT_NEAR(last.positions(0), 10.0, 1e-9);
    EXPECT_NEAR(last.positions(1), 2.0, 1e-9);
    EXPECT_NEAR(std::remainder(last.positions(2) + kPi / 2, 2 * kPi), 0.0, 1e-9);
    EXPECT_LE(response.verification().max_velocity_ratio(), 1.0 + 1e-9);
    EXPECT_LE(response.verification().max_acceleration_ratio(), 1.0 + 1e-9);
    // The car's path is kept as planned: every raw waypoint is in the returned path.
    EXPECT_EQ(static_cast<std::uint32_t>(response.path_size()), response.statistics().raw_waypoints());
    // The trajectory passes the wall on the far side of its end (y > 5), never through it.
    bool around = false;
    for (const v1::TrajectoryPoint& p : trajectory.points()) around |= p.positions(1) > 5.0;
    EXPECT_TRUE(around);
  }
}

TEST_F(MobileRobots, PlannersRefuseKindsTheyDoNotPlanFor) {
  v1::PlanRequest request = CarRequest(v1::MobileRobot::DUBINS_CAR);
  request.mutable_planner()->set_planner_id("prm");
  v1::PlanResponse response;
  grpc::Status status = server_->Plan(request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_EQ(status.error_message(),
            "planner 'prm' does not plan for dubins_car robots (robot 'car'): its roadmap joins states in both "
            "directions, but a Dubins car's curve from a to b is not the reverse of its curve from b to a; planners "
            "for dubins_car: informed_rrt_star, rrt, rrt_connect, rrt_star");

  // The planner catalogue says which kinds each planner takes.
  v1::ListPlannersResponse planners;
  ASSERT_TRUE(server_->ListPlanners(&planners).ok());
  for (const v1::PlannerDescription& p : planners.planners()) {
    if (p.id() == "prm") {
      EXPECT_EQ(std::vector<std::string>(p.robot_kinds().begin(), p.robot_kinds().end()),
                (std::vector<std::string>{"arm", "planar", "free_flyer", "reeds_shepp_car"}));
    }
  }
}

TEST_F(MobileRobots, PoseGoalsNeedAnArm) {
  v1::PlanRequest request = CarRequest(v1::MobileRobot::REEDS_SHEPP_CAR);
  request.clear_goal();
  request.mutable_pose_goal()->set_link("body");
  v1::PlanResponse response;
  const grpc::Status status = server_->Plan(request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_NE(status.error_message().find("pose_goal"), std::string::npos) << status.error_message();
  EXPECT_NE(status.error_message().find("reeds_shepp_car"), std::string::npos) << status.error_message();
}

// Issue 22, item 2: a goal enclosed by walls. The search planners search everything they can
// reach at their resolution and say so (NO_PATH_ON_LATTICE, with the nodes and the resolution in
// metres); a sampling planner runs out of its budget (NO_PATH_WITHIN_BUDGET, or APPROXIMATE_ONLY
// with a path that ends short): a client can tell
// "there is no way at this resolution" from "ran out of time".
TEST_F(MobileRobots, AnEnclosedGoalExhaustsTheLatticeRatherThanTheBudget) {
  v1::PlanRequest request;
  *request.mutable_robot() = LoadMobile("mobile_base");
  const auto wall = [&](const char* name, double x, double y, double sx, double sy) {
    v1::Box* box = request.mutable_scene()->add_boxes();
    box->set_name(name);
    box->mutable_size()->set_x(sx);
    box->mutable_size()->set_y(sy);
    box->mutable_size()->set_z(1.0);
    box->mutable_pose()->mutable_position()->set_x(x);
    box->mutable_pose()->mutable_position()->set_y(y);
    box->mutable_pose()->mutable_position()->set_z(0.5);
  };
  // A closed 2 × 2 m pen around (9, 4), walls 0.2 m thick.
  wall("pen_south", 9.0, 2.9, 2.4, 0.2);
  wall("pen_north", 9.0, 5.1, 2.4, 0.2);
  wall("pen_west", 7.9, 4.0, 0.2, 2.4);
  wall("pen_east", 10.1, 4.0, 0.2, 2.4);
  for (double q : {2.0, 4.0, 0.0}) request.mutable_start()->add_positions(q);
  for (double q : {9.0, 4.0, 0.0}) request.mutable_goal()->add_positions(q);
  request.set_time_budget(10.0);
  for (const char* planner : {"astar", "wavefront"}) {
    request.mutable_planner()->set_planner_id(planner);
    (*request.mutable_planner()->mutable_parameters())["resolution"].set_double_value(0.25);
    v1::PlanResponse response;
    ASSERT_TRUE(server_->Plan(request, &response).ok());
    EXPECT_EQ(response.outcome(), v1::NO_PATH_ON_LATTICE) << planner << ": " << response.message();
    EXPECT_NE(response.message().find("0.25"), std::string::npos) << response.message();
  }
  v1::PlanResponse astar;
  request.mutable_planner()->set_planner_id("astar");
  ASSERT_TRUE(server_->Plan(request, &astar).ok());
  EXPECT_NE(astar.message().find("reachable nodes were expanded"), std::string::npos) << astar.message();
  EXPECT_NE(astar.message().find("[m for prismatic coordinates, rad for revolute ones]"), std::string::npos)
      << astar.message();
  request.mutable_planner()->set_planner_id("rrt_connect");
  request.mutable_planner()->clear_parameters();
  request.set_time_budget(0.3);
  v1::PlanResponse sampled;
  ASSERT_TRUE(server_->Plan(request, &sampled).ok());
  // It proves nothing: out of time, with at best a path that ends short of the goal.
  EXPECT_TRUE(sampled.outcome() == v1::NO_PATH_WITHIN_BUDGET || sampled.outcome() == v1::APPROXIMATE_ONLY)
      << v1::PlanOutcome_Name(sampled.outcome()) << ": " << sampled.message();
}

TEST_F(MobileRobots, MalformedMobileDescriptionsNameTheField) {
  const auto expect = [](const v1::PlanRequest& request, const std::string& message) {
    v1::PlanResponse response;
    const grpc::Status status = server_->Plan(request, &response);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();
    EXPECT_EQ(status.error_message(), message);
  };
  v1::PlanRequest request = CarRequest(v1::MobileRobot::DUBINS_CAR);
  request.mutable_robot()->mutable_mobile()->set_turning_radius(-1.0);
  expect(request, "robot.mobile.turning_radius = -1 must be > 0 and finite");

  request = CarRequest(v1::MobileRobot::DUBINS_CAR);
  request.mutable_robot()->mutable_mobile()->mutable_body()->clear_spheres();
  expect(request, "robot.mobile.body has no collision geometry");

  request = CarRequest(v1::MobileRobot::DUBINS_CAR);
  request.mutable_robot()->mutable_mobile()->mutable_workspace_max()->set_y(-3.0);
  expect(request, "robot.mobile.workspace_min.y = 0 must be < workspace_max.y = -3");

  request = CarRequest(v1::MobileRobot::DUBINS_CAR);
  request.mutable_robot()->mutable_mobile()->set_kind(static_cast<v1::MobileRobot::Kind>(42));
  expect(request, "robot.mobile.kind = 42 is not PLANAR, DUBINS_CAR, REEDS_SHEPP_CAR or FREE_FLYER");

  request = CarRequest(v1::MobileRobot::DUBINS_CAR);
  request.mutable_start()->set_positions(0, 40.0);
  expect(request, "start.positions[0] = 40 must be within [0, 12] (joint 'x')");
}

}  // namespace
}  // namespace chasles::testing
