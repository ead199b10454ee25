// Issue 3 through the server: pose goals, the InverseKinematics RPC, DH/PoE robots, efforts.
// Every pose-goal example must come back as a verified trajectory that ends exactly at the
// reported IK solution, whose link pose (FK computed here) is within the request's tolerances;
// IK solutions are checked by FK (and by the collision checker when collision_free is set);
// bad inputs get their exact status and a message naming the field.
#include <cmath>
#include <initializer_list>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "chasles/collision/collision_checker.h"
#include "chasles/robot/dynamics.h"
#include "chasles/server/convert.h"
#include "server_fixture.h"

namespace chasles::testing {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

template <typename Message>
Message LoadJson(const std::string& relative) {
  Message message;
  const auto status = google::protobuf::util::JsonStringToMessage(ReadText(ExamplePath(relative)), &message);
  EXPECT_TRUE(status.ok()) << relative << ": " << status.ToString();
  return message;
}

std::shared_ptr<const RobotModel> DefaultPanda() {
  return RobotModel::FromUrdf(ReadText(ExamplePath("robots/panda.urdf")), ReadText(ExamplePath("robots/panda.srdf")));
}

/// The robot a request names (inline, or the default Panda).
template <typename Request>
std::shared_ptr<const RobotModel> RobotOf(const Request& request) {
  return request.has_robot() ? RobotFromProto(request.robot()) : DefaultPanda();
}

template <typename Request>
std::shared_ptr<const Scene> SceneOf(const Request& request) {
  return request.has_scene() ? SceneFromProto(request.scene()) : SceneFromProto(LoadScene("table"));
}

Eigen::VectorXd ToVector(const google::protobuf::RepeatedField<double>& values) {
  Eigen::VectorXd q(values.size());
  for (int i = 0; i < values.size(); ++i) q[i] = values[i];
  return q;
}

Eigen::Isometry3d LinkPose(const RobotModel& robot, const Eigen::VectorXd& q, int link) {
  std::vector<Eigen::Isometry3d> poses;
  robot.ForwardKinematics(q, &poses);
  return poses[link];
}

double PositionError(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.translation() - b.translation()).norm();
}

double OrientationError(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle();
}

int ResolvedLink(const RobotModel& robot, const std::string& name) { return LinkFromProto(robot, name, "link"); }

// --- pose goals end to end -----------------------------------------------------------------------

const std::vector<std::string> kPoseRequests = {"panda_pose_table", "ur5_pose_table", "ur5_dh_pose", "ur5_poe_pose",
                                                "puma560_dh_pose"};

class PoseGoalExample : public SharedServerTest<::testing::TestWithParam<std::string>> {};

