// The Benchmark RPC end to end: counts, per-run figures, summaries, OMPL logs that
// ompl_benchmark_statistics converts, StopBenchmark and client cancellation, named errors; the
// report functions and the heap accounting.
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "chasles/server/benchmark_report.h"
#include "chasles/server/heap_tracking.h"
#include "server_fixture.h"

namespace chasles {
namespace {

using testing::ExamplePath;
using testing::LoadRequest;
using testing::LoopbackServer;
using testing::ReadText;
namespace fs = std::filesystem;

v1::BenchmarkProblem Problem(const std::string& example, const std::string& name) {
  v1::BenchmarkProblem problem;
  problem.set_name(name);
  *problem.mutable_request() = LoadRequest(example);
  return problem;
}

v1::BenchmarkConfig Config(const std::string& planner, const std::string& name = "") {
  v1::BenchmarkConfig config;
  config.set_name(name);
  config.mutable_planner()->set_planner_id(planner);
  return config;
}

struct Stream {
  std::vector<v1::BenchmarkResponse> messages;
  std::vector<v1::BenchmarkRun> runs;
  std::optional<v1::BenchmarkSummary> summary;
  grpc::Status status;
};

Stream Collect(LoopbackServer& server, const v1::BenchmarkRequest& request, double deadline_s = 120.0) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::milliseconds(static_cast<int>(deadline_s * 1e3)));
  Stream stream;
  auto reader = server.stub().Benchmark(&context, request);
  v1::BenchmarkResponse message;
  while (reader->Read(&message)) {
    stream.messages.push_back(message);
    if (message.has_run()) stream.runs.push_back(message.run());
    if (message.has_summary()) stream.summary = message.summary();
  }
  stream.status = reader->Finish();
  return stream;
}

/// Runs a shell command; returns its exit status and captures stdout.
int RunCommand(const std::string& command, std::string* output) {
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return -1;
  char buffer[4096];
  while (std::fgets(buffer, sizeof(buffer), pipe)) *output += buffer;
  return pclose(pipe);
}

/// 3 configurations × 2 problems × 5 runs on the planar arm (fast problems).
v1::BenchmarkRequest ThreeByTwoByFive() {
  v1::BenchmarkRequest request;
  *request.add_problems() = Problem("planar_2r_table", "table");
  *request.add_problems() = Problem("planar_2r_shelf", "shelf");
  *request.add_configs() = Config("rrt_connect");
  v1::BenchmarkConfig rrt = Config("rrt", "rrt_range_0.5");
  (*rrt.mutable_planner()->mutable_parameters())["range"].set_double_value(0.5);
  *request.add_configs() = rrt;
  v1::BenchmarkConfig prm = Config("prm");
  prm.mutable_trajectory()->set_post_processing(v1::TrajectoryOptions::NONE);
  *request.add_configs() = prm;
  request.set_runs(5);
  request.set_run_budget(2.0);
  request.set_seed(40);
  request.set_experiment("counts test");
  return request;
}

