#include "chasles/server/metrics.h"

#include <arpa/inet.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <utility>
#include <vector>

#include <prometheus/collectable.h>
#include <prometheus/counter.h>
#include <prometheus/exposer.h>
#include <prometheus/family.h>
#include <prometheus/histogram.h>
#include <prometheus/metric_family.h>
#include <prometheus/registry.h>
#include <prometheus/text_serializer.h>

#include "chasles/v1/chasles.pb.h"

#ifndef CHASLES_VERSION
#define CHASLES_VERSION "unknown"
#endif

namespace chasles {
namespace {

constexpr const char* kOther = "other";
constexpr const char* kNone = "none";

// Durations from 1 ms to 60 s [s].
const std::vector<double> kDurationBuckets = {0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25,
                                              0.5,   1.0,    2.5,   5.0,  10.0,  20.0, 30.0, 60.0};
// Queue waits: mostly near zero, up to a minute under overload [s].
const std::vector<double> kQueueBuckets = {0.0001, 0.0005, 0.001, 0.005, 0.01, 0.05, 0.1,
                                           0.5,    1.0,    2.5,   5.0,   10.0, 30.0, 60.0};
// Peak heap per call, 64 KiB to 4 GiB in factors of 4 [bytes].
const std::vector<double> kHeapBuckets = {65536.0,     262144.0,     1048576.0,    4194304.0,   16777216.0,
                                          67108864.0,  268435456.0,  1073741824.0, 4294967296.0};

// The methods of chasles.v1.Planning, from the generated descriptor (so new RPCs need no edit here).
std::vector<std::string> KnownRpcs() {
  std::vector<std::string> names;
  const google::protobuf::ServiceDescriptor* service = v1::PlanResponse::descriptor()->file()->FindServiceByName("Planning");
  if (service != nullptr) {
    for (int i = 0; i < service->method_count(); ++i) names.push_back(service->method(i)->name());
  }
  return names;
}

// PlanOutcome names, and InverseKinematics' SOLVED / UNSOLVED (its response has no outcome enum).
std::vector<std::string> KnownOutcomes() {
  std::vector<std::string> names = {"SOLVED", "UNSOLVED"};
  const google::protobuf::EnumDescriptor* outcomes = v1::PlanOutcome_descriptor();
  for (int i = 0; i < outcomes->value_count(); ++i) {
    if (outcomes->value(i)->number() != v1::PLAN_OUTCOME_UNSPECIFIED) names.push_back(outcomes->value(i)->name());
  }
  return names;
}

bool Contains(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

// A stage name may become a label value if it is short snake_case.
bool WellFormedStage(const std::string& name) {
  if (name.empty() || name.size() > 32) return false;
  return std::all_of(name.begin(), name.end(),
                     [](char c) { return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_'; });
}

// "PORT" → "127.0.0.1:PORT"; "localhost:PORT" → "127.0.0.1:PORT"; IPv4 or [IPv6] hosts as given.
std::string CivetListeningPort(const std::string& listen) {
  auto fail = [&](const std::string& rule) {
    return std::runtime_error("--metrics-listen '" + listen + "': " + rule);
  };
  const std::size_t colon = listen.rfind(':');
  std::string host = colon == std::string::npos ? "127.0.0.1" : listen.substr(0, colon);
  const std::string port = colon == std::string::npos ? listen : listen.substr(colon + 1);
  if (port.empty() || port.size() > 5 || !std::all_of(port.begin(), port.end(), [](char c) { return c >= '0' && c <= '9'; }) ||
      std::stoi(port) > 65535) {
    throw fail("the port must be an integer in [0, 65535] (HOST:PORT or PORT)");
  }
  if (host == "localhost") host = "127.0.0.1";
  unsigned char address[16];
  if (host.size() > 2 && host.front() == '[' && host.back() == ']') {
    if (inet_pton(AF_INET6, host.substr(1, host.size() - 2).c_str(), address) != 1) {
      throw fail("'" + host + "' is not an IPv6 address");
    }
  } else if (inet_pton(AF_INET, host.c_str(), address) != 1) {
    throw fail("the host must be an IPv4 address, [IPv6 address] or localhost, got '" + host + "'");
  }
  return host + ":" + std::to_string(std::stoi(port));
}

// Resident set size from /proc/self/statm [bytes]; 0 when unreadable.
double ResidentBytes() {
  std::FILE* file = std::fopen("/proc/self/statm", "r");
  if (file == nullptr) return 0.0;
  unsigned long long size_pages = 0, resident_pages = 0;
  const int read = std::fscanf(file, "%llu %llu", &size_pages, &resident_pages);
  std::fclose(file);
  if (read != 2) return 0.0;
  return static_cast<double>(resident_pages) * static_cast<double>(sysconf(_SC_PAGESIZE));
}

prometheus::MetricFamily Family(const char* name, const char* help, prometheus::MetricType type) {
  prometheus::MetricFamily family;
  family.name = name;
  family.help = help;
  family.type = type;
  return family;
}

prometheus::MetricFamily Single(const char* name, const char* help, prometheus::MetricType type, double value) {
  prometheus::MetricFamily family = Family(name, help, type);
  prometheus::ClientMetric metric;
  if (type == prometheus::MetricType::Counter) {
    metric.counter.value = value;
  } else {
    metric.gauge.value = value;
  }
  family.metric.push_back(std::move(metric));
  return family;
}

// Gauges whose values are read when scraped: the callbacks, in-flight calls, RSS and build info.
class ScrapeTimeGauges : public prometheus::Collectable {
 public:
  ScrapeTimeGauges(std::vector<std::string> rpcs, std::function<SchedulerStats()> scheduler,
                   std::function<CacheStats()> cache)
      : rpcs_(std::move(rpcs)),
        in_flight_(rpcs_.size() + 1),
        scheduler_(std::move(scheduler)),
        cache_(std::move(cache)) {}

  // Index of `rpc` in the label set; the last index is "other".
  std::size_t RpcIndex(const std::string& rpc) const {
    return static_cast<std::size_t>(std::find(rpcs_.begin(), rpcs_.end(), rpc) - rpcs_.begin());
  }
  const std::string& RpcLabel(std::size_t index) const {
    static const std::string other = kOther;
    return index < rpcs_.size() ? rpcs_[index] : other;
  }

  void Started(std::size_t index) { in_flight_[index].fetch_add(1, std::memory_order_relaxed); }
  void Finished(std::size_t index) {
    std::atomic<std::int64_t>& count = in_flight_[index];
    std::int64_t value = count.load(std::memory_order_relaxed);
    while (value > 0 && !count.compare_exchange_weak(value, value - 1, std::memory_order_relaxed)) {
    }
  }

  std::vector<prometheus::MetricFamily> Collect() const override {
    using prometheus::MetricType;
    std::vector<prometheus::MetricFamily> families;

    prometheus::MetricFamily in_flight =
        Family("chasles_requests_in_flight", "Calls that arrived and are not answered yet, by RPC.", MetricType::Gauge);
    for (std::size_t i = 0; i < in_flight_.size(); ++i) {
      prometheus::ClientMetric metric;
      metric.label.push_back({"rpc", RpcLabel(i)});
      metric.gauge.value = static_cast<double>(in_flight_[i].load(std::memory_order_relaxed));
      in_flight.metric.push_back(std::move(metric));
    }
    families.push_back(std::move(in_flight));

    if (scheduler_) {
      try {
        const SchedulerStats stats = scheduler_();
        families.push_back(Single("chasles_queue_depth", "Calls waiting for a planning worker.", MetricType::Gauge,
                                  static_cast<double>(stats.queued)));
        families.push_back(Single("chasles_scheduler_in_flight",
                                  "Calls accepted by the worker scheduler and not answered yet (queued + running).",
                                  MetricType::Gauge, static_cast<double>(stats.in_flight)));
        families.push_back(Single("chasles_workers_busy", "Planning workers running a call.", MetricType::Gauge,
                                  static_cast<double>(stats.workers_busy)));
        families.push_back(
            Single("chasles_workers", "Planning worker threads.", MetricType::Gauge, static_cast<double>(stats.workers)));
      } catch (const std::exception&) {
        // Left out of this scrape; the next one tries again.
      }
    }
    if (cache_) {
      try {
        const CacheStats stats = cache_();
        families.push_back(Single("chasles_cache_entries", "Robots, scenes and checkers held by the model cache.",
                                  MetricType::Gauge, static_cast<double>(stats.entries)));
        families.push_back(Single("chasles_cache_bytes", "Estimated bytes held by the model cache.", MetricType::Gauge,
                                  static_cast<double>(stats.bytes)));
        families.push_back(Single("chasles_cache_capacity_bytes", "Capacity of the model cache (--cache-mb) in bytes.",
                                  MetricType::Gauge, static_cast<double>(stats.capacity_bytes)));
        families.push_back(Single("chasles_cache_evictions_total", "Model cache entries evicted since start.",
                                  MetricType::Counter, static_cast<double>(stats.evictions)));
      } catch (const std::exception&) {
      }
    }
    families.push_back(Single("chasles_process_resident_memory_bytes", "Resident set size of the server process in bytes.",
                              MetricType::Gauge, ResidentBytes()));
    prometheus::MetricFamily build = Family("chasles_build_info", "Always 1; the version label is the server's.",
                                            MetricType::Gauge);
    prometheus::ClientMetric metric;
    metric.label.push_back({"version", CHASLES_VERSION});
    metric.gauge.value = 1.0;
    build.metric.push_back(std::move(metric));
    families.push_back(std::move(build));
    return families;
  }

 private:
  const std::vector<std::string> rpcs_;
  // One per rpc label and one for "other"; the vector is never resized.
  std::vector<std::atomic<std::int64_t>> in_flight_;
  const std::function<SchedulerStats()> scheduler_;
  const std::function<CacheStats()> cache_;
};

}  // namespace

struct ServerMetrics::Impl {
  const std::vector<std::string> outcomes = KnownOutcomes();
  std::shared_ptr<prometheus::Registry> registry = std::make_shared<prometheus::Registry>();
  std::shared_ptr<ScrapeTimeGauges> gauges;
  prometheus::Family<prometheus::Counter>* requests = nullptr;
  prometheus::Family<prometheus::Histogram>* duration = nullptr;
  prometheus::Family<prometheus::Histogram>* queue_wait = nullptr;
  prometheus::Family<prometheus::Histogram>* stage_duration = nullptr;
  prometheus::Family<prometheus::Histogram>* peak_heap = nullptr;

  // The series of each rpc label (index as ScrapeTimeGauges::RpcIndex) and stage label, made on
  // first use: Family::Add builds a metric before looking its labels up, so it is called once per series.
  struct RpcSeries {
    prometheus::Histogram* duration = nullptr;
    prometheus::Histogram* queue_wait = nullptr;
    prometheus::Histogram* peak_heap = nullptr;
  };
  std::mutex series_mutex;
  std::vector<RpcSeries> rpc_series;
  std::vector<std::pair<std::string, prometheus::Histogram*>> stage_series;  // ≤ kMaxStageLabels + 1

  // Last member: destroyed first, so no scrape runs while the rest goes away.
  std::unique_ptr<prometheus::Exposer> exposer;

  const RpcSeries& Series(std::size_t index) {
    std::lock_guard<std::mutex> lock(series_mutex);
    RpcSeries& series = rpc_series[index];
    if (series.duration == nullptr) {
      const prometheus::Labels labels = {{"rpc", gauges->RpcLabel(index)}};
      series.duration = &duration->Add(labels, kDurationBuckets);
      series.queue_wait = &queue_wait->Add(labels, kQueueBuckets);
    }
    return series;
  }

  // Made on the first record with a peak heap, so RPCs that never measure it have no empty series.
  prometheus::Histogram& PeakHeapSeries(std::size_t index) {
    std::lock_guard<std::mutex> lock(series_mutex);
    RpcSeries& series = rpc_series[index];
    if (series.peak_heap == nullptr) series.peak_heap = &peak_heap->Add({{"rpc", gauges->RpcLabel(index)}}, kHeapBuckets);
    return *series.peak_heap;
  }

  // The series of stage `name`: "other" when it is not short snake_case or kMaxStageLabels names are taken.
  prometheus::Histogram& StageSeries(const std::string& name) {
    std::lock_guard<std::mutex> lock(series_mutex);
    std::string label = WellFormedStage(name) ? name : kOther;
    auto find = [&](const std::string& wanted) -> prometheus::Histogram* {
      for (const auto& [known, histogram] : stage_series) {
        if (known == wanted) return histogram;
      }
      return nullptr;
    };
    if (prometheus::Histogram* histogram = find(label)) return *histogram;
    const auto named = std::count_if(stage_series.begin(), stage_series.end(),
                                     [](const auto& entry) { return entry.first != kOther; });
    if (label != kOther && static_cast<std::size_t>(named) >= kMaxStageLabels) {
      label = kOther;
      if (prometheus::Histogram* histogram = find(label)) return *histogram;
    }
    prometheus::Histogram& histogram = stage_duration->Add({{"stage", label}}, kDurationBuckets);
    stage_series.emplace_back(label, &histogram);
    return histogram;
  }

  std::vector<std::weak_ptr<prometheus::Collectable>> Collectables() const { return {registry, gauges}; }
};

ServerMetrics::ServerMetrics(const std::string& listen, std::function<SchedulerStats()> scheduler,
                             std::function<CacheStats()> cache)
    : impl_(std::make_unique<Impl>()) {
  std::vector<std::string> rpcs = KnownRpcs();
  impl_->rpc_series.resize(rpcs.size() + 1);
  impl_->gauges = std::make_shared<ScrapeTimeGauges>(std::move(rpcs), std::move(scheduler), std::move(cache));
  using prometheus::BuildCounter;
  using prometheus::BuildHistogram;
  impl_->requests = &BuildCounter()
                         .Name("chasles_requests_total")
                         .Help("Finished calls by RPC, response outcome (PlanOutcome name or none) and gRPC status code.")
                         .Register(*impl_->registry);
  impl_->duration = &BuildHistogram()
                         .Name("chasles_request_duration_seconds")
                         .Help("Time from a call's arrival to its answer, by RPC, in seconds.")
                         .Register(*impl_->registry);
  impl_->queue_wait = &BuildHistogram()
                           .Name("chasles_queue_wait_seconds")
                           .Help("Time a call waited for a planning worker, by RPC, in seconds.")
                           .Register(*impl_->registry);
  impl_->stage_duration = &BuildHistogram()
                               .Name("chasles_stage_duration_seconds")
                               .Help("Time spent in one stage of a call (validate, plan, …), in seconds.")
                               .Register(*impl_->registry);
  impl_->peak_heap = &BuildHistogram()
                          .Name("chasles_request_peak_heap_bytes")
                          .Help("Peak heap allocated by a call's worker thread, by RPC, in bytes.")
                          .Register(*impl_->registry);
  if (listen.empty()) return;
  const std::string address = CivetListeningPort(listen);
  try {
    impl_->exposer = std::make_unique<prometheus::Exposer>(address, 2);
  } catch (const std::exception& e) {
    throw std::runtime_error("--metrics-listen '" + listen + "': cannot listen on " + address + " (" + e.what() + ")");
  }
  for (const auto& collectable : impl_->Collectables()) impl_->exposer->RegisterCollectable(collectable);
}

ServerMetrics::~ServerMetrics() = default;

int ServerMetrics::port() const {
  if (!impl_->exposer) return 0;
  const std::vector<int> ports = impl_->exposer->GetListeningPorts();
  return ports.empty() ? 0 : ports.front();
}

void ServerMetrics::RequestStarted(const std::string& rpc) { impl_->gauges->Started(impl_->gauges->RpcIndex(rpc)); }

void ServerMetrics::RequestFinished(const RequestRecord& record) {
  const std::size_t index = impl_->gauges->RpcIndex(record.rpc);
  impl_->gauges->Finished(index);
  const std::string& rpc = impl_->gauges->RpcLabel(index);
  const std::string outcome = record.outcome.empty() || record.outcome == "PLAN_OUTCOME_UNSPECIFIED" ? kNone
                              : Contains(impl_->outcomes, record.outcome)                             ? record.outcome
                                                                                                       : kOther;
  impl_->requests->Add({{"rpc", rpc}, {"outcome", outcome}, {"code", StatusCodeName(record.status_code)}}).Increment();
  const Impl::RpcSeries& series = impl_->Series(index);
  series.duration->Observe(std::max(0.0, record.total_seconds));
  series.queue_wait->Observe(std::max(0.0, record.queue_seconds));
  if (record.peak_heap_bytes > 0) impl_->PeakHeapSeries(index).Observe(static_cast<double>(record.peak_heap_bytes));
  for (const auto& [name, seconds] : record.stages) impl_->StageSeries(name).Observe(std::max(0.0, seconds));
}

std::string ServerMetrics::ExpositionText() const {
  std::vector<prometheus::MetricFamily> families;
  for (const auto& weak : impl_->Collectables()) {
    if (const auto collectable = weak.lock()) {
      std::vector<prometheus::MetricFamily> some = collectable->Collect();
      families.insert(families.end(), std::make_move_iterator(some.begin()), std::make_move_iterator(some.end()));
    }
  }
  return prometheus::TextSerializer().Serialize(families);
}

std::string ServerMetrics::StatusCodeName(int code) {
  static const std::array<const char*, 17> kNames = {
      "OK",           "CANCELLED",         "UNKNOWN",         "INVALID_ARGUMENT",    "DEADLINE_EXCEEDED", "NOT_FOUND",
      "ALREADY_EXISTS", "PERMISSION_DENIED", "RESOURCE_EXHAUSTED", "FAILED_PRECONDITION", "ABORTED",        "OUT_OF_RANGE",
      "UNIMPLEMENTED", "INTERNAL",         "UNAVAILABLE",     "DATA_LOSS",           "UNAUTHENTICATED"};
  return code >= 0 && code < static_cast<int>(kNames.size()) ? kNames[static_cast<std::size_t>(code)] : kOther;
}

}  // namespace chasles
