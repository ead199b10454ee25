// `chasles-bench --section viewer` (issue 19). The long trajectory is panda_shelf.json's plan
// timed at a tenth of the Panda's velocity limits with 1 ms samples (~10 s, ~10^4 samples); the
// short one the same plan at full speed and 10 ms. Each page is written (server/ view_page.h, as
// `chasles view` writes it) and opened `runs` times in headless Chromium with software WebGL; the
// figure is the median of the page's own load_ms.

#include "bench_viewer.h"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <google/protobuf/util/json_util.h>

#include "bench_pipeline.h"  // ReadFile, QuantileOrNan, StartBenchServer
#include "chasles/server/view_page.h"

namespace chasles {

void BenchViewer(const ViewerBenchOptions& options) {
  v1::PlanRequest base;
  const std::string path = options.examples_dir + "/requests/panda_shelf.json";
  if (!google::protobuf::util::JsonStringToMessage(ReadFile(path), &base).ok()) throw std::runtime_error(path);
  BenchServer server = StartBenchServer();
  ModelStore store(DefaultRobotProto(), DefaultSceneProto());
  std::printf("## Viewer page load (issue 19)\n\n");
  std::printf("panda_shelf.json's plan as a page (`chasles view`), opened %d times in headless Chromium "
              "(%s, SwiftShader WebGL, real time: no virtual time budget); load = the page's own load_ms "
              "(performance.now() from navigation start to every robot, plot and the first frame drawn), median.\n\n",
              options.runs, options.chromium.c_str());
  std::printf("| trajectory | samples | page [MB] | write [ms] | load median [ms] | load max [ms] |\n|---|---|---|---|---|---|\n");
  struct Case {
    const char* name;
    double speed;   // fraction of the velocity limits
    double period;  // [s]
  };
  for (const Case& c : {Case{"1.6 s at 10 ms", 1.0, 0.01}, Case{"~10 s at 1 ms (a tenth of the speed)", 0.1, 0.001}}) {
    v1::PlanRequest request = base;
    request.mutable_trajectory()->set_sample_period(c.period);
    const Eigen::VectorXd limits = store.default_robot().model->velocity_limits();
    for (int i = 0; i < limits.size(); ++i) request.mutable_trajectory()->add_max_velocity(c.speed * limits[i]);
    v1::PlanResponse response;
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
    if (!server.stub->Plan(&context, request, &response).ok() || response.outcome() != v1::SUCCESS) {
      std::printf("| %s | plan failed: %s | | | | |\n", c.name, response.message().c_str());
      continue;
    }
    const auto start = std::chrono::steady_clock::now();
    const std::string page = ViewPageHtml(ViewDataJson(ViewOfPlan(store, request, response)));
    const double write_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    const std::string file = "/tmp/chasles_bench_viewer.html";
    std::ofstream(file) << page;
    std::vector<double> loads;
    for (int r = 0; r < options.runs; ++r) {
      const std::string dom = "/tmp/chasles_bench_viewer_dom.txt";
      const std::string command = "timeout 120 " + options.chromium +
                                  " --no-sandbox --headless --use-angle=swiftshader --enable-unsafe-swiftshader "
                                  "--dump-dom file://" + file + " > " + dom + " 2>/dev/null";
      if (std::system(command.c_str()) != 0) continue;
      const std::string text = ReadFile(dom);
      const std::size_t at = text.find("load_ms");
      if (at == std::string::npos) continue;
      loads.push_back(std::atof(text.c_str() + text.find(':', at) + 1));
    }
    std::printf("| %s | %d | %.2f | %.1f | %.0f | %.0f |\n", c.name, response.trajectory().points_size(),
                static_cast<double>(page.size()) / (1 << 20), write_ms, QuantileOrNan(loads, 0.5), QuantileOrNan(loads, 1.0));
    std::fflush(stdout);
  }
  std::printf("\n");
}

}  // namespace chasles
