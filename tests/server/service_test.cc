// The Planning service beyond single requests: uploads and ids, deadlines, cancellation,
// determinism, concurrency, and the `chasles` CLI against an in-process server.
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <future>
#include <string>
#include <thread>
#include <vector>


#include <gtest/gtest.h>

#include "server_fixture.h"

namespace chasles::testing {
namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

TEST(Upload, SameContentSameIdThenPlanById) {
  LoopbackServer server;
  const v1::PlanRequest inline_request = LoadRequest("ur5_shelf");

  v1::UploadRobotRequest robot_upload;
  *robot_upload.mutable_robot() = inline_request.robot();
  v1::UploadRobotResponse robot_a, robot_b;
  {
    grpc::ClientContext context;
    ASSERT_TRUE(server.stub().UploadRobot(&context, robot_upload, &robot_a).ok());
  }
  {
    grpc::ClientContext context;
    ASSERT_TRUE(server.stub().UploadRobot(&context, robot_upload, &robot_b).ok());
  }
  EXPECT_EQ(robot_a.robot_id().size(), 32u);
  EXPECT_EQ(robot_a.robot_id(), robot_b.robot_id());
  ASSERT_EQ(robot_a.joint_names_size(), 6);
  EXPECT_EQ(robot_a.joint_names(0), "shoulder_pan_joint");
  ASSERT_EQ(robot_a.velocity_limits_size(), 6);
  EXPECT_GT(robot_a.velocity_limits(0), 0.0);
  EXPECT_LT(robot_a.lower_limits(2), robot_a.upper_limits(2));

  v1::UploadSceneRequest scene_upload;
  *scene_upload.mutable_scene() = inline_request.scene();
  v1::UploadSceneResponse scene_a, scene_b;
  {
    grpc::ClientContext context;
    ASSERT_TRUE(server.stub().UploadScene(&context, scene_upload, &scene_a).ok());
  }
  {
    grpc::ClientContext context;
    ASSERT_TRUE(server.stub().UploadScene(&context, scene_upload, &scene_b).ok());
  }
  EXPECT_EQ(scene_a.scene_id(), scene_b.scene_id());
  EXPECT_NE(scene_a.scene_id(), robot_a.robot_id());

  // A different scene gets a different id.
  v1::UploadSceneRequest other = scene_upload;
  other.mutable_scene()->mutable_boxes(0)->mutable_size()->set_x(other.scene().boxes(0).size().x() + 0.01);
  v1::UploadSceneResponse scene_c;
  {
    grpc::ClientContext context;
    ASSERT_TRUE(server.stub().UploadScene(&context, other, &scene_c).ok());
  }
  EXPECT_NE(scene_c.scene_id(), scene_a.scene_id());

  // Plan by id, then inline: the same ids come back and the same trajectory.
  v1::PlanRequest by_id = inline_request;
  by_id.set_robot_id(robot_a.robot_id());
  by_id.set_scene_id(scene_a.scene_id());
  v1::PlanResponse by_id_response, inline_response;
  ASSERT_TRUE(server.Plan(by_id, &by_id_response).ok());
  EXPECT_EQ(by_id_response.outcome(), v1::SUCCESS) << by_id_response.message();
  EXPECT_EQ(by_id_response.robot_id(), robot_a.robot_id());
  EXPECT_EQ(by_id_response.scene_id(), scene_a.scene_id());
  ASSERT_TRUE(server.Plan(inline_request, &inline_response).ok());
  EXPECT_EQ(inline_response.robot_id(), robot_a.robot_id());
  EXPECT_EQ(inline_response.scene_id(), scene_a.scene_id());
  EXPECT_EQ(inline_response.trajectory().points_size(), by_id_response.trajectory().points_size());
}

TEST(Defaults, RequestWithoutRobotOrSceneUsesTheEmbeddedPandaAndTable) {
  LoopbackServer server;
  v1::PlanRequest request = LoadRequest("panda_table");
  ASSERT_EQ(request.robot_source_case(), v1::PlanRequest::ROBOT_SOURCE_NOT_SET);
  ASSERT_EQ(request.scene_source_case(), v1::PlanRequest::SCENE_SOURCE_NOT_SET);
  request.clear_request_id();
  v1::PlanResponse response;
  ASSERT_TRUE(server.Plan(request, &response).ok());
  EXPECT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  EXPECT_FALSE(response.request_id().empty());  // generated
  ASSERT_EQ(response.trajectory().joint_names_size(), 7);
  EXPECT_EQ(response.trajectory().joint_names(0), "panda_joint1");

  // The default scene's id is the id of examples/scenes/table.json uploaded.
  v1::UploadSceneRequest upload;
  *upload.mutable_scene() = LoadScene("table");
  v1::UploadSceneResponse uploaded;
  grpc::ClientContext context;
  ASSERT_TRUE(server.stub().UploadScene(&context, upload, &uploaded).ok());
  EXPECT_EQ(uploaded.scene_id(), response.scene_id());
}

TEST(Deadline, ShortDeadlineOnAnOptimizingPlannerReturnsPromptly) {
  LoopbackServer server;
  v1::PlanRequest request = LoadRequest("panda_shelf");
  request.mutable_planner()->set_planner_id("rrt_star");
  request.set_time_budget(60.0);
  v1::PlanResponse response;
  const auto start = Clock::now();
  const grpc::Status status = server.Plan(request, &response, /*deadline_s=*/0.5);
  const double elapsed = SecondsSince(start);
  EXPECT_TRUE(status.ok() || status.error_code() == grpc::StatusCode::DEADLINE_EXCEEDED)
      << status.error_code() << ": " << status.error_message();
  if (status.ok()) {
    EXPECT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  }
  EXPECT_LT(elapsed, 0.5 + 2.0);  // liveness bound, not a timing claim

  // The worker is free again: a normal request completes.
  v1::PlanRequest quick = LoadRequest("panda_table");
  v1::PlanResponse quick_response;
  ASSERT_TRUE(server.Plan(quick, &quick_response, 20.0).ok());
  EXPECT_EQ(quick_response.outcome(), v1::SUCCESS);
}

TEST(Cancellation, ClientCancelStopsThePlannerAndFreesTheWorker) {
  LoopbackServer server(/*threads=*/1);
  v1::PlanRequest request = LoadRequest("panda_shelf");
  request.mutable_planner()->set_planner_id("rrt_star");
  request.set_time_budget(60.0);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(120));
  v1::PlanResponse response;
  auto call = std::async(std::launch::async, [&] { return server.stub().Plan(&context, request, &response); });
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const auto cancelled_at = Clock::now();
  context.TryCancel();
  const grpc::Status status = call.get();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::CANCELLED) << status.error_message();

  // With one worker, a follow-up request can only finish if the cancelled planner stopped
  // (otherwise it would hold the worker for its 60 s budget).
  v1::PlanRequest quick = LoadRequest("panda_table");
  v1::PlanResponse quick_response;
  const grpc::Status quick_status = server.Plan(quick, &quick_response, /*deadline_s=*/20.0);
  ASSERT_TRUE(quick_status.ok()) << quick_status.error_message();
  EXPECT_EQ(quick_response.outcome(), v1::SUCCESS);
  EXPECT_LT(SecondsSince(cancelled_at), 20.0);
}