TEST(Benchmark, CountsFiguresSummaryAndOmplDatabase) {
  LoopbackServer server(2);
  const Stream stream = Collect(server, ThreeByTwoByFive());
  ASSERT_TRUE(stream.status.ok()) << stream.status.error_message();
  ASSERT_TRUE(stream.summary.has_value());
  const v1::BenchmarkSummary& summary = *stream.summary;

  // Every (problem, config, run) exactly once, with the seed of its run.
  ASSERT_EQ(stream.runs.size(), 30u);
  std::set<std::tuple<int, int, int>> seen;
  for (const v1::BenchmarkRun& run : stream.runs) {
    EXPECT_TRUE(seen.emplace(run.problem(), run.config(), run.run()).second);
    EXPECT_LT(run.problem(), 2u);
    EXPECT_LT(run.config(), 3u);
    EXPECT_LT(run.run(), 5u);
    EXPECT_EQ(run.seed(), 40u + run.run());
    EXPECT_LT(run.worker(), 2u);
    // The figures of a solved run.
    EXPECT_TRUE(run.solved()) << run.message();
    EXPECT_EQ(run.outcome(), v1::SUCCESS);
    EXPECT_GT(run.path_length(), 0.0);
    EXPECT_GE(run.raw_path_length() + 1e-9, run.path_length());  // shortcutting never lengthens
    EXPECT_GT(run.duration(), 0.0);
    EXPECT_GE(run.smoothness(), 0.0);
    EXPECT_GT(run.min_clearance(), 0.0);
    EXPECT_GT(run.collision_checks(), 0u);
    EXPECT_GT(run.peak_memory(), 0u);
    EXPECT_LE(run.plan_time() + run.post_time(), run.total_time() + 1e-9);
  }
  EXPECT_EQ(seen.size(), 30u);

  // Progress: done counts up by one per run message, up to the total; the first message says 0.
  ASSERT_FALSE(stream.messages.empty());
  EXPECT_EQ(stream.messages.front().progress().done(), 0u);
  std::uint32_t done = 0;
  for (const v1::BenchmarkResponse& m : stream.messages) {
    EXPECT_EQ(m.progress().total(), 30u);
    EXPECT_GE(m.progress().done(), done);
    if (m.has_run()) {
      EXPECT_EQ(m.progress().done(), done + 1);
      EXPECT_GE(m.progress().eta(), 0.0);
    }
    done = m.progress().done();
  }
  EXPECT_EQ(done, 30u);

  // Summary per configuration.
  EXPECT_EQ(summary.runs_finished(), 30u);
  EXPECT_EQ(summary.runs_total(), 30u);
  EXPECT_FALSE(summary.stopped());
  EXPECT_EQ(summary.parallelism(), 2u);
  ASSERT_EQ(summary.config_names_size(), 3);
  EXPECT_EQ(summary.config_names(0), "rrt_connect");
  EXPECT_EQ(summary.config_names(1), "rrt_range_0.5");
  EXPECT_EQ(summary.config_names(2), "prm");
  ASSERT_EQ(summary.configs_size(), 3);
  for (const v1::ConfigSummary& c : summary.configs()) {
    EXPECT_EQ(c.runs(), 10u);
    EXPECT_EQ(c.solved(), 10u);
    EXPECT_DOUBLE_EQ(c.success_rate(), 1.0);
    EXPECT_GT(c.median_time(), 0.0);
    EXPECT_GE(c.p95_time(), c.median_time());
    EXPECT_GT(c.median_length(), 0.0);
    std::vector<double> times, lengths;
    for (const v1::BenchmarkRun& run : stream.runs) {
      if (run.config() != c.config()) continue;
      times.push_back(run.total_time());
      lengths.push_back(run.path_length());
    }
    EXPECT_DOUBLE_EQ(c.median_time(), Quantile(times, 0.5));
    EXPECT_DOUBLE_EQ(c.median_length(), Quantile(lengths, 0.5));
  }

  // One OMPL log per problem; ompl_benchmark_statistics turns them into one database.
  ASSERT_EQ(summary.logs_size(), 2);
  const fs::path dir = fs::temp_directory_path() / ("chasles_bench_test_" + std::to_string(getpid()));
  fs::create_directories(dir);
  std::string files;
  for (const v1::ProblemLog& log : summary.logs()) {
    const fs::path file = dir / (log.name() + ".log");
    std::ofstream(file) << log.ompl_log();
    files += " '" + file.string() + "'";
  }
  const fs::path db = dir / "results.db";
  std::string output;
  ASSERT_EQ(RunCommand("/usr/bin/ompl_benchmark_statistics" + files + " -d '" + db.string() + "' 2>&1", &output), 0)
      << output;
  const std::string query =
      "/usr/bin/python3 -c \"import sqlite3; c = sqlite3.connect('" + db.string() +
      "'); q = lambda s: c.execute(s).fetchall(); "
      "print(q('SELECT COUNT(*) FROM experiments')[0][0], q('SELECT COUNT(*) FROM runs')[0][0], "
      "q('SELECT COUNT(DISTINCT name) FROM plannerConfigs')[0][0], "
      "q('SELECT COUNT(*) FROM runs WHERE solved = 1')[0][0], "
      "q('SELECT COUNT(*) FROM runs WHERE status = 1')[0][0], "
      "sorted(set(n for (n,) in q('SELECT name FROM plannerConfigs'))), "
      "q('SELECT MIN(n), MAX(n) FROM (SELECT COUNT(*) AS n FROM runs GROUP BY experimentid, plannerid)')[0])\"";
  output.clear();
  ASSERT_EQ(RunCommand(query, &output), 0) << output;
  EXPECT_EQ(output, "2 30 3 30 30 ['prm', 'rrt_connect', 'rrt_range_0.5'] (5, 5)\n");
  fs::remove_all(dir);
}

