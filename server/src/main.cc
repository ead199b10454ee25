// chasles-server: the Chasles motion planning gRPC server.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <stdexcept>
#include <string>
#include <thread>

#include "chasles/server/planning_server.h"

namespace {

std::atomic<int> g_signal{0};

extern "C" void OnSignal(int signal) { g_signal.store(signal); }

void PrintUsage(std::FILE* out) {
  std::fprintf(out,
               "Usage: chasles-server [--listen ADDR] [--threads N] [--max-message-mb MB]\n"
               "\n"
               "Serves chasles.v1.Planning (Plan, Optimize, InverseKinematics, ListPlanners, UploadRobot,\n"
               "UploadScene, UpdateScene, Coordinate, workcells, Benchmark, StopBenchmark) and the standard\n"
               "gRPC health service. Requests that name no robot/scene use the embedded Franka Panda and\n"
               "table scene. Planning, benchmark runs and coordination share the N worker threads.\n"
               "\n"
               "  --listen ADDR         address:port to listen on (default 127.0.0.1:50051; port 0 = any)\n"
               "  --threads N           planning worker threads (default: hardware threads)\n"
               "  --max-message-mb MB   largest request/response message in MiB (default 64)\n"
               "  --tls-cert FILE       serve TLS with this certificate chain (PEM); needs --tls-key\n"
               "  --tls-key FILE        the certificate's private key (PEM, unencrypted)\n"
               "  --tls-client-ca FILE  mutual TLS: require client certificates signed by this CA (PEM)\n"
               "  --tokens FILE         require bearer tokens: lines 'NAME ROLE TOKEN', ROLE 'plan' (planning,\n"
               "                        uploads, benchmarks) or 'commit' (also CreateWorkcell, CommitTrajectory,\n"
               "                        Release); '#' comments. Health checks need none. Without TLS, tokens\n"
               "                        are accepted from loopback peers only (see README, Security)\n"
               "  --help                show this help\n"
               "\n"
               "SIGINT/SIGTERM shut the server down cleanly (running calls get 2 s to finish).\n");
}

bool ParseInt(const char* text, int* value) {
  char* end = nullptr;
  const long parsed = std::strtol(text, &end, 10);
  if (end == text || *end != '\0' || parsed < -1000000 || parsed > 1000000) return false;
  *value = static_cast<int>(parsed);
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  chasles::ServerOptions options;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto next = [&](const char* name) -> const char* {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "chasles-server: %s needs a value (see --help)\n", name);
        std::exit(2);
      }
      return argv[++i];
    };
    if (arg == "--help" || arg == "-h") {
      PrintUsage(stdout);
      return 0;
    } else if (arg == "--listen") {
      options.listen = next("--listen");
    } else if (arg == "--threads") {
      const char* value = next("--threads");
      if (!ParseInt(value, &options.threads)) {
        std::fprintf(stderr, "chasles-server: --threads '%s' is not an integer\n", value);
        return 2;
      }
    } else if (arg == "--max-message-mb") {
      const char* value = next("--max-message-mb");
      if (!ParseInt(value, &options.max_message_mb)) {
        std::fprintf(stderr, "chasles-server: --max-message-mb '%s' is not an integer\n", value);
        return 2;
      }
    } else if (arg == "--tls-cert") {
      options.security.tls_cert = next("--tls-cert");
    } else if (arg == "--tls-key") {
      options.security.tls_key = next("--tls-key");
    } else if (arg == "--tls-client-ca") {
      options.security.tls_client_ca = next("--tls-client-ca");
    } else if (arg == "--tokens") {
      options.security.tokens_file = next("--tokens");
    } else {
      std::fprintf(stderr, "chasles-server: unknown argument '%s' (see --help)\n", arg.c_str());
      return 2;
    }
  }

  try {
    if (options.security.tokens() && !options.security.tls() && !chasles::IsLoopbackAddress(options.listen)) {
      throw std::invalid_argument("--tokens without --tls-cert sends tokens in plaintext, accepted from loopback peers "
                                  "only, but --listen " + options.listen +
                                  " is not a loopback address: add --tls-cert and --tls-key, or listen on 127.0.0.1");
    }
    chasles::PlanningServer server(options);
    std::fprintf(stderr, "chasles-server: security: %s\n", chasles::AccessControl(options.security).Describe().c_str());
    const unsigned threads =
        options.threads > 0 ? static_cast<unsigned>(options.threads) : std::max(1u, std::thread::hardware_concurrency());
    std::fprintf(stderr,
                 "chasles-server: listening on %s (port %d), %u planning threads; requests that name no robot or "
                 "scene use the embedded default robot 'panda' (7 DOF) and scene 'table'\n",
                 options.listen.c_str(), server.port(), threads);
    std::signal(SIGINT, OnSignal);
    std::signal(SIGTERM, OnSignal);
    std::atomic<bool> done{false};
    std::thread watcher([&] {
      while (!done.load() && g_signal.load() == 0) std::this_thread::sleep_for(std::chrono::milliseconds(100));
      if (g_signal.load() != 0) {
        std::fprintf(stderr, "chasles-server: signal %d, shutting down\n", g_signal.load());
      }
      server.Shutdown(std::chrono::milliseconds(2000));
    });
    server.Wait();
    done.store(true);
    watcher.join();
    std::fprintf(stderr, "chasles-server: stopped\n");
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "chasles-server: %s\n", e.what());
    return 1;
  }
}
