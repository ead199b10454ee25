// Bad inputs: each gets its exact status code and a message that names the field; expected
// outcomes (start/goal in collision) are OK responses. After each, the server still answers.
#include <cmath>
#include <initializer_list>
#include <string>

#include <gtest/gtest.h>

#include "server_fixture.h"

namespace chasles::testing {
namespace {

// Panda: arm folded down onto the table top (checked: panda_hand touches table_top).
const double kPandaOnTable[] = {0.0, 1.2, 0.0, -0.5, 0.0, 1.5, 0.785};

class BadInput : public SharedServerTest<> {
 protected:
  void TearDown() override {
    // The server survives every bad input.
    v1::ListPlannersResponse planners;
    const grpc::Status status = server_->ListPlanners(&planners);
    EXPECT_TRUE(status.ok()) << status.error_message();
    EXPECT_GT(planners.planners_size(), 0);
  }

  /// The default-robot (Panda), default-scene (table) request from the examples.
  static v1::PlanRequest Base() { return LoadRequest("panda_table"); }

  static void ExpectPlanError(const v1::PlanRequest& request, grpc::StatusCode code,
                              std::initializer_list<const char*> fragments) {
    v1::PlanResponse response;
    const grpc::Status status = server_->Plan(request, &response);
    EXPECT_EQ(status.error_code(), code) << "message: " << status.error_message();
    for (const char* fragment : fragments) {
      EXPECT_NE(status.error_message().find(fragment), std::string::npos)
          << "'" << fragment << "' not in: " << status.error_message();
    }
  }

