// The viewer (issue 19) end to end, in a real browser: `chasles view` writes the page of a plan,
// of a coordinated team and of a plan among moving obstacles; headless Chromium (Debian's
// chromium-headless-shell, software WebGL) opens each page from disk with no network and the
// page's own published state is read back from its DOM: no errors, every frame loaded, and the
// trail link drawn where forward kinematics says — computed here by chaining the URDF joints
// (RobotModel::ForwardKinematicsByChaining), not by the product of exponentials the page's data
// comes from — at t = 0 and at the end. Screenshots are kept in build/test-artifacts/. The same
// pages over HTTP (--http-listen, with and without tokens), and the MoveIt / ROS exports read
// back and sent to Optimize.

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <grpcpp/security/credentials.h>

#include "chasles/robot/error.h"
#include "chasles/robot/robot_model.h"
#include "moveit_import.h"
#include "server_fixture.h"

// Last: it pulls in <resolv.h>, whose `_res` macro breaks Eigen headers included after it.
#include <httplib.h>

namespace chasles::testing {
namespace {

using ::testing::HasSubstr;

struct CommandResult {
  int exit_code = -1;
  std::string output;
};

/// Runs `command` through the shell, output (stdout and stderr) captured.
CommandResult Shell(const std::string& command) {
  static int calls = 0;
  const std::string log = ::testing::TempDir() + "/chasles_viewer_" + std::to_string(::getpid()) + "_" +
                          std::to_string(calls++) + ".txt";
  const int raw = std::system((command + " > " + log + " 2>&1").c_str());
  CommandResult result;
  result.exit_code = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  result.output = ReadText(log);
  std::remove(log.c_str());
  return result;
}

std::string Cli() { return CHASLES_CLI; }

std::string ArtifactDir() {
  const std::string dir = std::string(CHASLES_BINARY_DIR) + "/test-artifacts";
  std::filesystem::create_directories(dir);
  return dir;
}

/// The headless browser: every page opened from disk with software WebGL (SwiftShader).
std::string Browser() {
  return std::string(CHASLES_CHROMIUM) +
         " --no-sandbox --headless --use-angle=swiftshader --enable-unsafe-swiftshader --disable-gpu-sandbox"
         " --no-first-run --disable-extensions --user-data-dir=" +
         ::testing::TempDir() + "/chasles_chromium_" + std::to_string(::getpid());
}

/// The page's published state (#chasles-state) after it ran, as a Struct; fails the test when
/// the browser did not run or the page published none.
google::protobuf::Struct PageState(const std::string& html_path, const std::string& screenshot = "") {
  const CommandResult dom = Shell("timeout 120 " + Browser() + " --virtual-time-budget=10000 --dump-dom file://" + html_path);
  EXPECT_EQ(dom.exit_code, 0) << dom.output.substr(0, 2000);
  google::protobuf::Struct state;
  const std::string open = "<pre id=\"chasles-state\"";
  const std::size_t at = dom.output.find(open);
  if (at == std::string::npos) {
    ADD_FAILURE() << "the page published no #chasles-state: " << dom.output.substr(0, 2000);
    return state;
  }
  const std::size_t begin = dom.output.find('>', at) + 1;
  const std::size_t end = dom.output.find("</pre>", begin);
  std::string json = dom.output.substr(begin, end - begin);
  // The DOM escapes &, < and > in text.
  for (const auto& [from, to] : {std::pair<std::string, std::string>{"&quot;", "\""}, {"&lt;", "<"}, {"&gt;", ">"},
                                 {"&amp;", "&"}}) {
    for (std::size_t k = json.find(from); k != std::string::npos; k = json.find(from, k + to.size())) {
      json.replace(k, from.size(), to);
    }
  }
  EXPECT_TRUE(google::protobuf::util::JsonStringToMessage(json, &state).ok()) << json;
  if (!screenshot.empty()) {
    const CommandResult shot = Shell("timeout 120 " + Browser() + " --virtual-time-budget=5000 --window-size=1280,800 --screenshot=" +
                                   screenshot + " file://" + html_path);
    EXPECT_EQ(shot.exit_code, 0) << shot.output.substr(0, 2000);
    EXPECT_GT(std::filesystem::exists(screenshot) ? std::filesystem::file_size(screenshot) : 0u, 20000u) << screenshot;
  }
  return state;
}

Eigen::Vector3d Point(const google::protobuf::Value& value) {
  const auto& list = value.list_value();
  EXPECT_EQ(list.values_size(), 3);
  if (list.values_size() != 3) return Eigen::Vector3d::Zero();
  return {list.values(0).number_value(), list.values(1).number_value(), list.values(2).number_value()};
}

/// No errors, ready, and every robot's count.
void ExpectClean(const google::protobuf::Struct& state, int robots) {
  const auto& fields = state.fields();
  ASSERT_TRUE(fields.count("ready") && fields.at("ready").bool_value());
  ASSERT_TRUE(fields.count("errors"));
  const auto& errors = fields.at("errors").list_value();
  for (const auto& error : errors.values()) ADD_FAILURE() << "page error: " << error.string_value();
  ASSERT_TRUE(fields.count("robots"));
  EXPECT_EQ(fields.at("robots").list_value().values_size(), robots);
  EXPECT_GT(fields.at("frames").number_value(), 10.0);
}

Eigen::VectorXd Positions(const v1::TrajectoryPoint& point) {
  Eigen::VectorXd q(point.positions_size());
  for (int i = 0; i < q.size(); ++i) q[i] = point.positions(i);
  return q;
}

/// The link whose origin leaves the trail: the last with collision geometry (as the page draws it).
int TrailLink(const RobotModel& model) {
  for (int l = model.num_links() - 1; l >= 0; --l) {
    if (!model.links()[l].collision.empty()) return l;
  }
  return model.num_links() - 1;
}

Eigen::Vector3d ChainedPosition(const RobotModel& model, const Eigen::VectorXd& q, int link) {
  std::vector<Eigen::Isometry3d> poses;
  model.ForwardKinematicsByChaining(q, &poses);
  return poses[static_cast<std::size_t>(link)].translation();
}

template <typename Message>
std::string WriteJson(const Message& message, const std::string& name) {
  std::string json;
  google::protobuf::util::JsonPrintOptions print;
  print.preserve_proto_field_names = true;
  EXPECT_TRUE(google::protobuf::util::MessageToJsonString(message, &json, print).ok());
  const std::string path = ::testing::TempDir() + "/" + name;
  std::ofstream(path) << json;
  return path;
}

class Viewer : public SharedServerTest<> {};

TEST_F(Viewer, APlanIsDrawnWhereForwardKinematicsPutsTheArm) {
  const v1::PlanRequest request = LoadRequest("panda_shelf");
  v1::PlanResponse response;
  ASSERT_TRUE(server_->Plan(request, &response).ok());
  ASSERT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  const std::string page = ::testing::TempDir() + "/chasles_view_plan.html";
  const CommandResult view = Shell(Cli() + " view " + WriteJson(response, "chasles_view_plan_response.json") + " " +
                                 ExamplePath("requests/panda_shelf.json") + " --out " + page);
  ASSERT_EQ(view.exit_code, 0) << view.output;
  EXPECT_THAT(view.output, HasSubstr("view        Plan panda_shelf — SUCCESS"));
  const google::protobuf::Struct state = PageState(page, ArtifactDir() + "/viewer_plan.png");
  ExpectClean(state, 1);
  const auto panda = RobotModel::FromUrdf(ReadText(ExamplePath("robots/panda.urdf")), ReadText(ExamplePath("robots/panda.srdf")));
  const int link = TrailLink(*panda);
  const auto& robot = state.fields().at("robots").list_value().values(0).struct_value().fields();
  const v1::JointTrajectory& t = response.trajectory();
  EXPECT_LT((Point(robot.at("trail_start")) - ChainedPosition(*panda, Positions(t.points(0)), link)).norm(), 1e-4);
  EXPECT_LT((Point(robot.at("trail_end")) - ChainedPosition(*panda, Positions(t.points(t.points_size() - 1)), link)).norm(),
            1e-4);
  // The arm really moves: the two are apart.
  EXPECT_GT((Point(robot.at("trail_start")) - Point(robot.at("trail_end"))).norm(), 0.1);
}

TEST_F(Viewer, ATeamAndMovingObstaclesAreDrawnEveryOne) {
  v1::CoordinateRequest team;
  ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(ReadText(ExamplePath("requests/coordinate_corridor.json")), &team).ok());
  v1::CoordinateResponse coordinated;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(120));
  ASSERT_TRUE(server_->stub().Coordinate(&context, team, &coordinated).ok());
  ASSERT_EQ(coordinated.outcome(), v1::SUCCESS) << coordinated.message();
  const std::string page = ::testing::TempDir() + "/chasles_view_team.html";
  CommandResult view = Shell(Cli() + " view " + WriteJson(coordinated, "chasles_view_team_response.json") + " " +
                           ExamplePath("requests/coordinate_corridor.json") + " --out " + page);
  ASSERT_EQ(view.exit_code, 0) << view.output;
  ExpectClean(PageState(page, ArtifactDir() + "/viewer_team.png"), team.robots_size());
  // Every robot's trajectory exported: the first as named, the others with their name added.
  const std::string exported = ::testing::TempDir() + "/chasles_view_team_ros.json";
  view = Shell(Cli() + " view " + ::testing::TempDir() + "/chasles_view_team_response.json " +
               ExamplePath("requests/coordinate_corridor.json") + " --ros-json " + exported);
  ASSERT_EQ(view.exit_code, 0) << view.output;
  for (int k = 0; k < coordinated.robots_size(); ++k) {
    const std::string file =
        k == 0 ? exported : ::testing::TempDir() + "/chasles_view_team_ros_" + coordinated.robots(k).name() + ".json";
    const v1::JointTrajectory read = moveit::ImportJointTrajectory(ReadText(file), file);
    EXPECT_EQ(read.points_size(), coordinated.robots(k).trajectory().points_size()) << file;
  }

