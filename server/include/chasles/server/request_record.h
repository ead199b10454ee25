#pragma once
/// \file
/// What the server knows about one finished call: the one record that the request log line, the
/// JSON log and the metrics are all made from.

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace chasles {

/// One finished RPC (unary or stream). Filled by the service as the call goes.
struct RequestRecord {
  std::string rpc;         ///< method name as in the proto: "Plan", "Optimize", "UploadRobot", …
  std::string request_id;  ///< the client's request_id, or the generated one; empty when none
  std::string client;      ///< authenticated identity, else the peer address ("ipv4:127.0.0.1:5678")
  std::string outcome;     ///< the response's outcome name ("SUCCESS", "TIMEOUT", …), or "" when none
  int status_code = 0;     ///< grpc::StatusCode of the answer (0 = OK)
  std::string status_message;  ///< empty for OK
  double queue_seconds = 0.0;  ///< from arrival to a worker picking the call up [s]
  double total_seconds = 0.0;  ///< from arrival to the answer [s]
  /// Stage timings in the order they ran, e.g. {"validate", 0.001}, {"plan", 0.02}, … [s].
  std::vector<std::pair<std::string, double>> stages;
  /// Extra key/value facts for the log (robot id, planner, counts …); values are logged escaped.
  std::vector<std::pair<std::string, std::string>> fields;
  std::uint64_t peak_heap_bytes = 0;  ///< peak operator-new bytes of the call's worker thread
};

/// The scheduler's state when metrics are scraped.
struct SchedulerStats {
  std::uint64_t queued = 0;        ///< calls waiting for a worker
  std::uint64_t in_flight = 0;     ///< calls accepted and not yet answered (queued + running)
  std::uint64_t workers_busy = 0;  ///< workers running a call
  std::uint64_t workers = 0;       ///< worker threads
};

/// The model/scene/checker cache's state when metrics are scraped.
struct CacheStats {
  std::uint64_t entries = 0;
  std::uint64_t bytes = 0;           ///< estimated bytes held by the entries
  std::uint64_t capacity_bytes = 0;  ///< --cache-mb in bytes
  std::uint64_t evictions = 0;       ///< entries evicted since start
};

}  // namespace chasles
