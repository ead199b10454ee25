#include "chasles/server/planning_server.h"

#include <algorithm>
#include <atomic>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <mutex>
#include <new>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <type_traits>
#include <utility>

#include <google/protobuf/util/json_util.h>
#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>
#include <grpcpp/support/proto_buffer_reader.h>
#include <grpcpp/support/proto_buffer_writer.h>

#include "chasles/pipeline/plan_pipeline.h"
#include "chasles/planners/registry.h"
#include "chasles/robot/error.h"
#include "chasles/robot/inverse_kinematics.h"
#include "chasles/server/benchmark.h"
#include "chasles/server/convert.h"
#include "chasles/server/convert_cartesian.h"
#include "chasles/server/convert_multi.h"
#include "chasles/server/default_assets.h"
#include "chasles/server/fleet_sessions.h"
#include "chasles/server/groups.h"
#include "chasles/server/heap_tracking.h"
#include "chasles/server/metrics.h"
#include "chasles/server/model_store.h"
#include "chasles/server/redis_client.h"
#include "chasles/server/replan.h"
#include "chasles/server/request_log.h"
#include "chasles/server/security.h"
#include "chasles/server/status.h"
#include "chasles/server/thread_pool.h"
#include "chasles/server/view_server.h"
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

std::string IdPrefix(const std::string& id) { return id.empty() ? "-" : id.substr(0, 8); }

// ---- Budgets: how long a call may hold a worker --------------------------------------------

/// A budget field with the proto's "0 = default" rule; other values are validated later by the
/// conversion (this only classifies and caps).
double Defaulted(double value, double fallback) { return value == 0.0 ? fallback : value; }

/// The post-processing's own budget [s] (collocation and spline solves run after planning).
double PostProcessingBudget(const v1::TrajectoryOptions& options) {
  switch (options.post_processing()) {
    case v1::TrajectoryOptions::COLLOCATION: return Defaulted(options.collocation().time_budget(), 60.0);
    case v1::TrajectoryOptions::SPLINE: return Defaulted(options.spline().time_budget(), 5.0);
    case v1::TrajectoryOptions::POST_PROCESSING_UNSPECIFIED:
      return options.max_jerk_size() > 0 ? Defaulted(options.collocation().time_budget(), 60.0) : 0.0;
    default: return 0.0;
  }
}

/// The fields that set how long a call runs, with their values [s], per request type.
using BudgetFields = std::vector<std::pair<std::string, double>>;
BudgetFields BudgetsOf(const v1::PlanRequest& r) {
  BudgetFields fields{{"time_budget", Defaulted(r.time_budget(), 5.0)}};
  if (const double post = PostProcessingBudget(r.trajectory()); post > 0.0) fields.push_back({"trajectory post-processing time_budget", post});
  return fields;
}
BudgetFields BudgetsOf(const v1::OptimizeRequest& r) {
  BudgetFields fields{{"time_budget", Defaulted(r.time_budget(), 10.0)}};
  if (const double post = PostProcessingBudget(r.options()); post > 0.0) fields.push_back({"options post-processing time_budget", post});
  return fields;
}
BudgetFields BudgetsOf(const v1::CoordinateRequest& r) { return {{"time_budget", Defaulted(r.time_budget(), 30.0)}}; }
BudgetFields BudgetsOf(const v1::InverseKinematicsRequest& r) { return {{"time_budget", Defaulted(r.time_budget(), 0.05)}}; }
BudgetFields BudgetsOf(const v1::CartesianPathRequest& r) {
  BudgetFields fields{{"time_budget", Defaulted(r.time_budget(), 10.0)}};
  if (const double post = PostProcessingBudget(r.options()); post > 0.0) fields.push_back({"options post-processing time_budget", post});
  return fields;
}
template <typename Request>
BudgetFields BudgetsOf(const Request&) {
  return {};
}

/// A call's cancellation, reaching the Termination of the job running for it: a job started
/// after the client cancelled starts cancelled. Thread-safe (gRPC calls Cancel on its thread).
class CallCancellation {
 public:
  /// The job's Termination; if the call was already cancelled, it is cancelled too.
  Termination Start(Clock::time_point budget_end, Clock::time_point call_deadline) {
    std::lock_guard<std::mutex> lock(mutex_);
    termination_.emplace(budget_end, call_deadline);
    if (cancelled_) termination_->Cancel();
    return *termination_;
  }
  bool cancelled() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return cancelled_;
  }
  void Cancel() {
    std::lock_guard<std::mutex> lock(mutex_);
    cancelled_ = true;
    if (termination_) termination_->Cancel();
  }

 private:
  mutable std::mutex mutex_;
  bool cancelled_ = false;
  std::optional<Termination> termination_;
};

// ---- One unary call -----------------------------------------------------------------------

/// Everything one unary call owns: its parsed request, its response, its record (log line and
/// metrics), and its cancellation, which reaches the running job's Termination. The request is
/// parsed here from the raw bytes so a malformed message gets INVALID_ARGUMENT with a reason
/// (gRPC's generated handler answers UNIMPLEMENTED with no message).
template <typename Request, typename Response>
class UnaryCall final : public grpc::ServerUnaryReactor {
 public:
  UnaryCall(const char* rpc, grpc::CallbackServerContext* context, grpc::ByteBuffer* reply,
            std::function<void(const RequestRecord&)> on_done)
      : context(context), arrival(Clock::now()), deadline(SteadyDeadline(*context)), reply_(reply),
        on_done_(std::move(on_done)) {
    record.rpc = rpc;
  }

  /// Parses the request bytes. False (and the call finished with INVALID_ARGUMENT) when they
  /// are not a `Request`.
  bool Parse(const grpc::ByteBuffer* bytes) {
    request_bytes_ = bytes->Length();
    grpc::ByteBuffer copy(*bytes);
    grpc::ProtoBufferReader reader(&copy);
    if (request.ParseFromZeroCopyStream(&reader)) return true;
    Complete(grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                          "the request is not a valid " + Request::descriptor()->full_name() + " message (" +
                              std::to_string(bytes->Length()) +
                              " bytes that do not parse as protobuf wire format of that type); check that the "
                              "client and server use the same chasles.v1 proto"));
    return false;
  }

  /// Creates the job's Termination; if the call was already cancelled, it is cancelled too.
  Termination Start(Clock::time_point budget_end, Clock::time_point call_deadline) {
    return cancellation_.Start(budget_end, call_deadline);
  }
  bool cancelled() const { return cancellation_.cancelled(); }
  void OnCancel() override { cancellation_.Cancel(); }
  /// The call's buffers (request, response, gRPC's) are freed here, after the answer left; a call
  /// that held much gives the free heap back to the system then, so RSS returns to its level.
  void OnDone() override {
    const bool large = record.peak_heap_bytes > kTrimAboveBytes || request_bytes_ > kTrimAboveBytes;
    delete this;
    if (large) ReleaseFreeHeapMemory();
  }
  /// Calls whose peak heap or request exceeds this are followed by giving free memory back.
  static constexpr std::uint64_t kTrimAboveBytes = 16ull << 20;

  /// Serialises the response (when OK), records and logs the call, and finishes it. Called once.
  void Complete(grpc::Status status) {
    if (status.ok()) {
      grpc::ProtoBufferWriter writer(reply_, grpc::kProtoBufferWriterMaxBufferLength, response.ByteSizeLong());
      if (!response.SerializeToZeroCopyStream(&writer)) {
        status = grpc::Status(grpc::StatusCode::INTERNAL, "internal error: the response could not be serialised");
      }
    }
    if (!status.ok()) status = grpc::Status(status.error_code(), StatusMessage(status.error_message()));
    record.status_code = static_cast<int>(status.error_code());
    record.status_message = status.error_message();
    record.total_seconds = SecondsSince(arrival);
    if (on_done_) on_done_(record);
    Finish(status);
  }

  grpc::CallbackServerContext* const context;
  const Clock::time_point arrival;
  const Clock::time_point deadline;
  Request request;
  Response response;
  RequestRecord record;

 private:
  grpc::ByteBuffer* const reply_;
  std::size_t request_bytes_ = 0;
  std::function<void(const RequestRecord&)> on_done_;
  CallCancellation cancellation_;
};

/// Thrown from pool work to finish the call with DEADLINE_EXCEEDED.
struct DeadlineError {
  std::string message;
};

/// Thrown from work to finish the call with this status (after the response was filled).
struct StatusError {
  grpc::Status status;
};

using RawService = v1::Planning::WithRawCallbackMethod_Plan<v1::Planning::WithRawCallbackMethod_ListPlanners<
    v1::Planning::WithRawCallbackMethod_UploadRobot<v1::Planning::WithRawCallbackMethod_UploadScene<
        v1::Planning::WithRawCallbackMethod_UpdateScene<v1::Planning::WithRawCallbackMethod_InverseKinematics<
            v1::Planning::WithRawCallbackMethod_CartesianPath<
            v1::Planning::WithRawCallbackMethod_Optimize<v1::Planning::WithRawCallbackMethod_Coordinate<
                v1::Planning::WithRawCallbackMethod_CreateWorkcell<v1::Planning::WithRawCallbackMethod_CommitTrajectory<
                    v1::Planning::WithRawCallbackMethod_Release<v1::Planning::WithRawCallbackMethod_Benchmark<
                        v1::Planning::WithRawCallbackMethod_StopBenchmark<
                            v1::Planning::WithRawCallbackMethod_OpenFleetSession<
                                v1::Planning::WithRawCallbackMethod_AssignFleetGoals<
                                    v1::Planning::WithRawCallbackMethod_CloseFleetSession<
                                        v1::Planning::WithRawCallbackMethod_StreamFleetSession<
                                            v1::Planning::WithRawCallbackMethod_Replan<
                                            v1::Planning::Service>>>>>>>>>>>>>>>>>>>;

/// The service's collaborators and its share of the server options.
struct ServiceContext {
  const PlannerRegistry* registry = nullptr;
  ModelStore* store = nullptr;
  ThreadPool* pool = nullptr;
  WorkcellStore* workcells = nullptr;
  const AccessControl* access = nullptr;  ///< tokens and roles (the credentials checked them already)
  const ServerOptions* options = nullptr;
  ServerMetrics* metrics = nullptr;  ///< counts every call; never null
  RecentExchanges* recent = nullptr;  ///< kept for the viewer (--http-listen); null = none kept
};

class PlanningService final : public RawService {
 public:
  explicit PlanningService(const ServiceContext& services)
      : services_(services),
        registry_(*services.registry),
        pipeline_(*services.registry),
        store_(services.store),
        pool_(services.pool),
        workcells_(services.workcells),
        access_(services.access),
        options_(*services.options),
        log_format_(options_.log_format == "json" ? LogFormat::kJson : LogFormat::kText) {}

  grpc::ServerUnaryReactor* Plan(grpc::CallbackServerContext* context, const grpc::ByteBuffer* in,
                                 grpc::ByteBuffer* out) override {
    return Serve<v1::PlanRequest, v1::PlanResponse>("Plan", context, in, out, Where::kPool,
                                                    [this](auto& call) { RunPlan(call); });
  }

