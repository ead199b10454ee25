#include "chasles/collision/mesh.h"

#include <cmath>
#include <sstream>

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include "chasles/robot/error.h"

namespace chasles {
namespace {

// Appends every triangle of every mesh in `scene` (node transforms applied) to `out`.
void CollectNode(const aiScene& scene, const aiNode& node, const aiMatrix4x4& parent,
                 const Eigen::Vector3d& scale, TriangleMesh* out) {
  const aiMatrix4x4 transform = parent * node.mTransformation;
  for (unsigned m = 0; m < node.mNumMeshes; ++m) {
    const aiMesh* mesh = scene.mMeshes[node.mMeshes[m]];
    if (mesh == nullptr) continue;
    const int base = static_cast<int>(out->vertices.size());
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      const aiVector3D p = transform * mesh->mVertices[v];
      out->vertices.emplace_back(p.x * scale.x(), p.y * scale.y(), p.z * scale.z());
    }
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines left by triangulation
      out->triangles.emplace_back(base + static_cast<int>(face.mIndices[0]),
                                  base + static_cast<int>(face.mIndices[1]),
                                  base + static_cast<int>(face.mIndices[2]));
    }
  }
  for (unsigned c = 0; c < node.mNumChildren; ++c) {
    if (node.mChildren[c] != nullptr) CollectNode(scene, *node.mChildren[c], transform, scale, out);
  }
}

std::shared_ptr<const TriangleMesh> TryRead(const std::string& bytes, const char* hint,
                                            const Eigen::Vector3d& scale, std::string* why) {
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFileFromMemory(
      bytes.data(), bytes.size(), aiProcess_Triangulate | aiProcess_JoinIdenticalVertices, hint);
  if (scene == nullptr || scene->mRootNode == nullptr) {
    if (why->empty()) *why = importer.GetErrorString();
    return nullptr;
  }
  auto mesh = std::make_shared<TriangleMesh>();
  CollectNode(*scene, *scene->mRootNode, aiMatrix4x4(), scale, mesh.get());
  if (mesh->triangles.empty()) {
    *why = "it holds no triangles";
    return nullptr;
  }
  for (const Eigen::Vector3d& v : mesh->vertices) {
    if (!v.allFinite()) {
      *why = "it holds a vertex that is not finite";
      return nullptr;
    }
  }
  return mesh;
}

}  // namespace

std::shared_ptr<const TriangleMesh> ParseMesh(const std::string& bytes, const Eigen::Vector3d& scale,
                                              const std::string& field) {
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(scale[i]) || scale[i] <= 0.0) {
      std::ostringstream os;
      os << field << " scale[" << i << "] = " << scale[i] << " must be finite and > 0";
      ThrowInvalid(os.str());
    }
  }
  if (bytes.empty()) ThrowInvalid(field + " is empty (expected STL or OBJ file bytes)");
  std::string why;
  // Binary STL has no magic number, so try the formats we accept explicitly, STL first.
  for (const char* hint : {"stl", "obj"}) {
    if (auto mesh = TryRead(bytes, hint, scale, &why)) return mesh;
    if (why == "it holds no triangles" || why == "it holds a vertex that is not finite") break;
  }
  ThrowInvalid(field + " is not a readable STL or OBJ mesh" + (why.empty() ? "" : ": " + why));
}

}  // namespace chasles
