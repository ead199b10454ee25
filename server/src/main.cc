// chasles-server: the Chasles motion planning gRPC server.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <csignal>
#include <cstdio>
#include <exception>
#include <stdexcept>
#include <string>
#include <thread>

#include <CLI/CLI.hpp>

#include "chasles/server/planning_server.h"
#include "chasles/server/security.h"

namespace {

std::atomic<int> g_signal{0};

extern "C" void OnSignal(int signal) { g_signal.store(signal); }

/// Every flag, with its default shown by --help. Values are checked by ServerOptions::Validate
/// (messages name the flag, the value and the rule).
void AddFlags(CLI::App& app, chasles::ServerOptions& o, std::size_t& document_mb) {
  app.add_option("--listen", o.listen, "address:port to listen on (port 0 = any free port)")->capture_default_str();
  app.add_option("--shutdown-grace", o.shutdown_grace,
                 "on SIGTERM/SIGINT: seconds the calls in flight may take to finish while health says NOT_SERVING "
                 "and new calls are refused with UNAVAILABLE")
      ->capture_default_str();
  app.add_option("--store", o.store,
                 "where robots, scenes, workcells and reservations live: memory, or redis://HOST[:PORT][/DB] "
                 "shared by every replica pointed at it")
      ->capture_default_str();
  app.add_option("--threads", o.threads, "planning worker threads (0 = hardware threads)")->capture_default_str();
  app.add_option("--max-message-mb", o.max_message_mb, "largest request/response message [MiB], in [1, 2047]")
      ->capture_default_str();

  auto* caps = "Caps (checked before the work they drive)";
  app.add_option("--cache-mb", o.cache_mb, "uploaded robots, scenes and checkers kept, together [MiB]")
      ->capture_default_str()->group(caps);
  app.add_option("--max-samples", o.max_samples,
                 "trajectory samples in one reply (per robot) and points in one committed trajectory; the count "
                 "is estimated from the duration before sampling")
      ->capture_default_str()->group(caps);
  app.add_option("--max-team-robots", o.max_team_robots, "robots of one Coordinate request")
      ->capture_default_str()->group(caps);
  app.add_option("--request-memory-mb", o.request_memory_mb,
                 "heap one call may hold [MiB]; beyond it the call is abandoned with RESOURCE_EXHAUSTED (0 = no cap)")
      ->capture_default_str()->group(caps);
  app.add_option("--max-document-mb", document_mb, "one URDF/SRDF, robot description, mesh or OctoMap document [MiB]")
      ->capture_default_str()->group(caps);
  app.add_option("--max-xml-depth", o.limits.max_xml_depth, "element nesting depth of URDF/SRDF")
      ->capture_default_str()->group(caps);
  app.add_option("--max-links", o.limits.max_links, "links of one robot")->capture_default_str()->group(caps);
  app.add_option("--max-dofs", o.limits.max_dofs, "degrees of freedom of one robot")->capture_default_str()->group(caps);
  app.add_option("--max-mesh-triangles", o.limits.max_mesh_triangles, "triangles of one mesh")
      ->capture_default_str()->group(caps);
  app.add_option("--max-octomap-nodes", o.limits.max_octomap_nodes, "nodes of one OctoMap")
      ->capture_default_str()->group(caps);
  app.add_option("--max-cloud-points", o.limits.max_cloud_points, "points of one UpdateScene point cloud")
      ->capture_default_str()->group(caps);
  app.add_option("--max-scene-objects", o.limits.max_scene_objects,
                 "objects of one scene: primitives, meshes and OctoMaps together")
      ->capture_default_str()->group(caps);

  auto* fair = "Fairness (per-client queues served round-robin)";
  app.add_option("--max-budget", o.max_budget, "largest time budget a call may ask for [s], in (0, 600]")
      ->capture_default_str()->group(fair);
  app.add_option("--long-budget", o.long_budget, "a call whose budget exceeds this [s] is long")
      ->capture_default_str()->group(fair);
  app.add_option("--long-share", o.long_share,
                 "share of the workers long calls may hold at once, in (0, 1]; with 2+ workers at least one stays "
                 "free for short calls while the share is below 1")
      ->capture_default_str()->group(fair);
  app.add_option("--max-queued", o.max_queued, "calls waiting for a worker, all clients together")
      ->capture_default_str()->group(fair);
  app.add_option("--max-queued-per-client", o.max_queued_per_client, "calls of one client waiting for a worker")
      ->capture_default_str()->group(fair);

  auto* security = "Security";
  app.add_option("--tls-cert", o.security.tls_cert, "server certificate chain (PEM); enables TLS")->group(security);
  app.add_option("--tls-key", o.security.tls_key, "the certificate's private key (PEM, unencrypted)")->group(security);
  app.add_option("--tls-client-ca", o.security.tls_client_ca,
                 "CA certificates (PEM) that client certificates must chain to (mutual TLS)")
      ->group(security);
  app.add_option("--tokens", o.security.tokens_file,
                 "bearer tokens, one 'NAME ROLE TOKEN' per line (ROLE: plan or commit); without TLS only loopback "
                 "peers may use them")
      ->group(security);

  auto* ops = "Logs and metrics";
  app.add_option("--log-format", o.log_format, "request log on stderr: text (key=value) or json (one object per call)")
      ->capture_default_str()->group(ops);
  app.add_option("--log-field-max", o.log_field_max, "client-supplied log values are cut at this many bytes")
      ->capture_default_str()->group(ops);
  app.add_flag("--quiet", [&o](std::int64_t) { o.log_requests = false; }, "no request log")->group(ops);
  app.add_option("--metrics-listen", o.metrics_listen,
                 "serve Prometheus metrics on http://ADDR/metrics (default: off); a bare PORT means 127.0.0.1:PORT")
      ->group(ops);
  app.add_option("--http-listen", o.http_listen,
                 "serve the 3-D viewer of recent Plan, Optimize and Coordinate requests on http://HOST:PORT/ "
                 "(read-only; with --tokens a plan token, and a loopback address; default: off)")
      ->group(ops);
  app.add_option("--http-recent", o.http_recent, "requests kept for --http-listen (at most 256 MiB of messages)")
      ->capture_default_str()->group(ops);
}

}  // namespace

