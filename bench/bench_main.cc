// chasles-bench: collision-check throughput, planning time per planner and scene, and gRPC
// overhead. Every figure is a median (and p95) over repeated runs, each next to a baseline
// measured in the same run, because these machines are shared and noisy.
//
//   chasles-bench [--section checks|plan|pipeline|clutter|mesh_robot|sphere_fit|robots|families|grpc|kinematics|trajectory|effort|cartesian|carry|constraints|moving|viewer|coordination|fleet|fleet_coordinate|fleet_lattice|fleet_session|benchmark|fairness|memory|all] [--queries N] [--seed S]
//                 [--planners a,b,...] [--scenes a,b,...] [--budget S] [--anytime-budget S]
//                 [--grpc-requests N] [--shortcut-attempts N] [--ik-poses N] [--examples DIR]
//                 [--problems maze,office,drone_course,panda_shelf]
//                 [--segments N] [--paths N] [--knots K] [--methods topp,collocation,spline]
//                 [--runs N] [--scenarios crossing_arms,swap_bases,corridor] [--team-budget S] [--bench-repeats N]
//                 [--urdf a.urdf,b.urdf]

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <google/protobuf/util/json_util.h>
#include <grpcpp/grpcpp.h>

#include "chasles/collision/collision_checker.h"
#include "chasles/optimizers/collocation.h"
#include "chasles/optimizers/shortcut.h"
#include "chasles/optimizers/spline_smoothing.h"
#include "chasles/optimizers/time_parameterization.h"
#include "chasles/optimizers/verification.h"
#include "chasles/pipeline/plan_pipeline.h"
#include "chasles/planners/registry.h"
#include "chasles/robot/dynamics.h"
#include "chasles/robot/error.h"
#include "chasles/robot/inverse_kinematics.h"
#include "chasles/robot/kinematics.h"
#include "chasles/robot/lie_group.h"
#include "chasles/robot/mobile.h"
#include "chasles/multi/coordinator.h"
#include "chasles/server/benchmark.h"
#include "chasles/server/benchmark_report.h"
#include "chasles/server/convert.h"
#include "chasles/server/convert_multi.h"
#include "chasles/server/planning_server.h"
#include "chasles/v1/chasles.grpc.pb.h"
#include "bench_clutter.h"
#include "bench_cartesian.h"
#include "bench_constraints.h"
#include "bench_moving.h"
#include "bench_viewer.h"
#include "bench_effort.h"
#include "bench_fleet.h"
#include "bench_fleet_lattice.h"
#include "bench_fleet_session.h"
#include "bench_mesh_robot.h"
#include "bench_robots.h"
#include "bench_sphere_fit.h"
#include "bench_hardening.h"
#include "bench_pipeline.h"

