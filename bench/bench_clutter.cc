// `chasles-bench --section clutter` (issue 24): does a request cost what is near the robot, or
// what the scene holds? The panda_table request, unchanged, in the table scene plus N boxes the
// arm never comes near, then plus N small boxes in its workspace.

#include "bench_clutter.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <google/protobuf/util/json_util.h>
#include <grpcpp/grpcpp.h>

#include "bench_pipeline.h"  // ReadFile, StartBenchServer
#include "chasles/collision/collision_checker.h"
#include "chasles/robot/robot_model.h"
#include "chasles/server/convert.h"
#include "chasles/server/planning_server.h"
#include "chasles/v1/chasles.grpc.pb.h"

namespace chasles {
namespace {

using Clock = std::chrono::steady_clock;

double Median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

void AddBox(v1::Scene* scene, const std::string& name, double size, double x, double y, double z) {
  v1::Box* box = scene->add_boxes();
  box->set_name(name);
  box->mutable_size()->set_x(size);
  box->mutable_size()->set_y(size);
  box->mutable_size()->set_z(size);
  box->mutable_pose()->mutable_position()->set_x(x);
  box->mutable_pose()->mutable_position()->set_y(y);
  box->mutable_pose()->mutable_position()->set_z(z);
}

/// visit(i, x, y, z) for n seeded points on a ring 1.6–3 m from the base, 0–1.5 m high (the
/// same points every run, for boxes and meshes alike).
template <typename Visit>
void ForEachRingPoint(int n, const Visit& visit) {
  std::mt19937_64 rng(24);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < n; ++i) {
    const double angle = 2.0 * M_PI * u(rng), radius = 1.6 + 1.4 * u(rng);
    const double z = 1.5 * u(rng);
    visit(i, radius * std::cos(angle), radius * std::sin(angle), z);
  }
}

/// n 5 cm boxes on a ring 1.6–3 m from the base, 0–1.5 m high (seeded: the same every run).
void AddDistantBoxes(v1::Scene* scene, int n) {
  ForEachRingPoint(n, [&](int i, double x, double y, double z) {
    AddBox(scene, "far" + std::to_string(i), 0.05, x, y, z);
  });
}

/// A 5 cm cube as binary STL bytes (12 triangles).
std::string CubeStl() {
  std::string out(80, ' ');
  const auto put = [&out](const void* p, std::size_t n) { out.append(static_cast<const char*>(p), n); };
  const std::uint32_t count = 12;
  put(&count, 4);
  const int faces[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                            {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  for (const auto& f : faces) {
    const float normal[3] = {0.0f, 0.0f, 0.0f};
    put(normal, sizeof normal);
    for (int v : f) {
      const float x[3] = {v & 1 ? 0.025f : -0.025f, v & 2 ? 0.025f : -0.025f, v & 4 ? 0.025f : -0.025f};
      put(x, sizeof x);
    }
    const std::uint16_t attributes = 0;
    put(&attributes, 2);
  }
  return out;
}

/// n 5 cm mesh cubes on the distant ring (the same seeded placement as AddDistantBoxes).
void AddDistantMeshes(v1::Scene* scene, int n) {
  const std::string stl = CubeStl();
  ForEachRingPoint(n, [&](int i, double x, double y, double z) {
    v1::Mesh* mesh = scene->add_meshes();
    mesh->set_name("farmesh" + std::to_string(i));
    mesh->set_data(stl);
    mesh->mutable_pose()->mutable_position()->set_x(x);
    mesh->mutable_pose()->mutable_position()->set_y(y);
    mesh->mutable_pose()->mutable_position()->set_z(z);
  });
}

/// n 2 cm boxes 0.2–0.8 m from the base, 0.05–1.0 m high, none touching the robot at the
/// request's start or goal (rejection sampling with the real checker).
void AddNearBoxes(v1::Scene* scene, int n, const std::shared_ptr<const RobotModel>& robot,
                  const Eigen::VectorXd& start, const Eigen::VectorXd& goal) {
  std::mt19937_64 rng(25);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int added = 0, tries = 0; added < n && tries < 100 * n; ++tries) {
    const double angle = 2.0 * M_PI * u(rng), radius = 0.2 + 0.6 * u(rng);
    v1::Scene one;
    AddBox(&one, "near" + std::to_string(added), 0.02, radius * std::cos(angle), radius * std::sin(angle),
           0.05 + 0.95 * u(rng));
    const CollisionChecker checker(robot, SceneFromProto(one));
    if (!checker.IsValid(start) || !checker.IsValid(goal)) continue;
    *scene->add_boxes() = one.boxes(0);
    ++added;
  }
}

struct Row {
  int boxes = 0;
  double upload_ms = 0.0;  // UploadScene call (the scene converted and stored)
  double checker_ms = 0.0, checker_scan_ms = 0.0;  // CollisionChecker built with / without broad phase
  int solved = 0, calls = 0;
  std::vector<double> validate, plan, shortcut, verify, quality, total, untimed, call;
};

}  // namespace

void BenchClutter(const ClutterBenchOptions& options) {
  v1::PlanRequest request;
  {
    const std::string path = options.examples_dir + "/requests/panda_table.json";
    const auto parsed = google::protobuf::util::JsonStringToMessage(ReadFile(path), &request);
    if (!parsed.ok()) throw std::runtime_error(path + ": " + parsed.ToString());
  }
  v1::Scene table;
  {
    const std::string path = options.examples_dir + "/scenes/table.json";
    const auto parsed = google::protobuf::util::JsonStringToMessage(ReadFile(path), &table);
    if (!parsed.ok()) throw std::runtime_error(path + ": " + parsed.ToString());
  }
  const auto robot = RobotModel::FromUrdf(ReadFile(options.examples_dir + "/robots/panda.urdf"),
                                          ReadFile(options.examples_dir + "/robots/panda.srdf"));
  Eigen::VectorXd start(request.start().positions_size()), goal(request.goal().positions_size());
  for (int i = 0; i < start.size(); ++i) start[i] = request.start().positions(i);
  for (int i = 0; i < goal.size(); ++i) goal[i] = request.goal().positions(i);

  const BenchServer server = StartBenchServer(256);  // 100,000 boxes are ~10 MB of scene
  v1::Planning::Stub* const stub = server.stub.get();

  const auto run = [&](const v1::Scene& scene, int boxes) {
    Row row;
    row.boxes = boxes;
    grpc::ClientContext upload_context;
    v1::UploadSceneRequest upload;
    *upload.mutable_scene() = scene;
    v1::UploadSceneResponse uploaded;
    const auto t0 = Clock::now();
    const grpc::Status status = stub->UploadScene(&upload_context, upload, &uploaded);
    row.upload_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    if (!status.ok()) throw std::runtime_error("UploadScene: " + status.error_message());
    // The checker the server builds on the first plan, in-process: with the broad phase and
    // without (the difference is the hierarchy's build), best of three.
    const auto scene_model = SceneFromProto(scene);
    for (bool broad : {true, false}) {
      double best = 1e300;
      for (int k = 0; k < 3; ++k) {
        CollisionOptions collision;
        collision.broad_phase = broad;
        const auto t2 = Clock::now();
        const CollisionChecker checker(robot, scene_model, collision);
        best = std::min(best, std::chrono::duration<double, std::milli>(Clock::now() - t2).count());
      }
      (broad ? row.checker_ms : row.checker_scan_ms) = best;
    }
    v1::PlanRequest plan = request;
    plan.set_scene_id(uploaded.scene_id());
    // One call first, not counted: the scene's checker is built on its first plan.
    for (int k = -1; k < options.repeats; ++k) {
      grpc::ClientContext context;
      v1::PlanResponse response;
      const auto t1 = Clock::now();
      const grpc::Status s = stub->Plan(&context, plan, &response);
      const double call_ms = std::chrono::duration<double, std::milli>(Clock::now() - t1).count();
      if (!s.ok()) throw std::runtime_error("Plan: " + s.error_message());
      if (k < 0) continue;
      ++row.calls;
      if (response.outcome() != v1::SUCCESS) continue;
      ++row.solved;
      const v1::StageTimings& t = response.timings();
      row.validate.push_back(1e3 * t.validate());
      row.plan.push_back(1e3 * t.plan());
      row.shortcut.push_back(1e3 * t.shortcut());
      row.verify.push_back(1e3 * t.verify());
      row.total.push_back(1e3 * t.total());
      row.quality.push_back(1e3 * t.quality());
      row.untimed.push_back(1e3 * (t.total() - t.validate() - t.plan() - t.shortcut() - t.parameterize() -
                                   t.optimize() - t.verify() - t.quality() - t.sample()));
      row.call.push_back(call_ms);
    }
    return row;
  };
  const auto print = [](const std::vector<Row>& rows, const char* what) {
    std::printf("| %s | scene upload [ms] | checker build [ms] | of which broad phase [ms] | solved | validate [ms] | plan [ms] | shortcut [ms] | verify [ms] | "
                "quality [ms] | server total [ms] | untimed [ms] | Plan call [ms] | plan / empty | verify / empty | total / empty |\n",
                what);
    std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    const Row& base = rows.front();
    for (const Row& r : rows) {
      std::printf("| %d | %.1f | %.2f | %.2f | %d/%d | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.2f× | %.2f× | %.2f× |\n",
                  r.boxes, r.upload_ms, r.checker_ms, std::max(0.0, r.checker_ms - r.checker_scan_ms), r.solved, r.calls, Median(r.validate), Median(r.plan), Median(r.shortcut),
                  Median(r.verify), Median(r.quality), Median(r.total), Median(r.untimed), Median(r.call),
                  Median(r.plan) / Median(base.plan), Median(r.verify) / Median(base.verify),
                  Median(r.total) / Median(base.total));
    }
    std::printf("\n");
  };

  std::printf("\n## Scenes of thousands of objects: the panda_table request (RRT-Connect, seed %lld), medians of %d calls\n\n",
              static_cast<long long>(request.seed()), options.repeats);
  std::printf("Distant clutter: the table plus N 5 cm boxes on a ring 1.6–3 m from the base (the problem is "
              "unchanged). Server stage timings from each response; 'quality' is the returned trajectory's "
              "quality figures (min_clearance bound, deviation), 'untimed' = total − every named stage "
              "(quality and sampling included: conversion and hand-offs); the scene is uploaded once and one warm-up call, which builds "
              "the scene's collision checker, is not counted; 'checker build' times that construction "
              "in-process (best of 3) and 'of which broad phase' is its excess over a checker built with "
              "CollisionOptions::broad_phase = false.\n\n");
  // One table per kind of clutter: the table plus `add`(scene, N) for each N.
  const auto series = [&](const std::vector<int>& sizes, const char* what, const auto& add) {
    std::vector<Row> rows;
    for (int n : sizes) {
      v1::Scene scene = table;
      add(&scene, n);
      rows.push_back(run(scene, n));
      std::fflush(stdout);
    }
    print(rows, what);
  };
  series(options.distant, "distant boxes", AddDistantBoxes);
  std::printf("Near clutter: the table plus N 2 cm boxes 0.2–0.8 m from the base, 0.05–1 m high, none touching "
              "the arm at start or goal (the problem gets harder as N grows).\n\n");
  series(options.near, "near boxes", [&](v1::Scene* scene, int n) { AddNearBoxes(scene, n, robot, start, goal); });
  std::printf("Distant mesh clutter: the table plus N 5 cm cubes as STL meshes on the same ring. Meshes are FCL "
              "geometry, listed by the checker's broad phase when there are more than 32 (a scene with a mesh "
              "is checked state by state, so the baseline is N = 1, not the empty scene).\n\n");
  series(options.distant_meshes, "distant meshes", AddDistantMeshes);

  // Per check, in-process: the checker alone on 2000 seeded random states (9 passes, the two
  // checkers' interleaved; median of the per-pass means), with the broad phase and without, on the fast (sphere) path and on the
  // FCL path (force_fcl: every object is FCL geometry, FCL's dynamic AABB tree).
  std::printf("Per check, in-process: CollisionChecker::IsValid and Clearance on 2000 seeded random Panda states "
              "(median of 9 passes, the two checkers' passes interleaved), the table plus N objects (distant, or near the arm as above), with the broad phase and without "
              "(CollisionOptions::broad_phase = false scans every object); 'FCL' is the FCL path (force_fcl), where "
              "every object is FCL geometry listed by FCL's DynamicAABBTreeCollisionManager.\n\n");
  std::printf("| path | objects | N | state check [µs] | without broad phase [µs] | ratio | Clearance [µs] | "
              "without [µs] | ratio |\n|---|---|---|---|---|---|---|---|---|\n");
  std::mt19937_64 qrng(31);
  std::vector<Eigen::VectorXd> states;
  for (int i = 0; i < 2000; ++i) {
    Eigen::VectorXd q(robot->num_dofs());
    for (int j = 0; j < q.size(); ++j) {
      q[j] = std::uniform_real_distribution<double>(robot->lower_limits()[j], robot->upper_limits()[j])(qrng);
    }
    states.push_back(q);
  }
  for (const bool fcl_path : {false, true}) {
    for (const int kind : {0, 1, 2}) {  // distant boxes, distant meshes, near boxes
      const bool meshes = kind == 1;
      for (const int n : {1, 40, 100, 300, 1000, 10000}) {
        if (kind == 1 && n > 1000) continue;  // the server's max_mesh_files
        if (kind == 2 && (n > 300 || fcl_path)) continue;
        if (kind != 2 && n == 300) continue;
        v1::Scene scene = table;
        if (kind == 2) {
          AddNearBoxes(&scene, n, robot, start, goal);
        } else {
          meshes ? AddDistantMeshes(&scene, n) : AddDistantBoxes(&scene, n);
        }
        const auto model = SceneFromProto(scene);
        // Both checkers built first, then their passes interleaved (this machine is shared and
        // noisy: a slow spell then hits both alike).
        std::unique_ptr<CollisionChecker> checkers[2];  // [broad phase]
        for (const bool broad : {false, true}) {
          CollisionOptions collision;
          collision.broad_phase = broad;
          collision.force_fcl = fcl_path;
          checkers[broad ? 1 : 0] = std::make_unique<CollisionChecker>(robot, model, collision);
        }
        std::vector<double> state_us[2], clearance_us[2];
        int valid = 0;
        double sum = 0.0;
        for (int pass = 0; pass < 9; ++pass) {
          for (const int b : {pass % 2, 1 - pass % 2}) {
            const CollisionChecker& checker = *checkers[b];
            auto t0 = Clock::now();
            for (const Eigen::VectorXd& q : states) valid += checker.IsValid(q) ? 1 : 0;
            state_us[b].push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count() /
                                  states.size());
            t0 = Clock::now();
            for (std::size_t i = 0; i < states.size(); i += 4) sum += checker.Clearance(states[i]);
            clearance_us[b].push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count() /
                                      ((states.size() + 3) / 4));
          }
        }
        if (!(sum >= 0.0) || valid < 0) throw std::runtime_error("clutter bench: impossible clearance");
        double cost[2][2];  // [broad phase][state, clearance]
        for (int b = 0; b < 2; ++b) {
          cost[b][0] = Median(state_us[b]);
          cost[b][1] = Median(clearance_us[b]);
        }
        std::printf("| %s | %s | %d | %.3f | %.3f | %.2f× | %.3f | %.3f | %.2f× |\n", fcl_path ? "FCL" : "sphere",
                    kind == 2 ? "2 cm boxes near the arm" : meshes ? "5 cm mesh cubes" : "5 cm boxes", n, cost[1][0], cost[0][0], cost[1][0] / cost[0][0],
                    cost[1][1], cost[0][1], cost[1][1] / cost[0][1]);
        std::fflush(stdout);
      }
    }
  }
  std::printf("\n");
}

}  // namespace chasles
