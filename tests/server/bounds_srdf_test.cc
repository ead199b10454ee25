// Robots as people ship them (issue 25): published SRDFs whose entries name links the URDF
// lacks load with warnings (an error only when asked), and start/goal values a hair outside a
// joint limit are clamped onto it within a documented tolerance, reported in the response;
// farther out they are refused, the message printing the value and the limit exactly.

#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "chasles/collision/collision_checker.h"
#include "chasles/robot/error.h"
#include "chasles/robot/robot_model.h"
#include "../box_arm.h"
#include "server_fixture.h"

namespace chasles::testing {
namespace {

class RobotsAsShipped : public SharedServerTest<> {
 protected:
  static v1::UploadRobotRequest PandaWithStaleSrdf(bool strict) {
    v1::UploadRobotRequest request;
    v1::UrdfRobot* urdf = request.mutable_robot()->mutable_urdf();
    urdf->set_urdf(ReadText(ExamplePath("robots/panda.urdf")));
    std::string srdf = ReadText(ExamplePath("robots/panda.srdf"));
    // Two entries for links this URDF does not have (as Fetch's SRDF names bellows_link2).
    const std::string stale =
        "  <disable_collisions link1=\"panda_link0\" link2=\"bellows_link2\" reason=\"Never\"/>\n"
        "  <disable_collisions link1=\"collision_head_link\" link2=\"panda_link1\" reason=\"Never\"/>\n";
    srdf.insert(srdf.rfind("</robot>"), stale);
    urdf->set_srdf(srdf);
    urdf->set_strict_srdf(strict);
    return request;
  }
  /// panda_table with its goal 2.7e-6 rad above panda_joint7's limit of 2.8973 (in `workcell`
  /// unless empty), after checking that the default tolerance refuses it, printing the value
  /// and the limit exactly (the value is visibly above the limit).
  static v1::PlanRequest GoalJustAboveTheLimit(const std::string& workcell) {
    v1::PlanRequest request = LoadRequest("panda_table");
    if (!workcell.empty()) request.mutable_workcell()->set_name(workcell);
    request.mutable_goal()->set_positions(6, 2.8973 + 2.7e-6);
    v1::PlanResponse response;
    const grpc::Status status = server_->Plan(request, &response);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();
    EXPECT_EQ(status.error_message(),
              "goal.positions[6] = 2.8973027 must be within [-2.8973, 2.8973] (joint 'panda_joint7')");
    return request;
  }
  static grpc::Status Upload(const v1::UploadRobotRequest& request, v1::UploadRobotResponse* response) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
    return server_->stub().UploadRobot(&context, request, response);
  }
  /// examples/robots/mobile_manipulator.urdf/.srdf uploaded; its upload response.
  static v1::UploadRobotResponse UploadMobileManipulator() {
    v1::UploadRobotRequest upload;
    upload.mutable_robot()->mutable_urdf()->set_urdf(ReadText(ExamplePath("robots/mobile_manipulator.urdf")));
    upload.mutable_robot()->mutable_urdf()->set_srdf(ReadText(ExamplePath("robots/mobile_manipulator.srdf")));
    v1::UploadRobotResponse uploaded;
    const grpc::Status status = Upload(upload, &uploaded);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return uploaded;
  }
};

TEST_F(RobotsAsShipped, AnSrdfNamingUnknownLinksLoadsWithAWarningPerSkippedPair) {
  v1::UploadRobotResponse response;
  const grpc::Status status = Upload(PandaWithStaleSrdf(false), &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(response.warnings_size(), 2);
  EXPECT_NE(response.warnings(0).find("robot.urdf.srdf: disable_collisions["), std::string::npos) << response.warnings(0);
  EXPECT_NE(response.warnings(0).find("link2 = 'bellows_link2' is not a link of robot 'panda'; the pair is skipped"),
            std::string::npos)
      << response.warnings(0);
  EXPECT_NE(response.warnings(1).find("link1 = 'collision_head_link' is not a link of robot 'panda'; the pair is "
                                      "skipped"),
            std::string::npos)
      << response.warnings(1);
  // The uploaded robot plans, and the pairs that do name its links are honoured (the folded
  // start of the example is free only with the SRDF's adjacent-link pairs disabled).
  v1::PlanRequest plan = LoadRequest("panda_table");
  plan.set_robot_id(response.robot_id());
  v1::PlanResponse planned;
  const grpc::Status planned_status = server_->Plan(plan, &planned);
  ASSERT_TRUE(planned_status.ok()) << planned_status.error_message();
  EXPECT_EQ(planned.outcome(), v1::SUCCESS) << planned.message();
  EXPECT_EQ(planned.warnings_size(), 0);  // reported at upload, not again per request
  // Inline, the same robot's warnings come with the plan.
  *plan.mutable_robot() = PandaWithStaleSrdf(false).robot();
  ASSERT_TRUE(server_->Plan(plan, &planned).ok());
  EXPECT_EQ(planned.outcome(), v1::SUCCESS) << planned.message();
  EXPECT_EQ(planned.warnings_size(), 2);

  // strict_srdf: the first such entry is the error.
  const grpc::Status strict = Upload(PandaWithStaleSrdf(true), &response);
  EXPECT_EQ(strict.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(strict.error_message().find("robot.urdf.srdf: disable_collisions["), std::string::npos)
      << strict.error_message();
  EXPECT_NE(strict.error_message().find("link2 = 'bellows_link2' is not a link of robot 'panda'"), std::string::npos)
      << strict.error_message();
}

TEST_F(RobotsAsShipped, ARobotWithMimicGrippersUploadsPlansAndSolvesIkWithOneCoordinatePerGripper) {
  // examples/robots/dual_arm: each gripper's second finger is a URDF <mimic> of the first.
  v1::UploadRobotRequest upload;
  v1::UrdfRobot* urdf = upload.mutable_robot()->mutable_urdf();
  urdf->set_urdf(ReadText(ExamplePath("robots/dual_arm.urdf")));
  urdf->set_srdf(ReadText(ExamplePath("robots/dual_arm.srdf")));
  v1::UploadRobotResponse uploaded;
  const grpc::Status status = Upload(upload, &uploaded);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(uploaded.joint_names_size(), 13);
  EXPECT_EQ(uploaded.joint_names(6), "left_finger_joint");
  EXPECT_EQ(uploaded.joint_names(12), "right_finger_joint");
  ASSERT_EQ(uploaded.warnings_size(), 1);  // the SRDF's stale pair, nothing about the mimic joints
  EXPECT_NE(uploaded.warnings(0).find("'left_wrist_camera_link'"), std::string::npos) << uploaded.warnings(0);
  EXPECT_EQ(uploaded.collision_model().kind(), "shapes");

  // Plan: grippers from closed to open while the arms move.
  v1::PlanRequest plan;
  plan.set_robot_id(uploaded.robot_id());
  const std::vector<double> goal = {0.3, 0.4, 0.2, -1.2, 0.3, 0.6, 0.04, 0.4, -0.2, -1.2, -0.3, 0.6, 0.03};
  for (int i = 0; i < 13; ++i) plan.mutable_start()->add_positions(0.0);
  for (double g : goal) plan.mutable_goal()->add_positions(g);
  plan.mutable_planner()->set_planner_id("rrt_connect");
  plan.set_time_budget(3.0);
  plan.set_seed(7);
  v1::PlanResponse planned;
  const grpc::Status planned_status = server_->Plan(plan, &planned);
  ASSERT_TRUE(planned_status.ok()) << planned_status.error_message();
  ASSERT_EQ(planned.outcome(), v1::SUCCESS) << planned.message();
  ASSERT_EQ(planned.trajectory().joint_names_size(), 13);
  ASSERT_GT(planned.trajectory().points_size(), 1);
  const v1::TrajectoryPoint& last = planned.trajectory().points(planned.trajectory().points_size() - 1);
  ASSERT_EQ(last.positions_size(), 13);
  EXPECT_NEAR(last.positions(6), 0.04, 1e-9);
  EXPECT_EQ(last.efforts_size(), 13);  // the robot has inertia on every moving link, fingers included

  // InverseKinematics of the left gripper's tool frame, at a pose the arm reaches (FK of `goal`).
  const auto robot = RobotModel::FromUrdf(urdf->urdf(), urdf->srdf());
  std::vector<Eigen::Isometry3d> poses;
  robot->ForwardKinematics(Eigen::Map<const Eigen::VectorXd>(goal.data(), 13), &poses);
  const Eigen::Isometry3d target = poses[robot->FindLink("left_tcp")];
  v1::InverseKinematicsRequest ik;
  ik.set_robot_id(uploaded.robot_id());
  ik.set_link("left_tcp");
  ik.mutable_pose()->mutable_position()->set_x(target.translation().x());
  ik.mutable_pose()->mutable_position()->set_y(target.translation().y());
  ik.mutable_pose()->mutable_position()->set_z(target.translation().z());
  const Eigen::Quaterniond rotation(target.linear());
  ik.mutable_pose()->mutable_orientation()->set_x(rotation.x());
  ik.mutable_pose()->mutable_orientation()->set_y(rotation.y());
  ik.mutable_pose()->mutable_orientation()->set_z(rotation.z());
  ik.mutable_pose()->mutable_orientation()->set_w(rotation.w());
  ik.set_time_budget(1.0);
  v1::InverseKinematicsResponse solved;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
  ASSERT_TRUE(server_->stub().InverseKinematics(&context, ik, &solved).ok());
  ASSERT_TRUE(solved.solved()) << solved.message();
  ASSERT_EQ(solved.solutions(0).positions_size(), 13);
  Eigen::VectorXd q(13);
  for (int i = 0; i < 13; ++i) q[i] = solved.solutions(0).positions(i);
  robot->ForwardKinematics(q, &poses);
  EXPECT_LT((poses[robot->FindLink("left_tcp")].translation() - target.translation()).norm(), 1e-4 + 1e-12);
}

TEST_F(RobotsAsShipped, ValuesJustOutsideALimitAreClampedWithinTheToleranceAndRefusedBeyondIt) {
  v1::PlanRequest request = GoalJustAboveTheLimit("");
  v1::PlanResponse response;
  grpc::Status status;

  request.set_bounds_tolerance(1e-5);
  request.mutable_start()->set_positions(6, -2.8973 - 5e-7);
  status = server_->Plan(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  ASSERT_EQ(response.warnings_size(), 2);
  EXPECT_EQ(response.warnings(0), "start.positions[6] = -2.8973005 is 5e-07 below its lower limit -2.8973 (joint "
                                  "'panda_joint7'), within bounds_tolerance 1e-05: clamped onto the limit");
  EXPECT_NE(response.warnings(1).find("goal.positions[6] = 2.8973027 is "), std::string::npos) << response.warnings(1);
  EXPECT_NE(response.warnings(1).find(" above its upper limit 2.8973 (joint 'panda_joint7'), within bounds_tolerance "
                                      "1e-05: clamped onto the limit"),
            std::string::npos)
      << response.warnings(1);
  // The trajectory starts and ends on the limits, not outside them.
  ASSERT_GT(response.trajectory().points_size(), 1);
  EXPECT_EQ(response.trajectory().points(0).positions(6), -2.8973);
  EXPECT_EQ(response.trajectory().points(response.trajectory().points_size() - 1).positions(6), 2.8973);

  // The default tolerance (1e-6) absorbs 5e-7 with no request field.
  request = LoadRequest("panda_table");
  request.mutable_start()->set_positions(6, -2.8973 - 5e-7);
  status = server_->Plan(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.warnings_size(), 1);

  request.set_bounds_tolerance(0.02);
  status = server_->Plan(request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(status.error_message(), "bounds_tolerance = 0.02 must be within [0, 0.01]");
}

TEST_F(RobotsAsShipped, AWorkcellPlanClampsWithinTheToleranceToo) {
  // The same PlanRequest field on the workcell path (a team of one among committed motions).
  v1::CreateWorkcellRequest create;
  create.set_name("bounds_cell");
  v1::CreateWorkcellResponse created;
  {
    grpc::ClientContext context;
    ASSERT_TRUE(server_->stub().CreateWorkcell(&context, create, &created).ok());
  }
  v1::PlanRequest request = GoalJustAboveTheLimit("bounds_cell");
  request.set_bounds_tolerance(1e-5);
  v1::PlanResponse response;
  const grpc::Status status = server_->Plan(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  ASSERT_EQ(response.warnings_size(), 1);
  EXPECT_NE(response.warnings(0).find("goal.positions[6] = 2.8973027 is "), std::string::npos) << response.warnings(0);
  ASSERT_GT(response.trajectory().points_size(), 1);
  EXPECT_EQ(response.trajectory().points(response.trajectory().points_size() - 1).positions(6), 2.8973);
}

// Issue 25, item 5: a trajectory that fails the final verification is repaired, and the
// response says what failed and what was done. A planar arm of boxes (discrete checks) is
// planned at collision_resolution 0.1 past a 2 mm plate it can pass only folded: the coarse
// checks step over the plate, the verification at 0.005 rad finds it.
TEST_F(RobotsAsShipped, AVerificationFailureIsRepairedAndTheResponseSaysWhat) {
  v1::PlanRequest request;
  request.mutable_robot()->mutable_urdf()->set_urdf(test::kBoxArmUrdf);
  v1::Box* plate = request.mutable_scene()->add_boxes();
  plate->set_name("plate");
  plate->mutable_size()->set_x(0.8);
  plate->mutable_size()->set_y(0.002);
  plate->mutable_size()->set_z(1.0);
  plate->mutable_pose()->mutable_position()->set_x(1.7);
  plate->mutable_pose()->mutable_orientation()->set_w(1.0);
  request.mutable_start()->add_positions(-0.55);
  request.mutable_start()->add_positions(0.0);
  request.mutable_goal()->add_positions(0.62);
  request.mutable_goal()->add_positions(0.0);
  request.set_collision_resolution(0.1);
  request.set_time_budget(2.0);
  int repaired = 0;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    request.set_seed(seed);
    v1::PlanResponse response;
    const grpc::Status status = server_->Plan(request, &response);
    ASSERT_TRUE(status.ok()) << status.error_message();
    ASSERT_EQ(response.outcome(), v1::SUCCESS) << response.message();
    if (!response.has_repair()) continue;
    ++repaired;
    EXPECT_TRUE(response.repair().repaired());
    EXPECT_NE(response.repair().failure().find("'plate'"), std::string::npos) << response.repair().failure();
    ASSERT_GE(response.repair().actions_size(), 1);
    EXPECT_NE(response.repair().actions(response.repair().actions_size() - 1).find("verified"), std::string::npos);
    EXPECT_GT(response.timings().repair(), 0.0);
    EXPECT_GE(response.timings().total(), response.timings().repair());
  }
  EXPECT_GE(repaired, 1);
}

// Issue 25, item 1: several planning groups. The mobile manipulator's SRDF defines "arm" (a
// chain) and "arm_with_torso" (a joint and a subgroup); a plan for "arm" moves only the arm's
// seven joints, the torso held where the start puts it, and every state of it is free for the
// whole robot (re-checked here on a checker of the full robot).
TEST_F(RobotsAsShipped, APlanningGroupMovesOnlyItsJoints) {
  const v1::UploadRobotResponse uploaded = UploadMobileManipulator();
  ASSERT_FALSE(uploaded.robot_id().empty());
  ASSERT_EQ(uploaded.groups_size(), 2);
  EXPECT_EQ(uploaded.groups(0).name(), "arm");
  ASSERT_EQ(uploaded.groups(0).joint_names_size(), 7);
  EXPECT_EQ(uploaded.groups(0).joint_names(0), "shoulder_pan_joint");
  EXPECT_EQ(uploaded.groups(1).name(), "arm_with_torso");
  EXPECT_EQ(uploaded.groups(1).joint_names_size(), 8);
  bool group_warning = false;
  for (const std::string& w : uploaded.warnings()) {
    group_warning |= w.find("robot.urdf.srdf: group 'gripper_sensors' link[0] name = 'gripper_camera_link'") == 0;
  }
  EXPECT_TRUE(group_warning);

  v1::PlanRequest request;
  request.set_robot_id(uploaded.robot_id());
  request.mutable_scene();
  request.set_group("arm");
  const double start[8] = {0.2, 0.0, 0.3, 0.0, 1.0, 0.0, 0.6, 0.0};
  const double goal[7] = {0.9, -0.4, 0.5, 1.2, -0.4, 0.9, 0.3};
  for (double v : start) request.mutable_start()->add_positions(v);
  for (double v : goal) request.mutable_goal()->add_positions(v);
  v1::PlanResponse response;
  grpc::Status status = server_->Plan(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  ASSERT_EQ(response.trajectory().joint_names_size(), 7);
  for (int i = 0; i < 7; ++i) EXPECT_EQ(response.trajectory().joint_names(i), uploaded.groups(0).joint_names(i));
  const auto full = RobotModel::FromUrdf(ReadText(ExamplePath("robots/mobile_manipulator.urdf")),
                                         ReadText(ExamplePath("robots/mobile_manipulator.srdf")));
  const CollisionChecker checker(full, std::make_shared<Scene>());
  ASSERT_GT(response.trajectory().points_size(), 2);
  for (const v1::TrajectoryPoint& point : response.trajectory().points()) {
    ASSERT_EQ(point.positions_size(), 7);
    Eigen::VectorXd q(8);
    q[0] = start[0];
    for (int i = 0; i < 7; ++i) q[i + 1] = point.positions(i);
    EXPECT_FALSE(checker.Check(q).in_collision) << "t = " << point.time_from_start();
  }
  const v1::TrajectoryPoint& last = response.trajectory().points(response.trajectory().points_size() - 1);
  for (int i = 0; i < 7; ++i) EXPECT_NEAR(last.positions(i), goal[i], 1e-9);

  // A whole-robot goal works when the held joint stays; moving it is a named error.
  request.mutable_goal()->clear_positions();
  request.mutable_goal()->add_positions(start[0]);
  for (double v : goal) request.mutable_goal()->add_positions(v);
  status = server_->Plan(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  request.mutable_goal()->set_positions(0, 0.25);
  status = server_->Plan(request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(status.error_message(),
            "goal.positions[0] = 0.25 differs from start.positions[0] = 0.2, but joint 'torso_lift_joint' is not in "
            "group 'arm' and stays where the start puts it: give the group's joints ('shoulder_pan_joint', "
            "'shoulder_lift_joint', 'upperarm_roll_joint', 'elbow_flex_joint', 'forearm_roll_joint', "
            "'wrist_flex_joint', 'wrist_roll_joint'), or every joint with those outside the group equal to the "
            "start's");
  request.mutable_goal()->mutable_positions()->RemoveLast();
  request.mutable_goal()->mutable_positions()->RemoveLast();
  status = server_->Plan(request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("goal.positions has 6 values; group 'arm' of robot 'mobile_manipulator' has 7"),
            std::string::npos)
      << status.error_message();
  request.set_group("legs");
  status = server_->Plan(request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(status.error_message(),
            "group = 'legs' is not a planning group of robot 'mobile_manipulator' (its groups: 'arm', "
            "'arm_with_torso')");
}

// A continuous joint has no limit: values beyond the range it is planned in ([-π, π]) are the
// same angles as their equivalents inside it, used with a warning (not refused).
TEST_F(RobotsAsShipped, ContinuousJointValuesOutsideTheirPlanningRangeAreWrapped) {
  const v1::UploadRobotResponse uploaded = UploadMobileManipulator();
  ASSERT_FALSE(uploaded.robot_id().empty());
  v1::PlanRequest request;
  request.set_robot_id(uploaded.robot_id());
  request.mutable_scene();
  // Joint 5 (forearm_roll_joint) starts at -7 rad; joint 3 (upperarm_roll_joint) ends at 3.5 rad.
  const double start[8] = {0.2, 0.0, 0.3, 0.0, 1.0, -7.0, 0.6, 0.0};
  const double goal[8] = {0.2, 0.9, -0.4, 3.5, 1.2, -0.4, 0.9, 0.3};
  for (double v : start) request.mutable_start()->add_positions(v);
  for (double v : goal) request.mutable_goal()->add_positions(v);
  v1::PlanResponse response;
  const grpc::Status status = server_->Plan(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  ASSERT_EQ(response.warnings_size(), 2);
  EXPECT_EQ(response.warnings(0), "start.positions[5] = -7 on continuous joint 'forearm_roll_joint' is the angle " +
                                      FormatNumber(-7.0 + 2.0 * M_PI) +
                                      " of the range it is planned in [-3.141592653589793, 3.141592653589793]: wrapped");
  EXPECT_NE(response.warnings(1).find("goal.positions[3] = 3.5 on continuous joint 'upperarm_roll_joint' is the angle " +
                                      FormatNumber(3.5 - 2.0 * M_PI)),
            std::string::npos)
      << response.warnings(1);
  const auto& points = response.trajectory().points();
  EXPECT_NEAR(points[0].positions(5), -7.0 + 2.0 * M_PI, 1e-12);
  EXPECT_NEAR(points[points.size() - 1].positions(3), 3.5 - 2.0 * M_PI, 1e-12);
  // A prismatic or revolute joint far outside its limits is still refused.
  request.mutable_goal()->set_positions(0, 0.6);
  EXPECT_EQ(server_->Plan(request, &response).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
}

// OptimizeRequest.group: the first waypoint gives every joint; the others the group's joints or
// every joint with the held ones unchanged. The trajectory names and moves only the group's joints.
TEST_F(RobotsAsShipped, OptimizeTimesAPlanningGroupsPath) {
  const v1::UploadRobotResponse uploaded = UploadMobileManipulator();
  ASSERT_FALSE(uploaded.robot_id().empty());
  v1::OptimizeRequest request;
  request.set_robot_id(uploaded.robot_id());
  request.mutable_scene();
  request.set_group("arm");
  const double first[8] = {0.2, 0.0, 0.3, 0.0, 1.0, 0.0, 0.6, 0.0};
  const double middle[7] = {0.3, 0.1, 0.2, 1.1, 0.0, 0.7, 0.1};
  const double last[8] = {0.2, 0.6, -0.2, 0.4, 1.2, -0.3, 0.9, 0.3};
  v1::JointState* a = request.add_path();
  for (double v : first) a->add_positions(v);
  v1::JointState* b = request.add_path();
  for (double v : middle) b->add_positions(v);
  v1::JointState* c = request.add_path();
  for (double v : last) c->add_positions(v);
  v1::OptimizeResponse response;
  grpc::ClientContext context;
  grpc::Status status = server_->stub().Optimize(&context, request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  ASSERT_EQ(response.trajectory().joint_names_size(), 7);
  EXPECT_EQ(response.trajectory().joint_names(0), "shoulder_pan_joint");
  const auto& points = response.trajectory().points();
  ASSERT_GT(points.size(), 2);
  for (int i = 0; i < 7; ++i) {
    EXPECT_NEAR(points[0].positions(i), first[i + 1], 1e-12);
    EXPECT_NEAR(points[points.size() - 1].positions(i), last[i + 1], 1e-12);
  }
  // A held joint that moves between waypoints is refused, naming it.
  request.mutable_path(2)->set_positions(0, 0.25);
  grpc::ClientContext context2;
  status = server_->stub().Optimize(&context2, request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("path[2].positions[0] = 0.25 differs from path[0].positions[0] = 0.2, but "
                                        "joint 'torso_lift_joint' is not in group 'arm' and stays where the first "
                                        "waypoint puts it"),
            std::string::npos)
      << status.error_message();
}

// TeamRobot.group: two mobile manipulators side by side move their arms only; the team is
// verified with every robot's other joints standing where their starts put them.
TEST_F(RobotsAsShipped, CoordinateMovesEachRobotsPlanningGroup) {
  const v1::UploadRobotResponse uploaded = UploadMobileManipulator();
  ASSERT_FALSE(uploaded.robot_id().empty());
  v1::CoordinateRequest request;
  request.mutable_scene();
  const double start[8] = {0.1, 0.0, 0.3, 0.0, 1.0, 0.0, 0.6, 0.0};
  const double goal[7] = {0.9, -0.4, 0.5, 1.2, -0.4, 0.9, 0.3};
  for (int k = 0; k < 2; ++k) {
    v1::TeamRobot* robot = request.add_robots();
    robot->set_name(k == 0 ? "left" : "right");
    robot->set_robot_id(uploaded.robot_id());
    robot->set_group("arm");
    robot->mutable_base_pose()->mutable_position()->set_y(k == 0 ? 1.5 : -1.5);
    robot->mutable_base_pose()->mutable_orientation()->set_w(1.0);
    for (double v : start) robot->mutable_start()->add_positions(v);
    for (double v : goal) robot->mutable_goal()->add_positions(v);
  }
  request.set_time_budget(20.0);
  v1::CoordinateResponse response;
  {
    grpc::ClientContext context;
    const grpc::Status status = server_->stub().Coordinate(&context, request, &response);
    ASSERT_TRUE(status.ok()) << status.error_message();
  }
  ASSERT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  ASSERT_EQ(response.robots_size(), 2);
  for (const v1::RobotTrajectory& robot : response.robots()) {
    ASSERT_EQ(robot.trajectory().joint_names_size(), 7) << robot.name();
    const auto& points = robot.trajectory().points();
    for (int i = 0; i < 7; ++i) EXPECT_NEAR(points[points.size() - 1].positions(i), goal[i], 1e-9);
  }
  // 3 m apart: the arms (reach < 1.2 m each) never come near each other.
  EXPECT_GT(response.verification().min_robot_distance(), 0.2);
  request.mutable_robots(1)->set_group("legs");
  grpc::ClientContext context;
  const grpc::Status status = server_->stub().Coordinate(&context, request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(status.error_message(),
            "robots[1].group = 'legs' is not a planning group of robot 'mobile_manipulator' (its groups: 'arm', "
            "'arm_with_torso')");
}

// PlanRequest.group in a workcell, and CommitTrajectoryRequest.group: the group's trajectory is
// committed as Plan returns it, the robot's other joints standing at held_positions; a second
// robot in the same place at the same time is a conflict; a group trajectory committed without
// the group, or held_positions without a group or of the wrong size, is a named error.
TEST_F(RobotsAsShipped, AWorkcellPlansAndCommitsAPlanningGroup) {
  const v1::UploadRobotResponse uploaded = UploadMobileManipulator();
  ASSERT_FALSE(uploaded.robot_id().empty());
  {
    v1::CreateWorkcellRequest create;
    create.set_name("group_cell");
    v1::CreateWorkcellResponse created;
    grpc::ClientContext context;
    ASSERT_TRUE(server_->stub().CreateWorkcell(&context, create, &created).ok());
  }
  const double start[8] = {0.2, 0.0, 0.3, 0.0, 1.0, 0.0, 0.6, 0.0};
  const double goal[7] = {0.9, -0.4, 0.5, 1.2, -0.4, 0.9, 0.3};
  v1::PlanRequest request;
  request.set_robot_id(uploaded.robot_id());
  request.mutable_scene();
  request.set_group("arm");
  request.mutable_workcell()->set_name("group_cell");
  request.mutable_workcell()->set_robot_name("left");
  for (double v : start) request.mutable_start()->add_positions(v);
  for (double v : goal) request.mutable_goal()->add_positions(v);
  v1::PlanResponse planned;
  grpc::Status status = server_->Plan(request, &planned);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(planned.outcome(), v1::SUCCESS) << planned.message();
  ASSERT_EQ(planned.trajectory().joint_names_size(), 7);
  const v1::TrajectoryPoint& last = planned.trajectory().points(planned.trajectory().points_size() - 1);
  ASSERT_EQ(last.positions_size(), 7);
  for (int i = 0; i < 7; ++i) EXPECT_NEAR(last.positions(i), goal[i], 1e-9);

  const auto commit = [&](const std::string& robot_name, const std::string& group, int held,
                          v1::CommitTrajectoryResponse* response) {
    v1::CommitTrajectoryRequest c;
    c.set_workcell("group_cell");
    c.set_robot_name(robot_name);
    c.set_robot_id(uploaded.robot_id());
    c.set_group(group);
    for (int i = 0; i < held; ++i) c.add_held_positions(start[i]);
    *c.mutable_trajectory() = planned.trajectory();
    c.set_hold(600.0);  // from now, held at its end for 10 min: the second commit overlaps it
    grpc::ClientContext context;
    return server_->stub().CommitTrajectory(&context, c, response);
  };
  v1::CommitTrajectoryResponse committed;
  status = commit("left", "arm", 8, &committed);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(committed.active_reservations(), 1u);

  // The same robot model in the same place at the same time: the held torso and arm overlap.
  status = commit("right", "arm", 8, &committed);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION) << status.error_message();
  EXPECT_NE(status.error_message().find("conflicts with a committed one"), std::string::npos) << status.error_message();

  status = commit("right", "arm", 7, &committed);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(status.error_message(),
            "held_positions has 7 values; with group 'arm' it must hold all 8 joints of robot 'mobile_manipulator': "
            "those outside the group stand there while the trajectory moves the group's 7 ('shoulder_pan_joint', "
            "'shoulder_lift_joint', 'upperarm_roll_joint', 'elbow_flex_joint', 'forearm_roll_joint', "
            "'wrist_flex_joint', 'wrist_roll_joint')");
  status = commit("right", "", 8, &committed);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(status.error_message(),
            "held_positions is set without group: name the planning group the trajectory moves, or send no "
            "held_positions");
  status = commit("right", "", 0, &committed);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();
  status = commit("right", "legs", 8, &committed);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(status.error_message(),
            "group = 'legs' is not a planning group of robot 'mobile_manipulator' (its groups: 'arm', "
            "'arm_with_torso')");
}

// InverseKinematicsRequest.group: only the group's joints move, the others held at
// initial_guess; every solution, put back into the whole robot, reaches the pose (checked here
// with the robot's own forward kinematics).
TEST_F(RobotsAsShipped, InverseKinematicsSolvesForAPlanningGroup) {
  v1::InverseKinematicsRequest request;
  request.mutable_robot()->mutable_urdf()->set_urdf(ReadText(ExamplePath("robots/mobile_manipulator.urdf")));
  request.mutable_robot()->mutable_urdf()->set_srdf(ReadText(ExamplePath("robots/mobile_manipulator.srdf")));
  const auto full = RobotModel::FromUrdf(ReadText(ExamplePath("robots/mobile_manipulator.urdf")),
                                         ReadText(ExamplePath("robots/mobile_manipulator.srdf")));
  Eigen::VectorXd target(8);
  target << 0.3, 0.5, -0.3, 0.4, 1.1, -0.2, 0.7, 0.1;
  std::vector<Eigen::Isometry3d> poses;
  full->ForwardKinematics(target, &poses);
  const int link = full->FindLink("gripper_link");
  ASSERT_GE(link, 0);
  const Eigen::Isometry3d& pose = poses[static_cast<std::size_t>(link)];
  const Eigen::Quaterniond rotation(pose.linear());
  request.set_link("gripper_link");
  request.mutable_pose()->mutable_position()->set_x(pose.translation().x());
  request.mutable_pose()->mutable_position()->set_y(pose.translation().y());
  request.mutable_pose()->mutable_position()->set_z(pose.translation().z());
  request.mutable_pose()->mutable_orientation()->set_w(rotation.w());
  request.mutable_pose()->mutable_orientation()->set_x(rotation.x());
  request.mutable_pose()->mutable_orientation()->set_y(rotation.y());
  request.mutable_pose()->mutable_orientation()->set_z(rotation.z());
  request.set_group("arm");
  request.set_max_solutions(3);
  request.set_time_budget(1.0);
  const double guess[8] = {0.3, 0.2, 0.0, 0.0, 0.9, 0.0, 0.5, 0.0};  // the torso held at 0.3 m
  for (double v : guess) request.add_initial_guess(v);
  v1::InverseKinematicsResponse response;
  grpc::ClientContext context;
  grpc::Status status = server_->stub().InverseKinematics(&context, request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_TRUE(response.solved()) << response.message();
  ASSERT_EQ(response.joint_names_size(), 7);
  EXPECT_EQ(response.joint_names(0), "shoulder_pan_joint");
  for (const v1::JointState& solution : response.solutions()) {
    ASSERT_EQ(solution.positions_size(), 7);
    Eigen::VectorXd q(8);
    q[0] = 0.3;
    for (int i = 0; i < 7; ++i) q[i + 1] = solution.positions(i);
    full->ForwardKinematics(q, &poses);
    EXPECT_LT((poses[static_cast<std::size_t>(link)].translation() - pose.translation()).norm(), 1e-4 + 1e-9);
  }
  request.clear_initial_guess();
  grpc::ClientContext again;
  status = server_->stub().InverseKinematics(&again, request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(status.error_message(),
            "initial_guess has 0 values; with group 'arm' it must hold all 8 joints of robot 'mobile_manipulator': "
            "those outside the group are held at them");
}

}  // namespace
}  // namespace chasles::testing