  grpc::ServerUnaryReactor* Optimize(grpc::CallbackServerContext* context, const grpc::ByteBuffer* in,
                                     grpc::ByteBuffer* out) override {
    return Serve<v1::OptimizeRequest, v1::OptimizeResponse>("Optimize", context, in, out, Where::kPool, [this](auto& call) {
      v1::OptimizeResponse& response = call.response;
      call.record.request_id = RequestId(call.request.request_id(), "opt");
      response.set_request_id(call.record.request_id);
      StoredRobot robot = RobotOfRequest(*store_, call.request);
      // A planning group: the other joints held where the first waypoint puts them.
      v1::OptimizeRequest grouped;
      std::vector<std::string> warnings;
      if (!call.request.group().empty()) {
        grouped = call.request;
        robot = NarrowToGroup(robot, &grouped, &warnings);
        call.record.fields.push_back({"group", call.request.group()});
      }
      const v1::OptimizeRequest& request = call.request.group().empty() ? call.request : grouped;
      const std::string robot_id = robot.id;  // the robot as described (ids of carried loads are internal)
      robot = store_->Carrying(robot, request.attached_objects(), "attached_objects", &warnings);
      const StoredScene scene = SceneOfRequest(*store_, request);
      response.set_robot_id(robot_id);
      response.set_scene_id(scene.id);
      RequestSettings settings;
      double input_duration = 0.0;
      const double padding = PaddingFromProto(request.padding(), "padding");
      OptimizeQuery query =
          OptimizeQueryFromProto(request, store_->Checker(robot, scene, padding), &settings, &input_duration);
      ApplyReplyCap(&query.sample_cap);
      const Termination termination = call.Start(BudgetEnd(settings.time_budget, call.deadline), call.deadline);
      const OptimizeOutcome outcome = OptimizePath(query, termination);
      OptimizeOutcomeToProto(outcome, query, &response, request.options().knots_only());
      response.set_input_duration(input_duration);
      for (const std::string& w : warnings) response.add_warnings(w);
      call.record.outcome = v1::PlanOutcome_Name(response.outcome());
      call.record.fields.insert(call.record.fields.end(), {{"robot", IdPrefix(robot.id)},
                            {"scene", IdPrefix(scene.id)},
                            {"waypoints", std::to_string(query.path.size())},
                            {"method", ToString(outcome.stage.optimizer.requested)},
                            {"used", ToString(outcome.stage.optimizer.used)},
                            {"duration_s", FormatNumber(response.duration())}});
      call.record.stages = {{"parameterize", outcome.stage.parameterize_seconds},
                            {"optimize", outcome.stage.optimize_seconds},
                            {"verify", outcome.stage.verify_seconds}};
    });
  }

  grpc::ServerUnaryReactor* ListPlanners(grpc::CallbackServerContext* context, const grpc::ByteBuffer* in,
                                         grpc::ByteBuffer* out) override {
    return Serve<v1::ListPlannersRequest, v1::ListPlannersResponse>(
        "ListPlanners", context, in, out, Where::kInline, [this](auto& call) {
          for (const PlannerSpec& spec : registry_.List()) PlannerSpecToProto(spec, call.response.add_planners());
        });
  }

  grpc::ServerUnaryReactor* UploadRobot(grpc::CallbackServerContext* context, const grpc::ByteBuffer* in,
                                        grpc::ByteBuffer* out) override {
    return Serve<v1::UploadRobotRequest, v1::UploadRobotResponse>(
        "UploadRobot", context, in, out, Where::kPool, [this](auto& call) {
          const StoredRobot robot = store_->AddRobot(call.request.robot(), "robot");
          call.response.set_robot_id(robot.id);
          const RobotModel& model = *robot.model;
          for (const std::string& warning : RobotWarnings(model, "robot")) call.response.add_warnings(warning);
          for (const std::string& warning : robot.group_warnings) call.response.add_warnings(warning);
          for (const PlanningGroup& group : robot.groups) {
            v1::PlanningGroupInfo* info = call.response.add_groups();
            info->set_name(group.name);
            for (int dof : group.dofs) info->add_joint_names(model.dof_names()[dof]);
          }
          for (int i = 0; i < model.num_dofs(); ++i) {
            call.response.add_joint_names(model.dof_names()[i]);
            call.response.add_lower_limits(model.lower_limits()[i]);
            call.response.add_upper_limits(model.upper_limits()[i]);
            call.response.add_velocity_limits(model.velocity_limits()[i]);
          }
          v1::CollisionModel& collision = *call.response.mutable_collision_model();
          collision.set_kind(robot.fit != nullptr ? "fitted_spheres" : "shapes");
          if (robot.fit != nullptr) {
            collision.set_spheres(robot.fit->spheres);
            collision.set_shapes_fitted(robot.fit->shapes_fitted);
            collision.set_reach(robot.fit->reach);
            collision.set_reach_link(robot.fit->reach_link);
            collision.set_fit_seconds(robot.fit->seconds);
          }
          call.record.fields = {{"robot", IdPrefix(robot.id)}, {"name", model.name()}, {"dofs", std::to_string(model.num_dofs())}};
          if (robot.fit != nullptr) call.record.fields.push_back({"fitted_spheres", std::to_string(robot.fit->spheres)});
        });
  }

  grpc::ServerUnaryReactor* UploadScene(grpc::CallbackServerContext* context, const grpc::ByteBuffer* in,
                                        grpc::ByteBuffer* out) override {
    return Serve<v1::UploadSceneRequest, v1::UploadSceneResponse>(
        "UploadScene", context, in, out, Where::kPool, [this](auto& call) {
          const StoredScene scene = store_->AddScene(call.request.scene(), "scene");
          call.response.set_scene_id(scene.id);
          call.record.fields = {{"scene", IdPrefix(scene.id)},
                                {"objects", std::to_string(scene.scene->objects().size())},
                                {"maps", std::to_string(scene.scene->occupancy_maps().size())}};
        });
  }

  grpc::ServerUnaryReactor* UpdateScene(grpc::CallbackServerContext* context, const grpc::ByteBuffer* in,
                                        grpc::ByteBuffer* out) override {
    return Serve<v1::UpdateSceneRequest, v1::UpdateSceneResponse>(
        "UpdateScene", context, in, out, Where::kPool, [this](auto& call) {
          const StoredScene base =
              call.request.scene_id().empty() ? store_->default_scene() : store_->FindScene(call.request.scene_id());
          InsertPoints(call.request, base, &call.response, &call.record.fields);
        });
  }

  /// UpdateScene's work: `request`'s points into `base` (request.scene_id is base's), the new
  /// scene stored under its content id and returned; *response and *fields filled.
  StoredScene InsertPoints(const v1::UpdateSceneRequest& request, const StoredScene& base,
                           v1::UpdateSceneResponse* response, std::vector<std::pair<std::string, std::string>>* fields) {
    const PointCloudInsertion insertion = PointCloudInsertionFromProto(request);
    PointCloudInsertionStats stats;
    std::shared_ptr<const Scene> updated;
    std::uint64_t bytes = 0;
    {
      HeapScope measure;
      updated = std::make_shared<const Scene>(base.scene->InsertPointCloud(insertion, &stats, store_->limits()));
      bytes = static_cast<std::uint64_t>(std::max<std::int64_t>(measure.live_bytes(), 0));
    }
    // Content id: the base scene's id and the update (the same update of the same scene gives
    // the same id).
    v1::UpdateSceneRequest key = request;
    key.set_scene_id(base.id);
    const StoredScene scene = store_->PutScene(ProtoContentId(key), std::move(updated), bytes);
    response->set_scene_id(scene.id);
    response->set_octomap(stats.octomap);
    response->set_points_inserted(stats.points_inserted);
    response->set_occupied_leaves(stats.occupied_leaves);
    response->set_resolution(stats.resolution);
    response->set_seconds(stats.seconds);
    *fields = {{"scene", IdPrefix(base.id) + "->" + IdPrefix(scene.id)},
               {"map", stats.octomap + (stats.created ? " (new)" : "")},
               {"points", std::to_string(stats.points_inserted)},
               {"occupied", std::to_string(stats.occupied_leaves)}};
    return scene;
  }

  grpc::ServerUnaryReactor* InverseKinematics(grpc::CallbackServerContext* context, const grpc::ByteBuffer* in,
                                              grpc::ByteBuffer* out) override {
    return Serve<v1::InverseKinematicsRequest, v1::InverseKinematicsResponse>(
        "InverseKinematics", context, in, out, Where::kPool, [this](auto& call) {
          v1::InverseKinematicsResponse& response = call.response;
          // Robot (inline, id or default) and, for collision_free, the scene's cached checker;
          // with a planning group, the robot held outside it at initial_guess.
          StoredRobot robot = RobotOfRequest(*store_, call.request);
          response.set_robot_id(robot.id);
          v1::InverseKinematicsRequest grouped;
          if (!call.request.group().empty()) {
            grouped = call.request;
            robot = NarrowToGroup(robot, &grouped);
          }
          const v1::InverseKinematicsRequest& request = call.request.group().empty() ? call.request : grouped;
          IkRequest ik = IkRequestFromProto(request, *robot.model);
          std::string scene_id = "-";
          std::shared_ptr<const CollisionChecker> checker;
          if (request.collision_free()) {
            const StoredScene scene = SceneOfRequest(*store_, request);
            scene_id = IdPrefix(scene.id);
            checker = store_->Checker(robot, scene);
            ik.accept = [checker](const Eigen::VectorXd& q) { return checker->IsValid(q); };
          }
          // The solver's budget ends before the gRPC deadline, leaving time for the answer.
          const double left = std::chrono::duration<double>(call.deadline - Clock::now()).count();
          ik.time_budget = std::min(ik.time_budget, std::max(1e-3, 0.9 * left));
          ik.stop = [&call] { return call.cancelled(); };
          const IkResult result = SolveIk(*robot.model, ik);
          IkResultToProto(result, ik, *robot.model, &response);
          call.record.outcome = response.solved() ? "SOLVED" : "UNSOLVED";
          call.record.fields = {{"robot", IdPrefix(robot.id)},
                                {"scene", scene_id},
                                {"link", robot.model->links()[ik.link].name},
                                {"solutions", std::to_string(response.solutions_size()) + "/" + std::to_string(ik.max_solutions)},
                                {"attempts", std::to_string(result.attempts)}};
          if (!response.solved()) call.record.fields.push_back({"message", result.message});
        });
  }

  grpc::ServerUnaryReactor* CartesianPath(grpc::CallbackServerContext* context, const grpc::ByteBuffer* in,
                                          grpc::ByteBuffer* out) override {
    return Serve<v1::CartesianPathRequest, v1::CartesianPathResponse>(
        "CartesianPath", context, in, out, Where::kPool, [this](auto& call) {
          const v1::CartesianPathRequest& request = call.request;
          v1::CartesianPathResponse& response = call.response;
          call.record.request_id = RequestId(request.request_id(), "cart");
          response.set_request_id(call.record.request_id);
          std::vector<std::string> warnings;
          const StoredRobot described = RobotOfRequest(*store_, request);
          const StoredRobot robot = store_->Carrying(described, request.attached_objects(), "attached_objects", &warnings);
          for (const std::string& w : warnings) response.add_warnings(w);
          const StoredScene scene = SceneOfRequest(*store_, request);
          response.set_robot_id(described.id);
          response.set_scene_id(scene.id);
          const double padding = PaddingFromProto(request.padding(), "padding");
          const std::shared_ptr<const CollisionChecker> checker = store_->Checker(robot, scene, padding);
          const CartesianSpec spec = CartesianSpecFromProto(request, *robot.model);
          const Eigen::VectorXd start =
              ConfigurationFromProto(request.start().positions(), *robot.model, "start.positions", 0.0, nullptr);
          const auto t0 = Clock::now();
          const CartesianPathResult path =
              ComputeCartesianPath(*checker, start, spec, [&call] { return call.cancelled(); });
          response.set_seconds(std::chrono::duration<double>(Clock::now() - t0).count());
          CartesianResultToProto(path, *robot.model, &response);
          call.record.fields = {{"robot", IdPrefix(robot.id)},
                                {"scene", IdPrefix(scene.id)},
                                {"stop", ToString(path.stop)},
                                {"fraction", FormatNumber(path.fraction)},
                                {"states", std::to_string(path.path.size())}};
          if (path.path.size() < 2) {
            call.record.outcome = "UNSOLVED";  // nothing to time (the stop says why)
            if (!path.message.empty()) call.record.fields.push_back({"message", path.message});
            return;
          }
          // The states, timed as Optimize times a path.
          const v1::OptimizeRequest timing = CartesianTimingRequest(request, response);
          RequestSettings settings;
          double input_duration = 0.0;
          OptimizeQuery query = OptimizeQueryFromProto(timing, checker, &settings, &input_duration);
          ApplyReplyCap(&query.sample_cap);
          const Termination termination = call.Start(BudgetEnd(settings.time_budget, call.deadline), call.deadline);
          const OptimizeOutcome outcome = OptimizePath(query, termination);
          OptimizeOutcomeToProto(outcome, query, response.mutable_timed(), request.options().knots_only());
          const auto t_line = Clock::now();
          if (outcome.code == TrajectoryStageCode::kSuccess) {
            response.set_trajectory_line_deviation(
                TrajectoryLineDeviation(*robot.model, spec, start, outcome.stage.trajectory));
          }
          call.record.outcome = v1::PlanOutcome_Name(response.timed().outcome());
          call.record.stages = {{"cartesian", response.seconds()},
                                {"parameterize", outcome.stage.parameterize_seconds},
                                {"optimize", outcome.stage.optimize_seconds},
                                {"verify", outcome.stage.verify_seconds},
                                {"quality", outcome.stage.quality_seconds},
                                {"sample", outcome.sample_seconds},
                                {"line_deviation", std::chrono::duration<double>(Clock::now() - t_line).count()}};
        });
  }

