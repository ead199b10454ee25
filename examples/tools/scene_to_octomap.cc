// chasles-scene-to-octomap: voxelises the primitives of a chasles.v1.Scene (protobuf JSON) into
// an OctoMap OcTree and writes it as a .bt file, optionally also as a Scene JSON that holds just
// that OctoMap.
//
//   chasles-scene-to-octomap --scene shelf.json --out shelf.bt [--resolution 0.02]
//                            [--scene-json-out shelf_octomap.json] [--name shelf_octomap]
//
// A voxel is marked occupied when its centre lies inside a primitive or within half a voxel
// diagonal of it, so every voxel that touches the primitive is occupied (the map covers the
// primitives conservatively). Meshes and OctoMaps in the input are skipped with a note.

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

#include <Eigen/Geometry>
#include <google/protobuf/util/json_util.h>
#include <octomap/OcTree.h>

#include "chasles/v1/chasles.pb.h"

namespace {

Eigen::Isometry3d ToPose(const chasles::v1::Pose& p) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(p.position().x(), p.position().y(), p.position().z());
  const auto& q = p.orientation();
  if (q.x() != 0 || q.y() != 0 || q.z() != 0 || q.w() != 0) {
    t.linear() = Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z()).normalized().toRotationMatrix();
  }
  return t;
}

// Distance from a point given in the primitive's frame to the primitive (0 inside).
struct Prim {
  enum Kind { kBox, kSphere, kCylinder, kCapsule } kind = kBox;
  Eigen::Vector3d half = Eigen::Vector3d::Zero();  // box half extents
  double radius = 0, half_length = 0;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  double Distance(const Eigen::Vector3d& world) const {
    const Eigen::Vector3d l = pose.inverse() * world;
    switch (kind) {
      case kBox:
        return (l.cwiseAbs() - half).cwiseMax(0.0).norm();
      case kSphere:
        return std::max(l.norm() - radius, 0.0);
      case kCylinder: {
        const double dr = std::max(std::hypot(l.x(), l.y()) - radius, 0.0);
        const double dz = std::max(std::abs(l.z()) - half_length, 0.0);
        return std::hypot(dr, dz);
      }
      case kCapsule: {
        const double dz = std::max(std::abs(l.z()) - half_length, 0.0);
        return std::max(std::sqrt(l.x() * l.x() + l.y() * l.y() + dz * dz) - radius, 0.0);
      }
    }
    return 0;
  }
  double BoundingRadius() const {
    switch (kind) {
      case kBox: return half.norm();
      case kSphere: return radius;
      case kCylinder: return std::hypot(radius, half_length);
      case kCapsule: return radius + half_length;
    }
    return 0;
  }
};

