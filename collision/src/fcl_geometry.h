#pragma once
// Private to collision/: an FCL collision geometry built from a Shape, with its bounding sphere.

#include <memory>

#include <Eigen/Core>
#include <fcl/fcl.h>

#include "chasles/robot/geometry.h"

namespace chasles {

/// An FCL collision geometry with its bounding sphere in its own frame.
struct FclGeom {
  std::shared_ptr<fcl::CollisionGeometryd> geom;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  // bounding centre, own frame
  double radius = 0.0;
};

/// The FCL geometry of `s` (primitive, or a BVHModel<OBBRSS> for a mesh); `s.pose` is not applied.
/// A mesh's BVH is built once per TriangleMesh object and kept while that mesh lives (every
/// checker of a robot, or of a scene, shares its meshes' BVHs). Thread-safe.
FclGeom MakeGeom(const Shape& s);

}  // namespace chasles
