// Prometheus metrics: ServerMetrics on a loopback port scraped over real HTTP (python3's urllib),
// the text format parsed back — counters and histogram counts move by exactly what was recorded,
// gauges are the callbacks' values at each scrape, label values stay in their bounded sets — and
// end to end through a PlanningServer with --metrics-listen.
#include "chasles/server/metrics.h"

#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <chrono>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "server_fixture.h"

namespace chasles::testing {
namespace {

/// One sample line of the text format: `name{label="value",…} value`.
struct Sample {
  std::string name;
  std::map<std::string, std::string> labels;
  double value = 0.0;
};

/// Parses the sample lines of the Prometheus text format (comments skipped). Fails the test on a
/// line it cannot read.
std::vector<Sample> ParseExposition(const std::string& text) {
  std::vector<Sample> samples;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    if (line.empty() || line[0] == '#') continue;
    Sample sample;
    std::size_t i = line.find_first_of("{ ");
    if (i == std::string::npos) {
      ADD_FAILURE() << "unreadable line: " << line;
      continue;
    }
    sample.name = line.substr(0, i);
    if (line[i] == '{') {
      ++i;
      while (i < line.size() && line[i] != '}') {
        const std::size_t eq = line.find("=\"", i);
        if (eq == std::string::npos) break;
        const std::string key = line.substr(i, eq - i);
        std::string value;
        std::size_t j = eq + 2;
        for (; j < line.size() && line[j] != '"'; ++j) {
          if (line[j] == '\\' && j + 1 < line.size()) ++j;
          value += line[j];
        }
        sample.labels[key] = value;
        i = j + 1;
        if (i < line.size() && line[i] == ',') ++i;
      }
      ++i;  // '}'
    }
    std::istringstream rest(line.substr(i));
    std::string value;
    rest >> value;
    sample.value = value == "+Inf" ? HUGE_VAL : std::stod(value);
    samples.push_back(std::move(sample));
  }
  return samples;
}

/// The samples named `name` whose labels include all of `labels`.
std::vector<Sample> Matching(const std::vector<Sample>& samples, const std::string& name,
                             const std::map<std::string, std::string>& labels = {}) {
  std::vector<Sample> found;
  for (const Sample& sample : samples) {
    if (sample.name != name) continue;
    bool all = true;
    for (const auto& [key, value] : labels) {
      const auto it = sample.labels.find(key);
      all = all && it != sample.labels.end() && it->second == value;
    }
    if (all) found.push_back(sample);
  }
  return found;
}

/// Sum over the matching samples (0 when none).
double Sum(const std::vector<Sample>& samples, const std::string& name,
           const std::map<std::string, std::string>& labels = {}) {
  double sum = 0.0;
  for (const Sample& sample : Matching(samples, name, labels)) sum += sample.value;
  return sum;
}

/// The one matching sample's value; fails the test (and gives NaN) when there is not exactly one.
double Value(const std::vector<Sample>& samples, const std::string& name,
                            const std::map<std::string, std::string>& labels = {}) {
  const std::vector<Sample> found = Matching(samples, name, labels);
  if (found.size() != 1) {
    ADD_FAILURE() << found.size() << " samples of " << name << " match";
    return std::nan("");
  }
  return found.front().value;
}

/// GET http://127.0.0.1:port/metrics with Python's http.client (a client independent of the
/// server); fails unless the answer is 200 with the text format's content type. Debian's
/// /usr/bin/python3 with -I -S starts in ~0.1 s (a pyenv shim first on PATH takes > 1 s).
std::string HttpGet(int port) {
  const std::string python = access("/usr/bin/python3", X_OK) == 0 ? "/usr/bin/python3" : "python3";
  const std::string command =
      python + " -I -S -c 'import sys, http.client as h\n"
      "c = h.HTTPConnection(\"127.0.0.1\", " + std::to_string(port) + ", timeout=10)\n"
      "c.request(\"GET\", \"/metrics\")\n"
      "r = c.getresponse()\n"
      "body = r.read().decode()\n"
      "ok = r.status == 200 and r.getheader(\"Content-Type\", \"\").startswith(\"text/plain\")\n"
      "sys.stdout.write(body if ok else \"HTTP %d %s\\n%s\" % (r.status, r.getheader(\"Content-Type\"), body))\n"
      "sys.exit(0 if ok else 1)' 2>&1";
  std::FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) throw std::runtime_error("popen failed");
  std::string out;
  char buffer[4096];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0) out.append(buffer, n);
  const int status = pclose(pipe);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) throw std::runtime_error("scrape failed: " + out);
  return out;
}

std::vector<Sample> Scrape(int port) { return ParseExposition(HttpGet(port)); }

