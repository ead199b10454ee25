// A server that hostile or careless clients cannot crash, starve or fill: caps checked before
// the work, per-request memory, malformed messages, budgets, fair queueing, log escaping.
#include <atomic>
#include <cmath>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <fstream>
#include <future>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>
#include <grpcpp/generic/generic_stub.h>
#include <gtest/gtest.h>

#include "chasles/server/heap_tracking.h"
#include "chasles/server/request_log.h"
#include "chasles/server/thread_pool.h"
#include "server_fixture.h"

namespace chasles {
namespace {

using testing::LoadRequest;
using testing::LoopbackServer;

// ---- Fair queueing (the pool itself, no timing) ------------------------------------------

/// Holds a pool's workers until released, recording the order jobs start in.
struct Gate {
  std::mutex mutex;
  std::condition_variable opened;
  bool open = false;
  std::vector<std::string> order;
  void Wait() {
    std::unique_lock<std::mutex> lock(mutex);
    opened.wait(lock, [this] { return open; });
  }
  void Open() {
    {
      std::lock_guard<std::mutex> lock(mutex);
      open = true;
    }
    opened.notify_all();
  }
  void Record(const std::string& what) {
    std::lock_guard<std::mutex> lock(mutex);
    order.push_back(what);
  }
};

TEST(FairPool, ServesClientsRoundRobin) {
  PoolOptions options;
  options.threads = 1;
  ThreadPool pool(options);
  Gate gate;
  std::promise<void> blocked;
  // The one worker is held by a first job while the queues fill.
  ASSERT_TRUE(pool.Submit([&] { blocked.set_value(); gate.Wait(); }, {"setup", false}));
  blocked.get_future().wait();
  for (int k = 0; k < 5; ++k) {
    ASSERT_TRUE(pool.Submit([&gate, k] { gate.Record("flood" + std::to_string(k)); }, {"flooder", false}));
  }
  ASSERT_TRUE(pool.Submit([&] { gate.Record("b"); }, {"b", false}));
  ASSERT_TRUE(pool.Submit([&] { gate.Record("c"); }, {"c", false}));
  EXPECT_EQ(pool.stats().queued, 7u);
  EXPECT_EQ(pool.stats().workers_busy, 1u);
  std::promise<void> done;
  ASSERT_TRUE(pool.Submit([&] { done.set_value(); }, {"flooder", false}));
  gate.Open();
  done.get_future().wait();
  // One job of each waiting client in turn: the flooder's second job waits for b and c.
  const std::vector<std::string> expected = {"flood0", "b", "c", "flood1", "flood2", "flood3", "flood4"};
  EXPECT_EQ(gate.order, expected);
}

TEST(FairPool, LongJobsHoldAtMostTheirShareOfTheWorkers) {
  PoolOptions options;
  options.threads = 2;
  options.long_share = 0.5;
  ThreadPool pool(options);
  EXPECT_EQ(pool.max_long_workers(), 1);
  Gate gate;
  std::atomic<int> long_running{0}, max_long_running{0};
  auto long_job = [&] {
    const int now = ++long_running;
    int seen = max_long_running.load();
    while (now > seen && !max_long_running.compare_exchange_weak(seen, now)) {
    }
    gate.Wait();
    --long_running;
  };
  ASSERT_TRUE(pool.Submit(long_job, {"a", true}));
  ASSERT_TRUE(pool.Submit(long_job, {"a", true}));
  // A short job of another client (and of the same one) runs while both long jobs are queued
  // or running: one worker stays free for it.
  std::promise<void> short_b, short_a;
  ASSERT_TRUE(pool.Submit([&] { short_b.set_value(); }, {"b", false}));
  ASSERT_TRUE(pool.Submit([&] { short_a.set_value(); }, {"a", false}));
  EXPECT_EQ(short_b.get_future().wait_for(std::chrono::seconds(30)), std::future_status::ready);
  EXPECT_EQ(short_a.get_future().wait_for(std::chrono::seconds(30)), std::future_status::ready);
  EXPECT_EQ(max_long_running.load(), 1);
  gate.Open();
}

TEST(FairPool, RefusesBeyondAClientsQueue) {
  PoolOptions options;
  options.threads = 1;
  options.max_queued = 100;
  options.max_queued_per_client = 2;
  ThreadPool pool(options);
  Gate gate;
  std::promise<void> blocked;
  ASSERT_TRUE(pool.Submit([&] { blocked.set_value(); gate.Wait(); }, {"x", false}));
  blocked.get_future().wait();
  EXPECT_EQ(pool.TrySubmit([] {}, {"greedy", false}), SubmitResult::kQueued);
  EXPECT_EQ(pool.TrySubmit([] {}, {"greedy", false}), SubmitResult::kQueued);
  EXPECT_EQ(pool.TrySubmit([] {}, {"greedy", false}), SubmitResult::kClientQueueFull);
  EXPECT_EQ(pool.TrySubmit([] {}, {"polite", false}), SubmitResult::kQueued);
  gate.Open();
}

TEST(PoolOptions, LongWorkersFromTheShare) {
  PoolOptions options;
  options.long_share = 0.5;
  EXPECT_EQ(options.MaxLongWorkers(1), 1);
  EXPECT_EQ(options.MaxLongWorkers(2), 1);
  EXPECT_EQ(options.MaxLongWorkers(8), 4);
  options.long_share = 0.9;
  EXPECT_EQ(options.MaxLongWorkers(2), 1);  // one stays for short work
  options.long_share = 1.0;
  EXPECT_EQ(options.MaxLongWorkers(2), 2);
  options.long_share = 0.01;
  EXPECT_EQ(options.MaxLongWorkers(8), 1);
}

// ---- Per-request memory ----------------------------------------------------------------

TEST(HeapScope, RefusesAllocationsBeyondItsLimitAndNests) {
  HeapScope outer(1 << 20);
  std::vector<char> small(100000);
  EXPECT_GE(outer.live_bytes(), 100000);
  {
    HeapScope inner;  // no limit of its own: the outer one still holds
    EXPECT_THROW(std::vector<char>(2 << 20), std::bad_alloc);
    EXPECT_TRUE(outer.exceeded());
    EXPECT_FALSE(inner.exceeded());
  }
  std::vector<char> fits(500000);  // still within 1 MiB with `small`
  EXPECT_GE(outer.peak_bytes(), 600000u);
}

// ---- Logs -------------------------------------------------------------------------------

TEST(RequestLog, EscapesControlCharactersAndCapsValues) {
  EXPECT_EQ(EscapeForLog("ok id-1", 100), "ok id-1");
  EXPECT_EQ(EscapeForLog("a\nchasles-server: plan request=forged\x1b[31mred", 100),
            "a\\nchasles-server: plan request=forged\\x1b[31mred");
  EXPECT_EQ(EscapeForLog(std::string("nul\0cut", 7), 100), "nul\\x00cut");
  EXPECT_EQ(EscapeForLog("q\"b\\", 100), "q\\\"b\\\\");
  EXPECT_EQ(EscapeForLog(std::string(1000000, 'x'), 16), std::string(16, 'x') + "…(+999984 bytes)");
}

RequestRecord HostileRecord() {
  RequestRecord record;
  record.rpc = "Plan";
  record.request_id = "x\nchasles-server: Plan request=forged status=OK\x1b[2J" + std::string(1 << 20, 'A');
  record.client = "ipv4:127.0.0.1";
  record.outcome = "SUCCESS";
  record.status_code = 3;
  static const char kMessage[] = "planner.planner_id = 'rrt\0x' is unknown";
  record.status_message = std::string(kMessage, sizeof(kMessage) - 1);
  record.stages = {{"plan", 0.0123}};
  record.fields = {{"planner", "a b=c"}};
  return record;
}

TEST(RequestLog, TextLineIsOneCappedLineWithoutControlBytes) {
  const std::string line = FormatLogLine(HostileRecord(), LogFormat::kText, 64);
  EXPECT_EQ(line.find('\n'), std::string::npos);
  EXPECT_EQ(line.find('\x1b'), std::string::npos);
  EXPECT_EQ(line.find('\0'), std::string::npos);
  EXPECT_LT(line.size(), 1000u);
  EXPECT_NE(line.find("request=\"x\\nchasles-server: Plan request=forged status=OK\\x1b[2JAAAA"), std::string::npos)
      << line;
  EXPECT_NE(line.find("planner=\"a b=c\""), std::string::npos) << line;
  EXPECT_NE(line.find("status=INVALID_ARGUMENT"), std::string::npos) << line;
  EXPECT_NE(line.find("'rrt\\x00x' is unknown"), std::string::npos) << line;
  EXPECT_NE(line.find("…(+"), std::string::npos) << line;
}

TEST(RequestLog, JsonLineParsesAsOneObjectWithEveryField) {
  const std::string line = FormatLogLine(HostileRecord(), LogFormat::kJson, 64);
  EXPECT_EQ(line.find('\n'), std::string::npos);
  // An independent JSON parser (protobuf's, into google.protobuf.Struct) reads it back.
  google::protobuf::Struct parsed;
  const auto status = google::protobuf::util::JsonStringToMessage(line, &parsed);
  ASSERT_TRUE(status.ok()) << status.ToString() << "\n" << line;
  const auto& f = parsed.fields();
  EXPECT_EQ(f.at("rpc").string_value(), "Plan");
  EXPECT_EQ(f.at("status").string_value(), "INVALID_ARGUMENT");
  EXPECT_EQ(f.at("outcome").string_value(), "SUCCESS");
  EXPECT_EQ(f.at("client").string_value(), "ipv4:127.0.0.1");
  EXPECT_EQ(f.at("request_id").string_value().substr(0, 20), "x\nchasles-server: Pl");
  EXPECT_LT(f.at("request_id").string_value().size(), 200u);
  EXPECT_EQ(f.at("message").string_value(), HostileRecord().status_message);
  EXPECT_NEAR(f.at("stages_ms").struct_value().fields().at("plan").number_value(), 12.3, 1e-9);
  EXPECT_EQ(f.at("fields").struct_value().fields().at("planner").string_value(), "a b=c");
  EXPECT_TRUE(f.count("time") && f.count("queue_ms") && f.count("total_ms") && f.count("peak_heap_bytes"));
}

// ---- End to end: caps before the work, malformed messages, budgets ------------------------

class HardeningTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    ServerOptions options = LoopbackServer::QuietOptions(2);
    options.max_budget = 120;
    server_ = new LoopbackServer(options);
  }
  static void TearDownTestSuite() {
    delete server_;
    server_ = nullptr;
  }
  /// The server still plans the example at once.
  static void ExpectStillServing() {
    v1::PlanResponse response;
    const grpc::Status status = server_->Plan(LoadRequest("panda_table"), &response);
    ASSERT_TRUE(status.ok()) << status.error_message();
    EXPECT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  }
  static inline LoopbackServer* server_ = nullptr;
};

