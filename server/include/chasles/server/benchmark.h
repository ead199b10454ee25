#pragma once
/// \file
/// The Benchmark RPC: problems × configurations × runs on the server's worker pool. Internal
/// to server/.
///
/// A call prepares every (problem, configuration) query on the pool first (all validation
/// errors come back before any run starts, naming `problems[i].request.<field>` or
/// `configs[j].<field>`), then keeps `parallelism` runs in flight: each finished run streams at
/// once and queues the next, so other requests interleave with the benchmark's runs in the
/// pool's FIFO. Run r of every problem and configuration uses seed + r, and runs are issued run
/// by run (all problems and configurations of run 0, then run 1, …) so a load change on the
/// machine hits every configuration alike. Stop (StopBenchmark) cancels the runs in flight,
/// drops them, and answers the summary of the finished runs; a client cancel stops the same way
/// without a summary (the client has every finished run already).

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <string>

#include <grpcpp/grpcpp.h>

#include "chasles/pipeline/plan_pipeline.h"
#include "chasles/server/model_store.h"
#include "chasles/server/thread_pool.h"
#include "chasles/v1/chasles.pb.h"

namespace chasles {

class BenchmarkCall;

/// What a benchmark call uses of the server.
struct BenchmarkServices {
  const PlannerRegistry* registry = nullptr;
  const PlanningPipeline* pipeline = nullptr;
  ModelStore* store = nullptr;
  ThreadPool* pool = nullptr;
  JobTicket ticket;  ///< the calling client and whether its runs are long (fair queueing)
  std::function<void(const std::string&)> log;  ///< one line per event; may be empty
};

/// The running benchmarks by request id (StopBenchmark finds them here). Thread-safe.
class BenchmarkRegistry {
 public:
  /// False when `id` is running already.
  bool Add(const std::string& id, BenchmarkCall* call);
  /// Removes `id` when it is `call`'s (a cancelled call frees its id before it has wound down,
  /// so a newer call may hold it).
  void Remove(const std::string& id, const BenchmarkCall* call);
  /// Stops the benchmark `id`; false when none runs under that id.
  bool Stop(const std::string& id);

 private:
  std::mutex mutex_;
  std::map<std::string, BenchmarkCall*> calls_;
};

/// The PlanRequest one run executes: the problem's request with the configuration's planner,
/// its trajectory options when it has them, and the run's budget [s] and seed.
v1::PlanRequest BenchmarkRunRequest(const v1::PlanRequest& problem, const v1::BenchmarkConfig& config,
                                    double run_budget, std::uint64_t seed);

/// Starts a Benchmark call; `request_id` is the request's or a generated one; `deadline` is the
/// call's gRPC deadline on the steady clock.
grpc::ServerWriteReactor<grpc::ByteBuffer>* StartBenchmark(const BenchmarkServices& services,
                                                                 BenchmarkRegistry* registry,
                                                                 const v1::BenchmarkRequest* request,
                                                                 const std::string& request_id,
                                                                 std::chrono::steady_clock::time_point deadline);

}  // namespace chasles