RequestRecord Record(const std::string& rpc, const std::string& outcome, int code, double total_s, double queue_s) {
  RequestRecord record;
  record.rpc = rpc;
  record.request_id = "req-7f3a";
  record.client = "ipv4:127.0.0.1:5678";
  record.outcome = outcome;
  record.status_code = code;
  record.total_seconds = total_s;
  record.queue_seconds = queue_s;
  return record;
}

TEST(ServerMetrics, CountersAndHistogramsMoveByWhatWasRecorded) {
  ServerMetrics metrics("127.0.0.1:0", nullptr, nullptr);
  ASSERT_GT(metrics.port(), 0);
  const std::vector<Sample> before = Scrape(metrics.port());
  EXPECT_EQ(Sum(before, "chasles_requests_total"), 0.0);

  RequestRecord ok = Record("Plan", "SUCCESS", 0, 0.004, 0.0002);
  ok.stages = {{"validate", 0.001}, {"plan", 0.002}, {"verify", 0.0005}};
  ok.peak_heap_bytes = 3u << 20;
  metrics.RequestFinished(ok);
  ok.total_seconds = 0.2;
  metrics.RequestFinished(ok);
  metrics.RequestFinished(Record("Plan", "", 3, 0.0005, 0.0));                 // INVALID_ARGUMENT
  metrics.RequestFinished(Record("Optimize", "NO_PATH_WITHIN_BUDGET", 0, 1.5, 0.3));
  metrics.RequestFinished(Record("InverseKinematics", "UNSOLVED", 0, 0.05, 0.0));

  const std::vector<Sample> after = Scrape(metrics.port());
  EXPECT_EQ(Value(after, "chasles_requests_total", {{"rpc", "Plan"}, {"outcome", "SUCCESS"}, {"code", "OK"}}), 2.0);
  EXPECT_EQ(Value(after, "chasles_requests_total", {{"rpc", "Plan"}, {"outcome", "none"}, {"code", "INVALID_ARGUMENT"}}),
            1.0);
  EXPECT_EQ(Value(after, "chasles_requests_total",
                  {{"rpc", "Optimize"}, {"outcome", "NO_PATH_WITHIN_BUDGET"}, {"code", "OK"}}),
            1.0);
  EXPECT_EQ(Value(after, "chasles_requests_total", {{"rpc", "InverseKinematics"}, {"outcome", "UNSOLVED"}}), 1.0);
  EXPECT_EQ(Sum(after, "chasles_requests_total"), 5.0);

  EXPECT_EQ(Value(after, "chasles_request_duration_seconds_count", {{"rpc", "Plan"}}), 3.0);
  EXPECT_NEAR(Value(after, "chasles_request_duration_seconds_sum", {{"rpc", "Plan"}}), 0.2045, 1e-12);
  // Cumulative buckets: 0.0005 and 0.004 are ≤ 5 ms, 0.2 is not; all three are ≤ 60 s and +Inf.
  EXPECT_EQ(Value(after, "chasles_request_duration_seconds_bucket", {{"rpc", "Plan"}, {"le", "0.005"}}), 2.0);
  EXPECT_EQ(Value(after, "chasles_request_duration_seconds_bucket", {{"rpc", "Plan"}, {"le", "0.001"}}), 1.0);
  EXPECT_EQ(Value(after, "chasles_request_duration_seconds_bucket", {{"rpc", "Plan"}, {"le", "60"}}), 3.0);
  EXPECT_EQ(Value(after, "chasles_request_duration_seconds_bucket", {{"rpc", "Plan"}, {"le", "+Inf"}}), 3.0);
  EXPECT_EQ(Value(after, "chasles_request_duration_seconds_count", {{"rpc", "Optimize"}}), 1.0);
  EXPECT_EQ(Value(after, "chasles_queue_wait_seconds_count", {{"rpc", "Plan"}}), 3.0);
  EXPECT_NEAR(Value(after, "chasles_queue_wait_seconds_sum", {{"rpc", "Optimize"}}), 0.3, 1e-12);

  EXPECT_EQ(Value(after, "chasles_stage_duration_seconds_count", {{"stage", "plan"}}), 2.0);
  EXPECT_EQ(Value(after, "chasles_stage_duration_seconds_count", {{"stage", "validate"}}), 2.0);
  EXPECT_NEAR(Value(after, "chasles_stage_duration_seconds_sum", {{"stage", "verify"}}), 0.001, 1e-12);

  // Only the records with a peak heap are observed: two of 3 MiB, in the ≤ 4 MiB bucket, not ≤ 1 MiB.
  EXPECT_EQ(Value(after, "chasles_request_peak_heap_bytes_count", {{"rpc", "Plan"}}), 2.0);
  EXPECT_EQ(Value(after, "chasles_request_peak_heap_bytes_bucket", {{"rpc", "Plan"}, {"le", "4194304"}}), 2.0);
  EXPECT_EQ(Value(after, "chasles_request_peak_heap_bytes_bucket", {{"rpc", "Plan"}, {"le", "1048576"}}), 0.0);
  EXPECT_TRUE(Matching(after, "chasles_request_peak_heap_bytes_count", {{"rpc", "Optimize"}}).empty());

  // The in-process text and the scraped one agree.
  const std::vector<Sample> text = ParseExposition(metrics.ExpositionText());
  EXPECT_EQ(Sum(text, "chasles_requests_total"), 5.0);
}

