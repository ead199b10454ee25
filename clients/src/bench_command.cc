// chasles bench CONFIG.yaml: benchmark planner configurations through the Benchmark RPC, with
// a progress bar, an OMPL log per problem (and the SQLite database ompl_benchmark_statistics
// makes of them), runs.csv, results.json and a summary table.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include <google/protobuf/util/json_util.h>
#include <grpcpp/grpcpp.h>
#include <yaml-cpp/yaml.h>

#include "chasles/server/benchmark_report.h"
#include "chasles/server/model_store.h"
#include "chasles/server/view_page.h"
#include "chasles/v1/chasles.grpc.pb.h"
#include "commands.h"
#include "moveit_import.h"

namespace chasles::cli {
namespace {

namespace fs = std::filesystem;
namespace v1 = chasles::v1;

constexpr int kExitOk = 0;
constexpr int kExitFailed = 1;
constexpr int kExitUsage = 2;

const char kBenchUsage[] =
    "Usage: chasles [--server ADDR] [--tls-ca F] [--token T] [--timeout S] bench CONFIG.yaml [--out DIR] [--runs N]\n"
    "                                  [--parallelism N] [--run-budget S] [--no-db] [--views] [--quiet]\n"
    "\n"
    "CONFIG.yaml (paths relative to the file):\n"
    "  experiment: NAME           name in the OMPL logs (default: the file's stem)\n"
    "  runs: 10                   runs per problem and configuration\n"
    "  run_budget: 5              planning budget per run [s]\n"
    "  parallelism: 0             runs at once (0 = the server's worker threads)\n"
    "  seed: 1                    run r uses seed + r\n"
    "  out: DIR                   output directory (default: bench-<experiment>)\n"
    "  problems:                  each one of\n"
    "    - request: FILE.json     a chasles.v1.PlanRequest (protobuf JSON)    [name: N]\n"
    "    - moveit: DIR            every sceneNNNN.yaml / requestNNNN.yaml pair in DIR\n"
    "    - moveit_scene: S.yaml   one MoveIt scene + request pair             [name: N]\n"
    "      moveit_request: R.yaml\n"
    "      (moveit entries may add robot: F.urdf and srdf: F.srdf, read for the joint order and\n"
    "       embedded in every request; default: the server's Panda)\n"
    "  configs:\n"
    "    - planner: rrt_connect   planner id (chasles planners lists them)    [name: N]\n"
    "      parameters: {range: 0.5}\n"
    "      post_processing: topp  topp | collocation | spline | none (default: the problem's)\n"
    "\n"
    "Writes DIR/<problem>.log (OMPL benchmark logs), DIR/results.db (ompl_benchmark_statistics,\n"
    "unless --no-db), DIR/runs.csv and DIR/results.json; prints a table per configuration. --views also\n"
    "writes DIR/views/index.html, a table of the runs linking each solved run's 3-D viewer page.\n"
    "Ctrl-C stops the benchmark and keeps the finished runs; a second Ctrl-C abandons it.\n";

std::atomic<int> g_interrupts{0};
extern "C" void OnInterrupt(int) { g_interrupts.fetch_add(1); }

/// A configuration error naming the file and the key path.
struct ConfigError {
  std::string message;
};

[[noreturn]] void Fail(const std::string& file, const std::string& key, const std::string& rule) {
  throw ConfigError{file + ": " + key + " " + rule};
}

std::string ReadFile(const fs::path& path, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError{"cannot read " + what + " '" + path.string() + "': " + std::strerror(errno)};
  std::ostringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

template <typename T>
T Scalar(const YAML::Node& node, const std::string& file, const std::string& key, const char* what) {
  try {
    return node.as<T>();
  } catch (const YAML::Exception&) {
    Fail(file, key, "= '" + (node.IsScalar() ? node.Scalar() : std::string("(not a scalar)")) + "' must be " + what);
  }
}

v1::ParameterValue ParameterFromYaml(const YAML::Node& node, const std::string& file, const std::string& key) {
  if (!node.IsScalar()) Fail(file, key, "must be a number or true/false");
  const std::string text = node.Scalar();
  v1::ParameterValue value;
  if (text == "true" || text == "false") {
    value.set_bool_value(text == "true");
    return value;
  }
  char* end = nullptr;
  errno = 0;
  const long long integer = std::strtoll(text.c_str(), &end, 10);
  if (end != text.c_str() && *end == '\0' && errno == 0) {
    value.set_int_value(integer);
    return value;
  }
  end = nullptr;
  const double number = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0') Fail(file, key, "= '" + text + "' must be a number or true/false");
  value.set_double_value(number);
  return value;
}

/// The robot of a moveit entry: robot: F.urdf (and srdf: F.srdf), else the server's default.
moveit::RobotInfo MoveItRobot(const YAML::Node& entry, const fs::path& base, const std::string& file,
                              const std::string& key) {
  if (!entry["robot"]) {
    if (entry["srdf"]) Fail(file, key + ".srdf", "needs robot: F.urdf (the SRDF belongs to a URDF)");
    return moveit::DefaultRobot();
  }
  const fs::path urdf = base / Scalar<std::string>(entry["robot"], file, key + ".robot", "a file name");
  std::string srdf;
  if (entry["srdf"]) srdf = ReadFile(base / Scalar<std::string>(entry["srdf"], file, key + ".srdf", "a file name"), "SRDF");
  return moveit::RobotFromUrdf(ReadFile(urdf, "URDF"), srdf);
}

/// A request imported for `robot`: a robot given with robot: is embedded in it (the server
/// would otherwise plan for its default Panda); the default robot is left to the server.
void SetMoveItRobot(const YAML::Node& entry, const moveit::RobotInfo& robot, v1::PlanRequest* request) {
  if (entry["robot"]) *request->mutable_robot() = robot.model;
}

struct BenchConfig {
  v1::BenchmarkRequest request;
  std::string out;
};

BenchConfig LoadConfig(const std::string& path) {
  const std::string file = fs::path(path).filename().string();
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw ConfigError{"cannot read benchmark configuration '" + path + "': " + std::strerror(errno)};
  } catch (const YAML::ParserException& e) {
    throw ConfigError{file + ": malformed YAML at line " + std::to_string(e.mark.line + 1) + ", column " +
                      std::to_string(e.mark.column + 1) + ": " + e.msg};
  }
  if (!root.IsMap()) Fail(file, "(top level)", "must be a map with problems and configs");
  const fs::path base = fs::path(path).parent_path();
  BenchConfig config;
  v1::BenchmarkRequest& request = config.request;
  const std::string stem = fs::path(path).stem().string();
  request.set_experiment(root["experiment"] ? Scalar<std::string>(root["experiment"], file, "experiment", "a name") : stem);
  if (root["runs"]) request.set_runs(Scalar<std::uint32_t>(root["runs"], file, "runs", "a whole number >= 1"));
  if (root["run_budget"]) request.set_run_budget(Scalar<double>(root["run_budget"], file, "run_budget", "a number of seconds"));
  if (root["parallelism"]) {
    request.set_parallelism(Scalar<std::uint32_t>(root["parallelism"], file, "parallelism", "a whole number >= 0"));
  }
  if (root["seed"]) request.set_seed(Scalar<std::uint64_t>(root["seed"], file, "seed", "a whole number >= 0"));
  config.out = root["out"] ? (base / Scalar<std::string>(root["out"], file, "out", "a directory")).string()
                           : "bench-" + request.experiment();
  for (const auto& known : root) {
    static const char* const kKeys[] = {"experiment", "runs", "run_budget", "parallelism", "seed", "out", "problems", "configs"};
    const std::string key = known.first.as<std::string>();
    if (std::find(std::begin(kKeys), std::end(kKeys), key) == std::end(kKeys)) {
      Fail(file, key, "is not a known key (experiment, runs, run_budget, parallelism, seed, out, problems, configs)");
    }
  }

  const YAML::Node problems = root["problems"];
  if (!problems || !problems.IsSequence() || problems.size() == 0) Fail(file, "problems", "must be a non-empty list");
  for (std::size_t i = 0; i < problems.size(); ++i) {
    const YAML::Node entry = problems[i];
    const std::string key = "problems[" + std::to_string(i) + "]";
    if (!entry.IsMap()) Fail(file, key, "must be a map (request:, moveit: or moveit_scene: + moveit_request:)");
    const std::string name = entry["name"] ? Scalar<std::string>(entry["name"], file, key + ".name", "a name") : "";
    if (!entry["request"] && !entry["moveit"] && !(entry["moveit_scene"] && entry["moveit_request"])) {
      Fail(file, key, "needs request: FILE.json, moveit: DIR, or moveit_scene: + moveit_request:");
    }
    for (const auto& field : entry) {
      static const char* const kProblemKeys[] = {"name", "request", "moveit", "moveit_scene", "moveit_request", "robot", "srdf"};
      const std::string field_name = field.first.as<std::string>();
      if (std::find(std::begin(kProblemKeys), std::end(kProblemKeys), field_name) == std::end(kProblemKeys)) {
        Fail(file, key + "." + field_name,
             "is not a known key (name, request, moveit, moveit_scene, moveit_request, robot, srdf)");
      }
    }
    if (entry["request"] && (entry["robot"] || entry["srdf"])) {
      Fail(file, key + (entry["robot"] ? ".robot" : ".srdf"),
           "belongs to moveit entries (a request: FILE.json names its robot itself)");
    }
    try {
      if (entry["request"]) {
        const fs::path json = base / Scalar<std::string>(entry["request"], file, key + ".request", "a file name");
        v1::BenchmarkProblem* problem = request.add_problems();
        const auto status = google::protobuf::util::JsonStringToMessage(ReadFile(json, "request"), problem->mutable_request());
        if (!status.ok()) {
          Fail(file, key + ".request", "= '" + json.string() + "' is not a chasles.v1.PlanRequest in protobuf JSON: " +
                                           std::string(status.message()));
        }
        problem->set_name(name.empty() ? json.stem().string() : name);
      } else if (entry["moveit"]) {
        const fs::path directory = base / Scalar<std::string>(entry["moveit"], file, key + ".moveit", "a directory");
        const moveit::RobotInfo robot = MoveItRobot(entry, base, file, key);
        for (moveit::MoveItProblem& imported : moveit::ImportProblemDirectory(directory.string(), robot)) {
          v1::BenchmarkProblem* problem = request.add_problems();
          problem->set_name(name.empty() ? imported.name : name + "/" + imported.name);
          *problem->mutable_request() = std::move(imported.request);
          SetMoveItRobot(entry, robot, problem->mutable_request());
        }
      } else {  // moveit_scene + moveit_request
        const fs::path scene = base / Scalar<std::string>(entry["moveit_scene"], file, key + ".moveit_scene", "a file name");
        const fs::path motion = base / Scalar<std::string>(entry["moveit_request"], file, key + ".moveit_request", "a file name");
        const moveit::RobotInfo robot = MoveItRobot(entry, base, file, key);
        v1::BenchmarkProblem* problem = request.add_problems();
        *problem->mutable_request() =
            moveit::ImportMotionPlanRequest(ReadFile(scene, "MoveIt scene"), ReadFile(motion, "MoveIt request"), robot,
                                            scene.filename().string(), motion.filename().string());
        SetMoveItRobot(entry, robot, problem->mutable_request());
        problem->set_name(name.empty() ? scene.stem().string() : name);
      }
    } catch (const std::exception& e) {
      // Importer errors name the MoveIt file and key; say which problem entry it was.
      throw ConfigError{file + ": " + key + ": " + e.what()};
    }
  }

  const YAML::Node configs = root["configs"];
  if (!configs || !configs.IsSequence() || configs.size() == 0) Fail(file, "configs", "must be a non-empty list");
  for (std::size_t i = 0; i < configs.size(); ++i) {
    const YAML::Node entry = configs[i];
    const std::string key = "configs[" + std::to_string(i) + "]";
    if (!entry.IsMap() || !entry["planner"]) Fail(file, key, "must be a map with planner: ID");
    v1::BenchmarkConfig* out = request.add_configs();
    if (entry["name"]) out->set_name(Scalar<std::string>(entry["name"], file, key + ".name", "a name"));
    out->mutable_planner()->set_planner_id(Scalar<std::string>(entry["planner"], file, key + ".planner", "a planner id"));
    if (const YAML::Node parameters = entry["parameters"]) {
      if (!parameters.IsMap()) Fail(file, key + ".parameters", "must be a map NAME: VALUE");
      for (const auto& parameter : parameters) {
        const std::string pname = parameter.first.as<std::string>();
        (*out->mutable_planner()->mutable_parameters())[pname] =
            ParameterFromYaml(parameter.second, file, key + ".parameters." + pname);
      }
    }
    if (const YAML::Node post = entry["post_processing"]) {
      std::string word = Scalar<std::string>(post, file, key + ".post_processing", "topp, collocation, spline or none");
      for (char& c : word) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
      v1::TrajectoryOptions::PostProcessing value;
      if (!v1::TrajectoryOptions::PostProcessing_Parse(word, &value) || value == v1::TrajectoryOptions::POST_PROCESSING_UNSPECIFIED) {
        Fail(file, key + ".post_processing", "= '" + post.Scalar() + "' must be topp, collocation, spline or none");
      }
      out->mutable_trajectory()->set_post_processing(value);
    }
  }
  return config;
}

/// The progress line: a bar when stderr is a terminal, else a line every 10 %.
class ProgressBar {
 public:
  explicit ProgressBar(bool quiet) : quiet_(quiet), tty_(isatty(STDERR_FILENO) != 0) {}
  void Update(const v1::BenchmarkProgress& p, std::uint32_t solved) {
    if (quiet_ || p.total() == 0) return;
    const double fraction = static_cast<double>(p.done()) / p.total();
    char eta[32] = "?";
    if (p.eta() >= 0) std::snprintf(eta, sizeof(eta), "%.0f s", p.eta());
    if (tty_) {
      const int width = 30, filled = static_cast<int>(fraction * width + 0.5);
      std::fprintf(stderr, "\r[%s%s] %u/%u runs, %u solved, %u running, %.0f s elapsed, ETA %s   ",
                   std::string(filled, '#').c_str(), std::string(width - filled, '.').c_str(), p.done(), p.total(),
                   solved, p.running(), p.elapsed(), eta);
      std::fflush(stderr);
      drawn_ = true;
    } else {
      const int decile = static_cast<int>(fraction * 10);
      if (decile > last_decile_) {
        last_decile_ = decile;
        std::fprintf(stderr, "bench: %u/%u runs, %u solved, %.0f s elapsed, ETA %s\n", p.done(), p.total(), solved,
                     p.elapsed(), eta);
      }
    }
  }
  void End() {
    if (drawn_) std::fprintf(stderr, "\n");
    drawn_ = false;
  }

