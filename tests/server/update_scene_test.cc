// The UpdateScene RPC: point clouds inserted into a stored scene's OctoMap answer a new,
// deterministic scene id that Plan accepts; invalid updates fail with the field named; and the
// `chasles update-scene` CLI.
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "chasles/robot/robot_model.h"
#include "server_fixture.h"

namespace chasles::testing {
namespace {

class UpdateSceneTest : public SharedServerTest<> {
 protected:
  static grpc::Status Update(const v1::UpdateSceneRequest& request, v1::UpdateSceneResponse* response) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
    return server_->stub().UpdateScene(&context, request, response);
  }

  static void AddPoint(v1::UpdateSceneRequest* request, const Eigen::Vector3d& p) {
    request->add_points(p.x());
    request->add_points(p.y());
    request->add_points(p.z());
  }

  static void SetOrigin(v1::UpdateSceneRequest* request, double x, double y, double z) {
    request->mutable_sensor_origin()->set_x(x);
    request->mutable_sensor_origin()->set_y(y);
    request->mutable_sensor_origin()->set_z(z);
  }

  /// Points at the link origins of the Panda's start configuration in panda_table.json (inside
  /// its collision spheres), seen from a sensor in front of the robot.
  static v1::UpdateSceneRequest PointsOnTheArm() {
    const auto panda = RobotModel::FromUrdf(ReadText(ExamplePath("robots/panda.urdf")),
                                            ReadText(ExamplePath("robots/panda.srdf")));
    const v1::PlanRequest plan = LoadRequest("panda_table");
    Eigen::VectorXd q(plan.start().positions_size());
    for (int i = 0; i < q.size(); ++i) q[i] = plan.start().positions(i);
    std::vector<Eigen::Isometry3d> poses;
    panda->ForwardKinematics(q, &poses);
    v1::UpdateSceneRequest request;
    for (std::size_t l = 3; l < poses.size(); ++l) AddPoint(&request, poses[l].translation());
    SetOrigin(&request, 1.5, 0.0, 1.0);
    return request;
  }

