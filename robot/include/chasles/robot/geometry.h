#pragma once
/// \file
/// Collision shapes shared by robot links and scene objects. SI units (metres).

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace chasles {

enum class ShapeType { kSphere, kBox, kCylinder, kCapsule, kMesh };

/// A triangle mesh in the shape's own frame (metres, scale already applied).
struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i> triangles;  ///< indices into `vertices`
};

/// One collision shape placed at `pose` in its owner's frame (link frame or world).
/// Cylinders and capsules are centred on their origin with their axis along z.
struct Shape {
  ShapeType type = ShapeType::kSphere;
  double radius = 0.0;                       ///< sphere, cylinder, capsule [m]
  double length = 0.0;                       ///< cylinder, capsule: full length along z [m]
  Eigen::Vector3d size = Eigen::Vector3d::Zero();  ///< box: full extents x, y, z [m]
  std::shared_ptr<const TriangleMesh> mesh;  ///< kMesh only
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();

  static Shape Sphere(double radius, const Eigen::Isometry3d& pose = Eigen::Isometry3d::Identity());
  static Shape Box(const Eigen::Vector3d& size, const Eigen::Isometry3d& pose = Eigen::Isometry3d::Identity());
  static Shape Cylinder(double radius, double length, const Eigen::Isometry3d& pose = Eigen::Isometry3d::Identity());
  static Shape Capsule(double radius, double length, const Eigen::Isometry3d& pose = Eigen::Isometry3d::Identity());
};

/// The radius of the smallest ball about the shape's own origin (`pose` not applied) that holds
/// it [m]: a sphere's radius, half a box's diagonal, √(r² + (l/2)²) for a cylinder, r + l/2 for a
/// capsule, the farthest vertex of a mesh (0 for a null or empty mesh).
double BoundingRadius(const Shape& shape);

}  // namespace chasles