TEST(Determinism, SameSeededRequestGivesTheSameTrajectory) {
  LoopbackServer server;
  for (const char* name : {"ur5_shelf", "planar_2r_posts"}) {
    SCOPED_TRACE(name);
    const v1::PlanRequest request = LoadRequest(name);
    v1::PlanResponse first, second;
    ASSERT_TRUE(server.Plan(request, &first).ok());
    ASSERT_TRUE(server.Plan(request, &second).ok());
    ASSERT_EQ(first.outcome(), v1::SUCCESS) << first.message();
    ASSERT_EQ(first.trajectory().points_size(), second.trajectory().points_size());
    ASSERT_EQ(first.path_size(), second.path_size());
    for (int i = 0; i < first.trajectory().points_size(); ++i) {
      const v1::TrajectoryPoint& a = first.trajectory().points(i);
      const v1::TrajectoryPoint& b = second.trajectory().points(i);
      ASSERT_EQ(a.time_from_start(), b.time_from_start()) << "sample " << i;
      for (int j = 0; j < a.positions_size(); ++j) ASSERT_EQ(a.positions(j), b.positions(j)) << "sample " << i;
    }
    EXPECT_EQ(first.statistics().raw_waypoints(), second.statistics().raw_waypoints());
  }
}

TEST(Concurrency, ParallelRequestsAllSucceed) {
  LoopbackServer server(/*threads=*/2);
  std::vector<std::future<bool>> calls;
  const std::vector<std::string> names = {"panda_table", "ur5_table", "planar_2r_table", "panda_cage",
                                          "ur5_cage",    "planar_2r_cage"};
  for (const std::string& name : names) {
    calls.push_back(std::async(std::launch::async, [&server, name] {
      v1::PlanResponse response;
      return server.Plan(LoadRequest(name), &response).ok() && response.outcome() == v1::SUCCESS;
    }));
  }
  for (size_t i = 0; i < calls.size(); ++i) EXPECT_TRUE(calls[i].get()) << names[i];
}

