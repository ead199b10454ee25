// Robot descriptions as JSON (what `chasles upload-robot` reads: examples/robots/*_dh.json,
// *_poe.json, mobile bases): the text is read as a chasles.v1 DhRobot, PoeRobot, MobileRobot and
// RobotModel (protobuf's JSON parser), and each message it parses as goes through the server's
// conversion (DhFromProto + RobotFromDh, PoeFromProto + RobotFromPoe, RobotFromProto).

#include <google/protobuf/stubs/logging.h>
#include <google/protobuf/util/json_util.h>

#include "chasles/server/convert.h"
#include "fuzz_util.h"

namespace {

template <typename Message>
bool FromJson(const std::string& text, Message* message) {
  return google::protobuf::util::JsonStringToMessage(text, message).ok();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const bool quiet = [] {  // protobuf logs every malformed string field it rejects
    google::protobuf::SetLogHandler(nullptr);
    return true;
  }();
  (void)quiet;
  const std::string text(reinterpret_cast<const char*>(data), size);
  chasles::v1::RobotModel model;
  if (FromJson(text, model.mutable_dh())) {
    chasles::fuzz::Expect([&] { chasles::RobotFromProto(model, "robot"); });
  }
  model.Clear();
  if (FromJson(text, model.mutable_poe())) {
    chasles::fuzz::Expect([&] { chasles::RobotFromProto(model, "robot"); });
  }
  model.Clear();
  if (FromJson(text, model.mutable_mobile())) {
    chasles::fuzz::Expect([&] { chasles::RobotFromProto(model, "robot"); });
  }
  model.Clear();
  if (FromJson(text, &model)) {
    chasles::fuzz::Expect([&] { chasles::RobotFromProto(model, "robot"); });
  }
  return 0;
}
