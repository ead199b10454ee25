#include "chasles/collision/shape_spheres.h"

#include <cmath>
#include <string>

#include "chasles/robot/error.h"
#include "primitive_cover.h"

namespace chasles {
namespace {

TriangleMesh BoxMesh(const Eigen::Vector3d& size) {
  TriangleMesh mesh;
  const Eigen::Vector3d h = 0.5 * size;
  for (int i = 0; i < 8; ++i) {
    mesh.vertices.emplace_back((i & 1) ? h.x() : -h.x(), (i & 2) ? h.y() : -h.y(), (i & 4) ? h.z() : -h.z());
  }
  // Two triangles per face, outward normals.
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : faces) {
    mesh.triangles.emplace_back(f[0], f[1], f[2]);
    mesh.triangles.emplace_back(f[0], f[2], f[3]);
  }
  return mesh;
}

void CheckSize(double value, const char* field, bool zero_allowed) {
  if (!std::isfinite(value) || value < 0.0 || (value == 0.0 && !zero_allowed)) {
    ThrowInvalid(std::string("shape.") + field + " = " + FormatNumber(value) + " must be finite and " +
                 (zero_allowed ? ">= 0" : "> 0"));
  }
}

}  // namespace

FittedSpheres FitShapeSpheres(const Shape& shape, const SphereFitOptions& options) {
  options.Validate();
  switch (shape.type) {
    case ShapeType::kSphere: {
      CheckSize(shape.radius, "radius", false);
      FittedSpheres out;
      out.centres = {Eigen::Vector3d::Zero()};
      out.radii = {shape.radius};
      return out;
    }
    case ShapeType::kCapsule:
      CheckSize(shape.radius, "radius", false);
      CheckSize(shape.length, "length", true);
      return CoverCapsule(shape.radius, shape.length, options.max_reach, options.max_spheres);
    case ShapeType::kCylinder:
      CheckSize(shape.radius, "radius", false);
      CheckSize(shape.length, "length", false);
      return CoverCylinder(shape.radius, shape.length, options.max_reach, options.max_spheres);
    case ShapeType::kBox: {
      for (int axis = 0; axis < 3; ++axis) {
        const char* fields[3] = {"size.x", "size.y", "size.z"};
        CheckSize(shape.size[axis], fields[axis], false);
      }
      FittedSpheres out = FitSpheres(BoxMesh(shape.size), options);
      out.reach = std::min(out.reach, BoxReach(shape.size, out));
      return out;
    }
    case ShapeType::kMesh:
      if (shape.mesh == nullptr) ThrowInvalid("shape.mesh is null");
      return FitSpheres(*shape.mesh, options);
  }
  ThrowInvalid("shape.type is not a known shape type");
}

}  // namespace chasles