// --- CLI ---------------------------------------------------------------------------------------

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr
};

CommandResult RunCli(const std::string& arguments) {
  // One output file per invocation: ctest runs tests in parallel processes.
  static int calls = 0;
  const std::string log = ::testing::TempDir() + "/chasles_cli_output_" + std::to_string(::getpid()) + "_" +
                          std::to_string(calls++) + ".txt";
  const std::string command = std::string(CHASLES_CLI) + " " + arguments + " > " + log + " 2>&1";
  const int raw = std::system(command.c_str());
  CommandResult result;
  result.exit_code = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  result.output = ReadText(log);
  std::remove(log.c_str());
  return result;
}

TEST(Cli, HealthPlannersPlanAndUploads) {
  LoopbackServer server;
  const std::string at = "--server " + server.address() + " ";

  CommandResult health = RunCli(at + "health");
  EXPECT_EQ(health.exit_code, 0) << health.output;
  EXPECT_NE(health.output.find("SERVING"), std::string::npos) << health.output;

  CommandResult planners = RunCli(at + "planners");
  EXPECT_EQ(planners.exit_code, 0) << planners.output;
  EXPECT_NE(planners.output.find("rrt_connect"), std::string::npos) << planners.output;
  EXPECT_NE(planners.output.find("default"), std::string::npos) << planners.output;
  EXPECT_NE(planners.output.find("robot kinds            arm, planar, free_flyer\n"), std::string::npos) << planners.output;

  const std::string csv = ::testing::TempDir() + "/chasles_cli_panda_table.csv";
  CommandResult plan = RunCli(at + "plan " + ExamplePath("requests/panda_table.json") + " --out " + csv);
  EXPECT_EQ(plan.exit_code, 0) << plan.output;
  EXPECT_NE(plan.output.find("SUCCESS"), std::string::npos) << plan.output;
  const std::string table = ReadText(csv);
  EXPECT_EQ(table.rfind("t,q_panda_joint1,", 0), 0u) << table.substr(0, 200);
  EXPECT_NE(table.find(",qdd_panda_joint7\n"), std::string::npos);

  const std::string json = ::testing::TempDir() + "/chasles_cli_ur5_table.json";
  CommandResult plan_json = RunCli(at + "plan " + ExamplePath("requests/ur5_table.json") + " --out " + json);
  EXPECT_EQ(plan_json.exit_code, 0) << plan_json.output;
  v1::PlanResponse written;
  EXPECT_TRUE(google::protobuf::util::JsonStringToMessage(ReadText(json), &written).ok());
  EXPECT_EQ(written.outcome(), v1::SUCCESS);

  // No trajectory (start in collision): non-zero, reason on stderr.
  v1::PlanRequest colliding = LoadRequest("panda_table");
  colliding.mutable_start()->clear_positions();
  for (double q : {0.0, 1.2, 0.0, -0.5, 0.0, 1.5, 0.785}) colliding.mutable_start()->add_positions(q);
  std::string colliding_json;
  ASSERT_TRUE(google::protobuf::util::MessageToJsonString(colliding, &colliding_json).ok());
  const std::string colliding_path = ::testing::TempDir() + "/chasles_cli_colliding.json";
  std::ofstream(colliding_path) << colliding_json;
  CommandResult no_path = RunCli(at + "plan " + colliding_path);
  EXPECT_EQ(no_path.exit_code, 1) << no_path.output;
  EXPECT_NE(no_path.output.find("START_IN_COLLISION"), std::string::npos) << no_path.output;

  // Missing and unparsable request files name the file.
  CommandResult missing = RunCli(at + "plan /no/such/request.json");
  EXPECT_EQ(missing.exit_code, 2) << missing.output;
  EXPECT_NE(missing.output.find("/no/such/request.json"), std::string::npos) << missing.output;
  const std::string garbage = ::testing::TempDir() + "/chasles_cli_garbage.json";
  std::ofstream(garbage) << "{\"start\": {\"positions\": [1, \"x\"]}}";
  CommandResult unparsable = RunCli(at + "plan " + garbage);
  EXPECT_EQ(unparsable.exit_code, 2) << unparsable.output;
  EXPECT_NE(unparsable.output.find("chasles_cli_garbage.json"), std::string::npos) << unparsable.output;
  EXPECT_NE(unparsable.output.find("start.positions"), std::string::npos) << unparsable.output;

  // Invalid request: the server's INVALID_ARGUMENT message reaches stderr.
  v1::PlanRequest invalid = LoadRequest("panda_table");
  invalid.set_time_budget(-3);
  std::string invalid_json;
  ASSERT_TRUE(google::protobuf::util::MessageToJsonString(invalid, &invalid_json).ok());
  const std::string invalid_path = ::testing::TempDir() + "/chasles_cli_invalid.json";
  std::ofstream(invalid_path) << invalid_json;
  CommandResult rejected = RunCli(at + "plan " + invalid_path);
  EXPECT_EQ(rejected.exit_code, 1) << rejected.output;
  EXPECT_NE(rejected.output.find("INVALID_ARGUMENT"), std::string::npos) << rejected.output;
  EXPECT_NE(rejected.output.find("time_budget"), std::string::npos) << rejected.output;

  CommandResult robot = RunCli(at + "upload-robot " + ExamplePath("robots/ur5.urdf") + " --srdf " +
                               ExamplePath("robots/ur5.srdf"));
  EXPECT_EQ(robot.exit_code, 0) << robot.output;
  EXPECT_NE(robot.output.find("robot_id "), std::string::npos) << robot.output;
  EXPECT_NE(robot.output.find("shoulder_pan_joint"), std::string::npos) << robot.output;

  v1::UploadSceneRequest upload;
  *upload.mutable_scene() = LoadScene("shelf");
  v1::UploadSceneResponse uploaded;
  grpc::ClientContext context;
  ASSERT_TRUE(server.stub().UploadScene(&context, upload, &uploaded).ok());
  CommandResult scene = RunCli(at + "upload-scene " + ExamplePath("scenes/shelf.json"));
  EXPECT_EQ(scene.exit_code, 0) << scene.output;
  EXPECT_NE(scene.output.find("scene_id " + uploaded.scene_id()), std::string::npos) << scene.output;

  // Nothing listening: non-zero.
  CommandResult down = RunCli("--server 127.0.0.1:1 --timeout 1 health");
  EXPECT_NE(down.exit_code, 0) << down.output;
}

