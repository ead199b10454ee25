// Several replicas, one service (issue 15, item 1): servers started with --store redis://… share
// uploaded robots and scenes (any replica resolves any id) and workcells with their reservations.
// A real redis-server is started here on loopback (redis_fixture.h). Two replicas committing
// conflicting trajectories at the same moment: exactly one wins, every time, and the other is
// told the conflict. Replicas and Redis (append-only file) restarted: nothing is lost.

#include <atomic>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "chasles/robot/error.h"
#include "redis_fixture.h"
#include "server_fixture.h"

namespace chasles::testing {
namespace {

ServerOptions SharedOptions(const std::string& url) {
  ServerOptions options = LoopbackServer::QuietOptions(2);
  options.store = url;
  return options;
}

template <typename Request, typename Response, typename Method>
grpc::Status Call(LoopbackServer& server, const Request& request, Response* response, Method method) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  return (server.stub().*method)(&context, request, response);
}

std::string UploadPanda(LoopbackServer& server) {
  v1::UploadRobotRequest upload;
  upload.mutable_robot()->mutable_urdf()->set_urdf(ReadText(ExamplePath("robots/panda.urdf")));
  upload.mutable_robot()->mutable_urdf()->set_srdf(ReadText(ExamplePath("robots/panda.srdf")));
  v1::UploadRobotResponse uploaded;
  const grpc::Status status = Call(server, upload, &uploaded, &v1::Planning::Stub::UploadRobot);
  EXPECT_TRUE(status.ok()) << status.error_message();
  return uploaded.robot_id();
}

/// panda_table's start and goal, for the robot and scene given by id.
v1::PlanRequest PlanById(const std::string& robot_id, const std::string& scene_id) {
  v1::PlanRequest request = LoadRequest("panda_table");
  request.set_robot_id(robot_id);
  if (!scene_id.empty()) request.set_scene_id(scene_id);
  return request;
}

v1::CommitTrajectoryRequest CommitOf(const std::string& workcell, const std::string& robot, const std::string& robot_id,
                                     const v1::JointTrajectory& trajectory, double start_time) {
  v1::CommitTrajectoryRequest commit;
  commit.set_workcell(workcell);
  commit.set_robot_name(robot);
  commit.set_robot_id(robot_id);
  *commit.mutable_trajectory() = trajectory;
  commit.set_start_time(start_time);
  commit.set_hold(3600.0);
  return commit;
}

bool Create(LoopbackServer& server, const std::string& name, v1::CreateWorkcellResponse* created) {
  v1::CreateWorkcellRequest create;
  create.set_name(name);
  const grpc::Status status = Call(server, create, created, &v1::Planning::Stub::CreateWorkcell);
  EXPECT_TRUE(status.ok()) << status.error_message();
  return status.ok();
}

TEST(SharedStore, AnyReplicaResolvesWhatAnotherStored) {
  RedisServer redis;
  LoopbackServer a(SharedOptions(redis.url())), b(SharedOptions(redis.url()));
  const std::string robot_id = UploadPanda(a);
  v1::UploadSceneRequest upload_scene;
  *upload_scene.mutable_scene() = LoadScene("shelf");
  v1::UploadSceneResponse scene;
  ASSERT_TRUE(Call(a, upload_scene, &scene, &v1::Planning::Stub::UploadScene).ok());

  v1::PlanResponse planned;
  grpc::Status status = b.Plan(PlanById(robot_id, scene.scene_id()), &planned);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(planned.robot_id(), robot_id);
  EXPECT_EQ(planned.scene_id(), scene.scene_id());
  // A replica on the memory store does not know them.
  LoopbackServer alone(LoopbackServer::QuietOptions(2));
  status = alone.Plan(PlanById(robot_id, ""), &planned);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::NOT_FOUND) << status.error_message();

  // A workcell created on one replica exists on the other.
  v1::CreateWorkcellResponse created;
  ASSERT_TRUE(Create(a, "shared_cell", &created));
  EXPECT_TRUE(created.created());
  ASSERT_TRUE(Create(b, "shared_cell", &created));
  EXPECT_FALSE(created.created());
}

