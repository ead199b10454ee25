#include "chasles/robot/input_limits.h"

#include <string>

#include "chasles/robot/error.h"

namespace chasles {
namespace {

template <typename T>
void RequirePositive(T value, const char* name) {
  if (!(value > 0)) {
    ThrowInvalid(std::string("input_limits.") + name + " = " + std::to_string(value) + " must be > 0");
  }
}

}  // namespace

void InputLimits::Validate() const {
  RequirePositive(max_document_bytes, "max_document_bytes");
  RequirePositive(max_xml_depth, "max_xml_depth");
  RequirePositive(max_links, "max_links");
  RequirePositive(max_dofs, "max_dofs");
  RequirePositive(max_mesh_triangles, "max_mesh_triangles");
  RequirePositive(max_mesh_vertices, "max_mesh_vertices");
  RequirePositive(max_mesh_files, "max_mesh_files");
  RequirePositive(max_octomap_nodes, "max_octomap_nodes");
  RequirePositive(max_cloud_points, "max_cloud_points");
  RequirePositive(max_scene_objects, "max_scene_objects");
}

}  // namespace chasles
