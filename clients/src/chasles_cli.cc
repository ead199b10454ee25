// chasles: command-line client of the Chasles planning server.
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <future>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>
#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>

#include "chasles/robot/error.h"
#include "chasles/server/model_store.h"
#include "chasles/server/trajectory_export.h"
#include "chasles/server/view_page.h"
#include "chasles/v1/chasles.grpc.pb.h"
#include "commands.h"
#include "connection.h"
#include "moveit_import.h"
#include "plan_overrides.h"
#include "trajectory_csv.h"

namespace {

namespace v1 = chasles::v1;

constexpr int kExitOk = 0;
constexpr int kExitFailed = 1;  // RPC error, or no trajectory
constexpr int kExitUsage = 2;   // bad arguments or unreadable input files

const char kUsage[] =
    "Usage: chasles [--server ADDR] [--timeout S] COMMAND [ARGS]\n"
    "\n"
    "Commands:\n"
    "  health                          ask the server's gRPC health service (exit 0 when SERVING)\n"
    "  planners                        list planners with their parameters, defaults and ranges\n"
    "  plan REQUEST.json [--out F] [--method M] [--planner ID] [--budget S] [--seed N]\n"
    "       [--sample-period S] [--padding M] [--group NAME]\n"
    "                                  send a chasles.v1.PlanRequest (protobuf JSON); print a summary;\n"
    "                                  --out F.json writes the response, --out F.csv the trajectory\n"
    "                                  (columns t, q_<joint>..., qd_<joint>..., qdd_<joint>...);\n"
    "                                  --method topp|collocation|spline|none sets the post-processing;\n"
    "                                  --planner, --budget, --seed, --sample-period, --padding override\n"
    "                                  the request's (see below); exit 0 only when a trajectory came back\n"
    "  optimize REQUEST.json [--out F] [--method M] [--ros-trajectory F]\n"
    "                                  send a chasles.v1.OptimizeRequest (protobuf JSON: your own path\n"
    "                                  or timed trajectory); print the optimised trajectory's quality;\n"
    "                                  --out and --method as for plan; --ros-trajectory F takes the input\n"
    "                                  from a trajectory_msgs/JointTrajectory or moveit_msgs/RobotTrajectory\n"
    "                                  (YAML or JSON, e.g. from view --moveit-yaml / --ros-json)\n"
    "  ik REQUEST.json                 send a chasles.v1.InverseKinematicsRequest (protobuf JSON); print\n"
    "                                  each solution with its manipulability; exit 0 only when solved\n"
    "  cartesian REQUEST.json [--out F] [--method M]\n"
    "                                  send a chasles.v1.CartesianPathRequest (protobuf JSON: a link along\n"
    "                                  straight lines through waypoint poses); print where it stopped,\n"
    "                                  the fraction achieved and the timed trajectory; --out and --method\n"
    "                                  as for plan; exit 0 only when the whole path was achieved and timed\n"
    "  replan MESSAGES.jsonl [--out F]\n"
    "                                  a replanning stream: one chasles.v1.ReplanRequest per line\n"
    "                                  (protobuf JSON; blank lines and lines starting with # skipped; the\n"
    "                                  first carries the plan); print each answer (time, KEPT / PLANNED /\n"
    "                                  REPLANNED and why, outcome, duration); --out writes the last\n"
    "                                  answer as for plan; exit 0 only when the last answer has a trajectory\n"
    "  view RESPONSE.json [REQUEST.json] --out VIEW.html\n"
    "                                  write a self-contained 3-D viewer page (opens offline) of a saved\n"
    "                                  Plan, Optimize or Coordinate response (--out F.json of plan,\n"
    "                                  optimize, coordinate) with the request it answers (robot and scene;\n"
    "                                  none = the default robot and scene): the robot moving through the\n"
    "                                  scene, its trail and waypoints, limit plots, the closest approach\n"
    "                                  --moveit-yaml F / --ros-json F write the trajectory as\n"
    "                                  moveit_msgs/RobotTrajectory YAML / trajectory_msgs/JointTrajectory JSON\n"
    "                                  (a team: F for the first robot, F's stem + _<robot> for the others)\n"
    "  upload-robot FILE.urdf [--srdf FILE.srdf [--strict-srdf]] [--mesh NAME=FILE]... [--exact-meshes]\n"
    "  upload-robot --dh FILE.json | --poe FILE.json\n"
    "                                  store a robot (URDF, or a chasles.v1.DhRobot / PoeRobot in\n"
    "                                  protobuf JSON) on the server; prints its robot_id\n"
    "  upload-scene SCENE.json         store a chasles.v1.Scene (protobuf JSON); prints its scene_id\n"
    "  update-scene [--scene-id ID] [--octomap NAME] --points FILE --origin X,Y,Z\n"
    "               [--max-range R] [--resolution R]\n"
    "                                  insert a point cloud (world frame [m]; FILE holds x y z per line,\n"
    "                                  or a .json list of [x, y, z] triples or of flat numbers) into a\n"
    "                                  stored scene's OctoMap by ray casting from the sensor origin;\n"
    "                                  prints the updated scene_id (default scene: the server's own;\n"
    "                                  --max-range 0 = unlimited; --resolution of a new map, 0 = 0.05)\n"
    "  coordinate REQUEST.json [--method M] [--out F.json]\n"
    "                                  send a chasles.v1.CoordinateRequest (protobuf JSON: a scene and\n"
    "                                  several robots); print the outcome, the method that succeeded,\n"
    "                                  makespan, sum of durations, each robot's duration, start delay\n"
    "                                  and waiting, every method attempted and the joint verification;\n"
    "                                  --method auto|prioritized|composite|velocity_tuning|sequential|fleet\n"
    "                                  overrides the request's; --out F.json writes the response;\n"
    "                                  exit 0 only when a coordinated set came back\n"
    "  workcell NAME                   create a workcell for reservations (an existing one is kept);\n"
    "                                  prints its active reservations and clock\n"
    "  commit --workcell W --robot-name N --trajectory F.json [--robot R | --robot-id ID]\n"
    "         [--base-pose X,Y,Z[,YAW]] [--start-time T] [--hold S]\n"
    "                                  reserve the space-time of robot N's trajectory in workcell W: the\n"
    "                                  trajectory of a saved PlanResponse (plan --out F.json), or robot\n"
    "                                  N's entry of a saved CoordinateResponse (coordinate --out F.json);\n"
    "                                  R is a chasles.v1.RobotModel in protobuf JSON or a .urdf file (with\n"
    "                                  --srdf); --base-pose places it in the workcell (yaw about z [rad]);\n"
    "                                  T = workcell clock at the trajectory's start [s since the epoch],\n"
    "                                  0 = now; S = seconds it keeps its final configuration afterwards;\n"
    "                                  prints the reservation id\n"
    "  release --workcell W (--reservation ID | --robot-name N)\n"
    "                                  release one reservation, or all of robot N's\n"
    "  bench CONFIG.yaml [--out DIR] [--runs N] [--parallelism N] [--quiet]\n"
    "                                  benchmark planner configurations on problems (request JSON files or\n"
    "                                  MoveIt scene/request YAML) on the server; shows a progress bar,\n"
    "                                  writes an OMPL log per problem (for ompl_benchmark_statistics),\n"
    "                                  runs.csv and results.json into DIR and prints a summary table;\n"
    "                                  Ctrl-C stops it and keeps the finished runs (see docs/benchmarks.md)\n"
    "  import-moveit SCENE.yaml REQUEST.yaml [--robot F.urdf [--srdf F.srdf]] [--out F.json]\n"
    "                [--planner ID] [--budget S] [--seed N] [--sample-period S] [--padding M] [--group NAME]\n"
    "                                  convert a MoveIt PlanningScene and MotionPlanRequest (YAML) into a\n"
    "                                  chasles.v1.PlanRequest and print it as JSON (robot joint order from\n"
    "                                  the URDF; default: the server's default robot, a Panda); the\n"
    "                                  override flags set the request's fields as for plan\n"
    "\n"
    "Request overrides (plan, import-moveit):\n"
    "%s"
    "\n"
    "Options (before COMMAND or among its arguments):\n"
    "%s"
    "  --timeout S            gRPC deadline in seconds (default: 10; plan, optimize, coordinate: the\n"
    "                         request's budget + 30; upload-robot: 300, upload-scene: 30)\n"
    "  --help                 show this help\n";

struct Options {
  chasles::cli::ConnectionOptions connection;  // --server, --tls-*, --token*
  double timeout = 0.0;  // 0 = per command default
  std::string out;
  std::string moveit_yaml;   // view: the trajectory as moveit_msgs/RobotTrajectory YAML
  std::string ros_json;      // view: the trajectory as trajectory_msgs/JointTrajectory JSON
  std::string ros_trajectory;  // optimize: a trajectory_msgs/JointTrajectory (JSON or YAML) as the input
  std::string srdf;
  bool strict_srdf = false;
  bool exact_meshes = false;  // upload-robot: keep meshes exact (FCL, discrete) instead of fitted spheres
  std::string dh;   // DhRobot JSON file
  std::string poe;  // PoeRobot JSON file
  std::vector<std::string> meshes;  // NAME=FILE
  // update-scene
  std::string scene_id;
  std::string octomap;
  std::string points;  // point file
  std::string origin;  // X,Y,Z
  std::string max_range;
  std::string resolution;
  std::string method;  // plan / optimize: post-processing; coordinate: coordination method
  // commit / release
  std::string workcell;
  std::string robot_name;
  std::string trajectory;  // PlanResponse / CoordinateResponse JSON file
  std::string robot;       // RobotModel JSON or URDF file
  std::string robot_id;
  std::string base_pose;   // X,Y,Z[,YAW]
  std::string start_time;
  std::string hold;
  std::string reservation;
  chasles::cli::PlanOverrides overrides;  // plan: --planner, --budget, --seed, --sample-period, --padding
  std::vector<std::string> positional;
};

[[noreturn]] void UsageError(const std::string& message) {
  std::cerr << "chasles: " << message << "\n(see chasles --help)\n";
  std::exit(kExitUsage);
}

/// Reads a whole file or exits with a message naming it.
std::string ReadFileOrExit(const std::string& path, const char* what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    std::cerr << "chasles: cannot read " << what << " file '" << path << "': " << std::strerror(errno) << "\n";
    std::exit(kExitUsage);
  }
  std::ostringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

template <typename Message>
Message ParseJsonFileOrExit(const std::string& path) {
  Message message;
  const std::string text = ReadFileOrExit(path, Message::descriptor()->full_name().c_str());
  const auto status = google::protobuf::util::JsonStringToMessage(text, &message);
  if (!status.ok()) {
    std::cerr << "chasles: '" << path << "' is not a valid " << Message::descriptor()->full_name()
              << " in protobuf JSON: " << status.ToString() << "\n";
    std::exit(kExitUsage);
  }
  return message;
}

std::shared_ptr<grpc::Channel> MakeChannel(const Options& options) {
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(-1);
  args.SetMaxSendMessageSize(-1);
  return chasles::cli::MakeChannel(options.connection, args);
}

void SetDeadline(grpc::ClientContext* context, double seconds) {
  context->set_deadline(std::chrono::system_clock::now() +
                        std::chrono::duration_cast<std::chrono::system_clock::duration>(
                            std::chrono::duration<double>(seconds)));
}

const char* CodeName(grpc::StatusCode code) {
  switch (code) {
    case grpc::StatusCode::OK: return "OK";
    case grpc::StatusCode::CANCELLED: return "CANCELLED";
    case grpc::StatusCode::UNKNOWN: return "UNKNOWN";
    case grpc::StatusCode::INVALID_ARGUMENT: return "INVALID_ARGUMENT";
    case grpc::StatusCode::DEADLINE_EXCEEDED: return "DEADLINE_EXCEEDED";
    case grpc::StatusCode::NOT_FOUND: return "NOT_FOUND";
    case grpc::StatusCode::ALREADY_EXISTS: return "ALREADY_EXISTS";
    case grpc::StatusCode::PERMISSION_DENIED: return "PERMISSION_DENIED";
    case grpc::StatusCode::RESOURCE_EXHAUSTED: return "RESOURCE_EXHAUSTED";
    case grpc::StatusCode::FAILED_PRECONDITION: return "FAILED_PRECONDITION";
    case grpc::StatusCode::ABORTED: return "ABORTED";
    case grpc::StatusCode::OUT_OF_RANGE: return "OUT_OF_RANGE";
    case grpc::StatusCode::UNIMPLEMENTED: return "UNIMPLEMENTED";
    case grpc::StatusCode::INTERNAL: return "INTERNAL";
    case grpc::StatusCode::UNAVAILABLE: return "UNAVAILABLE";
    case grpc::StatusCode::DATA_LOSS: return "DATA_LOSS";
    case grpc::StatusCode::UNAUTHENTICATED: return "UNAUTHENTICATED";
    default: return "?";
  }
}

int ReportRpcError(const char* rpc, const Options& options, const grpc::Status& status) {
  std::cerr << "chasles: " << rpc << " on " << options.connection.server << " failed: " << CodeName(status.error_code())
            << ": " << status.error_message() << "\n";
  return kExitFailed;
}

// --- health ------------------------------------------------------------------------------------

int Health(const Options& options) {
  // grpc.health.v1.Health/Check through the generic stub: the request (service "") is empty and
  // the response is field 1 (enum ServingStatus, SERVING = 1) as a varint.
  grpc::GenericStub stub(MakeChannel(options));
  grpc::ClientContext context;
  SetDeadline(&context, options.timeout > 0 ? options.timeout : 10.0);
  grpc::Slice empty_slice(std::string{});
  grpc::ByteBuffer request(&empty_slice, 1);
  grpc::ByteBuffer response;
  std::promise<grpc::Status> done;
  stub.UnaryCall(&context, "/grpc.health.v1.Health/Check", grpc::StubOptions(), &request, &response,
                 [&done](grpc::Status status) { done.set_value(std::move(status)); });
  const grpc::Status status = done.get_future().get();
  if (!status.ok()) return ReportRpcError("health check", options, status);
  std::vector<grpc::Slice> slices;
  std::string bytes;
  if (response.Dump(&slices).ok()) {
    for (const grpc::Slice& slice : slices) bytes.append(reinterpret_cast<const char*>(slice.begin()), slice.size());
  }
  int serving_status = 0;  // UNKNOWN
  if (bytes.size() >= 2 && static_cast<unsigned char>(bytes[0]) == 0x08) {
    serving_status = static_cast<unsigned char>(bytes[1]) & 0x7f;
  }
  static const char* kNames[] = {"UNKNOWN", "SERVING", "NOT_SERVING", "SERVICE_UNKNOWN"};
  const char* name = serving_status >= 0 && serving_status <= 3 ? kNames[serving_status] : "?";
  std::cout << options.connection.server << ": " << name << "\n";
  return serving_status == 1 ? kExitOk : kExitFailed;
}

// --- planners ----------------------------------------------------------------------------------

std::string FormatValue(double value, v1::ParameterDescription::Type type) {
  std::ostringstream out;
  if (type == v1::ParameterDescription::BOOL) {
    out << (value != 0.0 ? "true" : "false");
  } else {
    out << value;
  }
  return out.str();
}

const char* TypeName(v1::ParameterDescription::Type type) {
  switch (type) {
    case v1::ParameterDescription::DOUBLE: return "double";
    case v1::ParameterDescription::INT: return "int";
    case v1::ParameterDescription::BOOL: return "bool";
    default: return "?";
  }
}

int Planners(const Options& options) {
  auto stub = v1::Planning::NewStub(MakeChannel(options));
  grpc::ClientContext context;
  SetDeadline(&context, options.timeout > 0 ? options.timeout : 10.0);
  v1::ListPlannersResponse response;
  const grpc::Status status = stub->ListPlanners(&context, v1::ListPlannersRequest(), &response);
  if (!status.ok()) return ReportRpcError("ListPlanners", options, status);
  std::printf("%-20s %-10s %s\n", "ID", "OPTIMIZING", "DESCRIPTION");
  for (const v1::PlannerDescription& planner : response.planners()) {
    std::printf("%-20s %-10s %s\n", planner.id().c_str(), planner.optimizing() ? "yes" : "no",
                planner.description().c_str());
    std::string kinds;
    for (const std::string& kind : planner.robot_kinds()) kinds += (kinds.empty() ? "" : ", ") + kind;
    std::printf("    %-22s %s\n", "robot kinds", kinds.c_str());
    for (const v1::ParameterDescription& p : planner.parameters()) {
      const std::string range = p.type() == v1::ParameterDescription::BOOL
                                    ? "true/false"
                                    : "[" + FormatValue(p.min(), p.type()) + ", " + FormatValue(p.max(), p.type()) + "]";
      std::printf("    %-22s %-6s default %-10s range %-18s %s\n", p.name().c_str(), TypeName(p.type()),
                  FormatValue(p.default_value(), p.type()).c_str(), range.c_str(), p.description().c_str());
    }
  }
  return kExitOk;
}

// --- plan --------------------------------------------------------------------------------------

bool EndsWith(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() && text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::string FormatPositions(const google::protobuf::RepeatedField<double>& values) {
  std::string out = "[";
  char buffer[32];
  for (int i = 0; i < values.size(); ++i) {
    std::snprintf(buffer, sizeof(buffer), "%s%.6f", i == 0 ? "" : ", ", values[i]);
    out += buffer;
  }
  return out + "]";
}

v1::TrajectoryOptions::PostProcessing MethodOrExit(const std::string& method) {
  if (method == "topp") return v1::TrajectoryOptions::TOPP;
  if (method == "collocation") return v1::TrajectoryOptions::COLLOCATION;
  if (method == "spline") return v1::TrajectoryOptions::SPLINE;
  if (method == "none") return v1::TrajectoryOptions::NONE;
  UsageError("--method '" + method + "' must be topp, collocation, spline or none");
}

void PrintOptimizer(const v1::OptimizerStatistics& o, const v1::TrajectoryQuality& q) {
  std::printf("trajectory  %s (asked: %s)%s%s\n", o.used().c_str(), o.requested().c_str(),
              o.fell_back() ? " — fell back: " : "", o.fell_back() ? o.message().c_str() : "");
  if (!o.solver_status().empty()) {
    std::printf("solver      %s, %d iterations, %.1f ms, violation %.2g, time scale %.6f\n", o.solver_status().c_str(),
                o.iterations(), 1e3 * o.solve_seconds(), o.constraint_violation(), o.time_scale());
  }
  if (o.blends() > 0 || o.blends_tightened() > 0) {
    std::printf("blends      %d corners blended (%d tightened off obstacles)\n", o.blends(), o.blends_tightened());
  }
  if (o.duration_ratio_to_topp() > 0.0) {
    std::printf("vs TOPP     %.6f of TOPP's %.4f s", o.duration_ratio_to_topp(), o.topp_duration());
    if (o.path_deviation() >= 0.0) std::printf("; within %.6f rad of the path (exact bound)", o.path_deviation());
    std::printf("\n");
  }
  // An empty scene has no clearance to report (the server sends the largest double).
  char clearance[64];
  if (q.min_clearance() > 1e300) {
    std::snprintf(clearance, sizeof clearance, "none (no obstacle)");
  } else {
    std::snprintf(clearance, sizeof clearance, "%.4g m", q.min_clearance());
  }
  std::printf("quality     max |qd|/v %.3f  |qdd|/a %.3f  |jerk| %.4g rad/s³%s  deviation %.4g rad  clearance %s  "
              "∫jerk² %.4g\n",
              q.max_velocity_ratio(), q.max_acceleration_ratio(), q.max_jerk(),
              q.max_effort_ratio() > 0 ? (" |τ|/τmax " + std::to_string(q.max_effort_ratio())).c_str() : "",
              q.max_deviation(), clearance, q.jerk_integral());
  if (q.max_constraint_ratio() > 0.0) {
    std::printf("constraints max |error|/tolerance %.4f at the samples (verification checks them with the collisions)\n",
                q.max_constraint_ratio());
  }
}

/// Writes `text` to `file`; prints where. False (with the reason on stderr) on failure.
bool WriteText(const std::string& file, const std::string& text) {
  std::ofstream out(file, std::ios::binary);
  out << text;
  if (!out.good()) {
    std::cerr << "chasles: cannot write '" << file << "': " << std::strerror(errno) << "\n";
    return false;
  }
  std::printf("wrote       %s\n", file.c_str());
  return true;
}

/// Writes the response (.json) or its trajectory (.csv); prints where. False on failure.
bool WriteOut(const std::string& file, const google::protobuf::Message& response, const v1::JointTrajectory& trajectory) {
  std::ofstream out(file, std::ios::binary);
  if (!out) {
    std::cerr << "chasles: cannot write '" << file << "': " << std::strerror(errno) << "\n";
    return false;
  }
  if (EndsWith(file, ".csv")) {
    chasles::WriteTrajectoryCsv(trajectory, out);
  } else {
    google::protobuf::util::JsonPrintOptions print;
    print.add_whitespace = true;
    print.preserve_proto_field_names = true;
    std::string json;
    google::protobuf::util::MessageToJsonString(response, &json, print);
    out << json;
  }
  if (!out.good()) {
    std::cerr << "chasles: writing '" << file << "' failed\n";
    return false;
  }
  std::printf("wrote       %s\n", file.c_str());
  return true;
}

void RequireOutFormat(const Options& options) {
  if (!options.out.empty() && !EndsWith(options.out, ".json") && !EndsWith(options.out, ".csv")) {
    UsageError("--out '" + options.out + "' must end in .json or .csv");
  }
}

/// Writes --out when given; exit 0 only when a trajectory came back.
int FinishWithTrajectory(const Options& options, const google::protobuf::Message& response, v1::PlanOutcome outcome,
                         const std::string& message, const v1::JointTrajectory& trajectory) {
  if (!options.out.empty() && !WriteOut(options.out, response, trajectory)) return kExitFailed;
  if (outcome != v1::SUCCESS || trajectory.points_size() == 0) {
    std::cerr << "chasles: no trajectory: " << v1::PlanOutcome_Name(outcome) << ": " << message << "\n";
    return kExitFailed;
  }
  return kExitOk;
}

int Plan(const Options& options) {
  if (options.positional.size() != 2) UsageError("plan takes one REQUEST.json");
  RequireOutFormat(options);
  const std::string& path = options.positional[1];
  v1::PlanRequest request = ParseJsonFileOrExit<v1::PlanRequest>(path);
  if (!options.method.empty()) request.mutable_trajectory()->set_post_processing(MethodOrExit(options.method));
  chasles::cli::ApplyPlanOverrides(options.overrides, &request);

  auto stub = v1::Planning::NewStub(MakeChannel(options));
  grpc::ClientContext context;
  const double budget = request.time_budget() > 0 ? request.time_budget() : 5.0;
  SetDeadline(&context, options.timeout > 0 ? options.timeout : budget + 30.0);
  v1::PlanResponse response;
  const grpc::Status status = stub->Plan(&context, request, &response);
  if (!status.ok()) return ReportRpcError("Plan", options, status);

  const v1::StageTimings& t = response.timings();
  const v1::Verification& v = response.verification();
  std::printf("request     %s\n", response.request_id().c_str());
  std::printf("outcome     %s\n", v1::PlanOutcome_Name(response.outcome()).c_str());
  std::printf("message     %s\n", response.message().c_str());
  for (const std::string& warning : response.warnings()) std::printf("warning     %s\n", warning.c_str());
  if (response.has_repair()) {
    std::printf("repair      %s after verification found: %s\n", response.repair().repaired() ? "succeeded" : "failed",
                response.repair().failure().c_str());
    for (const std::string& action : response.repair().actions()) std::printf("  tried     %s\n", action.c_str());
  }
  std::printf("robot/scene %s / %s\n", response.robot_id().c_str(), response.scene_id().c_str());
  std::printf("duration    %.4f s\n", response.duration());
  std::printf("waypoints   %d (planner returned %u)\n", response.path_size(), response.statistics().raw_waypoints());
  std::printf("samples     %d\n", response.trajectory().points_size());
  std::printf("path length %.4f (joint space: rad, m for prismatic joints)\n", response.statistics().path_length());
  std::printf("timings ms  validate %.1f  plan %.1f  shortcut %.1f  parameterize %.1f  optimize %.1f  verify %.1f  "
              "repair %.1f  total %.1f\n",
              1e3 * t.validate(), 1e3 * t.plan(), 1e3 * t.shortcut(), 1e3 * t.parameterize(), 1e3 * t.optimize(),
              1e3 * t.verify(), 1e3 * t.repair(), 1e3 * t.total());
  PrintOptimizer(response.optimizer(), response.quality());
  if (v.collision_guarantee() == "certified") {
    std::printf("verified    %u states, certified along the continuous motion, max |qd|/v %.3f, max |qdd|/a %.3f\n",
                v.states_checked(), v.max_velocity_ratio(), v.max_acceleration_ratio());
  } else {
    std::printf("verified    %u states at step %.4g rad, max |qd|/v %.3f, max |qdd|/a %.3f\n", v.states_checked(),
                v.max_joint_step(), v.max_velocity_ratio(), v.max_acceleration_ratio());
    if (!v.collision_guarantee_reason().empty()) std::printf("            %s\n", v.collision_guarantee_reason().c_str());
  }
  if (response.has_reached_goal()) {
    std::printf("reached     %s (manipulability %.4g)\n", FormatPositions(response.reached_goal().positions()).c_str(),
                response.goal_manipulability());
  }
  double max_effort = -1.0;
  for (const v1::TrajectoryPoint& point : response.trajectory().points()) {
    for (double e : point.efforts()) max_effort = std::max(max_effort, std::abs(e));
  }
  if (max_effort >= 0.0) std::printf("max |effort| %.4g N·m (N for prismatic joints)\n", max_effort);

  return FinishWithTrajectory(options, response, response.outcome(), response.message(), response.trajectory());
}

// --- optimize ----------------------------------------------------------------------------------

int Optimize(const Options& options) {
  if (options.positional.size() != 2) UsageError("optimize takes one REQUEST.json");
  RequireOutFormat(options);
  v1::OptimizeRequest request = ParseJsonFileOrExit<v1::OptimizeRequest>(options.positional[1]);
  if (!options.method.empty()) request.mutable_options()->set_post_processing(MethodOrExit(options.method));
  if (!options.ros_trajectory.empty()) {  // the input: a ROS / MoveIt trajectory instead of the request's
    try {
      *request.mutable_trajectory() = chasles::moveit::ImportJointTrajectory(
          ReadFileOrExit(options.ros_trajectory, "trajectory"), options.ros_trajectory);
    } catch (const chasles::Error& e) {
      std::cerr << "chasles: " << e.what() << "\n";
      return kExitUsage;
    }
    request.clear_path();
  }
  auto stub = v1::Planning::NewStub(MakeChannel(options));
  grpc::ClientContext context;
  const double budget = request.time_budget() > 0 ? request.time_budget() : 10.0;
  SetDeadline(&context, options.timeout > 0 ? options.timeout : budget + 30.0);
  v1::OptimizeResponse response;
  const grpc::Status status = stub->Optimize(&context, request, &response);
  if (!status.ok()) return ReportRpcError("Optimize", options, status);
  const v1::StageTimings& t = response.timings();
  std::printf("request     %s\n", response.request_id().c_str());
  std::printf("outcome     %s\n", v1::PlanOutcome_Name(response.outcome()).c_str());
  std::printf("message     %s\n", response.message().c_str());
  std::printf("duration    %.4f s%s\n", response.duration(),
              response.input_duration() > 0
                  ? (" (input " + std::to_string(response.input_duration()) + " s)").c_str()
                  : "");
  std::printf("samples     %d\n", response.trajectory().points_size());
  std::printf("timings ms  parameterize %.1f  optimize %.1f  verify %.1f  total %.1f\n", 1e3 * t.parameterize(),
              1e3 * t.optimize(), 1e3 * t.verify(), 1e3 * t.total());
  PrintOptimizer(response.optimizer(), response.quality());
  return FinishWithTrajectory(options, response, response.outcome(), response.message(), response.trajectory());
}

// --- cartesian ---------------------------------------------------------------------------------

int CartesianPath(const Options& options) {
  if (options.positional.size() != 2) UsageError("cartesian takes one REQUEST.json");
  RequireOutFormat(options);
  v1::CartesianPathRequest request = ParseJsonFileOrExit<v1::CartesianPathRequest>(options.positional[1]);
  if (!options.method.empty()) request.mutable_options()->set_post_processing(MethodOrExit(options.method));
  auto stub = v1::Planning::NewStub(MakeChannel(options));
  grpc::ClientContext context;
  const double budget = request.time_budget() > 0 ? request.time_budget() : 10.0;
  SetDeadline(&context, options.timeout > 0 ? options.timeout : budget + 30.0);
  v1::CartesianPathResponse response;
  const grpc::Status status = stub->CartesianPath(&context, request, &response);
  if (!status.ok()) return ReportRpcError("CartesianPath", options, status);
  std::printf("request     %s\n", response.request_id().c_str());
  std::printf("stop        %s\n", v1::CartesianPathResponse::Stop_Name(response.stop()).c_str());
  if (!response.message().empty()) std::printf("message     %s\n", response.message().c_str());
  for (const std::string& warning : response.warnings()) std::printf("warning     %s\n", warning.c_str());
  std::printf("fraction    %.4f (%d of %u steps; %u waypoints reached) in %.2f ms\n", response.fraction(),
              response.path_size() - 1, response.steps(), response.waypoints_reached(), 1e3 * response.seconds());
  std::printf("pose error  %.3g m, %.3g rad at the states; line %.3g m, %.3g rad between them\n",
              response.max_position_error(), response.max_orientation_error(), response.max_line_deviation(),
              response.max_line_rotation_deviation());
  const v1::OptimizeResponse& timed = response.timed();
  if (response.path_size() < 2) {
    if (!options.out.empty() && !WriteOut(options.out, response, timed.trajectory())) return kExitFailed;
    std::cerr << "chasles: no Cartesian path: " << v1::CartesianPathResponse::Stop_Name(response.stop()) << ": "
              << response.message() << "\n";
    return kExitFailed;
  }
  std::printf("timed       %s, %.4f s, %d samples; the link within %.3g m of the lines\n",
              v1::PlanOutcome_Name(timed.outcome()).c_str(), timed.duration(), timed.trajectory().points_size(),
              response.trajectory_line_deviation());
  // A partial path is still a trajectory (fraction says how far it goes); exit 0 only when complete.
  const int finished = FinishWithTrajectory(options, response, timed.outcome(), timed.message(), timed.trajectory());
  if (finished != kExitOk) return finished;
  if (response.stop() != v1::CartesianPathResponse::COMPLETE) {
    std::cerr << "chasles: the Cartesian path ends at fraction " << response.fraction() << ": " << response.message()
              << "\n";
    return kExitFailed;
  }
  return kExitOk;
}

// --- replan ------------------------------------------------------------------------------------

int Replan(const Options& options) {
  if (options.positional.size() != 2) UsageError("replan takes one MESSAGES.jsonl");
  RequireOutFormat(options);
  const std::string& path = options.positional[1];
  std::istringstream lines(ReadFileOrExit(path, "chasles.v1.ReplanRequest lines"));
  std::vector<v1::ReplanRequest> messages;
  std::string line;
  for (int number = 1; std::getline(lines, line); ++number) {
    if (line.find_first_not_of(" \t\r") == std::string::npos || line[line.find_first_not_of(" \t")] == '#') continue;
    v1::ReplanRequest message;
    const auto status = google::protobuf::util::JsonStringToMessage(line, &message);
    if (!status.ok()) {
      std::cerr << "chasles: '" << path << "' line " << number << " is not a valid chasles.v1.ReplanRequest in protobuf JSON: "
                << status.ToString() << "\n";
      return kExitUsage;
    }
    messages.push_back(std::move(message));
  }
  if (messages.empty()) UsageError("'" + path + "' holds no ReplanRequest");
  auto stub = v1::Planning::NewStub(MakeChannel(options));
  grpc::ClientContext context;
  double budget = 0.0;
  for (const v1::ReplanRequest& m : messages) budget += m.plan().time_budget() > 0 ? m.plan().time_budget() : 5.0;
  SetDeadline(&context, options.timeout > 0 ? options.timeout : budget + 30.0);
  auto stream = stub->Replan(&context);
  v1::ReplanResponse last;
  bool answered = false;
  for (const v1::ReplanRequest& message : messages) {
    if (!stream->Write(message)) break;
    v1::ReplanResponse answer;
    if (!stream->Read(&answer)) break;
    const v1::PlanResponse& plan = answer.plan();
    std::printf("message %-3llu t = %-8.3f %-9s %s, %.4f s, %d samples, %.2f ms%s%s\n",
                static_cast<unsigned long long>(answer.sequence()), answer.time(),
                v1::ReplanResponse::Action_Name(answer.action()).c_str(), v1::PlanOutcome_Name(plan.outcome()).c_str(),
                plan.duration(), plan.trajectory().points_size(), 1e3 * answer.seconds(),
                answer.reason().empty() ? "" : "\n            because ", answer.reason().c_str());
    if (plan.outcome() != v1::SUCCESS) std::printf("            %s\n", plan.message().c_str());
    last = answer;
    answered = true;
  }
  stream->WritesDone();
  const grpc::Status status = stream->Finish();
  if (!status.ok()) return ReportRpcError("Replan", options, status);
  if (!answered) {
    std::cerr << "chasles: the stream ended without an answer\n";
    return kExitFailed;
  }
  return FinishWithTrajectory(options, last, last.plan().outcome(), last.plan().message(), last.plan().trajectory());
}

// --- view --------------------------------------------------------------------------------------

/// Parses `text` as `Message` (protobuf JSON, unknown fields refused); false when it is not one.
template <typename Message>
bool ParsesAs(const std::string& text, Message* message) {
  return google::protobuf::util::JsonStringToMessage(text, message).ok();
}

int View(const Options& options) {
  if (options.positional.size() < 2 || options.positional.size() > 3) UsageError("view takes RESPONSE.json [REQUEST.json]");
  const bool exports = !options.moveit_yaml.empty() || !options.ros_json.empty();
  if (options.out.empty() && !exports) UsageError("view needs --out VIEW.html (or --moveit-yaml F / --ros-json F)");
  if (!options.out.empty() && !EndsWith(options.out, ".html")) UsageError("--out '" + options.out + "' must end in .html");
  const std::string response_text = ReadFileOrExit(options.positional[1], "response");
  const std::string request_text = options.positional.size() == 3 ? ReadFileOrExit(options.positional[2], "request") : "";
  try {
    chasles::ModelStore store(chasles::DefaultRobotProto(), chasles::DefaultSceneProto());
    chasles::ViewInput view;
    v1::CoordinateResponse coordinated;
    v1::PlanResponse planned;
    v1::OptimizeResponse optimized;
    v1::CoordinateRequest team;
    v1::PlanRequest plan;
    v1::OptimizeRequest optimize;
    const bool has_request = !request_text.empty();
    if (ParsesAs(response_text, &coordinated) && coordinated.robots_size() > 0) {
      if (has_request && !ParsesAs(request_text, &team)) UsageError("'" + options.positional[2] + "' is not a chasles.v1.CoordinateRequest");
      view = chasles::ViewOfCoordinate(store, team, coordinated);
    } else if ((!has_request || ParsesAs(request_text, &plan)) && ParsesAs(response_text, &planned)) {
      view = chasles::ViewOfPlan(store, plan, planned);
    } else if ((!has_request || ParsesAs(request_text, &optimize)) && ParsesAs(response_text, &optimized)) {
      view = chasles::ViewOfOptimize(store, optimize, optimized);
    } else {
      std::cerr << "chasles: '" << options.positional[1] << "'" << (has_request ? " with '" + options.positional[2] + "'" : "")
                << " is not a Plan, Optimize or Coordinate response (and request) in protobuf JSON\n";
      return kExitUsage;
    }
    if (!options.moveit_yaml.empty() || !options.ros_json.empty()) {
      // One file per robot: the planning robot's (or a team's first) as named, every other
      // robot of a team as <stem>_<robot><extension>. Moving obstacles are not exported.
      const auto named = [](const std::string& file, const std::string& robot, bool first) {
        if (first) return file;
        const std::size_t dot = file.rfind('.');
        const std::size_t slash = file.rfind('/');
        const bool extension = dot != std::string::npos && (slash == std::string::npos || dot > slash);
        return extension ? file.substr(0, dot) + "_" + robot + file.substr(dot) : file + "_" + robot;
      };
      bool first = true;
      for (const chasles::ViewRobot& robot : view.robots) {
        if (robot.samples.empty() || !robot.measure_clearance) continue;
        if (!options.moveit_yaml.empty() &&
            !WriteText(named(options.moveit_yaml, robot.name, first), chasles::MoveItTrajectoryYaml(*robot.robot.model, robot.samples))) {
          return kExitFailed;
        }
        if (!options.ros_json.empty() &&
            !WriteText(named(options.ros_json, robot.name, first), chasles::RosTrajectoryJson(*robot.robot.model, robot.samples))) {
          return kExitFailed;
        }
        first = false;
      }
    }
    if (!options.out.empty()) {
      if (!WriteText(options.out, chasles::ViewPageHtml(chasles::ViewDataJson(view)))) return kExitFailed;
      std::printf("view        %s (%zu robot%s, %.3f s)\n", view.title.c_str(), view.robots.size(),
                  view.robots.size() == 1 ? "" : "s", view.robots.empty() || view.robots.front().samples.empty() ? 0.0
                                                                                 : view.robots.front().samples.back().t);
    }
  } catch (const chasles::Error& e) {
    std::cerr << "chasles: view: " << e.what() << "\n";
    return kExitFailed;
  }
  return kExitOk;
}

// --- ik ----------------------------------------------------------------------------------------

int InverseKinematics(const Options& options) {
  if (options.positional.size() != 2) UsageError("ik takes one REQUEST.json");
  const v1::InverseKinematicsRequest request = ParseJsonFileOrExit<v1::InverseKinematicsRequest>(options.positional[1]);
  auto stub = v1::Planning::NewStub(MakeChannel(options));
  grpc::ClientContext context;
  const double budget = request.time_budget() > 0 ? request.time_budget() : 0.05;
  SetDeadline(&context, options.timeout > 0 ? options.timeout : budget + 10.0);
  v1::InverseKinematicsResponse response;
  const grpc::Status status = stub->InverseKinematics(&context, request, &response);
  if (!status.ok()) return ReportRpcError("InverseKinematics", options, status);
  std::printf("solved      %s\n", response.solved() ? "yes" : "no");
  if (!response.message().empty()) std::printf("message     %s\n", response.message().c_str());
  std::printf("robot       %s\n", response.robot_id().c_str());
  std::printf("attempts    %u in %.2f ms; best error %.3g m, %.3g rad\n", response.attempts(), 1e3 * response.seconds(),
              response.best_position_error(), response.best_orientation_error());
  std::string names;
  for (const std::string& name : response.joint_names()) names += (names.empty() ? "" : ", ") + name;
  std::printf("joints      %s\n", names.c_str());
  for (int i = 0; i < response.solutions_size(); ++i) {
    std::printf("solution %d  %s  manipulability %.4g%s\n", i, FormatPositions(response.solutions(i).positions()).c_str(),
                i < response.manipulability_size() ? response.manipulability(i) : 0.0,
                i < response.singular_size() && response.singular(i) ? "  SINGULAR" : "");
  }
  if (!response.solved()) {
    std::cerr << "chasles: no IK solution: " << response.message() << "\n";
    return kExitFailed;
  }
  return kExitOk;
}

// --- uploads -----------------------------------------------------------------------------------

int UploadRobot(const Options& options) {
  v1::UploadRobotRequest request;
  if (!options.dh.empty() || !options.poe.empty()) {
    if (!options.dh.empty() && !options.poe.empty()) UsageError("upload-robot takes --dh or --poe, not both");
    if (options.positional.size() != 1) UsageError("upload-robot --dh/--poe takes no FILE.urdf");
    if (!options.srdf.empty() || !options.meshes.empty()) {
      UsageError("--srdf and --mesh belong to URDF robots, not --dh/--poe");
    }
    if (!options.dh.empty()) {
      *request.mutable_robot()->mutable_dh() = ParseJsonFileOrExit<v1::DhRobot>(options.dh);
    } else {
      *request.mutable_robot()->mutable_poe() = ParseJsonFileOrExit<v1::PoeRobot>(options.poe);
    }
  } else {
    if (options.positional.size() != 2) UsageError("upload-robot takes one FILE.urdf (or --dh/--poe FILE.json)");
    v1::UrdfRobot* urdf = request.mutable_robot()->mutable_urdf();
    urdf->set_urdf(ReadFileOrExit(options.positional[1], "URDF"));
    if (!options.srdf.empty()) urdf->set_srdf(ReadFileOrExit(options.srdf, "SRDF"));
    urdf->set_strict_srdf(options.strict_srdf);
    urdf->set_exact_meshes(options.exact_meshes);
    for (const std::string& mesh : options.meshes) {
      const auto eq = mesh.find('=');
      if (eq == std::string::npos || eq == 0 || eq + 1 == mesh.size()) {
        UsageError("--mesh '" + mesh + "' must be NAME=FILE (NAME as in the URDF <mesh filename>)");
      }
      (*urdf->mutable_mesh_files())[mesh.substr(0, eq)] = ReadFileOrExit(mesh.substr(eq + 1), "mesh");
    }
  }
  auto stub = v1::Planning::NewStub(MakeChannel(options));
  grpc::ClientContext context;
  // An upload of a mesh robot fits its spheres once, which can take a while for a big robot.
  SetDeadline(&context, options.timeout > 0 ? options.timeout : 300.0);
  v1::UploadRobotResponse response;
  const grpc::Status status = stub->UploadRobot(&context, request, &response);
  if (!status.ok()) return ReportRpcError("UploadRobot", options, status);
  std::printf("robot_id %s\n", response.robot_id().c_str());
  for (const std::string& warning : response.warnings()) std::printf("warning  %s\n", warning.c_str());
  for (const v1::PlanningGroupInfo& group : response.groups()) {
    std::string joints;
    for (const std::string& joint : group.joint_names()) joints += (joints.empty() ? "" : ", ") + joint;
    std::printf("group    %s: %s\n", group.name().c_str(), joints.c_str());
  }
  const v1::CollisionModel& collision = response.collision_model();
  if (collision.kind() == "fitted_spheres") {
    std::printf("collision model: %d spheres fitted to %d shapes in %.2f s, reaching at most %.1f mm outside them "
                "(link '%s')\n",
                collision.spheres(), collision.shapes_fitted(), collision.fit_seconds(), 1e3 * collision.reach(),
                collision.reach_link().c_str());
  } else {
    std::printf("collision model: %s\n", collision.kind().c_str());
  }
  for (int i = 0; i < response.joint_names_size(); ++i) {
    // Limits as the server holds them (shortest text that reads back exactly), never rounded:
    // a value compared against them must see the same number.
    std::printf("  %-24s [%s, %s]  v_max %s\n", response.joint_names(i).c_str(),
                chasles::FormatNumber(response.lower_limits(i)).c_str(),
                chasles::FormatNumber(response.upper_limits(i)).c_str(),
                chasles::FormatNumber(response.velocity_limits(i)).c_str());
  }
  return kExitOk;
}

int UploadScene(const Options& options) {
  if (options.positional.size() != 2) UsageError("upload-scene takes one SCENE.json");
  v1::UploadSceneRequest request;
  *request.mutable_scene() = ParseJsonFileOrExit<v1::Scene>(options.positional[1]);
  auto stub = v1::Planning::NewStub(MakeChannel(options));
  grpc::ClientContext context;
  SetDeadline(&context, options.timeout > 0 ? options.timeout : 30.0);
  v1::UploadSceneResponse response;
  const grpc::Status status = stub->UploadScene(&context, request, &response);
  if (!status.ok()) return ReportRpcError("UploadScene", options, status);
  std::printf("scene_id %s\n", response.scene_id().c_str());
  return kExitOk;
}

// --- update-scene ------------------------------------------------------------------------------

/// Parses a number or exits naming `what`.
double ParseNumberOrExit(const std::string& text, const std::string& what) {
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || end == text.c_str() || *end != '\0') UsageError(what + " '" + text + "' is not a number");
  return value;
}

/// Reads a point file: `x y z` per line (commas also separate; blank lines and `#` comments are
/// skipped), or, for a .json file, a JSON list of [x, y, z] triples or of flat numbers.
std::vector<double> ReadPointsOrExit(const std::string& path) {
  const std::string text = ReadFileOrExit(path, "point");
  std::vector<double> points;
  if (EndsWith(path, ".json")) {
    google::protobuf::ListValue list;
    const auto status = google::protobuf::util::JsonStringToMessage(text, &list);
    if (!status.ok()) {
      UsageError("'" + path + "' is not a JSON list of points: " + status.ToString());
    }
    for (int i = 0; i < list.values_size(); ++i) {
      const google::protobuf::Value& v = list.values(i);
      if (v.kind_case() == google::protobuf::Value::kNumberValue) {
        points.push_back(v.number_value());
        continue;
      }
      bool ok = v.kind_case() == google::protobuf::Value::kListValue && v.list_value().values_size() == 3;
      for (int k = 0; ok && k < 3; ++k) {
        ok = v.list_value().values(k).kind_case() == google::protobuf::Value::kNumberValue;
        if (ok) points.push_back(v.list_value().values(k).number_value());
      }
      if (!ok) UsageError("'" + path + "' entry " + std::to_string(i) + " is neither a number nor an [x, y, z] list");
    }
    return points;
  }
  std::istringstream in(text);
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.erase(hash);
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream fields(line);
    std::vector<std::string> tokens;
    for (std::string token; fields >> token;) tokens.push_back(token);
    if (tokens.empty()) continue;
    if (tokens.size() != 3) {
      UsageError("'" + path + "' line " + std::to_string(number) + " has " + std::to_string(tokens.size()) +
                 " values, expected x y z");
    }
    for (const std::string& token : tokens) {
      points.push_back(ParseNumberOrExit(token, "'" + path + "' line " + std::to_string(number) + ": value"));
    }
  }
  return points;
}