  grpc::ServerUnaryReactor* Coordinate(grpc::CallbackServerContext* context, const grpc::ByteBuffer* in,
                                       grpc::ByteBuffer* out) override {
    return Serve<v1::CoordinateRequest, v1::CoordinateResponse>(
        "Coordinate", context, in, out, Where::kPool, [this](auto& call) {
          const v1::CoordinateRequest& request = call.request;
          v1::CoordinateResponse& response = call.response;
          call.record.request_id = RequestId(request.request_id(), "team");
          response.set_request_id(call.record.request_id);
          const StoredScene scene = SceneOfRequest(*store_, request);
          response.set_scene_id(scene.id);
          std::vector<std::string> warnings;
          // Robots with a planning group: held outside it where their start puts them.
          v1::CoordinateRequest grouped;
          std::map<std::string, std::shared_ptr<const RobotModel>> held;
          NarrowTeamToGroups(request, &grouped, &held, &warnings);
          const v1::CoordinateRequest& team = grouped.robots_size() > 0 ? grouped : request;
          CoordinationQuery query = CoordinationQueryFromProto(
              team, scene.scene,
              [this, &held, &warnings](const v1::TeamRobot& robot, const std::string& field) {
                const auto it = held.find(field);
                return it != held.end() ? it->second : TeamRobotOf(robot, field, &warnings).model;
              },
              registry_, &warnings, options_.max_team_robots);
          for (int k = 0; k < request.robots_size(); ++k) {
            if (!request.robots(k).has_robot()) continue;  // an uploaded robot reported them at upload
            const std::string field = "robots[" + std::to_string(k) + "].robot";
            // A grouped robot's held model has no load warnings: they are the described robot's.
            const std::shared_ptr<const RobotModel> described =
                request.robots(k).group().empty() ? query.robots[static_cast<std::size_t>(k)].placement.model
                                                  : TeamRobotOf(request.robots(k), "robots[" + std::to_string(k) + "]").model;
            for (const std::string& w : RobotWarnings(*described, field)) response.add_warnings(w);
          }
          for (const std::string& w : warnings) response.add_warnings(w);
          ApplyReplyCap(&query.sample_cap, query.robots.size());
          query.scene_id = scene.id;
          query.lattice_cache = &fleet_lattices_;
          if (request.has_workcell()) {
            const double origin =
                request.workcell().start_time() == 0.0 ? workcells_->Now() : request.workcell().start_time();
            response.set_start_time(origin);
            for (const Reservation& r : workcells_->Active(request.workcell().name())) {
              const bool own = std::any_of(query.robots.begin(), query.robots.end(), [&r](const TeamRobotSpec& robot) {
                return robot.placement.name == r.robot_name;
              });
              if (!own) query.committed.push_back(MotionOf(r, origin));
            }
          }
          const Termination termination = call.Start(BudgetEnd(query.time_budget, call.deadline), call.deadline);
          const CoordinationOutcome outcome = chasles::Coordinate(query, registry_, termination);
          CoordinationOutcomeToProto(outcome, query, &response, KnotsFor(team));
          call.record.outcome = v1::PlanOutcome_Name(response.outcome());
          call.record.fields = {
              {"scene", IdPrefix(scene.id)},
              {"robots", std::to_string(request.robots_size())},
              {"method", ToString(query.method)},
              {"used", outcome.code == CoordinationCode::kSuccess ? ToString(outcome.method) : "-"},
              {"makespan_s", FormatNumber(outcome.makespan)},
              {"reorderings", std::to_string(outcome.reorderings)},
              {"states", std::to_string(static_cast<unsigned long long>(outcome.verification.states_checked))}};
          if (outcome.code == CoordinationCode::kDeadlineExceeded) {
            throw DeadlineError{"the gRPC deadline passed before coordination finished"};
          }
        });
  }

  grpc::ServerUnaryReactor* CreateWorkcell(grpc::CallbackServerContext* context, const grpc::ByteBuffer* in,
                                           grpc::ByteBuffer* out) override {
    return Serve<v1::CreateWorkcellRequest, v1::CreateWorkcellResponse>(
        "CreateWorkcell", context, in, out, Where::kInline, [this](auto& call) {
          call.response.set_created(workcells_->Create(call.request.name()));
          call.response.set_active_reservations(static_cast<std::uint32_t>(workcells_->ActiveCount(call.request.name())));
          call.response.set_now(workcells_->Now());
          call.record.fields = {{"workcell", call.request.name()}, {"created", call.response.created() ? "1" : "0"}};
        });
  }

  grpc::ServerUnaryReactor* CommitTrajectory(grpc::CallbackServerContext* context, const grpc::ByteBuffer* in,
                                             grpc::ByteBuffer* out) override {
    return Serve<v1::CommitTrajectoryRequest, v1::CommitTrajectoryResponse>(
        "CommitTrajectory", context, in, out, Where::kPool, [this](auto& call) {
          const v1::CommitTrajectoryRequest& request = call.request;
          v1::CommitTrajectoryResponse& response = call.response;
          if (request.robot_name().empty()) ThrowInvalid("robot_name is empty: name the robot that moves");
          if (static_cast<std::uint64_t>(request.trajectory().points_size()) > options_.max_samples) {
            ThrowResourceExhausted("trajectory.points has " + std::to_string(request.trajectory().points_size()) +
                                   " points, more than the server's cap of " + std::to_string(options_.max_samples) +
                                   " (--max-samples); commit a coarser trajectory (the server interpolates between "
                                   "points with cubic Hermite pieces)");
          }
          const Reservation reservation = ReservationFromCommit(request, *store_, workcells_->Now());
          const Reservation committed =
              workcells_->Commit(request.workcell(), reservation, request.hold(), request.robot_padding());
          response.set_reservation_id(committed.id);
          response.set_start_time(committed.start_time);
          response.set_end_time(committed.end_time);
          response.set_expires_at(committed.expires_at);
          response.set_active_reservations(static_cast<std::uint32_t>(workcells_->ActiveCount(request.workcell())));
          call.record.fields = {{"workcell", request.workcell()},
                                {"robot", request.robot_name()},
                                {"reservation", committed.id},
                                {"duration_s", FormatNumber(committed.end_time - committed.start_time)},
                                {"hold_s", FormatNumber(committed.expires_at - committed.end_time)}};
        });
  }

  grpc::ServerUnaryReactor* OpenFleetSession(grpc::CallbackServerContext* context, const grpc::ByteBuffer* in,
                                             grpc::ByteBuffer* out) override {
    return Serve<v1::OpenFleetSessionRequest, v1::OpenFleetSessionResponse>(
        "OpenFleetSession", context, in, out, Where::kPool, [this](auto& call) {
          const v1::OpenFleetSessionRequest& request = call.request;
          call.record.request_id = RequestId(request.request_id(), "fleet");
          CheckName("name", request.name());  // before the lattice is built
          const StoredScene scene = SceneOfRequest(*store_, request);
          const double start_time = ClockTimeFromProto(request.start_time(), workcells_->Now(), "start_time");
          std::map<std::string, StoredRobot> resolved;  // by field, each robot resolved once
          std::shared_ptr<OpenFleet> fleet = OpenFleetFromProto(
              request, scene.scene, scene.id,
              [this, &resolved](const v1::TeamRobot& robot, const std::string& field) {
                return (resolved[field] = TeamRobotOf(robot, field)).model;
              },
              start_time, options_.max_team_robots, &fleet_lattices_, &call.response);
          // The record another replica rebuilds the session from: robots and scene by id.
          v1::OpenFleetSessionRequest record = request;
          record.set_scene_id(scene.id);
          record.set_start_time(start_time);
          for (int k = 0; k < request.robots_size(); ++k) {
            if (!request.robots(k).has_robot()) continue;  // an uploaded robot reported them at upload
            const StoredRobot& stored = resolved.at("robots[" + std::to_string(k) + "]");
            for (const std::string& w : RobotWarnings(*stored.model, "robots[" + std::to_string(k) + "].robot")) {
              call.response.add_warnings(w);
            }
            record.mutable_robots(k)->set_robot_id(stored.id);
          }
          fleet_sessions_.Add(request.name(), std::move(fleet), record);
          call.record.fields = {{"session", request.name()},
                                {"scene", IdPrefix(scene.id)},
                                {"robots", std::to_string(request.robots_size())},
                                {"resolution_m", FormatNumber(call.response.lattice().resolution())}};
        });
  }

  grpc::ServerUnaryReactor* AssignFleetGoals(grpc::CallbackServerContext* context, const grpc::ByteBuffer* in,
                                             grpc::ByteBuffer* out) override {
    return Serve<v1::AssignFleetGoalsRequest, v1::AssignFleetGoalsResponse>(
        "AssignFleetGoals", context, in, out, Where::kPool, [this](auto& call) {
          const v1::AssignFleetGoalsRequest& request = call.request;
          call.record.request_id = RequestId(request.request_id(), "goals");
          const Termination termination = call.Start(BudgetEnd(30.0, call.deadline), call.deadline);
          AssignFleetGoalsBatch(request.name(), request, termination, &call.response);
          int solved = 0;
          for (const v1::FleetGoalResult& result : call.response.results()) solved += result.outcome() == v1::SUCCESS;
          call.record.fields = {{"session", request.name()},
                                {"goals", std::to_string(request.goals_size())},
                                {"states", std::to_string(request.states_size())},
                                {"solved", std::to_string(solved)},
                                {"plans", std::to_string(call.response.plans_size())}};
        });
  }

  grpc::ServerUnaryReactor* CloseFleetSession(grpc::CallbackServerContext* context, const grpc::ByteBuffer* in,
                                              grpc::ByteBuffer* out) override {
    return Serve<v1::CloseFleetSessionRequest, v1::CloseFleetSessionResponse>(
        "CloseFleetSession", context, in, out, Where::kInline, [this](auto& call) {
          call.response.set_closed(fleet_sessions_.Close(call.request.name()));
          call.record.fields = {{"session", call.request.name()},
                                {"closed", call.response.closed() ? "true" : "false"}};
        });
  }

  grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>* StreamFleetSession(
      grpc::CallbackServerContext* context) override {
    return new FleetStream(this, context);
  }

  grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>* Replan(grpc::CallbackServerContext* context) override {
    return new ReplanStream(this, context);
  }

  grpc::ServerUnaryReactor* Release(grpc::CallbackServerContext* context, const grpc::ByteBuffer* in,
                                    grpc::ByteBuffer* out) override {
    return Serve<v1::ReleaseRequest, v1::ReleaseResponse>(
        "Release", context, in, out, Where::kInline, [this](auto& call) {
          const v1::ReleaseRequest& request = call.request;
          const int released = workcells_->Release(request.workcell(), request.reservation_id(), request.robot_name());
          call.response.set_released(static_cast<std::uint32_t>(released));
          call.response.set_active_reservations(static_cast<std::uint32_t>(workcells_->ActiveCount(request.workcell())));
          call.record.fields = {{"workcell", request.workcell()},
                                {"reservation", request.reservation_id()},
                                {"robot", request.robot_name()},
                                {"released", std::to_string(released)}};
        });
  }

  grpc::ServerWriteReactor<grpc::ByteBuffer>* Benchmark(grpc::CallbackServerContext* context,
                                                        const grpc::ByteBuffer* in) override {
    if (grpc::Status refused = access_->Authorize(*context, "Benchmark"); !refused.ok()) {
      return RefuseStream(*context, refused);
    }
    v1::BenchmarkRequest request;
    {
      grpc::ByteBuffer copy(*in);
      grpc::ProtoBufferReader reader(&copy);
      if (!request.ParseFromZeroCopyStream(&reader)) {
        return RefuseStream(*context, grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                                                   "the request is not a valid chasles.v1.BenchmarkRequest message (" +
                                                       std::to_string(in->Length()) +
                                                       " bytes that do not parse as protobuf wire format of that "
                                                       "type); check that the client and server use the same "
                                                       "chasles.v1 proto"));
      }
    }
    const double run_budget = Defaulted(request.run_budget(), 5.0);
    if (const grpc::Status refused = CheckBudgets({{"run_budget", run_budget}}); !refused.ok()) {
      return RefuseStream(*context, refused);
    }
    const std::string request_id = RequestId(request.request_id(), "bench");
    BenchmarkServices services;
    services.registry = &registry_;
    services.pipeline = &pipeline_;
    services.store = store_;
    services.pool = pool_;
    services.ticket.client = ClientOf(*context);
    services.ticket.long_running = run_budget > options_.long_budget;
    if (options_.log_requests) {
      const std::size_t cap = options_.log_field_max;
      services.log = [cap](const std::string& line) {
        std::fprintf(stderr, "chasles-server: %s\n", EscapeForLog(line, 8 * cap).c_str());
      };
    }
    return StartBenchmark(services, &benchmarks_, &request, request_id, SteadyDeadline(*context));
  }

  grpc::ServerUnaryReactor* StopBenchmark(grpc::CallbackServerContext* context, const grpc::ByteBuffer* in,
                                          grpc::ByteBuffer* out) override {
    return Serve<v1::StopBenchmarkRequest, v1::StopBenchmarkResponse>(
        "StopBenchmark", context, in, out, Where::kInline, [this](auto& call) {
          const std::string& id = call.request.request_id();
          call.record.request_id = id;
          if (id.empty()) {
            throw StatusError{grpc::Status(grpc::StatusCode::INVALID_ARGUMENT, "request_id is empty: name the running benchmark")};
          }
          if (!benchmarks_.Stop(id)) {
            throw StatusError{grpc::Status(grpc::StatusCode::NOT_FOUND,
                                           "request_id = '" + EscapeForLog(id, options_.log_field_max) +
                                               "' names no running benchmark (finished, or never started)")};
          }
          call.response.set_stopped(true);
        });
  }

  /// A call the credentials refused before any handler ran (see AccessControl): one log line and
  /// its metrics, like every other call; the client is the token's name when it was known.
  /// Fleet sessions in the shared store (before serving): a session opened on another replica is
  /// rebuilt here from its record, with this replica's model store and lattice cache.
  void UseSharedFleets(std::shared_ptr<RedisClient> redis) {
    fleet_sessions_.UseShared(std::move(redis), [this](const v1::OpenFleetSessionRequest& record) {
      const StoredScene scene = SceneOfRequest(*store_, record);
      v1::OpenFleetSessionResponse ignored;
      return OpenFleetFromProto(
          record, scene.scene, scene.id,
          [this](const v1::TeamRobot& robot, const std::string& field) { return TeamRobotOf(robot, field).model; },
          record.start_time(), options_.max_team_robots, &fleet_lattices_, &ignored);
    });
  }

  /// Shutting down: from now on every new unary call is refused with UNAVAILABLE (clients retry
  /// it on another replica); calls already accepted run to their end.
  void StartDraining() { draining_.store(true); }
  /// Unary calls accepted and not yet answered.
  int in_flight() const { return in_flight_.load(); }

  void RecordRefusal(const AccessRefusal& refusal) const {
    RequestRecord record;
    record.rpc = refusal.rpc.substr(refusal.rpc.rfind('/') + 1);
    record.client = refusal.name.empty() ? "-" : refusal.name;
    record.status_code = static_cast<int>(refusal.code);
    record.status_message = refusal.message;
    services_.metrics->RequestStarted(record.rpc);
    Record(record);
  }

 private:
  enum class Where { kInline, kPool };

  /// Runs a call's work inside a HeapScope capped at --request-memory-mb: OK, or the status its
  /// exception maps to (DeadlineError, StatusError, the memory cap, StatusFromException).
  /// *peak_bytes gets the work's peak heap.
  grpc::Status RunCapped(const std::function<void()>& work, std::uint64_t* peak_bytes) const {
    grpc::Status status;
    HeapScope heap(options_.request_memory_mb << 20);
    try {
      work();
    } catch (const DeadlineError& e) {
      status = grpc::Status(grpc::StatusCode::DEADLINE_EXCEEDED, e.message);
    } catch (const StatusError& e) {
      status = e.status;
    } catch (...) {
      status = heap.exceeded() ? MemoryCapStatus() : StatusFromException(std::current_exception());
    }
    *peak_bytes = heap.peak_bytes();
    return status;
  }

  /// One goal-and-state batch of a fleet session (AssignFleetGoals, a StreamFleetSession message).
  void AssignFleetGoalsBatch(const std::string& name, const v1::AssignFleetGoalsRequest& request,
                             const Termination& termination, v1::AssignFleetGoalsResponse* response) {
    if (request.goals_size() > 10000) {
      ThrowInvalid("goals has " + std::to_string(request.goals_size()) + " entries; send at most 10000 at once");
    }
    if (request.states_size() > 100000) {
      ThrowInvalid("states has " + std::to_string(request.states_size()) + " entries; send at most 100000 at once");
    }
    const double now = request.now() == 0.0 ? workcells_->Now() : request.now();
    fleet_sessions_.Assign(name, request, now, termination, response);
  }

  /// A bidirectional stream answered in order (StreamFleetSession, Replan): a message is read,
  /// answered on the pool (fair queue, per-request heap cap) by Respond, the answer written, and
  /// only then the next message read — so answers come in order, a stream holds at most one
  /// worker and a client cannot queue more than one message. An error ends the stream with its
  /// status, the message index in front; the client's half-close ends it with OK. One
  /// RequestRecord for the whole stream.
  template <typename Request, typename Response>
  class OrderedStream : public grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer> {
   public:
    /// `reopen`: what a client should do when the server drains mid-stream.
    OrderedStream(PlanningService* service, grpc::CallbackServerContext* context, const char* rpc, std::string reopen)
        : service_(service), deadline_(SteadyDeadline(*context)), arrival_(Clock::now()), reopen_(std::move(reopen)) {
      record_.rpc = rpc;
      record_.client = service_->ClientOf(*context);
      service_->services_.metrics->RequestStarted(record_.rpc);
      service_->in_flight_.fetch_add(1);
      if (service_->draining_.load()) {
        End(grpc::Status(grpc::StatusCode::UNAVAILABLE,
                         "this server is shutting down and takes no new calls; send it to another replica"));
        return;
      }
      if (grpc::Status refused = service_->access_->Authorize(*context, record_.rpc); !refused.ok()) {
        End(refused);
        return;
      }
      StartRead(&in_);
    }

    void OnReadDone(bool ok) override {
      if (!ok) {  // the client closed its side (or the call ended)
        End(grpc::Status::OK);
        return;
      }
      if (service_->draining_.load()) {
        End(grpc::Status(grpc::StatusCode::UNAVAILABLE, Prefix() + "this server is shutting down; " + reopen_));
        return;
      }
      request_.Clear();
      grpc::ProtoBufferReader reader(&in_);
      if (!request_.ParseFromZeroCopyStream(&reader)) {
        End(grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                         Prefix() + "not a valid " + Request::descriptor()->full_name() + " message (" +
                             std::to_string(in_.Length()) + " bytes); check that the client and server use the "
                             "same chasles.v1 proto"));
        return;
      }
      if (!Accept()) return;
      JobTicket ticket;
      ticket.client = record_.client;
      switch (service_->pool_->TrySubmit([this] { Answer(); }, ticket)) {
        case SubmitResult::kQueued: return;
        case SubmitResult::kClientQueueFull:
        case SubmitResult::kQueueFull:
          End(grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED,
                           Prefix() + "the server's work queue is full; reopen the stream later"));
          return;
        case SubmitResult::kStopping:
          End(grpc::Status(grpc::StatusCode::UNAVAILABLE, Prefix() + "the server is shutting down"));
          return;
      }
    }

    void OnWriteDone(bool ok) override {
      if (!ok) {
        End(grpc::Status(grpc::StatusCode::CANCELLED, "the stream ended before an answer was delivered"));
        return;
      }
      ++answered_;
      StartRead(&in_);
    }

    void OnCancel() override { cancellation_.Cancel(); }

    void OnDone() override {
      record_.fields = Fields();
      record_.total_seconds = SecondsSince(arrival_);
      service_->Record(record_);
      service_->in_flight_.fetch_sub(1);
      delete this;
    }

   protected:
    /// After a message parsed: false ends the stream (the override has called End).
    virtual bool Accept() { return true; }
    /// On a worker: answers request_ (throws Error / StatusError / DeadlineError to end the stream).
    virtual void Respond(Response* response) = 0;
    /// The stream's log fields.
    virtual std::vector<std::pair<std::string, std::string>> Fields() const = 0;

    std::string Prefix() const { return "message " + std::to_string(answered_) + ": "; }

    /// Finishes the stream once, recording its status.
    void End(const grpc::Status& status) {
      const grpc::Status sent(status.error_code(), StatusMessage(status.error_message()));
      record_.status_code = static_cast<int>(sent.error_code());
      record_.status_message = sent.error_message();
      Finish(sent);
    }

    PlanningService* const service_;
    const Clock::time_point deadline_;
    Request request_;
    std::uint64_t answered_ = 0;
    CallCancellation cancellation_;

   private:
    /// On a worker: Respond, then the answer written, or the stream ended.
    void Answer() {
      Response response;
      std::uint64_t peak = 0;
      const grpc::Status status = service_->RunCapped([&] { Respond(&response); }, &peak);
      record_.peak_heap_bytes = std::max(record_.peak_heap_bytes, peak);
      if (!status.ok()) {
        End(grpc::Status(status.error_code(), Prefix() + status.error_message()));
        return;
      }
      out_.Clear();
      grpc::ProtoBufferWriter writer(&out_, grpc::kProtoBufferWriterMaxBufferLength, response.ByteSizeLong());
      if (!response.SerializeToZeroCopyStream(&writer)) {
        End(grpc::Status(grpc::StatusCode::INTERNAL, Prefix() + "the answer could not be serialised"));
        return;
      }
      StartWrite(&out_);
    }

    const Clock::time_point arrival_;
    const std::string reopen_;
    RequestRecord record_;
    grpc::ByteBuffer in_, out_;
  };

  /// One StreamFleetSession call: each message answered as AssignFleetGoals answers it.
  class FleetStream final : public OrderedStream<v1::AssignFleetGoalsRequest, v1::AssignFleetGoalsResponse> {
   public:
    FleetStream(PlanningService* service, grpc::CallbackServerContext* context)
        : OrderedStream(service, context, "StreamFleetSession",
                        "reopen the stream on another replica (the session is shared with --store redis://…)") {}

   private:
    bool Accept() override {
      if (name_.empty()) name_ = request_.name();
      if (!request_.name().empty() && request_.name() != name_) {
        End(grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                         Prefix() + "name = '" + request_.name() + "' differs from the stream's session '" + name_ +
                             "'; one stream serves one session"));
        return false;
      }
      return true;
    }
    void Respond(v1::AssignFleetGoalsResponse* response) override {
      const Termination termination = cancellation_.Start(BudgetEnd(30.0, deadline_), deadline_);
      service_->AssignFleetGoalsBatch(name_, request_, termination, response);
      goals_ += static_cast<std::uint64_t>(request_.goals_size());
      states_ += static_cast<std::uint64_t>(request_.states_size());
    }
    std::vector<std::pair<std::string, std::string>> Fields() const override {
      return {{"session", name_},
              {"messages", std::to_string(answered_)},
              {"goals", std::to_string(goals_)},
              {"states", std::to_string(states_)}};
    }

    std::string name_;
    std::uint64_t goals_ = 0, states_ = 0;
  };

  /// One answer's plan inside a Replan stream: what RunPlan needs of a call.
  struct PlanJob {
    v1::PlanRequest request;
    v1::PlanResponse response;
    RequestRecord record;
    Clock::time_point arrival;
    Clock::time_point deadline;
    CallCancellation* cancellation = nullptr;
    const StoredScene* scene = nullptr;  ///< the stream's scene (not the request's)
    TimedTrajectory trajectory;          ///< set by RunPlan on success: exactly what was returned
    Termination Start(Clock::time_point budget_end, Clock::time_point call_deadline) {
      return cancellation->Start(budget_end, call_deadline);
    }
    bool cancelled() const { return cancellation->cancelled(); }
  };
  StoredScene SceneOfCall(const UnaryCall<v1::PlanRequest, v1::PlanResponse>&, const v1::PlanRequest& request) {
    return SceneOfRequest(*store_, request);
  }
  StoredScene SceneOfCall(const PlanJob& job, const v1::PlanRequest&) { return *job.scene; }
  static void KeepTrajectory(UnaryCall<v1::PlanRequest, v1::PlanResponse>&, const TimedTrajectory&) {}
  static void KeepTrajectory(PlanJob& job, const TimedTrajectory& trajectory) { job.trajectory = trajectory; }

  /// One Replan call (see ReplanRequest), answered in order as OrderedStream does. The stream
  /// keeps its problem, its scene (changed by the messages), its moving obstacles on the stream's
  /// clock and the current trajectory (stream time current_begin_ is its t = 0). An invalid
  /// message ends the stream with INVALID_ARGUMENT naming the message, field and rule; expected
  /// failures are outcomes.
  class ReplanStream final : public OrderedStream<v1::ReplanRequest, v1::ReplanResponse> {
   public:
    ReplanStream(PlanningService* service, grpc::CallbackServerContext* context)
        : OrderedStream(service, context, "Replan", "reopen the stream on another replica with the problem and the state") {}

   private:
    std::vector<std::pair<std::string, std::string>> Fields() const override {
      return {{"messages", std::to_string(answered_)}, {"planned", std::to_string(planned_)}, {"kept", std::to_string(kept_)}};
    }

    void Respond(v1::ReplanResponse* response) override {
      const Clock::time_point started = Clock::now();
      Work(response);
      response->set_sequence(answered_);
      response->set_seconds(SecondsSince(started));
    }

    /// The robot the problem plans for, with what it carries (as RunPlan resolves it).
    StoredRobot Robot() const {
      std::vector<std::string> ignored;
      return service_->store_->Carrying(RobotOfRequest(*service_->store_, problem_), problem_.attached_objects(),
                                        "plan.attached_objects", &ignored);
    }

    /// The work of one message (throws Error / StatusError for invalid input).
    void Work(v1::ReplanResponse* response) {
      const bool first = answered_ == 0;
      // 1. The problem (first message, or a new one) and the time.
      if (first && !request_.has_plan()) {
        ThrowInvalid("plan is required in the first message (the problem: robot, scene, start, goal, planner)");
      }
      const double time = first ? 0.0 : request_.time();
      if (!std::isfinite(time) || time < last_time_) {
        ThrowInvalid("time = " + FormatNumber(time) + " must be finite and >= the previous message's " +
                     FormatNumber(last_time_) + " s");
      }
      if (request_.time_budget() != 0.0 &&
          !(std::isfinite(request_.time_budget()) && request_.time_budget() > 0.0 && request_.time_budget() <= 600.0)) {
        ThrowInvalid("time_budget = " + FormatNumber(request_.time_budget()) + " must be within (0, 600] s (0 = the plan's)");
      }
      bool new_problem = false;
      if (request_.has_plan()) {
        const v1::PlanRequest& plan = request_.plan();
        if (plan.has_workcell()) ThrowInvalid("plan.workcell is not supported in Replan: plan in the workcell with Plan");
        if (!plan.group().empty()) ThrowInvalid("plan.group is not supported in Replan: give every joint");
        if (plan.has_path_constraints()) ThrowInvalid("plan.path_constraints are not supported in Replan");
        if (plan.target_case() != v1::PlanRequest::kGoal) ThrowInvalid("plan.goal (joint positions) is required in Replan");
        if (const grpc::Status refused = service_->CheckBudgets(BudgetsOf(plan)); !refused.ok()) {
          throw StatusError{refused};
        }
        const bool keep_scene = !first && plan.scene_source_case() == v1::PlanRequest::SCENE_SOURCE_NOT_SET;
        problem_ = plan;
        problem_.clear_moving_obstacles();
        if (!keep_scene) scene_ = SceneOfRequest(*service_->store_, problem_, "plan.scene");
        obstacles_ = ShiftedMovingObstacles(plan.moving_obstacles(), -time);  // on the stream's clock
        new_problem = true;
      }
      // 2. What changed.
      std::string changed;
      if (request_.has_scene()) {
        scene_ = service_->store_->AddScene(request_.scene(), "scene");
        changed = "the scene changed";
      }
      if (request_.has_points()) {
        v1::UpdateSceneRequest points = request_.points();
        points.set_scene_id(scene_.id);
        v1::UpdateSceneResponse ignored;
        std::vector<std::pair<std::string, std::string>> fields;
        scene_ = service_->InsertPoints(points, scene_, &ignored, &fields);
        changed = changed.empty() ? "points were added to the scene" : changed + " and points were added";
      }
      bool obstacles_changed = false;
      if (request_.moving_obstacles_changed() && !first) {
        MovingObstaclesFromProto(request_.moving_obstacles());  // validates (names the field)
        obstacles_ = request_.moving_obstacles();
        obstacles_changed = true;
      }
      last_time_ = time;
      const StoredRobot robot = Robot();
      const RobotModel& model = *robot.model;

      // 3. The state at `time`.
      Eigen::VectorXd q, v;
      const bool on_trajectory = has_current_ && request_.state().positions_size() == 0 && !first;
      if (request_.state().positions_size() > 0) {
        q = ConfigurationFromProto(request_.state().positions(), model, "state.positions", 1e-6, nullptr);
      } else if (on_trajectory) {
        q = current_.Evaluate(time - current_begin_).q;
      } else if (first) {
        q = ConfigurationFromProto(problem_.start().positions(), model, "plan.start.positions",
                                   BoundsToleranceFromProto(problem_.bounds_tolerance()), nullptr);
      } else {
        ThrowInvalid("state.positions is empty and there is no current trajectory to take the state from; "
                     "send the robot's joint positions");
      }
      if (request_.velocities_size() > 0) {
        v = JointValuesFromProto(request_.velocities(), model, "velocities");
      } else if (on_trajectory) {
        v = current_.Evaluate(time - current_begin_).qd;
      } else {
        v = Eigen::VectorXd::Zero(model.num_dofs());
      }
      response->set_time(time);

      // 4. Keep the current trajectory while it holds.
      std::string reason;
      if (!first && !new_problem) {
        reason = Invalidation(robot, q, v, time, changed, obstacles_changed);
        if (reason.empty()) {
          ++kept_;
          response->set_action(v1::ReplanResponse::KEPT);
          KeptToProto(model, time, response->mutable_plan());
          return;
        }
      }
      response->set_action(first || new_problem ? v1::ReplanResponse::PLANNED : v1::ReplanResponse::REPLANNED);
      response->set_reason(reason);

      // 5. Plan: brake first when moving, then plan from where it stops.
      ++planned_;
      has_current_ = false;
      const Eigen::VectorXd limits = AccelerationLimits(model);
      const TimedTrajectory braking = BrakingTrajectory(q, v, limits);
      const double stop = braking.duration();
      const Eigen::VectorXd rest = braking.Evaluate(stop).q;
      if (stop > 0.0) {
        if (std::string hit = BrakingConflict(robot, braking, time); !hit.empty()) {
          v1::PlanResponse* plan = response->mutable_plan();
          plan->set_outcome(v1::START_IN_COLLISION);
          plan->set_message("the robot cannot stop without a collision: braking from its velocity at t = " +
                            FormatNumber(time) + " s along a straight line over " + FormatNumber(stop) + " s " + hit);
          return;
        }
      }
      PlanJob job;
      job.request = problem_;
      job.request.mutable_start()->clear_positions();
      ToProto(rest, job.request.mutable_start()->mutable_positions());
      *job.request.mutable_moving_obstacles() = ShiftedMovingObstacles(obstacles_, time + stop);
      if (request_.time_budget() != 0.0) job.request.set_time_budget(request_.time_budget());
      job.arrival = Clock::now();
      job.deadline = deadline_;
      job.cancellation = &cancellation_;
      job.scene = &scene_;
      service_->RunPlan(job);
      *response->mutable_plan() = std::move(job.response);
      v1::PlanResponse* plan = response->mutable_plan();
      if (plan->outcome() != v1::SUCCESS) return;
      // The new current trajectory: the braking, then the plan.
      current_ = Concatenated(braking, job.trajectory);
      current_begin_ = time;
      has_current_ = true;
      if (stop > 0.0) {
        plan->set_duration(current_.duration());
        SamplePlan(model, plan);
        plan->set_message("braked for " + FormatNumber(stop) + " s from its velocity, then: " + plan->message());
      }
    }

    /// Acceleration limits of the problem: trajectory.max_acceleration, else 2 × the velocity limits.
    Eigen::VectorXd AccelerationLimits(const RobotModel& model) const {
      const v1::TrajectoryOptions& options = problem_.trajectory();
      Eigen::VectorXd a(model.num_dofs());
      for (int i = 0; i < model.num_dofs(); ++i) {
        a[i] = options.max_acceleration_size() == model.num_dofs() ? options.max_acceleration(i)
                                                                    : 2.0 * model.velocity_limits()[i];
      }
      return a;
    }

    /// Why the current trajectory no longer holds from `time`, or "".
    std::string Invalidation(const StoredRobot& robot, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                             double time, const std::string& changed, bool obstacles_changed) {
      if (!has_current_) return "there is no current trajectory (the previous answer had none)";
      const double local = time - current_begin_;
      const TrajectorySample expected = current_.Evaluate(local);
      const double off = (q - expected.q).cwiseAbs().maxCoeff();
      if (off > kStateTolerance) {
        return "the state is " + FormatNumber(off) + " rad off the current trajectory at t = " + FormatNumber(time) +
               " s (tolerance " + FormatNumber(kStateTolerance) + ")";
      }
      const double off_speed = (v - expected.qd).cwiseAbs().maxCoeff();
      if (off_speed > kVelocityTolerance) {
        return "the velocity is " + FormatNumber(off_speed) + " rad/s off the current trajectory's at t = " +
               FormatNumber(time) + " s (tolerance " + FormatNumber(kVelocityTolerance) + ")";
      }
      const TimedTrajectory rest = TrajectoryFrom(current_, local);
      if (!changed.empty()) {
        const double padding = PaddingFromProto(problem_.padding(), "plan.padding");
        const std::shared_ptr<const CollisionChecker> checker = service_->store_->Checker(robot, scene_, padding);
        const double resolution = problem_.collision_resolution() == 0.0 ? 0.005 : problem_.collision_resolution();
        if (std::string hit = FindTrajectoryCollision(*checker, rest, 0.0, resolution); !hit.empty()) {
          return changed + ": the current trajectory collides " + ShiftedTime(hit, time);
        }
      }
      if (obstacles_changed) {
        if (std::string hit = ObstacleConflict(robot, rest, time); !hit.empty()) return hit;
      }
      return "";
    }

    /// "at t = x s (...)" with x moved from the trajectory's clock to the stream's.
    static std::string ShiftedTime(const std::string& hit, double origin) {
      const std::string key = "at t = ";
      const std::size_t at = hit.find(key);
      if (at == std::string::npos) return hit;
      const std::size_t end = hit.find(" s", at);
      const double t = std::stod(hit.substr(at + key.size(), end - at - key.size()));
      return hit.substr(0, at) + key + FormatNumber(std::round((t + origin) * 1e6) / 1e6) + hit.substr(end);  // µs
    }

    /// The first conflict of `motion` (starting at stream time `time`) with a moving obstacle, or "".
    std::string ObstacleConflict(const StoredRobot& robot, const TimedTrajectory& motion, double time) const {
      CommittedMotion mine;
      mine.id = "the current trajectory";
      mine.placement.name = "robot";
      mine.placement.model = robot.model;
      mine.trajectory = motion;
      mine.until = std::numeric_limits<double>::infinity();
      const std::vector<MovingObstacle> obstacles = MovingObstaclesFromProto(ShiftedMovingObstacles(obstacles_, time));
      const double resolution = problem_.collision_resolution() == 0.0 ? 0.005 : problem_.collision_resolution();
      for (std::size_t i = 0; i < obstacles.size(); ++i) {
        const CommittedMotion other = MotionOfObstacle(obstacles[i], "moving_obstacles[" + std::to_string(i) + "]");
        const std::string conflict = FindMotionConflict(mine, other, 0.0, 1e-3, resolution);
        if (!conflict.empty()) return ShiftedTime(conflict, time);
      }
      return "";
    }

    /// The braking motion against the scene and the moving obstacles, or "".
    std::string BrakingConflict(const StoredRobot& robot, const TimedTrajectory& braking, double time) {
      const double padding = PaddingFromProto(problem_.padding(), "plan.padding");
      const std::shared_ptr<const CollisionChecker> checker = service_->store_->Checker(robot, scene_, padding);
      if (!checker->IsMotionFree(braking.Evaluate(0.0).q, braking.Evaluate(braking.duration()).q, 0.005)) {
        return "(the scene): " + ShiftedTime(FindTrajectoryCollision(*checker, braking, 0.0, 0.005), time);
      }
      const std::string conflict = ObstacleConflict(robot, braking, time);
      return conflict.empty() ? "" : "(" + conflict + ")";
    }

    /// The current trajectory's rest from `time`, as Plan returns a trajectory.
    void KeptToProto(const RobotModel& model, double time, v1::PlanResponse* plan) {
      const TimedTrajectory rest = TrajectoryFrom(current_, time - current_begin_);
      current_ = rest;
      current_begin_ = time;
      plan->set_outcome(v1::SUCCESS);
      plan->set_message("kept: the current trajectory still holds from t = " + FormatNumber(time) + " s");
      plan->set_duration(rest.duration());
      SamplePlan(model, plan);
    }

    /// The response's samples and path from current_ at the problem's sample period.
    void SamplePlan(const RobotModel& model, v1::PlanResponse* plan) const {
      const v1::TrajectoryOptions& options = problem_.trajectory();
      plan->clear_trajectory();
      plan->clear_knots();
      // As Plan answers: knots when asked for (and the pieces allow), samples unless only knots.
      const bool knots = options.knots_only() && KnotsToProto(current_, model.dof_names(), plan->mutable_knots());
      if (!knots || options.sample_period() != 0.0) {
        const double period = options.sample_period() == 0.0 ? 0.01 : options.sample_period();
        SamplesToProto(current_.Sample(period), model, plan->mutable_trajectory());
      }
      plan->clear_path();
      for (const Eigen::VectorXd& q : current_.Waypoints()) ToProto(q, plan->add_path()->mutable_positions());
    }

    static constexpr double kStateTolerance = 1e-3;     ///< [rad or m] state off the trajectory
    static constexpr double kVelocityTolerance = 1e-2;  ///< [rad/s or m/s]

    std::uint64_t planned_ = 0, kept_ = 0;
    v1::PlanRequest problem_;
    StoredScene scene_;
    google::protobuf::RepeatedPtrField<v1::MovingObstacle> obstacles_;  ///< on the stream's clock
    TimedTrajectory current_;
    double current_begin_ = 0.0;
    bool has_current_ = false;
    double last_time_ = 0.0;
  };

  /// A write reactor that only answers an error (a Benchmark refused before it starts).
  class RefusedWriter final : public grpc::ServerWriteReactor<grpc::ByteBuffer> {
   public:
    explicit RefusedWriter(const grpc::Status& status) { Finish(status); }
    void OnDone() override { delete this; }
  };

  /// Answers a Benchmark stream with `status` before it starts, and records it.
  grpc::ServerWriteReactor<grpc::ByteBuffer>* RefuseStream(const grpc::CallbackServerContext& context,
                                                           const grpc::Status& status) {
    RequestRecord record;
    record.rpc = "Benchmark";
    record.client = ClientOf(context);
    record.status_code = static_cast<int>(status.error_code());
    record.status_message = StatusMessage(status.error_message());
    services_.metrics->RequestStarted(record.rpc);
    Record(record);
    return new RefusedWriter(grpc::Status(status.error_code(), record.status_message));
  }

  /// Who the caller is, for fair queueing and the log: the authenticated identity (token name or
  /// client certificate) when there is one, else the peer (address and port: one connection).
  std::string ClientOf(const grpc::CallbackServerContext& context) const {
    const ClientIdentity identity = access_->IdentifyClient(context);
    return identity.authenticated ? identity.name : context.peer();
  }

  /// Parses the call, then runs `work(call)` inline (cheap calls) or on the pool under the fair
  /// scheduler, and finishes the call with OK, the work's own status, or the mapped exception.
  /// Every path records the call once (log line, metrics).
  template <typename Request, typename Response, typename Work>
  grpc::ServerUnaryReactor* Serve(const char* rpc, grpc::CallbackServerContext* context, const grpc::ByteBuffer* in,
                                  grpc::ByteBuffer* out, Where where, Work work) {
    using Call = UnaryCall<Request, Response>;
    services_.metrics->RequestStarted(rpc);
    in_flight_.fetch_add(1);
    auto* call = new Call(rpc, context, out, [this](const RequestRecord& record) {
      Record(record);
      in_flight_.fetch_sub(1);
    });
    call->record.client = ClientOf(*context);
    if (draining_.load()) {
      call->Complete(grpc::Status(grpc::StatusCode::UNAVAILABLE,
                                  "this server is shutting down and takes no new calls; send it to another replica"));
      return call;
    }
    if (grpc::Status refused = access_->Authorize(*context, rpc); !refused.ok()) {
      call->Complete(refused);
      return call;
    }
    if (!call->Parse(in)) return call;
    const BudgetFields budgets = BudgetsOf(call->request);
    if (const grpc::Status refused = CheckBudgets(budgets); !refused.ok()) {
      call->Complete(refused);
      return call;
    }
    JobTicket ticket;
    ticket.client = call->record.client;
    for (const auto& [field, seconds] : budgets) {
      if (seconds > options_.long_budget) ticket.long_running = true;
    }
    auto job = [this, rpc, call, work = std::move(work)]() mutable {
      call->record.queue_seconds = SecondsSince(call->arrival);
      if (call->cancelled()) {
        call->Complete(grpc::Status(grpc::StatusCode::CANCELLED, "cancelled before it started"));
        return;
      }
      std::uint64_t peak = 0;
      grpc::Status status = RunCapped([&] { work(*call); }, &peak);
      if (status.ok() && call->cancelled()) status = grpc::Status(grpc::StatusCode::CANCELLED, "cancelled by the client");
      if (status.ok()) Remember(rpc, *call);
      call->record.peak_heap_bytes = peak;
      call->Complete(status);  // OnDone gives a large call's free heap back to the system
    };
    if (where == Where::kInline) {
      job();
      return call;
    }
    switch (pool_->TrySubmit(std::move(job), ticket)) {
      case SubmitResult::kQueued: break;
      case SubmitResult::kClientQueueFull:
        call->Complete(grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED,
                                    "this client already has " + std::to_string(options_.max_queued_per_client) +
                                        " calls waiting for a worker (--max-queued-per-client); wait for answers "
                                        "before sending more"));
        break;
      case SubmitResult::kQueueFull:
        call->Complete(grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED,
                                    "the server's work queue is full (" + std::to_string(options_.max_queued) +
                                        " calls waiting, --max-queued); retry later"));
        break;
      case SubmitResult::kStopping:
        call->Complete(grpc::Status(grpc::StatusCode::UNAVAILABLE, "the server is shutting down"));
        break;
    }
    return call;
  }

  /// INVALID_ARGUMENT naming the first budget above --max-budget, else OK.
  grpc::Status CheckBudgets(const BudgetFields& budgets) const {
    for (const auto& [field, seconds] : budgets) {
      if (seconds > options_.max_budget) {
        return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                            field + " = " + FormatNumber(seconds) + " s exceeds this server's maximum budget of " +
                                FormatNumber(options_.max_budget) + " s (--max-budget); ask for less, or run a server "
                                "with a larger --max-budget");
      }
    }
    return grpc::Status::OK;
  }

  grpc::Status MemoryCapStatus() const {
    return grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED,
                        "the request needed more than this server's per-request memory cap of " +
                            std::to_string(options_.request_memory_mb) +
                            " MiB (--request-memory-mb) and was abandoned; use a smaller input, budget or "
                            "planner graph (e.g. max_nodes), or a larger sample_period");
  }

  /// The server's caps on a reply's samples: --max-samples each, and the message cap less room
  /// for everything else (1 MiB, or an eighth of small caps) shared by `robots` trajectories.
  void ApplyReplyCap(SampleCap* cap, std::size_t robots = 1) const {
    const std::uint64_t max_message = static_cast<std::uint64_t>(options_.max_message_mb) << 20;
    const std::uint64_t margin = std::min<std::uint64_t>(max_message / 8, 1u << 20);
    const std::uint64_t shares = std::max<std::uint64_t>(1, robots);
    cap->max_samples = options_.max_samples;
    cap->max_reply_bytes = (max_message - margin) / shares;
    cap->reply_cap_source = "--max-message-mb " + std::to_string(options_.max_message_mb) + " less " +
                            (margin == (1u << 20) ? "1 MiB" : std::to_string(margin >> 10) + " KiB");
    if (shares > 1) cap->reply_cap_source += " shared by " + std::to_string(shares) + " robots";
  }

  /// Logs the finished call and hands it to the metrics.
  void Record(const RequestRecord& record) const {
    if (options_.log_requests) {
      const std::string line = FormatLogLine(record, log_format_, options_.log_field_max);
      std::fprintf(stderr, "%s\n", line.c_str());
    }
    services_.metrics->RequestFinished(record);
  }

  /// Keeps a finished Plan, Optimize or Coordinate exchange for the viewer (--http-listen).
  template <typename Call>
  void Remember(const char* rpc, const Call& call) {
    using Request = std::decay_t<decltype(call.request)>;
    if constexpr (std::is_same_v<Request, v1::PlanRequest> || std::is_same_v<Request, v1::OptimizeRequest> ||
                  std::is_same_v<Request, v1::CoordinateRequest>) {
      if (services_.recent == nullptr || call.record.request_id.empty()) return;
      Exchange exchange;
      exchange.rpc = rpc;
      exchange.request_id = call.record.request_id;
      call.request.SerializeToString(&exchange.request);
      call.response.SerializeToString(&exchange.response);
      exchange.unix_time = workcells_->Now();
      exchange.outcome = v1::PlanOutcome_Name(call.response.outcome());
      services_.recent->Add(std::move(exchange));
    }
  }

  /// A Plan call's work. `Call` is a UnaryCall or a ReplanStream's PlanJob: request, response,
  /// record, arrival, deadline, Start(budget_end, deadline) and cancelled().
  template <typename Call>
  void RunPlan(Call& call) {
    v1::PlanResponse& response = call.response;
    call.record.request_id = RequestId(call.request.request_id(), "req");
    response.set_request_id(call.record.request_id);
    std::string planner =
        call.request.planner().planner_id().empty() ? "rrt_connect" : call.request.planner().planner_id();
    call.record.fields = {{"planner", planner}};

    // 1. Robot, scene and checker (parsed or cached). With a planning group, the robot with
    //    every other joint held at the start, and the request narrowed to the group's joints
    //    (in a workcell too: the held robot is what the other reservations see).
    const StoredRobot described = RobotOfRequest(*store_, call.request);
    StoredRobot robot = described;
    response.set_robot_id(robot.id);
    v1::PlanRequest grouped;
    std::vector<std::string> group_warnings;
    if (!call.request.group().empty()) {
      grouped = call.request;
      robot = NarrowToGroup(robot, &grouped, &group_warnings);
      call.record.fields.push_back({"group", call.request.group()});
    }
    const v1::PlanRequest& request = call.request.group().empty() ? call.request : grouped;
    // Objects the robot carries: links of their own (built once per robot and objects).
    robot = store_->Carrying(robot, request.attached_objects(), "attached_objects", &group_warnings);
    if (request.attached_objects_size() > 0) {
      call.record.fields.push_back({"attached", std::to_string(request.attached_objects_size())});
    }
    const StoredScene scene = SceneOfCall(call, request);
    response.set_scene_id(scene.id);
    call.record.fields.push_back({"robot", IdPrefix(robot.id)});
    call.record.fields.push_back({"scene", IdPrefix(scene.id)});
    const double padding = PaddingFromProto(request.padding(), "padding");
    if (request.has_workcell() || request.moving_obstacles_size() > 0) {
      // Both are planned in space-time: a team of one among committed motions.
      const std::string with = request.has_workcell() ? "workcell" : "moving_obstacles";
      if (request.has_path_constraints()) {
        ThrowInvalid("path_constraints are not supported with " + with + " (it is planned in space-time "
                     "without them); plan without " + with + ", or without path_constraints");
      }
      if (padding != 0.0) {
        ThrowInvalid("padding = " + FormatNumber(padding) + " is not supported with " + with +
                     " (it is planned in space-time without robot padding); send padding 0, or plan without " + with);
      }
      const bool steer = request.moving_obstacle_method() == v1::PlanRequest::VELOCITY_OBSTACLES;
      if (!v1::PlanRequest::MovingObstacleMethod_IsValid(request.moving_obstacle_method())) {
        ThrowInvalid("moving_obstacle_method = " + std::to_string(request.moving_obstacle_method()) +
                     " is not a method (SPACE_TIME, VELOCITY_OBSTACLES)");
      }
      if (steer && request.has_workcell()) {
        ThrowInvalid("moving_obstacle_method = VELOCITY_OBSTACLES is not supported with workcell: its committed "
                     "trajectories are not discs; use SPACE_TIME");
      }
      const std::vector<MovingObstacle> obstacles = MovingObstaclesFromProto(request.moving_obstacles());
      call.record.fields.front().second = (request.has_workcell() ? "workcell:" : steer ? "velocity_obstacles:" : "space_time:") + planner;
      if (!obstacles.empty()) call.record.fields.push_back({"moving_obstacles", std::to_string(obstacles.size())});
      std::vector<std::string> warnings = group_warnings;
      CoordinationQuery query = WorkcellPlanQuery(request, robot.model, scene.scene, registry_, &warnings);
      ApplyReplyCap(&query.sample_cap);
      query.sample_cap.field = "trajectory.sample_period";
      if (request.has_workcell()) {
        const double origin =
            request.workcell().start_time() == 0.0 ? workcells_->Now() : request.workcell().start_time();
        for (const Reservation& r : workcells_->Active(request.workcell().name())) {
          if (r.robot_name != query.robots.front().placement.name) query.committed.push_back(MotionOf(r, origin));
        }
      }
      for (std::size_t i = 0; i < obstacles.size(); ++i) {
        query.committed.push_back(MotionOfObstacle(obstacles[i], "moving_obstacles[" + std::to_string(i) + "]"));
        if (steer) query.moving_discs.push_back(DiscOfObstacle(obstacles[i]));
      }
      if (steer) query.method = CoordinationMethod::kVelocityObstacles;
      const Termination termination = call.Start(BudgetEnd(query.time_budget, call.deadline), call.deadline);
      const CoordinationOutcome outcome = chasles::Coordinate(query, registry_, termination);
      WorkcellPlanToProto(outcome, query, &response);
      if (outcome.code == CoordinationCode::kSuccess) KeepTrajectory(call, outcome.robots.front().trajectory);
      AddPlanWarnings(request, described, warnings, &response);
      call.record.outcome = v1::PlanOutcome_Name(response.outcome());
      if (outcome.code == CoordinationCode::kCancelled) {
        throw StatusError{grpc::Status(grpc::StatusCode::CANCELLED, "cancelled by the client")};
      }
      if (outcome.code == CoordinationCode::kDeadlineExceeded) {
        throw DeadlineError{"the gRPC deadline passed before planning finished"};
      }
      return;
    }
    std::shared_ptr<const CollisionChecker> checker = store_->Checker(robot, scene, padding);
    if (padding != 0.0) call.record.fields.push_back({"padding", FormatNumber(padding)});

    // 2. The query, with the proto's defaults and the server's caps.
    RequestSettings settings;
    PlanQuery query = PlanQueryFromProto(request, checker, registry_, &settings);
    ApplyReplyCap(&query.sample_cap);
    const double prepare = SecondsSince(call.arrival) - call.record.queue_seconds;

    // 3. Budget: the request's, cut short so a result can still travel back before the gRPC
    //    deadline (which itself stops everything).
    const Termination termination = call.Start(BudgetEnd(settings.time_budget, call.deadline), call.deadline);

    // 4. Plan.
    PlanOutcome outcome = pipeline_.Plan(query, termination);
    // A start or goal that touches only the fitted spheres of a mesh robot (they reach up to
    // fit->reach outside its meshes) is free as described: plan on the exact meshes instead
    // (discrete checks, slower), rather than refuse a request the robot can serve.
    if (robot.exact && robot.fit &&
        (outcome.code == PlanOutcomeCode::kStartInCollision || outcome.code == PlanOutcomeCode::kGoalInCollision)) {
      StoredRobot exact;
      exact.id = robot.id + "/exact";
      exact.model = robot.exact;
      std::shared_ptr<const CollisionChecker> exact_checker = store_->Checker(exact, scene, padding);
      if (const PathConstraints* constraints = query.checker->path_constraints()) {
        exact_checker = CollisionChecker::WithPathConstraints(
            exact_checker, std::make_shared<const PathConstraints>(exact.model, constraints->orientation(),
                                                                   constraints->position(), "path_constraints"));
      }
      if (exact_checker->IsValid(query.start) && (query.pose_goal || exact_checker->IsValid(query.goal))) {
        settings.warnings.push_back(
            std::string(outcome.code == PlanOutcomeCode::kStartInCollision ? "start" : "goal") +
            " collides only with the fitted spheres, which reach up to " + FormatNumber(1e3 * robot.fit->reach) +
            " mm outside the meshes (" + outcome.message + "); planned on the exact meshes instead (discrete checks)");
        query.checker = std::move(exact_checker);
        outcome = pipeline_.Plan(query, termination);
      }
    }
    outcome.seconds.validate += prepare;
    call.record.outcome = v1::PlanOutcome_Name(OutcomeToProto(outcome.code));
    call.record.stages = {{"validate", outcome.seconds.validate},   {"plan", outcome.seconds.plan},
                          {"shortcut", outcome.seconds.shortcut},   {"parameterize", outcome.seconds.parameterize},
                          {"optimize", outcome.seconds.optimize},   {"verify", outcome.seconds.verify}};
    outcome.seconds.total = SecondsSince(call.arrival);
    PlanOutcomeToProto(outcome, query, &response, request.trajectory().knots_only());
    if (outcome.code == PlanOutcomeCode::kSuccess) KeepTrajectory(call, outcome.trajectory);
    group_warnings.insert(group_warnings.end(), settings.warnings.begin(), settings.warnings.end());
    AddPlanWarnings(request, described, group_warnings, &response);
    grpc::Status status = StatusFromOutcome(outcome.code, outcome.message);
    if (status.ok() && (call.cancelled() || termination.Reason() == StopReason::kCancelled) &&
        outcome.code != PlanOutcomeCode::kSuccess) {
      status = grpc::Status(grpc::StatusCode::CANCELLED, "cancelled by the client");
    }
    if (!status.ok()) throw StatusError{status};
  }

  /// TeamRobot.group: when some robot of `request` names a group, *grouped is the request with
  /// those robots' start and goal narrowed to their group, and held["robots[k]"] robot k held
  /// outside its group where its start puts it; else both are left empty. Values clamped within
  /// bounds_tolerance are reported in *warnings. \throws Error(kInvalidArgument) naming the field.
  void NarrowTeamToGroups(const v1::CoordinateRequest& request, v1::CoordinateRequest* grouped,
                          std::map<std::string, std::shared_ptr<const RobotModel>>* held,
                          std::vector<std::string>* warnings) {
    if (std::none_of(request.robots().begin(), request.robots().end(),
                     [](const v1::TeamRobot& r) { return !r.group().empty(); })) {
      return;
    }
    CheckTeamSize(request, options_.max_team_robots);  // before any robot is resolved
    *grouped = request;
    const double tolerance = BoundsToleranceFromProto(request.bounds_tolerance());
    for (int k = 0; k < grouped->robots_size(); ++k) {
      v1::TeamRobot& robot = *grouped->mutable_robots(k);
      if (robot.group().empty()) continue;
      const std::string field = "robots[" + std::to_string(k) + "]";
      if (robot.target_case() == v1::TeamRobot::kPoseGoal) {
        ThrowInvalid(field + ".group = '" + robot.group() + "' cannot be combined with " + field +
                     ".pose_goal: give a joint goal");
      }
      const StoredRobot stored = TeamRobotOf(robot, field, warnings);
      const PlanningGroup& group = FindGroup(stored, robot.group(), field + ".group");
      const Eigen::VectorXd start = TakeHeldState(robot.mutable_start()->mutable_positions(), *stored.model, group,
                                                  field + ".start.positions", tolerance, warnings);
      NarrowPositions(robot.mutable_goal()->mutable_positions(), *stored.model, group, start, field + ".goal.positions",
                      field + ".start.positions", "the start", tolerance, warnings);
      (*held)[field] = HoldOutside(stored, group, start).model;
    }
  }

  /// A plan's warnings: an inline robot's load warnings (an uploaded one reported them at
  /// upload), then what the request's conversion adjusted.
  static void AddPlanWarnings(const v1::PlanRequest& request, const StoredRobot& robot,
                              const std::vector<std::string>& adjusted, v1::PlanResponse* response) {
    if (request.has_robot()) {
      for (const std::string& warning : RobotWarnings(*robot.model, "robot")) response->add_warnings(warning);
      for (const std::string& warning : robot.group_warnings) response->add_warnings(warning);
    }
    for (const std::string& warning : adjusted) response->add_warnings(warning);
  }

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
  /// A team robot as stored, carrying its attached_objects (their warnings into `warnings` when
  /// given).
  StoredRobot TeamRobotOf(const v1::TeamRobot& robot, const std::string& field,
                          std::vector<std::string>* warnings = nullptr) {
    StoredRobot stored;
    switch (robot.robot_source_case()) {
      case v1::TeamRobot::kRobot: stored = store_->AddRobot(robot.robot(), field + ".robot"); break;
      case v1::TeamRobot::kRobotId: stored = store_->FindRobot(robot.robot_id()); break;
      default: ThrowInvalid(field + " has no robot: set robot or robot_id");
    }
    std::vector<std::string> unused;
    return store_->Carrying(stored, robot.attached_objects(), field + ".attached_objects",
                            warnings != nullptr ? warnings : &unused);
  }

  /// The client's request id, or a generated "<prefix>-NNNNNN" when it sent none.
  std::string RequestId(const std::string& given, const char* prefix) {
    if (!given.empty()) return given;
    char buffer[32];
    std::snprintf(buffer, sizeof(buffer), "%s-%06" PRIu64, prefix, ++next_request_);
    return buffer;
  }


  const ServiceContext services_;
  const PlannerRegistry& registry_;
  const PlanningPipeline pipeline_;
  ModelStore* store_;
  ThreadPool* pool_;
  WorkcellStore* workcells_;
  FleetLatticeCache fleet_lattices_{16};  ///< FLEET lattices by scene id and footprint (fleet_lattice.h)
  FleetSessionStore fleet_sessions_{64};  ///< open fleet sessions by name (fleet_sessions.h)
  std::atomic<bool> draining_{false};
  std::atomic<int> in_flight_{0};
  const AccessControl* access_;
  const ServerOptions& options_;
  const LogFormat log_format_;
  BenchmarkRegistry benchmarks_;
  std::atomic<std::uint64_t> next_request_{0};
};

}  // namespace