TEST(ServerMetrics, GaugesAreTheCallbacksValuesAtEachScrape) {
  std::atomic<std::uint64_t> queued{3};
  ServerMetrics metrics(
      "127.0.0.1:0",
      [&] {
        SchedulerStats stats;
        stats.queued = queued.load();
        stats.in_flight = queued.load() + 2;
        stats.workers_busy = 2;
        stats.workers = 4;
        return stats;
      },
      [] {
        CacheStats stats;
        stats.entries = 7;
        stats.bytes = 123456789;
        stats.capacity_bytes = 256ull << 20;
        stats.evictions = 11;
        return stats;
      });
  std::vector<Sample> samples = Scrape(metrics.port());
  EXPECT_EQ(Value(samples, "chasles_queue_depth"), 3.0);
  EXPECT_EQ(Value(samples, "chasles_scheduler_in_flight"), 5.0);
  EXPECT_EQ(Value(samples, "chasles_workers_busy"), 2.0);
  EXPECT_EQ(Value(samples, "chasles_workers"), 4.0);
  EXPECT_EQ(Value(samples, "chasles_cache_entries"), 7.0);
  EXPECT_EQ(Value(samples, "chasles_cache_bytes"), 123456789.0);
  EXPECT_EQ(Value(samples, "chasles_cache_capacity_bytes"), static_cast<double>(256ull << 20));
  EXPECT_EQ(Value(samples, "chasles_cache_evictions_total"), 11.0);
  EXPECT_GT(Value(samples, "chasles_process_resident_memory_bytes"), 1e6);  // this process holds > 1 MB
  EXPECT_EQ(Value(samples, "chasles_build_info"), 1.0);
  ASSERT_EQ(Matching(samples, "chasles_build_info").size(), 1u);
  EXPECT_FALSE(Matching(samples, "chasles_build_info").front().labels.at("version").empty());

  queued = 9;  // read again at the next scrape, not cached
  samples = Scrape(metrics.port());
  EXPECT_EQ(Value(samples, "chasles_queue_depth"), 9.0);
  EXPECT_EQ(Value(samples, "chasles_scheduler_in_flight"), 11.0);
}

TEST(ServerMetrics, InFlightPerRpcNeverBelowZero) {
  ServerMetrics metrics("127.0.0.1:0", nullptr, nullptr);
  metrics.RequestStarted("Plan");
  metrics.RequestStarted("Plan");
  metrics.RequestStarted("ListPlanners");
  std::vector<Sample> samples = Scrape(metrics.port());
  EXPECT_EQ(Value(samples, "chasles_requests_in_flight", {{"rpc", "Plan"}}), 2.0);
  EXPECT_EQ(Value(samples, "chasles_requests_in_flight", {{"rpc", "ListPlanners"}}), 1.0);
  EXPECT_EQ(Value(samples, "chasles_requests_in_flight", {{"rpc", "Optimize"}}), 0.0);

  metrics.RequestFinished(Record("Plan", "SUCCESS", 0, 0.01, 0.0));
  metrics.RequestFinished(Record("ListPlanners", "", 0, 0.001, 0.0));
  metrics.RequestFinished(Record("ListPlanners", "", 0, 0.001, 0.0));  // one more than started
  samples = Scrape(metrics.port());
  EXPECT_EQ(Value(samples, "chasles_requests_in_flight", {{"rpc", "Plan"}}), 1.0);
  EXPECT_EQ(Value(samples, "chasles_requests_in_flight", {{"rpc", "ListPlanners"}}), 0.0);
}