  // The base among walkers: the base and both walkers are robots of the page.
  const v1::PlanRequest walkers = LoadRequest("base_crossing_people");
  v1::PlanResponse planned;
  ASSERT_TRUE(server_->Plan(walkers, &planned).ok());
  ASSERT_EQ(planned.outcome(), v1::SUCCESS) << planned.message();
  const std::string moving = ::testing::TempDir() + "/chasles_view_moving.html";
  view = Shell(Cli() + " view " + WriteJson(planned, "chasles_view_moving_response.json") + " " +
             ExamplePath("requests/base_crossing_people.json") + " --out " + moving);
  ASSERT_EQ(view.exit_code, 0) << view.output;
  ExpectClean(PageState(moving, ArtifactDir() + "/viewer_moving_obstacles.png"), 3);
}

TEST_F(Viewer, ExportsReadBackAndOptimize) {
  const v1::PlanRequest request = LoadRequest("panda_table");
  v1::PlanResponse response;
  ASSERT_TRUE(server_->Plan(request, &response).ok());
  ASSERT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  const std::string dir = ::testing::TempDir();
  const CommandResult exported =
      Shell(Cli() + " view " + WriteJson(response, "chasles_export_response.json") + " " + ExamplePath("requests/panda_table.json") +
          " --moveit-yaml " + dir + "/chasles_export.yaml --ros-json " + dir + "/chasles_export.json");
  ASSERT_EQ(exported.exit_code, 0) << exported.output;
  for (const std::string file : {dir + "/chasles_export.yaml", dir + "/chasles_export.json"}) {
    const v1::JointTrajectory read = moveit::ImportJointTrajectory(ReadText(file), file);
    ASSERT_EQ(read.points_size(), response.trajectory().points_size()) << file;
    ASSERT_EQ(read.joint_names_size(), 7);
    EXPECT_EQ(read.joint_names(0), "panda_joint1");
    for (int k = 0; k < read.points_size(); k += 7) {
      const v1::TrajectoryPoint& a = read.points(k);
      const v1::TrajectoryPoint& b = response.trajectory().points(k);
      EXPECT_NEAR(a.time_from_start(), b.time_from_start(), 1e-9) << file;
      for (int j = 0; j < 7; ++j) {
        EXPECT_NEAR(a.positions(j), b.positions(j), 1e-12) << file;
        EXPECT_NEAR(a.velocities(j), b.velocities(j), 1e-12) << file;
      }
    }
  }
  // The exported trajectory as Optimize's input (the request's own path replaced).
  v1::OptimizeRequest optimize;
  optimize.mutable_path()->Add()->CopyFrom(request.start());
  const std::string optimize_path = WriteJson(optimize, "chasles_export_optimize.json");
  const CommandResult optimized = Shell(Cli() + " --server " + server_->address() + " optimize " + optimize_path +
                                      " --ros-trajectory " + dir + "/chasles_export.yaml");
  EXPECT_EQ(optimized.exit_code, 0) << optimized.output;
  EXPECT_THAT(optimized.output, HasSubstr("SUCCESS"));
  // A malformed file names the field.
  std::ofstream(dir + "/chasles_export_bad.json") << R"({"joint_names": ["a", "b"], "points": [{"positions": [1], "time_from_start": 0}]})";
  try {
    moveit::ImportJointTrajectory(ReadText(dir + "/chasles_export_bad.json"), "bad.json");
    ADD_FAILURE() << "accepted";
  } catch (const chasles::Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("bad.json: points[0].positions has 1 values for 2 joint_names"));
  }
  // Not a response: a named usage error.
  const CommandResult refused = Shell(Cli() + " view " + ExamplePath("robots/car.json") + " --out " + dir + "/x.html");
  EXPECT_EQ(refused.exit_code, 2) << refused.output;
  EXPECT_THAT(refused.output, HasSubstr("is not a Plan, Optimize or Coordinate response"));
}

