// A robot shipped with mesh collision geometry (issue 25, "any URDF at sphere speed"): uploaded
// with its STL files, its meshes are covered by spheres once, at upload, and it plans on them —
// certified along the continuous motion — while UrdfRobot.exact_meshes keeps the meshes (FCL,
// discrete). Every returned state is re-checked here on the exact meshes.

#include <map>
#include <memory>
#include <random>
#include <utility>
#include <string>

#include <gtest/gtest.h>

#include "chasles/collision/collision_checker.h"
#include "chasles/collision/mesh.h"
#include "chasles/collision/robot_spheres.h"
#include "server_fixture.h"

namespace chasles::testing {
namespace {

constexpr const char* kLinks[] = {"base_link",    "shoulder_link", "upper_arm_link", "forearm_link",
                                  "wrist_1_link", "wrist_2_link",  "wrist_3_link"};

v1::RobotModel MeshUr5(bool exact_meshes) {
  v1::RobotModel robot;
  v1::UrdfRobot* urdf = robot.mutable_urdf();
  urdf->set_urdf(ReadText(ExamplePath("robots/ur5_meshes.urdf")));
  urdf->set_srdf(ReadText(ExamplePath("robots/ur5_meshes.srdf")));
  for (const char* link : kLinks) {
    const std::string file = std::string(link) + "_0.stl";
    (*urdf->mutable_mesh_files())["package://ur5_meshes/" + file] = ReadText(ExamplePath("robots/ur5_meshes/" + file));
  }
  urdf->set_exact_meshes(exact_meshes);
  return robot;
}

/// The same robot with its exact meshes, parsed here (the re-check's model).
std::shared_ptr<const RobotModel> ExactMeshUr5() {
  std::map<std::string, std::shared_ptr<const TriangleMesh>> meshes;
  for (const char* link : kLinks) {
    const std::string file = std::string(link) + "_0.stl";
    meshes["package://ur5_meshes/" + file] =
        ParseMesh(ReadText(ExamplePath("robots/ur5_meshes/" + file)), Eigen::Vector3d::Ones(), file);
  }
  return RobotModel::FromUrdf(ReadText(ExamplePath("robots/ur5_meshes.urdf")),
                              ReadText(ExamplePath("robots/ur5_meshes.srdf")), meshes);
}

/// A shelf board and a post the UR5 reaches around.
v1::Scene Obstacles() {
  v1::Scene scene;
  v1::Box* board = scene.add_boxes();
  board->set_name("board");
  board->mutable_size()->set_x(0.3);
  board->mutable_size()->set_y(0.8);
  board->mutable_size()->set_z(0.02);
  board->mutable_pose()->mutable_position()->set_x(0.45);
  board->mutable_pose()->mutable_position()->set_z(0.35);
  board->mutable_pose()->mutable_orientation()->set_w(1.0);
  v1::Cylinder* post = scene.add_cylinders();
  post->set_name("post");
  post->set_radius(0.03);
  post->set_length(1.0);
  post->mutable_pose()->mutable_position()->set_y(0.45);
  post->mutable_pose()->mutable_position()->set_z(0.5);
  post->mutable_pose()->mutable_orientation()->set_w(1.0);
  return scene;
}

/// Obstacles() as the checker's Scene (the re-check's).
std::shared_ptr<const Scene> ObstacleScene() {
  auto scene = std::make_shared<Scene>();
  Eigen::Isometry3d board = Eigen::Isometry3d::Identity();
  board.translation() << 0.45, 0.0, 0.35;
  scene->AddObject({"board", Shape::Box({0.3, 0.8, 0.02}, board)});
  Eigen::Isometry3d post = Eigen::Isometry3d::Identity();
  post.translation() << 0.0, 0.45, 0.5;
  scene->AddObject({"post", Shape::Cylinder(0.03, 1.0, post)});
  return scene;
}

class MeshRobot : public SharedServerTest<> {
 protected:
  static v1::UploadRobotResponse Upload(bool exact_meshes) {
    v1::UploadRobotRequest request;
    *request.mutable_robot() = MeshUr5(exact_meshes);
    v1::UploadRobotResponse response;
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
    const grpc::Status status = server_->stub().UploadRobot(&context, request, &response);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return response;
  }
  /// A start and goal 1 rad or more apart, free with 5 cm to spare for the exact meshes and free
  /// for the fitted spheres too (fitted here as the server fits them).
  static v1::PlanRequest Request(const std::string& robot_id) {
    static const std::pair<Eigen::VectorXd, Eigen::VectorXd> ends = [] {
      const auto exact_robot = ExactMeshUr5();
      const auto scene = ObstacleScene();
      const CollisionChecker exact(exact_robot, scene);
      const CollisionChecker fitted(FitRobotSpheres(*exact_robot).model, scene);
      std::mt19937_64 rng(11);
      const auto pick = [&] {
        for (;;) {
          Eigen::VectorXd q(6);
          for (int i = 0; i < 6; ++i) q[i] = std::uniform_real_distribution<double>(-M_PI, M_PI)(rng);
          if (exact.IsValid(q) && fitted.IsValid(q) && exact.Clearance(q) > 0.05) return q;
        }
      };
      Eigen::VectorXd a = pick(), b = pick();
      while ((a - b).cwiseAbs().maxCoeff() < 1.0) b = pick();
      return std::make_pair(a, b);
    }();
    v1::PlanRequest request;
    request.set_robot_id(robot_id);
    *request.mutable_scene() = Obstacles();
    for (int i = 0; i < 6; ++i) {
      request.mutable_start()->add_positions(ends.first[i]);
      request.mutable_goal()->add_positions(ends.second[i]);
    }
    request.mutable_planner()->set_planner_id("rrt_connect");
    request.set_seed(7);
    return request;
  }
};

/// A whole meshes folder may be sent: files no collision geometry names (visual meshes, here a
/// COLLADA file and bytes that are no mesh at all) are never read.
TEST_F(MeshRobot, MeshFilesNoCollisionGeometryNamesAreNotRead) {
  v1::UploadRobotRequest request;
  *request.mutable_robot() = MeshUr5(/*exact_meshes=*/true);
  auto& files = *request.mutable_robot()->mutable_urdf()->mutable_mesh_files();
  files["package://ur5_meshes/visual/base.dae"] = "<?xml version=\"1.0\"?><COLLADA>not really</COLLADA>";
  files["package://ur5_meshes/readme.txt"] = "not a mesh";
  v1::UploadRobotResponse response;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  const grpc::Status status = server_->stub().UploadRobot(&context, request, &response);
  EXPECT_TRUE(status.ok()) << status.error_message();
  // A collision mesh that is missing is still an error, naming it.
  v1::UploadRobotRequest missing;
  *missing.mutable_robot() = MeshUr5(/*exact_meshes=*/true);
  missing.mutable_robot()->mutable_urdf()->mutable_mesh_files()->erase("package://ur5_meshes/forearm_link_0.stl");
  grpc::ClientContext context2;
  const grpc::Status refused = server_->stub().UploadRobot(&context2, missing, &response);
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(refused.error_message().find("1 collision mesh is not in the supplied meshes: link 'forearm_link' "
                                         "collision[1] mesh filename 'package://ur5_meshes/forearm_link_0.stl'"),
            std::string::npos)
      << refused.error_message();
}

TEST_F(MeshRobot, ItsMeshesAreCoveredBySpheresAtUploadAndItPlansCertified) {
  const v1::UploadRobotResponse uploaded = Upload(false);
  const v1::CollisionModel& model = uploaded.collision_model();
  EXPECT_EQ(model.kind(), "fitted_spheres");
  EXPECT_EQ(model.shapes_fitted(), 7);
  EXPECT_GT(model.spheres(), 7);
  EXPECT_GT(model.reach(), 0.0);
  EXPECT_LE(model.reach(), 0.02);
  EXPECT_FALSE(model.reach_link().empty());
  EXPECT_GT(model.fit_seconds(), 0.0);
  std::printf("[ fit ] %d spheres, reach %.4f m ('%s'), fitted in %.3f s\n", model.spheres(), model.reach(),
              model.reach_link().c_str(), model.fit_seconds());

  v1::PlanResponse response;
  const grpc::Status status = server_->Plan(Request(uploaded.robot_id()), &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  EXPECT_EQ(response.verification().collision_guarantee(), "certified");
  // Every returned state is free for the exact meshes (FCL, a checker of its own).
  const auto scene = ObstacleScene();
  const CollisionChecker exact(ExactMeshUr5(), scene);
  ASSERT_FALSE(exact.uses_fast_path());
  ASSERT_GT(response.trajectory().points_size(), 10);
  for (const v1::TrajectoryPoint& point : response.trajectory().points()) {
    Eigen::VectorXd q(point.positions_size());
    for (int i = 0; i < q.size(); ++i) q[i] = point.positions(i);
    EXPECT_FALSE(exact.Check(q).in_collision) << "t = " << point.time_from_start();
  }
}

TEST_F(MeshRobot, ExactMeshesKeepTheMeshesAndCheckThemAtDiscreteStates) {
  const v1::UploadRobotResponse uploaded = Upload(true);
  EXPECT_EQ(uploaded.collision_model().kind(), "shapes");
  EXPECT_EQ(uploaded.collision_model().spheres(), 0);
  EXPECT_NE(uploaded.robot_id(), Upload(false).robot_id());
  v1::PlanResponse response;
  const grpc::Status status = server_->Plan(Request(uploaded.robot_id()), &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  EXPECT_EQ(response.verification().collision_guarantee(), "discrete");
}

// A start free on the meshes but within the fitted spheres' reach of an obstacle is planned on
// the exact meshes (said in a warning) rather than refused as START_IN_COLLISION; a start that
// collides with the meshes themselves still is refused.
TEST_F(MeshRobot, AStartTouchingOnlyTheFittedSpheresIsPlannedOnTheExactMeshes) {
  const v1::UploadRobotResponse uploaded = Upload(false);
  const auto exact_robot = ExactMeshUr5();
  const auto scene = ObstacleScene();
  const CollisionChecker exact(exact_robot, scene);
  const CollisionChecker fitted(FitRobotSpheres(*exact_robot).model, scene);
  std::mt19937_64 rng(5);
  Eigen::VectorXd start(6), inside(6);
  bool found_start = false, found_inside = false;
  for (int tries = 0; tries < 200000 && !(found_start && found_inside); ++tries) {
    Eigen::VectorXd q(6);
    for (int i = 0; i < 6; ++i) q[i] = std::uniform_real_distribution<double>(-M_PI, M_PI)(rng);
    const bool exact_free = exact.IsValid(q);
    if (!found_start && exact_free && !fitted.IsValid(q) && !exact.Check(q).self_collision &&
        !fitted.Check(q).self_collision) {
      start = q;
      found_start = true;
    }
    if (!found_inside && !exact_free && !exact.Check(q).self_collision) {
      inside = q;
      found_inside = true;
    }
  }
  ASSERT_TRUE(found_start && found_inside);
  v1::PlanRequest request = Request(uploaded.robot_id());
  for (int i = 0; i < 6; ++i) request.mutable_start()->set_positions(i, start[i]);
  request.set_time_budget(10.0);
  v1::PlanResponse response;
  grpc::Status status = server_->Plan(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  EXPECT_EQ(response.verification().collision_guarantee(), "discrete");
  ASSERT_EQ(response.warnings_size(), 1);
  EXPECT_NE(response.warnings(0).find("start collides only with the fitted spheres, which reach up to"),
            std::string::npos)
      << response.warnings(0);
  EXPECT_NE(response.warnings(0).find("planned on the exact meshes instead"), std::string::npos);
  for (const v1::TrajectoryPoint& point : response.trajectory().points()) {
    Eigen::VectorXd q(point.positions_size());
    for (int i = 0; i < q.size(); ++i) q[i] = point.positions(i);
    EXPECT_FALSE(exact.Check(q).in_collision) << "t = " << point.time_from_start();
  }

  for (int i = 0; i < 6; ++i) request.mutable_start()->set_positions(i, inside[i]);
  status = server_->Plan(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.outcome(), v1::START_IN_COLLISION) << response.message();
  EXPECT_EQ(response.warnings_size(), 0);
}

}  // namespace
}  // namespace chasles::testing
