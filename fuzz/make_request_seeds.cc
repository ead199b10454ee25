// fuzz_request_seeds OUT_DIR FILE.json...: each JSON request (examples/requests) as a seed of
// fuzz_request: one selector byte, then the message's wire bytes. The message type is chosen
// from the file name (coordinate_* = CoordinateRequest, ik_* = InverseKinematicsRequest,
// optimize_* = OptimizeRequest, cartesian_* = CartesianPathRequest, else PlanRequest);
// examples/robots/*.json DH/PoE/mobile files
// become UploadRobotRequest seeds and examples/scenes/*.json UploadSceneRequest seeds.

#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>

#include <google/protobuf/util/json_util.h>

#include "chasles/v1/chasles.pb.h"

namespace {

std::string Read(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

bool Json(const std::string& text, google::protobuf::Message* message) {
  return google::protobuf::util::JsonStringToMessage(text, message).ok();
}

}  // namespace

int main(int argc, char** argv) {
  namespace v1 = chasles::v1;
  if (argc < 3) {
    std::cerr << "usage: fuzz_request_seeds OUT_DIR FILE.json...\n";
    return 2;
  }
  const std::filesystem::path out_dir = argv[1];
  std::filesystem::create_directories(out_dir);
  int failures = 0;
  for (int i = 2; i < argc; ++i) {
    const std::filesystem::path path = argv[i];
    const std::string name = path.stem().string();
    const std::string folder = path.parent_path().filename().string();
    const std::string text = Read(path.string());
    std::unique_ptr<google::protobuf::Message> message;
    char selector = 0;
    bool ok = false;
    if (folder == "robots") {
      auto upload = std::make_unique<v1::UploadRobotRequest>();
      v1::RobotModel* robot = upload->mutable_robot();
      ok = Json(text, robot->mutable_dh()) || Json(text, robot->mutable_poe()) || Json(text, robot->mutable_mobile());
      selector = 3;
      message = std::move(upload);
    } else if (folder == "scenes") {
      auto upload = std::make_unique<v1::UploadSceneRequest>();
      ok = Json(text, upload->mutable_scene());
      selector = 4;
      message = std::move(upload);
    } else if (name.rfind("coordinate_", 0) == 0) {
      message = std::make_unique<v1::CoordinateRequest>();
      selector = 2;
    } else if (name.rfind("ik_", 0) == 0) {
      message = std::make_unique<v1::InverseKinematicsRequest>();
      selector = 6;
    } else if (name.rfind("optimize_", 0) == 0) {
      message = std::make_unique<v1::OptimizeRequest>();
      selector = 1;
    } else if (name.rfind("cartesian_", 0) == 0) {
      message = std::make_unique<v1::CartesianPathRequest>();
      selector = 7;
    } else {
      message = std::make_unique<v1::PlanRequest>();
      selector = 0;
    }
    if (folder != "robots" && folder != "scenes") ok = Json(text, message.get());
    if (!ok) {
      std::cerr << path << ": not a " << message->GetTypeName() << " in JSON\n";
      ++failures;
      continue;
    }
    std::ofstream out(out_dir / (name + ".bin"), std::ios::binary);
    out.put(selector);
    out << message->SerializeAsString();
  }
  return failures == 0 ? 0 : 1;
}