/// Resident set size of this process [bytes] (the server runs in it).
std::size_t ResidentBytes() {
  std::ifstream statm("/proc/self/statm");
  std::size_t pages = 0, resident = 0;
  statm >> pages >> resident;
  return resident * static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
}

TEST_F(HardeningTest, AHugeSampleCountIsRefusedBeforeSampling) {
  // The 200-byte request that took 4.4 GB: slow joints, a 0.1 ms sample period.
  v1::PlanRequest request = LoadRequest("panda_table");
  for (int i = 0; i < 7; ++i) request.mutable_trajectory()->add_max_velocity(0.002);
  request.mutable_trajectory()->set_sample_period(1e-4);
  const std::size_t before = ResidentBytes();
  v1::PlanResponse response;
  const grpc::Status status = server_->Plan(request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << status.error_message();
  const std::string& message = status.error_message();
  EXPECT_NE(message.find("trajectory.sample_period = 0.0001 s over the "), std::string::npos) << message;
  EXPECT_NE(message.find("samples (~"), std::string::npos) << message;
  EXPECT_NE(message.find("more than the server's cap of 1000000 samples (--max-samples); use a "
                         "trajectory.sample_period of at least "),
            std::string::npos)
      << message;
  // The refusal came before any sample was made: RSS grew by far less than the reply would be.
  EXPECT_LT(ResidentBytes(), before + (256u << 20));
  ExpectStillServing();
}

TEST_F(HardeningTest, TheSuggestedSamplePeriodIsAccepted) {
  v1::PlanRequest request = LoadRequest("panda_table");
  // Fewer samples than --max-samples, but more bytes than a reply may carry.
  for (int i = 0; i < 7; ++i) request.mutable_trajectory()->add_max_velocity(0.02);
  request.mutable_trajectory()->set_sample_period(1e-4);
  v1::PlanResponse response;
  grpc::Status status = server_->Plan(request, &response);
  ASSERT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << status.error_message();
  EXPECT_NE(status.error_message().find("more than the server's reply cap of 63 MiB (--max-message-mb 64 less 1 MiB)"),
            std::string::npos)
      << status.error_message();
  const std::string key = "trajectory.sample_period of at least ";
  const std::size_t at = status.error_message().find(key);
  ASSERT_NE(at, std::string::npos) << status.error_message();
  const double suggested = std::stod(status.error_message().substr(at + key.size()));
  request.mutable_trajectory()->set_sample_period(std::min(1.0, suggested * 1.001));
  status = server_->Plan(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  EXPECT_LE(response.trajectory().points_size(), 1000000);
}

TEST_F(HardeningTest, MalformedMessagesGetInvalidArgumentWithAReason) {
  grpc::GenericStub generic(server_->channel());
  const std::string garbage = "\xff\xff\xff\xff\x0f not a protobuf";
  grpc::Slice slice(garbage);
  const grpc::ByteBuffer request(&slice, 1);
  for (const char* method : {"/chasles.v1.Planning/Plan", "/chasles.v1.Planning/UploadRobot",
                             "/chasles.v1.Planning/CommitTrajectory", "/chasles.v1.Planning/ListPlanners"}) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
    std::promise<grpc::Status> done;
    grpc::ByteBuffer reply;
    generic.UnaryCall(&context, method, grpc::StubOptions(), &request, &reply,
                      [&done](grpc::Status status) { done.set_value(status); });
    const grpc::Status status = done.get_future().get();
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << method;
    EXPECT_NE(status.error_message().find("is not a valid chasles.v1."), std::string::npos)
        << method << ": " << status.error_message();
    EXPECT_NE(status.error_message().find("bytes that do not parse as protobuf wire format"), std::string::npos)
        << status.error_message();
  }
  ExpectStillServing();
}

TEST_F(HardeningTest, BudgetsAboveTheServersMaximumAreRefusedByName) {
  v1::PlanRequest request = LoadRequest("panda_table");
  request.set_time_budget(300);
  v1::PlanResponse response;
  grpc::Status status = server_->Plan(request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(status.error_message(),
            "time_budget = 300 s exceeds this server's maximum budget of 120 s (--max-budget); ask for less, or run "
            "a server with a larger --max-budget");
  request.set_time_budget(1);
  request.mutable_trajectory()->set_post_processing(v1::TrajectoryOptions::COLLOCATION);
  request.mutable_trajectory()->mutable_collocation()->set_time_budget(500);
  status = server_->Plan(request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("trajectory post-processing time_budget = 500 s exceeds"), std::string::npos)
      << status.error_message();
}

/// A binary STL of `triangles` facets (a fan of thin slivers), as bytes.
std::string BinaryStl(int triangles) {
  std::string bytes(80, ' ');
  auto put_u32 = [&bytes](std::uint32_t v) { bytes.append(reinterpret_cast<const char*>(&v), 4); };
  auto put_f32 = [&bytes](float v) { bytes.append(reinterpret_cast<const char*>(&v), 4); };
  put_u32(static_cast<std::uint32_t>(triangles));
  for (int k = 0; k < triangles; ++k) {
    const float a = 1e-5f * static_cast<float>(k);
    for (float v : {0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f + a, 0.f, 0.f, 1.f + a, 1.f, 0.f}) put_f32(v);
    bytes.append(2, '\0');
  }
  return bytes;
}

TEST(SceneCap, ASceneBeyondItIsRefusedByNameAndAScatteredOneUnderItPlans) {
  ServerOptions options = LoopbackServer::QuietOptions(2);
  options.limits.max_scene_objects = 20000;
  options.request_memory_mb = 256;
  LoopbackServer server(options);
  // 20,000 5 cm boxes in a ring 1.6–3 m from the arm: within both caps, so it plans.
  v1::PlanRequest request = LoadRequest("panda_table");
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int i = request.scene().boxes_size(); i < 20000; ++i) {
    v1::Box* box = request.mutable_scene()->add_boxes();
    const double r = 1.6 + 1.4 * unit(rng), a = 6.283185307179586 * unit(rng);
    box->mutable_pose()->mutable_position()->set_x(r * std::cos(a));
    box->mutable_pose()->mutable_position()->set_y(r * std::sin(a));
    box->mutable_pose()->mutable_position()->set_z(2.0 * unit(rng));
    box->mutable_pose()->mutable_orientation()->set_w(1.0);
    box->mutable_size()->set_x(0.05);
    box->mutable_size()->set_y(0.05);
    box->mutable_size()->set_z(0.05);
  }
  v1::PlanResponse response;
  grpc::Status status = server.Plan(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  // One more object: refused before anything is built, naming the count and the cap.
  request.mutable_scene()->add_spheres()->set_radius(0.05);
  status = server.Plan(request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << status.error_message();
  EXPECT_NE(status.error_message().find("scene holds 20001 objects (20000 boxes, 1 spheres,"), std::string::npos)
      << status.error_message();
  EXPECT_NE(status.error_message().find("more than the cap of 20000 (InputLimits::max_scene_objects, "
                                        "--max-scene-objects)"),
            std::string::npos)
      << status.error_message();
  const grpc::Status after = server.Plan(LoadRequest("panda_table"), &response);
  ASSERT_TRUE(after.ok()) << after.error_message();
  EXPECT_EQ(response.outcome(), v1::SUCCESS) << response.message();
}

TEST(MemoryCap, ARequestBeyondItIsAbandonedAndTheServerServesOn) {
  ServerOptions options = LoopbackServer::QuietOptions(2);
  options.request_memory_mb = 64;
  LoopbackServer server(options);
  // ~600k triangles: assimp and the FCL mesh need far more than the 64 MiB cap of this server.
  v1::UploadSceneRequest request;
  v1::Mesh* mesh = request.mutable_scene()->add_meshes();
  mesh->set_name("huge");
  mesh->set_data(BinaryStl(600000));
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(120));
  v1::UploadSceneResponse response;
  const grpc::Status status = server.stub().UploadScene(&context, request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << status.error_message();
  EXPECT_EQ(status.error_message(),
            "the request needed more than this server's per-request memory cap of 64 MiB (--request-memory-mb) and "
            "was abandoned; use a smaller input, budget or planner graph (e.g. max_nodes), or a larger sample_period");
  v1::PlanResponse plan;
  const grpc::Status after = server.Plan(LoadRequest("panda_table"), &plan);
  ASSERT_TRUE(after.ok()) << after.error_message();
  EXPECT_EQ(plan.outcome(), v1::SUCCESS) << plan.message();
}

}  // namespace
}  // namespace chasles