  /// A 1.1 m × 1.0 m wall of points 1.4 m in front of the robot (out of its reach).
  static v1::UpdateSceneRequest WallInFront() {
    v1::UpdateSceneRequest request;
    for (int j = -5; j <= 5; ++j) {
      for (int k = 0; k <= 10; ++k) AddPoint(&request, Eigen::Vector3d(1.4, 0.1 * j, 0.1 * k));
    }
    SetOrigin(&request, 0.0, 0.0, 1.5);
    return request;
  }
};

TEST_F(UpdateSceneTest, PointsOnTheArmMakeTheStartCollideInPlanByTheNewId) {
  // The default scene (the table, no OctoMap) gets a new map "points".
  const v1::UpdateSceneRequest request = PointsOnTheArm();
  v1::UpdateSceneResponse response;
  const grpc::Status status = Update(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.scene_id().size(), 32u);
  EXPECT_EQ(response.octomap(), "points");
  EXPECT_EQ(response.points_inserted(), static_cast<std::uint64_t>(request.points_size() / 3));
  EXPECT_GT(response.occupied_leaves(), 0u);
  EXPECT_LE(response.occupied_leaves(), response.points_inserted());
  EXPECT_DOUBLE_EQ(response.resolution(), 0.05);
  EXPECT_GE(response.seconds(), 0.0);

  v1::PlanRequest plan = LoadRequest("panda_table");
  v1::PlanResponse before;
  ASSERT_TRUE(server_->Plan(plan, &before).ok());
  EXPECT_EQ(before.outcome(), v1::SUCCESS) << before.message();

  plan.set_scene_id(response.scene_id());
  v1::PlanResponse after;
  const grpc::Status planned = server_->Plan(plan, &after);
  ASSERT_TRUE(planned.ok()) << planned.error_message();
  EXPECT_EQ(after.outcome(), v1::START_IN_COLLISION) << after.message();
  // The message names the voxel the arm touches, in metres (issue 22, item 2).
  EXPECT_NE(after.message().find("touches 'points' (the voxel centred at ("), std::string::npos) << after.message();
  EXPECT_NE(after.message().find(" m)"), std::string::npos) << after.message();
  EXPECT_EQ(after.scene_id(), response.scene_id());
  EXPECT_NE(after.scene_id(), before.scene_id());
}

TEST_F(UpdateSceneTest, PlanAroundACloudInFrontSucceedsAndUpdatesChain) {
  v1::UpdateSceneResponse wall;
  ASSERT_TRUE(Update(WallInFront(), &wall).ok());
  v1::PlanRequest plan = LoadRequest("panda_table");
  plan.set_scene_id(wall.scene_id());
  v1::PlanResponse response;
  ASSERT_TRUE(server_->Plan(plan, &response).ok());
  EXPECT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  EXPECT_EQ(response.scene_id(), wall.scene_id());

  // A second update of the updated scene goes into the same map ("points", the only one).
  v1::UpdateSceneRequest more = PointsOnTheArm();
  more.set_scene_id(wall.scene_id());
  v1::UpdateSceneResponse chained;
  ASSERT_TRUE(Update(more, &chained).ok());
  EXPECT_EQ(chained.octomap(), "points");
  EXPECT_NE(chained.scene_id(), wall.scene_id());
  EXPECT_GT(chained.occupied_leaves(), wall.occupied_leaves());
  plan.set_scene_id(chained.scene_id());
  ASSERT_TRUE(server_->Plan(plan, &response).ok());
  EXPECT_EQ(response.outcome(), v1::START_IN_COLLISION) << response.message();
}

TEST_F(UpdateSceneTest, SameUpdateOfTheSameSceneGivesTheSameId) {
  v1::UpdateSceneResponse a, b, c, d;
  const v1::UpdateSceneRequest request = WallInFront();
  ASSERT_TRUE(Update(request, &a).ok());
  ASSERT_TRUE(Update(request, &b).ok());
  EXPECT_EQ(a.scene_id(), b.scene_id());
  EXPECT_EQ(a.occupied_leaves(), b.occupied_leaves());

  v1::UpdateSceneRequest other = request;
  other.set_max_range(1.0);  // cuts every ray before the wall: nothing occupied
  ASSERT_TRUE(Update(other, &c).ok());
  EXPECT_NE(c.scene_id(), a.scene_id());
  EXPECT_EQ(c.occupied_leaves(), 0u);

  // Naming the default scene by its id is the same update as leaving scene_id empty.
  v1::PlanResponse plan;
  ASSERT_TRUE(server_->Plan(LoadRequest("panda_table"), &plan).ok());
  v1::UpdateSceneRequest by_id = request;
  by_id.set_scene_id(plan.scene_id());
  ASSERT_TRUE(Update(by_id, &d).ok());
  EXPECT_EQ(d.scene_id(), a.scene_id());
}

TEST_F(UpdateSceneTest, UploadedOctoMapSceneUpdatesItsOnlyMap) {
  v1::UploadSceneRequest upload;
  *upload.mutable_scene() = LoadScene("shelf_octomap");
  v1::UploadSceneResponse uploaded;
  {
    grpc::ClientContext context;
    ASSERT_TRUE(server_->stub().UploadScene(&context, upload, &uploaded).ok());
  }
  v1::UpdateSceneRequest request = WallInFront();
  request.set_scene_id(uploaded.scene_id());
  request.set_resolution(0.2);  // only for new maps
  v1::UpdateSceneResponse response;
  const grpc::Status status = Update(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.octomap(), upload.scene().octomaps(0).name());
  EXPECT_DOUBLE_EQ(response.resolution(), 0.02);

  request.set_octomap("lidar");
  const grpc::Status unknown = Update(request, &response);
  EXPECT_EQ(unknown.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_EQ(unknown.error_message(), "octomap = 'lidar' names no OctoMap of the scene (its maps: '" +
                                         upload.scene().octomaps(0).name() + "')");
}

TEST_F(UpdateSceneTest, InvalidUpdatesNameTheField) {
  struct Case {
    std::function<void(v1::UpdateSceneRequest*)> edit;
    grpc::StatusCode code;
    std::string message;
  };
  const std::vector<Case> cases = {
      {[](v1::UpdateSceneRequest* r) { r->add_points(1.0); }, grpc::StatusCode::INVALID_ARGUMENT,
       "points has 4 values, must be a multiple of 3 (x, y, z triples)"},
      {[](v1::UpdateSceneRequest* r) {
         for (double v : {1.0, 0.1, std::nan("")}) r->add_points(v);
       },
       grpc::StatusCode::INVALID_ARGUMENT, "points[5] = nan must be finite (point 1, z)"},
      {[](v1::UpdateSceneRequest* r) { r->set_max_range(-1.0); }, grpc::StatusCode::INVALID_ARGUMENT,
       "max_range = -1 must be finite and >= 0 (0 = unlimited)"},
      {[](v1::UpdateSceneRequest* r) { r->set_resolution(20.0); }, grpc::StatusCode::INVALID_ARGUMENT,
       "resolution = 20 must be within [0.001, 10] (0 = 0.05)"},
      {[](v1::UpdateSceneRequest* r) { r->mutable_sensor_origin()->set_y(std::nan("")); },
       grpc::StatusCode::INVALID_ARGUMENT, "sensor_origin.y = nan must be finite"},
      {[](v1::UpdateSceneRequest* r) { r->set_octomap("lidar"); }, grpc::StatusCode::NOT_FOUND,
       "octomap = 'lidar' names no OctoMap of the scene (it has none; leave octomap empty to create a new map "
       "'points')"},
  };
  for (const Case& c : cases) {
    v1::UpdateSceneRequest request;  // one valid point, then the edit
    for (double v : {1.0, 0.0, 0.5}) request.add_points(v);
    c.edit(&request);
    v1::UpdateSceneResponse response;
    const grpc::Status status = Update(request, &response);
    EXPECT_EQ(status.error_code(), c.code) << status.error_message();
    EXPECT_EQ(status.error_message(), c.message);
  }

  v1::UpdateSceneRequest unknown = WallInFront();
  unknown.set_scene_id("0123456789abcdef0123456789abcdef");
  v1::UpdateSceneResponse response;
  const grpc::Status status = Update(unknown, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_NE(status.error_message().find("scene_id '0123456789abcdef0123456789abcdef' is not stored"),
            std::string::npos)
      << status.error_message();
}

// --- CLI ---------------------------------------------------------------------------------------

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr
};

CommandResult RunCli(const std::string& arguments) {
  static int calls = 0;
  const std::string log = ::testing::TempDir() + "/chasles_update_scene_cli_" + std::to_string(::getpid()) + "_" +
                          std::to_string(calls++) + ".txt";
  const std::string command = std::string(CHASLES_CLI) + " " + arguments + " > " + log + " 2>&1";
  const int raw = std::system(command.c_str());
  CommandResult result;
  result.exit_code = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  result.output = ReadText(log);
  std::remove(log.c_str());
  return result;
}

TEST_F(UpdateSceneTest, CliUpdateSceneTextAndJsonPointFiles) {
  const std::string at = "--server " + server_->address() + " ";
  // The same points as a text file and as a JSON list give the same id as the RPC.
  const v1::UpdateSceneRequest request = WallInFront();
  v1::UpdateSceneResponse rpc;
  ASSERT_TRUE(Update(request, &rpc).ok());
  const std::string text = ::testing::TempDir() + "/chasles_update_scene_points.txt";
  const std::string json = ::testing::TempDir() + "/chasles_update_scene_points.json";
  {
    std::ofstream t(text);
    std::ofstream j(json);
    t << "# x y z [m]\n";
    j << "[";
    char line[128];
    for (int i = 0; i < request.points_size(); i += 3) {
      std::snprintf(line, sizeof(line), "%.17g %.17g %.17g", request.points(i), request.points(i + 1),
                    request.points(i + 2));
      t << line << "\n";
      std::snprintf(line, sizeof(line), "%s[%.17g, %.17g, %.17g]", i == 0 ? "" : ", ", request.points(i),
                    request.points(i + 1), request.points(i + 2));
      j << line;
    }
    j << "]\n";
  }
  for (const std::string& file : {text, json}) {
    CommandResult result = RunCli(at + "update-scene --points " + file + " --origin 0,0,1.5");
    EXPECT_EQ(result.exit_code, 0) << result.output;
    EXPECT_NE(result.output.find("scene_id " + rpc.scene_id()), std::string::npos) << result.output;
    EXPECT_NE(result.output.find("octomap  points"), std::string::npos) << result.output;
    EXPECT_NE(result.output.find("121 inserted"), std::string::npos) << result.output;
  }

  CommandResult chained = RunCli(at + "update-scene --scene-id " + rpc.scene_id() +
                                 " --octomap points --points " + text + " --origin 0,0,1.5 --max-range 1");
  EXPECT_EQ(chained.exit_code, 0) << chained.output;
  EXPECT_EQ(chained.output.find("scene_id " + rpc.scene_id()), std::string::npos) << chained.output;

  // Server-side rejection reaches stderr; bad arguments exit 2 naming the problem.
  CommandResult rejected = RunCli(at + "update-scene --points " + text + " --origin 0,0,1.5 --max-range -1");
  EXPECT_EQ(rejected.exit_code, 1) << rejected.output;
  EXPECT_NE(rejected.output.find("INVALID_ARGUMENT: max_range = -1"), std::string::npos) << rejected.output;
  CommandResult no_origin = RunCli(at + "update-scene --points " + text);
  EXPECT_EQ(no_origin.exit_code, 2) << no_origin.output;
  EXPECT_NE(no_origin.output.find("--origin"), std::string::npos) << no_origin.output;
  const std::string bad = ::testing::TempDir() + "/chasles_update_scene_bad.txt";
  std::ofstream(bad) << "1 2 3\n4 5\n";
  CommandResult short_line = RunCli(at + "update-scene --points " + bad + " --origin 0,0,0");
  EXPECT_EQ(short_line.exit_code, 2) << short_line.output;
  EXPECT_NE(short_line.output.find("line 2 has 2 values"), std::string::npos) << short_line.output;
}

}  // namespace
}  // namespace chasles::testing
