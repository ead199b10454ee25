// `chasles bench CONFIG.yaml` against an in-process server: files written (OMPL logs, the
// database ompl_benchmark_statistics makes, runs.csv, results.json), the summary table, named
// configuration errors, and Ctrl-C keeping the finished runs.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "../budget_scale.h"
#include "server_fixture.h"

namespace chasles {
namespace {

namespace fs = std::filesystem;
using testing::ExamplePath;
using testing::LoopbackServer;
using testing::ReadText;

struct CliResult {
  int exit_code = -1;
  std::string output;
};

CliResult RunCli(const std::string& arguments, const fs::path& log) {
  const std::string command = std::string(CHASLES_CLI) + " " + arguments + " > '" + log.string() + "' 2>&1";
  const int status = std::system(command.c_str());
  CliResult result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.output = ReadText(log.string());
  return result;
}

std::size_t Lines(const std::string& text) {
  std::size_t n = 0;
  for (char c : text) n += c == '\n' ? 1 : 0;
  return n;
}

class BenchCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("chasles_bench_cli_" + std::to_string(getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path Write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
    return dir_ / name;
  }
  fs::path dir_;
};

TEST_F(BenchCli, WritesLogsDatabaseCsvJsonAndATable) {
  LoopbackServer server(2);
  const fs::path config = Write("planar.yaml",
                                "experiment: planar\n"
                                "runs: 3\n"
                                "run_budget: 1.5\n"
                                "seed: 5\n"
                                "problems:\n"
                                "  - request: " + ExamplePath("requests/planar_2r_table.json") + "\n"
                                "    name: table\n"
                                "  - request: " + ExamplePath("requests/planar_2r_shelf.json") + "\n"
                                "configs:\n"
                                "  - planner: rrt_connect\n"
                                "  - name: rrt_coarse\n"
                                "    planner: rrt\n"
                                "    parameters: {range: 0.5, goal_bias: 0.1}\n"
                                "  - planner: prm\n"
                                "    post_processing: none\n");
  const fs::path out = dir_ / "out";
  const CliResult result =
      RunCli("--server " + server.address() + " bench '" + config.string() + "' --out '" + out.string() + "' --quiet",
             dir_ / "log.txt");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("rrt_coarse"), std::string::npos) << result.output;
  EXPECT_NE(result.output.find("18 of 18 runs finished"), std::string::npos) << result.output;
  EXPECT_EQ(Lines(ReadText((out / "runs.csv").string())), 19u);  // header + 2 × 3 × 3
  ASSERT_TRUE(fs::exists(out / "table.log"));
  ASSERT_TRUE(fs::exists(out / "planar_2r_shelf.log"));
  EXPECT_NE(ReadText((out / "table.log").string()).find("planner = rrt\ngoal_bias = 0.1\nrange = 0.5\n"),
            std::string::npos);
  ASSERT_TRUE(fs::exists(out / "results.db")) << result.output;
  // results.json: the summary and every run.
  const std::string json = ReadText((out / "results.json").string());
  EXPECT_NE(json.find("\"runs_finished\":18"), std::string::npos) << json.substr(0, 400);
  std::size_t runs = 0;
  for (std::size_t at = json.find("\"worker\""); at != std::string::npos; at = json.find("\"worker\"", at + 1)) ++runs;
  EXPECT_EQ(runs, 18u);
}

/// runs.csv rows as "problem,config,run,seed,outcome,solved" -> path_length, sorted.
std::map<std::string, std::string> RunsByKey(const std::string& csv) {
  std::map<std::string, std::string> rows;
  std::istringstream in(csv);
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::vector<std::string> fields;
    std::stringstream split(line);
    for (std::string field; std::getline(split, field, ',');) fields.push_back(field);
    if (fields.size() < 11) continue;
    rows[fields[0] + "," + fields[1] + "," + fields[2] + "," + fields[3] + "," + fields[4] + "," + fields[5]] = fields[10];
  }
  return rows;
}

