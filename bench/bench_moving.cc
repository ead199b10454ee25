// `chasles-bench --section moving` (issue 18). Problems: the base of base_crossing_people.json
// from (1, y0) to (11, y1), y0 and y1 uniform in [2, 6]; 2 to 4 walkers (radius 0.3 m) each crossing
// the yard at 0.6–1.4 m/s on a straight line from one long side to the other, timed to be at a
// random point of the base's obstacle-free trajectory when the base is there (so that trajectory
// meets each of them unless another walker is in the way). Figures per method: solved, plan
// (whole request) median and p95, the trajectory's duration over the obstacle-free one, the
// smallest clearance to a walker over all trajectories (1 ms samples, measured here), and how
// many trajectories touch a walker.

#include "bench_moving.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <google/protobuf/util/json_util.h>

#include "bench_pipeline.h"  // ReadFile, QuantileOrNan, StartBenchServer

namespace chasles {
namespace {

struct Walk {
  double t0, t1;
  double x0, y0, x1, y1;
  Eigen::Vector2d At(double t) const {
    const double s = std::clamp((t - t0) / (t1 - t0), 0.0, 1.0);
    return {x0 + s * (x1 - x0), y0 + s * (y1 - y0)};
  }
};

/// Smallest clearance [m] of the base's body spheres to the walkers over the samples.
double Clearance(const v1::JointTrajectory& trajectory, const std::vector<Walk>& walks) {
  double closest = std::numeric_limits<double>::infinity();
  for (const v1::TrajectoryPoint& p : trajectory.points()) {
    for (const double along : {0.15, -0.15}) {
      const Eigen::Vector2d body(p.positions(0) + along * std::cos(p.positions(2)),
                                 p.positions(1) + along * std::sin(p.positions(2)));
      for (const Walk& w : walks) closest = std::min(closest, (body - w.At(p.time_from_start())).norm() - 0.5);
    }
  }
  return closest;
}

}  // namespace

void BenchMoving(const MovingBenchOptions& options) {
  v1::PlanRequest example;
  const std::string path = options.examples_dir + "/requests/base_crossing_people.json";
  const auto parsed = google::protobuf::util::JsonStringToMessage(ReadFile(path), &example);
  if (!parsed.ok()) throw std::runtime_error(path + ": " + parsed.ToString());
  const v1::MovingObstacle person = example.moving_obstacles(0);
  example.clear_moving_obstacles();
  example.mutable_trajectory()->set_sample_period(0.001);
  BenchServer server = StartBenchServer();
  const auto plan = [&](const v1::PlanRequest& request, v1::PlanResponse* response) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
    return server.stub->Plan(&context, request, response).ok();
  };