 private:
  bool quiet_, tty_, drawn_ = false;
  int last_decile_ = -1;
};

std::string SafeFileName(std::string name) {
  for (char& c : name) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.')) c = '_';
  }
  return name;
}

void WriteFile(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  if (!out) throw ConfigError{"cannot write '" + path.string() + "': " + std::strerror(errno)};
}

/// --views: DIR/views/<problem>-<config>-<run>.html for every solved run with knots (the
/// viewer page, three.js shared in DIR/views/three.js) and DIR/views/index.html linking each
/// run of the table. Returns the number of pages.
std::size_t WriteViews(const fs::path& dir, const v1::BenchmarkRequest& request, const std::vector<v1::BenchmarkRun>& runs,
                       const std::vector<std::string>& problem_names, const std::vector<std::string>& config_names) {
  fs::create_directories(dir);
  WriteFile(dir / "three.js", ViewerLibraryJs());
  ModelStore store(DefaultRobotProto(), DefaultSceneProto());
  std::vector<v1::BenchmarkRun> sorted = runs;
  std::sort(sorted.begin(), sorted.end(), [](const v1::BenchmarkRun& a, const v1::BenchmarkRun& b) {
    return std::make_tuple(a.problem(), a.config(), a.run()) < std::make_tuple(b.problem(), b.config(), b.run());
  });
  std::string index =
      "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>chasles bench: runs</title></head>"
      "<body style=\"font-family:sans-serif\"><h1>Benchmark runs</h1><table cellpadding=\"4\"><tr><th>problem</th>"
      "<th>configuration</th><th>run</th><th>outcome</th><th>plan [ms]</th><th>total [ms]</th><th>duration [s]</th>"
      "<th>min clearance [mm]</th></tr>";
  std::size_t pages = 0;
  for (const v1::BenchmarkRun& run : sorted) {
    const std::string problem = run.problem() < problem_names.size() ? problem_names[run.problem()] : "?";
    const std::string config = run.config() < config_names.size() ? config_names[run.config()] : "?";
    std::string cell = v1::PlanOutcome_Name(run.outcome());
    if (run.solved() && run.knots().times_size() > 0 && run.problem() < static_cast<std::uint32_t>(request.problems_size())) {
      v1::PlanResponse response;
      response.set_outcome(run.outcome());
      response.set_message(run.message());
      response.set_request_id(problem + " / " + config + " / run " + std::to_string(run.run()));
      response.set_duration(run.duration());
      *response.mutable_knots() = run.knots();
      const std::string file = SafeFileName(problem + "-" + config + "-" + std::to_string(run.run())) + ".html";
      WriteFile(dir / file, ViewPageHtml(ViewDataJson(ViewOfPlan(store, request.problems(run.problem()).request(), response)),
                                         "three.js"));
      cell = "<a href=\"" + HtmlEscaped(file) + "\">" + cell + "</a>";
      ++pages;
    }
    char numbers[160];
    std::snprintf(numbers, sizeof numbers, "<td>%.2f</td><td>%.2f</td><td>%.3f</td><td>%s</td>", 1e3 * run.plan_time(),
                  1e3 * run.total_time(), run.duration(),
                  run.min_clearance() < 0.0 ? "" : std::to_string(1e3 * run.min_clearance()).c_str());
    index += "<tr><td>" + HtmlEscaped(problem) + "</td><td>" + HtmlEscaped(config) + "</td><td>" +
             std::to_string(run.run()) + "</td><td>" + cell + "</td>" + numbers + "</tr>";
  }
  index += "</table></body></html>\n";
  WriteFile(dir / "index.html", index);
  return pages;
}

std::string Json(const google::protobuf::Message& message) {
  std::string json;
  google::protobuf::util::JsonPrintOptions options;
  options.preserve_proto_field_names = true;
  options.always_print_primitive_fields = true;
  (void)google::protobuf::util::MessageToJsonString(message, &json, options);
  return json;
}

void PrintTable(const v1::BenchmarkSummary& summary) {
  std::printf("%-24s %5s %6s %8s %11s %11s %12s %11s\n", "configuration", "runs", "solved", "success",
              "median [s]", "p95 [s]", "length [rad]", "duration [s]");
  for (const v1::ConfigSummary& c : summary.configs()) {
    std::printf("%-24s %5u %6u %7.0f%% %11.4f %11.4f %12.3f %11.3f\n", c.name().c_str(), c.runs(), c.solved(),
                100.0 * c.success_rate(), c.median_time(), c.p95_time(), c.median_length(), c.median_duration());
  }
  std::printf("%u of %u runs finished in %.1f s wall, %u at once%s\n", summary.runs_finished(), summary.runs_total(),
              summary.wall_time(), summary.parallelism(), summary.stopped() ? " (stopped early)" : "");
}

}  // namespace