TEST(Benchmark, SameSeedsSameRunsWhateverTheParallelism) {
  LoopbackServer server(2);
  v1::BenchmarkRequest request = ThreeByTwoByFive();
  request.set_runs(2);
  request.set_parallelism(1);
  const Stream one = Collect(server, request);
  request.set_parallelism(2);
  const Stream two = Collect(server, request);
  ASSERT_TRUE(one.status.ok() && two.status.ok());
  ASSERT_EQ(one.runs.size(), 12u);
  ASSERT_EQ(two.runs.size(), 12u);
  std::map<std::tuple<int, int, int>, v1::BenchmarkRun> first;
  for (const auto& run : one.runs) {
    EXPECT_EQ(run.worker(), 0u);
    first[{run.problem(), run.config(), run.run()}] = run;
  }
  for (const auto& run : two.runs) {
    const v1::BenchmarkRun& other = first.at({run.problem(), run.config(), run.run()});
    EXPECT_EQ(run.path_length(), other.path_length());
    EXPECT_EQ(run.duration(), other.duration());
    EXPECT_EQ(run.graph_states(), other.graph_states());
  }
  EXPECT_EQ(one.summary->parallelism(), 1u);
}

/// Long runs: RRT* refines until its budget ends.
v1::BenchmarkRequest LongRuns(const std::string& id) {
  v1::BenchmarkRequest request;
  *request.add_problems() = Problem("planar_2r_table", "table");
  *request.add_configs() = Config("rrt_star");
  request.set_runs(20);
  request.set_run_budget(0.4);
  request.set_parallelism(2);
  request.set_request_id(id);
  return request;
}

TEST(Benchmark, StopKeepsTheFinishedRunsAndAnswersTheirSummary) {
  LoopbackServer server(2);
  v1::BenchmarkRequest request = LongRuns("stop-me");
  request.set_run_budget(5.0);  // a run in flight would take 5 s unless the stop cuts it
  request.set_runs(6);
  request.mutable_problems(0)->mutable_request()->mutable_planner()->set_planner_id("rrt_connect");
  *request.add_configs() = Config("rrt_connect");  // quick runs finish before the stop
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(120));
  auto reader = server.stub().Benchmark(&context, request);
  v1::BenchmarkResponse message;
  std::vector<v1::BenchmarkRun> runs;
  std::optional<v1::BenchmarkSummary> summary;
  std::chrono::steady_clock::time_point stopped_at;
  bool stop_sent = false;
  while (reader->Read(&message)) {
    if (message.has_run()) runs.push_back(message.run());
    if (message.has_summary()) summary = message.summary();
    if (!stop_sent && !runs.empty()) {
      // RRT* now holds a worker for 5 s; stop.
      grpc::ClientContext stop_context;
      v1::StopBenchmarkRequest stop;
      stop.set_request_id("stop-me");
      v1::StopBenchmarkResponse answer;
      ASSERT_TRUE(server.stub().StopBenchmark(&stop_context, stop, &answer).ok());
      EXPECT_TRUE(answer.stopped());
      stopped_at = std::chrono::steady_clock::now();
      stop_sent = true;
    }
  }
  const grpc::Status status = reader->Finish();
  const double after_stop = std::chrono::duration<double>(std::chrono::steady_clock::now() - stopped_at).count();
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_TRUE(summary.has_value());
  EXPECT_TRUE(summary->stopped());
  EXPECT_EQ(summary->runs_finished(), runs.size());
  EXPECT_LT(summary->runs_finished(), summary->runs_total());
  std::uint32_t counted = 0;
  for (const auto& c : summary->configs()) counted += c.runs();
  EXPECT_EQ(counted, runs.size());
  // The RRT* run in flight was cut, not run to its 5 s budget.
  EXPECT_LT(after_stop, 2.5);
  // Its log holds exactly the finished runs.
  ASSERT_EQ(summary->logs_size(), 1);
  const std::string& log = summary->logs(0).ompl_log();
  std::size_t lines = 0;
  for (std::size_t at = log.find("; \n"); at != std::string::npos; at = log.find("; \n", at + 1)) ++lines;
  EXPECT_EQ(lines, runs.size());
  // Stopping it again: it is gone.
  grpc::ClientContext again;
  v1::StopBenchmarkRequest stop;
  stop.set_request_id("stop-me");
  v1::StopBenchmarkResponse answer;
  const grpc::Status gone = server.stub().StopBenchmark(&again, stop, &answer);
  EXPECT_EQ(gone.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_NE(gone.error_message().find("stop-me"), std::string::npos);
}

