// `chasles-bench --section effort` (issue 23). Per group of paths, with torque limits 1.2, 1.5
// and 2 times max(the largest static torque along the path, 1 N·m): the duration against the
// reference (paths that stop at every waypoint; the reference is the sum of its segments'),
// against the velocity/acceleration-only TOPP, the largest torque, velocity and acceleration
// ratios at 1 kHz and at every piece's ends and midpoint (InverseDynamics with friction), and the
// solve time of ParameterizeTimeOptimal with and without max_effort, medians over repeats.

#include "bench_effort.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "bench_pipeline.h"  // ReadFile, QuantileOrNan, MedianMillis, RandomBlockedPair
#include "bench_robots.h"    // RobotsBenchScene
#include "chasles/collision/collision_checker.h"
#include "chasles/optimizers/time_parameterization.h"
#include "chasles/pipeline/plan_pipeline.h"
#include "chasles/planners/registry.h"
#include "chasles/robot/dynamics.h"
#include "chasles/robot/robot_model.h"
#include "effort_reference.h"

namespace chasles {
namespace {

struct Row {
  std::string group;
  double scale = 0;
  std::vector<double> ratio_reference, ratio_kinematic, solve_ms, kinematic_ms, effort_peak;
  int violations = 0, failed = 0, bound = 0, cases = 0;
};

}  // namespace

void BenchEffort(const EffortBenchOptions& options) {
  const std::string dir = options.examples_dir + "/robots/";
  const std::shared_ptr<const RobotModel> robot =
      RobotModel::FromUrdf(ReadFile(dir + "panda.urdf"), ReadFile(dir + "panda.srdf"));
  const auto checker = std::make_shared<CollisionChecker>(robot, std::make_shared<Scene>());
  std::mt19937_64 rng(options.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const Eigen::VectorXd lo = robot->lower_limits(), hi = robot->upper_limits();
  const auto random_q = [&] {
    Eigen::VectorXd q(7);
    for (int i = 0; i < 7; ++i) q[i] = lo[i] + (hi[i] - lo[i]) * (0.1 + 0.8 * unit(rng));
    return q;
  };
  const auto random_path = [&](int waypoints) {
    JointPath path;
    for (int k = 0; k < waypoints; ++k) path.push_back(random_q());
    return path;
  };
  struct Group {
    std::string name;
    std::vector<JointPath> paths;
    double deviation;
  };
  std::vector<Group> groups;
  groups.push_back({"straight segment", {}, 0.0});
  groups.push_back({"5 waypoints, stops", {}, 0.0});
  groups.push_back({"5 waypoints, blended 0.05 rad", {}, 0.05});
  for (int c = 0; c < options.cases; ++c) groups[0].paths.push_back(random_path(2));
  for (int c = 0; c < options.cases; ++c) groups[1].paths.push_back(random_path(5));
  groups[2].paths = groups[1].paths;
  // Planner paths: RRT-Connect through the pipeline (shortcut) in the robots section's scene,
  // between free states at least 1 rad apart whose straight segment collides.
  {
    PlannerRegistry registry;
    RegisterDefaultPlanners(&registry);
    const PlanningPipeline pipeline(registry);
    const auto scene_checker = std::make_shared<const CollisionChecker>(robot, RobotsBenchScene());
    std::mt19937_64 plan_rng(options.seed + 1);
    groups.push_back({"planner paths (RRT-Connect, shortcut), stops", {}, 0.0});
    for (int c = 0, tries = 0; c < options.cases && tries < 20 * options.cases; ++tries) {
      auto [a, b] = RandomBlockedPair(*scene_checker, &plan_rng);
      PlanQuery query;
      query.checker = scene_checker;
      query.start = a;
      query.goal = b;
      query.seed = options.seed + static_cast<std::uint64_t>(tries);
      const PlanOutcome planned = pipeline.Plan(query, Termination::After(std::chrono::duration<double>(1.0)));
      if (planned.code != PlanOutcomeCode::kSuccess) continue;
      groups.back().paths.push_back(planned.path);
      ++c;
    }
    groups.push_back({"planner paths, blended 0.05 rad", groups.back().paths, 0.05});
  }
  groups.push_back({"shelf path (examples/requests), stops", {}, 0.0});
  {
    Eigen::VectorXd a(7), b(7), c(7), d(7);
    a << 0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785;
    b << 0.48292, -0.229452, -1.593533, -0.677452, 0.158394, 2.147618, 1.521398;
    c << 0.775164, -0.268651, -1.362654, -0.869069, 0.135445, 2.068276, 1.414705;
    d << 2.5, -0.5, 0.0, -2.0, 0.0, 1.6, 0.785;
    groups.back().paths.push_back({a, b, c, d});
  }

  std::vector<Row> rows;
  for (const Group& group : groups) {
    for (double scale : {1.2, 1.5, 2.0}) {
      Row row;
      row.group = group.name;
      row.scale = scale;
      for (const JointPath& path : group.paths) {
        KinematicLimits limits;
        limits.max_velocity = robot->velocity_limits();
        limits.max_acceleration = 5.0 * robot->velocity_limits();
        TimeOptimalOptions topp;
        topp.max_deviation = group.deviation;
        ++row.cases;
        TimedTrajectory kinematic, traj;
        row.kinematic_ms.push_back(MedianMillis(options.repeats, [&] { kinematic = ParameterizeTimeOptimal(path, limits, topp); }));
        limits.max_effort = scale * reference::StaticNeed(*robot, path).cwiseMax(Eigen::VectorXd::Constant(7, 1.0));
        TimeOptimalReport report;
        try {
          row.solve_ms.push_back(MedianMillis(options.repeats, [&] {
            traj = ParameterizeTimeOptimal(path, limits, topp, checker.get(), &report);
          }));
        } catch (const std::exception& e) {
          ++row.failed;
          std::fprintf(stderr, "effort: %s scale %.1f: %s\n", group.name.c_str(), scale, e.what());
          continue;
        }
        row.bound += report.effort_passes > 0 ? 1 : 0;
        row.ratio_kinematic.push_back(traj.duration() / kinematic.duration());
        const reference::Peaks peaks = reference::PeaksOf(traj, *robot, limits);
        row.effort_peak.push_back(peaks.effort);
        if (peaks.effort > 1.0 + 1e-9 || peaks.velocity > 1.0 + 1e-9 || peaks.acceleration > 1.0 + 1e-9) ++row.violations;
        if (group.deviation == 0.0) {
          row.ratio_reference.push_back(traj.duration() / reference::ReferencePath(*robot, limits, path, 1e-3));
        }
      }
      rows.push_back(std::move(row));
    }
  }
  std::printf("\n### TOPP under torque limits (Panda, acceleration limits 5 × velocity limits)\n\n");
  std::printf("| paths | τmax / static need | cases | torque bound | failed | duration / reference, median | p95 | max | "
              "duration / without torque limits, median | peak |τ|/τmax, median | violations at 1 kHz and piece ends/midpoints | "
              "solve median [ms] | p95 [ms] | without torque limits, median [ms] |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const Row& r : rows) {
    const auto f = [](const std::vector<double>& v, double p, const char* format) {
      static char buffer[64];
      if (v.empty()) return std::string("—");
      std::snprintf(buffer, sizeof buffer, format, QuantileOrNan(v, p));
      return std::string(buffer);
    };
    std::printf("| %s | %.1f | %d | %d | %d | %s | %s | %s | %s | %s | %d | %s | %s | %s |\n", r.group.c_str(), r.scale, r.cases,
                r.bound, r.failed, f(r.ratio_reference, 0.5, "%.4f").c_str(), f(r.ratio_reference, 0.95, "%.4f").c_str(),
                f(r.ratio_reference, 1.0, "%.4f").c_str(),
                f(r.ratio_kinematic, 0.5, "%.3f").c_str(), f(r.effort_peak, 0.5, "%.6f").c_str(), r.violations,
                f(r.solve_ms, 0.5, "%.2f").c_str(), f(r.solve_ms, 0.95, "%.2f").c_str(), f(r.kinematic_ms, 0.5, "%.3f").c_str());
  }
}

}  // namespace chasles
