#include "chasles/collision/mesh.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <utility>
#include <vector>

#include <assimp/Importer.hpp>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include "chasles/robot/error.h"

namespace chasles {
namespace {

// The name assimp gives a file read from memory (AI_MEMORYIO_MAGIC_FILENAME); its messages
// quote it, and ours name the caller's field instead.
constexpr char kAssimpMemoryName[] = "$$$___magic___$$$";

std::string ReplaceAll(std::string text, const std::string& from, const std::string& to) {
  for (std::size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size())) {
    text.replace(at, from.size(), to);
  }
  return text;
}

std::string Exhausted(const std::string& field, const char* what, std::uint64_t count, std::size_t cap,
                      const char* limit) {
  return field + " holds " + std::to_string(count) + " " + what + ", more than the cap of " + std::to_string(cap) +
         " per mesh (InputLimits::" + limit + "); simplify the mesh or raise the server's cap";
}

// The meshes every node references, with their node transforms, walked iteratively (the node
// graph comes from the file).
std::vector<std::pair<const aiMesh*, aiMatrix4x4>> PlacedMeshes(const aiScene& scene) {
  std::vector<std::pair<const aiMesh*, aiMatrix4x4>> placed;
  std::vector<std::pair<const aiNode*, aiMatrix4x4>> stack{{scene.mRootNode, scene.mRootNode->mTransformation}};
  while (!stack.empty()) {
    const auto [node, transform] = stack.back();
    stack.pop_back();
    for (unsigned m = 0; m < node->mNumMeshes; ++m) {
      if (node->mMeshes[m] >= scene.mNumMeshes) continue;
      const aiMesh* mesh = scene.mMeshes[node->mMeshes[m]];
      if (mesh != nullptr) placed.emplace_back(mesh, transform);
    }
    // Children pushed in reverse so they are visited in order.
    for (unsigned c = node->mNumChildren; c-- > 0;) {
      if (node->mChildren[c] != nullptr) stack.emplace_back(node->mChildren[c], transform * node->mChildren[c]->mTransformation);
    }
  }
  return placed;
}

std::shared_ptr<const TriangleMesh> TryRead(const std::string& bytes, const char* hint, const Eigen::Vector3d& scale,
                                            const std::string& field, const InputLimits& limits, std::string* why) {
  Assimp::Importer importer;
  // COLLADA: keep the axes as written. assimp would turn a Z_UP document to its own Y-up
  // convention; robot description files are Z-up and ROS tools (RViz, MoveIt's
  // geometric_shapes) undo that turn. The document's <unit meter=…> is still applied.
  importer.SetPropertyBool(AI_CONFIG_IMPORT_COLLADA_IGNORE_UP_DIRECTION, true);
  const aiScene* scene = importer.ReadFileFromMemory(
      bytes.data(), bytes.size(), aiProcess_Triangulate | aiProcess_JoinIdenticalVertices, hint);
  if (scene == nullptr || scene->mRootNode == nullptr) {
    if (why->empty()) {
      *why = ReplaceAll(ReplaceAll(importer.GetErrorString(), std::string(kAssimpMemoryName) + "." + hint, field),
                        kAssimpMemoryName, field);
    }
    return nullptr;
  }
  // Sizes as assimp reports them, before anything is copied.
  const auto placed = PlacedMeshes(*scene);
  std::uint64_t faces = 0, vertices = 0;
  for (const auto& [mesh, transform] : placed) {
    faces += mesh->mNumFaces;
    vertices += mesh->mNumVertices;
  }
  if (faces > limits.max_mesh_triangles) {
    ThrowResourceExhausted(Exhausted(field, "triangles", faces, limits.max_mesh_triangles, "max_mesh_triangles"));
  }
  if (vertices > limits.max_mesh_vertices) {
    ThrowResourceExhausted(Exhausted(field, "vertices", vertices, limits.max_mesh_vertices, "max_mesh_vertices"));
  }

  auto out = std::make_shared<TriangleMesh>();
  out->vertices.reserve(vertices);
  out->triangles.reserve(faces);
  for (const auto& [mesh, transform] : placed) {
    const int base = static_cast<int>(out->vertices.size());
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      const aiVector3D p = transform * mesh->mVertices[v];
      out->vertices.emplace_back(p.x * scale.x(), p.y * scale.y(), p.z * scale.z());
    }
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines left by triangulation
      for (int k = 0; k < 3; ++k) {
        if (face.mIndices[k] >= mesh->mNumVertices) {
          *why = "a face refers to vertex " + std::to_string(face.mIndices[k]) + " of a mesh with " +
                 std::to_string(mesh->mNumVertices) + " vertices";
          return nullptr;
        }
      }
      out->triangles.emplace_back(base + static_cast<int>(face.mIndices[0]), base + static_cast<int>(face.mIndices[1]),
                                  base + static_cast<int>(face.mIndices[2]));
    }
  }
  if (out->triangles.empty()) {
    *why = "it holds no triangles";
    return nullptr;
  }
  for (const Eigen::Vector3d& v : out->vertices) {
    if (!v.allFinite()) {
      *why = "it holds a vertex that is not finite";
      return nullptr;
    }
  }
  return out;
}

}  // namespace

