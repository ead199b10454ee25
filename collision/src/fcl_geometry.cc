#include "fcl_geometry.h"

#include <iterator>
#include <mutex>
#include <unordered_map>
#include <vector>

namespace chasles {
namespace {

// A mesh's BVH is built once per mesh object. A robot's meshes are shared by every checker
// built for it — one per scene it plans in, so one per request with an inline scene — and the
// build is the dear part (~80 ms for a 20,000-triangle mesh). An entry holds its mesh weakly
// (a hit needs that very mesh object alive: no address reuse) and its BVH strongly, so the BVH
// lives as long as the mesh does, that is as long as its robot or scene, even between checkers;
// entries whose mesh is gone are dropped whenever a BVH is built.
struct CachedBvh {
  std::weak_ptr<const TriangleMesh> mesh;
  std::shared_ptr<fcl::CollisionGeometryd> bvh;
};

struct BvhTable {
  std::mutex mutex;
  std::unordered_map<const TriangleMesh*, CachedBvh> entries;
};

BvhTable& Bvhs() {
  static BvhTable table;
  return table;
}

std::shared_ptr<fcl::CollisionGeometryd> BuildBvh(const TriangleMesh& mesh) {
  auto model = std::make_shared<fcl::BVHModel<fcl::OBBRSSd>>();
  std::vector<fcl::Vector3d> vertices(mesh.vertices.begin(), mesh.vertices.end());
  std::vector<fcl::Triangle> triangles;
  triangles.reserve(mesh.triangles.size());
  for (const Eigen::Vector3i& t : mesh.triangles) triangles.emplace_back(t[0], t[1], t[2]);
  model->beginModel(static_cast<int>(triangles.size()), static_cast<int>(vertices.size()));
  model->addSubModel(vertices, triangles);
  model->endModel();
  model->computeLocalAABB();
  return model;
}

std::shared_ptr<fcl::CollisionGeometryd> SharedBvh(const std::shared_ptr<const TriangleMesh>& mesh) {
  BvhTable& table = Bvhs();
  std::lock_guard<std::mutex> lock(table.mutex);
  const auto it = table.entries.find(mesh.get());
  if (it != table.entries.end() && it->second.mesh.lock() == mesh) return it->second.bvh;
  for (auto e = table.entries.begin(); e != table.entries.end();) {
    e = e->second.mesh.expired() ? table.entries.erase(e) : std::next(e);
  }
  auto bvh = BuildBvh(*mesh);
  table.entries[mesh.get()] = {mesh, bvh};
  return bvh;
}

}  // namespace

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
    case ShapeType::kMesh:
      g.geom = SharedBvh(s.mesh);  // shared: its local AABB was computed once, when it was built
      break;
  }
  if (s.type != ShapeType::kMesh) g.geom->computeLocalAABB();
  g.center = g.geom->aabb_center;
  g.radius = g.geom->aabb_radius;
  return g;
}

}  // namespace chasles