int UpdateScene(const Options& options) {
  if (options.positional.size() != 1) UsageError("update-scene takes no positional arguments (use --points FILE)");
  if (options.points.empty()) UsageError("update-scene needs --points FILE");
  if (options.origin.empty()) UsageError("update-scene needs --origin X,Y,Z (the sensor position, world frame [m])");
  v1::UpdateSceneRequest request;
  request.set_scene_id(options.scene_id);
  request.set_octomap(options.octomap);
  std::vector<std::string> parts;
  {
    std::istringstream in(options.origin);
    for (std::string part; std::getline(in, part, ',');) parts.push_back(part);
  }
  if (parts.size() != 3) UsageError("--origin '" + options.origin + "' must be X,Y,Z");
  request.mutable_sensor_origin()->set_x(ParseNumberOrExit(parts[0], "--origin x"));
  request.mutable_sensor_origin()->set_y(ParseNumberOrExit(parts[1], "--origin y"));
  request.mutable_sensor_origin()->set_z(ParseNumberOrExit(parts[2], "--origin z"));
  if (!options.max_range.empty()) request.set_max_range(ParseNumberOrExit(options.max_range, "--max-range"));
  if (!options.resolution.empty()) request.set_resolution(ParseNumberOrExit(options.resolution, "--resolution"));
  for (double value : ReadPointsOrExit(options.points)) request.add_points(value);

  auto stub = v1::Planning::NewStub(MakeChannel(options));
  grpc::ClientContext context;
  SetDeadline(&context, options.timeout > 0 ? options.timeout : 60.0);
  v1::UpdateSceneResponse response;
  const grpc::Status status = stub->UpdateScene(&context, request, &response);
  if (!status.ok()) return ReportRpcError("UpdateScene", options, status);
  std::printf("scene_id %s\n", response.scene_id().c_str());
  std::printf("octomap  %s (resolution %.4g m)\n", response.octomap().c_str(), response.resolution());
  std::printf("points   %llu inserted in %.2f ms; %llu occupied leaves\n",
              static_cast<unsigned long long>(response.points_inserted()), 1e3 * response.seconds(),
              static_cast<unsigned long long>(response.occupied_leaves()));
  return kExitOk;
}

