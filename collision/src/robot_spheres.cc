#include "chasles/collision/robot_spheres.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>
#include <vector>

#include "chasles/robot/error.h"

namespace chasles {
namespace {

constexpr int kPrismSides = 24;

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

/// A closed prism around the cylinder of `radius` and `length` along z: its sides touch the
/// cylinder from outside (circumradius radius / cos(π/n)), so it contains the cylinder.
TriangleMesh CircumscribedPrism(double radius, double length) {
  TriangleMesh mesh;
  const double outer = radius / std::cos(M_PI / kPrismSides);
  const double z = 0.5 * length;
  for (int k = 0; k < kPrismSides; ++k) {
    const double a = 2.0 * M_PI * k / kPrismSides;
    mesh.vertices.emplace_back(outer * std::cos(a), outer * std::sin(a), -z);
    mesh.vertices.emplace_back(outer * std::cos(a), outer * std::sin(a), z);
  }
  const int bottom = static_cast<int>(mesh.vertices.size());
  mesh.vertices.emplace_back(0.0, 0.0, -z);
  mesh.vertices.emplace_back(0.0, 0.0, z);
  for (int k = 0; k < kPrismSides; ++k) {
    const int a = 2 * k, b = 2 * ((k + 1) % kPrismSides);
    mesh.triangles.emplace_back(a, b, b + 1);
    mesh.triangles.emplace_back(a, b + 1, a + 1);
    mesh.triangles.emplace_back(bottom, b, a);
    mesh.triangles.emplace_back(bottom + 1, a + 1, b + 1);
  }
  return mesh;
}

}  // namespace

void RobotSphereOptions::Validate() const {
  fit.Validate();
  if (max_spheres_per_link < 1) {
    ThrowInvalid("sphere_fit.max_spheres_per_link = " + std::to_string(max_spheres_per_link) + " must be >= 1");
  }
}

RobotSphereFit FitRobotSpheres(const RobotModel& robot, const RobotSphereOptions& options) {
  options.Validate();
  RobotSphereFit out;
  bool has_mesh = false;
  for (const Link& link : robot.links()) {
    for (const Shape& shape : link.collision) has_mesh = has_mesh || shape.type == ShapeType::kMesh;
  }
  if (!has_mesh) return out;
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<Link> links = robot.links();
  for (Link& link : links) {
    int to_fit = 0;
    for (const Shape& shape : link.collision) to_fit += shape.type == ShapeType::kSphere ? 0 : 1;
    if (to_fit == 0) continue;
    SphereFitOptions fit = options.fit;
    fit.max_spheres = std::max(1, options.max_spheres_per_link / to_fit);
    std::vector<Shape> spheres;
    for (std::size_t s = 0; s < link.collision.size(); ++s) {
      const Shape& shape = link.collision[s];
      const auto add = [&](const Eigen::Vector3d& centre, double radius) {
        spheres.push_back(Shape::Sphere(radius, shape.pose * Eigen::Translation3d(centre)));
      };
      double extra = 0.0;  // how far the fitted stand-in reaches outside the shape itself
      TriangleMesh stand_in;
      const TriangleMesh* mesh = nullptr;
      switch (shape.type) {
        case ShapeType::kSphere:
          spheres.push_back(shape);
          continue;
        case ShapeType::kMesh:
          mesh = shape.mesh.get();
          break;
        case ShapeType::kBox:
          stand_in = BoxMesh(shape.size);
          mesh = &stand_in;
          break;
        case ShapeType::kCylinder:
        case ShapeType::kCapsule:
          stand_in = CircumscribedPrism(shape.radius, shape.length);
          extra = shape.radius * (1.0 / std::cos(M_PI / kPrismSides) - 1.0);
          mesh = &stand_in;
          if (shape.type == ShapeType::kCapsule) {
            add(Eigen::Vector3d(0.0, 0.0, -0.5 * shape.length), shape.radius);
            add(Eigen::Vector3d(0.0, 0.0, 0.5 * shape.length), shape.radius);
          }
          break;
      }
      FittedSpheres fitted;
      try {
        fitted = FitSpheres(*mesh, fit);
      } catch (const Error& e) {
        ThrowInvalid("link '" + link.name + "' collision[" + std::to_string(s) + "]: " + e.what());
      }
      for (std::size_t i = 0; i < fitted.centres.size(); ++i) add(fitted.centres[i], fitted.radii[i]);
      ++out.shapes_fitted;
      if (fitted.reach + extra > out.reach) {
        out.reach = fitted.reach + extra;
        out.reach_link = link.name;
      }
    }
    link.collision = std::move(spheres);
  }
  for (const Link& link : links) out.spheres += static_cast<int>(link.collision.size());
  // The allowed pairs as the robot has them (FromTree adds parent/child pairs again).
  std::vector<std::pair<std::string, std::string>> allowed;
  const int n = robot.num_links();
  for (int a = 0; a < n; ++a) {
    for (int b = a + 1; b < n; ++b) {
      if (robot.allowed_collisions().IsAllowed(a, b)) allowed.emplace_back(links[a].name, links[b].name);
    }
  }
  out.model = RobotModel::FromTree(robot.name(), std::move(links), robot.joints(), allowed, robot.motion(),
                                   robot.load_warnings());
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace chasles
