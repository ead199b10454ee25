#pragma once
/// \file
/// chasles-bench --section pipeline (issue 16): the whole single-arm request — plan, shortcut,
/// time-parameterise (TOPP), certify — on the Panda scenes, in-process against the same queries
/// through the FCL path, and as a Plan RPC over loopback against the in-process pipeline.

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "chasles/server/planning_server.h"
#include "chasles/v1/chasles.grpc.pb.h"

namespace chasles {

class CollisionChecker;
class RobotModel;

/// The whole file at `path` (the benches' robots and scenes). \throws std::runtime_error naming it.
std::string ReadFile(const std::string& path);

/// A configuration drawn uniformly within the robot's joint limits (uniform doubles from the
/// generator's top 53 bits: the same sequence on every platform).
Eigen::VectorXd RandomConfiguration(const RobotModel& robot, std::mt19937_64* rng);

/// The report's quantile (linear interpolation), but nan for no values: a table cell, not a 0.
double QuantileOrNan(std::vector<double> values, double p);

/// Median over `repeats` runs of the time of `call()` [ms].
template <typename Call>
double MedianMillis(int repeats, Call&& call) {
  std::vector<double> ms;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    call();
    ms.push_back(1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  return QuantileOrNan(ms, 0.5);
}

/// A planning problem worth planning: two valid configurations (drawn by RandomConfiguration)
/// at least 1 rad (or m) apart in some joint whose straight segment collides.
std::pair<Eigen::VectorXd, Eigen::VectorXd> RandomBlockedPair(const CollisionChecker& checker, std::mt19937_64* rng);

/// A planning server in this process on a loopback port (one planning worker, no request log)
/// and a stub to it, messages up to `max_message_mb` [MiB] both ways (the server's cap too).
struct BenchServer {
  std::unique_ptr<PlanningServer> server;
  std::unique_ptr<v1::Planning::Stub> stub;
};
BenchServer StartBenchServer(int max_message_mb = 64);

/// `count` seeded start/goal pairs for `checker`: both collision-free, the straight segment
/// between them colliding (bench_main.cc's MakeQueries, so the plan section's queries are these).
using QueryMaker = std::function<std::vector<std::pair<Eigen::VectorXd, Eigen::VectorXd>>(
    const CollisionChecker& checker, int count, std::uint64_t seed)>;

struct PipelineBenchOptions {
  std::string examples_dir;  ///< holds robots/panda.urdf, robots/panda.srdf, scenes/<name>.json
  std::vector<std::string> scenes = {"table", "shelf", "cage", "bin"};
  std::vector<std::string> planners = {"rrt_connect"};
  int queries = 50;             ///< per scene, >= 1
  std::uint64_t seed = 1;       ///< of the queries; query k plans with seed + k
  int repeats = 3;              ///< alternations of (ours, FCL path, Plan RPC), >= 1
  double budget = 1.0;          ///< per query, non-optimizing planners [s]
  double anytime_budget = 0.1;  ///< per query, optimizing planners [s]
  double sample_period = 0.01;  ///< of the returned samples [s]
};

/// Prints three markdown tables to stdout: the stages in-process (ours and the FCL path), the
/// Plan RPC against the in-process pipeline, and the targets, met or not.
/// \throws std::runtime_error when an example file is missing or an RPC fails.
void BenchPipeline(const PipelineBenchOptions& options, const QueryMaker& make_queries);

}  // namespace chasles
