// chasles-bench --section pipeline: the single-arm pipeline's speed (issue 16). For each Panda
// scene, the same seeded queries run in-process through the fast checker ("ours"), through the
// same checker forced through FCL (the baseline), and as Plan RPCs over loopback; the three
// alternate `repeats` times so a load change on the machine hits all of them, and every figure
// is a median (or p95) over all runs.
#include "bench_pipeline.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <google/protobuf/util/json_util.h>
#include <grpcpp/grpcpp.h>

#include "chasles/collision/collision_checker.h"
#include "chasles/pipeline/plan_pipeline.h"
#include "chasles/planners/registry.h"
#include "chasles/robot/robot_model.h"
#include "chasles/server/benchmark_report.h"
#include "chasles/server/convert.h"
#include "chasles/server/planning_server.h"
#include "chasles/v1/chasles.grpc.pb.h"

namespace chasles {

Eigen::VectorXd RandomConfiguration(const RobotModel& robot, std::mt19937_64* rng) {
  Eigen::VectorXd q(robot.num_dofs());
  for (int i = 0; i < q.size(); ++i) {
    const double u = static_cast<double>((*rng)() >> 11) * 0x1.0p-53;
    q[i] = robot.lower_limits()[i] + u * (robot.upper_limits()[i] - robot.lower_limits()[i]);
  }
  return q;
}

double QuantileOrNan(std::vector<double> values, double p) {
  return values.empty() ? std::nan("") : ::chasles::Quantile(std::move(values), p);
}

std::pair<Eigen::VectorXd, Eigen::VectorXd> RandomBlockedPair(const CollisionChecker& checker, std::mt19937_64* rng) {
  const auto valid = [&] {
    for (;;) {
      Eigen::VectorXd q = RandomConfiguration(checker.robot(), rng);
      if (checker.IsValid(q)) return q;
    }
  };
  Eigen::VectorXd a, b;
  do {
    a = valid();
    b = valid();
  } while ((a - b).cwiseAbs().maxCoeff() < 1.0 || checker.IsMotionValid(a, b, 0.005));
  return {std::move(a), std::move(b)};
}

BenchServer StartBenchServer(int max_message_mb) {
  ServerOptions options;
  options.listen = "127.0.0.1:0";
  options.threads = 1;
  options.log_requests = false;
  options.max_message_mb = max_message_mb;
  BenchServer out;
  out.server = std::make_unique<PlanningServer>(options);
  grpc::ChannelArguments arguments;
  arguments.SetMaxReceiveMessageSize(max_message_mb << 20);
  arguments.SetMaxSendMessageSize(max_message_mb << 20);
  out.stub = v1::Planning::NewStub(grpc::CreateCustomChannel("127.0.0.1:" + std::to_string(out.server->port()),
                                                             grpc::InsecureChannelCredentials(), arguments));
  return out;
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

namespace {

using Clock = std::chrono::steady_clock;

// The targets (RRT-Connect, Panda).
constexpr double kPlanMedianTargetMs = 0.25;
constexpr double kPipelineMedianTargetMs = 2.0;
constexpr double kRpcMedianTargetMs = 4.0;
constexpr double kP95OverMedianTarget = 10.0;

/// The p-quantile, but nan (a visible table cell) for no values instead of 0.
double MillisSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

/// The load averages over 1, 5 and 15 minutes, as /proc/loadavg has them.
std::string LoadAverage() {
  std::ifstream in("/proc/loadavg");
  double one = 0, five = 0, fifteen = 0;
  if (!(in >> one >> five >> fifteen)) return "unknown";
  char text[64];
  std::snprintf(text, sizeof text, "%.2f %.2f %.2f", one, five, fifteen);
  return text;
}

/// One checker path's figures over every run of every repeat (solved queries only).
struct StageSeries {
  std::vector<double> plan, shortcut, parameterize, verify, other, total, state_checks;  // [ms], counts
  std::vector<double> repeat_total_medians;  // the pipeline median of each repeat [ms]
  std::map<std::string, int> unsolved;       // outcome → count
  std::map<std::string, std::string> first_message;  // outcome → the first such query's message
  int solved = 0, runs = 0;
  double slowest_ms = 0;     // the slowest solved query of all repeats, and where its time went
  std::string slowest;
  /// Solved queries by index (first repeat), with their trajectory duration [s].
  std::map<std::size_t, double> durations;
};

struct RpcSeries {
  std::vector<double> call, server_total, response_kb;  // [ms], [ms], [kB]
  std::vector<double> transport;  // call − server-side total of the same call [ms]
  std::map<std::string, int> unsolved;
  int solved = 0, runs = 0;
  int duration_mismatches = 0;  ///< solved both ways with a different trajectory duration
};

struct Case {
  std::string scene, planner;
  bool optimizing = false;
  std::shared_ptr<const CollisionChecker> ours, fcl;
  std::vector<std::pair<Eigen::VectorXd, Eigen::VectorXd>> queries;
  std::vector<v1::PlanRequest> requests;  // the same queries as Plan RPCs
  StageSeries ours_series, fcl_series;
  RpcSeries rpc;
};

void RunInProcess(const PlanningPipeline& pipeline, const Case& c, const std::shared_ptr<const CollisionChecker>& checker,
                  double budget, double sample_period, std::uint64_t seed, StageSeries* series) {
  std::vector<double> totals;
  for (std::size_t k = 0; k < c.queries.size(); ++k) {
    PlanQuery query;  // default trajectory options: TOPP, 100 shortcut attempts, 0.005 rad
    query.checker = checker;
    query.start = c.queries[k].first;
    query.goal = c.queries[k].second;
    query.planner_id = c.planner;
    query.seed = seed + k;
    query.sample_period = sample_period;
    const PlanOutcome out = pipeline.Plan(query, Termination::After(std::chrono::duration<double>(budget)));
    ++series->runs;
    if (out.code != PlanOutcomeCode::kSuccess) {
      if (series->unsolved[ToString(out.code)]++ == 0) {
        series->first_message[ToString(out.code)] = "query " + std::to_string(k) + ": " + out.message;
      }
      continue;
    }
    ++series->solved;
    const StageSeconds& s = out.seconds;
    series->plan.push_back(1e3 * s.plan);
    series->shortcut.push_back(1e3 * s.shortcut);
    series->parameterize.push_back(1e3 * s.parameterize);
    series->verify.push_back(1e3 * s.verify);
    // Not in a stage's timer: validation, the trajectory's quality figures (clearance) and sampling.
    series->other.push_back(1e3 * (s.total - s.plan - s.shortcut - s.parameterize - s.optimize - s.verify));
    series->total.push_back(1e3 * s.total);
    series->state_checks.push_back(static_cast<double>(out.state_checks));
    totals.push_back(1e3 * s.total);
    if (1e3 * s.total > series->slowest_ms) {
      char text[320];
      std::snprintf(text, sizeof text,
                    "query %zu, %.2f ms: plan %.2f, shortcut %.2f, TOPP %.2f, certify %.2f, other %.2f ms; "
                    "%zu → %zu waypoints, %.2f s trajectory, %llu state checks",
                    k, 1e3 * s.total, 1e3 * s.plan, 1e3 * s.shortcut, 1e3 * s.parameterize, 1e3 * s.verify,
                    series->other.back(), out.raw_path.size(), out.path.size(), out.trajectory.duration(),
                    static_cast<unsigned long long>(out.state_checks));
      series->slowest_ms = 1e3 * s.total;
      series->slowest = text;
    }
    series->durations.emplace(k, out.trajectory.duration());
  }
  series->repeat_total_medians.push_back(QuantileOrNan(totals, 0.5));
}

/// Our in-process runs under a name of their own, so a profiler can count them alone:
/// valgrind --tool=callgrind --toggle-collect='chasles::(anonymous namespace)::RunOurs*' …
[[gnu::noinline]] void RunOurs(const PlanningPipeline& pipeline, Case& c, double budget, double sample_period,
                               std::uint64_t seed) {
  RunInProcess(pipeline, c, c.ours, budget, sample_period, seed, &c.ours_series);
}

void RunRpc(v1::Planning::Stub* stub, Case* c) {
  for (std::size_t k = 0; k < c->requests.size(); ++k) {
    grpc::ClientContext context;
    v1::PlanResponse response;
    const auto t0 = Clock::now();
    const grpc::Status status = stub->Plan(&context, c->requests[k], &response);
    const double ms = MillisSince(t0);
    if (!status.ok()) {
      throw std::runtime_error("Plan RPC on " + c->scene + " failed: " + std::to_string(status.error_code()) + " " +
                               status.error_message());
    }
    ++c->rpc.runs;
    if (response.outcome() != v1::SUCCESS) {
      ++c->rpc.unsolved[v1::PlanOutcome_Name(response.outcome())];
      continue;
    }
    ++c->rpc.solved;
    c->rpc.call.push_back(ms);
    c->rpc.server_total.push_back(1e3 * response.timings().total());
    c->rpc.transport.push_back(ms - 1e3 * response.timings().total());
    c->rpc.response_kb.push_back(response.ByteSizeLong() / 1e3);
    const auto it = c->ours_series.durations.find(k);
    if (it != c->ours_series.durations.end() && std::abs(it->second - response.duration()) > 1e-9) {
      ++c->rpc.duration_mismatches;
    }
  }
}

std::string Unsolved(const std::map<std::string, int>& unsolved) {
  std::string text;
  for (const auto& [code, count] : unsolved) text += (text.empty() ? " (" : ", ") + code + " " + std::to_string(count);
  return text.empty() ? text : text + ")";
}

std::string Verdict(double value, double bound, const char* unit) {
  char text[96];
  std::snprintf(text, sizeof text, "%.3g%s: %s", value, unit, value <= bound ? "met" : "**not met**");
  return text;
}

}  // namespace

void BenchPipeline(const PipelineBenchOptions& options, const QueryMaker& make_queries) {
  if (options.queries < 1 || options.repeats < 1) throw std::runtime_error("--queries and --bench-repeats must be >= 1");
  const std::string load_at_start = LoadAverage();
  PlannerRegistry registry;
  RegisterDefaultPlanners(&registry);
  const PlanningPipeline pipeline(registry);
  const auto robot = RobotModel::FromUrdf(ReadFile(options.examples_dir + "/robots/panda.urdf"),
                                          ReadFile(options.examples_dir + "/robots/panda.srdf"));

  // A server in this process with one planning worker, the default robot (the same Panda) and
  // each scene uploaded once.
  const BenchServer server = StartBenchServer();
  v1::Planning::Stub* const stub = server.stub.get();

  std::vector<Case> cases;
  int fcl_query_differences = 0;
  for (const std::string& scene_name : options.scenes) {
    v1::Scene scene_proto;
    const std::string path = options.examples_dir + "/scenes/" + scene_name + ".json";
    const auto parsed = google::protobuf::util::JsonStringToMessage(ReadFile(path), &scene_proto);
    if (!parsed.ok()) throw std::runtime_error(path + ": " + parsed.ToString());
    const auto scene = SceneFromProto(scene_proto);
    CollisionOptions fcl_options;
    fcl_options.force_fcl = true;
    auto ours = std::make_shared<const CollisionChecker>(robot, scene);
    auto fcl = std::make_shared<const CollisionChecker>(robot, scene, fcl_options);
    // The plan section's queries (fast checker); the FCL checker must give the same ones.
    const auto queries = make_queries(*ours, options.queries, options.seed);
    const auto fcl_queries = make_queries(*fcl, options.queries, options.seed);
    for (std::size_t k = 0; k < queries.size(); ++k) {
      if (queries[k].first != fcl_queries[k].first || queries[k].second != fcl_queries[k].second) ++fcl_query_differences;
    }

    grpc::ClientContext upload_context;
    v1::UploadSceneRequest upload;
    *upload.mutable_scene() = scene_proto;
    v1::UploadSceneResponse uploaded;
    const grpc::Status status = stub->UploadScene(&upload_context, upload, &uploaded);
    if (!status.ok()) throw std::runtime_error("UploadScene " + scene_name + ": " + status.error_message());

    for (const std::string& planner : options.planners) {
      Case c;
      c.scene = scene_name;
      c.planner = planner;
      c.optimizing = registry.Spec(planner).optimizing;
      c.ours = ours;
      c.fcl = fcl;
      c.queries = queries;
      for (std::size_t k = 0; k < queries.size(); ++k) {
        v1::PlanRequest request;
        request.set_scene_id(uploaded.scene_id());
        for (int i = 0; i < queries[k].first.size(); ++i) request.mutable_start()->add_positions(queries[k].first[i]);
        for (int i = 0; i < queries[k].second.size(); ++i) request.mutable_goal()->add_positions(queries[k].second[i]);
        request.mutable_planner()->set_planner_id(planner);
        request.set_time_budget(c.optimizing ? options.anytime_budget : options.budget);
        request.set_seed(options.seed + k);
        request.mutable_trajectory()->set_sample_period(options.sample_period);
        c.requests.push_back(std::move(request));
      }
      // Warm-up, not counted: the server builds the scene's checker on its first call.
      grpc::ClientContext context;
      v1::PlanResponse response;
      (void)stub->Plan(&context, c.requests.front(), &response);
      cases.push_back(std::move(c));
    }
  }

  // Alternate: every case in-process, through FCL, then over gRPC; `repeats` times.
  std::vector<double> floor_ms;
  for (int repeat = 0; repeat < options.repeats; ++repeat) {
    for (Case& c : cases) {
      const double budget = c.optimizing ? options.anytime_budget : options.budget;
      RunOurs(pipeline, c, budget, options.sample_period, options.seed);
      RunInProcess(pipeline, c, c.fcl, budget, options.sample_period, options.seed, &c.fcl_series);
      RunRpc(stub, &c);
    }
    // The transport floor: a trivial RPC (ListPlanners, answered on the same pool).
    for (int i = 0; i < 50; ++i) {
      grpc::ClientContext context;
      v1::ListPlannersResponse planners;
      const auto t0 = Clock::now();
      if (stub->ListPlanners(&context, v1::ListPlannersRequest(), &planners).ok()) floor_ms.push_back(MillisSince(t0));
    }
    std::fflush(stdout);
  }
  const std::string load_at_end = LoadAverage();

  std::printf("\n## Single-arm pipeline (panda): %d seeded queries per scene whose straight line collides, %d repeats\n\n",
              options.queries, options.repeats);
  std::printf("Per query: validate, plan (budget %.2g s; anytime planners %.2g s), shortcut (100 attempts), TOPP, "
              "certify (dense verification), quality figures and samples every %.3g s. Each repeat runs every scene "
              "in-process with our checker, then the same queries with the checker forced through FCL, then as Plan "
              "RPCs; medians and p95s are over the solved queries of all repeats. Load average (1, 5, 15 min) at the "
              "start: %s; at the end: %s.\n\n",
              options.budget, options.anytime_budget, options.sample_period, load_at_start.c_str(), load_at_end.c_str());
  if (fcl_query_differences > 0) {
    std::printf("Note: %d queries differ when generated with the FCL checker (they should not).\n\n",
                fcl_query_differences);
  }
  std::printf("| scene | planner | checker | solved | plan median [ms] | plan p95 [ms] | shortcut median [ms] | "
              "TOPP median [ms] | certify median [ms] | other median [ms] | pipeline median [ms] | pipeline p95 [ms] | "
              "p95 / median | pipeline median per repeat, min–max [ms] | state checks median | plan vs FCL | "
              "pipeline vs FCL |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const Case& c : cases) {
    const double fcl_plan = QuantileOrNan(c.fcl_series.plan, 0.5), fcl_total = QuantileOrNan(c.fcl_series.total, 0.5);
    for (const StageSeries* s : {&c.ours_series, &c.fcl_series}) {
      const double plan = QuantileOrNan(s->plan, 0.5), total = QuantileOrNan(s->total, 0.5), p95 = QuantileOrNan(s->total, 0.95);
      std::printf("| %s | %s | %s | %d/%d%s | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.1f | "
                  "%.3f–%.3f | %.0f | %.3f× | %.3f× |\n",
                  c.scene.c_str(), c.planner.c_str(),
                  s == &c.ours_series ? (c.ours->uses_fast_path() ? "ours (spheres)" : "ours (FCL: no fast path)")
                                      : "FCL path (baseline)",
                  s->solved, s->runs, Unsolved(s->unsolved).c_str(), plan, QuantileOrNan(s->plan, 0.95),
                  QuantileOrNan(s->shortcut, 0.5), QuantileOrNan(s->parameterize, 0.5), QuantileOrNan(s->verify, 0.5),
                  QuantileOrNan(s->other, 0.5), total, p95, p95 / total, QuantileOrNan(s->repeat_total_medians, 0.0),
                  QuantileOrNan(s->repeat_total_medians, 1.0), QuantileOrNan(s->state_checks, 0.5), plan / fcl_plan,
                  total / fcl_total);
    }
  }
  std::printf("\nThe slowest query of each scene (ours, all repeats):\n");
  for (const Case& c : cases) {
    std::printf("- %s, %s: %s\n", c.scene.c_str(), c.planner.c_str(), c.ours_series.slowest.c_str());
  }
  bool any_unsolved = false;
  for (const Case& c : cases) any_unsolved |= c.ours_series.solved < c.ours_series.runs || c.fcl_series.solved < c.fcl_series.runs;
  if (any_unsolved) std::printf("\nUnsolved queries, by outcome (the first one's message):\n");
  for (const Case& c : cases) {
    for (const StageSeries* s : {&c.ours_series, &c.fcl_series}) {
      for (const auto& [code, message] : s->first_message) {
        std::printf("- %s, %s, %s: %d × %s, first: %s\n", c.scene.c_str(), c.planner.c_str(),
                    s == &c.ours_series ? "ours" : "FCL path", s->unsolved.at(code), code.c_str(), message.c_str());
      }
    }
  }
  std::printf("\n\"other\" = validation, the returned trajectory's quality figures (clearance) and sampling: "
              "the pipeline's time outside the stage timers. Ratios divide our median by the FCL path's.\n");

  std::printf("\n## Plan RPC over loopback (in-process server, 1 worker; scene uploaded once, default robot)\n\n");
  std::printf("| scene | planner | solved | Plan RPC median [ms] | Plan RPC p95 [ms] | server-side total median [ms] | "
              "call − server-side total, median [ms] | in-process pipeline median, same queries [ms] | RPC / pipeline | "
              "response median [kB] |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  for (const Case& c : cases) {
    const double call = QuantileOrNan(c.rpc.call, 0.5), local = QuantileOrNan(c.ours_series.total, 0.5);
    std::string note = Unsolved(c.rpc.unsolved);
    if (c.rpc.duration_mismatches > 0) {
      note += "; " + std::to_string(c.rpc.duration_mismatches) + " trajectories differ from in-process";
    }
    std::printf("| %s | %s | %d/%d%s | %.3f | %.3f | %.3f | %.3f | %.3f | %.2f× | %.1f |\n", c.scene.c_str(),
                c.planner.c_str(), c.rpc.solved, c.rpc.runs, note.c_str(), call, QuantileOrNan(c.rpc.call, 0.95),
                QuantileOrNan(c.rpc.server_total, 0.5), QuantileOrNan(c.rpc.transport, 0.5), local, call / local,
                QuantileOrNan(c.rpc.response_kb, 0.5));
  }
  std::printf("\n\"call − server-side total\" is measured on each call (the response's timings.total): transport, "
              "the client's and server's message handling and the hand-off to the worker, robust to load changes "
              "between the in-process and RPC runs.\n");
  std::printf("\nTransport floor: a trivial RPC (ListPlanners) over the same channel, median %.3f ms, p95 %.3f ms (%zu "
              "calls).\n",
              QuantileOrNan(floor_ms, 0.5), QuantileOrNan(floor_ms, 0.95), floor_ms.size());

  std::printf("\n## Issue 16 targets (medians and p95 over all repeats)\n\n");
  std::printf("| scene | planner | plan median ≤ %.2g ms | pipeline median ≤ %.3g ms | Plan RPC median ≤ %.3g ms | "
              "pipeline p95 ≤ %.3g × median |\n|---|---|---|---|---|---|\n",
              kPlanMedianTargetMs, kPipelineMedianTargetMs, kRpcMedianTargetMs, kP95OverMedianTarget);
  for (const Case& c : cases) {
    const double total = QuantileOrNan(c.ours_series.total, 0.5);
    std::printf("| %s | %s | %s | %s | %s | %s |\n", c.scene.c_str(), c.planner.c_str(),
                Verdict(QuantileOrNan(c.ours_series.plan, 0.5), kPlanMedianTargetMs, " ms").c_str(),
                Verdict(total, kPipelineMedianTargetMs, " ms").c_str(),
                Verdict(QuantileOrNan(c.rpc.call, 0.5), kRpcMedianTargetMs, " ms").c_str(),
                Verdict(QuantileOrNan(c.ours_series.total, 0.95) / total, kP95OverMedianTarget, "×").c_str());
  }
  std::fflush(stdout);
}

}  // namespace chasles
