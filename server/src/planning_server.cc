#include "chasles/server/planning_server.h"

#include <algorithm>
#include <atomic>
#include <cinttypes>
#include <cstdio>
#include <functional>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include <google/protobuf/util/json_util.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>

#include "chasles/pipeline/plan_pipeline.h"
#include "chasles/planners/registry.h"
#include "chasles/robot/error.h"
#include "chasles/robot/inverse_kinematics.h"
#include "chasles/server/benchmark.h"
#include "chasles/server/convert.h"
#include "chasles/server/convert_multi.h"
#include "chasles/server/default_assets.h"
#include "chasles/server/model_store.h"
#include "chasles/server/status.h"
#include "chasles/server/thread_pool.h"
#include "chasles/server/workcells.h"
#include "chasles/v1/chasles.grpc.pb.h"

namespace chasles {
namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// The gRPC deadline of a call on the steady clock (far future when the client set none).
Clock::time_point SteadyDeadline(const grpc::CallbackServerContext& context) {
  const auto system_now = std::chrono::system_clock::now();
  const auto deadline = context.deadline();
  const auto far = std::chrono::hours(24 * 365);
  if (deadline >= system_now + far) return Clock::now() + far;
  return Clock::now() + std::chrono::duration_cast<Clock::duration>(deadline - system_now);
}

v1::RobotModel DefaultRobotProto() {
  v1::RobotModel robot;
  robot.set_name("panda");
  robot.mutable_urdf()->set_urdf(std::string(kDefaultRobotUrdf));
  robot.mutable_urdf()->set_srdf(std::string(kDefaultRobotSrdf));
  return robot;
}

v1::Scene DefaultSceneProto() {
  v1::Scene scene;
  const auto status = google::protobuf::util::JsonStringToMessage(std::string(kDefaultSceneJson), &scene);
  if (!status.ok()) {
    throw std::runtime_error("embedded default scene (examples/scenes/table.json) does not parse: " +
                             status.ToString());
  }
  return scene;
}

std::string IdPrefix(const std::string& id) { return id.substr(0, 8); }

/// A unary reactor whose work runs on the pool; cancellation (client cancel, deadline, server
/// shutdown) reaches the Termination of the running job.
class PoolReactor final : public grpc::ServerUnaryReactor {
 public:
  /// Creates the job's Termination; if the call was already cancelled, it is cancelled too.
  Termination Start(Clock::time_point budget_end, Clock::time_point deadline) {
    std::lock_guard<std::mutex> lock(mutex_);
    termination_.emplace(budget_end, deadline);
    if (cancelled_) termination_->Cancel();
    return *termination_;
  }
  bool cancelled() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return cancelled_;
  }
  void OnCancel() override {
    std::lock_guard<std::mutex> lock(mutex_);
    cancelled_ = true;
    if (termination_) termination_->Cancel();
  }
  void OnDone() override { delete this; }

 private:
  mutable std::mutex mutex_;
  bool cancelled_ = false;
  std::optional<Termination> termination_;
};

class PlanningService final : public v1::Planning::CallbackService {
 public:
  PlanningService(const PlannerRegistry& registry, ModelStore* store, ThreadPool* pool, WorkcellStore* workcells,
                  bool log, const AccessControl* access)
      : registry_(registry), pipeline_(registry), store_(store), pool_(pool), workcells_(workcells), log_(log),
        access_(access) {}

