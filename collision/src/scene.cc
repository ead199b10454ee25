#include "chasles/collision/scene.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <sstream>

#include <octomap/AbstractOcTree.h>
#include <octomap/OcTree.h>

#include "chasles/robot/error.h"

namespace chasles {
namespace {

constexpr char kBinaryHeader[] = "# Octomap OcTree binary file";
constexpr char kFullHeader[] = "# Octomap OcTree file";
constexpr int kTreeDepth = 16;  // octomap::OcTree's fixed depth: leaves live at depth 16

void CheckPositive(double v, const std::string& what) {
  if (!std::isfinite(v) || v <= 0.0) ThrowInvalid(what + " = " + FormatNumber(v) + " must be finite and > 0");
}

void CheckPose(const Eigen::Isometry3d& pose, const std::string& field) {
  if (!pose.matrix().allFinite()) ThrowInvalid(field + " pose is not finite");
  const Eigen::Matrix3d r = pose.linear();
  if (!(r.transpose() * r).isApprox(Eigen::Matrix3d::Identity(), 1e-6) || r.determinant() < 0.0) {
    ThrowInvalid(field + " pose rotation is not a proper rotation (orthonormal, det = +1)");
  }
}

// --- OctoMap byte validation -------------------------------------------------------------
// octomap's readers do not bound recursion depth or check stream failures in every place,
// so random or truncated bytes could make them recurse without end. We walk the node stream
// ourselves first (depth <= 16, every byte present) and only then hand the bytes to octomap.

struct Header {
  std::string id;
  long long size = -1;
  double res = 0.0;
  std::size_t data_offset = 0;  // first byte after the "data" line
};

// Reads the header lines after the magic line; false with `why` set when malformed.
bool ParseHeader(const std::string& bytes, std::size_t pos, Header* h, std::string* why) {
  constexpr std::size_t kMaxLine = 4096;
  for (int lines = 0; lines < 1000; ++lines) {
    const std::size_t eol = bytes.find('\n', pos);
    if (eol == std::string::npos || eol - pos > kMaxLine) {
      *why = "its header ends before the 'data' line";
      return false;
    }
    std::string line = bytes.substr(pos, eol - pos);
    pos = eol + 1;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ls(line);
    std::string token;
    ls >> token;
    // octomap reads the header token by token, across lines; a line with more than its key and
    // value would be read differently there, so it is refused here.
    const auto no_more = [&ls, &line, why]() {
      std::string extra;
      if (ls >> extra) {
        *why = "its header line '" + line.substr(0, 40) + "' holds more than a key and its value";
        return false;
      }
      return true;
    };
    if (token == "data") {
      if (!no_more()) return false;
      h->data_offset = pos;
      if (h->id.empty()) { *why = "its header has no 'id' line"; return false; }
      if (h->size < 0) { *why = "its header has no valid 'size' line"; return false; }
      if (!(h->res > 0.0) || !std::isfinite(h->res)) {
        *why = "its header has no valid 'res' line (resolution must be finite and > 0)";
        return false;
      }
      return true;
    } else if (token == "id" || token == "size" || token == "res") {
      // A value octomap's stream cannot read stops its header (it refuses the file): refused here.
      const bool read = token == "id" ? static_cast<bool>(ls >> h->id)
                        : token == "size" ? static_cast<bool>(ls >> h->size) && h->size >= 0
                                          : static_cast<bool>(ls >> h->res);
      if (!read) {
        *why = "its header line '" + line.substr(0, 40) + "' has no valid value";
        return false;
      }
      if (!no_more()) return false;
    } else {
      *why = "its header holds an unknown line '" + line.substr(0, 40) + "'";
      return false;
    }
  }
  *why = "its header is too long";
  return false;
}

// Binary (.bt) node: two bytes, two bits per child: 01 occupied leaf, 10 free leaf,
// 11 inner node (its own record follows, depth first), 00 none.
// `nodes` counts every node below the root (the root is counted by the caller); `leaves` the
// occupied and free leaves.
bool WalkBinary(const std::string& bytes, std::size_t* pos, int depth, std::uint64_t* nodes,
                std::uint64_t* leaves) {
  if (*pos + 2 > bytes.size()) return false;
  const unsigned char b[2] = {static_cast<unsigned char>(bytes[*pos]),
                              static_cast<unsigned char>(bytes[*pos + 1])};
  *pos += 2;
  int inner = 0;
  for (int k = 0; k < 2; ++k) {
    for (int i = 0; i < 4; ++i) {
      const int code = (b[k] >> (2 * i)) & 3;
      if (code != 0) ++*nodes;
      if (code == 3) ++inner;
      else if (code != 0) ++*leaves;
    }
  }
  if (inner > 0 && depth + 1 >= kTreeDepth) return false;  // children below the leaf level
  for (int i = 0; i < inner; ++i) {
    if (!WalkBinary(bytes, pos, depth + 1, nodes, leaves)) return false;
  }
  return true;
}

// Full (.ot) OcTree node: float log-odds, one byte of child flags, then the children.
bool WalkFull(const std::string& bytes, std::size_t* pos, int depth, std::uint64_t* nodes) {
  if (*pos + 5 > bytes.size()) return false;
  float value;
  std::memcpy(&value, bytes.data() + *pos, sizeof(float));
  if (!std::isfinite(value)) return false;
  const unsigned char children = static_cast<unsigned char>(bytes[*pos + 4]);
  *pos += 5;
  ++*nodes;
  if (children != 0 && depth >= kTreeDepth) return false;
  for (int i = 0; i < 8; ++i) {
    if ((children >> i) & 1) {
      if (!WalkFull(bytes, pos, depth + 1, nodes)) return false;
    }
  }
  return true;
}

}  // namespace

void Scene::AddObject(SceneObject object, const std::string& field) {
  const Shape& s = object.shape;
  switch (s.type) {
    case ShapeType::kSphere:
      CheckPositive(s.radius, field + ".radius");
      break;
    case ShapeType::kBox:
      for (int i = 0; i < 3; ++i) CheckPositive(s.size[i], field + ".size[" + std::to_string(i) + "]");
      break;
    case ShapeType::kCylinder:
    case ShapeType::kCapsule:
      CheckPositive(s.radius, field + ".radius");
      CheckPositive(s.length, field + ".length");
      break;
    case ShapeType::kMesh:
      if (!s.mesh || s.mesh->triangles.empty()) ThrowInvalid(field + " mesh holds no triangles");
      for (const Eigen::Vector3i& t : s.mesh->triangles) {
        for (int k = 0; k < 3; ++k) {
          if (t[k] < 0 || t[k] >= static_cast<int>(s.mesh->vertices.size())) {
            ThrowInvalid(field + " mesh triangle index " + std::to_string(t[k]) + " is out of range");
          }
        }
      }
      break;
  }
  CheckPose(s.pose, field);
  objects_.push_back(std::move(object));
}

std::string OctoMapFileFromMessage(bool binary, const std::string& id, double resolution, const std::string& data,
                                   const std::string& field) {
  if (id != "OcTree") ThrowInvalid(field + ".id = '" + id + "': only 'OcTree' maps are supported");
  if (!(resolution >= 1e-4 && resolution <= 1e3)) {
    ThrowInvalid(field + ".resolution = " + FormatNumber(resolution) + " must be within [1e-4, 1e3] m");
  }
  if (data.empty()) ThrowInvalid(field + ".data is empty");
  std::size_t pos = 0;
  std::uint64_t nodes = 1, leaves = 0;
  const bool ok = binary ? WalkBinary(data, &pos, 0, &nodes, &leaves) : WalkFull(data, &pos, 0, &nodes);
  if (!binary) nodes -= 1;  // WalkFull counts the root itself
  if (!ok) {
    ThrowInvalid(field + ".data is truncated or corrupt: its " + std::string(binary ? "binary" : "full") +
                 " node data ends early, goes deeper than 16 levels or holds a non-finite value");
  }
  if (pos != data.size()) {
    ThrowInvalid(field + ".data holds " + std::to_string(data.size() - pos) + " bytes after its tree");
  }
  char header[160];
  std::snprintf(header, sizeof(header), "%s\nid OcTree\nsize %llu\nres %.17g\ndata\n",
                binary ? kBinaryHeader : kFullHeader, static_cast<unsigned long long>(nodes), resolution);
  return header + data;
}

void Scene::AddOctoMap(const std::string& name, const std::string& bytes, const Eigen::Isometry3d& pose,
                       const std::string& field, const InputLimits& limits) {
  CheckPose(pose, field);
  const auto fail = [&](const std::string& why) { ThrowInvalid(field + " " + why); };
  if (bytes.empty()) fail("is empty (expected the bytes of a .bt or .ot OctoMap file)");
  if (bytes.size() > limits.max_document_bytes) {
    ThrowResourceExhausted(field + " holds " + std::to_string(bytes.size()) + " bytes, more than the cap of " +
                           std::to_string(limits.max_document_bytes) +
                           " bytes per document (InputLimits::max_document_bytes); send a smaller map or raise the server's cap");
  }
  const std::size_t eol = bytes.find('\n');
  std::string first = bytes.substr(0, eol == std::string::npos ? std::min<std::size_t>(bytes.size(), 64) : eol);
  if (!first.empty() && first.back() == '\r') first.pop_back();
  const bool binary = first.rfind(kBinaryHeader, 0) == 0;
  const bool full = !binary && first.rfind(kFullHeader, 0) == 0;
  if ((!binary && !full) || eol == std::string::npos) {
    fail("is not an OctoMap file (expected a '# Octomap OcTree' header)");
  }
  Header h;
  std::string why;
  if (!ParseHeader(bytes, eol + 1, &h, &why)) fail("is not a valid OctoMap file: " + why);
  if (h.id != "OcTree") {
    fail("holds an OctoMap of type '" + h.id + "'; only 'OcTree' is supported");
  }
  if (h.size == 0) fail("holds an empty OctoMap (size 0)");
  if (h.res < 1e-4 || h.res > 1e3) fail("has resolution " + FormatNumber(h.res) + " m outside [1e-4, 1e3]");

  std::size_t pos = h.data_offset;
  std::uint64_t nodes = 1, leaves = 0;  // the root
  const bool ok = binary ? WalkBinary(bytes, &pos, 0, &nodes, &leaves) : WalkFull(bytes, &pos, 0, &nodes);
  if (!binary) {
    nodes -= 1;  // WalkFull counts the root itself
    leaves = nodes > 1 ? nodes - 1 : 0;  // only "has any node below the root" matters
  }
  if (!ok) {
    fail(std::string("is truncated or corrupt: its ") + (binary ? "binary" : "full") +
         " node data ends early, goes deeper than 16 levels or holds a non-finite value");
  }
  if (leaves == 0) fail("holds an empty OctoMap (no leaves)");
  // Every node costs memory once octomap reads it: the count, not the byte size, is the bound.
  if (nodes > limits.max_octomap_nodes) {
    ThrowResourceExhausted(field + " holds " + std::to_string(nodes) + " OcTree nodes, more than the cap of " +
                           std::to_string(limits.max_octomap_nodes) +
                           " (InputLimits::max_octomap_nodes); send a coarser or smaller map or raise the server's cap");
  }
  if (nodes != static_cast<std::uint64_t>(h.size)) {
    fail("is corrupt: its header says " + std::to_string(h.size) + " nodes but its data holds " +
         std::to_string(nodes));
  }

  std::shared_ptr<octomap::OcTree> tree;
  std::istringstream in(bytes);
  if (binary) {
    tree = std::make_shared<octomap::OcTree>(h.res);
    if (!tree->readBinary(in)) fail("could not be read as a binary OctoMap OcTree");
  } else {
    std::unique_ptr<octomap::AbstractOcTree> abstract(octomap::AbstractOcTree::read(in));
    auto* as_tree = dynamic_cast<octomap::OcTree*>(abstract.get());
    if (as_tree == nullptr) fail("could not be read as an OctoMap OcTree");
    abstract.release();
    tree.reset(as_tree);
  }
  if (tree->size() == 0) fail("holds an empty OctoMap");
  OccupancyMap map;
  map.name = name;
  map.tree = std::move(tree);
  map.pose = pose;
  maps_.push_back(std::move(map));
}

void Scene::AddOccupancyMap(OccupancyMap map) {
  if (!map.tree) ThrowInvalid("occupancy map '" + map.name + "' has no tree");
  CheckPose(map.pose, "occupancy map '" + map.name + "'");
  maps_.push_back(std::move(map));
}

void Scene::AllowCollision(const std::string& link, const std::string& other, const std::string& field_name) {
  const std::string field =
      field_name.empty() ? "scene.allowed_collisions[" + std::to_string(allowed_.size()) + "]" : field_name;
  if (link.empty()) ThrowInvalid(field + ".link1 is empty: it must name a robot link");
  if (other.empty()) {
    ThrowInvalid(field + ".link2 is empty: it must name a robot link or an object or OctoMap of the scene");
  }
  allowed_.push_back({link, other});
}

}  // namespace chasles