TEST_F(Viewer, BenchmarkRunsAreLinkedToTheirPages) {
  const std::string dir = ::testing::TempDir() + "/chasles_view_bench_" + std::to_string(::getpid());
  std::filesystem::create_directories(dir);
  std::ofstream(dir + "/bench.yaml") << "experiment: views\nruns: 2\nrun_budget: 2\nproblems:\n  - request: "
                                     << ExamplePath("requests/panda_table.json") << "\n    name: table\n"
                                     << "configs:\n  - planner: rrt_connect\n";
  const CommandResult bench = Shell(Cli() + " --server " + server_->address() + " bench " + dir + "/bench.yaml --out " + dir +
                                    "/out --views --no-db --quiet");
  ASSERT_EQ(bench.exit_code, 0) << bench.output;
  EXPECT_THAT(bench.output, HasSubstr("views/index.html and 2 viewer pages"));
  const std::string index = ReadText(dir + "/out/views/index.html");
  for (const char* page : {"table-rrt_connect-0.html", "table-rrt_connect-1.html"}) {
    EXPECT_THAT(index, HasSubstr(std::string("<a href=\"") + page + "\">SUCCESS</a>"));
    ASSERT_TRUE(std::filesystem::exists(dir + "/out/views/" + page)) << page;
  }
  // A page loads three.js from the file beside it and draws the run.
  ExpectClean(PageState(dir + "/out/views/table-rrt_connect-1.html"), 1);
}

