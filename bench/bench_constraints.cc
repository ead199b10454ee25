// `chasles-bench --section constraints` (issue 18). Problems: the hand at the example's
// orientation (pointing into the shelf, its x axis — the glass — up) at random points of two
// different compartments (x 0.62–0.68 m, y ±0.25 m, z at a compartment's middle ±3 cm), each solved
// by seeded collision-free IK. Per problem and configuration one Plan RPC (seed = problem index
// + 1); figures: solved, plan and whole-request medians, the largest |error|/tolerance over each
// trajectory at 0.002 rad steps (measured here: chained FK and Eigen's AngleAxis), and how many
// trajectories break the constraint.

#include "bench_constraints.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <google/protobuf/util/json_util.h>

#include "bench_pipeline.h"  // ReadFile, QuantileOrNan, StartBenchServer
#include "chasles/collision/collision_checker.h"
#include "chasles/robot/inverse_kinematics.h"
#include "chasles/server/convert.h"

namespace chasles {

void BenchConstraints(const ConstraintsBenchOptions& options) {
  v1::PlanRequest example;
  const std::string path = options.examples_dir + "/requests/panda_shelf_glass.json";
  const auto parsed = google::protobuf::util::JsonStringToMessage(ReadFile(path), &example);
  if (!parsed.ok()) throw std::runtime_error(path + ": " + parsed.ToString());
  const std::shared_ptr<const RobotModel> panda = RobotModel::FromUrdf(
      ReadFile(options.examples_dir + "/robots/panda.urdf"), ReadFile(options.examples_dir + "/robots/panda.srdf"));
  const CollisionChecker checker(panda, SceneFromProto(example.scene()));
  const v1::OrientationConstraint& glass = example.path_constraints().orientation(0);
  const int hand = panda->FindLink(glass.link());
  const Eigen::Quaterniond target(glass.orientation().w(), glass.orientation().x(), glass.orientation().y(),
                                  glass.orientation().z());

  // Problems: IK at random points of two different compartments.
  std::mt19937_64 rng(options.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double middles[3] = {0.18, 0.525, 0.875};
  const auto solve = [&](int compartment, std::uint64_t seed, Eigen::VectorXd* q) {
    IkRequest ik;
    ik.link = hand;
    ik.target.linear() = target.toRotationMatrix();
    ik.target.translation() = Eigen::Vector3d(0.62 + 0.06 * unit(rng), -0.25 + 0.5 * unit(rng),
                                              middles[compartment] - 0.03 + 0.06 * unit(rng));
    ik.time_budget = 0.5;
    ik.seed = seed;
    ik.accept = [&](const Eigen::VectorXd& x) { return checker.IsValid(x); };
    const IkResult result = SolveIk(*panda, ik);
    if (result.solutions.empty()) return false;
    *q = result.solutions.front();
    return true;
  };
  std::vector<std::pair<Eigen::VectorXd, Eigen::VectorXd>> problems;
  for (int tries = 0; static_cast<int>(problems.size()) < options.cases && tries < 20 * options.cases; ++tries) {
    const int from = static_cast<int>(3 * unit(rng)) % 3;
    const int to = (from + 1 + static_cast<int>(2 * unit(rng)) % 2) % 3;
    Eigen::VectorXd a, b;
    if (solve(from, 2 * tries + 1, &a) && solve(to, 2 * tries + 2, &b)) problems.emplace_back(a, b);
  }

  // The largest |rotation-vector component| / tolerance over a trajectory, at 0.002 rad steps.
  const auto worst_ratio = [&](const v1::JointTrajectory& t, const Eigen::Vector3d& tolerance) {
    std::vector<Eigen::Isometry3d> poses;
    double worst = 0.0;
    for (int s = 0; s + 1 < t.points_size(); ++s) {
      Eigen::VectorXd a(7), b(7);
      for (int i = 0; i < 7; ++i) {
        a[i] = t.points(s).positions(i);
        b[i] = t.points(s + 1).positions(i);
      }
      const int n = std::max(1, static_cast<int>(std::ceil((b - a).cwiseAbs().maxCoeff() / 0.002)));
      for (int i = 0; i <= n; ++i) {
        panda->ForwardKinematicsByChaining(a + (b - a) * (static_cast<double>(i) / n), &poses);
        const Eigen::AngleAxisd e(target.toRotationMatrix().transpose() * poses[static_cast<std::size_t>(hand)].linear());
        worst = std::max(worst, ((e.axis() * e.angle()).cwiseAbs().array() / tolerance.array()).maxCoeff());
      }
    }
    return worst;
  };

  struct Config {
    const char* name;
    double tolerance;  // about the two horizontal axes [rad]; 0 = no constraint
    bool projected_space;
  };
  const Config configs[] = {{"projected samples (default), 0.1 rad", 0.1, false},
                            {"OMPL projected space, 0.1 rad", 0.1, true},
                            {"projected samples (default), 0.01 rad", 0.01, false},
                            {"OMPL projected space, 0.01 rad", 0.01, true},
                            {"no constraint (baseline)", 0.0, true}};
  BenchServer server = StartBenchServer();
  std::printf("## Path constraints: carrying a glass upright (issue 18)\n\n");
  std::printf("examples/requests/panda_shelf_glass.json's scene and hand orientation; %zu start/goal pairs in two "
              "different compartments of the shelf (IK, seed %llu), rrt_connect, %.0f s budget, Plan RPCs to an "
              "in-process server. The constraint: rotation vector of the hand against its target within the "
              "tolerance about the two horizontal axes, π about the vertical. Ratio = largest |error| / tolerance "
              "over the trajectory at 0.002 rad steps (chained URDF joints, Eigen AngleAxis), for the baseline "
              "against 0.1 rad.\n\n",
              problems.size(), static_cast<unsigned long long>(options.seed), options.budget);
  std::printf("| configuration | solved | plan median [ms] | plan p95 [ms] | request median [ms] | worst ratio | "
              "trajectories breaking it |\n|---|---|---|---|---|---|---|\n");
  for (const Config& config : configs) {
    int solved = 0, breaking = 0;
    double worst = 0.0;
    std::vector<double> plan_ms, total_ms;
    for (std::size_t k = 0; k < problems.size(); ++k) {
      v1::PlanRequest request = example;
      request.clear_start();
      request.clear_goal();
      for (int i = 0; i < 7; ++i) {
        request.mutable_start()->add_positions(problems[k].first[i]);
        request.mutable_goal()->add_positions(problems[k].second[i]);
      }
      request.set_seed(k + 1);
      request.set_time_budget(options.budget);
      const double tol = config.tolerance == 0.0 ? 0.1 : config.tolerance;
      if (config.tolerance == 0.0) {
        request.clear_path_constraints();
      } else {
        v1::OrientationConstraint* c = request.mutable_path_constraints()->mutable_orientation(0);
        c->mutable_tolerance()->set_y(tol);
        c->mutable_tolerance()->set_z(tol);
        (*request.mutable_planner()->mutable_parameters())["constrained_space"].set_bool_value(config.projected_space);
      }
      v1::PlanResponse response;
      grpc::ClientContext context;
      context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(120));
      if (!server.stub->Plan(&context, request, &response).ok() || response.outcome() != v1::SUCCESS) continue;
      ++solved;
      plan_ms.push_back(1e3 * response.timings().plan());
      total_ms.push_back(1e3 * response.timings().total());
      const double ratio = worst_ratio(response.trajectory(), Eigen::Vector3d(glass.tolerance().x(), tol, tol));
      worst = std::max(worst, ratio);
      breaking += ratio > 1.0;
    }
    std::printf("| %s | %d/%zu | %.1f | %.1f | %.1f | %.3f | %d |\n", config.name, solved, problems.size(),
                QuantileOrNan(plan_ms, 0.5), QuantileOrNan(plan_ms, 0.95), QuantileOrNan(total_ms, 0.5), worst,
                breaking);
    std::fflush(stdout);
  }
  std::printf("\n");
}

}  // namespace chasles