// Issue 15, item 4: `chasles --server a,b,c bench` spreads the runs over the replicas (run r keeps
// seed + r) and merges the answers into the same files: the same runs, seeds, outcomes and path
// lengths as on one server, one OMPL log per problem that ompl_benchmark_statistics reads.
TEST_F(BenchCli, SeveralServersShareTheRunsAndTheFilesAreTheSame) {
  LoopbackServer a(1), b(1), c(1);
  const fs::path config = Write("fan.yaml",
                                "experiment: fan\n"
                                "runs: 5\n"
                                "run_budget: 1.5\n"
                                "seed: 5\n"
                                "problems:\n"
                                "  - request: " + ExamplePath("requests/planar_2r_table.json") + "\n"
                                "    name: table\n"
                                "configs:\n"
                                "  - planner: rrt_connect\n"
                                "  - planner: rrt\n");
  const fs::path one = dir_ / "one", three = dir_ / "three";
  CliResult result = RunCli("--server " + a.address() + " bench '" + config.string() + "' --out '" + one.string() +
                                "' --quiet",
                            dir_ / "one.txt");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  result = RunCli("--server " + a.address() + "," + b.address() + "," + c.address() + " bench '" + config.string() +
                      "' --out '" + three.string() + "' --quiet",
                  dir_ / "three.txt");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("10 of 10 runs finished"), std::string::npos) << result.output;
  const auto single = RunsByKey(ReadText((one / "runs.csv").string()));
  const auto shared = RunsByKey(ReadText((three / "runs.csv").string()));
  EXPECT_EQ(single.size(), 10u);
  EXPECT_EQ(shared, single);
  const std::string log = ReadText((three / "table.log").string());
  EXPECT_NE(log.find("5 runs per planner"), std::string::npos) << log.substr(0, 600);
  std::size_t planners = 0;
  for (std::size_t at = log.find("\n5 runs\n"); at != std::string::npos; at = log.find("\n5 runs\n", at + 1)) ++planners;
  EXPECT_EQ(planners, 2u) << log;
  EXPECT_TRUE(fs::exists(three / "results.db")) << result.output;
}

TEST_F(BenchCli, ConfigurationErrorsNameFileAndKey) {
  const std::string table = ExamplePath("requests/planar_2r_table.json");
  const struct {
    const char* yaml;
    const char* expected;
  } cases[] = {
      {"problems: [\n  - request: x\n", "bad.yaml: malformed YAML at line"},
      {"problems:\n  - request: TABLE\nconfigs:\n  - planner: rrt\n    parameters: {range: fast}\n",
       "bad.yaml: configs[0].parameters.range = 'fast' must be a number or true/false"},
      {"problems:\n  - request: TABLE\nconfigs:\n  - name: x\n", "bad.yaml: configs[0] must be a map with planner: ID"},
      {"problems:\n  - request: TABLE\nconfigs:\n  - planner: rrt\n    post_processing: smooth\n",
       "bad.yaml: configs[0].post_processing = 'smooth' must be topp, collocation, spline or none"},
      {"problems:\n  - request: TABLE\nconfigs:\n  - planner: rrt\nrun: 3\n", "bad.yaml: run is not a known key"},
      {"problems:\n  - scene: s.yaml\nconfigs:\n  - planner: rrt\n", "bad.yaml: problems[0] needs request: FILE.json"},
      {"problems:\n  - request: /no/such.json\nconfigs:\n  - planner: rrt\n", "cannot read request '/no/such.json'"},
      {"configs:\n  - planner: rrt\n", "bad.yaml: problems must be a non-empty list"},
      {"runs: -2\nproblems:\n  - request: TABLE\nconfigs:\n  - planner: rrt\n", "bad.yaml: runs = '-2' must be a whole number"},
      {"problems:\n  - moveit: d\n    urdf: r.urdf\nconfigs:\n  - planner: rrt\n",
       "bad.yaml: problems[0].urdf is not a known key (name, request, moveit, moveit_scene, moveit_request, robot, srdf)"},
      {"problems:\n  - moveit: d\n    srdf: r.srdf\nconfigs:\n  - planner: rrt\n",
       "bad.yaml: problems[0].srdf needs robot: F.urdf"},
      {"problems:\n  - request: TABLE\n    robot: r.urdf\nconfigs:\n  - planner: rrt\n",
       "bad.yaml: problems[0].robot belongs to moveit entries"},
  };
  for (const auto& c : cases) {
    std::string yaml = c.yaml;
    for (std::size_t at = yaml.find("TABLE"); at != std::string::npos; at = yaml.find("TABLE")) yaml.replace(at, 5, table);
    const fs::path config = Write("bad.yaml", yaml);
    const CliResult result = RunCli("bench '" + config.string() + "' --quiet", dir_ / "log.txt");
    EXPECT_EQ(result.exit_code, 2) << yaml << "\n" << result.output;
    EXPECT_NE(result.output.find(c.expected), std::string::npos) << yaml << "\n" << result.output;
  }
}

