#include "chasles/robot/geometry.h"

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

}  // namespace chasles