TEST(ServerMetrics, LabelValuesStayInTheirBoundedSets) {
  ServerMetrics metrics("127.0.0.1:0", nullptr, nullptr);
  RequestRecord odd = Record("Plan; DROP TABLE", "client-chose-this-7f3a", 99, 0.01, 0.0);
  odd.stages = {{"User Supplied Stage!", 0.001}};
  metrics.RequestStarted("NoSuchRpc");
  metrics.RequestFinished(odd);
  RequestRecord many = Record("Plan", "SUCCESS", 0, 0.01, 0.0);
  for (int i = 0; i < 40; ++i) many.stages.emplace_back("stage_" + std::to_string(i), 0.001);
  metrics.RequestFinished(many);

  const std::string text = HttpGet(metrics.port());
  const std::vector<Sample> samples = ParseExposition(text);
  EXPECT_EQ(Value(samples, "chasles_requests_total", {{"rpc", "other"}, {"outcome", "other"}, {"code", "other"}}), 1.0);
  EXPECT_EQ(Value(samples, "chasles_requests_in_flight", {{"rpc", "other"}}), 0.0);  // started and finished
  // The request id and client name of the records never appear.
  EXPECT_EQ(text.find("7f3a"), std::string::npos);
  EXPECT_EQ(text.find("127.0.0.1:5678"), std::string::npos);
  EXPECT_EQ(text.find("DROP"), std::string::npos);

  // Stages: the first kMaxStageLabels well-formed names get their own label, the rest and the
  // malformed one are "other".
  std::set<std::string> stages;
  for (const Sample& sample : Matching(samples, "chasles_stage_duration_seconds_count")) {
    stages.insert(sample.labels.at("stage"));
  }
  EXPECT_EQ(stages.size(), ServerMetrics::kMaxStageLabels + 1);
  const std::size_t last_named = ServerMetrics::kMaxStageLabels - 1;
  EXPECT_EQ(stages.count("stage_0"), 1u);
  EXPECT_EQ(stages.count("stage_" + std::to_string(last_named)), 1u);
  EXPECT_EQ(stages.count("stage_" + std::to_string(last_named + 1)), 0u);
  // The malformed name plus the 40 - kMaxStageLabels names that came too late.
  EXPECT_EQ(Value(samples, "chasles_stage_duration_seconds_count", {{"stage", "other"}}),
            1.0 + (40.0 - static_cast<double>(ServerMetrics::kMaxStageLabels)));

  // Every rpc label of every series is a Planning method or "other".
  const std::set<std::string> methods = {"Plan", "ListPlanners", "UploadRobot", "UploadScene", "UpdateScene",
                                         "InverseKinematics", "CartesianPath", "Optimize", "Coordinate", "CreateWorkcell",
                                         "CommitTrajectory", "Release", "Benchmark", "StopBenchmark",
                                         "OpenFleetSession", "AssignFleetGoals", "CloseFleetSession", "StreamFleetSession",
                                         "Replan", "other"};
  for (const Sample& sample : samples) {
    const auto rpc = sample.labels.find("rpc");
    if (rpc != sample.labels.end()) {
      EXPECT_EQ(methods.count(rpc->second), 1u) << sample.name << " rpc=" << rpc->second;
    }
  }
}

TEST(ServerMetrics, ConcurrentRecordsAreAllCounted) {
  ServerMetrics metrics("", nullptr, nullptr);
  EXPECT_EQ(metrics.port(), 0);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&metrics, t] {
      RequestRecord record = Record(t % 2 == 0 ? "Plan" : "Optimize", "SUCCESS", 0, 0.01, 0.001);
      record.stages = {{"plan", 0.005}, {"stage_t" + std::to_string(t), 0.001}};
      for (int i = 0; i < 500; ++i) {
        metrics.RequestStarted(record.rpc);
        metrics.RequestFinished(record);
      }
    });
  }
  for (std::thread& thread : threads) thread.join();
  const std::vector<Sample> samples = ParseExposition(metrics.ExpositionText());
  EXPECT_EQ(Sum(samples, "chasles_requests_total"), 2000.0);
  EXPECT_EQ(Value(samples, "chasles_request_duration_seconds_count", {{"rpc", "Plan"}}), 1000.0);
  EXPECT_EQ(Value(samples, "chasles_stage_duration_seconds_count", {{"stage", "plan"}}), 2000.0);
  EXPECT_EQ(Sum(samples, "chasles_requests_in_flight"), 0.0);
}

TEST(ServerMetrics, ThrowingCallbackLeavesOnlyItsGaugesOut) {
  ServerMetrics metrics(
      "127.0.0.1:0", []() -> SchedulerStats { throw std::runtime_error("scheduler gone"); },
      [] {
        CacheStats stats;
        stats.entries = 2;
        return stats;
      });
  const std::vector<Sample> samples = Scrape(metrics.port());
  EXPECT_TRUE(Matching(samples, "chasles_queue_depth").empty());
  EXPECT_EQ(Value(samples, "chasles_cache_entries"), 2.0);
  EXPECT_GT(Value(samples, "chasles_process_resident_memory_bytes"), 0.0);
}