/// One server's share of a benchmark: its request (runs first_run … first_run + runs - 1 of the
/// whole, seeded as they would be there) and what it answered.
struct Shard {
  ConnectionOptions connection;
  v1::BenchmarkRequest request;
  std::uint32_t first_run = 0;
  grpc::ClientContext context;
  std::unique_ptr<v1::Planning::Stub> stub;
  std::vector<v1::BenchmarkRun> finished;
  v1::BenchmarkProgress progress;
  std::uint32_t solved = 0;
  v1::BenchmarkSummary summary;
  bool have_summary = false;
  grpc::Status status;

  /// Its channel and deadline, before any thread streams or stops it.
  Shard(const ConnectionOptions& options, v1::BenchmarkRequest shard_request, std::uint32_t first, double timeout)
      : connection(options), request(std::move(shard_request)), first_run(first) {
    grpc::ChannelArguments channel_args;
    channel_args.SetMaxReceiveMessageSize(-1);
    channel_args.SetMaxSendMessageSize(-1);
    stub = v1::Planning::NewStub(MakeChannel(connection, channel_args));
    if (timeout > 0) {
      context.set_deadline(std::chrono::system_clock::now() + std::chrono::duration_cast<std::chrono::system_clock::duration>(
                                                                  std::chrono::duration<double>(timeout)));
    }
  }