int Usage() {
  std::cerr << "usage: chasles-scene-to-octomap --scene SCENE.json --out MAP.bt [--resolution 0.02]\n"
               "                                [--scene-json-out SCENE_OCTOMAP.json] [--name NAME]\n";
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  std::string scene_path, out_path, json_out, name = "octomap";
  double resolution = 0.02;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::cerr << arg << " needs a value\n";
        std::exit(Usage());
      }
      return argv[++i];
    };
    if (arg == "--scene") scene_path = value();
    else if (arg == "--out") out_path = value();
    else if (arg == "--scene-json-out") json_out = value();
    else if (arg == "--name") name = value();
    else if (arg == "--resolution") {
      const std::string v = value();
      char* end = nullptr;
      resolution = std::strtod(v.c_str(), &end);
      if (end == v.c_str() || *end != '\0' || !std::isfinite(resolution) || resolution <= 0) {
        std::cerr << "--resolution = " << v << " must be a finite number > 0 [m]\n";
        return 2;
      }
    } else if (arg == "-h" || arg == "--help") {
      Usage();
      return 0;
    } else {
      std::cerr << "unknown argument " << arg << "\n";
      return Usage();
    }
  }
  if (scene_path.empty() || out_path.empty()) return Usage();

  std::ifstream in(scene_path, std::ios::binary);
  if (!in) {
    std::cerr << "cannot open " << scene_path << "\n";
    return 1;
  }
  std::stringstream buffer;
  buffer << in.rdbuf();
  chasles::v1::Scene scene;
  const auto status = google::protobuf::util::JsonStringToMessage(buffer.str(), &scene);
  if (!status.ok()) {
    std::cerr << scene_path << " is not a chasles.v1.Scene in JSON: " << status.ToString() << "\n";
    return 1;
  }

  std::vector<Prim> prims;
  for (const auto& b : scene.boxes()) {
    Prim p;
    p.kind = Prim::kBox;
    p.half = 0.5 * Eigen::Vector3d(b.size().x(), b.size().y(), b.size().z());
    p.pose = ToPose(b.pose());
    prims.push_back(p);
  }
  for (const auto& s : scene.spheres()) {
    Prim p;
    p.kind = Prim::kSphere;
    p.radius = s.radius();
    p.pose = ToPose(s.pose());
    prims.push_back(p);
  }
  for (const auto& c : scene.cylinders()) {
    Prim p;
    p.kind = Prim::kCylinder;
    p.radius = c.radius();
    p.half_length = 0.5 * c.length();
    p.pose = ToPose(c.pose());
    prims.push_back(p);
  }
  for (const auto& c : scene.capsules()) {
    Prim p;
    p.kind = Prim::kCapsule;
    p.radius = c.radius();
    p.half_length = 0.5 * c.length();
    p.pose = ToPose(c.pose());
    prims.push_back(p);
  }
  if (scene.meshes_size() > 0 || scene.octomaps_size() > 0) {
    std::cerr << "note: skipping " << scene.meshes_size() << " mesh(es) and " << scene.octomaps_size()
              << " octomap(s); only primitives are voxelised\n";
  }

  octomap::OcTree tree(resolution);
  const double grow = 0.5 * std::sqrt(3.0) * resolution;  // half a voxel diagonal
  const float occupied = tree.getClampingThresMaxLog();
  std::size_t marked = 0;
  for (const Prim& p : prims) {
    const Eigen::Vector3d c = p.pose.translation();
    const double r = p.BoundingRadius() + grow;
    // World AABB of the primitive: |R| · half-extents of its local AABB.
    Eigen::Vector3d local_half;
    switch (p.kind) {
      case Prim::kBox: local_half = p.half; break;
      case Prim::kSphere: local_half.setConstant(p.radius); break;
      case Prim::kCylinder: local_half = Eigen::Vector3d(p.radius, p.radius, p.half_length); break;
      case Prim::kCapsule: local_half = Eigen::Vector3d(p.radius, p.radius, p.half_length + p.radius); break;
    }
    Eigen::Vector3d half = p.pose.linear().cwiseAbs() * local_half;
    half = half.cwiseMin(Eigen::Vector3d::Constant(r - grow)) + Eigen::Vector3d::Constant(grow);
    octomap::OcTreeKey lo, hi;
    if (!tree.coordToKeyChecked(c.x() - half.x(), c.y() - half.y(), c.z() - half.z(), lo) ||
        !tree.coordToKeyChecked(c.x() + half.x(), c.y() + half.y(), c.z() + half.z(), hi)) {
      std::cerr << "a primitive lies outside the OctoMap's range at this resolution\n";
      return 1;
    }
    octomap::OcTreeKey k;
    for (k[0] = lo[0]; k[0] <= hi[0]; ++k[0]) {
      for (k[1] = lo[1]; k[1] <= hi[1]; ++k[1]) {
        for (k[2] = lo[2]; k[2] <= hi[2]; ++k[2]) {
          const octomap::point3d v = tree.keyToCoord(k);
          if (p.Distance(Eigen::Vector3d(v.x(), v.y(), v.z())) <= grow) {
            tree.setNodeValue(k, occupied, /*lazy_eval=*/true);
            ++marked;
          }
        }
      }
    }
  }
  tree.updateInnerOccupancy();
  tree.prune();
  if (!tree.writeBinary(out_path)) {
    std::cerr << "cannot write " << out_path << "\n";
    return 1;
  }
  std::cerr << "voxelised " << prims.size() << " primitive(s) at " << resolution << " m: " << marked
            << " voxel marks, " << tree.getNumLeafNodes() << " leaves after pruning -> " << out_path << "\n";

  if (!json_out.empty()) {
    std::ifstream bt(out_path, std::ios::binary);
    std::stringstream bytes;
    bytes << bt.rdbuf();
    chasles::v1::Scene out_scene;
    auto* map = out_scene.add_octomaps();
    map->set_name(name);
    map->set_data(bytes.str());
    map->mutable_pose()->mutable_orientation()->set_w(1.0);
    std::string json;
    google::protobuf::util::JsonPrintOptions options;
    options.add_whitespace = true;
    const auto st = google::protobuf::util::MessageToJsonString(out_scene, &json, options);
    if (!st.ok()) {
      std::cerr << "cannot encode the scene JSON: " << st.ToString() << "\n";
      return 1;
    }
    std::ofstream js(json_out, std::ios::binary);
    js << json;
    if (!js) {
      std::cerr << "cannot write " << json_out << "\n";
      return 1;
    }
    std::cerr << "wrote " << json_out << "\n";
  }
  return 0;
}