namespace chasles {
namespace {

using Clock = std::chrono::steady_clock;

struct Options {
  std::string section = "all";
  int queries = 50;
  std::uint64_t seed = 1;
  std::vector<std::string> planners;  // empty = all
  std::vector<std::string> scenes = {"table", "shelf", "cage", "shelf_octomap"};
  bool scenes_given = false;  // --scenes: else the pipeline section uses its own (with bin)
  double budget = 1.0;          // non-optimizing planners [s]
  double anytime_budget = 0.1;  // optimizing planners [s]
  int grpc_requests = 200;
  int shortcut_attempts = 100;
  int ik_poses = 1000;
  double resolution = 0.005;  // motion-check resolution of the planning queries [rad]
  std::vector<std::string> problems = {"maze", "office", "drone_course", "panda_shelf"};
  int segments = 200;   // trajectory: straight rest-to-rest segments
  int paths = 200;      // trajectory: planner-produced paths of 5–10 waypoints
  int knots = 50;       // trajectory: collocation knots (the API's default)
  std::vector<std::string> methods = {"topp", "collocation", "spline"};
  int runs = 5;         // coordination: seeds per scenario and method
  std::vector<std::string> scenarios = {"crossing_arms", "swap_bases", "corridor"};
  double team_budget = 30.0;  // coordination: time budget per request [s]
  int bench_repeats = 5;      // benchmark, fairness: alternating repeats of each measurement
  double long_budget = 20.0;  // fairness: budget of the long rrt_star plans [s]
  int uploads = 8;            // memory: distinct 50 MB STL uploads
  std::vector<std::string> urdfs;  // sphere_fit: more robots, their collision meshes as boxes
};

std::vector<std::string> Split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

std::string examples_dir;

std::shared_ptr<const RobotModel> LoadRobot(const std::string& name) {
  return RobotModel::FromUrdf(ReadFile(examples_dir + "/robots/" + name + ".urdf"),
                              ReadFile(examples_dir + "/robots/" + name + ".srdf"));
}

std::shared_ptr<const Scene> LoadScene(const std::string& name) {
  v1::Scene scene;
  const auto status =
      google::protobuf::util::JsonStringToMessage(ReadFile(examples_dir + "/scenes/" + name + ".json"), &scene);
  if (!status.ok()) throw std::runtime_error(name + ".json: " + status.ToString());
  return SceneFromProto(scene);
}

// ---------------------------------------------------------------------------------------------
// Full-robot state checks per second.

struct Rate {
  double median_per_second = 0;
  double valid_fraction = 0;
};

Rate MeasureChecks(const CollisionChecker& checker, const std::vector<Eigen::VectorXd>& configs, int repeats) {
  std::vector<double> rates;
  int valid = 0;
  for (int r = 0; r < repeats; ++r) {
    valid = 0;
    const auto t0 = Clock::now();
    for (const auto& q : configs) valid += checker.IsValid(q) ? 1 : 0;
    const double s = std::chrono::duration<double>(Clock::now() - t0).count();
    rates.push_back(configs.size() / s);
  }
  return {QuantileOrNan(rates, 0.5), static_cast<double>(valid) / configs.size()};
}

void BenchChecks(const Options& options) {
  std::printf("\n## Full-robot state checks (FK + self + scene), one thread\n\n");
  std::printf("| robot | scene | checker path | configurations | valid | checks/s (median of 7) | µs/check | vs FCL path |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  struct Case {
    std::string robot, scene;
  };
  const std::vector<Case> cases = {{"panda", "shelf"}, {"panda", "table"}, {"panda", "cage"},
                                   {"panda", "shelf_octomap"}, {"ur5", "shelf"}};
  for (const auto& c : cases) {
    auto robot = LoadRobot(c.robot);
    auto scene = LoadScene(c.scene);
    CollisionOptions fcl_options;
    fcl_options.force_fcl = true;
    const CollisionChecker fast(robot, scene);
    const CollisionChecker fcl(robot, scene, fcl_options);
    std::mt19937_64 rng(options.seed);
    std::vector<Eigen::VectorXd> random, free;
    while (random.size() < 20000) random.push_back(RandomConfiguration(*robot, &rng));
    for (const auto& q : random) {
      if (fcl.IsValid(q)) free.push_back(q);
    }
    for (const auto* set : {&random, &free}) {
      const char* label = set == &random ? "uniform random" : "collision-free only";
      const Rate base = MeasureChecks(fcl, *set, 7);
      const Rate ours = fast.uses_fast_path() ? MeasureChecks(fast, *set, 7) : base;
      std::printf("| %s | %s | %s | %s (%zu) | %.0f%% | %.0f | %.2f | %.1f× |\n", c.robot.c_str(), c.scene.c_str(),
                  fast.uses_fast_path() ? "fast spheres" : "FCL", label, set->size(), 100 * ours.valid_fraction,
                  ours.median_per_second, 1e6 / ours.median_per_second,
                  ours.median_per_second / base.median_per_second);
      if (fast.uses_fast_path()) {
        std::printf("| %s | %s | FCL (baseline) | %s (%zu) | %.0f%% | %.0f | %.2f | 1.0× |\n", c.robot.c_str(),
                    c.scene.c_str(), label, set->size(), 100 * base.valid_fraction, base.median_per_second,
                    1e6 / base.median_per_second);
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Planning time per planner and scene over seeded random queries.

/// True when some segment of `path` collides at a 0.001 re-check (finer than any planner uses).
bool CollidesAtRecheck(const CollisionChecker& checker, const JointPath& path) {
  for (size_t i = 0; i + 1 < path.size(); ++i) {
    if (!checker.IsMotionValid(path[i], path[i + 1], 0.001)) return true;
  }
  return false;
}

std::vector<std::pair<Eigen::VectorXd, Eigen::VectorXd>> MakeQueries(const CollisionChecker& checker, int n,
                                                                     std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<std::pair<Eigen::VectorXd, Eigen::VectorXd>> out;
  const auto valid = [&] {
    for (;;) {
      Eigen::VectorXd q = RandomConfiguration(checker.robot(), &rng);
      if (checker.IsValid(q)) return q;
    }
  };
  while (static_cast<int>(out.size()) < n) {
    Eigen::VectorXd a = valid();
    Eigen::VectorXd b = valid();
    // Keep queries whose straight line collides: trivial ones say nothing about a planner.
    if (!checker.IsMotionValid(a, b, 0.005)) out.emplace_back(std::move(a), std::move(b));
  }
  return out;
}

void BenchPlanning(const Options& options) {
  PlannerRegistry registry;
  RegisterDefaultPlanners(&registry);
  const PlanningPipeline pipeline(registry);
  // The sampling (OMPL) family; the search and field families have their own section.
  std::vector<std::string> planners = options.planners;
  if (planners.empty()) {
    planners = {"bit_star", "informed_rrt_star", "lazy_prm_star", "prm", "prm_star", "rrt", "rrt_connect", "rrt_star"};
  }
  // RRT-Connect first: it is the baseline every other figure is compared with.
  std::stable_partition(planners.begin(), planners.end(), [](const std::string& id) { return id == "rrt_connect"; });
  auto robot = LoadRobot("panda");
  std::printf("\n## Planning (panda), %d seeded queries per scene whose straight line collides\n\n", options.queries);
  std::printf("Non-optimizing planners get %.2g s per query; anytime planners %.2g s and are compared by path length.\n"
              "Every returned path is re-checked at 0.001 rad; the solved column names any that collide.\n\n",
              options.budget, options.anytime_budget);
  std::printf("| scene | planner | solved | plan median [ms] | plan p95 [ms] | vs rrt_connect (median) | pipeline median [ms] | "
              "shortcut median [ms] | verify median [ms] | raw length median [rad] | shortcut length median [rad] |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const auto& scene_name : options.scenes) {
    auto checker = std::make_shared<const CollisionChecker>(robot, LoadScene(scene_name));
    const auto queries = MakeQueries(*checker, options.queries, options.seed);
    double baseline_median = std::nan("");
    for (const auto& id : planners) {
      const bool optimizing = registry.Spec(id).optimizing;
      std::vector<double> plan_ms, total_ms, shortcut_ms, verify_ms, raw_length, length;
      int solved = 0;
      int collide_when_rechecked = 0;  // returned paths with a collision at a 0.001 rad re-check
      std::map<std::string, int> failures;  // outcome → count, for the unsolved queries
      for (size_t k = 0; k < queries.size(); ++k) {
        PlanQuery query;
        query.checker = checker;
        query.start = queries[k].first;
        query.goal = queries[k].second;
        query.planner_id = id;
        query.seed = options.seed + k;
        query.shortcut_attempts = options.shortcut_attempts;
        query.collision_resolution = options.resolution;
        const PlanOutcome out = pipeline.Plan(
            query, Termination::After(std::chrono::duration<double>(optimizing ? options.anytime_budget : options.budget)));
        if (out.code != PlanOutcomeCode::kSuccess) {
          ++failures[ToString(out.code)];
          continue;
        }
        ++solved;
        if (CollidesAtRecheck(*checker, out.path)) ++collide_when_rechecked;
        plan_ms.push_back(1e3 * out.seconds.plan);
        total_ms.push_back(1e3 * out.seconds.total);
        shortcut_ms.push_back(1e3 * out.seconds.shortcut);
        verify_ms.push_back(1e3 * out.seconds.verify);
        raw_length.push_back(PathLength(out.raw_path));
        length.push_back(PathLength(out.path));
      }
      const double median = QuantileOrNan(plan_ms, 0.5);
      if (id == "rrt_connect") baseline_median = median;
      std::string unsolved;
      for (const auto& [code, count] : failures) unsolved += (unsolved.empty() ? " (" : ", ") + code + " " + std::to_string(count);
      if (!unsolved.empty()) unsolved += ")";
      if (collide_when_rechecked > 0) {
        unsolved += "; " + std::to_string(collide_when_rechecked) + " collide at a 0.001 rad re-check";
      }
      std::printf("| %s | %s | %d/%zu%s | %.2f | %.2f | %.2f× | %.2f | %.2f | %.2f | %.2f | %.2f |\n", scene_name.c_str(),
                  id.c_str(), solved, queries.size(), unsolved.c_str(), median, QuantileOrNan(plan_ms, 0.95), median / baseline_median,
                  QuantileOrNan(total_ms, 0.5), QuantileOrNan(shortcut_ms, 0.5), QuantileOrNan(verify_ms, 0.5),
                  QuantileOrNan(raw_length, 0.5), QuantileOrNan(length, 0.5));
      std::fflush(stdout);
    }
  }
}


// ---------------------------------------------------------------------------------------------
// Planner families (issue 4): A*, potential field and wavefront against RRT-Connect and RRT* on
// the same queries, per problem: mobile bases, a drone and arms.

std::shared_ptr<const RobotModel> LoadMobileRobot(const std::string& name, const Eigen::Vector3d* lo = nullptr,
                                                  const Eigen::Vector3d* hi = nullptr) {
  v1::RobotModel robot;
  const auto status = google::protobuf::util::JsonStringToMessage(
      ReadFile(examples_dir + "/robots/" + name + ".json"), robot.mutable_mobile());
  if (!status.ok()) throw std::runtime_error(name + ".json: " + status.ToString());
  if (lo != nullptr) {
    robot.mutable_mobile()->mutable_workspace_min()->set_x(lo->x());
    robot.mutable_mobile()->mutable_workspace_min()->set_y(lo->y());
    robot.mutable_mobile()->mutable_workspace_max()->set_x(hi->x());
    robot.mutable_mobile()->mutable_workspace_max()->set_y(hi->y());
  }
  return RobotFromProto(robot, "robot");
}

struct FamilyProblem {
  std::string name;
  std::shared_ptr<const RobotModel> robot;
  std::string scene;
};

FamilyProblem LoadFamilyProblem(const std::string& name) {
  if (name == "maze") {
    const Eigen::Vector3d lo(0, 0, 0), hi(8, 8, 0);
    return {name, LoadMobileRobot("mobile_base", &lo, &hi), "maze_octomap"};
  }
  if (name == "office") return {name, LoadMobileRobot("mobile_base"), "office_octomap"};
  if (name == "drone_course") return {name, LoadMobileRobot("drone"), "drone_course_octomap"};
  const auto underscore = name.find('_', name.find("planar_2r") == 0 ? 9 : 0);
  if (underscore == std::string::npos) throw std::runtime_error("unknown problem '" + name + "'");
  return {name, LoadRobot(name.substr(0, underscore)), name.substr(underscore + 1)};
}

/// Seeded valid start/goal pairs whose straight segment collides. Mobile robots keep their
/// heading (and a drone stays level), as a base or drone usually does between waypoints; the
/// planners still search every coordinate except the wavefront, which holds equal ones fixed.
std::vector<std::pair<Eigen::VectorXd, Eigen::VectorXd>> MakeFamilyQueries(const CollisionChecker& checker, int n,
                                                                           std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  const RobotModel& robot = checker.robot();
  const int translations = robot.kind() == RobotKind::kFreeFlyer ? 3 : 2;
  std::vector<std::pair<Eigen::VectorXd, Eigen::VectorXd>> out;
  int attempts = 0;
  while (static_cast<int>(out.size()) < n && ++attempts < 1000000) {
    Eigen::VectorXd a = RandomConfiguration(robot, &rng);
    Eigen::VectorXd b = RandomConfiguration(robot, &rng);
    if (robot.kind() != RobotKind::kArm) {
      for (int i = translations; i < a.size(); ++i) {
        a[i] = robot.kind() == RobotKind::kFreeFlyer && i > translations ? 0.0 : a[i];
        b[i] = a[i];
      }
    }
    if (checker.IsValid(a) && checker.IsValid(b) && !checker.IsMotionValid(a, b, 0.005)) {
      out.emplace_back(std::move(a), std::move(b));
    }
  }
  return out;
}

/// "astar[epsilon=2;max_nodes=1e6]" → ("astar", {epsilon: 2, max_nodes: 1e6}).
std::pair<std::string, ParameterValues> ParsePlannerConfig(const std::string& text) {
  const auto open = text.find('[');
  if (open == std::string::npos) return {text, {}};
  ParameterValues values;
  std::stringstream ss(text.substr(open + 1, text.size() - open - 2));
  std::string item;
  while (std::getline(ss, item, ';')) {
    const auto eq = item.find('=');
    if (eq == std::string::npos) throw std::runtime_error("planner parameter '" + item + "' needs name=value");
    values[item.substr(0, eq)] = std::stod(item.substr(eq + 1));
  }
  return {text.substr(0, open), values};
}

void BenchFamilies(const Options& options) {
  PlannerRegistry registry;
  RegisterDefaultPlanners(&registry);
  const PlanningPipeline pipeline(registry);
  std::vector<std::string> planners = options.planners;
  if (planners.empty()) planners = {"rrt_connect", "rrt_star", "astar", "astar[epsilon=2]", "potential_field", "wavefront"};
  std::printf("\n## Planner families, %d seeded queries per problem whose straight line collides\n\n", options.queries);
  std::printf("Budget %.2g s per query (rrt_star, anytime: %.2g s). No shortcutting: the lengths are the planners' own "
              "paths (C-space length, [m] and [rad] summed as the configuration norm). Ratios are against rrt_connect on "
              "the same queries in the same run; every returned path is re-checked at 0.001.\n\n",
              options.budget, options.anytime_budget);
  std::printf("| problem | planner | solved | plan median [ms] | plan p95 [ms] | time vs rrt_connect | length median | "
              "length vs rrt_connect | other outcomes |\n|---|---|---|---|---|---|---|---|---|\n");
  for (const std::string& name : options.problems) {
    const FamilyProblem problem = LoadFamilyProblem(name);
    auto checker = std::make_shared<const CollisionChecker>(problem.robot, LoadScene(problem.scene));
    const auto queries = MakeFamilyQueries(*checker, options.queries, options.seed);
    double base_time = std::nan(""), base_length = std::nan("");
    for (const std::string& config : planners) {
      const auto [id, parameters] = ParsePlannerConfig(config);
      const bool optimizing = registry.Spec(id).optimizing;
      std::vector<double> plan_ms, length;
      int solved = 0, collide = 0;
      std::map<std::string, int> failures;
      for (size_t k = 0; k < queries.size(); ++k) {
        PlanQuery query;
        query.checker = checker;
        query.start = queries[k].first;
        query.goal = queries[k].second;
        query.planner_id = id;
        query.parameters = parameters;
        query.seed = options.seed + k;
        query.shortcut_attempts = -1;
        query.collision_resolution = options.resolution;
        PlanOutcome out;
        try {
          out = pipeline.Plan(query, Termination::After(std::chrono::duration<double>(
                                         optimizing ? options.anytime_budget : options.budget)));
        } catch (const Error& e) {
          ++failures[e.code() == ErrorCode::kFailedPrecondition ? "refused" : "error"];
          continue;
        }
        if (out.code != PlanOutcomeCode::kSuccess) {
          ++failures[ToString(out.code)];
          continue;
        }
        ++solved;
        if (CollidesAtRecheck(*checker, out.path)) ++collide;
        plan_ms.push_back(1e3 * out.seconds.plan);
        length.push_back(PathLength(out.path));
      }
      const double t = QuantileOrNan(plan_ms, 0.5), l = QuantileOrNan(length, 0.5);
      if (id == "rrt_connect") {
        base_time = t;
        base_length = l;
      }
      std::string other;
      for (const auto& [code, count] : failures) other += (other.empty() ? "" : ", ") + code + " " + std::to_string(count);
      if (collide > 0) other += (other.empty() ? "" : "; ") + std::to_string(collide) + " collide at the re-check";
      std::printf("| %s | %s | %d/%zu | %.2f | %.2f | %.2f× | %.3f | %.2f× | %s |\n", name.c_str(), config.c_str(), solved,
                  queries.size(), t, QuantileOrNan(plan_ms, 0.95), t / base_time, l, l / base_length, other.c_str());
      std::fflush(stdout);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// gRPC overhead: the same request over loopback and in-process.

void BenchGrpc(const Options& options) {
  ServerOptions server_options;
  server_options.listen = "127.0.0.1:0";
  server_options.threads = 1;
  server_options.log_requests = false;
  PlanningServer server(server_options);
  auto channel = grpc::CreateChannel("127.0.0.1:" + std::to_string(server.port()), grpc::InsecureChannelCredentials());
  auto stub = v1::Planning::NewStub(channel);

  // Default robot (panda) and scene (table); a short free motion so planning is a small part.
  v1::PlanRequest request;
  const std::vector<double> start = {0, -0.785, 0, -2.356, 0, 1.571, 0.785};
  const std::vector<double> goal = {0.3, -0.6, 0.1, -2.2, 0.1, 1.7, 0.9};
  for (double v : start) request.mutable_start()->add_positions(v);
  for (double v : goal) request.mutable_goal()->add_positions(v);
  request.mutable_planner()->set_planner_id("rrt_connect");

  PlannerRegistry registry;
  RegisterDefaultPlanners(&registry);
  const PlanningPipeline pipeline(registry);
  auto robot = LoadRobot("panda");
  auto checker = std::make_shared<const CollisionChecker>(robot, LoadScene("table"));

  std::vector<double> remote_ms, local_ms, convert_ms;
  std::size_t response_bytes = 0;
  for (int i = 0; i < options.grpc_requests + 10; ++i) {
    grpc::ClientContext context;
    v1::PlanResponse response;
    auto t0 = Clock::now();
    const grpc::Status status = stub->Plan(&context, request, &response);
    const double remote = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    if (!status.ok() || response.outcome() != v1::SUCCESS) {
      std::fprintf(stderr, "grpc bench: request failed: %s %s\n", status.error_message().c_str(),
                   response.message().c_str());
      return;
    }
    response_bytes = response.ByteSizeLong();

    t0 = Clock::now();
    RequestSettings settings;
    PlanQuery query = PlanQueryFromProto(request, checker, registry, &settings);
    const PlanOutcome out = pipeline.Plan(query, Termination::After(std::chrono::duration<double>(settings.time_budget)));
    const auto t1 = Clock::now();
    v1::PlanResponse local;
    PlanOutcomeToProto(out, query, &local);
    const auto t2 = Clock::now();
    if (i >= 10) {  // warm-up excluded
      remote_ms.push_back(remote);
      local_ms.push_back(std::chrono::duration<double, std::milli>(t2 - t0).count());
      convert_ms.push_back(std::chrono::duration<double, std::milli>(t2 - t1).count());
    }
  }
  // Transport floor: a trivial RPC (ListPlanners, answered on the same pool) over the same channel.
  std::vector<double> floor_ms;
  for (int i = 0; i < options.grpc_requests + 10; ++i) {
    grpc::ClientContext context;
    v1::ListPlannersResponse planners;
    const auto t0 = Clock::now();
    const grpc::Status status = stub->ListPlanners(&context, v1::ListPlannersRequest(), &planners);
    if (!status.ok()) return;
    if (i >= 10) floor_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
  }
  const double remote = QuantileOrNan(remote_ms, 0.5), local = QuantileOrNan(local_ms, 0.5);
  std::printf("\n## Plan latency: loopback gRPC vs in-process (panda, table, rrt_connect, %d requests)\n\n",
              options.grpc_requests);
  std::printf("| path | median [ms] | p95 [ms] |\n|---|---|---|\n");
  std::printf("| in-process: convert request + pipeline + convert response | %.3f | %.3f |\n", local,
              QuantileOrNan(local_ms, 0.95));
  std::printf("| loopback gRPC Plan (same work + transport, %zu-byte response) | %.3f | %.3f |\n", response_bytes,
              remote, QuantileOrNan(remote_ms, 0.95));
  std::printf("| of which response conversion (in-process) | %.3f | %.3f |\n", QuantileOrNan(convert_ms, 0.5),
              QuantileOrNan(convert_ms, 0.95));
  std::printf("| trivial RPC (ListPlanners) over the same channel: transport floor | %.3f | %.3f |\n",
              QuantileOrNan(floor_ms, 0.5), QuantileOrNan(floor_ms, 0.95));
  std::printf("\ngRPC overhead (difference of medians): %.3f ms; ratio %.2f×\n", remote - local, remote / local);
}

// ---------------------------------------------------------------------------------------------
// Kinematics and dynamics (issue 3): FK, Jacobian, IK, RNEA, mass matrix, each with a baseline.

/// Median over `repeats` runs of the mean time per call [µs] of `call(i)` over i in [0, n).
template <typename Call>
double MedianMicros(int n, int repeats, Call&& call) {
  std::vector<double> per_call;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = Clock::now();
    for (int i = 0; i < n; ++i) call(i);
    per_call.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count() / n);
  }
  return QuantileOrNan(per_call, 0.5);
}

volatile double bench_sink = 0.0;  // keeps results alive

void BenchKinematics(const Options& options) {
  constexpr int kRuns = 21;
  std::printf("\n## Kinematics and dynamics, one thread (median of %d runs of 1000 calls; µs per call)\n\n", kRuns);
  std::printf("| robot | operation | ours [µs] | baseline | baseline [µs] | speed-up |\n|---|---|---|---|---|---|\n");
  struct IkRow {
    std::string robot, method;
    int solved = 0, total = 0;
    double median_us = 0, p95_us = 0, attempts = 0;
  };
  std::vector<IkRow> ik_rows;
  for (const std::string name : {"ur5", "panda"}) {
    auto robot_ptr = LoadRobot(name);
    const RobotModel& robot = *robot_ptr;
    const int tool = robot.FindLink("tool") >= 0 ? robot.FindLink("tool") : robot.num_links() - 1;
    const int n = robot.num_dofs();
    std::mt19937_64 rng(options.seed);
    const int count = 1000;
    std::vector<Eigen::VectorXd> qs, qds, qdds;
    std::normal_distribution<double> normal(0.0, 1.0);
    for (int i = 0; i < count; ++i) {
      qs.push_back(RandomConfiguration(robot, &rng));
      Eigen::VectorXd qd(n), qdd(n);
      for (int j = 0; j < n; ++j) {
        qd[j] = normal(rng);
        qdd[j] = normal(rng);
      }
      qds.push_back(qd);
      qdds.push_back(qdd);
    }
    std::vector<Eigen::Isometry3d> poses;
    const auto row = [&](const char* op, double ours, const char* baseline, double base) {
      std::printf("| %s | %s | %.3f | %s | %.3f | %.1f× |\n", name.c_str(), op, ours, baseline, base, base / ours);
      std::fflush(stdout);
    };

    // FK of every link: PoE vs chaining the joint transforms.
    const double fk = MedianMicros(count, kRuns, [&](int i) {
      robot.ForwardKinematics(qs[i], &poses);
      bench_sink = bench_sink + poses.back().translation().x();
    });
    const double fk_chain = MedianMicros(count, kRuns, [&](int i) {
      robot.ForwardKinematicsByChaining(qs[i], &poses);
      bench_sink = bench_sink + poses.back().translation().x();
    });
    row("FK, all links", fk, "ForwardKinematicsByChaining", fk_chain);

    // Space Jacobian of the tool vs central differences of FK (2n FK calls and logs).
    const double jac = MedianMicros(count, kRuns, [&](int i) {
      const Jacobian J = SpaceJacobian(robot, qs[i], tool);
      bench_sink = bench_sink + J(0, 0);
    });
    const double jac_fd = MedianMicros(count, kRuns, [&](int i) {
      Jacobian J(6, n);
      const double h = 1e-6;
      std::vector<Eigen::Isometry3d> plus, minus;
      for (int j = 0; j < n; ++j) {
        Eigen::VectorXd qp = qs[i], qm = qs[i];
        qp[j] += h;
        qm[j] -= h;
        robot.ForwardKinematics(qp, &plus);
        robot.ForwardKinematics(qm, &minus);
        J.col(j) = LogSE3(plus[tool] * minus[tool].inverse()) / (2 * h);
      }
      bench_sink = bench_sink + J(0, 0);
    });
    row("space Jacobian (tool)", jac, "central differences of FK", jac_fd);

    // Dynamics (only when every moving link has a mass).
    if (HasInertia(robot)) {
      const double rnea = MedianMicros(count, kRuns, [&](int i) {
        const Eigen::VectorXd tau = InverseDynamics(robot, qs[i], qds[i], qdds[i]);
        bench_sink = bench_sink + tau[0];
      });
      const double closed = MedianMicros(count, kRuns, [&](int i) {
        const Eigen::VectorXd tau = MassMatrix(robot, qs[i]) * qdds[i] + CoriolisTorques(robot, qs[i], qds[i]) +
                                    GravityTorques(robot, qs[i]);
        bench_sink = bench_sink + tau[0];
      });
      row("InverseDynamics (RNEA)", rnea, "M q̈ + c + g (MassMatrix, CoriolisTorques, GravityTorques)", closed);
      const double mass = MedianMicros(count, kRuns, [&](int i) {
        const Eigen::MatrixXd M = MassMatrix(robot, qs[i]);
        bench_sink = bench_sink + M(0, 0);
      });
      DynamicsOptions no_bias;
      no_bias.gravity.setZero();
      no_bias.include_friction = false;
      const Eigen::VectorXd zero = Eigen::VectorXd::Zero(n);
      const double mass_rnea = MedianMicros(count, kRuns, [&](int i) {
        Eigen::MatrixXd M(n, n);
        for (int j = 0; j < n; ++j) M.col(j) = InverseDynamics(robot, qs[i], zero, Eigen::VectorXd::Unit(n, j), no_bias);
        bench_sink = bench_sink + M(0, 0);
      });
      row("MassMatrix", mass, "n RNEA calls with unit q̈", mass_rnea);
    } else {
      std::printf("| %s | dynamics | — | robot has no inertia on every moving link | — | — |\n", name.c_str());
    }

    // IK: random reachable poses (FK of random configurations), random restarts from the seed.
    for (const IkMethod method : {IkMethod::kDampedLeastSquares, IkMethod::kNewtonRaphson}) {
      IkRow ik_row;
      ik_row.robot = name;
      ik_row.method = method == IkMethod::kDampedLeastSquares ? "damped least squares (default)" : "Newton–Raphson";
      std::vector<double> micros;
      double attempts = 0;
      std::mt19937_64 ik_rng(options.seed + 17);
      for (int k = 0; k < options.ik_poses; ++k) {
        const Eigen::VectorXd q = RandomConfiguration(robot, &ik_rng);
        robot.ForwardKinematics(q, &poses);
        IkRequest request;
        request.link = tool;
        request.target = poses[tool];
        request.method = method;
        request.seed = options.seed + k;
        const auto t0 = Clock::now();
        const IkResult result = SolveIk(robot, request);
        micros.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
        ik_row.solved += result.solutions.empty() ? 0 : 1;
        attempts += result.attempts;
      }
      ik_row.total = options.ik_poses;
      ik_row.median_us = QuantileOrNan(micros, 0.5);
      ik_row.p95_us = QuantileOrNan(micros, 0.95);
      ik_row.attempts = attempts / options.ik_poses;
      ik_rows.push_back(ik_row);
    }
  }
  std::printf("\n## Inverse kinematics of the tool link: %d random reachable poses per robot "
              "(FK of uniform random configurations; tolerances 1e-4 m / 1e-3 rad; budget 0.05 s)\n\n",
              options.ik_poses);
  std::printf("| robot | method | solved | median [µs] | p95 [µs] | attempts per solve (mean) |\n|---|---|---|---|---|---|\n");
  for (const IkRow& r : ik_rows) {
    std::printf("| %s | %s | %d/%d (%.1f%%) | %.1f | %.1f | %.2f |\n", r.robot.c_str(), r.method.c_str(), r.solved,
                r.total, 100.0 * r.solved / r.total, r.median_us, r.p95_us, r.attempts);
  }
}

// ---------------------------------------------------------------------------------------------
// Trajectory optimisation (issue 5): the time-optimal parameterisation, collocation and spline
// smoothing on straight segments (against the exact minimum time T*) and on planner paths
// (against the time-optimal parameterisation of the same path), in one run.


struct MethodRow {
  std::vector<double> ratio, ms, iterations, velocity, acceleration, deviation, clearance;
  int fell_back = 0, failed_verification = 0, runs = 0, fd_violations = 0;
  std::map<std::string, int> reasons;  ///< why results were not ok: the message up to its first figure
};

/// Samples 1 ms apart whose finite differences exceed a limit by more than 1e-6 relative: the
/// first difference against the velocity limit, the second against the acceleration limit.
int FiniteDifferenceViolations(const TimedTrajectory& trajectory, const KinematicLimits& limits) {
  const std::vector<TrajectorySample> s = trajectory.Sample(1e-3);
  int count = 0;
  for (std::size_t k = 1; k + 1 < s.size(); ++k) {
    const double dt0 = s[k].t - s[k - 1].t, dt1 = s[k + 1].t - s[k].t;
    if (std::abs(dt0 - dt1) > 1e-12) continue;  // the last, shorter step
    const Eigen::VectorXd v = (s[k + 1].q - s[k].q) / dt1;
    const Eigen::VectorXd a = (s[k + 1].q - 2 * s[k].q + s[k - 1].q) / (dt0 * dt1);
    for (int i = 0; i < v.size(); ++i) {
      if (std::abs(v[i]) > limits.max_velocity[i] * (1 + 1e-6) ||
          std::abs(a[i]) > limits.max_acceleration[i] * (1 + 1e-6)) {
        ++count;
        break;
      }
    }
  }
  return count;
}

/// One result into its row: duration over `reference`, compute time, limits, deviation from the
/// path, clearance (with obstacles), dense verification and the 1 kHz finite-difference check.
void RecordMethod(MethodRow* row, const TimedTrajectory& trajectory, double ms, const OptimizerReport* report,
                  const JointPath& path, const KinematicLimits& limits, const CollisionChecker& checker,
                  double reference) {
  ++row->runs;
  if (report != nullptr && !report->ok) {
    ++row->fell_back;
    const std::size_t figure = report->message.find_first_of("0123456789");
    ++row->reasons[report->message.substr(0, figure == std::string::npos ? report->message.size() : figure)];
    return;
  }
  const bool obstacles = !checker.scene().empty();
  const TrajectoryQuality q = MeasureTrajectory(trajectory, limits, path, obstacles ? &checker : nullptr);
  row->ratio.push_back(trajectory.duration() / reference);
  row->ms.push_back(ms);
  row->iterations.push_back(report != nullptr ? report->iterations : 0);
  row->velocity.push_back(q.max_velocity_ratio);
  row->acceleration.push_back(q.max_acceleration_ratio);
  row->deviation.push_back(q.max_deviation);
  if (obstacles) row->clearance.push_back(q.min_clearance);
  if (!VerifyTrajectory(trajectory, path.front(), path.back(), checker, limits).ok) ++row->failed_verification;
  row->fd_violations += FiniteDifferenceViolations(trajectory, limits);
}

void PrintMethodRows(const std::string& what, const std::string& ratio_name, std::map<std::string, MethodRow>& rows,
                     const std::vector<std::string>& order, double topp_ms_median) {
  std::printf("| %s | method | runs | %s median | %s p95 | %s max | compute median [ms] | compute p95 [ms] | "
              "vs topp compute | iterations median | max |q̇|/v | max |q̈|/a | 1 kHz finite-difference violations | "
              "deviation median [rad] | deviation max [rad] | min clearance [m] | not ok |\n",
              what.c_str(), ratio_name.c_str(), ratio_name.c_str(), ratio_name.c_str());
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const std::string& m : order) {
    if (rows.count(m) == 0) continue;
    MethodRow& r = rows[m];
    const double ms = QuantileOrNan(r.ms, 0.5);
    double vmax = 0, amax = 0, cmin = std::numeric_limits<double>::infinity(), dmax = 0;
    for (double v : r.velocity) vmax = std::max(vmax, v);
    for (double a : r.acceleration) amax = std::max(amax, a);
    for (double c : r.clearance) cmin = std::min(cmin, c);
    for (double d : r.deviation) dmax = std::max(dmax, d);
    std::printf("| %s | %s | %d | %.6f | %.6f | %.6f | %.4f | %.4f | %.1f× | %.0f | %.6f | %.6f | %d | %.4f | %.4f | %s | "
                "%d%s |\n",
                what.c_str(), m.c_str(), r.runs, QuantileOrNan(r.ratio, 0.5), QuantileOrNan(r.ratio, 0.95),
                r.ratio.empty() ? std::nan("") : *std::max_element(r.ratio.begin(), r.ratio.end()), ms,
                QuantileOrNan(r.ms, 0.95), ms / topp_ms_median, QuantileOrNan(r.iterations, 0.5), vmax, amax,
                r.fd_violations, QuantileOrNan(r.deviation, 0.5), dmax,
                std::isfinite(cmin) ? std::to_string(cmin).c_str() : "no obstacles", r.fell_back,
                r.failed_verification > 0 ? (" (" + std::to_string(r.failed_verification) + " failed verification)").c_str() : "");
  }
  for (const std::string& m : order) {
    if (rows.count(m) == 0 || rows[m].reasons.empty()) continue;
    std::printf("\n%s, %s not ok:", what.c_str(), m.c_str());
    for (const auto& [reason, count] : rows[m].reasons) std::printf(" %d× \"%s…\";", count, reason.c_str());
    std::printf("\n");
  }
}

/// Every requested method on each path, into `rows`; ratios over TOPP's duration on the same
/// path (max_deviation 0.05 rad), or over `exact` when given (straight segments: T*).
void RunMethods(const std::vector<JointPath>& paths, const std::vector<double>& exact, const KinematicLimits& limits,
                const CollisionChecker& checker, const Options& options, std::map<std::string, MethodRow>* rows) {
  const auto want = [&](const char* m) {
    return std::find(options.methods.begin(), options.methods.end(), m) != options.methods.end();
  };
  CollocationOptions collocation;
  collocation.knots = options.knots;
  SplineOptions spline;
  const auto millis = [](Clock::time_point t0) { return 1e3 * std::chrono::duration<double>(Clock::now() - t0).count(); };
  for (std::size_t p = 0; p < paths.size(); ++p) {
    const JointPath& path = paths[p];
    TimedTrajectory topp;
    const double topp_ms = MedianMillis(5, [&] { topp = ParameterizeTimeOptimal(path, limits, {}, &checker); });
    const double reference = exact.empty() ? topp.duration() : exact[p];
    RecordMethod(&(*rows)["topp"], topp, topp_ms, nullptr, path, limits, checker, reference);
    if (path.size() > 2) {
      TimedTrajectory stops;
      const double stops_ms = MedianMillis(5, [&] { stops = ParameterizeRestToRest(path, limits); });
      RecordMethod(&(*rows)["none (stops)"], stops, stops_ms, nullptr, path, limits, checker, reference);
    }
    if (want("collocation")) {
      auto t0 = Clock::now();
      CollocationResult result = OptimizeByCollocation(topp, limits, collocation, &checker, &path);
      RecordMethod(&(*rows)["collocation (along the path)"], result.trajectory, millis(t0), &result.report, path, limits,
                   checker, reference);
      t0 = Clock::now();
      result = OptimizeByCollocation(topp, limits, collocation, &checker);
      RecordMethod(&(*rows)["collocation (free)"], result.trajectory, millis(t0), &result.report, path, limits, checker,
                   reference);
    }
    if (want("spline")) {
      const auto t0 = Clock::now();
      const SplineResult result = SmoothWithBSpline(topp, limits, spline, &checker);
      RecordMethod(&(*rows)["spline"], result.trajectory, millis(t0), &result.report, path, limits, checker, reference);
    }
  }
}

const std::vector<std::string> kMethodOrder = {"topp", "none (stops)", "collocation (along the path)",
                                               "collocation (free)", "spline"};

void BenchTrajectory(const Options& options) {
  auto robot = LoadRobot("panda");
  const int n = robot->num_dofs();
  KinematicLimits limits;
  limits.max_velocity = robot->velocity_limits();
  limits.max_acceleration = 2.0 * robot->velocity_limits();  // the server's default

  // 1. Straight rest-to-rest segments in free space, against the exact minimum time.
  auto free_space = std::make_shared<const CollisionChecker>(robot, std::make_shared<Scene>());
  std::mt19937_64 rng(options.seed);
  std::vector<JointPath> segments;
  std::vector<double> t_star;
  while (static_cast<int>(segments.size()) < options.segments) {
    // Endpoints and the line between them free of self-collision, so verification applies.
    const Eigen::VectorXd a = RandomConfiguration(*robot, &rng), b = RandomConfiguration(*robot, &rng);
    if (!free_space->IsValid(a) || !free_space->IsValid(b) || !free_space->IsMotionValid(a, b, 0.005)) continue;
    double v = std::numeric_limits<double>::infinity(), acc = v;
    for (int i = 0; i < n; ++i) {
      const double d = std::abs(b[i] - a[i]);
      if (d == 0) continue;
      v = std::min(v, limits.max_velocity[i] / d);
      acc = std::min(acc, limits.max_acceleration[i] / d);
    }
    segments.push_back({a, b});
    t_star.push_back(v * v > acc ? 2.0 / std::sqrt(acc) : 1.0 / v + v / acc);
  }
  std::map<std::string, MethodRow> rows;
  RunMethods(segments, t_star, limits, *free_space, options, &rows);
  std::printf("\n## Trajectory optimisation (panda, v = model limits, a = 2·v per second)\n\n");
  std::printf("%d seeded straight rest-to-rest segments between random configurations (free space, no self-collision "
              "on the line), T* = 1/V + V/A (or 2/√A); collocation with K = %d knots, budget %d iterations. compute = "
              "one call (topp: median of 5 repeats).\n\n",
              options.segments, options.knots, CollocationOptions().max_iterations);
  PrintMethodRows("straight", "T/T*", rows, kMethodOrder, QuantileOrNan(rows["topp"].ms, 0.5));
  std::fflush(stdout);

  // 2. Random multi-waypoint paths in free space: 2–10 waypoints, steps of up to 0.6 rad per
  // joint, every segment free of self-collision.
  std::vector<JointPath> random_paths;
  while (static_cast<int>(random_paths.size()) < options.paths) {
    const int waypoints = 2 + static_cast<int>(rng() % 9);
    JointPath path{RandomConfiguration(*robot, &rng)};
    if (!free_space->IsValid(path[0])) continue;
    std::uniform_real_distribution<double> step(-0.6, 0.6);
    for (int tries = 0; static_cast<int>(path.size()) < waypoints && tries < 100; ++tries) {
      Eigen::VectorXd q = path.back();
      for (int i = 0; i < n; ++i) q[i] = std::clamp(q[i] + step(rng), robot->lower_limits()[i], robot->upper_limits()[i]);
      if (free_space->IsValid(q) && free_space->IsMotionValid(path.back(), q, 0.005)) path.push_back(q);
    }
    if (static_cast<int>(path.size()) == waypoints) random_paths.push_back(path);
  }
  std::map<std::string, MethodRow> random_rows;
  RunMethods(random_paths, {}, limits, *free_space, options, &random_rows);
  std::printf("\n%zu random paths of 2–10 waypoints in free space (steps up to 0.6 rad per joint); ratios are "
              "durations over TOPP's (max_deviation 0.05 rad) on the same path; collocation along the path keeps a "
              "0.05 rad corridor, free keeps only the ends.\n\n",
              random_paths.size());
  PrintMethodRows("random path", "T/T_topp", random_rows, kMethodOrder, QuantileOrNan(random_rows["topp"].ms, 0.5));
  std::fflush(stdout);

  // 3. Planner paths of 5–10 waypoints in the shelf scene.
  PlannerRegistry registry;
  RegisterDefaultPlanners(&registry);
  const PlanningPipeline pipeline(registry);
  auto shelf = std::make_shared<const CollisionChecker>(robot, LoadScene("shelf"));
  std::vector<JointPath> paths;
  int attempts = 0;
  std::uint64_t seed = options.seed;
  while (static_cast<int>(paths.size()) < options.paths && attempts < 50 * std::max(1, options.paths)) {
    const auto queries = MakeQueries(*shelf, 20, seed++);
    for (const auto& [start, goal] : queries) {
      if (static_cast<int>(paths.size()) >= options.paths) break;
      ++attempts;
      PlanQuery query;
      query.checker = shelf;
      query.start = start;
      query.goal = goal;
      query.planner_id = "rrt_connect";
      query.seed = seed * 1000 + attempts;
      query.shortcut_attempts = 20;
      query.trajectory.method = PostProcessing::kNone;
      const PlanOutcome out = pipeline.Plan(query, Termination::After(std::chrono::duration<double>(1.0)));
      if (out.code != PlanOutcomeCode::kSuccess) continue;
      if (out.path.size() < 5 || out.path.size() > 10) continue;
      paths.push_back(out.path);
    }
  }
  std::vector<double> waypoints;
  for (const JointPath& path : paths) waypoints.push_back(static_cast<double>(path.size()));
  std::map<std::string, MethodRow> path_rows;
  RunMethods(paths, {}, limits, *shelf, options, &path_rows);
  std::printf("\n%zu RRT-Connect paths in the shelf scene with 5–10 waypoints after 20 shortcut attempts (median %.0f "
              "waypoints); ratios are durations over the time-optimal parameterisation of the same path (max_deviation "
              "0.05 rad), so 'none' shows what blending gains and the optimisers what they gain over it.\n\n",
              paths.size(), QuantileOrNan(waypoints, 0.5));
  PrintMethodRows("planner path", "T/T_topp", path_rows, kMethodOrder, QuantileOrNan(path_rows["topp"].ms, 0.5));
}

// ---------------------------------------------------------------------------------------------
// Coordination: every method on the example scenarios (examples/requests/coordinate_*.json), each
// against one robot after another (SEQUENTIAL) with the same seed in the same run.

void BenchCoordination(const Options& options) {
  PlannerRegistry registry;
  RegisterDefaultPlanners(&registry);
  const std::vector<CoordinationMethod> methods = {CoordinationMethod::kSequential, CoordinationMethod::kPrioritized,
                                                   CoordinationMethod::kVelocityTuning, CoordinationMethod::kComposite};
  std::printf("\n== coordination: %d seeds per scenario and method, budget %.0f s ==\n", options.runs,
              options.team_budget);
  std::printf("%-14s %-16s %8s %12s %12s %12s %14s %12s %10s\n", "scenario", "method", "success", "median s",
              "p95 s", "makespan s", "vs sequential", "sum dur s", "vs alone");
  for (const std::string& scenario : options.scenarios) {
    v1::CoordinateRequest request;
    const std::string path = examples_dir + "/requests/coordinate_" + scenario + ".json";
    const auto status = google::protobuf::util::JsonStringToMessage(ReadFile(path), &request);
    if (!status.ok()) throw std::runtime_error(path + ": " + status.ToString());
    const std::shared_ptr<const Scene> scene = SceneFromProto(request.scene());
    std::vector<std::string> warnings;
    CoordinationQuery base = CoordinationQueryFromProto(
        request, scene, [](const v1::TeamRobot& robot, const std::string& field) { return RobotFromProto(robot.robot(), field); },
        registry, &warnings);
    base.time_budget = options.team_budget;
    // One robot after another as if the others were out of the way: the sum of each robot's
    // duration alone (the baseline where strict one-after-another is impossible because a goal is
    // another robot's start).
    double alone_sum = 0.0;
    for (const TeamRobotSpec& robot : base.robots) {
      CoordinationQuery alone = base;
      alone.robots = {robot};
      alone.method = CoordinationMethod::kSequential;
      const CoordinationOutcome solo = Coordinate(alone, registry, Termination());
      if (solo.code == CoordinationCode::kSuccess) alone_sum += solo.makespan;
    }
    std::printf("%-14s %-16s %8s %12s %12s %12.3f %14s %12s\n", scenario.c_str(), "(alone, summed)", "-", "-", "-",
                alone_sum, "-", "-");
    std::map<std::uint64_t, double> sequential_makespan;  // by seed
    for (CoordinationMethod method : methods) {
      std::vector<double> seconds, makespans, ratios, sums;
      int solved = 0;
      for (int run = 0; run < options.runs; ++run) {
        CoordinationQuery query = base;
        query.method = method;
        query.seed = options.seed + static_cast<std::uint64_t>(run);
        const auto t0 = Clock::now();
        const CoordinationOutcome outcome = Coordinate(query, registry, Termination());
        seconds.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
        if (outcome.code != CoordinationCode::kSuccess) continue;
        ++solved;
        makespans.push_back(outcome.makespan);
        sums.push_back(outcome.sum_of_durations);
        if (method == CoordinationMethod::kSequential) sequential_makespan[query.seed] = outcome.makespan;
        const auto it = sequential_makespan.find(query.seed);
        if (it != sequential_makespan.end()) ratios.push_back(outcome.makespan / it->second);
      }
      std::printf("%-14s %-16s %5d/%-2d %12.3f %12.3f %12.3f %14.3f %12.3f %10.3f\n", scenario.c_str(), ToString(method),
                  solved, options.runs, QuantileOrNan(seconds, 0.5), QuantileOrNan(seconds, 0.95), QuantileOrNan(makespans, 0.5),
                  QuantileOrNan(ratios, 0.5), QuantileOrNan(sums, 0.5), QuantileOrNan(makespans, 0.5) / alone_sum);
      std::fflush(stdout);
    }
  }
  std::printf("\nTimes are wall time per Coordinate call (planning, timing and the joint verification at 1 ms and "
              "0.005 rad); makespan and its ratio to one robot after another (same seed) are medians over the "
              "solved runs; 'vs alone' divides the median makespan by the sum of the robots' durations alone (one "
              "after another with the others out of the way).\n");
}

// ---------------------------------------------------------------------------------------------
// Benchmark RPC throughput (issue 7): runs per second with 1 and 2 worker threads, next to the
// same runs executed one after another in-process (no gRPC) in the same process run.

void BenchBenchmarkRpc(const Options& options) {
  const std::vector<std::string> examples = {"panda_table", "panda_shelf", "planar_2r_table", "planar_2r_shelf"};
  v1::BenchmarkRequest request;
  for (const std::string& name : examples) {
    v1::BenchmarkProblem* problem = request.add_problems();
    problem->set_name(name);
    const auto status = google::protobuf::util::JsonStringToMessage(
        ReadFile(examples_dir + "/requests/" + name + ".json"), problem->mutable_request());
    if (!status.ok()) throw std::runtime_error(name + ".json: " + status.ToString());
  }
  for (const char* planner : {"rrt_connect", "rrt", "prm"}) request.add_configs()->mutable_planner()->set_planner_id(planner);
  request.set_runs(static_cast<std::uint32_t>(options.runs));
  request.set_run_budget(options.budget);
  request.set_seed(options.seed);
  const int total = request.problems_size() * request.configs_size() * options.runs;

  // Baseline: the same runs, in-process, one after another.
  PlannerRegistry registry;
  RegisterDefaultPlanners(&registry);
  const PlanningPipeline pipeline(registry);
  std::vector<PlanQuery> queries;
  for (const v1::BenchmarkProblem& problem : request.problems()) {
    // No robot or scene in the request: the server's defaults (the Panda at the table).
    const v1::PlanRequest& plan = problem.request();
    auto checker = std::make_shared<const CollisionChecker>(
        plan.has_robot() ? RobotFromProto(plan.robot()) : LoadRobot("panda"),
        plan.has_scene() ? SceneFromProto(plan.scene()) : LoadScene("table"));
    for (const v1::BenchmarkConfig& config : request.configs()) {
      RequestSettings settings;
      queries.push_back(PlanQueryFromProto(BenchmarkRunRequest(problem.request(), config, options.budget, options.seed),
                                           checker, registry, &settings));
    }
  }
  const auto direct = [&]() {
    const auto t0 = Clock::now();
    int solved = 0;
    for (int r = 0; r < options.runs; ++r) {
      for (PlanQuery query : queries) {
        query.seed = options.seed + r;
        solved += pipeline.Plan(query, Termination::After(std::chrono::duration<double>(options.budget))).code ==
                          PlanOutcomeCode::kSuccess ? 1 : 0;
      }
    }
    if (solved != total) std::fprintf(stderr, "benchmark bench: %d of %d direct runs solved\n", solved, total);
    return total / std::chrono::duration<double>(Clock::now() - t0).count();
  };

  std::map<int, std::unique_ptr<PlanningServer>> servers;
  std::map<int, std::unique_ptr<v1::Planning::Stub>> stubs;
  for (int threads : {1, 2}) {
    ServerOptions server_options;
    server_options.listen = "127.0.0.1:0";
    server_options.threads = threads;
    server_options.log_requests = false;
    servers[threads] = std::make_unique<PlanningServer>(server_options);
    stubs[threads] = v1::Planning::NewStub(grpc::CreateChannel(
        "127.0.0.1:" + std::to_string(servers[threads]->port()), grpc::InsecureChannelCredentials()));
  }
  const auto remote = [&](int threads) {
    grpc::ClientContext context;
    const auto t0 = Clock::now();
    auto reader = stubs[threads]->Benchmark(&context, request);
    v1::BenchmarkResponse message;
    int runs = 0, solved = 0;
    while (reader->Read(&message)) {
      if (message.has_run()) {
        ++runs;
        solved += message.run().solved() ? 1 : 0;
      }
    }
    const grpc::Status status = reader->Finish();
    if (!status.ok() || runs != total) {
      throw std::runtime_error("Benchmark RPC failed: " + status.error_message() + " (" + std::to_string(runs) + " runs)");
    }
    if (solved != total) std::fprintf(stderr, "benchmark bench: %d of %d runs solved\n", solved, total);
    return total / std::chrono::duration<double>(Clock::now() - t0).count();
  };

  // Alternate the three measurements so a load change on the machine hits all of them.
  std::vector<double> direct_rates, one_rates, two_rates, speedups;
  (void)remote(1);  // warm-up: parses and caches the robots, scenes and checkers
  (void)remote(2);
  for (int repeat = 0; repeat < options.bench_repeats; ++repeat) {
    direct_rates.push_back(direct());
    one_rates.push_back(remote(1));
    two_rates.push_back(remote(2));
    speedups.push_back(two_rates.back() / one_rates.back());
  }
  std::printf("\n## Benchmark RPC throughput (%zu example problems x %d configurations x %d runs = %d runs per call, "
              "budget %.2g s, %d repeats)\n\n",
              examples.size(), request.configs_size(), options.runs, total, options.budget, options.bench_repeats);
  std::printf("| how | median runs/s | min | max | ratio to in-process |\n|---|---|---|---|---|\n");
  const double base = QuantileOrNan(direct_rates, 0.5);
  const auto row = [&](const char* how, const std::vector<double>& rates) {
    std::printf("| %s | %.1f | %.1f | %.1f | %.2f× |\n", how, QuantileOrNan(rates, 0.5), QuantileOrNan(rates, 0.0),
                QuantileOrNan(rates, 1.0), QuantileOrNan(rates, 0.5) / base);
  };
  row("in-process pipeline, one run after another (baseline)", direct_rates);
  row("Benchmark RPC, server with 1 worker thread", one_rates);
  row("Benchmark RPC, server with 2 worker threads", two_rates);
  std::printf("\n2 threads vs 1: median of the per-repeat ratios %.2f×\n", QuantileOrNan(speedups, 0.5));
}

int Main(int argc, char** argv) {
  Options options;
  examples_dir = CHASLES_EXAMPLES_DIR;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::runtime_error(arg + " needs a value");
      return argv[++i];
    };
    if (arg == "--section") options.section = value();
    else if (arg == "--queries") options.queries = std::stoi(value());
    else if (arg == "--seed") options.seed = std::stoull(value());
    else if (arg == "--planners") options.planners = Split(value());
    else if (arg == "--scenes") {
      options.scenes = Split(value());
      options.scenes_given = true;
    }
    else if (arg == "--budget") options.budget = std::stod(value());
    else if (arg == "--anytime-budget") options.anytime_budget = std::stod(value());
    else if (arg == "--grpc-requests") options.grpc_requests = std::stoi(value());
    else if (arg == "--examples") examples_dir = value();
    else if (arg == "--shortcut-attempts") options.shortcut_attempts = std::stoi(value());
    else if (arg == "--resolution") options.resolution = std::stod(value());
    else if (arg == "--ik-poses") options.ik_poses = std::stoi(value());
    else if (arg == "--problems") options.problems = Split(value());
    else if (arg == "--segments") options.segments = std::stoi(value());
    else if (arg == "--paths") options.paths = std::stoi(value());
    else if (arg == "--knots") options.knots = std::stoi(value());
    else if (arg == "--methods") options.methods = Split(value());
    else if (arg == "--runs") options.runs = std::stoi(value());
    else if (arg == "--scenarios") options.scenarios = Split(value());
    else if (arg == "--team-budget") options.team_budget = std::stod(value());
    else if (arg == "--bench-repeats") options.bench_repeats = std::stoi(value());
    else if (arg == "--long-budget") options.long_budget = std::stod(value());
    else if (arg == "--uploads") options.uploads = std::stoi(value());
    else if (arg == "--urdf") options.urdfs = Split(value());
    else {
      std::fprintf(stderr,
                   "usage: chasles-bench [--section checks|plan|pipeline|clutter|mesh_robot|sphere_fit|robots|families|grpc|kinematics|trajectory|effort|cartesian|carry|constraints|moving|viewer|coordination|fleet|fleet_coordinate|fleet_lattice|fleet_session|benchmark|fairness|memory|all]\n"
                   "                     [--queries N]\n"
                   "                     [--seed S]\n"
                   "                     [--planners a,b] [--scenes a,b] [--budget S] [--anytime-budget S]\n"
                   "                     [--grpc-requests N] [--shortcut-attempts N] [--ik-poses N] [--examples DIR]\n"
                   "                     [--problems maze,office,drone_course,panda_shelf]\n"
                   "                     [--segments N] [--paths N] [--knots K] [--methods topp,collocation,spline]\n"
                   "                     [--runs N] [--scenarios crossing_arms,swap_bases,corridor] [--team-budget S]\n"
                   "                     [--bench-repeats N] [--urdf a.urdf,b.urdf]\n"
                   "  pipeline: --scenes (default table,shelf,cage,bin), --planners (default rrt_connect), --queries,\n"
                   "            --seed, --budget, --anytime-budget, --bench-repeats (alternations of ours, FCL, RPC)\n");
      return arg == "--help" ? 0 : 2;
    }
  }
  if (options.section == "checks" || options.section == "all") BenchChecks(options);
  if (options.section == "plan" || options.section == "all") BenchPlanning(options);
  if (options.section == "pipeline" || options.section == "all") {
    PipelineBenchOptions pipeline;
    pipeline.examples_dir = examples_dir;
    if (options.scenes_given) pipeline.scenes = options.scenes;
    if (!options.planners.empty()) pipeline.planners = options.planners;
    pipeline.queries = options.queries;
    pipeline.seed = options.seed;
    pipeline.repeats = options.bench_repeats;
    pipeline.budget = options.budget;
    pipeline.anytime_budget = options.anytime_budget;
    BenchPipeline(pipeline, MakeQueries);
  }
  if (options.section == "clutter" || options.section == "all") {
    ClutterBenchOptions clutter;
    clutter.examples_dir = examples_dir;
    clutter.repeats = std::max(options.bench_repeats, 5);
    BenchClutter(clutter);
  }
  if (options.section == "mesh_robot" || options.section == "all") {
    MeshRobotBenchOptions mesh;
    mesh.examples_dir = CHASLES_EXAMPLES_DIR;
    mesh.queries = options.queries;
    mesh.seed = options.seed;
    BenchMeshRobot(mesh);
  }
  if (options.section == "sphere_fit" || options.section == "all") {
    SphereFitBenchOptions fit;
    fit.examples_dir = CHASLES_EXAMPLES_DIR;
    fit.urdfs = options.urdfs;
    fit.repeats = options.bench_repeats;
    BenchSphereFit(fit);
  }
  if (options.section == "robots" || options.section == "all") {
    RobotsBenchOptions robots;
    robots.examples_dir = CHASLES_EXAMPLES_DIR;
    robots.queries = options.queries;
    robots.seed = options.seed;
    robots.budget = options.budget;
    BenchRobots(robots);
  }
  if (options.section == "fleet" || options.section == "all") BenchFleet({options.runs, options.seed});
  if (options.section == "fleet_coordinate" || options.section == "all") {
    BenchFleetCoordinate({options.runs, options.seed}, "docs/fleet_scaling.svg");
  }
  if (options.section == "families" || options.section == "all") BenchFamilies(options);
  if (options.section == "grpc" || options.section == "all") BenchGrpc(options);
  if (options.section == "kinematics" || options.section == "all") BenchKinematics(options);
  if (options.section == "trajectory" || options.section == "all") BenchTrajectory(options);
  if (options.section == "effort" || options.section == "all") {
    EffortBenchOptions effort;
    effort.examples_dir = CHASLES_EXAMPLES_DIR;
    effort.cases = options.runs * 2;
    effort.repeats = options.bench_repeats;
    effort.seed = options.seed;
    BenchEffort(effort);
  }
  if (options.section == "coordination" || options.section == "all") BenchCoordination(options);
  if (options.section == "cartesian" || options.section == "all") {
    CartesianBenchOptions cartesian;
    cartesian.examples_dir = examples_dir;
    cartesian.cases = options.queries;
    cartesian.repeats = options.bench_repeats;
    cartesian.seed = options.seed;
    BenchCartesian(cartesian);
  }
  if (options.section == "carry" || options.section == "all") {
    CartesianBenchOptions carry;
    carry.examples_dir = examples_dir;
    carry.cases = options.queries;
    carry.seed = options.seed;
    BenchCarry(carry);
  }
  if (options.section == "viewer") {  // needs Chromium: not part of "all"
    ViewerBenchOptions viewer;
    viewer.examples_dir = examples_dir;
    BenchViewer(viewer);
  }
  if (options.section == "moving" || options.section == "all") {
    MovingBenchOptions moving;
    moving.examples_dir = examples_dir;
    moving.cases = options.queries;
    moving.seed = options.seed;
    BenchMoving(moving);
  }
  if (options.section == "constraints" || options.section == "all") {
    ConstraintsBenchOptions constraints;
    constraints.examples_dir = examples_dir;
    constraints.cases = std::min(options.queries, 20);
    constraints.seed = options.seed;
    BenchConstraints(constraints);
  }
  if (options.section == "fleet_session" || options.section == "all") {
    FleetSessionBenchOptions session;
    session.seed = options.seed;
    BenchFleetSession(session);
  }
  if (options.section == "fleet_lattice" || options.section == "all") {
    FleetLatticeBenchOptions fleet;
    fleet.repeats = std::max(options.bench_repeats, 5);
    BenchFleetLattice(fleet);
  }
  if (options.section == "benchmark" || options.section == "all") BenchBenchmarkRpc(options);
  if (options.section == "fairness" || options.section == "all") BenchFairness(options.bench_repeats, options.long_budget);
  if (options.section == "memory" || options.section == "all") BenchMemory(options.uploads);
  return 0;
}

}  // namespace
}  // namespace chasles

int main(int argc, char** argv) {
  try {
    return chasles::Main(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "chasles-bench: %s\n", e.what());
    return 1;
  }
}