TEST(SharedStore, ConflictingCommitsOnTwoReplicasOneWinsEveryTime) {
  RedisServer redis;
  LoopbackServer a(SharedOptions(redis.url())), b(SharedOptions(redis.url()));
  const std::string robot_id = UploadPanda(a);
  v1::PlanResponse planned;
  ASSERT_TRUE(a.Plan(PlanById(robot_id, ""), &planned).ok());
  ASSERT_EQ(planned.outcome(), v1::SUCCESS);
  const double start = 4.0e9;  // far ahead: nothing expires during the test
  int a_won = 0, b_won = 0;
  for (int round = 0; round < 100; ++round) {
    const std::string cell = "race" + std::to_string(round);
    v1::CreateWorkcellResponse created;
    ASSERT_TRUE(Create(a, cell, &created));
    // Two robots of the same model at the same place and time: their trajectories conflict.
    const v1::CommitTrajectoryRequest left = CommitOf(cell, "left", robot_id, planned.trajectory(), start);
    const v1::CommitTrajectoryRequest right = CommitOf(cell, "right", robot_id, planned.trajectory(), start);
    std::atomic<int> ready{0};
    grpc::Status status_a, status_b;
    v1::CommitTrajectoryResponse response_a, response_b;
    std::thread ta([&] {
      ++ready;
      while (ready.load() < 2) {
      }
      status_a = Call(a, left, &response_a, &v1::Planning::Stub::CommitTrajectory);
    });
    std::thread tb([&] {
      ++ready;
      while (ready.load() < 2) {
      }
      status_b = Call(b, right, &response_b, &v1::Planning::Stub::CommitTrajectory);
    });
    ta.join();
    tb.join();
    ASSERT_NE(status_a.ok(), status_b.ok()) << "round " << round << ": a: " << status_a.error_message()
                                            << " b: " << status_b.error_message();
    const grpc::Status& lost = status_a.ok() ? status_b : status_a;
    EXPECT_EQ(lost.error_code(), grpc::StatusCode::FAILED_PRECONDITION) << lost.error_message();
    EXPECT_NE(lost.error_message().find("conflicts with a committed one"), std::string::npos) << lost.error_message();
    (status_a.ok() ? a_won : b_won) += 1;
    // Both replicas see the one reservation.
    ASSERT_TRUE(Create(b, cell, &created));
    EXPECT_EQ(created.active_reservations(), 1u);
  }
  std::cout << "[ race     ] 100 rounds: replica a won " << a_won << ", replica b " << b_won << "\n";
  EXPECT_EQ(a_won + b_won, 100);
}

TEST(SharedStore, RestartedReplicasAndRedisLoseNothing) {
  RedisServer redis;
  std::string robot_id;
  v1::PlanResponse planned;
  {
    LoopbackServer a(SharedOptions(redis.url()));
    robot_id = UploadPanda(a);
    ASSERT_TRUE(a.Plan(PlanById(robot_id, ""), &planned).ok());
    v1::CreateWorkcellResponse created;
    ASSERT_TRUE(Create(a, "kept", &created));
    v1::CommitTrajectoryResponse committed;
    const grpc::Status status =
        Call(a, CommitOf("kept", "left", robot_id, planned.trajectory(), 4.0e9), &committed,
             &v1::Planning::Stub::CommitTrajectory);
    ASSERT_TRUE(status.ok()) << status.error_message();
  }  // the replica stops
  redis.Kill();   // SIGKILL: no shutdown save
  redis.Start();  // reads its append-only file back
  LoopbackServer c(SharedOptions(redis.url()));
  v1::CreateWorkcellResponse created;
  ASSERT_TRUE(Create(c, "kept", &created));
  EXPECT_FALSE(created.created());
  EXPECT_EQ(created.active_reservations(), 1u);
  v1::PlanResponse again;
  grpc::Status status = c.Plan(PlanById(robot_id, ""), &again);
  ASSERT_TRUE(status.ok()) << status.error_message();
  v1::CommitTrajectoryResponse committed;
  status = Call(c, CommitOf("kept", "right", robot_id, planned.trajectory(), 4.0e9), &committed,
                &v1::Planning::Stub::CommitTrajectory);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION) << status.error_message();
  EXPECT_NE(status.error_message().find("kept/1"), std::string::npos) << status.error_message();
}

TEST(SharedStore, ABadOrUnreachableStoreIsANamedError) {
  EXPECT_THROW(ParseRedisUrl("http://x"), Error);
  EXPECT_EQ(ParseRedisUrl("redis://db.example:6380/2").text(), "redis://db.example:6380/2");
  try {
    ParseRedisUrl("redis://host:99999");
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "--store = 'redis://host:99999': the port must be a number in [1, 65535]");
  }
  const int port = FreeLoopbackPort();  // nobody listens there
  try {
    PlanningServer server(SharedOptions("redis://127.0.0.1:" + std::to_string(port)));
    ADD_FAILURE() << "a server started on an unreachable store";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kUnavailable);
    EXPECT_NE(std::string(e.what()).find("redis://127.0.0.1:" + std::to_string(port)), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace chasles::testing