// --- coordinate --------------------------------------------------------------------------------

v1::CoordinateRequest::Method CoordinationMethodOrExit(const std::string& method) {
  if (method == "auto") return v1::CoordinateRequest::AUTO;
  if (method == "prioritized") return v1::CoordinateRequest::PRIORITIZED;
  if (method == "composite") return v1::CoordinateRequest::COMPOSITE;
  if (method == "velocity_tuning") return v1::CoordinateRequest::VELOCITY_TUNING;
  if (method == "sequential") return v1::CoordinateRequest::SEQUENTIAL;
  if (method == "fleet") return v1::CoordinateRequest::FLEET;
  UsageError("--method '" + method + "' must be auto, prioritized, composite, velocity_tuning, sequential or fleet");
}

int Coordinate(const Options& options) {
  if (options.positional.size() != 2) UsageError("coordinate takes one REQUEST.json");
  if (!options.out.empty() && !EndsWith(options.out, ".json")) {
    UsageError("--out '" + options.out + "' must end in .json (coordinate writes the whole response)");
  }
  v1::CoordinateRequest request = ParseJsonFileOrExit<v1::CoordinateRequest>(options.positional[1]);
  if (!options.method.empty()) request.set_method(CoordinationMethodOrExit(options.method));

  auto stub = v1::Planning::NewStub(MakeChannel(options));
  grpc::ClientContext context;
  const double budget = request.time_budget() > 0 ? request.time_budget() : 30.0;
  SetDeadline(&context, options.timeout > 0 ? options.timeout : budget + 30.0);
  v1::CoordinateResponse response;
  const grpc::Status status = stub->Coordinate(&context, request, &response);
  if (!status.ok()) return ReportRpcError("Coordinate", options, status);

  std::printf("request     %s\n", response.request_id().c_str());
  std::printf("outcome     %s\n", v1::PlanOutcome_Name(response.outcome()).c_str());
  std::printf("message     %s\n", response.message().c_str());
  std::string order;
  for (const std::string& name : response.order()) order += (order.empty() ? "" : ", ") + name;
  std::printf("method      %s%s%s (%u reorderings)\n", response.method().empty() ? "-" : response.method().c_str(),
              order.empty() ? "" : ", order ", order.c_str(), response.reorderings());
  std::printf("makespan    %.4f s   sum of durations %.4f s   server %.1f ms\n", response.makespan(),
              response.sum_of_durations(), 1e3 * response.seconds());
  if (response.has_fleet()) {
    const v1::FleetStatistics& f = response.fleet();
    std::printf("fleet       lattice %u x %u at %.4g m (%u free nodes%s, %.1f ms), search %.1f ms, schedule %.1f ms; "
                "%u steps, sum of costs %llu (%llu alone); %d dependencies\n",
                f.width(), f.height(), f.resolution(), f.free_nodes(), f.lattice_cached() ? ", cached" : "",
                1e3 * f.lattice_seconds(), 1e3 * f.search_seconds(), 1e3 * f.schedule_seconds(), f.makespan_steps(),
                static_cast<unsigned long long>(f.sum_of_costs()), static_cast<unsigned long long>(f.sum_of_lower_bounds()),
                response.dependencies_size());
  }
  if (response.robots_size() > 0) {
    std::printf("%-16s %12s %14s %12s %8s %6s\n", "robot", "duration [s]", "start delay [s]", "wait [s]", "samples",
                "knots");
    int shown = 0;
    for (const v1::RobotTrajectory& robot : response.robots()) {
      if (++shown > 20 && response.robots_size() > 24) {
        std::printf("… and %d more robots (--out writes them all)\n", response.robots_size() - 20);
        break;
      }
      std::printf("%-16s %12.4f %14.4f %12.4f %8d %6d\n", robot.name().c_str(), robot.duration(), robot.start_delay(),
                  robot.wait_time(), robot.trajectory().points_size(), robot.knots().times_size());
    }
  }
  for (const v1::MethodAttempt& attempt : response.attempts()) {
    std::printf("attempt     %-16s %-9s %8.1f ms", attempt.method().c_str(),
                attempt.succeeded() ? "succeeded" : "failed", 1e3 * attempt.seconds());
    if (attempt.succeeded()) std::printf("  makespan %.4f s", attempt.makespan());
    if (!attempt.message().empty()) std::printf("  %s", attempt.message().c_str());
    std::printf("\n");
  }
  if (response.has_verification()) {
    const v1::TeamVerification& v = response.verification();
    std::printf("verified    %llu team states at <= %.4g s and joint steps <= %.4g (rad, m for bases); "
                "min robot distance %.4g m; "
                "max |qd|/v %.3f, max |qdd|/a %.3f\n",
                static_cast<unsigned long long>(v.states_checked()), v.time_step(), v.max_joint_step(),
                v.min_robot_distance(), v.max_velocity_ratio(), v.max_acceleration_ratio());
  }
  if (response.start_time() > 0) std::printf("start time  %.3f (workcell clock)\n", response.start_time());

  if (!options.out.empty() && !WriteOut(options.out, response, v1::JointTrajectory())) return kExitFailed;
  if (response.outcome() != v1::SUCCESS || response.robots_size() == 0) {
    std::cerr << "chasles: no coordinated trajectories: " << v1::PlanOutcome_Name(response.outcome()) << ": "
              << response.message() << "\n";
    return kExitFailed;
  }
  return kExitOk;
}