  /// Streams the benchmark; `report` is called (under `mutex`'s protection of this shard's
  /// progress) after every message.
  void Run(std::mutex& mutex, const std::function<void()>& report) {
    auto reader = stub->Benchmark(&context, request);
    v1::BenchmarkResponse message;
    while (reader->Read(&message)) {
      {
        std::lock_guard<std::mutex> lock(mutex);
        if (message.has_run()) {
          v1::BenchmarkRun run = message.run();
          run.set_run(run.run() + first_run);
          if (run.solved()) ++solved;
          finished.push_back(std::move(run));
        }
        if (message.has_summary()) {
          summary = message.summary();
          have_summary = true;
        }
        progress = message.progress();
      }
      report();
    }
    status = reader->Finish();
  }

  /// StopBenchmark for this shard (its server answers the summary of the finished runs).
  void Stop() {
    grpc::ClientContext stop_context;
    stop_context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(5));
    v1::StopBenchmarkRequest stop;
    stop.set_request_id(request.request_id());
    v1::StopBenchmarkResponse stopped;
    (void)stub->StopBenchmark(&stop_context, stop, &stopped);
  }
};

/// The OMPL logs of one problem from several shards as one: the first's header and settings,
/// every shard's run lines under each planner (in shard order, so in run order), the run and time
/// totals updated. \throws ConfigError when the logs do not have the same planners.
std::string MergeOmplLogs(const std::vector<std::string>& logs, std::uint32_t runs_per_planner, double seconds) {
  std::vector<std::vector<std::string>> lines(logs.size());
  for (std::size_t k = 0; k < logs.size(); ++k) {
    std::istringstream in(logs[k]);
    for (std::string line; std::getline(in, line);) lines[k].push_back(line);
  }
  const auto ends_with = [](const std::string& line, const std::string& tail) {
    return line.size() >= tail.size() && line.compare(line.size() - tail.size(), tail.size(), tail) == 0;
  };
  // Per shard: where each planner's "N runs" line is.
  std::vector<std::vector<std::size_t>> run_lines(logs.size());
  for (std::size_t k = 0; k < logs.size(); ++k) {
    for (std::size_t i = 0; i < lines[k].size(); ++i) {
      const std::string& line = lines[k][i];
      if (ends_with(line, " runs") && line.find_first_not_of("0123456789") == line.size() - 5) run_lines[k].push_back(i);
    }
    if (run_lines[k].size() != run_lines[0].size()) throw ConfigError{"the shards' OMPL logs list different planners"};
  }
  std::ostringstream out;
  const auto copy = [&](std::size_t from, std::size_t until) {  // shard 0's lines, totals updated
    for (std::size_t i = from; i < until; ++i) {
      const std::string& line = lines[0][i];
      if (ends_with(line, " runs per planner")) {
        out << runs_per_planner << " runs per planner\n";
      } else if (ends_with(line, " seconds spent to collect the data")) {
        out << seconds << " seconds spent to collect the data\n";
      } else {
        out << line << "\n";
      }
    }
  };
  std::size_t next = 0;
  for (std::size_t p = 0; p < run_lines[0].size(); ++p) {
    copy(next, run_lines[0][p]);
    std::vector<std::string> rows;  // this planner's runs, shard after shard
    for (std::size_t k = 0; k < logs.size(); ++k) {
      const std::size_t at = run_lines[k][p];
      const std::size_t n = std::stoul(lines[k][at]);
      for (std::size_t r = 0; r < n && at + 1 + r < lines[k].size(); ++r) rows.push_back(lines[k][at + 1 + r]);
    }
    out << rows.size() << " runs\n";
    for (const std::string& row : rows) out << row << "\n";
    next = run_lines[0][p] + 1 + std::stoul(lines[0][run_lines[0][p]]);
  }
  copy(next, lines[0].size());
  return out.str();
}