TEST(Benchmark, ClientCancelEndsPromptlyAndTheServerKeepsServing) {
  LoopbackServer server(2);
  v1::BenchmarkRequest request = LongRuns("cancel-me");
  request.set_run_budget(5.0);
  grpc::ClientContext context;
  auto reader = server.stub().Benchmark(&context, request);
  v1::BenchmarkResponse message;
  ASSERT_TRUE(reader->Read(&message));  // the first progress message: runs have started
  EXPECT_EQ(message.progress().total(), 20u);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const auto cancelled_at = std::chrono::steady_clock::now();
  context.TryCancel();
  while (reader->Read(&message)) {
  }
  EXPECT_EQ(reader->Finish().error_code(), grpc::StatusCode::CANCELLED);
  // The server side has let go of its workers: a plan is answered at once, not after 5 s.
  v1::PlanResponse response;
  ASSERT_TRUE(server.Plan(LoadRequest("planar_2r_table"), &response).ok());
  EXPECT_EQ(response.outcome(), v1::SUCCESS);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - cancelled_at).count(), 2.5);
  // The id is free again once the server has seen the cancel (a liveness bound, polled).
  request.set_runs(1);
  request.set_run_budget(0.05);
  Stream again;
  for (int attempt = 0; attempt < 100; ++attempt) {
    again = Collect(server, request);
    if (again.status.error_code() != grpc::StatusCode::ALREADY_EXISTS) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  EXPECT_TRUE(again.status.ok()) << again.status.error_message();
}