  // Problems: the walkers timed against the obstacle-free trajectory.
  std::mt19937_64 rng(options.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  struct Problem {
    v1::PlanRequest request;
    std::vector<Walk> walks;
    double free_duration;
  };
  std::vector<Problem> problems;
  for (int k = 0; static_cast<int>(problems.size()) < options.cases && k < 4 * options.cases; ++k) {
    Problem problem;
    problem.request = example;
    problem.request.mutable_start()->set_positions(1, 2.0 + 4.0 * unit(rng));
    problem.request.mutable_goal()->set_positions(1, 2.0 + 4.0 * unit(rng));
    problem.request.set_seed(static_cast<std::uint64_t>(k + 1));
    v1::PlanResponse alone;
    if (!plan(problem.request, &alone) || alone.outcome() != v1::SUCCESS) continue;
    problem.free_duration = alone.duration();
    const int walkers = 2 + static_cast<int>(3 * unit(rng)) % 3;
    for (int w = 0; w < walkers; ++w) {
      // Where and when the base is at a random point of its trajectory (not its ends).
      const int n = alone.trajectory().points_size();
      const v1::TrajectoryPoint& meet = alone.trajectory().points(static_cast<int>((0.15 + 0.7 * unit(rng)) * (n - 1)));
      const double speed = 0.6 + 0.8 * unit(rng);
      const bool north = unit(rng) < 0.5;
      const double x_south = meet.positions(0) + (unit(rng) - 0.5) * 4.0, x_north = 2.0 * meet.positions(0) - x_south;
      Walk walk;
      walk.x0 = north ? x_south : x_north;
      walk.y0 = north ? 0.3 : 7.7;
      walk.x1 = north ? x_north : x_south;
      walk.y1 = north ? 7.7 : 0.3;
      const double length = std::hypot(walk.x1 - walk.x0, walk.y1 - walk.y0);
      const double to_meet = std::hypot(meet.positions(0) - walk.x0, meet.positions(1) - walk.y0);
      walk.t0 = meet.time_from_start() - to_meet / speed;
      walk.t1 = walk.t0 + length / speed;
      if (walk.t0 < 0.0) {  // seen already on its way at t = 0
        const Eigen::Vector2d now = walk.At(0.0);
        walk.x0 = now.x();
        walk.y0 = now.y();
        walk.t0 = 0.0;
      }
      problem.walks.push_back(walk);
      v1::MovingObstacle* o = problem.request.add_moving_obstacles();
      *o = person;
      o->set_name("walker_" + std::to_string(w));
      o->clear_waypoints();
      for (const auto& [t, x, y] : {std::tuple<double, double, double>{walk.t0, walk.x0, walk.y0},
                                    std::tuple<double, double, double>{walk.t1, walk.x1, walk.y1}}) {
        v1::TimedPose* waypoint = o->add_waypoints();
        waypoint->set_time(t);
        waypoint->mutable_pose()->mutable_position()->set_x(x);
        waypoint->mutable_pose()->mutable_position()->set_y(y);
      }
    }
    // Starts or goals a walker stands on at t = 0 or at the end are not crossings: skip them.
    bool clear_ends = true;
    for (const Walk& w : problem.walks) {
      for (const auto* state : {&problem.request.start(), static_cast<const v1::JointState*>(nullptr)}) {
        const Eigen::Vector2d at = state ? Eigen::Vector2d(state->positions(0), state->positions(1))
                                         : Eigen::Vector2d(problem.request.goal().positions(0), problem.request.goal().positions(1));
        const double t = state ? 0.0 : w.t1;
        clear_ends = clear_ends && (at - w.At(t)).norm() > 0.9;
      }
    }
    if (clear_ends) problems.push_back(std::move(problem));
  }

  std::printf("## Moving obstacles: a base crossing people walking by (issue 18)\n\n");
  std::printf("examples/requests/base_crossing_people.json's base (1 m/s, 2 m/s²) and yard; %zu problems (seed %llu): "
              "start (1, y0), goal (11, y1), 2–4 walkers (r 0.3 m, 0.6–1.4 m/s) crossing the yard, each timed to "
              "meet the base's obstacle-free trajectory. Plan RPCs to an in-process server; clearance = smallest "
              "distance from the base's body spheres to a walker at the 1 ms samples, measured by the bench.\n\n",
              problems.size(), static_cast<unsigned long long>(options.seed));
  std::printf("| method | solved | request median [ms] | request p95 [ms] | duration / obstacle-free, median | "
              "smallest clearance [m] | trajectories touching a walker |\n|---|---|---|---|---|---|---|\n");
  std::vector<std::pair<std::string, std::vector<std::string>>> failed;  // per method: why not solved
  struct Method {
    const char* name;
    int value;  // -1 = the walkers left out
  };
  for (const Method& method : {Method{"SPACE_TIME", v1::PlanRequest::SPACE_TIME},
                               Method{"VELOCITY_OBSTACLES", v1::PlanRequest::VELOCITY_OBSTACLES},
                               Method{"walkers left out (baseline)", -1}}) {
    int solved = 0, touching = 0;
    std::vector<std::string> failures;
    double closest = std::numeric_limits<double>::infinity();
    std::vector<double> total_ms, stretch;
    for (const Problem& problem : problems) {
      v1::PlanRequest request = problem.request;
      if (method.value < 0) {
        request.clear_moving_obstacles();
      } else {
        request.set_moving_obstacle_method(static_cast<v1::PlanRequest::MovingObstacleMethod>(method.value));
      }
      v1::PlanResponse response;
      const auto start = std::chrono::steady_clock::now();
      if (!plan(request, &response) || response.outcome() != v1::SUCCESS) {
        failures.push_back(v1::PlanOutcome_Name(response.outcome()) + ": " + response.message());
        continue;
      }
      total_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
      ++solved;
      stretch.push_back(response.duration() / problem.free_duration);
      const double clearance = Clearance(response.trajectory(), problem.walks);
      closest = std::min(closest, clearance);
      touching += clearance <= 0.0;
    }
    std::printf("| %s | %d/%zu | %.1f | %.1f | %.3f | %.3f | %d |\n", method.name, solved, problems.size(),
                QuantileOrNan(total_ms, 0.5), QuantileOrNan(total_ms, 0.95), QuantileOrNan(stretch, 0.5), closest,
                touching);
    failed.emplace_back(method.name, failures);
    std::fflush(stdout);
  }
  std::printf("\n");
  for (const auto& [name, messages] : failed) {
    for (const std::string& message : messages) std::printf("- %s, not solved: %s\n", name.c_str(), message.c_str());
  }
  std::printf("\n");
}

}  // namespace chasles
