// `chasles-bench --section cartesian` (issue 18). Per case: a free start drawn within the joint
// limits whose TCP is at least 5 cm above the table top, a line of 0.05–0.4 m in a uniform random
// direction with a turn of 0–0.5 rad about a uniform random axis; ComputeCartesianPath with the
// server's defaults, then OptimizePath with the RPC's timing defaults (TOPP, max_deviation 0.001
// rad). Figures: how the moves ended, the fraction, compute times (medians of `repeats` runs),
// the states' pose errors, the link's distance from the line between states and over the timed
// trajectory, each measured here by projection onto the line (not read from the result).

#include "bench_cartesian.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <google/protobuf/util/json_util.h>

#include "bench_pipeline.h"  // ReadFile, RandomConfiguration, QuantileOrNan, MedianMillis
#include "chasles/collision/collision_checker.h"
#include "chasles/pipeline/cartesian_path.h"
#include "chasles/pipeline/trajectory_stage.h"
#include "chasles/robot/attached_objects.h"
#include "chasles/robot/inverse_kinematics.h"
#include "chasles/server/convert.h"
#include "chasles/server/planning_server.h"

namespace chasles {
namespace {

double SegmentDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d d = b - a;
  const double u = std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
  return (p - (a + u * d)).norm();
}

Eigen::Vector3d UnitVector(std::mt19937_64* rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::Vector3d v(normal(*rng), normal(*rng), normal(*rng));
  return v.normalized();
}

}  // namespace