/// The samples of two trajectories agree (times and positions; JSON round-trips doubles).
void ExpectSameTrajectory(const v1::JointTrajectory& a, const v1::JointTrajectory& b) {
  ASSERT_EQ(a.points_size(), b.points_size());
  for (int i = 0; i < a.points_size(); ++i) {
    ASSERT_NEAR(a.points(i).time_from_start(), b.points(i).time_from_start(), 1e-12) << "sample " << i;
    ASSERT_EQ(a.points(i).positions_size(), b.points(i).positions_size());
    for (int j = 0; j < a.points(i).positions_size(); ++j) {
      ASSERT_NEAR(a.points(i).positions(j), b.points(i).positions(j), 1e-12) << "sample " << i << " joint " << j;
    }
  }
}

// plan --planner/--budget/--seed/--sample-period/--padding replace the JSON's planner.plannerId,
// timeBudget (3 s in planar_2r_posts.json), seed (7), trajectory.samplePeriod and padding.
// Several replicas in --server (issue 15, item 2a): calls are balanced round-robin over them and
// idempotent ones retried on UNAVAILABLE, so a list whose first replica is down still answers,
// every time; an address that does not resolve is a usage error naming it.
TEST(Cli, SeveralServersBalanceAndSkipOneThatIsDown) {
  LoopbackServer a, b;
  int down = 0;
  {
    LoopbackServer gone;  // a port that was a server's a moment ago
    down = gone.port();
  }
  const std::string list = "--server 127.0.0.1:" + std::to_string(down) + "," + a.address() + ",localhost:" +
                           std::to_string(b.port()) + " ";
  for (int k = 0; k < 4; ++k) {
    const CommandResult planners = RunCli(list + "planners");
    EXPECT_EQ(planners.exit_code, 0) << planners.output;
    EXPECT_NE(planners.output.find("rrt_connect"), std::string::npos) << planners.output;
  }
  const CommandResult plan = RunCli(list + "plan " + ExamplePath("requests/panda_table.json"));
  EXPECT_EQ(plan.exit_code, 0) << plan.output;
  const CommandResult unresolved = RunCli("--server " + a.address() + ",no-such-host.invalid:1 planners");
  EXPECT_EQ(unresolved.exit_code, 2) << unresolved.output;
  EXPECT_NE(unresolved.output.find("--server 'no-such-host.invalid:1' does not resolve"), std::string::npos)
      << unresolved.output;
}