  static v1::PlanRequest Planar() { return LoadRequest("planar_2r_posts"); }

};

TEST_F(BadInput, MalformedUrdf) {
  v1::PlanRequest request = Planar();
  request.mutable_robot()->mutable_urdf()->set_urdf("<robot name='broken'><link name='a'>");
  ExpectPlanError(request, grpc::StatusCode::INVALID_ARGUMENT, {"robot.urdf.urdf"});
}

TEST_F(BadInput, EmptyRobotDescription) {
  v1::PlanRequest request = Planar();
  request.mutable_robot()->clear_urdf();
  ExpectPlanError(request, grpc::StatusCode::INVALID_ARGUMENT, {"robot", "urdf"});
}

TEST_F(BadInput, SrdfNamingAnUnknownLink) {
  v1::PlanRequest request = Planar();
  request.mutable_robot()->mutable_urdf()->set_srdf(
      "<robot name='planar_2r'><disable_collisions link1='link1' link2='no_such_link' reason='Never'/></robot>");
  // By default the pair is skipped and reported (as MoveIt does); the plan goes ahead.
  v1::PlanResponse response;
  const grpc::Status lenient = server_->Plan(request, &response);
  ASSERT_TRUE(lenient.ok()) << lenient.error_message();
  ASSERT_EQ(response.warnings_size(), 1);
  EXPECT_EQ(response.warnings(0), "robot.urdf.srdf: disable_collisions[0] link2 = 'no_such_link' is not a link of "
                                  "robot 'planar_2r'; the pair is skipped");
  // strict_srdf: the error, naming the field and the link.
  request.mutable_robot()->mutable_urdf()->set_strict_srdf(true);
  ExpectPlanError(request, grpc::StatusCode::INVALID_ARGUMENT, {"robot.urdf.srdf", "no_such_link"});

  // Upload reports the same error.
  v1::UploadRobotRequest upload;
  *upload.mutable_robot() = request.robot();
  v1::UploadRobotResponse uploaded;
  grpc::ClientContext context;
  const grpc::Status status = server_->stub().UploadRobot(&context, upload, &uploaded);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("no_such_link"), std::string::npos) << status.error_message();
}

TEST_F(BadInput, CorruptOctoMapBytes) {
  v1::PlanRequest request = Base();
  v1::OctoMap* map = request.mutable_scene()->add_octomaps();
  map->set_name("broken");
  map->set_data("# Octomap OcTree binary file\nid OcTree\nsize 99\nres 0.02\ndata\n\x01\x02garbage");
  ExpectPlanError(request, grpc::StatusCode::INVALID_ARGUMENT, {"scene.octomaps[0].data"});
}

TEST_F(BadInput, NanStart) {
  v1::PlanRequest request = Base();
  request.mutable_start()->set_positions(2, std::nan(""));
  ExpectPlanError(request, grpc::StatusCode::INVALID_ARGUMENT, {"start.positions[2]", "nan"});
}

TEST_F(BadInput, OutOfLimitStart) {
  v1::PlanRequest request = Base();
  request.mutable_start()->set_positions(1, 3.0);  // panda_joint2 is within ±1.7628
  ExpectPlanError(request, grpc::StatusCode::INVALID_ARGUMENT, {"start.positions[1]"});
}

TEST_F(BadInput, WrongJointCount) {
  v1::PlanRequest request = Base();
  request.mutable_goal()->mutable_positions()->RemoveLast();
  ExpectPlanError(request, grpc::StatusCode::INVALID_ARGUMENT, {"goal.positions has 6 values", "7 joints"});
}

TEST_F(BadInput, StartInCollisionIsAnOutcome) {
  v1::PlanRequest request = Base();
  request.mutable_start()->clear_positions();
  for (double q : kPandaOnTable) request.mutable_start()->add_positions(q);
  v1::PlanResponse response;
  const grpc::Status status = server_->Plan(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.outcome(), v1::START_IN_COLLISION);
  EXPECT_NE(response.message().find("table_top"), std::string::npos) << response.message();
  EXPECT_EQ(response.trajectory().points_size(), 0);
}

TEST_F(BadInput, GoalInCollisionIsAnOutcome) {
  v1::PlanRequest request = Base();
  request.mutable_goal()->clear_positions();
  for (double q : kPandaOnTable) request.mutable_goal()->add_positions(q);
  v1::PlanResponse response;
  const grpc::Status status = server_->Plan(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.outcome(), v1::GOAL_IN_COLLISION);
  EXPECT_FALSE(response.message().empty());
  EXPECT_EQ(response.trajectory().points_size(), 0);
}

TEST_F(BadInput, UnknownPlannerListsKnownIds) {
  v1::PlanRequest request = Base();
  request.mutable_planner()->set_planner_id("no_such_planner");
  ExpectPlanError(request, grpc::StatusCode::NOT_FOUND, {"no_such_planner", "rrt_connect", "prm"});
}

TEST_F(BadInput, ParameterOutOfRange) {
  v1::PlanRequest request = Base();
  (*request.mutable_planner()->mutable_parameters())["range"].set_double_value(-1.0);
  ExpectPlanError(request, grpc::StatusCode::INVALID_ARGUMENT, {"planner.parameters['range']", "-1"});
}

TEST_F(BadInput, UnknownParameter) {
  v1::PlanRequest request = Base();
  (*request.mutable_planner()->mutable_parameters())["foo"].set_double_value(1.0);
  ExpectPlanError(request, grpc::StatusCode::INVALID_ARGUMENT, {"planner.parameters['foo']"});
}

TEST_F(BadInput, ParameterOfTheWrongType) {
  v1::PlanRequest request = Base();
  (*request.mutable_planner()->mutable_parameters())["range"].set_bool_value(true);
  ExpectPlanError(request, grpc::StatusCode::INVALID_ARGUMENT, {"planner.parameters['range']"});
}

TEST_F(BadInput, NegativeBudget) {
  v1::PlanRequest request = Base();
  request.set_time_budget(-1.0);
  ExpectPlanError(request, grpc::StatusCode::INVALID_ARGUMENT, {"time_budget = -1"});
}

TEST_F(BadInput, UnknownRobotId) {
  v1::PlanRequest request = Base();
  request.set_robot_id("00000000000000000000000000000000");
  ExpectPlanError(request, grpc::StatusCode::NOT_FOUND, {"robot_id '00000000000000000000000000000000'", "inline"});
}

TEST_F(BadInput, UnknownSceneId) {
  v1::PlanRequest request = Base();
  request.set_scene_id("feedfacefeedfacefeedfacefeedface");
  ExpectPlanError(request, grpc::StatusCode::NOT_FOUND, {"scene_id 'feedfacefeedfacefeedfacefeedface'", "inline"});
}

TEST_F(BadInput, NonUnitQuaternion) {
  v1::PlanRequest request = Base();
  *request.mutable_scene() = LoadScene("table");
  v1::Quaternion* q = request.mutable_scene()->mutable_boxes(1)->mutable_pose()->mutable_orientation();
  q->set_x(0.0);
  q->set_y(0.0);
  q->set_z(0.0);
  q->set_w(0.5);
  ExpectPlanError(request, grpc::StatusCode::INVALID_ARGUMENT, {"scene.boxes[1].pose.orientation has norm 0.5"});
}

TEST_F(BadInput, NegativeBoxSize) {
  v1::PlanRequest request = Base();
  *request.mutable_scene() = LoadScene("table");
  request.mutable_scene()->mutable_boxes(2)->mutable_size()->set_x(-1.0);
  ExpectPlanError(request, grpc::StatusCode::INVALID_ARGUMENT, {"scene.boxes[2].size.x = -1 must be"});
}

TEST_F(BadInput, NanSphereRadius) {
  v1::PlanRequest request = Base();
  v1::Sphere* sphere = request.mutable_scene()->add_spheres();
  sphere->set_radius(std::nan(""));
  ExpectPlanError(request, grpc::StatusCode::INVALID_ARGUMENT, {"scene.spheres[0].radius = nan"});
}

TEST_F(BadInput, MeshBytesThatAreNotAMesh) {
  v1::PlanRequest request = Base();
  v1::Mesh* mesh = request.mutable_scene()->add_meshes();
  mesh->set_name("junk");
  mesh->set_data("this is certainly not an STL or OBJ file \x01\x02\x03");
  ExpectPlanError(request, grpc::StatusCode::INVALID_ARGUMENT, {"scene.meshes[0].data"});
}

TEST_F(BadInput, SamplePeriodOutOfRange) {
  v1::PlanRequest request = Base();
  request.mutable_trajectory()->set_sample_period(5.0);
  ExpectPlanError(request, grpc::StatusCode::INVALID_ARGUMENT, {"trajectory.sample_period = 5"});
}

TEST_F(BadInput, VelocityOverrideNotPositive) {
  v1::PlanRequest request = Base();
  for (int i = 0; i < 7; ++i) request.mutable_trajectory()->add_max_velocity(i == 3 ? 0.0 : 1.0);
  ExpectPlanError(request, grpc::StatusCode::INVALID_ARGUMENT, {"trajectory.max_velocity[3] = 0"});
}

TEST_F(BadInput, GoalToleranceOutOfRange) {
  v1::PlanRequest request = Base();
  request.mutable_goal()->set_tolerance(0.5);
  ExpectPlanError(request, grpc::StatusCode::INVALID_ARGUMENT, {"goal.tolerance = 0.5"});
}

TEST_F(BadInput, CollisionResolutionOutOfRange) {
  v1::PlanRequest request = Base();
  request.set_collision_resolution(1.0);
  ExpectPlanError(request, grpc::StatusCode::INVALID_ARGUMENT, {"collision_resolution = 1"});
}

TEST_F(BadInput, UploadSceneReportsErrorsAtUpload) {
  v1::UploadSceneRequest upload;
  *upload.mutable_scene() = LoadScene("table");
  upload.mutable_scene()->mutable_capsules(0)->set_length(0.0);
  v1::UploadSceneResponse uploaded;
  grpc::ClientContext context;
  const grpc::Status status = server_->stub().UploadScene(&context, upload, &uploaded);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("scene.capsules[0].length = 0"), std::string::npos) << status.error_message();
}

}  // namespace
}  // namespace chasles::testing
