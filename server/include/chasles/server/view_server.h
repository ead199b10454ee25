#pragma once
/// \file
/// The viewer over HTTP (chasles-server --http-listen): the server keeps its most recent Plan,
/// Optimize and Coordinate exchanges (RecentExchanges) and serves, read-only, an index of them
/// (GET /) and each one's viewer page (GET /view/<request_id>, view_page.h), rendered on
/// request. Plain HTTP (cpp-httplib): with --tokens a request needs a token of the `plan` role
/// (`Authorization: Bearer <token>`, or `?token=<token>` for a browser's address bar), and the
/// listener must be a loopback address (put a TLS proxy in front to reach it from elsewhere).

#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "chasles/server/model_store.h"

namespace chasles {

/// One exchange: the rpc ("Plan", "Optimize", "Coordinate"), its request id, and both messages
/// serialised.
struct Exchange {
  std::string rpc;
  std::string request_id;
  std::string request, response;
  double unix_time = 0.0;  ///< [s] when it finished
  std::string outcome;     ///< e.g. "SUCCESS"
};

/// The last `max_count` exchanges, at most `max_bytes` together (older ones dropped first).
/// Thread-safe.
class RecentExchanges {
 public:
  RecentExchanges(std::size_t max_count, std::uint64_t max_bytes) : max_count_(max_count), max_bytes_(max_bytes) {}
  void Add(Exchange exchange);
  /// Newest first.
  std::vector<Exchange> List() const;
  std::optional<Exchange> Find(const std::string& request_id) const;

 private:
  mutable std::mutex mutex_;
  std::deque<Exchange> exchanges_;
  std::size_t max_count_;
  std::uint64_t max_bytes_;
  std::uint64_t bytes_ = 0;
};

/// The page of an exchange (view_page.h), robots and scenes resolved through `store`.
/// \throws Error when the messages do not parse or do not fit.
std::string ViewPageOf(const Exchange& exchange, ModelStore& store);

/// The HTTP listener. `authorize(authorization)` gets the Authorization header value (or
/// "Bearer <token>" from ?token=) — absent = nullopt — and returns "" to allow or the refusal
/// text (answered 401).
class ViewServer {
 public:
  /// Binds `listen` ("HOST:PORT", port 0 = any free port) and starts serving on its own threads.
  /// \throws std::runtime_error when it cannot bind.
  ViewServer(const std::string& listen, RecentExchanges* recent, ModelStore* store,
             std::function<std::string(const std::optional<std::string>&)> authorize);
  ~ViewServer();
  ViewServer(const ViewServer&) = delete;
  ViewServer& operator=(const ViewServer&) = delete;
  int port() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace chasles