TEST(Cli, PlanOverridesPlannerBudgetSeedAndSamplePeriod) {
  ServerOptions options = LoopbackServer::QuietOptions(2);
  options.max_budget = 1.0;  // planar_2r_posts.json asks for 3 s: it plans only with --budget <= 1
  LoopbackServer server(options);
  const std::string at = "--server " + server.address() + " ";
  const std::string file = ExamplePath("requests/planar_2r_posts.json");

  // --budget sets time_budget: the file's 3 s and --budget 2 exceed the server's maximum.
  CommandResult as_written = RunCli(at + "plan " + file);
  EXPECT_EQ(as_written.exit_code, 1) << as_written.output;
  EXPECT_NE(as_written.output.find("time_budget = 3 s exceeds"), std::string::npos) << as_written.output;
  CommandResult too_long = RunCli(at + "plan " + file + " --budget 2");
  EXPECT_EQ(too_long.exit_code, 1) << too_long.output;
  EXPECT_NE(too_long.output.find("time_budget = 2 s exceeds"), std::string::npos) << too_long.output;

  // --planner sets planner.planner_id: an unknown id is the server's NOT_FOUND naming it.
  CommandResult unknown = RunCli(at + "plan " + file + " --budget 0.8 --planner no_such_planner");
  EXPECT_EQ(unknown.exit_code, 1) << unknown.output;
  EXPECT_NE(unknown.output.find("NOT_FOUND"), std::string::npos) << unknown.output;
  EXPECT_NE(unknown.output.find("no_such_planner"), std::string::npos) << unknown.output;

  // All five: the trajectory is the server's for the request with those fields.
  const std::string json = ::testing::TempDir() + "/chasles_cli_overrides_" + std::to_string(::getpid()) + ".json";
  CommandResult planned = RunCli(at + "plan " + file +
                                 " --planner rrt --budget 0.8 --seed 3 --sample-period 0.05 --padding 0.01 --out " + json);
  ASSERT_EQ(planned.exit_code, 0) << planned.output;
  v1::PlanResponse written;
  ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(ReadText(json), &written).ok());
  std::remove(json.c_str());
  ASSERT_GE(written.trajectory().points_size(), 3);
  EXPECT_NEAR(written.trajectory().points(1).time_from_start() - written.trajectory().points(0).time_from_start(),
              0.05, 1e-9);
  v1::PlanRequest expected = LoadRequest("planar_2r_posts");
  expected.mutable_planner()->set_planner_id("rrt");
  expected.set_time_budget(0.8);
  expected.set_seed(3);
  expected.mutable_trajectory()->set_sample_period(0.05);
  expected.set_padding(0.01);
  v1::PlanResponse direct;
  ASSERT_TRUE(server.Plan(expected, &direct).ok());
  ASSERT_EQ(direct.outcome(), v1::SUCCESS) << direct.message();
  ExpectSameTrajectory(written.trajectory(), direct.trajectory());
  // The padding made a difference: without it the same seed gives another path, or the same
  // path with clearances measured from the unpadded robot.
  expected.set_padding(0.0);
  v1::PlanResponse bare;
  ASSERT_TRUE(server.Plan(expected, &bare).ok());
  ASSERT_EQ(bare.outcome(), v1::SUCCESS) << bare.message();
  EXPECT_TRUE(bare.statistics().path_length() != written.statistics().path_length() ||
              bare.quality().min_clearance() != written.quality().min_clearance())
      << "padding 0.01 and 0 gave the same path length " << bare.statistics().path_length()
      << " and min_clearance " << bare.quality().min_clearance();
  expected.set_padding(0.01);
  // The seed made the difference: the file's seed 7 gives another path.
  expected.set_seed(7);
  v1::PlanResponse seven;
  ASSERT_TRUE(server.Plan(expected, &seven).ok());
  ASSERT_EQ(seven.outcome(), v1::SUCCESS) << seven.message();
  EXPECT_NE(seven.statistics().path_length(), written.statistics().path_length());
}