void ServerOptions::Validate() const {
  if (listen.empty()) ThrowInvalid("--listen is empty: give ADDRESS:PORT, e.g. 127.0.0.1:50051");
  if (threads < 0) ThrowInvalid("--threads = " + std::to_string(threads) + " must be >= 0 (0 = hardware threads)");
  if (max_message_mb < 1 || max_message_mb > 2047) {
    ThrowInvalid("--max-message-mb = " + std::to_string(max_message_mb) + " must be within [1, 2047]");
  }
  if (cache_mb < 1 || cache_mb > (1ull << 30)) ThrowInvalid("--cache-mb = " + std::to_string(cache_mb) + " must be within [1, 2^30]");
  if (max_samples < 1) ThrowInvalid("--max-samples = 0 must be >= 1");
  if (max_team_robots < 1) ThrowInvalid("--max-team-robots = " + std::to_string(max_team_robots) + " must be >= 1");
  if (store != "memory") ParseRedisUrl(store, "--store");
  if (!(shutdown_grace >= 0.0 && shutdown_grace <= 3600.0)) {
    ThrowInvalid("--shutdown-grace = " + FormatNumber(shutdown_grace) + " must be within [0, 3600] s");
  }
  if (request_memory_mb > (1ull << 30)) {
    ThrowInvalid("--request-memory-mb = " + std::to_string(request_memory_mb) + " must be within [0, 2^30] (0 = no cap)");
  }
  if (!(max_budget > 0.0 && max_budget <= 600.0)) {
    ThrowInvalid("--max-budget = " + FormatNumber(max_budget) + " must be within (0, 600] s");
  }
  if (!(long_budget > 0.0) || !std::isfinite(long_budget)) {
    ThrowInvalid("--long-budget = " + FormatNumber(long_budget) + " must be finite and > 0 s");
  }
  if (!(long_share > 0.0 && long_share <= 1.0)) {
    ThrowInvalid("--long-share = " + FormatNumber(long_share) + " must be within (0, 1]");
  }
  if (max_queued < 1) ThrowInvalid("--max-queued = 0 must be >= 1");
  if (max_queued_per_client < 1) ThrowInvalid("--max-queued-per-client = 0 must be >= 1");
  if (log_format != "text" && log_format != "json") {
    ThrowInvalid("--log-format = '" + EscapeForLog(log_format, 64) + "' must be 'text' or 'json'");
  }
  limits.Validate();
  if (log_field_max < 16) ThrowInvalid("--log-field-max = " + std::to_string(log_field_max) + " must be >= 16");
  if (http_recent < 1 || http_recent > 10000) {
    ThrowInvalid("--http-recent = " + std::to_string(http_recent) + " must be within [1, 10000]");
  }
  if (!http_listen.empty()) {
    if (http_listen.rfind(':') == std::string::npos) ThrowInvalid("--http-listen = '" + http_listen + "' must be HOST:PORT");
    if (security.tokens() && !IsLoopbackAddress(http_listen)) {
      ThrowInvalid("--http-listen " + http_listen + " serves plain HTTP, where bearer tokens (--tokens) travel "
                   "readable: listen on a loopback address (e.g. 127.0.0.1:8080) and put a TLS proxy in front");
    }
  }
}