// --- workcells ---------------------------------------------------------------------------------

int CreateWorkcell(const Options& options) {
  if (options.positional.size() != 2) UsageError("workcell takes one NAME");
  v1::CreateWorkcellRequest request;
  request.set_name(options.positional[1]);
  auto stub = v1::Planning::NewStub(MakeChannel(options));
  grpc::ClientContext context;
  SetDeadline(&context, options.timeout > 0 ? options.timeout : 10.0);
  v1::CreateWorkcellResponse response;
  const grpc::Status status = stub->CreateWorkcell(&context, request, &response);
  if (!status.ok()) return ReportRpcError("CreateWorkcell", options, status);
  std::printf("workcell    %s (%s)\n", request.name().c_str(), response.created() ? "created" : "existed");
  std::printf("reserved    %u active reservations\n", response.active_reservations());
  std::printf("clock       %.3f s since the epoch\n", response.now());
  return kExitOk;
}

/// The trajectory to commit: a saved PlanResponse's (or OptimizeResponse's) `trajectory`, or the
/// entry of `robot_name` in a saved CoordinateResponse.
v1::JointTrajectory CommitTrajectoryOrExit(const std::string& path, const std::string& robot_name) {
  const std::string text = ReadFileOrExit(path, "trajectory");
  v1::PlanResponse plan;
  if (google::protobuf::util::JsonStringToMessage(text, &plan).ok() && plan.has_trajectory()) {
    return plan.trajectory();
  }
  v1::CoordinateResponse coordinated;
  if (google::protobuf::util::JsonStringToMessage(text, &coordinated).ok() && coordinated.robots_size() > 0) {
    std::string names;
    for (const v1::RobotTrajectory& robot : coordinated.robots()) {
      if (robot.name() == robot_name) return robot.trajectory();
      names += (names.empty() ? "'" : ", '") + robot.name() + "'";
    }
    UsageError("--robot-name '" + robot_name + "' is not a robot of the CoordinateResponse '" + path +
               "' (robots: " + names + ")");
  }
  v1::OptimizeResponse optimized;
  if (google::protobuf::util::JsonStringToMessage(text, &optimized).ok() && optimized.has_trajectory()) {
    return optimized.trajectory();
  }
  UsageError("--trajectory '" + path +
             "' is neither a chasles.v1.PlanResponse with a trajectory nor a CoordinateResponse with robots "
             "(protobuf JSON, as plan/coordinate --out F.json write them)");
}