void ExpectListenError(const std::string& listen, const std::string& fragment) {
  try {
    ServerMetrics metrics(listen, nullptr, nullptr);
    ADD_FAILURE() << "'" << listen << "' was accepted";
  } catch (const std::runtime_error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("--metrics-listen"), std::string::npos) << message;
    EXPECT_NE(message.find(fragment), std::string::npos) << message;
  }
}

TEST(ServerMetrics, BadOrTakenAddressesAreNamedErrors) {
  ServerMetrics first("127.0.0.1:0", nullptr, nullptr);
  ExpectListenError("127.0.0.1:" + std::to_string(first.port()), "cannot listen");
  ExpectListenError("example.com:9464", "IPv4");
  ExpectListenError("127.0.0.1:70000", "[0, 65535]");
  ExpectListenError("127.0.0.1:", "port");
  ExpectListenError("[::1:9464", "host");
}

TEST(ServerMetrics, BarePortAndLocalhostListenOnLoopback) {
  ServerMetrics metrics("localhost:0", nullptr, nullptr);
  ASSERT_GT(metrics.port(), 0);
  EXPECT_NO_THROW(Scrape(metrics.port()));
  ServerMetrics bare("0", nullptr, nullptr);
  ASSERT_GT(bare.port(), 0);
  EXPECT_NO_THROW(Scrape(bare.port()));
}

// Through a real server: one good Plan and one malformed one move chasles_requests_total{rpc="Plan"}
// under code OK and INVALID_ARGUMENT by one each.
TEST(ServerMetricsEndToEnd, PlanOkAndInvalidArgumentAreCounted) {
  ServerOptions options;
  options.listen = "127.0.0.1:0";
  options.threads = 2;
  options.log_requests = false;
  options.metrics_listen = "127.0.0.1:0";
  PlanningServer server(options);
  const int metrics_port = server.metrics_port();
  ASSERT_GT(metrics_port, 0);
  auto channel = grpc::CreateChannel("127.0.0.1:" + std::to_string(server.port()), grpc::InsecureChannelCredentials());
  auto stub = v1::Planning::NewStub(channel);

  const std::vector<Sample> before = Scrape(metrics_port);
  const double ok_before = Sum(before, "chasles_requests_total", {{"rpc", "Plan"}, {"code", "OK"}});
  const double bad_before = Sum(before, "chasles_requests_total", {{"rpc", "Plan"}, {"code", "INVALID_ARGUMENT"}});

  v1::PlanRequest good = LoadRequest("planar_2r_posts");
  v1::PlanRequest bad = good;
  bad.mutable_robot()->mutable_urdf()->set_urdf("<robot name='broken'><link name='a'>");
  for (const auto* request : {&good, &bad}) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
    v1::PlanResponse response;
    const grpc::Status status = stub->Plan(&context, *request, &response);
    EXPECT_EQ(status.error_code(), request == &good ? grpc::StatusCode::OK : grpc::StatusCode::INVALID_ARGUMENT)
        << status.error_message();
  }

  // The record is finished after the answer is sent: poll briefly (a liveness bound, not a timing).
  std::vector<Sample> after;
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  do {
    after = Scrape(metrics_port);
    if (Sum(after, "chasles_request_duration_seconds_count", {{"rpc", "Plan"}}) >= 2.0) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  } while (std::chrono::steady_clock::now() < give_up);

  EXPECT_EQ(Sum(after, "chasles_requests_total", {{"rpc", "Plan"}, {"code", "OK"}}) - ok_before, 1.0);
  EXPECT_EQ(Sum(after, "chasles_requests_total", {{"rpc", "Plan"}, {"code", "INVALID_ARGUMENT"}}) - bad_before, 1.0);
  EXPECT_EQ(Value(after, "chasles_requests_total", {{"rpc", "Plan"}, {"code", "INVALID_ARGUMENT"}, {"outcome", "none"}}),
            1.0);
  EXPECT_EQ(Value(after, "chasles_request_duration_seconds_count", {{"rpc", "Plan"}}), 2.0);
  EXPECT_EQ(Value(after, "chasles_workers"), 2.0);
  EXPECT_EQ(Value(after, "chasles_requests_in_flight", {{"rpc", "Plan"}}), 0.0);
  EXPECT_GT(Value(after, "chasles_process_resident_memory_bytes"), 0.0);
  server.Shutdown();
  server.Wait();
}

}  // namespace
}  // namespace chasles::testing