struct PlanningServer::Impl {
  ServerOptions options;
  PlannerRegistry registry;
  std::unique_ptr<ModelStore> store;
  std::unique_ptr<ThreadPool> pool;
  WorkcellStore workcells;
  std::unique_ptr<AccessControl> access;
  std::unique_ptr<ServerMetrics> metrics;
  std::unique_ptr<PlanningService> service;
  std::unique_ptr<grpc::Server> server;
  std::unique_ptr<RecentExchanges> recent;  ///< with --http-listen
  std::unique_ptr<ViewServer> views;
  int port = 0;
  std::once_flag shutdown_once;
};

PlanningServer::PlanningServer(const ServerOptions& options) : impl_(std::make_unique<Impl>()) {
  options.Validate();
  impl_->options = options;
  // Large blocks (samples, meshes, maps) come from mmap and go back to the system when freed.
  UseFixedMmapThreshold(1u << 20);
  RegisterDefaultPlanners(&impl_->registry);
  impl_->store =
      std::make_unique<ModelStore>(DefaultRobotProto(), DefaultSceneProto(), options.cache_mb << 20, options.limits);
  std::optional<RedisAddress> shared;
  if (options.store != "memory") {
    // Own connections: model reads and writes do not wait behind a workcell commit's transaction.
    const RedisAddress address = ParseRedisUrl(options.store, "--store");
    shared = address;
    impl_->store->UseShared(std::make_shared<RedisClient>(address));
    ModelStore* models = impl_->store.get();
    impl_->workcells.UseShared(std::make_shared<RedisClient>(address), [models](const std::string& record) {
      return ReservationFromRecord(record, *models);
    });
  }
  PoolOptions pool;
  pool.threads = options.threads;
  pool.max_queued = options.max_queued;
  pool.max_queued_per_client = options.max_queued_per_client;
  pool.long_share = options.long_share;
  impl_->pool = std::make_unique<ThreadPool>(pool);
  // Calls the credentials refuse never reach a handler; they are logged and counted here.
  impl_->access = std::make_unique<AccessControl>(options.security, [impl = impl_.get()](const AccessRefusal& refusal) {
    if (impl->service) impl->service->RecordRefusal(refusal);
  });
  ModelStore* store = impl_->store.get();
  ThreadPool* workers = impl_->pool.get();
  impl_->metrics = std::make_unique<ServerMetrics>(
      options.metrics_listen, [workers] { return workers->stats(); }, [store] { return store->cache_stats(); });

  ServiceContext services;
  services.registry = &impl_->registry;
  services.store = impl_->store.get();
  services.pool = impl_->pool.get();
  services.workcells = &impl_->workcells;
  services.access = impl_->access.get();
  services.metrics = impl_->metrics.get();
  services.options = &impl_->options;
  if (!options.http_listen.empty()) {
    impl_->recent = std::make_unique<RecentExchanges>(static_cast<std::size_t>(options.http_recent), 256ull << 20);
    services.recent = impl_->recent.get();
  }
  impl_->service = std::make_unique<PlanningService>(services);
  if (shared) impl_->service->UseSharedFleets(std::make_shared<RedisClient>(*shared));

  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
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
  if (impl_->recent) {
    const AccessControl* access = impl_->access.get();
    impl_->views = std::make_unique<ViewServer>(
        options.http_listen, impl_->recent.get(), impl_->store.get(), [access](const std::optional<std::string>& authorization) {
          const grpc::Status status = access->AuthorizeHeader(authorization, "View");
          return status.ok() ? std::string() : status.error_message();
        });
  }
}

