#pragma once
/// \file
/// The default robot and scene, embedded at build time from examples/ (see server/CMakeLists.txt).

#include <string_view>

namespace chasles {

/// examples/robots/panda.urdf
extern const std::string_view kDefaultRobotUrdf;
/// examples/robots/panda.srdf
extern const std::string_view kDefaultRobotSrdf;
/// examples/scenes/table.json (chasles.v1.Scene in protobuf JSON)
extern const std::string_view kDefaultSceneJson;

}  // namespace chasles