// A MoveIt directory for a robot other than the server's default Panda: the planar 2R arm of
// examples/robots/ (joints joint1, joint2), a post in the way of the straight line. The bench
// configuration names the robot with robot: / srdf:, so every run plans for the 2R arm; planning
// for the default Panda instead (7 joints, 2 positions given) solves none.
TEST_F(BenchCli, MoveItDirectoryPlansForTheConfiguredRobot) {
  LoopbackServer server(2);
  fs::create_directories(dir_ / "set");
  const std::string scene =
      "name: post\n"
      "world:\n"
      "  collision_objects:\n"
      "    - id: post\n"
      "      header: {frame_id: base_link}\n"
      "      primitives: [{type: box, dimensions: [0.2, 0.2, 0.4]}]\n"
      "      primitive_poses: [{position: [1.0, 1.0, 0.2], orientation: [0, 0, 0, 1]}]\n";
  const std::string request =
      "group_name: arm\n"
      "start_state:\n  joint_state: {name: [joint1, joint2], position: [0.0, 0.0]}\n"
      "goal_constraints:\n"
      "  - joint_constraints:\n"
      "      - {joint_name: joint1, position: 1.5708}\n"
      "      - {joint_name: joint2, position: 0.0}\n"
      "allowed_planning_time: 2\n";
  Write("set/scene0001.yaml", scene);
  Write("set/request0001.yaml", request);
  Write("set/scene0002.yaml", scene);
  Write("set/request0002.yaml", request);
  const fs::path config = Write("planar_moveit.yaml",
                                "runs: 2\n"
                                "run_budget: 2\n"
                                "problems:\n"
                                "  - moveit: set\n"
                                "    robot: " + ExamplePath("robots/planar_2r.urdf") + "\n"
                                "    srdf: " + ExamplePath("robots/planar_2r.srdf") + "\n"
                                "  - moveit_scene: set/scene0001.yaml\n"
                                "    moveit_request: set/request0001.yaml\n"
                                "    name: pair\n"
                                "    robot: " + ExamplePath("robots/planar_2r.urdf") + "\n"
                                "configs:\n"
                                "  - planner: rrt_connect\n");
  const fs::path out = dir_ / "out";
  const CliResult result =
      RunCli("--server " + server.address() + " bench '" + config.string() + "' --out '" + out.string() +
                 "' --quiet --no-db",
             dir_ / "log.txt");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("6 of 6 runs finished"), std::string::npos) << result.output;
  // Every run of every problem (scene0001, scene0002, pair) solved.
  const std::string csv = ReadText((out / "runs.csv").string());
  EXPECT_EQ(Lines(csv), 7u) << csv;
  std::size_t solved = 0;
  for (std::size_t at = csv.find(",SUCCESS,1,"); at != std::string::npos; at = csv.find(",SUCCESS,1,", at + 1)) ++solved;
  EXPECT_EQ(solved, 6u) << csv;
}

TEST_F(BenchCli, InterruptStopsAndKeepsTheFinishedRuns) {
  LoopbackServer server(2);
  const fs::path config = Write("long.yaml",
                                "runs: 50\n"
                                "run_budget: " + std::to_string(test::Budget(0.5)) + "\n"
                                "problems:\n"
                                "  - request: " + ExamplePath("requests/planar_2r_table.json") + "\n"
                                "configs:\n"
                                "  - planner: rrt_star\n");
  const fs::path out = dir_ / "out";
  const fs::path log = dir_ / "log.txt";
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fd, 1);
    dup2(fd, 2);
    const std::string address = server.address();
    execl(CHASLES_CLI, CHASLES_CLI, "--server", address.c_str(), "bench", config.c_str(), "--out", out.c_str(), "--no-db",
          static_cast<char*>(nullptr));
    _exit(127);
  }
  // RRT* uses its whole 0.5 s budget: 50 runs on 2 workers take 12.5 s; interrupt after ~1.2 s.
  // Both scaled under the sanitizers (budget_scale.h), where the CLI and the runs start slower.
  std::this_thread::sleep_for(std::chrono::duration<double>(test::Budget(1.2)));
  kill(pid, SIGINT);
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  const std::string output = ReadText(log.string());
  ASSERT_TRUE(WIFEXITED(status)) << output;
  EXPECT_EQ(WEXITSTATUS(status), 0) << output;
  EXPECT_NE(output.find("stopping the benchmark"), std::string::npos) << output;
  EXPECT_NE(output.find("(stopped early)"), std::string::npos) << output;
  const std::size_t rows = Lines(ReadText((out / "runs.csv").string())) - 1;
  EXPECT_GE(rows, 1u);
  EXPECT_LT(rows, 50u);
  EXPECT_NE(output.find(std::to_string(rows) + " of 50 runs finished"), std::string::npos) << output;
}

}  // namespace
}  // namespace chasles
