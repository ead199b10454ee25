#pragma once
/// \file
/// The chasles.v1.Planning gRPC server: service, caches, worker pool and health service.
/// Used by the `chasles-server` binary and, in-process, by the end-to-end tests.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "chasles/robot/input_limits.h"
#include "chasles/server/security.h"

namespace chasles {

struct ServerOptions {
  std::string listen = "127.0.0.1:50051";  ///< address:port; port 0 picks a free port
  int threads = 0;                         ///< planning workers; 0 = hardware threads
  int max_message_mb = 64;                 ///< largest request/response message [MiB]; in [1, 2047]
  bool log_requests = true;                ///< one line per request on stderr

  // Memory: every size a client controls is capped before the work it drives.
  std::uint64_t cache_mb = 256;          ///< uploaded robots, scenes and checkers together [MiB], >= 1
  std::uint64_t max_samples = 1000000;   ///< trajectory samples in one reply (per robot), >= 1
  int max_team_robots = 1000;            ///< robots of one Coordinate request, >= 1
  std::uint64_t request_memory_mb = 4096;  ///< operator-new bytes one call may hold [MiB]; 0 = no cap
  InputLimits limits;  ///< documents, links, DOF, mesh triangles, OctoMap nodes, cloud points

  // Fairness: per-client queues served round-robin; long budgets get a share of the workers.
  double max_budget = 600.0;   ///< largest time budget a call may ask for [s], in (0, 600]
  double long_budget = 5.0;    ///< a call whose budget exceeds this is long [s], > 0
  double long_share = 0.5;     ///< share of the workers long calls may hold, in (0, 1]
  std::size_t max_queued = 1024;           ///< calls waiting for a worker, over all clients, >= 1
  std::size_t max_queued_per_client = 64;  ///< calls of one client waiting for a worker, >= 1

  // Logs: one line per call on stderr, client text escaped and capped.
  std::string log_format = "text";  ///< "text" (key=value) or "json" (one object per call)
  std::size_t log_field_max = 200;  ///< client-supplied values longer than this are cut [bytes], >= 16
  /// Prometheus endpoint "HOST:PORT" (or "PORT" = 127.0.0.1:PORT, loopback by default; port 0
  /// picks a free port) serving /metrics; "" = no endpoint. See ServerMetrics.
  std::string metrics_listen;
  /// The viewer over HTTP "HOST:PORT" (port 0 picks a free port): an index of the most recent
  /// Plan, Optimize and Coordinate requests at / and each one's viewer page at /view/<request_id>
  /// (view_server.h); "" = off. With tokens it must be a loopback address (plain HTTP).
  std::string http_listen;
  int http_recent = 32;  ///< exchanges kept for it, in [1, 10000] (and at most 256 MiB of messages)
  /// Where uploaded robots and scenes, workcells and reservations live: "memory" (this process
  /// only) or "redis://HOST[:PORT][/DB]" (shared by every replica pointed at the same Redis,
  /// surviving restarts as far as Redis persists; see workcells.h and model_store.h).
  std::string store = "memory";
  double shutdown_grace = 10.0;  ///< [s] in-flight calls may take to finish on SIGTERM, in [0, 3600]
  /// TLS, mutual TLS and bearer tokens (--tls-cert, --tls-key, --tls-client-ca, --tokens);
  /// all empty = plaintext without authentication. See security.h.
  SecurityOptions security;
  /// \throws Error(kInvalidArgument) naming the option.
  void Validate() const;
};

/// A running server. Construction binds and starts it; destruction shuts it down.
class PlanningServer {
 public:
  /// \throws Error when the options are invalid or the embedded default robot/scene do not parse;
  ///         std::runtime_error when the address cannot be bound.
  explicit PlanningServer(const ServerOptions& options);
  ~PlanningServer();
  PlanningServer(const PlanningServer&) = delete;
  PlanningServer& operator=(const PlanningServer&) = delete;

  /// The bound port (useful with port 0).
  int port() const;
  /// The bound port of the Prometheus endpoint (--metrics-listen), 0 when there is none.
  int metrics_port() const;
  /// The bound port of the viewer (--http-listen), 0 when there is none.
  int http_port() const;
  /// One line on transport security and authentication, e.g. "TLS with client certificates, 3 bearer tokens".
  std::string security_description() const;
  /// Drains, then stops: health turns NOT_SERVING and new calls are refused with UNAVAILABLE
  /// while the calls in flight finish, for at most `grace`; then the listener closes and calls
  /// still running are cancelled. SIGTERM and SIGINT do this with --shutdown-grace. Idempotent.
  void Shutdown(std::chrono::milliseconds grace = std::chrono::milliseconds(2000));
  /// Blocks until the server has shut down.
  void Wait();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace chasles
