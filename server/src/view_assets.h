#pragma once
// The viewer page's parts, embedded at build time (server/cmake/embed_viewer.cmake): three.js and
// its OrbitControls from Debian's libjs-three, and clients/viewer/'s script, style and template.

#include <string_view>

namespace chasles {

extern const std::string_view kThreeJs;
extern const std::string_view kOrbitControlsJs;
extern const std::string_view kViewerJs;
extern const std::string_view kViewerCss;
extern const std::string_view kViewerTemplate;

}  // namespace chasles
