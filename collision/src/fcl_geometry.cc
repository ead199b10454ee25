#include "fcl_geometry.h"

#include <vector>

namespace chasles {

FclGeom MakeGeom(const Shape& s) {
  FclGeom g;
  switch (s.type) {
    case ShapeType::kSphere:
      g.geom = std::make_shared<fcl::Sphered>(s.radius);
      break;
    case ShapeType::kBox:
      g.geom = std::make_shared<fcl::Boxd>(s.size.x(), s.size.y(), s.size.z());
      break;
    case ShapeType::kCylinder:
      g.geom = std::make_shared<fcl::Cylinderd>(s.radius, s.length);
      break;
    case ShapeType::kCapsule:
      g.geom = std::make_shared<fcl::Capsuled>(s.radius, s.length);
      break;
    case ShapeType::kMesh: {
      auto model = std::make_shared<fcl::BVHModel<fcl::OBBRSSd>>();
      std::vector<fcl::Vector3d> vertices(s.mesh->vertices.begin(), s.mesh->vertices.end());
      std::vector<fcl::Triangle> triangles;
      triangles.reserve(s.mesh->triangles.size());
      for (const Eigen::Vector3i& t : s.mesh->triangles) triangles.emplace_back(t[0], t[1], t[2]);
      model->beginModel(static_cast<int>(triangles.size()), static_cast<int>(vertices.size()));
      model->addSubModel(vertices, triangles);
      model->endModel();
      g.geom = model;
      break;
    }
  }
  g.geom->computeLocalAABB();
  g.center = g.geom->aabb_center;
  g.radius = g.geom->aabb_radius;
  return g;
}

}  // namespace chasles