PlanningServer::~PlanningServer() {
  Shutdown();
  impl_->server->Wait();
  impl_->pool.reset();  // every call has finished; joins the idle workers
}

int PlanningServer::port() const { return impl_->port; }

int PlanningServer::metrics_port() const { return impl_->metrics->port(); }

int PlanningServer::http_port() const { return impl_->views ? impl_->views->port() : 0; }

std::string PlanningServer::security_description() const { return impl_->access->Describe(); }

void PlanningServer::Shutdown(std::chrono::milliseconds grace) {
  std::call_once(impl_->shutdown_once, [&] {
    // Drain: health says NOT_SERVING and new calls are refused (UNAVAILABLE, so balancing
    // clients retry elsewhere) while the calls in flight finish, for at most `grace`; then the
    // listener closes and what still runs is cancelled.
    const auto end = std::chrono::steady_clock::now() + grace;
    impl_->service->StartDraining();
    if (auto* health = impl_->server->GetHealthCheckService()) {
      health->SetServingStatus(false);
      health->SetServingStatus("chasles.v1.Planning", false);
    }
    while (impl_->service->in_flight() > 0 && std::chrono::steady_clock::now() < end) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    if (auto* health = impl_->server->GetHealthCheckService()) health->Shutdown();
    const auto left = std::max(std::chrono::steady_clock::duration(std::chrono::milliseconds(100)),
                               end - std::chrono::steady_clock::now());
    impl_->server->Shutdown(std::chrono::system_clock::now() +
                            std::chrono::duration_cast<std::chrono::system_clock::duration>(left));
  });
}

void PlanningServer::Wait() { impl_->server->Wait(); }

}  // namespace chasles