/// One summary from the shards': names from the first, configuration summaries from every run,
/// each problem's OMPL log merged.
v1::BenchmarkSummary MergeSummaries(const std::vector<const v1::BenchmarkSummary*>& parts,
                                    const std::vector<v1::BenchmarkRun>& runs, const std::string& request_id,
                                    double wall_time) {
  v1::BenchmarkSummary merged;
  const v1::BenchmarkSummary& first = *parts.front();
  *merged.mutable_problem_names() = first.problem_names();
  *merged.mutable_config_names() = first.config_names();
  const std::vector<std::string> config_names(first.config_names().begin(), first.config_names().end());
  for (v1::ConfigSummary& c : SummarizeConfigs(runs, config_names)) *merged.add_configs() = std::move(c);
  std::uint32_t runs_total = 0, parallelism = 0, runs_per_planner = 0;
  for (const v1::BenchmarkSummary* part : parts) {
    runs_total += part->runs_total();
    parallelism += part->parallelism();
    merged.set_stopped(merged.stopped() || part->stopped());
  }
  const std::uint32_t cells = static_cast<std::uint32_t>(std::max(1, first.problem_names_size() * first.config_names_size()));
  runs_per_planner = runs_total / cells;
  for (int p = 0; p < first.logs_size(); ++p) {
    std::vector<std::string> logs;
    for (const v1::BenchmarkSummary* part : parts) {
      if (p < part->logs_size()) logs.push_back(part->logs(p).ompl_log());
    }
    v1::ProblemLog* log = merged.add_logs();
    log->set_problem(first.logs(p).problem());
    log->set_name(first.logs(p).name());
    log->set_ompl_log(MergeOmplLogs(logs, runs_per_planner, wall_time));
  }
  merged.set_runs_finished(static_cast<std::uint32_t>(runs.size()));
  merged.set_runs_total(runs_total);
  merged.set_wall_time(wall_time);
  merged.set_parallelism(parallelism);
  merged.set_request_id(request_id);
  return merged;
}