int main(int argc, char** argv) {
  chasles::ServerOptions options;
  CLI::App app{
      "chasles-server: serves chasles.v1.Planning (Plan, Optimize, InverseKinematics, ListPlanners, UploadRobot,\n"
      "UploadScene, UpdateScene, Coordinate, workcells, Benchmark, StopBenchmark), the standard gRPC health\n"
      "service and server reflection. Requests that name no robot/scene use the embedded Franka Panda and table\n"
      "scene. Planning, benchmark runs and coordination share the worker threads. SIGINT/SIGTERM shut the\n"
      "server down cleanly: health turns NOT_SERVING, new calls are refused, running calls get --shutdown-grace\n"
      "to finish.",
      "chasles-server"};
  std::size_t document_mb = options.limits.max_document_bytes >> 20;
  AddFlags(app, options, document_mb);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  options.limits.max_document_bytes = document_mb << 20;

  try {
    if (options.security.tokens() && !options.security.tls() && !chasles::IsLoopbackAddress(options.listen)) {
      throw std::invalid_argument("--tokens without --tls-cert sends tokens in plaintext, accepted from loopback peers "
                                  "only, but --listen " + options.listen +
                                  " is not a loopback address: add --tls-cert and --tls-key, or listen on 127.0.0.1");
    }
    chasles::PlanningServer server(options);
    const unsigned threads =
        options.threads > 0 ? static_cast<unsigned>(options.threads) : std::max(1u, std::thread::hardware_concurrency());
    std::fprintf(stderr, "chasles-server: security: %s\n", server.security_description().c_str());
    if (server.http_port() != 0) {
      std::fprintf(stderr, "chasles-server: viewer of recent requests on http://%s (port %d)/\n",
                   options.http_listen.c_str(), server.http_port());
    }
    if (server.metrics_port() != 0) {
      std::fprintf(stderr, "chasles-server: metrics on %s (port %d) at /metrics\n", options.metrics_listen.c_str(),
                   server.metrics_port());
    }
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
      server.Shutdown(std::chrono::milliseconds(static_cast<long long>(options.shutdown_grace * 1e3)));
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
