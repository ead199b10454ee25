#pragma once
/// \file
/// The chasles.v1.Planning gRPC server: service, caches, worker pool and health service.
/// Used by the `chasles-server` binary and, in-process, by the end-to-end tests.

#include <chrono>
#include <cstddef>
#include <memory>
#include <string>

#include "chasles/server/security.h"

namespace chasles {

struct ServerOptions {
  std::string listen = "127.0.0.1:50051";  ///< address:port; port 0 picks a free port
  int threads = 0;                         ///< planning workers; 0 = hardware threads
  int max_message_mb = 64;                 ///< largest request/response message [MiB]; in [1, 2047]
  std::size_t cache_capacity = 64;         ///< robots, scenes and checkers kept each (LRU)
  bool log_requests = true;                ///< one line per request on stderr
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
  /// Stops accepting calls; calls still running after `grace` are cancelled. Idempotent.
  void Shutdown(std::chrono::milliseconds grace = std::chrono::milliseconds(2000));
  /// Blocks until the server has shut down.
  void Wait();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace chasles
