// chasles-bench --section fairness|memory: how a server shares its workers between clients, and
// how much memory hostile-sized requests leave behind. Medians over repeats, each beside a
// baseline measured in the same run.
#include "bench_hardening.h"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <future>
#include <memory>
#include <string>
#include <utility>
#include <thread>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "chasles/server/planning_server.h"
#include "chasles/v1/chasles.grpc.pb.h"

namespace chasles {
namespace {

using Clock = std::chrono::steady_clock;

double Median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

double SecondsSince(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

/// A Plan on the default robot and table: a short free motion.
v1::PlanRequest TablePlan(const std::string& planner, double budget) {
  v1::PlanRequest request;
  for (double v : {0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785}) request.mutable_start()->add_positions(v);
  for (double v : {0.3, -0.6, 0.1, -2.2, 0.1, 1.7, 0.9}) request.mutable_goal()->add_positions(v);
  request.mutable_planner()->set_planner_id(planner);
  request.set_time_budget(budget);
  return request;
}

struct Loopback {
  explicit Loopback(ServerOptions options) {
    options.listen = "127.0.0.1:0";
    options.log_requests = false;
    server = std::make_unique<PlanningServer>(options);
    address = "127.0.0.1:" + std::to_string(server->port());
  }
  /// A new connection: the server tells unauthenticated clients apart by their peer.
  std::unique_ptr<v1::Planning::Stub> Connect(int max_receive_mb = 64) const {
    grpc::ChannelArguments arguments;
    arguments.SetMaxReceiveMessageSize(max_receive_mb << 20);
    arguments.SetInt("grpc.use_local_subchannel_pool", 1);  // a connection of its own
    return v1::Planning::NewStub(grpc::CreateCustomChannel(address, grpc::InsecureChannelCredentials(), arguments));
  }
  std::unique_ptr<PlanningServer> server;
  std::string address;
};

/// Seconds until a short plan is answered, sent while `long_calls` long rrt_star plans of another
/// client run or wait; the long plans are cancelled once it is answered.
double ShortPlanLatency(const Loopback& server, int long_calls, double long_budget) {
  auto long_client = server.Connect();
  std::vector<std::unique_ptr<grpc::ClientContext>> contexts;
  std::vector<std::future<void>> running;
  for (int k = 0; k < long_calls; ++k) {
    contexts.push_back(std::make_unique<grpc::ClientContext>());
    grpc::ClientContext* context = contexts.back().get();
    running.push_back(std::async(std::launch::async, [&long_client, context, long_budget] {
      v1::PlanResponse response;
      long_client->Plan(context, TablePlan("rrt_star", long_budget), &response);
    }));
  }
  if (long_calls > 0) std::this_thread::sleep_for(std::chrono::milliseconds(300));  // they hold their workers
  auto short_client = server.Connect();
  grpc::ClientContext context;
  v1::PlanResponse response;
  const auto start = Clock::now();
  const grpc::Status status = short_client->Plan(&context, TablePlan("rrt_connect", 1.0), &response);
  const double latency = SecondsSince(start);
  if (!status.ok() || response.outcome() != v1::SUCCESS) {
    std::fprintf(stderr, "fairness: the short plan failed: %s %s\n", status.error_message().c_str(),
                 response.message().c_str());
  }
  for (auto& c : contexts) c->TryCancel();
  for (auto& r : running) r.wait();
  return latency;
}


/// A binary STL of `triangles` distinct slivers (content differs by `salt`).
std::string BinaryStl(int triangles, int salt) {
  std::string bytes(80, ' ');
  std::memcpy(bytes.data(), &salt, sizeof(salt));
  auto put = [&bytes](const void* p, std::size_t n) { bytes.append(static_cast<const char*>(p), n); };
  const std::uint32_t count = static_cast<std::uint32_t>(triangles);
  put(&count, 4);
  for (int k = 0; k < triangles; ++k) {
    const float a = 1e-5f * static_cast<float>(k) + 1e-3f * static_cast<float>(salt);
    const float v[12] = {0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f + a, 0.f, 0.f, 1.f + a, 1.f, 0.f};
    put(v, sizeof(v));
    bytes.append(2, '\0');
  }
  return bytes;
}

/// A chasles-server process started with `flags` on a free loopback port; its RSS is the
/// server's alone (the client's buffers are in this process).
class ServerProcess {
 public:
  explicit ServerProcess(const std::vector<std::string>& flags) {
    char self[4096] = {0};
    const ssize_t n = readlink("/proc/self/exe", self, sizeof(self) - 1);
    std::string binary = std::string(self, n > 0 ? static_cast<std::size_t>(n) : 0);
    binary = binary.substr(0, binary.rfind('/') + 1) + "chasles-server";
    char log_name[] = "/tmp/chasles-bench-server-XXXXXX";
    const int log = mkstemp(log_name);
    log_ = log_name;
    pid_ = fork();
    if (pid_ == 0) {
      dup2(log, 2);
      std::vector<std::string> args = {binary, "--listen", "127.0.0.1:0", "--threads", "2"};
      args.insert(args.end(), flags.begin(), flags.end());
      std::vector<char*> argv;
      for (auto& a : args) argv.push_back(a.data());
      argv.push_back(nullptr);
      execv(binary.c_str(), argv.data());
      _exit(127);
    }
    close(log);
    for (int k = 0; k < 600 && port_ == 0; ++k) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      std::ifstream in(log_);
      const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      const std::size_t at = text.find("(port ");
      if (at != std::string::npos) port_ = std::atoi(text.c_str() + at + 6);
    }
  }
  ~ServerProcess() {
    kill(pid_, SIGTERM);
    waitpid(pid_, nullptr, 0);
    std::remove(log_.c_str());
  }
  std::unique_ptr<v1::Planning::Stub> Connect() const {
    grpc::ChannelArguments arguments;
    arguments.SetMaxReceiveMessageSize(64 << 20);
    return v1::Planning::NewStub(grpc::CreateCustomChannel("127.0.0.1:" + std::to_string(port_),
                                                           grpc::InsecureChannelCredentials(), arguments));
  }
  /// The server's resident set size [MiB].
  double ResidentMiB() const {
    std::ifstream statm("/proc/" + std::to_string(pid_) + "/statm");
    double pages = 0, resident = 0;
    statm >> pages >> resident;
    return resident * static_cast<double>(sysconf(_SC_PAGESIZE)) / 1048576.0;
  }
  bool ok() const { return port_ != 0; }

 private:
  pid_t pid_ = -1;
  int port_ = 0;
  std::string log_;
};

/// The server's RSS growth [MiB] over `uploads` distinct 50 MB STL uploads with `--cache-mb`.
double UploadGrowth(int uploads, const std::string& cache_mb) {
  ServerProcess server({"--quiet", "--cache-mb", cache_mb});
  if (!server.ok()) return -1.0;
  auto client = server.Connect();
  const double before = server.ResidentMiB();
  for (int k = 0; k < uploads; ++k) {
    v1::UploadSceneRequest request;
    v1::Mesh* mesh = request.mutable_scene()->add_meshes();
    mesh->set_name("part");
    mesh->set_data(BinaryStl(1000000, k));
    grpc::ClientContext context;
    v1::UploadSceneResponse response;
    const grpc::Status status = client->UploadScene(&context, request, &response);
    if (!status.ok()) std::fprintf(stderr, "memory: upload %d: %s\n", k, status.error_message().c_str());
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // the last call's OnDone has run
  return server.ResidentMiB() - before;
}

}  // namespace

void BenchFairness(int repeats, double long_budget) {
  std::printf("\n== fairness: a 1 s rrt_connect plan sent while two %.0f s rrt_star plans of another client run; "
              "2 workers; %d repeats ==\n",
              long_budget, repeats);
  ServerOptions fair;
  fair.threads = 2;
  ServerOptions unshared = fair;
  unshared.long_share = 1.0;  // long calls may hold every worker: the FIFO pool of before
  Loopback fair_server(fair), unshared_server(unshared);
  std::vector<double> alone, behind_fair, behind_unshared;
  for (int r = 0; r < repeats; ++r) {  // alternating, so drift hits every row alike
    alone.push_back(ShortPlanLatency(fair_server, 0, long_budget));
    behind_fair.push_back(ShortPlanLatency(fair_server, 2, long_budget));
  }
  // The unshared pool: the short plan waits until a long one ends (cancelled after 1 repeat).
  behind_unshared.push_back(ShortPlanLatency(unshared_server, 2, std::min(long_budget, 20.0)));
  const double base = Median(alone);
  std::printf("%-58s %10s %8s\n", "short plan answered after", "median s", "ratio");
  std::printf("%-58s %10.3f %8.2f\n", "alone (baseline)", base, 1.0);
  std::printf("%-58s %10.3f %8.2f\n", "behind 2 long plans, --long-share 0.5 (default)", Median(behind_fair),
              Median(behind_fair) / base);
  std::printf("%-58s %10.3f %8.2f\n", "behind 2 long plans, --long-share 1 (no cap, 1 run)", Median(behind_unshared),
              Median(behind_unshared) / base);
  std::fflush(stdout);
}

void BenchMemory(int uploads) {
  std::printf("\n== memory: RSS of a chasles-server process (MiB), measured from /proc/PID/statm ==\n");
  const double unbounded = UploadGrowth(uploads, "1048576");
  const double bounded = UploadGrowth(uploads, "256");
  std::printf("%-72s %10s\n", ("RSS growth over " + std::to_string(uploads) + " distinct 50 MB STL uploads").c_str(), "MiB");
  std::printf("%-72s %10.0f\n", "  --cache-mb 1048576 (no bound in practice, as the entry-count cache was)", unbounded);
  std::printf("%-72s %10.0f  (ratio %.2f)\n", "  --cache-mb 256 (default)", bounded, bounded / unbounded);

  ServerProcess server({"--quiet"});
  auto client = server.Connect();
  {
    grpc::ClientContext context;
    v1::PlanResponse response;
    client->Plan(&context, TablePlan("rrt_connect", 1.0), &response);  // libraries and pools loaded
  }
  // A large reply: a slow trajectory sampled finely (under the reply cap), three times.
  for (int k = 0; k < 3; ++k) {
    v1::PlanRequest request = TablePlan("rrt_connect", 1.0);
    request.set_seed(k + 1);
    for (int i = 0; i < 7; ++i) request.mutable_trajectory()->add_max_velocity(0.05);
    request.mutable_trajectory()->set_sample_period(1e-4);
    const double before = server.ResidentMiB();
    grpc::Status status;
    std::size_t bytes = 0;
    {
      grpc::ClientContext context;
      v1::PlanResponse response;
      status = client->Plan(&context, request, &response);
      bytes = response.ByteSizeLong();
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    const double after = server.ResidentMiB();
    std::printf("%-72s %10.0f  (%s, %zu MB reply; before %.0f, %+.1f %%)\n", "after a large-reply plan", after,
                status.ok() ? "OK" : status.error_message().c_str(), bytes >> 20, before,
                100.0 * (after - before) / before);
  }
  // The 200-byte request that took 4.4 GB before: refused before any sampling.
  {
    v1::PlanRequest request = TablePlan("rrt_connect", 1.0);
    for (int i = 0; i < 7; ++i) request.mutable_trajectory()->add_max_velocity(0.002);
    request.mutable_trajectory()->set_sample_period(1e-4);
    const double before = server.ResidentMiB();
    grpc::ClientContext context;
    v1::PlanResponse response;
    const auto start = Clock::now();
    const grpc::Status status = client->Plan(&context, request, &response);
    std::printf("%-72s %10.0f  (code %d in %.3f s; before %.0f)\n", "after the 0.002 rad/s, 1e-4 s sample request",
                server.ResidentMiB(), static_cast<int>(status.error_code()), SecondsSince(start), before);
  }
  std::fflush(stdout);
}

}  // namespace chasles