// A bad value is a usage error (exit 2) naming the flag, the value and the rule, before any RPC.
TEST(Cli, PlanOverrideValuesAreValidated) {
  const std::string file = ExamplePath("requests/panda_table.json");
  const struct {
    const char* flags;
    const char* expected;
  } cases[] = {
      {"--budget 0", "--budget '0' must be a number of seconds in (0, 600]"},
      {"--budget 601", "--budget '601' must be a number of seconds in (0, 600]"},
      {"--budget soon", "--budget 'soon' must be a number of seconds in (0, 600]"},
      {"--budget nan", "--budget 'nan' must be a number of seconds in (0, 600]"},
      {"--seed -1", "--seed '-1' must be a whole number in [0, 18446744073709551615]"},
      {"--seed 1.5", "--seed '1.5' must be a whole number"},
      {"--seed 18446744073709551616", "--seed '18446744073709551616' must be a whole number"},
      {"--sample-period 0.00001", "--sample-period '0.00001' must be a number of seconds in [0.0001, 1]"},
      {"--sample-period 2", "--sample-period '2' must be a number of seconds in [0.0001, 1]"},
      {"--padding -0.01", "--padding '-0.01' must be a number of metres in [0, 0.5]"},
      {"--padding 0.6", "--padding '0.6' must be a number of metres in [0, 0.5]"},
      {"--planner ''", "--planner '' must be a planner id"},
      {"--seed", "--seed needs a value"},
  };
  for (const auto& c : cases) {
    // Nothing listens on port 1: a usage error must come before any call.
    CommandResult result = RunCli("--server 127.0.0.1:1 plan " + file + " " + c.flags);
    EXPECT_EQ(result.exit_code, 2) << c.flags << "\n" << result.output;
    EXPECT_NE(result.output.find(c.expected), std::string::npos) << c.flags << "\n" << result.output;
  }
  // The flags belong to plan (and import-moveit), not to other commands.
  CommandResult elsewhere = RunCli("--server 127.0.0.1:1 optimize " + file + " --seed 3");
  EXPECT_EQ(elsewhere.exit_code, 2) << elsewhere.output;
  EXPECT_NE(elsewhere.output.find("belong to plan and import-moveit, not optimize"), std::string::npos)
      << elsewhere.output;
}

