#include "chasles/collision/robot_spheres.h"

#include <algorithm>
#include <chrono>
#include <utility>
#include <vector>

#include "chasles/collision/shape_spheres.h"
#include "chasles/robot/error.h"

namespace chasles {

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
      if (shape.type == ShapeType::kSphere) {
        spheres.push_back(shape);
        continue;
      }
      FittedSpheres fitted;
      try {
        fitted = FitShapeSpheres(shape, fit);
      } catch (const Error& e) {
        throw Error(e.code(), "link '" + link.name + "' collision[" + std::to_string(s) + "]: " + e.what());
      }
      for (std::size_t i = 0; i < fitted.centres.size(); ++i) {
        spheres.push_back(Shape::Sphere(fitted.radii[i], shape.pose * Eigen::Translation3d(fitted.centres[i])));
      }
      ++out.shapes_fitted;
      if (fitted.reach > out.reach) {
        out.reach = fitted.reach;
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
