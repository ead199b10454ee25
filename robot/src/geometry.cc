#include "chasles/robot/geometry.h"

#include <algorithm>
#include <cmath>

namespace chasles {

Shape Shape::Sphere(double radius, const Eigen::Isometry3d& pose) {
  Shape s;
  s.type = ShapeType::kSphere;
  s.radius = radius;
  s.pose = pose;
  return s;
}

Shape Shape::Box(const Eigen::Vector3d& size, const Eigen::Isometry3d& pose) {
  Shape s;
  s.type = ShapeType::kBox;
  s.size = size;
  s.pose = pose;
  return s;
}

Shape Shape::Cylinder(double radius, double length, const Eigen::Isometry3d& pose) {
  Shape s;
  s.type = ShapeType::kCylinder;
  s.radius = radius;
  s.length = length;
  s.pose = pose;
  return s;
}

Shape Shape::Capsule(double radius, double length, const Eigen::Isometry3d& pose) {
  Shape s;
  s.type = ShapeType::kCapsule;
  s.radius = radius;
  s.length = length;
  s.pose = pose;
  return s;
}

double BoundingRadius(const Shape& shape) {
  switch (shape.type) {
    case ShapeType::kSphere: return shape.radius;
    case ShapeType::kBox: return 0.5 * shape.size.norm();
    case ShapeType::kCylinder: return std::hypot(shape.radius, 0.5 * shape.length);
    case ShapeType::kCapsule: return shape.radius + 0.5 * shape.length;
    case ShapeType::kMesh: {
      double r = 0.0;
      if (shape.mesh) {
        for (const Eigen::Vector3d& v : shape.mesh->vertices) r = std::max(r, v.norm());
      }
      return r;
    }
  }
  return 0.0;
}

}  // namespace chasles