void BenchCartesian(const CartesianBenchOptions& options) {
  const std::string dir = options.examples_dir;
  const std::shared_ptr<const RobotModel> robot =
      RobotModel::FromUrdf(ReadFile(dir + "/robots/panda.urdf"), ReadFile(dir + "/robots/panda.srdf"));
  v1::Scene scene_proto;
  const auto parsed = google::protobuf::util::JsonStringToMessage(ReadFile(dir + "/scenes/table.json"), &scene_proto);
  if (!parsed.ok()) throw std::runtime_error("scenes/table.json: " + parsed.ToString());
  const auto checker = std::make_shared<const CollisionChecker>(robot, SceneFromProto(scene_proto));
  const int tcp = robot->FindLink("panda_tcp");
  std::vector<Eigen::Isometry3d> poses;
  const auto pose = [&](const Eigen::VectorXd& q) {
    robot->ForwardKinematics(q, &poses);
    return poses[static_cast<std::size_t>(tcp)];
  };
  std::mt19937_64 rng(options.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);

  std::map<std::string, int> stops;
  std::vector<double> fraction, path_ms, timing_ms, baseline_ms, states, duration, line_states, line_timed;
  double pose_error = 0.0, orientation_error = 0.0;
  int timed_ok = 0, timed_failed = 0, baseline_jumps = 0, baseline_unsolved = 0, cases = 0;
  for (int tries = 0; cases < options.cases && tries < 100 * options.cases; ++tries) {
    const Eigen::VectorXd start = RandomConfiguration(*robot, &rng);
    if (!checker->IsValid(start) || pose(start).translation().z() < 0.05) continue;
    ++cases;
    const Eigen::Isometry3d a = pose(start);
    Eigen::Isometry3d b = a;
    b.translation() += (0.05 + 0.35 * unit(rng)) * UnitVector(&rng);
    b.linear() = a.linear() * Eigen::AngleAxisd(0.5 * unit(rng), UnitVector(&rng)).toRotationMatrix();
    CartesianSpec spec;
    spec.link = tcp;
    spec.waypoints = {b};
    CartesianPathResult result;
    path_ms.push_back(MedianMillis(options.repeats, [&] { result = ComputeCartesianPath(*checker, start, spec); }));
    ++stops[ToString(result.stop)];
    fraction.push_back(result.fraction);
    states.push_back(static_cast<double>(result.path.size()));
    pose_error = std::max(pose_error, result.max_position_error);
    orientation_error = std::max(orientation_error, result.max_orientation_error);
    // The link between states, 20 points a step, against the line (measured here).
    double between = 0.0;
    for (std::size_t s = 0; s + 1 < result.path.size(); ++s) {
      for (int i = 0; i <= 20; ++i) {
        const Eigen::VectorXd q = result.path[s] + (result.path[s + 1] - result.path[s]) * (i / 20.0);
        between = std::max(between, SegmentDistance(pose(q).translation(), a.translation(), b.translation()));
      }
    }
    line_states.push_back(between);
    if (result.path.size() >= 2) {
      OptimizeQuery query;
      query.checker = checker;
      query.path = result.path;
      query.trajectory.method = PostProcessing::kTimeOptimal;
      query.trajectory.max_deviation = 0.001;
      OptimizeOutcome timed;
      timing_ms.push_back(MedianMillis(options.repeats, [&] { timed = OptimizePath(query, Termination()); }));
      if (timed.code == TrajectoryStageCode::kSuccess) {
        ++timed_ok;
        duration.push_back(timed.stage.trajectory.duration());
        double farthest = 0.0;
        for (const TrajectorySample& sample : timed.samples) {
          farthest = std::max(farthest, SegmentDistance(pose(sample.q).translation(), a.translation(), b.translation()));
        }
        line_timed.push_back(farthest);
      } else {
        ++timed_failed;
      }
    }
    // Baseline: every state solved on its own (random restarts, no seed), as many states.
    IkRequest ik;
    ik.link = tcp;
    ik.time_budget = 0.05;
    Eigen::VectorXd previous = start;
    const int steps = std::max(1, result.steps);
    baseline_ms.push_back(MedianMillis(options.repeats, [&] {
      previous = start;
      for (int k = 1; k <= steps; ++k) {
        ik.target = InterpolatePose(a, b, static_cast<double>(k) / steps);
        ik.seed = static_cast<std::uint64_t>(k);
        const IkResult solved = SolveIk(*robot, ik);
        if (solved.solutions.empty()) break;
        previous = solved.solutions.front();
      }
    }));
    // Its jumps (one more run, counted).
    previous = start;
    bool jumped = false, unsolved = false;
    for (int k = 1; k <= steps && !jumped && !unsolved; ++k) {
      ik.target = InterpolatePose(a, b, static_cast<double>(k) / steps);
      ik.seed = static_cast<std::uint64_t>(k);
      const IkResult solved = SolveIk(*robot, ik);
      if (solved.solutions.empty()) {
        unsolved = true;
        break;
      }
      jumped = (solved.solutions.front() - previous).cwiseAbs().maxCoeff() > spec.max_joint_jump;
      previous = solved.solutions.front();
    }
    baseline_jumps += jumped;
    baseline_unsolved += unsolved;
  }
  const auto q = [](const std::vector<double>& v, double p) { return QuantileOrNan(v, p); };
  std::printf("## Cartesian moves (issue 18)\n\n");
  std::printf("Panda TCP in the table scene, %d random lines (0.05–0.4 m, turning 0–0.5 rad), seed %llu, "
              "medians of %d runs per line; defaults: max_step 0.01 m, max_rotation_step 0.05 rad, "
              "max_joint_jump 0.2 rad, line_tolerance 0.5 mm; timed by TOPP with max_deviation 0.001 rad.\n\n",
              cases, static_cast<unsigned long long>(options.seed), options.repeats);
  std::printf("| ended | lines |\n|---|---|\n");
  for (const auto& [name, count] : stops) std::printf("| %s | %d |\n", name.c_str(), count);
  std::printf("\n| figure | median | p95 | max |\n|---|---|---|---|\n");
  std::printf("| states | %.0f | %.0f | %.0f |\n", q(states, 0.5), q(states, 0.95), q(states, 1.0));
  std::printf("| Cartesian path [ms] | %.3f | %.3f | %.3f |\n", q(path_ms, 0.5), q(path_ms, 0.95), q(path_ms, 1.0));
  std::printf("| timing (OptimizePath) [ms] | %.3f | %.3f | %.3f |\n", q(timing_ms, 0.5), q(timing_ms, 0.95),
              q(timing_ms, 1.0));
  std::printf("| baseline: unseeded IK per state [ms] | %.3f | %.3f | %.3f |\n", q(baseline_ms, 0.5),
              q(baseline_ms, 0.95), q(baseline_ms, 1.0));
  std::printf("| link from the line between states [mm] | %.4f | %.4f | %.4f |\n", 1e3 * q(line_states, 0.5),
              1e3 * q(line_states, 0.95), 1e3 * q(line_states, 1.0));
  std::printf("| link from the line, timed trajectory samples [mm] | %.4f | %.4f | %.4f |\n", 1e3 * q(line_timed, 0.5),
              1e3 * q(line_timed, 0.95), 1e3 * q(line_timed, 1.0));
  std::printf("| timed duration [s] | %.3f | %.3f | %.3f |\n", q(duration, 0.5), q(duration, 0.95), q(duration, 1.0));
  std::vector<double> ratio;
  for (std::size_t i = 0; i < path_ms.size(); ++i) ratio.push_back(path_ms[i] / baseline_ms[i]);
  double mean_fraction = 0.0;
  for (const double f : fraction) mean_fraction += f / static_cast<double>(std::max<std::size_t>(1, fraction.size()));
  std::printf("\nFraction achieved: median %.3f, mean %.3f. States' pose errors: max %.3g m, %.3g rad. Timed: %d SUCCESS, %d not. Cartesian path time / "
              "baseline time per line: median %.3f. The baseline (each state by SolveIk with random restarts, "
              "0.05 s budget) jumped by more than 0.2 rad between consecutive states on %d of %d lines and "
              "found no solution on %d.\n\n",
              q(fraction, 0.5), mean_fraction, pose_error, orientation_error, timed_ok, timed_failed, q(ratio, 0.5),
              baseline_jumps, cases,
              baseline_unsolved);
}