/// "X,Y,Z" or "X,Y,Z,YAW" [m, rad] → a pose turned by YAW about z.
v1::Pose BasePoseOrExit(const std::string& text) {
  std::vector<std::string> parts;
  std::istringstream in(text);
  for (std::string part; std::getline(in, part, ',');) parts.push_back(part);
  if (parts.size() != 3 && parts.size() != 4) UsageError("--base-pose '" + text + "' must be X,Y,Z or X,Y,Z,YAW");
  v1::Pose pose;
  pose.mutable_position()->set_x(ParseNumberOrExit(parts[0], "--base-pose x"));
  pose.mutable_position()->set_y(ParseNumberOrExit(parts[1], "--base-pose y"));
  pose.mutable_position()->set_z(ParseNumberOrExit(parts[2], "--base-pose z"));
  if (parts.size() == 4) {
    const double yaw = ParseNumberOrExit(parts[3], "--base-pose yaw");
    pose.mutable_orientation()->set_z(std::sin(yaw / 2));
    pose.mutable_orientation()->set_w(std::cos(yaw / 2));
  }
  return pose;
}

int CommitTrajectory(const Options& options) {
  if (options.positional.size() != 1) UsageError("commit takes no positional arguments (use --trajectory FILE)");
  if (options.workcell.empty()) UsageError("commit needs --workcell W");
  if (options.robot_name.empty()) UsageError("commit needs --robot-name N (who moves)");
  if (options.trajectory.empty()) UsageError("commit needs --trajectory F.json (a saved Plan or Coordinate response)");
  if (!options.robot.empty() && !options.robot_id.empty()) UsageError("commit takes --robot or --robot-id, not both");
  if (!options.srdf.empty() && !EndsWith(options.robot, ".urdf")) UsageError("--srdf belongs to a --robot FILE.urdf");
  v1::CommitTrajectoryRequest request;
  request.set_workcell(options.workcell);
  request.set_robot_name(options.robot_name);
  *request.mutable_trajectory() = CommitTrajectoryOrExit(options.trajectory, options.robot_name);
  if (EndsWith(options.robot, ".urdf")) {
    v1::UrdfRobot* urdf = request.mutable_robot()->mutable_urdf();
    urdf->set_urdf(ReadFileOrExit(options.robot, "URDF"));
    if (!options.srdf.empty()) urdf->set_srdf(ReadFileOrExit(options.srdf, "SRDF"));
    urdf->set_strict_srdf(options.strict_srdf);
  } else if (!options.robot.empty()) {
    *request.mutable_robot() = ParseJsonFileOrExit<v1::RobotModel>(options.robot);
  } else if (!options.robot_id.empty()) {
    request.set_robot_id(options.robot_id);
  }
  if (!options.base_pose.empty()) *request.mutable_base_pose() = BasePoseOrExit(options.base_pose);
  if (!options.start_time.empty()) request.set_start_time(ParseNumberOrExit(options.start_time, "--start-time"));
  if (!options.hold.empty()) request.set_hold(ParseNumberOrExit(options.hold, "--hold"));

  auto stub = v1::Planning::NewStub(MakeChannel(options));
  grpc::ClientContext context;
  SetDeadline(&context, options.timeout > 0 ? options.timeout : 30.0);
  v1::CommitTrajectoryResponse response;
  const grpc::Status status = stub->CommitTrajectory(&context, request, &response);
  if (!status.ok()) return ReportRpcError("CommitTrajectory", options, status);
  std::printf("reservation %s\n", response.reservation_id().c_str());
  std::printf("time        %.3f … %.3f s since the epoch (%.3f s), expires at %.3f\n", response.start_time(),
              response.end_time(), response.end_time() - response.start_time(), response.expires_at());
  std::printf("reserved    %u active reservations in %s\n", response.active_reservations(), options.workcell.c_str());
  return kExitOk;
}