TEST_P(PoseGoalExample, EndsExactlyAtAnIkSolutionWithinTheTolerances) {
  const v1::PlanRequest request = LoadRequest(GetParam());
  ASSERT_EQ(request.target_case(), v1::PlanRequest::kPoseGoal);
  const auto robot = RobotOf(request);
  const int dofs = robot->num_dofs();
  v1::PlanResponse response;
  const grpc::Status status = server_->Plan(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(response.outcome(), v1::SUCCESS) << v1::PlanOutcome_Name(response.outcome()) << ": " << response.message();

  // The trajectory starts at the start and ends exactly at the reported goal.
  ASSERT_EQ(response.reached_goal().positions_size(), dofs);
  const Eigen::VectorXd goal = ToVector(response.reached_goal().positions());
  const v1::JointTrajectory& trajectory = response.trajectory();
  ASSERT_GT(trajectory.points_size(), 1);
  const Eigen::VectorXd first = ToVector(trajectory.points(0).positions());
  const Eigen::VectorXd last = ToVector(trajectory.points(trajectory.points_size() - 1).positions());
  ASSERT_EQ(last.size(), dofs);
  EXPECT_LE((first - ToVector(request.start().positions())).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_LE((last - goal).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_LE((ToVector(response.path(response.path_size() - 1).positions()) - goal).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_LE(response.verification().max_velocity_ratio(), 1.0 + 1e-9);
  EXPECT_LE(response.verification().max_acceleration_ratio(), 1.0 + 1e-9);
  EXPECT_GT(response.verification().states_checked(), 0u);

  // FK of the goal is within the tolerances of the target; the goal is within limits and free.
  const v1::PoseGoal& pose_goal = request.pose_goal();
  const int link = ResolvedLink(*robot, pose_goal.link());
  const Eigen::Isometry3d target = PoseFromProto(pose_goal.pose(), "pose");
  const Eigen::Isometry3d reached = LinkPose(*robot, goal, link);
  const double position_tolerance = pose_goal.position_tolerance() > 0 ? pose_goal.position_tolerance() : 1e-4;
  const double orientation_tolerance = pose_goal.orientation_tolerance() > 0 ? pose_goal.orientation_tolerance() : 1e-3;
  EXPECT_LE(PositionError(reached, target), position_tolerance + 1e-12);
  EXPECT_LE(OrientationError(reached, target), orientation_tolerance + 1e-12);
  EXPECT_NO_THROW(robot->ValidateConfiguration(goal, "goal"));
  const CollisionChecker checker(robot, SceneOf(request));
  EXPECT_TRUE(checker.IsValid(goal));
  EXPECT_GE(response.goal_manipulability(), 0.0);

  // Efforts: one per joint on every point exactly when every moving link has a mass.
  // The example Panda and UR5 (URDF) carry inertials; the PUMA 560 table has none.
  if (GetParam() == "panda_pose_table" || GetParam() == "ur5_pose_table") {
    EXPECT_TRUE(HasInertia(*robot));
  }
  if (GetParam() == "puma560_dh_pose") {
    EXPECT_FALSE(HasInertia(*robot));
  }
  const int expected_efforts = HasInertia(*robot) ? dofs : 0;
  for (const v1::TrajectoryPoint& point : trajectory.points()) {
    ASSERT_EQ(point.efforts_size(), expected_efforts);
    for (double e : point.efforts()) ASSERT_TRUE(std::isfinite(e));
  }
}

INSTANTIATE_TEST_SUITE_P(Examples, PoseGoalExample, ::testing::ValuesIn(kPoseRequests),
                         [](const ::testing::TestParamInfo<std::string>& info) { return info.param; });

// --- the InverseKinematics RPC --------------------------------------------------------------------

class Ik : public SharedServerTest<> {
 protected:
  void TearDown() override {
    v1::ListPlannersResponse planners;  // the server survives every request
    EXPECT_TRUE(server_->ListPlanners(&planners).ok());
  }
  static grpc::Status Solve(const v1::InverseKinematicsRequest& request, v1::InverseKinematicsResponse* response) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
    return server_->stub().InverseKinematics(&context, request, response);
  }
  static void ExpectError(const v1::InverseKinematicsRequest& request, grpc::StatusCode code,
                          std::initializer_list<const char*> fragments) {
    v1::InverseKinematicsResponse response;
    const grpc::Status status = Solve(request, &response);
    EXPECT_EQ(status.error_code(), code) << status.error_message();
    for (const char* fragment : fragments) {
      EXPECT_NE(status.error_message().find(fragment), std::string::npos)
          << "'" << fragment << "' not in: " << status.error_message();
    }
  }
};

class IkExample : public Ik, public ::testing::WithParamInterface<std::string> {};

TEST_P(IkExample, SolutionsAreWithinTolerancesLimitsAndCollisionFree) {
  const auto request = LoadJson<v1::InverseKinematicsRequest>("requests/" + GetParam() + ".json");
  const auto robot = RobotOf(request);
  v1::InverseKinematicsResponse response;
  const grpc::Status status = Solve(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_TRUE(response.solved()) << response.message();
  ASSERT_GE(response.solutions_size(), 1);
  EXPECT_LE(response.solutions_size(), static_cast<int>(std::max(1u, request.max_solutions())));
  ASSERT_EQ(response.manipulability_size(), response.solutions_size());
  ASSERT_EQ(response.singular_size(), response.solutions_size());
  ASSERT_EQ(response.joint_names_size(), robot->num_dofs());
  EXPECT_EQ(response.robot_id().size(), 32u);
  const int link = ResolvedLink(*robot, request.link());
  const Eigen::Isometry3d target = PoseFromProto(request.pose(), "pose");
  const double position_tolerance = request.position_tolerance() > 0 ? request.position_tolerance() : 1e-4;
  const double orientation_tolerance = request.orientation_tolerance() > 0 ? request.orientation_tolerance() : 1e-3;
  const CollisionChecker checker(robot, SceneOf(request));
  for (int i = 0; i < response.solutions_size(); ++i) {
    const Eigen::VectorXd q = ToVector(response.solutions(i).positions());
    ASSERT_EQ(q.size(), robot->num_dofs());
    const Eigen::Isometry3d pose = LinkPose(*robot, q, link);
    EXPECT_LE(PositionError(pose, target), position_tolerance + 1e-12) << "solution " << i;
    EXPECT_LE(OrientationError(pose, target), orientation_tolerance + 1e-12) << "solution " << i;
    EXPECT_NO_THROW(robot->ValidateConfiguration(q, "solution"));
    if (request.collision_free()) {
      EXPECT_TRUE(checker.IsValid(q)) << "solution " << i;
    }
    EXPECT_GE(response.manipulability(i), 0.0);
    if (response.singular(i)) {
      EXPECT_LT(response.manipulability(i), 1e-3) << "solution " << i;
    }
  }
  // Distinct solutions.
  for (int i = 0; i < response.solutions_size(); ++i) {
    for (int j = i + 1; j < response.solutions_size(); ++j) {
      EXPECT_GT((ToVector(response.solutions(i).positions()) - ToVector(response.solutions(j).positions()))
                    .cwiseAbs()
                    .maxCoeff(),
                1e-3);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Examples, IkExample, ::testing::Values("ik_panda", "ik_ur5"),
                         [](const ::testing::TestParamInfo<std::string>& info) { return info.param; });

TEST_F(Ik, UnreachablePoseIsAnOkResponseWithoutSolutions) {
  auto request = LoadJson<v1::InverseKinematicsRequest>("requests/ik_panda.json");
  request.mutable_pose()->mutable_position()->set_x(5.0);  // far beyond the Panda's reach
  request.set_time_budget(0.05);
  v1::InverseKinematicsResponse response;
  const grpc::Status status = Solve(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_FALSE(response.solved());
  EXPECT_EQ(response.solutions_size(), 0);
  EXPECT_FALSE(response.message().empty());
  EXPECT_GT(response.best_position_error(), 1.0);
  EXPECT_GT(response.attempts(), 0u);
}

TEST_F(Ik, DefaultLinkAndDefaultsApply) {
  // Panda has no link called "tool": the empty link is the last link (panda_tcp).
  auto request = LoadJson<v1::InverseKinematicsRequest>("requests/ik_panda.json");
  request.clear_link();
  request.set_collision_free(false);
  request.set_max_solutions(0);
  v1::InverseKinematicsResponse response;
  ASSERT_TRUE(Solve(request, &response).ok());
  ASSERT_TRUE(response.solved()) << response.message();
  EXPECT_EQ(response.solutions_size(), 1);  // 0 = 1
  const auto robot = DefaultPanda();
  const Eigen::Isometry3d pose =
      LinkPose(*robot, ToVector(response.solutions(0).positions()), robot->FindLink("panda_tcp"));
  EXPECT_LE(PositionError(pose, PoseFromProto(request.pose(), "pose")), 1e-4 + 1e-12);
}

// The URDF, DH and PoE UR5 describe one arm (up to constant base/tool frames), so an IK solution
// of one reaches, on every other, the pose that other reaches at the original configuration.
TEST_F(Ik, UrdfDhAndPoeUr5AgreeThroughIkRoundTrips) {
  std::vector<v1::RobotModel> models;
  models.push_back(LoadRequest("ur5_table").robot());
  for (const char* file : {"robots/ur5_dh.json", "robots/ur5_poe.json"}) {
    v1::RobotModel model;
    model.set_name("ur5");
    if (std::string(file).find("_dh") != std::string::npos) {
      *model.mutable_dh() = LoadJson<v1::DhRobot>(file);
    } else {
      *model.mutable_poe() = LoadJson<v1::PoeRobot>(file);
    }
    models.push_back(model);
  }
  std::vector<std::shared_ptr<const RobotModel>> robots;
  std::vector<int> links;
  for (const v1::RobotModel& model : models) {
    robots.push_back(RobotFromProto(model));
    links.push_back(ResolvedLink(*robots.back(), robots.back()->FindLink("tool") >= 0 ? "tool" : "tool0"));
    ASSERT_EQ(robots.back()->num_dofs(), 6);
  }
  Eigen::VectorXd q(6);
  q << 0.7, -1.1, 1.3, -0.9, 1.2, 0.4;
  for (size_t a = 0; a < models.size(); ++a) {
    v1::InverseKinematicsRequest request;
    *request.mutable_robot() = models[a];
    request.set_link(robots[a]->links()[links[a]].name);
    const Eigen::Isometry3d target = LinkPose(*robots[a], q, links[a]);
    const Eigen::Quaterniond quat(target.linear());
    v1::Pose* pose = request.mutable_pose();
    pose->mutable_position()->set_x(target.translation().x());
    pose->mutable_position()->set_y(target.translation().y());
    pose->mutable_position()->set_z(target.translation().z());
    pose->mutable_orientation()->set_x(quat.x());
    pose->mutable_orientation()->set_y(quat.y());
    pose->mutable_orientation()->set_z(quat.z());
    pose->mutable_orientation()->set_w(quat.w());
    request.set_time_budget(0.5);
    request.set_seed(3);
    v1::InverseKinematicsResponse response;
    ASSERT_TRUE(Solve(request, &response).ok());
    ASSERT_TRUE(response.solved()) << "model " << a << ": " << response.message();
    const Eigen::VectorXd solution = ToVector(response.solutions(0).positions());
    for (size_t b = 0; b < models.size(); ++b) {
      const Eigen::Isometry3d expected = LinkPose(*robots[b], q, links[b]);
      const Eigen::Isometry3d got = LinkPose(*robots[b], solution, links[b]);
      EXPECT_LE(PositionError(got, expected), 2e-4) << "IK on model " << a << ", FK on model " << b;
      EXPECT_LE(OrientationError(got, expected), 2e-3) << "IK on model " << a << ", FK on model " << b;
    }
  }
}

// --- bad inputs -----------------------------------------------------------------------------------

/// A small PoE arm (planar 2R, both axes along z, tool at x = 1.8).
v1::RobotModel PoeArm() {
  v1::RobotModel model;
  v1::PoeRobot* poe = model.mutable_poe();
  poe->set_name("poe_2r");
  poe->mutable_home()->mutable_position()->set_x(1.8);
  for (int i = 0; i < 2; ++i) {
    v1::PoeJoint* joint = poe->add_joints();
    joint->mutable_screw()->mutable_angular()->set_z(1.0);
    joint->mutable_screw()->mutable_linear()->set_y(-1.0 * i);  // v = −ω × (i, 0, 0)
    joint->mutable_limits()->set_lower(-3.0);
    joint->mutable_limits()->set_upper(3.0);
    joint->mutable_limits()->set_velocity(2.0);
    joint->mutable_link()->add_spheres()->set_radius(0.05);
  }
  return model;
}

/// A small DH arm (standard convention, three revolute joints).
v1::RobotModel DhArm() {
  v1::RobotModel model;
  v1::DhRobot* dh = model.mutable_dh();
  dh->set_name("dh_3r");
  for (int i = 0; i < 3; ++i) {
    v1::DhJoint* joint = dh->add_joints();
    joint->set_a(0.5);
    joint->set_alpha(i == 0 ? M_PI / 2 : 0.0);
    joint->mutable_limits()->set_lower(-3.0);
    joint->mutable_limits()->set_upper(3.0);
    joint->mutable_limits()->set_velocity(2.0);
  }
  return model;
}

v1::InverseKinematicsRequest IkFor(const v1::RobotModel& model) {
  v1::InverseKinematicsRequest request;
  *request.mutable_robot() = model;
  request.mutable_pose()->mutable_position()->set_x(1.0);
  return request;
}

TEST_F(Ik, SmallDescriptionsParse) {
  // The valid forms of the bad inputs below parse (so each bad input fails for its own reason).
  for (const v1::RobotModel& model : {PoeArm(), DhArm()}) {
    v1::UploadRobotRequest upload;
    *upload.mutable_robot() = model;
    v1::UploadRobotResponse uploaded;
    grpc::ClientContext context;
    const grpc::Status status = server_->stub().UploadRobot(&context, upload, &uploaded);
    EXPECT_TRUE(status.ok()) << status.error_message();
  }
}

TEST_F(Ik, PoeRevoluteScrewWithNonUnitOmega) {
  v1::RobotModel model = PoeArm();
  model.mutable_poe()->mutable_joints(1)->mutable_screw()->mutable_angular()->set_z(0.5);
  ExpectError(IkFor(model), grpc::StatusCode::INVALID_ARGUMENT, {"robot.poe.joints[1].screw", "0.5"});
}

TEST_F(Ik, PoePrismaticScrewWithNonUnitV) {
  v1::RobotModel model = PoeArm();
  v1::PoeJoint* joint = model.mutable_poe()->mutable_joints(0);
  joint->set_type(v1::PRISMATIC);
  joint->mutable_screw()->mutable_angular()->set_z(0.0);
  joint->mutable_screw()->mutable_linear()->set_x(2.0);
  joint->mutable_screw()->mutable_linear()->set_y(0.0);
  ExpectError(IkFor(model), grpc::StatusCode::INVALID_ARGUMENT, {"robot.poe.joints[0].screw", "2"});
}

TEST_F(Ik, PoeHomeNotInSe3) {
  v1::RobotModel model = PoeArm();
  model.mutable_poe()->mutable_home()->mutable_orientation()->set_w(0.5);
  ExpectError(IkFor(model), grpc::StatusCode::INVALID_ARGUMENT, {"robot.poe.home"});
}

TEST_F(Ik, DhNan) {
  v1::RobotModel model = DhArm();
  model.mutable_dh()->mutable_joints(2)->set_alpha(kNan);
  ExpectError(IkFor(model), grpc::StatusCode::INVALID_ARGUMENT, {"robot.dh.joints[2].alpha = nan must be finite"});
}

TEST_F(Ik, MaxSolutionsOutOfRange) {
  auto request = LoadJson<v1::InverseKinematicsRequest>("requests/ik_panda.json");
  request.set_max_solutions(65);
  ExpectError(request, grpc::StatusCode::INVALID_ARGUMENT, {"max_solutions = 65"});
}

TEST_F(Ik, TimeBudgetNotPositive) {
  auto request = LoadJson<v1::InverseKinematicsRequest>("requests/ik_panda.json");
  request.set_time_budget(-1.0);
  ExpectError(request, grpc::StatusCode::INVALID_ARGUMENT, {"time_budget = -1"});
}

TEST_F(Ik, UnknownLink) {
  auto request = LoadJson<v1::InverseKinematicsRequest>("requests/ik_panda.json");
  request.set_link("no_such_link");
  ExpectError(request, grpc::StatusCode::INVALID_ARGUMENT, {"link = 'no_such_link'", "panda_tcp"});
}

TEST_F(Ik, UnknownRobotId) {
  auto request = LoadJson<v1::InverseKinematicsRequest>("requests/ik_panda.json");
  request.set_robot_id("00000000000000000000000000000000");
  ExpectError(request, grpc::StatusCode::NOT_FOUND, {"robot_id '00000000000000000000000000000000'"});
}

class PoseGoalBadInput : public Ik {
 protected:
  static void ExpectPlanError(const v1::PlanRequest& request, grpc::StatusCode code,
                              std::initializer_list<const char*> fragments) {
    v1::PlanResponse response;
    const grpc::Status status = server_->Plan(request, &response);
    EXPECT_EQ(status.error_code(), code) << status.error_message();
    for (const char* fragment : fragments) {
      EXPECT_NE(status.error_message().find(fragment), std::string::npos)
          << "'" << fragment << "' not in: " << status.error_message();
    }
  }
};

TEST_F(PoseGoalBadInput, UnknownLinkListsTheKnownOnes) {
  v1::PlanRequest request = LoadRequest("panda_pose_table");
  request.mutable_pose_goal()->set_link("gripper");
  ExpectPlanError(request, grpc::StatusCode::INVALID_ARGUMENT, {"pose_goal.link = 'gripper'", "panda_link0", "panda_tcp"});
}

TEST_F(PoseGoalBadInput, PositionToleranceOutOfRange) {
  v1::PlanRequest request = LoadRequest("panda_pose_table");
  request.mutable_pose_goal()->set_position_tolerance(0.5);
  ExpectPlanError(request, grpc::StatusCode::INVALID_ARGUMENT, {"pose_goal.position_tolerance = 0.5"});
}

TEST_F(PoseGoalBadInput, OrientationToleranceNegative) {
  v1::PlanRequest request = LoadRequest("panda_pose_table");
  request.mutable_pose_goal()->set_orientation_tolerance(-0.1);
  ExpectPlanError(request, grpc::StatusCode::INVALID_ARGUMENT, {"pose_goal.orientation_tolerance = -0.1"});
}

TEST_F(PoseGoalBadInput, NanGravity) {
  v1::PlanRequest request = LoadRequest("panda_pose_table");
  request.mutable_gravity()->set_z(kNan);
  ExpectPlanError(request, grpc::StatusCode::INVALID_ARGUMENT, {"gravity.z = nan"});
}

TEST_F(PoseGoalBadInput, GravityChangesTheEfforts) {
  v1::PlanRequest request = LoadRequest("panda_pose_table");
  v1::PlanResponse with_gravity, without_gravity;
  ASSERT_TRUE(server_->Plan(request, &with_gravity).ok());
  request.mutable_gravity()->set_z(0.0);  // present and zero: no gravity
  ASSERT_TRUE(server_->Plan(request, &without_gravity).ok());
  ASSERT_EQ(with_gravity.outcome(), v1::SUCCESS);
  ASSERT_EQ(without_gravity.outcome(), v1::SUCCESS);
  const v1::TrajectoryPoint& a = with_gravity.trajectory().points(0);
  const v1::TrajectoryPoint& b = without_gravity.trajectory().points(0);
  ASSERT_EQ(a.efforts_size(), 7);
  ASSERT_EQ(b.efforts_size(), 7);
  double difference = 0.0;
  for (int j = 0; j < 7; ++j) difference = std::max(difference, std::abs(a.efforts(j) - b.efforts(j)));
  EXPECT_GT(difference, 1.0);  // the Panda's gravity load at the ready pose is tens of N·m
}

TEST_F(PoseGoalBadInput, UnreachablePoseIsAnOutcome) {
  v1::PlanRequest request = LoadRequest("panda_pose_table");
  request.mutable_pose_goal()->mutable_pose()->mutable_position()->set_x(5.0);
  request.mutable_pose_goal()->set_ik_time_budget(0.05);
  v1::PlanResponse response;
  const grpc::Status status = server_->Plan(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.outcome(), v1::GOAL_UNREACHABLE) << response.message();
  EXPECT_FALSE(response.message().empty());
  EXPECT_EQ(response.trajectory().points_size(), 0);
}

}  // namespace
}  // namespace chasles::testing