  grpc::ServerUnaryReactor* Plan(grpc::CallbackServerContext* context, const v1::PlanRequest* request,
                                 v1::PlanResponse* response) override {
    if (auto* refused = Refuse(context, "Plan")) return refused;
    const Clock::time_point arrival = Clock::now();
    const Clock::time_point deadline = SteadyDeadline(*context);
    const std::string request_id = RequestId(request->request_id(), "req");
    auto* reactor = new PoolReactor();
    const bool queued = pool_->Submit([=] { RunPlan(reactor, context, request, response, request_id, arrival, deadline); });
    if (!queued) {
      Log("plan request=%s status=RESOURCE_EXHAUSTED (planning queue full)", request_id.c_str());
      reactor->Finish(grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED,
                                   "the server's planning queue is full; retry later"));
    }
    return reactor;
  }

  grpc::ServerUnaryReactor* Optimize(grpc::CallbackServerContext* context, const v1::OptimizeRequest* request,
                                     v1::OptimizeResponse* response) override {
    if (auto* refused = Refuse(context, "Optimize")) return refused;
    const Clock::time_point arrival = Clock::now();
    const Clock::time_point deadline = SteadyDeadline(*context);
    const std::string request_id = RequestId(request->request_id(), "opt");
    response->set_request_id(request_id);
    return RunOnPool("optimize", [this, request, response, request_id, arrival, deadline](PoolReactor& reactor) {
      const StoredRobot robot = RobotOf(*request);
      const StoredScene scene = SceneOf(*request);
      response->set_robot_id(robot.id);
      response->set_scene_id(scene.id);
      RequestSettings settings;
      double input_duration = 0.0;
      const OptimizeQuery query =
          OptimizeQueryFromProto(*request, store_->Checker(robot, scene), &settings, &input_duration);
      const Termination termination = reactor.Start(BudgetEnd(settings.time_budget, deadline), deadline);
      const OptimizeOutcome outcome = OptimizePath(query, termination);
      OptimizeOutcomeToProto(outcome, query, response);
      response->set_input_duration(input_duration);
      Log("optimize request=%s robot=%s scene=%s waypoints=%zu method=%s used=%s outcome=%s duration=%.3f ms "
          "parameterize=%.1f optimize=%.1f verify=%.1f total=%.1f",
          request_id.c_str(), IdPrefix(robot.id).c_str(), IdPrefix(scene.id).c_str(), query.path.size(),
          ToString(outcome.stage.optimizer.requested), ToString(outcome.stage.optimizer.used),
          v1::PlanOutcome_Name(response->outcome()).c_str(), response->duration(),
          1e3 * outcome.stage.parameterize_seconds, 1e3 * outcome.stage.optimize_seconds,
          1e3 * outcome.stage.verify_seconds, 1e3 * SecondsSince(arrival));
    });
  }

  grpc::ServerUnaryReactor* ListPlanners(grpc::CallbackServerContext* context, const v1::ListPlannersRequest*,
                                         v1::ListPlannersResponse* response) override {
    if (auto* refused = Refuse(context, "ListPlanners")) return refused;
    grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
    grpc::Status status;
    try {
      for (const PlannerSpec& spec : registry_.List()) PlannerSpecToProto(spec, response->add_planners());
    } catch (...) {
      status = StatusFromException(std::current_exception());
    }
    reactor->Finish(status);
    return reactor;
  }

  grpc::ServerUnaryReactor* UploadRobot(grpc::CallbackServerContext* context, const v1::UploadRobotRequest* request,
                                        v1::UploadRobotResponse* response) override {
    if (auto* refused = Refuse(context, "UploadRobot")) return refused;
    return RunOnPool("upload-robot", [this, request, response](const PoolReactor&) {
      const Clock::time_point start = Clock::now();
      StoredRobot robot = store_->AddRobot(request->robot(), "robot");
      response->set_robot_id(robot.id);
      const RobotModel& model = *robot.model;
      for (int i = 0; i < model.num_dofs(); ++i) {
        response->add_joint_names(model.dof_names()[i]);
        response->add_lower_limits(model.lower_limits()[i]);
        response->add_upper_limits(model.upper_limits()[i]);
        response->add_velocity_limits(model.velocity_limits()[i]);
      }
      Log("upload-robot robot=%s name=%s dofs=%d status=OK ms=%.1f", IdPrefix(robot.id).c_str(),
          model.name().c_str(), model.num_dofs(), 1e3 * SecondsSince(start));
    });
  }

  grpc::ServerUnaryReactor* UploadScene(grpc::CallbackServerContext* context, const v1::UploadSceneRequest* request,
                                        v1::UploadSceneResponse* response) override {
    if (auto* refused = Refuse(context, "UploadScene")) return refused;
    return RunOnPool("upload-scene", [this, request, response](const PoolReactor&) {
      const Clock::time_point start = Clock::now();
      StoredScene scene = store_->AddScene(request->scene(), "scene");
      response->set_scene_id(scene.id);
      Log("upload-scene scene=%s objects=%zu maps=%zu status=OK ms=%.1f", IdPrefix(scene.id).c_str(),
          scene.scene->objects().size(), scene.scene->occupancy_maps().size(), 1e3 * SecondsSince(start));
    });
  }

  grpc::ServerUnaryReactor* UpdateScene(grpc::CallbackServerContext* context, const v1::UpdateSceneRequest* request,
                                        v1::UpdateSceneResponse* response) override {
    if (auto* refused = Refuse(context, "UpdateScene")) return refused;
    return RunOnPool("update-scene", [this, request, response](const PoolReactor&) {
      const Clock::time_point start = Clock::now();
      const StoredScene base =
          request->scene_id().empty() ? store_->default_scene() : store_->FindScene(request->scene_id());
      PointCloudInsertion insertion;
      insertion.octomap = request->octomap();
      insertion.points.assign(request->points().begin(), request->points().end());
      const v1::Vector3& origin = request->sensor_origin();
      insertion.sensor_origin = Eigen::Vector3d(origin.x(), origin.y(), origin.z());
      insertion.max_range = request->max_range();
      insertion.resolution = request->resolution();
      PointCloudInsertionStats stats;
      auto updated = std::make_shared<const Scene>(base.scene->InsertPointCloud(insertion, &stats));
      // Content id: the base scene's id and the update (the same update of the same scene gives
      // the same id).
      v1::UpdateSceneRequest key = *request;
      key.set_scene_id(base.id);
      const StoredScene scene = store_->PutScene(ProtoContentId(key), std::move(updated));
      response->set_scene_id(scene.id);
      response->set_octomap(stats.octomap);
      response->set_points_inserted(stats.points_inserted);
      response->set_occupied_leaves(stats.occupied_leaves);
      response->set_resolution(stats.resolution);
      response->set_seconds(stats.seconds);
      Log("update-scene scene=%s->%s map=%s%s points=%zu occupied=%zu status=OK ms=%.1f", IdPrefix(base.id).c_str(),
          IdPrefix(scene.id).c_str(), stats.octomap.c_str(), stats.created ? " (new)" : "", stats.points_inserted,
          stats.occupied_leaves, 1e3 * SecondsSince(start));
    });
  }

  grpc::ServerUnaryReactor* InverseKinematics(grpc::CallbackServerContext* context,
                                              const v1::InverseKinematicsRequest* request,
                                              v1::InverseKinematicsResponse* response) override {
    if (auto* refused = Refuse(context, "InverseKinematics")) return refused;
    const Clock::time_point arrival = Clock::now();
    const Clock::time_point deadline = SteadyDeadline(*context);
    return RunOnPool("ik", [this, request, response, arrival, deadline](const PoolReactor& reactor) {
      // Robot (inline, id or default) and, for collision_free, the scene's cached checker.
      const StoredRobot robot = RobotOf(*request);
      response->set_robot_id(robot.id);
      IkRequest ik = IkRequestFromProto(*request, *robot.model);
      std::string scene_id = "-";
      std::shared_ptr<const CollisionChecker> checker;
      if (request->collision_free()) {
        const StoredScene scene = SceneOf(*request);
        scene_id = IdPrefix(scene.id);
        checker = store_->Checker(robot, scene);
        ik.accept = [checker](const Eigen::VectorXd& q) { return checker->IsValid(q); };
      }
      // The solver's budget ends before the gRPC deadline, leaving time for the answer.
      const double left = std::chrono::duration<double>(deadline - Clock::now()).count();
      ik.time_budget = std::min(ik.time_budget, std::max(1e-3, 0.9 * left));
      ik.stop = [&reactor] { return reactor.cancelled(); };
      const IkResult result = SolveIk(*robot.model, ik);
      IkResultToProto(result, ik, *robot.model, response);
      Log("ik robot=%s scene=%s link=%s solutions=%d/%d attempts=%d status=OK ms=%.1f%s%s",
          IdPrefix(robot.id).c_str(), scene_id.c_str(), robot.model->links()[ik.link].name.c_str(),
          response->solutions_size(), ik.max_solutions, result.attempts, 1e3 * SecondsSince(arrival),
          response->solved() ? "" : " message=", response->solved() ? "" : result.message.c_str());
    });
  }

  grpc::ServerUnaryReactor* Coordinate(grpc::CallbackServerContext* context, const v1::CoordinateRequest* request,
                                       v1::CoordinateResponse* response) override {
    if (auto* refused = Refuse(context, "Coordinate")) return refused;
    const Clock::time_point arrival = Clock::now();
    const Clock::time_point deadline = SteadyDeadline(*context);
    const std::string request_id = RequestId(request->request_id(), "team");
    response->set_request_id(request_id);
    return RunOnPool("coordinate", [this, request, response, request_id, arrival, deadline](PoolReactor& reactor) {
      const StoredScene scene = SceneOf(*request);
      response->set_scene_id(scene.id);
      CoordinationQuery query = CoordinationQueryFromProto(
          *request, scene.scene,
          [this](const v1::TeamRobot& robot, const std::string& field) { return TeamRobotOf(robot, field).model; },
          registry_);
      if (request->has_workcell()) {
        const double origin = request->workcell().start_time() == 0.0 ? workcells_->Now() : request->workcell().start_time();
        response->set_start_time(origin);
        for (const Reservation& r : workcells_->Active(request->workcell().name())) {
          const bool own = std::any_of(query.robots.begin(), query.robots.end(),
                                       [&r](const TeamRobotSpec& robot) { return robot.placement.name == r.robot_name; });
          if (!own) query.committed.push_back(MotionOf(r, origin));
        }
      }
      const Termination termination = reactor.Start(BudgetEnd(query.time_budget, deadline), deadline);
      const CoordinationOutcome outcome = chasles::Coordinate(query, registry_, termination);
      CoordinationOutcomeToProto(outcome, query, response);
      if (outcome.code == CoordinationCode::kDeadlineExceeded) {
        throw DeadlineError{"the gRPC deadline passed before coordination finished"};
      }
      Log("coordinate request=%s scene=%s robots=%d method=%s used=%s outcome=%s makespan=%.3f sum=%.3f "
          "reorderings=%d states=%llu ms=%.1f",
          request_id.c_str(), IdPrefix(scene.id).c_str(), request->robots_size(), ToString(query.method),
          outcome.code == CoordinationCode::kSuccess ? ToString(outcome.method) : "-",
          v1::PlanOutcome_Name(response->outcome()).c_str(), outcome.makespan, outcome.sum_of_durations,
          outcome.reorderings, static_cast<unsigned long long>(outcome.verification.states_checked),
          1e3 * SecondsSince(arrival));
    });
  }

  grpc::ServerUnaryReactor* CreateWorkcell(grpc::CallbackServerContext* context,
                                           const v1::CreateWorkcellRequest* request,
                                           v1::CreateWorkcellResponse* response) override {
    if (auto* refused = Refuse(context, "CreateWorkcell")) return refused;
    grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
    grpc::Status status;
    try {
      response->set_created(workcells_->Create(request->name()));
      response->set_active_reservations(static_cast<std::uint32_t>(workcells_->ActiveCount(request->name())));
      response->set_now(workcells_->Now());
      Log("create-workcell name=%s created=%d", request->name().c_str(), response->created() ? 1 : 0);
    } catch (...) {
      status = StatusFromException(std::current_exception());
    }
    reactor->Finish(status);
    return reactor;
  }

  grpc::ServerUnaryReactor* CommitTrajectory(grpc::CallbackServerContext* context,
                                             const v1::CommitTrajectoryRequest* request,
                                             v1::CommitTrajectoryResponse* response) override {
    if (auto* refused = Refuse(context, "CommitTrajectory")) return refused;
    return RunOnPool("commit", [this, request, response](const PoolReactor&) {
      const Clock::time_point start = Clock::now();
      if (request->robot_name().empty()) ThrowInvalid("robot_name is empty: name the robot that moves");
      const StoredRobot robot = RobotOf(*request);
      Reservation reservation;
      reservation.robot_name = request->robot_name();
      reservation.placement.name = request->robot_name();
      reservation.placement.model = robot.model;
      if (request->has_base_pose()) reservation.placement.base_pose = PoseFromProto(request->base_pose(), "base_pose");
      reservation.trajectory = TrajectoryFromPoints(request->trajectory(), *robot.model, "trajectory");
      const double start_time = request->start_time();
      if (!std::isfinite(start_time) || start_time < 0.0) {
        ThrowInvalid("start_time = " + FormatNumber(start_time) + " must be finite and >= 0 s since the Unix epoch (0 = now)");
      }
      reservation.start_time = start_time == 0.0 ? workcells_->Now() : start_time;
      const Reservation committed =
          workcells_->Commit(request->workcell(), reservation, request->hold(), request->robot_padding());
      response->set_reservation_id(committed.id);
      response->set_start_time(committed.start_time);
      response->set_end_time(committed.end_time);
      response->set_expires_at(committed.expires_at);
      response->set_active_reservations(static_cast<std::uint32_t>(workcells_->ActiveCount(request->workcell())));
      Log("commit workcell=%s robot=%s reservation=%s duration=%.3f hold=%.3f status=OK ms=%.1f",
          request->workcell().c_str(), request->robot_name().c_str(), committed.id.c_str(),
          committed.end_time - committed.start_time, committed.expires_at - committed.end_time, 1e3 * SecondsSince(start));
    });
  }

  grpc::ServerUnaryReactor* Release(grpc::CallbackServerContext* context, const v1::ReleaseRequest* request,
                                    v1::ReleaseResponse* response) override {
    if (auto* refused = Refuse(context, "Release")) return refused;
    grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
    grpc::Status status;
    try {
      const int released = workcells_->Release(request->workcell(), request->reservation_id(), request->robot_name());
      response->set_released(static_cast<std::uint32_t>(released));
      response->set_active_reservations(static_cast<std::uint32_t>(workcells_->ActiveCount(request->workcell())));
      Log("release workcell=%s reservation=%s robot=%s released=%d", request->workcell().c_str(),
          request->reservation_id().c_str(), request->robot_name().c_str(), released);
    } catch (...) {
      status = StatusFromException(std::current_exception());
      Log("release status=%d message=%s", static_cast<int>(status.error_code()), status.error_message().c_str());
    }
    reactor->Finish(status);
    return reactor;
  }

  grpc::ServerWriteReactor<v1::BenchmarkResponse>* Benchmark(grpc::CallbackServerContext* context,
                                                             const v1::BenchmarkRequest* request) override {
    if (grpc::Status s = access_->Authorize(*context, "Benchmark"); !s.ok()) return new RefusedWriter<v1::BenchmarkResponse>(s);
    const std::string request_id = RequestId(request->request_id(), "bench");
    BenchmarkServices services;
    services.registry = &registry_;
    services.pipeline = &pipeline_;
    services.store = store_;
    services.pool = pool_;
    if (log_) services.log = [](const std::string& line) { std::fprintf(stderr, "chasles-server: %s\n", line.c_str()); };
    return StartBenchmark(services, &benchmarks_, request, request_id, SteadyDeadline(*context));
  }

  grpc::ServerUnaryReactor* StopBenchmark(grpc::CallbackServerContext* context, const v1::StopBenchmarkRequest* request,
                                          v1::StopBenchmarkResponse* response) override {
    if (auto* refused = Refuse(context, "StopBenchmark")) return refused;
    grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
    grpc::Status status;
    if (request->request_id().empty()) {
      status = grpc::Status(grpc::StatusCode::INVALID_ARGUMENT, "request_id is empty: name the running benchmark");
    } else if (!benchmarks_.Stop(request->request_id())) {
      status = grpc::Status(grpc::StatusCode::NOT_FOUND,
                            "request_id = '" + request->request_id() + "' names no running benchmark (finished, or never started)");
    } else {
      response->set_stopped(true);
      Log("stop-benchmark request=%s stopping", request->request_id().c_str());
    }
    reactor->Finish(status);
    return reactor;
  }

 private:
  /// Finishes the call with the access check's refusal (UNAUTHENTICATED, PERMISSION_DENIED), or
  /// returns null when the caller may call `rpc`.
  grpc::ServerUnaryReactor* Refuse(grpc::CallbackServerContext* context, const char* rpc) const {
    const grpc::Status status = access_->Authorize(*context, rpc);
    if (status.ok()) return nullptr;
    Log("%s status=%d message=%s", rpc, static_cast<int>(status.error_code()), status.error_message().c_str());
    grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
    reactor->Finish(status);
    return reactor;
  }

  /// A server-streaming call refused before it started.
  template <typename Response>
  class RefusedWriter final : public grpc::ServerWriteReactor<Response> {
   public:
    explicit RefusedWriter(const grpc::Status& status) { this->Finish(status); }
    void OnDone() override { delete this; }
  };

  /// Thrown from pool work to finish the call with DEADLINE_EXCEEDED.
  struct DeadlineError {
    std::string message;
  };

  /// The end of a request's budget, cut short so a result can still travel back before the
  /// gRPC deadline.
  static Clock::time_point BudgetEnd(double budget_seconds, Clock::time_point deadline) {
    const Clock::time_point now = Clock::now();
    Clock::time_point budget_end =
        now + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(budget_seconds));
    const auto margin = std::min<Clock::duration>(std::chrono::milliseconds(200), (deadline - now) / 10);
    return std::min(budget_end, deadline - margin);
  }

  /// A team robot: inline (parsed and cached) or by id; errors name `field`.
  StoredRobot TeamRobotOf(const v1::TeamRobot& robot, const std::string& field) {
    switch (robot.robot_source_case()) {
      case v1::TeamRobot::kRobot: return store_->AddRobot(robot.robot(), field + ".robot");
      case v1::TeamRobot::kRobotId: return store_->FindRobot(robot.robot_id());
      default: ThrowInvalid(field + " has no robot: set robot or robot_id");
    }
  }

  /// The client's request id, or a generated "<prefix>-NNNNNN" when it sent none.
  std::string RequestId(const std::string& given, const char* prefix) {
    if (!given.empty()) return given;
    char buffer[32];
    std::snprintf(buffer, sizeof(buffer), "%s-%06" PRIu64, prefix, ++next_request_);
    return buffer;
  }

  template <typename Request>
  StoredRobot RobotOf(const Request& request) {
    return RobotOfRequest(*store_, request);
  }
  template <typename Request>
  StoredScene SceneOf(const Request& request) {
    return SceneOfRequest(*store_, request);
  }

  /// Runs `work` on the pool and finishes the call with OK or the mapped exception.
  grpc::ServerUnaryReactor* RunOnPool(const char* what, std::function<void(PoolReactor&)> work) {
    auto* reactor = new PoolReactor();
    const bool queued = pool_->Submit([this, reactor, what, work = std::move(work)] {
      grpc::Status status;
      if (reactor->cancelled()) {
        status = grpc::Status(grpc::StatusCode::CANCELLED, "cancelled before it started");
      } else {
        try {
          work(*reactor);
          if (reactor->cancelled()) status = grpc::Status(grpc::StatusCode::CANCELLED, "cancelled by the client");
        } catch (const DeadlineError& e) {
          status = grpc::Status(grpc::StatusCode::DEADLINE_EXCEEDED, e.message);
        } catch (...) {
          status = StatusFromException(std::current_exception());
          Log("%s status=%d message=%s", what, static_cast<int>(status.error_code()),
              status.error_message().c_str());
        }
      }
      reactor->Finish(status);
    });
    if (!queued) {
      reactor->Finish(grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED, "the server's work queue is full; retry later"));
    }
    return reactor;
  }

  void RunPlan(PoolReactor* reactor, grpc::CallbackServerContext* context, const v1::PlanRequest* request,
               v1::PlanResponse* response, const std::string& request_id, Clock::time_point arrival,
               Clock::time_point deadline) {
    grpc::Status status;
    std::string robot_id, scene_id;
    std::string planner = request->planner().planner_id().empty() ? "rrt_connect" : request->planner().planner_id();
    std::string outcome_name = "-";
    StageSeconds seconds;
    if (reactor->cancelled() || context->IsCancelled()) {
      status = grpc::Status(grpc::StatusCode::CANCELLED, "cancelled before planning started");
    } else try {
      // 1. Robot, scene and checker (parsed or cached).
      const StoredRobot robot = RobotOf(*request);
      robot_id = robot.id;
      const StoredScene scene = SceneOf(*request);
      scene_id = scene.id;
      if (request->has_workcell()) {
        // A team of one among the workcell's committed trajectories.
        planner = "workcell:" + planner;
        CoordinationQuery query = WorkcellPlanQuery(*request, robot.model, scene.scene, registry_);
        const double origin =
            request->workcell().start_time() == 0.0 ? workcells_->Now() : request->workcell().start_time();
        for (const Reservation& r : workcells_->Active(request->workcell().name())) {
          if (r.robot_name != query.robots.front().placement.name) query.committed.push_back(MotionOf(r, origin));
        }
        Termination termination = reactor->Start(BudgetEnd(query.time_budget, deadline), deadline);
        const CoordinationOutcome outcome = chasles::Coordinate(query, registry_, termination);
        outcome_name = ToString(outcome.code);
        WorkcellPlanToProto(outcome, query, response);
        seconds.total = SecondsSince(arrival);
        if (outcome.code == CoordinationCode::kCancelled) {
          status = grpc::Status(grpc::StatusCode::CANCELLED, "cancelled by the client");
        } else if (outcome.code == CoordinationCode::kDeadlineExceeded) {
          status = grpc::Status(grpc::StatusCode::DEADLINE_EXCEEDED, "the gRPC deadline passed before planning finished");
        }
      } else {
        std::shared_ptr<const CollisionChecker> checker = store_->Checker(robot, scene);

        // 2. The query, with the proto's defaults.
        RequestSettings settings;
        PlanQuery query = PlanQueryFromProto(*request, checker, registry_, &settings);
        const double prepare = SecondsSince(arrival);

        // 3. Budget: the request's, cut short so a result can still travel back before the
        //    gRPC deadline (which itself stops everything).
        Termination termination = reactor->Start(BudgetEnd(settings.time_budget, deadline), deadline);

        // 4. Plan.
        PlanOutcome outcome = pipeline_.Plan(query, termination);
        outcome.seconds.validate += prepare;
        outcome.seconds.total = SecondsSince(arrival);
        seconds = outcome.seconds;
        outcome_name = ToString(outcome.code);
        PlanOutcomeToProto(outcome, query, response);
        status = StatusFromOutcome(outcome.code, outcome.message);
        if (status.ok() && (reactor->cancelled() || termination.Reason() == StopReason::kCancelled) &&
            outcome.code != PlanOutcomeCode::kSuccess) {
          status = grpc::Status(grpc::StatusCode::CANCELLED, "cancelled by the client");
        }
      }
    } catch (...) {
      status = StatusFromException(std::current_exception());
    }
    response->set_request_id(request_id);
    response->set_robot_id(robot_id);
    response->set_scene_id(scene_id);
    if (!status.ok()) seconds.total = SecondsSince(arrival);
    Log("plan request=%s robot=%s scene=%s planner=%s status=%s outcome=%s ms validate=%.1f plan=%.1f "
        "shortcut=%.1f parameterize=%.1f optimize=%.1f verify=%.1f total=%.1f%s%s",
        request_id.c_str(), robot_id.empty() ? "-" : IdPrefix(robot_id).c_str(),
        scene_id.empty() ? "-" : IdPrefix(scene_id).c_str(), planner.c_str(), StatusName(status.error_code()),
        outcome_name.c_str(), 1e3 * seconds.validate, 1e3 * seconds.plan, 1e3 * seconds.shortcut,
        1e3 * seconds.parameterize, 1e3 * seconds.optimize, 1e3 * seconds.verify, 1e3 * seconds.total, status.ok() ? "" : " error=",
        status.ok() ? "" : status.error_message().c_str());
    reactor->Finish(status);
  }

  static const char* StatusName(grpc::StatusCode code) {
    switch (code) {
      case grpc::StatusCode::OK: return "OK";
      case grpc::StatusCode::CANCELLED: return "CANCELLED";
      case grpc::StatusCode::INVALID_ARGUMENT: return "INVALID_ARGUMENT";
      case grpc::StatusCode::DEADLINE_EXCEEDED: return "DEADLINE_EXCEEDED";
      case grpc::StatusCode::NOT_FOUND: return "NOT_FOUND";
      case grpc::StatusCode::FAILED_PRECONDITION: return "FAILED_PRECONDITION";
      case grpc::StatusCode::RESOURCE_EXHAUSTED: return "RESOURCE_EXHAUSTED";
      case grpc::StatusCode::INTERNAL: return "INTERNAL";
      default: return "OTHER";
    }
  }

  template <typename... Args>
  void Log(const char* format, Args... args) const {
    if (!log_) return;
    char line[2048];
    std::snprintf(line, sizeof(line), format, args...);
    std::fprintf(stderr, "chasles-server: %s\n", line);
  }

  const PlannerRegistry& registry_;
  const PlanningPipeline pipeline_;
  ModelStore* store_;
  ThreadPool* pool_;
  WorkcellStore* workcells_;
  BenchmarkRegistry benchmarks_;
  const bool log_;
  const AccessControl* access_;  // tokens and roles (the credentials checked them already)
  std::atomic<std::uint64_t> next_request_{0};
};

}  // namespace