TEST(ViewerOverHttp, RecentRequestsAreServedBehindTheTokens) {
  const std::string tokens = ::testing::TempDir() + "/chasles_view_tokens.txt";
  std::ofstream(tokens) << "alice plan 0123456789abcdef0123\n";
  for (const bool with_tokens : {false, true}) {
    ServerOptions options = LoopbackServer::QuietOptions(2);
    options.http_listen = "127.0.0.1:0";
    if (with_tokens) options.security.tokens_file = tokens;
    LoopbackServer server(options);
    ASSERT_GT(server.server().http_port(), 0);
    v1::PlanRequest request = LoadRequest("panda_table");
    request.set_request_id("view-me");
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
    if (with_tokens) context.AddMetadata("authorization", "Bearer 0123456789abcdef0123");
    // With tokens and no TLS the server takes gRPC local credentials (loopback peers only).
    const auto channel = with_tokens ? grpc::CreateChannel(server.address(), grpc::experimental::LocalCredentials(LOCAL_TCP))
                                     : server.channel();
    v1::PlanResponse response;
    const grpc::Status planned = v1::Planning::NewStub(channel)->Plan(&context, request, &response);
    ASSERT_TRUE(planned.ok()) << planned.error_message();
    httplib::Client http("127.0.0.1", server.server().http_port());
    const std::string token = with_tokens ? "?token=0123456789abcdef0123" : "";
    auto index = http.Get("/" + token);
    ASSERT_TRUE(index);
    EXPECT_EQ(index->status, 200);
    EXPECT_THAT(index->body, HasSubstr("/view/view-me"));
    auto page = http.Get("/view/view-me" + token);
    ASSERT_TRUE(page);
    EXPECT_EQ(page->status, 200);
    EXPECT_THAT(page->body, HasSubstr("const CHASLES_VIEW = {"));
    EXPECT_THAT(page->body, HasSubstr("view-me"));
    auto missing = http.Get("/view/nobody" + token);
    ASSERT_TRUE(missing);
    EXPECT_EQ(missing->status, 404);
    if (with_tokens) {
      auto refused = http.Get("/view/view-me");
      ASSERT_TRUE(refused);
      EXPECT_EQ(refused->status, 401);
      EXPECT_THAT(refused->body, HasSubstr("bearer token"));
      auto wrong = http.Get("/view/view-me?token=wrongwrongwrongwrong");
      ASSERT_TRUE(wrong);
      EXPECT_EQ(wrong->status, 401);
    }
  }
  // Plain HTTP with tokens only on loopback.
  ServerOptions exposed = LoopbackServer::QuietOptions(2);
  exposed.http_listen = "0.0.0.0:0";
  exposed.security.tokens_file = tokens;
  try {
    exposed.Validate();
    ADD_FAILURE() << "accepted";
  } catch (const chasles::Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("--http-listen 0.0.0.0:0 serves plain HTTP"));
  }
}

}  // namespace
}  // namespace chasles::testing