/// The shards of `request` over the --server addresses: shard k runs its share of the runs from
/// its first run on, seeded as those runs would be on one server.
std::vector<std::unique_ptr<Shard>> MakeShards(const ConnectionOptions& connection, const v1::BenchmarkRequest& request,
                                               double timeout) {
  const std::vector<std::string> servers = ServerAddresses(connection.server);
  const std::uint32_t total_runs = request.runs() == 0 ? 10 : request.runs();
  const std::uint64_t first_seed = request.seed() == 0 ? 1 : request.seed();
  std::vector<std::unique_ptr<Shard>> shards;
  for (std::size_t k = 0, start = 0; k < servers.size(); ++k) {
    const std::uint32_t share = static_cast<std::uint32_t>(total_runs / servers.size() + (k < total_runs % servers.size()));
    if (share == 0) continue;
    ConnectionOptions one = connection;
    one.server = servers[k];
    v1::BenchmarkRequest part = request;
    part.set_runs(share);
    part.set_seed(first_seed + start);
    if (servers.size() > 1) part.set_request_id(request.request_id() + "-" + std::to_string(k));
    shards.push_back(std::make_unique<Shard>(one, std::move(part), static_cast<std::uint32_t>(start), timeout));
    start += share;
  }
  return shards;
}

/// Streams every shard at once, with one progress bar; Ctrl-C first stops them (their servers
/// answer the summary of the finished runs), a second Ctrl-C cancels them.
void StreamShards(const std::vector<std::unique_ptr<Shard>>& shards, const v1::BenchmarkRequest& request, bool quiet) {
  const std::uint32_t total_runs = request.runs() == 0 ? 10 : request.runs();
  const std::uint32_t total = total_runs * static_cast<std::uint32_t>(request.problems_size() * request.configs_size());
  const auto started = std::chrono::steady_clock::now();
  g_interrupts = 0;
  std::signal(SIGINT, OnInterrupt);
  std::atomic<bool> streaming{true};
  std::thread watcher([&] {
    int handled = 0;
    while (streaming.load()) {
      const int seen = g_interrupts.load();
      if (seen > handled) {
        handled = seen;
        if (handled == 1) {
          std::fprintf(stderr, "\nchasles: stopping the benchmark (finished runs are kept; Ctrl-C again to abandon it)\n");
          for (const auto& shard : shards) shard->Stop();
        } else {
          for (const auto& shard : shards) shard->context.TryCancel();
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  });

  ProgressBar bar(quiet);
  std::mutex progress_mutex;
  const auto report = [&] {  // the shards' progress together
    std::lock_guard<std::mutex> lock(progress_mutex);
    v1::BenchmarkProgress p;
    std::uint32_t solved = 0;
    double eta = 0.0;
    for (const auto& shard : shards) {
      p.set_done(p.done() + shard->progress.done());
      p.set_running(p.running() + shard->progress.running());
      eta = std::max(eta, shard->progress.eta());
      solved += shard->solved;
    }
    p.set_total(total);
    p.set_elapsed(std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count());
    p.set_eta(eta);
    bar.Update(p, solved);
  };
  std::vector<std::thread> readers;
  for (const auto& shard : shards) {
    readers.emplace_back([&shard, &report, &progress_mutex] { shard->Run(progress_mutex, report); });
  }
  for (std::thread& reader : readers) reader.join();
  streaming = false;
  watcher.join();
  std::signal(SIGINT, SIG_DFL);
  bar.End();
}

/// The shards' answers as one benchmark's.
struct MergedRuns {
  std::vector<v1::BenchmarkRun> finished;  ///< run numbers of the whole benchmark
  v1::BenchmarkSummary summary;
  bool have_summary = true;  ///< every shard answered its summary
  grpc::Status status;       ///< the first shard's failure, naming its server
};

/// Runs renumbered from their shard's first run; summaries recomputed from all runs and each
/// problem's OMPL log merged (MergeSummaries), or one shard's summary as it came.
/// \throws ConfigError when the shards' logs do not fit together.
MergedRuns MergeShards(const std::vector<std::unique_ptr<Shard>>& shards, const std::string& request_id,
                       double wall_time) {
  MergedRuns merged;
  std::vector<const v1::BenchmarkSummary*> summaries;
  for (const auto& shard : shards) {
    merged.finished.insert(merged.finished.end(), shard->finished.begin(), shard->finished.end());
    if (!shard->status.ok() && merged.status.ok()) {
      merged.status =
          grpc::Status(shard->status.error_code(), shard->connection.server + ": " + shard->status.error_message());
    }
    if (shard->have_summary) {
      summaries.push_back(&shard->summary);
    } else {
      merged.have_summary = false;
    }
  }
  if (merged.have_summary && summaries.size() == 1) {
    merged.summary = *summaries[0];
  } else if (merged.have_summary) {
    merged.summary = MergeSummaries(summaries, merged.finished, request_id, wall_time);
  }
  return merged;
}

int BenchCommand(const ConnectionOptions& connection, double timeout, const std::vector<std::string>& args) {
  const std::string& server = connection.server;
  std::string config_path, out_dir;
  std::int64_t runs = -1, parallelism = -1;
  double run_budget = -1;
  bool quiet = false, make_db = true, views = false;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= args.size()) {
        std::cerr << "chasles: bench " << arg << " needs a value\n";
        std::exit(kExitUsage);
      }
      return args[++i];
    };
    auto number = [&](const std::string& text, double min) {
      char* end = nullptr;
      const double v = std::strtod(text.c_str(), &end);
      if (end == text.c_str() || *end != '\0' || !(v >= min)) {
        std::cerr << "chasles: bench " << arg << " '" << text << "' must be a number >= " << min << "\n";
        std::exit(kExitUsage);
      }
      return v;
    };
    if (arg == "--help" || arg == "-h") {
      std::cout << kBenchUsage;
      return kExitOk;
    } else if (arg == "--out") {
      out_dir = value();
    } else if (arg == "--runs") {
      runs = static_cast<std::int64_t>(number(value(), 1));
    } else if (arg == "--parallelism") {
      parallelism = static_cast<std::int64_t>(number(value(), 0));
    } else if (arg == "--run-budget") {
      run_budget = number(value(), 1e-3);
    } else if (arg == "--quiet") {
      quiet = true;
    } else if (arg == "--no-db") {
      make_db = false;
    } else if (arg == "--views") {
      views = true;
    } else if (!arg.empty() && arg[0] == '-') {
      std::cerr << "chasles: bench: unknown option '" << arg << "'\n(see chasles bench --help)\n";
      return kExitUsage;
    } else if (config_path.empty()) {
      config_path = arg;
    } else {
      std::cerr << "chasles: bench takes one CONFIG.yaml\n";
      return kExitUsage;
    }
  }
  if (config_path.empty()) {
    std::cerr << "chasles: bench needs CONFIG.yaml\n(see chasles bench --help)\n";
    return kExitUsage;
  }

  BenchConfig config;
  try {
    config = LoadConfig(config_path);
  } catch (const ConfigError& e) {
    std::cerr << "chasles: " << e.message << "\n";
    return kExitUsage;
  }
  v1::BenchmarkRequest& request = config.request;
  if (runs > 0) request.set_runs(static_cast<std::uint32_t>(runs));
  if (parallelism >= 0) request.set_parallelism(static_cast<std::uint32_t>(parallelism));
  if (run_budget > 0) request.set_run_budget(run_budget);
  if (!out_dir.empty()) config.out = out_dir;
  if (views) request.set_trajectories(true);
  request.set_request_id("cli-bench-" + std::to_string(getpid()) + "-" +
                         std::to_string(std::chrono::system_clock::now().time_since_epoch().count() % 1000000007));

  // One shard per --server address: each runs its share of the runs (run r keeps seed + r), and
  // the answers are merged into one set of runs, summaries and OMPL logs.
  const auto started = std::chrono::steady_clock::now();
  const std::vector<std::unique_ptr<Shard>> shards = MakeShards(connection, request, timeout);
  StreamShards(shards, request, quiet);
  MergedRuns merged;
  try {
    merged = MergeShards(shards, request.request_id(),
                         std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count());
  } catch (const ConfigError& e) {
    std::cerr << "chasles: " << e.message << "\n";
    return kExitFailed;
  }
  const std::vector<v1::BenchmarkRun>& finished = merged.finished;
  const v1::BenchmarkSummary& summary = merged.summary;
  const bool have_summary = merged.have_summary;
  const grpc::Status& status = merged.status;
  std::vector<std::string> problem_names, config_names;
  if (have_summary) {
    problem_names.assign(summary.problem_names().begin(), summary.problem_names().end());
    config_names.assign(summary.config_names().begin(), summary.config_names().end());
  } else {
    for (const auto& p : request.problems()) problem_names.push_back(p.name());
    for (const auto& c : request.configs()) config_names.push_back(c.name().empty() ? c.planner().planner_id() : c.name());
  }
  if (!status.ok() && finished.empty()) {
    std::cerr << "chasles: Benchmark on " << server << " failed (gRPC status " << status.error_code()
              << "): " << status.error_message() << "\n";
    return kExitFailed;
  }

  try {
    const fs::path out(config.out);
    fs::create_directories(out);
    WriteFile(out / "runs.csv", BenchmarkRunsCsv(finished, problem_names, config_names));
    std::ostringstream json;
    json << "{\n\"request_id\": \"" << request.request_id() << "\",\n\"summary\": "
         << (have_summary ? Json(summary) : "null") << ",\n\"runs\": [";
    for (std::size_t i = 0; i < finished.size(); ++i) json << (i ? ",\n" : "\n") << Json(finished[i]);
    json << "\n]\n}\n";
    WriteFile(out / "results.json", json.str());
    std::vector<std::string> logs;
    for (const v1::ProblemLog& log : summary.logs()) {
      const fs::path file = out / (SafeFileName(log.name()) + ".log");
      WriteFile(file, log.ompl_log());
      logs.push_back(file.string());
    }
    if (have_summary) PrintTable(summary);
    std::printf("wrote %s/runs.csv, results.json", out.string().c_str());
    if (!logs.empty()) std::printf(" and %zu OMPL log%s", logs.size(), logs.size() == 1 ? "" : "s");
    std::printf("\n");
    if (views) {
      const std::size_t pages = WriteViews(out / "views", request, finished, problem_names, config_names);
      std::printf("wrote %s/views/index.html and %zu viewer page%s (one per solved run)\n", out.string().c_str(), pages,
                  pages == 1 ? "" : "s");
    }
    if (!logs.empty() && make_db) {
      const fs::path db = out / "results.db";
      fs::remove(db);
      // Debian's ompl_benchmark_statistics (package ompl-demos) runs under /usr/bin/python3.
      std::string command = "/usr/bin/ompl_benchmark_statistics";
      for (const std::string& log : logs) command += " '" + log + "'";
      command += " -d '" + db.string() + "' > '" + (out / "ompl_benchmark_statistics.txt").string() + "' 2>&1";
      if (access("/usr/bin/ompl_benchmark_statistics", X_OK) != 0) {
        std::printf("ompl_benchmark_statistics is not installed (Debian package ompl-demos): no results.db\n");
      } else if (std::system(command.c_str()) == 0) {
        std::printf("wrote %s (Planner Arena database; ompl_benchmark_statistics)\n", db.string().c_str());
      } else {
        std::printf("ompl_benchmark_statistics failed; see %s\n", (out / "ompl_benchmark_statistics.txt").string().c_str());
      }
    }
  } catch (const std::exception& e) {
    std::cerr << "chasles: " << e.what() << "\n";
    return kExitFailed;
  } catch (const ConfigError& e) {
    std::cerr << "chasles: " << e.message << "\n";
    return kExitFailed;
  }
  if (!status.ok()) {
    std::cerr << "chasles: the benchmark ended early (gRPC status " << status.error_code() << "): "
              << status.error_message() << "; the " << finished.size() << " finished runs were written\n";
    return kExitFailed;
  }
  return kExitOk;
}

}  // namespace chasles::cli
