// `chasles-bench --section mesh_robot` (issue 25): is a mesh robot planned at sphere speed? The
// UR5 with its collision geometry as STL meshes, uploaded as users upload it (its meshes covered
// by spheres at upload), against the hand-made sphere model of the same arm, and with the meshes
// kept exact (FCL, discrete states), on the same seeded problems in a shelf scene; every returned
// trajectory is re-checked on the exact meshes every 0.002 rad.

#include "bench_mesh_robot.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "bench_pipeline.h"  // ReadFile, QuantileOrNan, StartBenchServer
#include "chasles/collision/collision_checker.h"
#include "chasles/collision/mesh.h"
#include "chasles/robot/robot_model.h"
#include "chasles/server/convert.h"
#include "chasles/server/planning_server.h"
#include "chasles/v1/chasles.grpc.pb.h"

namespace chasles {
namespace {

using Clock = std::chrono::steady_clock;

constexpr const char* kMeshLinks[] = {"base_link",    "shoulder_link", "upper_arm_link", "forearm_link",
                                      "wrist_1_link", "wrist_2_link",  "wrist_3_link"};

/// A table, a shelf board over it and two posts, in reach of the UR5.
v1::Scene ShelfScene() {
  v1::Scene scene;
  const auto box = [&](const char* name, double sx, double sy, double sz, double x, double y, double z) {
    v1::Box* b = scene.add_boxes();
    b->set_name(name);
    b->mutable_size()->set_x(sx);
    b->mutable_size()->set_y(sy);
    b->mutable_size()->set_z(sz);
    b->mutable_pose()->mutable_position()->set_x(x);
    b->mutable_pose()->mutable_position()->set_y(y);
    b->mutable_pose()->mutable_position()->set_z(z);
    b->mutable_pose()->mutable_orientation()->set_w(1.0);
  };
  box("table", 0.6, 1.2, 0.04, 0.55, 0.0, -0.05);
  box("board", 0.35, 1.0, 0.02, 0.55, 0.0, 0.4);
  box("post_left", 0.04, 0.04, 0.8, 0.35, 0.45, 0.35);
  box("post_right", 0.04, 0.04, 0.8, 0.35, -0.45, 0.35);
  return scene;
}

struct Model {
  std::string name;
  v1::RobotModel robot;
  std::string id, collision;
  double upload_ms = 0.0;
  std::vector<double> call, total, plan, validate, shortcut, parameterize, verify, quality, sample;
  int solved = 0, certified = 0, touching = 0;
};

}  // namespace

void BenchMeshRobot(const MeshRobotBenchOptions& options) {
  const std::string dir = options.examples_dir + "/robots/";
  std::map<std::string, std::shared_ptr<const TriangleMesh>> meshes;
  v1::RobotModel mesh_robot;
  mesh_robot.mutable_urdf()->set_urdf(ReadFile(dir + "ur5_meshes.urdf"));
  mesh_robot.mutable_urdf()->set_srdf(ReadFile(dir + "ur5_meshes.srdf"));
  for (const char* link : kMeshLinks) {
    const std::string file = std::string(link) + "_0.stl";
    const std::string bytes = ReadFile(dir + "ur5_meshes/" + file);
    (*mesh_robot.mutable_urdf()->mutable_mesh_files())["package://ur5_meshes/" + file] = bytes;
    meshes["package://ur5_meshes/" + file] = ParseMesh(bytes, Eigen::Vector3d::Ones(), file);
  }
  std::vector<Model> models(3);
  models[0].name = "ur5_spheres (hand-made spheres)";
  models[0].robot.mutable_urdf()->set_urdf(ReadFile(dir + "ur5_spheres.urdf"));
  models[0].robot.mutable_urdf()->set_srdf(ReadFile(dir + "ur5_spheres.srdf"));
  models[1].name = "ur5_meshes (default: fitted spheres)";
  models[1].robot = mesh_robot;
  models[2].name = "ur5_meshes (exact_meshes)";
  models[2].robot = mesh_robot;
  models[2].robot.mutable_urdf()->set_exact_meshes(true);

  // The re-check and the queries: on the exact meshes (FCL) and on the hand-made spheres, so every
  // problem is valid for every model.
  const v1::Scene scene_proto = ShelfScene();
  const auto scene = SceneFromProto(scene_proto);
  const auto exact_robot = RobotModel::FromUrdf(ReadFile(dir + "ur5_meshes.urdf"), ReadFile(dir + "ur5_meshes.srdf"), meshes);
  const auto sphere_robot = RobotModel::FromUrdf(ReadFile(dir + "ur5_spheres.urdf"), ReadFile(dir + "ur5_spheres.srdf"));
  const CollisionChecker exact(exact_robot, scene);
  const CollisionChecker spheres(sphere_robot, scene);
  std::mt19937_64 rng(options.seed);
  const auto random_valid = [&] {
    for (;;) {
      Eigen::VectorXd q(exact_robot->num_dofs());
      for (int i = 0; i < q.size(); ++i) {
        // The elbow within ±π, the others within ±π too (the UR5's ±2π doubles every problem).
        q[i] = std::uniform_real_distribution<double>(-M_PI, M_PI)(rng);
      }
      if (exact.IsValid(q) && spheres.IsValid(q) && exact.Clearance(q) > 0.02) return q;
    }
  };
  std::vector<std::pair<Eigen::VectorXd, Eigen::VectorXd>> queries;
  while (static_cast<int>(queries.size()) < options.queries) {
    Eigen::VectorXd a = random_valid(), b = random_valid();
    if ((a - b).cwiseAbs().maxCoeff() >= 1.0) queries.emplace_back(std::move(a), std::move(b));
  }

  const BenchServer server = StartBenchServer();
  v1::Planning::Stub* const stub = server.stub.get();
  v1::UploadSceneResponse scene_uploaded;
  {
    grpc::ClientContext context;
    v1::UploadSceneRequest request;
    *request.mutable_scene() = scene_proto;
    const grpc::Status status = stub->UploadScene(&context, request, &scene_uploaded);
    if (!status.ok()) throw std::runtime_error("UploadScene: " + status.error_message());
  }
  for (Model& m : models) {
    grpc::ClientContext context;
    v1::UploadRobotRequest request;
    *request.mutable_robot() = m.robot;
    v1::UploadRobotResponse response;
    const auto t0 = Clock::now();
    const grpc::Status status = stub->UploadRobot(&context, request, &response);
    m.upload_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    if (!status.ok()) throw std::runtime_error("UploadRobot " + m.name + ": " + status.error_message());
    m.id = response.robot_id();
    const v1::CollisionModel& c = response.collision_model();
    char text[200];
    if (c.kind() == "fitted_spheres") {
      std::snprintf(text, sizeof text, "%d spheres fitted to %d shapes, reach ≤ %.1f mm ('%s')", c.spheres(),
                    c.shapes_fitted(), 1e3 * c.reach(), c.reach_link().c_str());
    } else {
      std::snprintf(text, sizeof text, "as described");
    }
    m.collision = text;
  }
  // Alternate the models query by query (the machine's noise falls on all of them alike).
  for (std::size_t k = 0; k < queries.size(); ++k) {
    for (Model& m : models) {
      v1::PlanRequest request;
      request.set_robot_id(m.id);
      request.set_scene_id(scene_uploaded.scene_id());
      for (int i = 0; i < queries[k].first.size(); ++i) {
        request.mutable_start()->add_positions(queries[k].first[i]);
        request.mutable_goal()->add_positions(queries[k].second[i]);
      }
      request.mutable_planner()->set_planner_id("rrt_connect");
      request.set_seed(options.seed + k);
      request.set_time_budget(options.budget);
      grpc::ClientContext context;
      v1::PlanResponse response;
      const auto t0 = Clock::now();
      const grpc::Status status = stub->Plan(&context, request, &response);
      const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
      if (!status.ok()) throw std::runtime_error("Plan " + m.name + ": " + status.error_message());
      if (response.outcome() != v1::SUCCESS) continue;
      ++m.solved;
      m.call.push_back(ms);
      m.total.push_back(1e3 * response.timings().total());
      m.plan.push_back(1e3 * response.timings().plan());
      m.validate.push_back(1e3 * response.timings().validate());
      m.shortcut.push_back(1e3 * response.timings().shortcut());
      m.parameterize.push_back(1e3 * response.timings().parameterize());
      m.verify.push_back(1e3 * response.timings().verify());
      m.quality.push_back(1e3 * response.timings().quality());
      m.sample.push_back(1e3 * response.timings().sample());
      m.certified += response.verification().collision_guarantee() == "certified";
      // The re-check on the exact meshes: the returned samples, and states every 0.002 rad
      // between consecutive samples (straight in joint space between them).
      bool touching = false;
      Eigen::VectorXd prev;
      for (const v1::TrajectoryPoint& p : response.trajectory().points()) {
        Eigen::VectorXd q(p.positions_size());
        for (int i = 0; i < q.size(); ++i) q[i] = p.positions(i);
        if (prev.size() == q.size()) {
          const int n = std::max(1, static_cast<int>(std::ceil((q - prev).cwiseAbs().maxCoeff() / 0.002)));
          for (int s = 1; s <= n && !touching; ++s) {
            touching = exact.Check(prev + (q - prev) * (static_cast<double>(s) / n)).in_collision;
          }
        } else {
          touching = exact.Check(q).in_collision;
        }
        prev = q;
        if (touching) break;
      }
      m.touching += touching;
    }
  }
  std::printf("\n## A robot shipped with meshes (issue 25): the UR5 as STL meshes against its hand-made sphere "
              "model, %d seeded problems (RRT-Connect, %.1f s budget), shelf scene, over gRPC\n\n",
              options.queries, options.budget);
  std::printf("Every returned trajectory is re-checked on the exact meshes (FCL) at its 10 ms samples and every "
              "0.002 rad between them. Upload times include parsing the meshes and, by default, fitting the spheres "
              "(once per robot).\n\n");
  std::printf("| robot | collision model | upload [ms] | solved | certified | touching the meshes at the re-check | "
              "Plan call median [ms] | p95 [ms] | server total median [ms] | validate median [ms] | plan median [ms] | "
              "shortcut median [ms] | TOPP median [ms] | certify median [ms] | quality median [ms] | samples median [ms] | "
              "call / hand-made spheres |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  const double base = QuantileOrNan(models[0].call, 0.5);
  for (const Model& m : models) {
    std::printf("| %s | %s | %.0f | %d/%d | %d | %d | %.2f | %.2f | %.2f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | "
                "%.2f× |\n",
                m.name.c_str(), m.collision.c_str(), m.upload_ms, m.solved, options.queries, m.certified, m.touching,
                QuantileOrNan(m.call, 0.5), QuantileOrNan(m.call, 0.95), QuantileOrNan(m.total, 0.5), QuantileOrNan(m.validate, 0.5),
                QuantileOrNan(m.plan, 0.5), QuantileOrNan(m.shortcut, 0.5), QuantileOrNan(m.parameterize, 0.5),
                QuantileOrNan(m.verify, 0.5), QuantileOrNan(m.quality, 0.5), QuantileOrNan(m.sample, 0.5),
                QuantileOrNan(m.call, 0.5) / base);
  }
  std::printf("\n");
}

}  // namespace chasles