// Issue 25, item 1: a benchmark problem may name a planning group, as Plan does: the mobile
// manipulator's "arm" moves, its torso stays where the start puts it, and every run's
// trajectory is for the arm alone; the setup in the OMPL log says so. A goal moving a held
// joint is named with the problem's field.
TEST(Benchmark, AProblemPlansItsPlanningGroup) {
  LoopbackServer server(2);
  v1::BenchmarkRequest request;
  v1::PlanRequest* problem = request.add_problems()->mutable_request();
  problem->mutable_robot()->mutable_urdf()->set_urdf(ReadText(ExamplePath("robots/mobile_manipulator.urdf")));
  problem->mutable_robot()->mutable_urdf()->set_srdf(ReadText(ExamplePath("robots/mobile_manipulator.srdf")));
  problem->mutable_scene();
  problem->set_group("arm");
  for (double v : {0.2, 0.0, 0.3, 0.0, 1.0, 0.0, 0.6, 0.0}) problem->mutable_start()->add_positions(v);
  for (double v : {0.9, -0.4, 0.5, 1.2, -0.4, 0.9, 0.3}) problem->mutable_goal()->add_positions(v);
  request.add_configs()->mutable_planner()->set_planner_id("rrt_connect");
  request.set_runs(3);
  request.set_run_budget(5.0);
  const Stream stream = Collect(server, request);
  ASSERT_TRUE(stream.status.ok()) << stream.status.error_message();
  ASSERT_EQ(stream.runs.size(), 3u);
  for (const v1::BenchmarkRun& run : stream.runs) EXPECT_TRUE(run.solved()) << run.message();
  ASSERT_TRUE(stream.summary.has_value());
  ASSERT_EQ(stream.summary->logs_size(), 1);
  EXPECT_NE(stream.summary->logs(0).ompl_log().find("7 joints of group arm (the others held at the start)"),
            std::string::npos)
      << stream.summary->logs(0).ompl_log().substr(0, 600);

  problem->mutable_goal()->clear_positions();
  for (double v : {0.25, 0.9, -0.4, 0.5, 1.2, -0.4, 0.9, 0.3}) problem->mutable_goal()->add_positions(v);
  const Stream refused = Collect(server, request);
  EXPECT_TRUE(refused.runs.empty());
  EXPECT_EQ(refused.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(refused.status.error_message().find("problems[0].request.goal.positions[0] = 0.25 differs from "
                                                "problems[0].request.start.positions[0] = 0.2, but joint "
                                                "'torso_lift_joint' is not in group 'arm'"),
            std::string::npos)
      << refused.status.error_message();
}

TEST(Benchmark, BadInputGetsNamedErrors) {
  LoopbackServer server(2);
  const auto error = [&](const v1::BenchmarkRequest& request) {
    const Stream stream = Collect(server, request);
    EXPECT_TRUE(stream.runs.empty());
    return stream.status;
  };
  const v1::BenchmarkRequest good = ThreeByTwoByFive();

  v1::BenchmarkRequest r = good;
  r.clear_problems();
  grpc::Status s = error(r);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(s.error_message().find("problems has 0 entries"), std::string::npos) << s.error_message();

  r = good;
  r.clear_configs();
  s = error(r);
  EXPECT_NE(s.error_message().find("configs has 0 entries"), std::string::npos) << s.error_message();

  // A planning group the problem's robot lacks is named with the problem (the planar arm has
  // no SRDF, so no groups).
  r = good;
  r.mutable_problems(1)->mutable_request()->set_group("arm");
  s = error(r);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(s.error_message().find("problems[1].request.group = 'arm' is not a planning group of robot"),
            std::string::npos)
      << s.error_message();

  r = good;
  r.mutable_configs(1)->mutable_planner()->set_planner_id("rrt_sideways");
  s = error(r);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_NE(s.error_message().find("configs[1].planner"), std::string::npos) << s.error_message();
  EXPECT_NE(s.error_message().find("rrt_sideways"), std::string::npos) << s.error_message();

  r = good;
  (*r.mutable_configs(1)->mutable_planner()->mutable_parameters())["range"].set_double_value(-3);
  s = error(r);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(s.error_message().find("configs[1].planner.parameters['range'] = -3"), std::string::npos) << s.error_message();

  r = good;
  r.mutable_problems(1)->mutable_request()->mutable_start()->set_positions(1, std::nan(""));
  s = error(r);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(s.error_message().find("problems[1].request.start.positions[1] = nan"), std::string::npos)
      << s.error_message();
  EXPECT_NE(s.error_message().find("'shelf'"), std::string::npos) << s.error_message();

  r = good;
  r.mutable_problems(1)->mutable_request()->mutable_robot()->mutable_urdf()->set_urdf("<robot name='x'><link");
  s = error(r);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(s.error_message().find("problems[1].request.robot"), std::string::npos) << s.error_message();

  r = good;
  r.mutable_problems(1)->set_name("table");
  s = error(r);
  EXPECT_NE(s.error_message().find("problems[1].name = 'table' repeats problems[0].name"), std::string::npos)
      << s.error_message();

  r = good;
  r.mutable_configs(2)->set_name("rrt_connect");
  s = error(r);
  EXPECT_NE(s.error_message().find("configs[2].name = 'rrt_connect' repeats configs[0].name"), std::string::npos)
      << s.error_message();

  r = good;
  r.set_runs(10001);
  s = error(r);
  EXPECT_NE(s.error_message().find("runs = 10001 must be at most 10000"), std::string::npos) << s.error_message();

  r = good;
  r.set_run_budget(-1);
  s = error(r);
  EXPECT_NE(s.error_message().find("run_budget = -1 must be in (0, 600]"), std::string::npos) << s.error_message();

  r = good;
  r.mutable_problems(0)->mutable_request()->mutable_workcell()->set_name("cell");
  s = error(r);
  EXPECT_NE(s.error_message().find("problems[0].request.workcell"), std::string::npos) << s.error_message();

  // StopBenchmark without an id, or with an unknown one.
  grpc::ClientContext c1, c2;
  v1::StopBenchmarkRequest stop;
  v1::StopBenchmarkResponse answer;
  EXPECT_EQ(server.stub().StopBenchmark(&c1, stop, &answer).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  stop.set_request_id("nobody");
  EXPECT_EQ(server.stub().StopBenchmark(&c2, stop, &answer).error_code(), grpc::StatusCode::NOT_FOUND);

  // After all that, the server still benchmarks.
  r = good;
  r.set_runs(1);
  const Stream ok = Collect(server, r);
  EXPECT_TRUE(ok.status.ok());
  EXPECT_EQ(ok.runs.size(), 6u);
}

TEST(Benchmark, ARunningIdCannotBeReused) {
  LoopbackServer server(2);
  v1::BenchmarkRequest request = LongRuns("twice");
  grpc::ClientContext context;
  auto reader = server.stub().Benchmark(&context, request);
  v1::BenchmarkResponse message;
  ASSERT_TRUE(reader->Read(&message));  // registered and running
  request.set_runs(1);
  const Stream second = Collect(server, request);
  EXPECT_EQ(second.status.error_code(), grpc::StatusCode::ALREADY_EXISTS);
  EXPECT_NE(second.status.error_message().find("'twice'"), std::string::npos);
  context.TryCancel();
  while (reader->Read(&message)) {
  }
  reader->Finish();
}

TEST(BenchmarkReport, QuantileInterpolatesBetweenOrderStatistics) {
  EXPECT_EQ(Quantile({}, 0.5), 0.0);
  EXPECT_EQ(Quantile({3.0}, 0.95), 3.0);
  EXPECT_DOUBLE_EQ(Quantile({4, 1, 3, 2}, 0.5), 2.5);
  EXPECT_DOUBLE_EQ(Quantile({1, 2, 3, 4, 5}, 0.5), 3.0);
  // numpy.percentile([0..19], 95) = 18.05
  std::vector<double> values;
  for (int i = 19; i >= 0; --i) values.push_back(i);
  EXPECT_DOUBLE_EQ(Quantile(values, 0.95), 18.05);
}

TEST(BenchmarkReport, CsvHasAHeaderAndOneQuotedLinePerRun) {
  std::vector<v1::BenchmarkRun> runs(2);
  runs[0].set_problem(0);
  runs[0].set_config(1);
  runs[0].set_outcome(v1::SUCCESS);
  runs[0].set_solved(true);
  runs[0].set_total_time(0.25);
  runs[1].set_problem(1);
  runs[1].set_config(0);
  runs[1].set_run(3);
  runs[1].set_outcome(v1::NO_PATH_WITHIN_BUDGET);
  const std::string csv = BenchmarkRunsCsv(runs, {"table", "odd, \"name\""}, {"a", "b"});
  std::vector<std::string> lines;
  std::size_t start = 0;
  for (std::size_t at = csv.find('\n'); at != std::string::npos; at = csv.find('\n', start)) {
    lines.push_back(csv.substr(start, at - start));
    start = at + 1;
  }
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_EQ(lines[0].rfind("problem,config,run,seed,outcome,solved,", 0), 0u);
  EXPECT_EQ(lines[1].rfind("table,b,0,0,SUCCESS,1,0,0,0,0.25,", 0), 0u) << lines[1];
  EXPECT_EQ(lines[2].rfind("\"odd, \"\"name\"\"\",a,3,0,NO_PATH_WITHIN_BUDGET,0,", 0), 0u) << lines[2];
}

void* volatile g_sink = nullptr;

TEST(HeapTracking, ScopesCountTheirThreadsOperatorNew) {
  HeapScope outer;
  std::unique_ptr<std::vector<char>> block;
  {
    HeapScope inner;
    block = std::make_unique<std::vector<char>>(1 << 20);
    EXPECT_GE(inner.peak_bytes(), 1u << 20);
    EXPECT_GE(inner.live_bytes(), 1 << 20);
    block.reset();
    EXPECT_LT(inner.live_bytes(), 1024);
    EXPECT_GE(inner.peak_bytes(), 1u << 20);  // the peak stays
  }
  // The inner scope's blocks count in the enclosing scope too (so its limit holds inside).
  EXPECT_GE(outer.peak_bytes(), 1u << 20);
  EXPECT_LT(outer.live_bytes(), 1024);
  const std::uint64_t peak = outer.peak_bytes();
  // Another thread's allocations are not this scope's.
  std::thread([] { std::vector<char> other(4 << 20); (void)other; }).join();
  EXPECT_EQ(outer.peak_bytes(), peak);
  EXPECT_LT(outer.live_bytes(), 1024);
  auto* array = new double[1000];
  g_sink = array;  // keeps the compiler from eliding the new/delete pair
  EXPECT_GE(outer.live_bytes(), static_cast<std::int64_t>(sizeof(double) * 1000));
  delete[] array;
}

}  // namespace
}  // namespace chasles
