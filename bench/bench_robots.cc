// `chasles-bench --section robots` (issue 25, item 6): every robot the project ships, planned
// beside the Panda on the same kind of problems. One scene (a table, a shelf board over it, two
// posts) in reach of each arm; per robot, seeded start/goal pairs, both free, at least 1 rad (or m)
// apart in some joint, whose straight segment collides (trivial problems say nothing); RRT-Connect
// through the whole pipeline (plan, shortcut, TOPP, verify), in-process. Every returned
// trajectory is re-checked on the generic FCL path (CollisionOptions::force_fcl) every 0.002
// rad or m of joint motion: an implementation apart from the sphere path that certified it.

#include "bench_robots.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "bench_pipeline.h"  // ReadFile, QuantileOrNan, RandomBlockedPair
#include "chasles/collision/collision_checker.h"
#include "chasles/pipeline/plan_pipeline.h"
#include "chasles/planners/registry.h"
#include "chasles/robot/robot_model.h"

namespace chasles {

std::shared_ptr<Scene> RobotsBenchScene() {
  auto scene = std::make_shared<Scene>();
  const auto box = [&](const char* name, double sx, double sy, double sz, double x, double y, double z) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() << x, y, z;
    scene->AddObject({name, Shape::Box({sx, sy, sz}, pose)});
  };
  box("table", 0.6, 1.2, 0.04, 0.65, 0.0, 0.3);
  box("board", 0.35, 1.0, 0.02, 0.6, 0.0, 0.75);
  box("post_left", 0.04, 0.04, 1.0, 0.45, 0.5, 0.6);
  box("post_right", 0.04, 0.04, 1.0, 0.45, -0.5, 0.6);
  return scene;
}

namespace {

/// States every `step` of joint motion along each piece, and the end, on `fcl`: true when one collides.
bool TouchesAtRecheck(const TimedTrajectory& trajectory, const CollisionChecker& fcl, double step) {
  const RobotModel& robot = fcl.robot();
  const auto collides = [&](const Eigen::VectorXd& raw) {
    return fcl.Check(raw.cwiseMax(robot.lower_limits()).cwiseMin(robot.upper_limits())).in_collision;
  };
  for (const TimedTrajectory::Piece& piece : trajectory.pieces()) {
    const int m = std::max(1, static_cast<int>(std::ceil(piece.MaxJointTravel() / step)));
    for (int i = 0; i < m; ++i) {
      if (collides(piece.State(piece.duration * i / m).q)) return true;
    }
  }
  return collides(trajectory.Evaluate(trajectory.duration()).q);
}

struct Row {
  std::string name;
  int dofs = 0, spheres = 0, solved = 0, certified = 0, touching = 0;
  bool fast = false;
  std::vector<double> plan, total;
};

}  // namespace

void BenchRobots(const RobotsBenchOptions& options) {
  PlannerRegistry registry;
  RegisterDefaultPlanners(&registry);
  const PlanningPipeline pipeline(registry);
  const std::shared_ptr<const Scene> scene = RobotsBenchScene();
  std::vector<Row> rows;
  for (const std::string& name : options.robots) {
    const auto robot = RobotModel::FromUrdf(ReadFile(options.examples_dir + "/robots/" + name + ".urdf"),
                                            ReadFile(options.examples_dir + "/robots/" + name + ".srdf"));
    const auto checker = std::make_shared<const CollisionChecker>(robot, scene);
    CollisionOptions fcl_options;
    fcl_options.force_fcl = true;
    const CollisionChecker fcl(robot, scene, fcl_options);
    Row row;
    row.name = name;
    row.dofs = robot->num_dofs();
    row.fast = checker->certifies_motion();
    for (const Link& link : robot->links()) row.spheres += static_cast<int>(link.collision.size());
    std::mt19937_64 rng(options.seed);
    for (int k = 0; k < options.queries; ++k) {
      auto [a, b] = RandomBlockedPair(*checker, &rng);
      PlanQuery query;
      query.checker = checker;
      query.start = a;
      query.goal = b;
      query.seed = options.seed + static_cast<std::uint64_t>(k);
      const PlanOutcome out = pipeline.Plan(query, Termination::After(std::chrono::duration<double>(options.budget)));
      row.total.push_back(1e3 * out.seconds.total);
      if (out.code != PlanOutcomeCode::kSuccess) continue;
      ++row.solved;
      row.plan.push_back(1e3 * out.seconds.plan);
      if (out.verification.collision_guarantee == "certified") ++row.certified;
      if (TouchesAtRecheck(out.trajectory, fcl, 0.002)) ++row.touching;
    }
    rows.push_back(std::move(row));
  }
  std::printf("\n## Shipped robots beside the Panda (issue 25), %d seeded problems each\n\n", options.queries);
  std::printf("One shelf scene; start and goal free, >= 1 rad (or m) apart, their straight segment colliding; "
              "RRT-Connect, %.2g s budget, the whole pipeline in-process (plan, shortcut, TOPP, verify). Every "
              "trajectory re-checked on the generic FCL path every 0.002 rad.\n\n",
              options.budget);
  std::printf("| robot | joints | collision shapes | checks | solved | certified | touching at the re-check | "
              "plan median [ms] | plan p95 [ms] | request median [ms] | request p95 [ms] | request / panda |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  const double panda = rows.empty() ? NAN : QuantileOrNan(rows.front().total, 0.5);
  for (const Row& row : rows) {
    const double median = QuantileOrNan(row.total, 0.5);
    std::printf("| %s | %d | %d | %s | %d/%d | %d | %d | %.3f | %.3f | %.3f | %.3f | %.2f× |\n", row.name.c_str(),
                row.dofs, row.spheres, row.fast ? "spheres (certified)" : "FCL (discrete)", row.solved,
                static_cast<int>(row.total.size()), row.certified, row.touching, QuantileOrNan(row.plan, 0.5),
                QuantileOrNan(row.plan, 0.95), median, QuantileOrNan(row.total, 0.95), median / panda);
  }
}

}  // namespace chasles
