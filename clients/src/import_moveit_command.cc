// chasles import-moveit: MoveIt PlanningScene + MotionPlanRequest YAML -> chasles.v1.PlanRequest JSON.
#include <google/protobuf/util/json_util.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>

#include "commands.h"
#include "moveit_import.h"
#include "plan_overrides.h"

namespace chasles::cli {
namespace {

constexpr int kOk = 0;
constexpr int kConversionFailed = 1;
constexpr int kUsage = 2;

constexpr const char* kHelpHead =
    "usage: chasles import-moveit SCENE.yaml REQUEST.yaml [--robot F.urdf [--srdf F.srdf]] [--out F.json]\n"
    "                             [--planner ID] [--budget S] [--seed N] [--sample-period S] [--padding M]\n"
    "                             [--group NAME]\n"
    "  Converts a MoveIt PlanningScene and MotionPlanRequest (YAML, e.g. a MotionBenchMaker pair) into a\n"
    "  chasles.v1.PlanRequest and prints it as protobuf JSON (or writes it to --out F.json). No server needed.\n"
    "  A GetCartesianPath request (a REQUEST.yaml with waypoints) becomes a chasles.v1.CartesianPathRequest\n"
    "  for `chasles cartesian` (--sample-period and --padding apply to it, the other flags do not).\n"
    "  --robot F.urdf  read joint and link names from this URDF and embed it (and --srdf) in the request;\n"
    "                  default: the server's default robot (a Panda), not embedded\n"
    "  --srdf F.srdf   its SRDF (allowed collisions)\n"
    "  --out F.json    write the JSON to F.json instead of printing it\n"
    "  The request's planner is left unset (the server's default, rrt_connect) and its budget is the\n"
    "  MoveIt request's allowed_planning_time; these set them, and seed and sample period, instead:\n";

void PrintHelp(std::ostream& out) { out << kHelpHead << kPlanOverridesUsage; }

int Usage(const std::string& message) {
  std::cerr << "chasles: import-moveit: " << message << "\n";
  PrintHelp(std::cerr);
  return kUsage;
}

bool ReadFile(const std::string& path, const char* what, std::string* text) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    std::cerr << "chasles: cannot read " << what << " file '" << path << "': " << std::strerror(errno) << "\n";
    return false;
  }
  std::ostringstream buffer;
  buffer << in.rdbuf();
  *text = buffer.str();
  return true;
}

}  // namespace

int ImportMoveItCommand(const std::vector<std::string>& args) {
  std::vector<std::string> positional;
  std::string robot_file, srdf_file, out;
  PlanOverrides overrides;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    if (arg == "--help" || arg == "-h") {
      PrintHelp(std::cout);
      return kOk;
    }
    if (arg == "--robot" || arg == "--srdf" || arg == "--out") {
      if (i + 1 >= args.size()) return Usage(arg + " needs a value");
      (arg == "--robot" ? robot_file : arg == "--srdf" ? srdf_file : out) = args[++i];
    } else if (IsPlanOverrideFlag(arg)) {
      if (i + 1 >= args.size()) return Usage(arg + " needs a value");
      try {
        SetPlanOverride(arg, args[++i], &overrides);
      } catch (const std::invalid_argument& e) {
        return Usage(e.what());
      }
    } else if (arg.size() > 1 && arg[0] == '-') {
      return Usage("unknown option '" + arg + "'");
    } else {
      positional.push_back(arg);
    }
  }
  if (positional.size() != 2) return Usage("takes SCENE.yaml and REQUEST.yaml");
  if (!srdf_file.empty() && robot_file.empty()) return Usage("--srdf needs --robot F.urdf");
  if (!out.empty() && (out.size() < 5 || out.compare(out.size() - 5, 5, ".json") != 0)) {
    return Usage("--out '" + out + "' must end in .json");
  }

  std::string scene_yaml, request_yaml, urdf, srdf;
  if (!ReadFile(positional[0], "scene", &scene_yaml) || !ReadFile(positional[1], "request", &request_yaml))
    return kUsage;
  if (!robot_file.empty() && !ReadFile(robot_file, "URDF", &urdf)) return kUsage;
  if (!srdf_file.empty() && !ReadFile(srdf_file, "SRDF", &srdf)) return kUsage;

  moveit::RobotInfo robot;
  try {
    robot = robot_file.empty() ? moveit::DefaultRobot() : moveit::RobotFromUrdf(urdf, srdf);
  } catch (const std::exception& e) {
    std::cerr << "chasles: " << (robot_file.empty() ? "the default robot" : robot_file) << ": " << e.what() << "\n";
    return kUsage;
  }
  v1::PlanRequest plan;
  v1::CartesianPathRequest cartesian;
  const bool is_cartesian = moveit::IsCartesianPathRequest(request_yaml);
  if (is_cartesian && (overrides.planner_id || overrides.time_budget || overrides.seed || overrides.group)) {
    return Usage("--planner, --budget, --seed and --group do not apply to a Cartesian path (" + positional[1] +
                 " is a GetCartesianPath request); --sample-period and --padding do");
  }
  try {
    if (is_cartesian) {
      cartesian = moveit::ImportCartesianPathRequest(scene_yaml, request_yaml, robot, positional[0], positional[1]);
    } else {
      plan = moveit::ImportMotionPlanRequest(scene_yaml, request_yaml, robot, positional[0], positional[1]);
    }
  } catch (const std::exception& e) {
    std::cerr << "chasles: " << e.what() << "\n";
    return kConversionFailed;
  }
  if (is_cartesian) {
    if (!robot_file.empty()) *cartesian.mutable_robot() = robot.model;  // self-contained
    if (overrides.sample_period) cartesian.mutable_options()->set_sample_period(*overrides.sample_period);
    if (overrides.padding) cartesian.set_padding(*overrides.padding);
  } else {
    if (!robot_file.empty()) *plan.mutable_robot() = robot.model;  // self-contained
    ApplyPlanOverrides(overrides, &plan);
  }
  const google::protobuf::Message& request = is_cartesian ? static_cast<const google::protobuf::Message&>(cartesian)
                                                          : static_cast<const google::protobuf::Message&>(plan);

  google::protobuf::util::JsonPrintOptions print;
  print.add_whitespace = true;
  print.preserve_proto_field_names = true;
  std::string json;
  const auto status = google::protobuf::util::MessageToJsonString(request, &json, print);
  if (!status.ok()) {
    std::cerr << "chasles: cannot print the request as JSON: " << status.ToString() << "\n";
    return kConversionFailed;
  }
  if (out.empty()) {
    std::cout << json;
    return kOk;
  }
  std::ofstream file(out, std::ios::binary);
  file << json;
  if (!file.good()) {
    std::cerr << "chasles: cannot write '" << out << "': " << std::strerror(errno) << "\n";
    return kUsage;
  }
  std::cout << "wrote       " << out << "\n";
  return kOk;
}

}  // namespace chasles::cli