std::shared_ptr<const TriangleMesh> ParseMesh(const std::string& bytes, const Eigen::Vector3d& scale,
                                              const std::string& field, const InputLimits& limits) {
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(scale[i]) || scale[i] <= 0.0) {
      std::ostringstream os;
      os << field << " scale[" << i << "] = " << FormatNumber(scale[i]) << " must be finite and > 0";
      ThrowInvalid(os.str());
    }
  }
  if (bytes.empty()) ThrowInvalid(field + " is empty (expected STL, OBJ or COLLADA file bytes)");
  if (bytes.size() > limits.max_document_bytes) {
    ThrowResourceExhausted(field + " holds " + std::to_string(bytes.size()) + " bytes, more than the cap of " +
                           std::to_string(limits.max_document_bytes) +
                           " bytes per document (InputLimits::max_document_bytes); send a smaller mesh or raise the server's cap");
  }
  // A binary STL says its triangle count in its header (bytes 80..83) and is exactly
  // 84 + 50 · count bytes long: refuse a big one before assimp reads it.
  if (bytes.size() >= 84) {
    std::uint32_t count = 0;
    std::memcpy(&count, bytes.data() + 80, sizeof(count));
    if (84 + 50 * static_cast<std::uint64_t>(count) == bytes.size() && count > limits.max_mesh_triangles) {
      ThrowResourceExhausted(Exhausted(field, "triangles", count, limits.max_mesh_triangles, "max_mesh_triangles"));
    }
  }
  std::string why;
  // A COLLADA document is XML whose root element is <COLLADA>: read as such and only as such.
  const std::size_t first = bytes.find_first_not_of(" \t\r\n\xEF\xBB\xBF");  // whitespace, UTF-8 BOM
  if (first != std::string::npos && bytes[first] == '<' && bytes.find("<COLLADA") < 4096) {
    if (auto mesh = TryRead(bytes, "dae", scale, field, limits, &why)) return mesh;
    ThrowInvalid(field + " is not a readable COLLADA mesh" + (why.empty() ? "" : ": " + why));
  }
  // Binary STL has no magic number, so try the formats we accept explicitly, STL first.
  for (const char* hint : {"stl", "obj"}) {
    if (auto mesh = TryRead(bytes, hint, scale, field, limits, &why)) return mesh;
    if (!why.empty() && why.rfind("it holds", 0) == 0) break;
    if (why.rfind("a face refers", 0) == 0) break;
  }
  ThrowInvalid(field + " is not a readable STL, OBJ or COLLADA mesh" + (why.empty() ? "" : ": " + why));
}

}  // namespace chasles