void BenchCarry(const CartesianBenchOptions& options) {
  v1::PlanRequest example;
  const std::string path = options.examples_dir + "/requests/panda_carry_rod.json";
  const auto parsed = google::protobuf::util::JsonStringToMessage(ReadFile(path), &example);
  if (!parsed.ok()) throw std::runtime_error(path + ": " + parsed.ToString());
  const std::shared_ptr<const RobotModel> panda = RobotModel::FromUrdf(
      ReadFile(options.examples_dir + "/robots/panda.urdf"), ReadFile(options.examples_dir + "/robots/panda.srdf"));
  CollisionOptions fcl;
  fcl.force_fcl = true;
  const CollisionChecker exact(
      AttachObjects(*panda, AttachedObjectsFromProto(example.attached_objects(), *panda, "attached_objects")),
      SceneFromProto(example.scene()), fcl);
  const auto dense_collisions = [&](const v1::JointTrajectory& trajectory) {
    int colliding = 0;
    for (int s = 0; s + 1 < trajectory.points_size(); ++s) {
      Eigen::VectorXd a(7), b(7);
      for (int i = 0; i < 7; ++i) {
        a[i] = trajectory.points(s).positions(i);
        b[i] = trajectory.points(s + 1).positions(i);
      }
      const int n = std::max(1, static_cast<int>(std::ceil((b - a).cwiseAbs().maxCoeff() / 0.002)));
      for (int i = 0; i < n; ++i) colliding += exact.Check(a + (b - a) * (static_cast<double>(i) / n)).in_collision;
    }
    return colliding > 0;
  };
  BenchServer server = StartBenchServer();
  std::mt19937_64 rng(options.seed);
  std::uniform_real_distribution<double> side(0.4, 0.9);
  struct Row {
    int solved = 0, colliding = 0, cases = 0;
    std::vector<double> total_ms, duration;
  } bare, carrying;
  double first_ms = 0.0;
  for (int c = 0; c < options.cases; ++c) {
    v1::PlanRequest request = example;
    request.mutable_start()->set_positions(0, side(rng));
    request.mutable_goal()->set_positions(0, -side(rng));
    request.set_seed(static_cast<std::uint64_t>(c + 1));
    for (const bool carry : {true, false}) {
      v1::PlanRequest sent = request;
      if (!carry) sent.clear_attached_objects();
      Row& row = carry ? carrying : bare;
      ++row.cases;
      v1::PlanResponse response;
      grpc::ClientContext context;
      context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
      if (!server.stub->Plan(&context, sent, &response).ok() || response.outcome() != v1::SUCCESS) continue;
      ++row.solved;
      if (carry && c == 0) {
        first_ms = 1e3 * response.timings().total();  // the rod's sphere cover is made here
      } else {
        row.total_ms.push_back(1e3 * response.timings().total());
      }
      row.duration.push_back(response.duration());
      row.colliding += dense_collisions(response.trajectory());
    }
  }
  const auto q = [](const std::vector<double>& v, double p) { return QuantileOrNan(v, p); };
  std::printf("## Carried objects (issue 18)\n\n");
  std::printf("examples/requests/panda_carry_rod.json with %d random start/goal pairs (joint 1 from +0.4..0.9 to "
              "-0.4..-0.9 rad), seed %llu, Plan RPCs to an in-process server (1 worker); each trajectory re-checked "
              "at 0.002 rad steps against the rod's exact box (FCL).\n\n",
              options.cases, static_cast<unsigned long long>(options.seed));
  std::printf("| request | solved | server total median [ms] | p95 [ms] | duration median [s] | trajectories through "
              "the block with the rod held |\n|---|---|---|---|---|---|\n");
  for (const auto& [name, row] : {std::pair<const char*, const Row&>{"carrying the rod", carrying},
                                  std::pair<const char*, const Row&>{"bare (rod ignored)", bare}}) {
    std::printf("| %s | %d/%d | %.3f | %.3f | %.3f | %d |\n", name, row.solved, row.cases, q(row.total_ms, 0.5),
                q(row.total_ms, 0.95), q(row.duration, 0.5), row.colliding);
  }
  std::printf("\nThe first carrying request (the rod covered by spheres, then cached) took %.1f ms; it is left out "
              "of the medians. Carrying / bare server time, medians: %.2f.\n\n",
              first_ms, q(carrying.total_ms, 0.5) / q(bare.total_ms, 0.5));
}

}  // namespace chasles