TEST(Cli, IkPoseGoalAndDhPoeUploads) {
  LoopbackServer server;
  const std::string at = "--server " + server.address() + " ";

  CommandResult ik = RunCli(at + "ik " + ExamplePath("requests/ik_ur5.json"));
  EXPECT_EQ(ik.exit_code, 0) << ik.output;
  EXPECT_NE(ik.output.find("solved      yes"), std::string::npos) << ik.output;
  EXPECT_NE(ik.output.find("solution 0"), std::string::npos) << ik.output;
  EXPECT_NE(ik.output.find("manipulability"), std::string::npos) << ik.output;

  // Unreachable: OK response without solutions, exit 1 with the reason.
  v1::InverseKinematicsRequest far;
  ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(ReadText(ExamplePath("requests/ik_panda.json")), &far).ok());
  far.mutable_pose()->mutable_position()->set_z(4.0);
  far.set_time_budget(0.05);
  std::string far_json;
  ASSERT_TRUE(google::protobuf::util::MessageToJsonString(far, &far_json).ok());
  const std::string far_path = ::testing::TempDir() + "/chasles_cli_ik_far.json";
  std::ofstream(far_path) << far_json;
  CommandResult unsolved = RunCli(at + "ik " + far_path);
  EXPECT_EQ(unsolved.exit_code, 1) << unsolved.output;
  EXPECT_NE(unsolved.output.find("solved      no"), std::string::npos) << unsolved.output;

  CommandResult pose = RunCli(at + "plan " + ExamplePath("requests/panda_pose_table.json"));
  EXPECT_EQ(pose.exit_code, 0) << pose.output;
  EXPECT_NE(pose.output.find("reached     ["), std::string::npos) << pose.output;

  // A Cartesian move: the whole rectangle, timed; --out writes the trajectory as CSV.
  const std::string cartesian_csv = ::testing::TempDir() + "/chasles_cli_cartesian.csv";
  CommandResult cartesian =
      RunCli(at + "cartesian " + ExamplePath("requests/cartesian_panda_table.json") + " --out " + cartesian_csv);
  EXPECT_EQ(cartesian.exit_code, 0) << cartesian.output;
  EXPECT_NE(cartesian.output.find("stop        COMPLETE"), std::string::npos) << cartesian.output;
  EXPECT_NE(cartesian.output.find("fraction    1.0000"), std::string::npos) << cartesian.output;
  EXPECT_NE(cartesian.output.find("timed       SUCCESS"), std::string::npos) << cartesian.output;
  EXPECT_GT(ReadText(cartesian_csv).size(), 1000u);
  // Ended early (a line out of reach): the partial path is reported, exit 1 with the reason.
  v1::CartesianPathRequest reach;
  ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(
                  ReadText(ExamplePath("requests/cartesian_panda_table.json")), &reach)
                  .ok());
  reach.mutable_waypoints(0)->mutable_position()->set_y(2.0);
  reach.set_max_joint_jump(6.0);
  std::string reach_json;
  ASSERT_TRUE(google::protobuf::util::MessageToJsonString(reach, &reach_json).ok());
  const std::string reach_path = ::testing::TempDir() + "/chasles_cli_cartesian_reach.json";
  std::ofstream(reach_path) << reach_json;
  CommandResult partial = RunCli(at + "cartesian " + reach_path);
  EXPECT_EQ(partial.exit_code, 1) << partial.output;
  EXPECT_NE(partial.output.find("stop        UNREACHABLE"), std::string::npos) << partial.output;
  EXPECT_NE(partial.output.find("the Cartesian path ends at fraction"), std::string::npos) << partial.output;

  for (const char* option : {"--dh robots/ur5_dh.json", "--poe robots/ur5_poe.json"}) {
    std::string arguments = option;
    arguments.replace(arguments.find(' ') + 1, 0, ExamplePath(""));
    CommandResult upload = RunCli(at + "upload-robot " + arguments);
    EXPECT_EQ(upload.exit_code, 0) << upload.output;
    EXPECT_NE(upload.output.find("robot_id "), std::string::npos) << upload.output;
  }
  CommandResult both = RunCli(at + "upload-robot --dh a.json --poe b.json");
  EXPECT_EQ(both.exit_code, 2) << both.output;
}

TEST(Cli, MovingObstaclesAndAReplanningStream) {
  LoopbackServer server;
  const std::string at = "--server " + server.address() + " ";
  for (const char* example : {"base_crossing_people", "base_crossing_people_vo"}) {
    CommandResult plan = RunCli(at + "plan " + ExamplePath(std::string("requests/") + example + ".json"));
    EXPECT_EQ(plan.exit_code, 0) << plan.output;
    EXPECT_NE(plan.output.find("outcome     SUCCESS"), std::string::npos) << plan.output;
  }
  // The example stream: kept, the pallet replanned around, the person seen replanned around, kept.
  const std::string csv = ::testing::TempDir() + "/chasles_cli_replan.csv";
  CommandResult replan = RunCli(at + "replan " + ExamplePath("requests/replan_base.jsonl") + " --out " + csv);
  EXPECT_EQ(replan.exit_code, 0) << replan.output;
  for (const char* line : {"message 0   t = 0.000    PLANNED   SUCCESS", "message 1   t = 1.000    KEPT      SUCCESS",
                           "message 2   t = 2.000    REPLANNED SUCCESS", "'body' touches 'dropped_pallet'",
                           "message 3   t = 3.000    REPLANNED SUCCESS", "moving obstacle 'walker_c'",
                           "message 4   t = 4.000    KEPT      SUCCESS"}) {
    EXPECT_NE(replan.output.find(line), std::string::npos) << line << "\n" << replan.output;
  }
  EXPECT_GT(ReadText(csv).size(), 1000u);
  // A line that is not a ReplanRequest names the line.
  const std::string bad = ::testing::TempDir() + "/chasles_cli_replan_bad.jsonl";
  std::ofstream(bad) << "# comment\n{\"time\": \"soon\"}\n";
  CommandResult refused = RunCli(at + "replan " + bad);
  EXPECT_EQ(refused.exit_code, 2) << refused.output;
  EXPECT_NE(refused.output.find("line 2 is not a valid chasles.v1.ReplanRequest"), std::string::npos) << refused.output;
}

}  // namespace
}  // namespace chasles::testing
