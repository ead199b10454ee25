#pragma once
/// \file
/// Prometheus metrics of the server: request counters and latency histograms made from each
/// finished call's RequestRecord, and gauges (queue, workers, cache, resident memory) read from
/// callbacks at every scrape. Served as the Prometheus text format on `http://ADDR/metrics`.
///
/// Label values are bounded: `rpc` is a method of chasles.v1.Planning, `outcome` a PlanOutcome
/// name (or SOLVED / UNSOLVED, as InverseKinematics answers), `code` a gRPC status code name, `stage` one of the first kMaxStageLabels distinct
/// well-formed stage names; anything else is counted under "other" (an empty outcome under
/// "none"). Request ids and client names never become labels.

#include <cstddef>
#include <functional>
#include <memory>
#include <string>

#include "chasles/server/request_record.h"

namespace chasles {

/// Thread-safe: RequestStarted/RequestFinished may be called from any number of threads at once,
/// while the endpoint is being scraped.
class ServerMetrics {
 public:
  /// Distinct `stage` label values kept; later new stage names are counted under "other".
  static constexpr std::size_t kMaxStageLabels = 32;

  /// \param listen    address of the HTTP endpoint: "HOST:PORT" with an IPv4 HOST, "[IPv6]" or
  ///                  "localhost"; a bare "PORT" means 127.0.0.1:PORT (loopback unless an address
  ///                  such as 0.0.0.0 is given); port 0 picks a free port; "" = no endpoint
  ///                  (counting still works, see ExpositionText()).
  /// \param scheduler read at each scrape for the queue/worker gauges; may be empty (gauges omitted).
  /// \param cache     read at each scrape for the cache gauges; may be empty (gauges omitted).
  /// The callbacks run on the endpoint's threads and must stay callable until this object is
  /// destroyed (the destructor stops the endpoint first). A callback that throws leaves its
  /// gauges out of that scrape.
  /// \throws std::runtime_error naming --metrics-listen when the address is malformed or cannot be bound.
  ServerMetrics(const std::string& listen, std::function<SchedulerStats()> scheduler,
                std::function<CacheStats()> cache);
  ~ServerMetrics();
  ServerMetrics(const ServerMetrics&) = delete;
  ServerMetrics& operator=(const ServerMetrics&) = delete;

  /// The bound port of the endpoint (the picked one when listening on port 0); 0 when none.
  int port() const;

  /// A call of `rpc` arrived: raises chasles_requests_in_flight{rpc}.
  void RequestStarted(const std::string& rpc);
  /// A call finished: lowers chasles_requests_in_flight{rpc} (never below 0), counts it in
  /// chasles_requests_total and observes its durations, stages and peak heap.
  void RequestFinished(const RequestRecord& record);

  /// Everything the endpoint would serve now, in the Prometheus text format (also without an endpoint).
  std::string ExpositionText() const;

  /// The gRPC status code name of `code` ("OK", "INVALID_ARGUMENT", …), "other" outside 0..16.
  static std::string StatusCodeName(int code);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace chasles