void ServerOptions::Validate() const {
  if (listen.empty()) ThrowInvalid("--listen is empty: give ADDRESS:PORT, e.g. 127.0.0.1:50051");
  if (threads < 0) ThrowInvalid("--threads = " + std::to_string(threads) + " must be >= 0 (0 = hardware threads)");
  if (max_message_mb < 1 || max_message_mb > 2047) {
    ThrowInvalid("--max-message-mb = " + std::to_string(max_message_mb) + " must be within [1, 2047]");
  }
  if (cache_capacity == 0) ThrowInvalid("cache_capacity = 0 must be >= 1");
}

struct PlanningServer::Impl {
  PlannerRegistry registry;
  std::unique_ptr<ModelStore> store;
  std::unique_ptr<ThreadPool> pool;
  WorkcellStore workcells;
  std::unique_ptr<AccessControl> access;
  std::unique_ptr<PlanningService> service;
  std::unique_ptr<grpc::Server> server;
  int port = 0;
  std::once_flag shutdown_once;
};

PlanningServer::PlanningServer(const ServerOptions& options) : impl_(std::make_unique<Impl>()) {
  options.Validate();
  RegisterDefaultPlanners(&impl_->registry);
  impl_->store = std::make_unique<ModelStore>(DefaultRobotProto(), DefaultSceneProto(), options.cache_capacity);
  impl_->pool = std::make_unique<ThreadPool>(options.threads);
  impl_->access = std::make_unique<AccessControl>(options.security);
  impl_->service = std::make_unique<PlanningService>(impl_->registry, impl_->store.get(), impl_->pool.get(),
                                                     &impl_->workcells, options.log_requests, impl_->access.get());

  grpc::EnableDefaultHealthCheckService(true);
  grpc::ServerBuilder builder;
  builder.AddListeningPort(options.listen, impl_->access->MakeServerCredentials(), &impl_->port);
  const int max_bytes = options.max_message_mb * 1024 * 1024;
  builder.SetMaxReceiveMessageSize(max_bytes);
  builder.SetMaxSendMessageSize(max_bytes);
  builder.RegisterService(impl_->service.get());
  impl_->server = builder.BuildAndStart();
  if (!impl_->server || impl_->port == 0) {
    throw std::runtime_error("cannot listen on " + options.listen);
  }
  if (auto* health = impl_->server->GetHealthCheckService()) {
    health->SetServingStatus(true);
    health->SetServingStatus("chasles.v1.Planning", true);
  }
}

PlanningServer::~PlanningServer() {
  Shutdown();
  impl_->server->Wait();
  impl_->pool.reset();  // every call has finished; joins the idle workers
}

int PlanningServer::port() const { return impl_->port; }

void PlanningServer::Shutdown(std::chrono::milliseconds grace) {
  std::call_once(impl_->shutdown_once, [&] {
    if (auto* health = impl_->server->GetHealthCheckService()) health->Shutdown();
    impl_->server->Shutdown(std::chrono::system_clock::now() + grace);
  });
}

void PlanningServer::Wait() { impl_->server->Wait(); }

}  // namespace chasles