int Release(const Options& options) {
  if (options.positional.size() != 1) UsageError("release takes no positional arguments");
  if (options.workcell.empty()) UsageError("release needs --workcell W");
  if (options.reservation.empty() == options.robot_name.empty()) {
    UsageError("release takes exactly one of --reservation ID and --robot-name N");
  }
  v1::ReleaseRequest request;
  request.set_workcell(options.workcell);
  request.set_reservation_id(options.reservation);
  request.set_robot_name(options.robot_name);
  auto stub = v1::Planning::NewStub(MakeChannel(options));
  grpc::ClientContext context;
  SetDeadline(&context, options.timeout > 0 ? options.timeout : 10.0);
  v1::ReleaseResponse response;
  const grpc::Status status = stub->Release(&context, request, &response);
  if (!status.ok()) return ReportRpcError("Release", options, status);
  std::printf("released    %u reservations; %u active in %s\n", response.released(), response.active_reservations(),
              options.workcell.c_str());
  return kExitOk;
}


}  // namespace

int main(int argc, char** argv) {
  // bench and import-moveit parse their own options (after the global connection flags and --timeout).
  {
    chasles::cli::ConnectionOptions connection;
    double timeout = 0.0;
    int i = 1;
    while (i + 1 < argc) {
      if (chasles::cli::ParseConnectionFlag(argc, argv, &i, &connection)) {
        ++i;
        continue;
      }
      if (std::strcmp(argv[i], "--timeout") != 0) break;
      char* end = nullptr;
      timeout = std::strtod(argv[i + 1], &end);
      if (end == argv[i + 1] || *end != '\0' || !(timeout > 0)) {
        UsageError(std::string("--timeout '") + argv[i + 1] + "' must be a number of seconds > 0");
      }
      i += 2;
    }
    if (i < argc && (std::strcmp(argv[i], "bench") == 0 || std::strcmp(argv[i], "import-moveit") == 0)) {
      const std::vector<std::string> args(argv + i + 1, argv + argc);
      return std::strcmp(argv[i], "bench") == 0 ? chasles::cli::BenchCommand(connection, timeout, args)
                                                : chasles::cli::ImportMoveItCommand(args);
    }
  }
  Options options;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) UsageError(arg + " needs a value");
      return argv[++i];
    };
    if (arg == "--help" || arg == "-h") {
      std::printf(kUsage, chasles::cli::kPlanOverridesUsage, chasles::cli::kConnectionUsage);
      return kExitOk;
    } else if (chasles::cli::ParseConnectionFlag(argc, argv, &i, &options.connection)) {
      continue;
    } else if (arg == "--timeout") {
      const std::string text = value();
      char* end = nullptr;
      options.timeout = std::strtod(text.c_str(), &end);
      if (end == text.c_str() || *end != '\0' || !(options.timeout > 0)) {
        UsageError("--timeout '" + text + "' must be a number of seconds > 0");
      }
    } else if (arg == "--moveit-yaml") {
      options.moveit_yaml = value();
    } else if (arg == "--ros-json") {
      options.ros_json = value();
    } else if (arg == "--ros-trajectory") {
      options.ros_trajectory = value();
    } else if (arg == "--out") {
      options.out = value();
    } else if (arg == "--srdf") {
      options.srdf = value();
    } else if (arg == "--strict-srdf") {
      options.strict_srdf = true;
    } else if (arg == "--exact-meshes") {
      options.exact_meshes = true;
    } else if (arg == "--dh") {
      options.dh = value();
    } else if (arg == "--poe") {
      options.poe = value();
    } else if (arg == "--mesh") {
      options.meshes.push_back(value());
    } else if (arg == "--scene-id") {
      options.scene_id = value();
    } else if (arg == "--octomap") {
      options.octomap = value();
    } else if (arg == "--points") {
      options.points = value();
    } else if (arg == "--origin") {
      options.origin = value();
    } else if (arg == "--max-range") {
      options.max_range = value();
    } else if (arg == "--resolution") {
      options.resolution = value();
    } else if (arg == "--method") {
      options.method = value();
    } else if (arg == "--workcell") {
      options.workcell = value();
    } else if (arg == "--robot-name") {
      options.robot_name = value();
    } else if (arg == "--trajectory") {
      options.trajectory = value();
    } else if (arg == "--robot") {
      options.robot = value();
    } else if (arg == "--robot-id") {
      options.robot_id = value();
    } else if (arg == "--base-pose") {
      options.base_pose = value();
    } else if (arg == "--start-time") {
      options.start_time = value();
    } else if (arg == "--hold") {
      options.hold = value();
    } else if (arg == "--reservation") {
      options.reservation = value();
    } else if (chasles::cli::IsPlanOverrideFlag(arg)) {
      const std::string text = value();
      try {
        chasles::cli::SetPlanOverride(arg, text, &options.overrides);
      } catch (const std::invalid_argument& e) {
        UsageError(e.what());
      }
    } else if (arg.size() > 1 && arg[0] == '-') {
      UsageError("unknown option '" + arg + "'");
    } else {
      options.positional.push_back(arg);
    }
  }
  if (options.positional.empty()) UsageError("missing COMMAND");
  const std::string& command = options.positional[0];
  if (command == "health" || command == "planners") {
    if (options.positional.size() != 1) UsageError(command + " takes no arguments");
    return command == "health" ? Health(options) : Planners(options);
  }
  if (command == "plan") return Plan(options);
  if (!options.overrides.empty()) {
    UsageError("--planner, --budget, --seed, --sample-period and --padding belong to plan and import-moveit, not " +
               command);
  }
  if (command == "optimize") return Optimize(options);
  if (command == "ik") return InverseKinematics(options);
  if (command == "cartesian") return CartesianPath(options);
  if (command == "replan") return Replan(options);
  if (command == "view") return View(options);
  if (command == "upload-robot") return UploadRobot(options);
  if (command == "upload-scene") return UploadScene(options);
  if (command == "update-scene") return UpdateScene(options);
  if (command == "coordinate") return Coordinate(options);
  if (command == "workcell") return CreateWorkcell(options);
  if (command == "commit") return CommitTrajectory(options);
  if (command == "release") return Release(options);
  UsageError("unknown command '" + command + "'");
}
