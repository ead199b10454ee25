// Hostile meshes, OctoMaps and point clouds: InputLimits caps (kResourceExhausted, checked before
// the expensive work), error messages that name the caller's field (never assimp's internal
// file name), and OctoMap headers that octomap would read differently from the validation.

#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "chasles/collision/mesh.h"
#include "chasles/collision/scene.h"
#include "chasles/robot/error.h"
#include "chasles/robot/input_limits.h"

namespace chasles {
namespace {

const char kMeshField[] = "scene.meshes[0].data";
const char kMapField[] = "scene.octomaps[0].data";

std::string ReadExample(const std::string& relative) {
  std::ifstream in(std::string(CHASLES_SOURCE_DIR) + "/examples/" + relative, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

void ExpectError(ErrorCode code, const std::function<void()>& fn, const std::string& message) {
  try {
    fn();
    ADD_FAILURE() << "no Error thrown; expected: " << message;
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), code) << e.what();
    EXPECT_EQ(std::string(e.what()), message);
  }
}

const char kCubeObj[] =
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
    "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n";

TEST(InputLimitsCollision, MeshErrorsNameTheFieldNotAssimpsFileName) {
  // assimp's message quotes the name it gives memory input ("$$$___magic___$$$.stl").
  ExpectError(ErrorCode::kInvalidArgument, [] { ParseMesh("v 1 2\nf 1 2 3\n", Eigen::Vector3d::Ones(), kMeshField); },
              "scene.meshes[0].data is not a readable STL, OBJ or COLLADA mesh: Failed to determine STL storage "
              "representation for scene.meshes[0].data.");
}

TEST(InputLimitsCollision, MeshTrianglesVerticesAndBytesAreCapped) {
  InputLimits limits;
  EXPECT_EQ(ParseMesh(kCubeObj, Eigen::Vector3d::Ones(), kMeshField, limits)->triangles.size(), 12u);
  limits.max_mesh_triangles = 11;
  ExpectError(ErrorCode::kResourceExhausted, [&] { ParseMesh(kCubeObj, Eigen::Vector3d::Ones(), kMeshField, limits); },
              "scene.meshes[0].data holds 12 triangles, more than the cap of 11 per mesh "
              "(InputLimits::max_mesh_triangles); simplify the mesh or raise the server's cap");
  limits = InputLimits{};
  limits.max_mesh_vertices = 5;
  try {
    ParseMesh(kCubeObj, Eigen::Vector3d::Ones(), kMeshField, limits);
    ADD_FAILURE() << "no Error thrown";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kResourceExhausted);
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("scene.meshes[0].data holds ", 0), 0u) << what;
    EXPECT_NE(what.find(" vertices, more than the cap of 5 per mesh (InputLimits::max_mesh_vertices); "), std::string::npos)
        << what;
  }
  limits = InputLimits{};
  limits.max_document_bytes = 64;
  const std::string cube = kCubeObj;
  ExpectError(ErrorCode::kResourceExhausted, [&] { ParseMesh(cube, Eigen::Vector3d::Ones(), kMeshField, limits); },
              "scene.meshes[0].data holds " + std::to_string(cube.size()) +
                  " bytes, more than the cap of 64 bytes per document (InputLimits::max_document_bytes); send a "
                  "smaller mesh or raise the server's cap");
}

TEST(InputLimitsCollision, BinaryStlTriangleCountIsCappedFromItsHeader) {
  // 80-byte header, count 5, 5 records of 50 bytes (all zero: degenerate, but the count alone decides).
  std::string stl(84 + 5 * 50, '\0');
  const std::uint32_t count = 5;
  std::memcpy(&stl[80], &count, sizeof(count));
  InputLimits limits;
  limits.max_mesh_triangles = 4;
  ExpectError(ErrorCode::kResourceExhausted, [&] { ParseMesh(stl, Eigen::Vector3d::Ones(), kMeshField, limits); },
              "scene.meshes[0].data holds 5 triangles, more than the cap of 4 per mesh "
              "(InputLimits::max_mesh_triangles); simplify the mesh or raise the server's cap");
}

TEST(InputLimitsCollision, OctoMapBytesAndNodesAreCapped) {
  const std::string shelf = ReadExample("scenes/shelf.bt");
  const std::size_t size_at = shelf.find("\nsize ") + 6;
  const std::string nodes = shelf.substr(size_at, shelf.find('\n', size_at) - size_at);
  InputLimits limits;
  Scene scene;
  scene.AddOctoMap("shelf", shelf, Eigen::Isometry3d::Identity(), kMapField, limits);
  limits.max_octomap_nodes = std::stoull(nodes) - 1;
  ExpectError(ErrorCode::kResourceExhausted,
              [&] { Scene().AddOctoMap("shelf", shelf, Eigen::Isometry3d::Identity(), kMapField, limits); },
              "scene.octomaps[0].data holds " + nodes + " OcTree nodes, more than the cap of " +
                  std::to_string(limits.max_octomap_nodes) +
                  " (InputLimits::max_octomap_nodes); send a coarser or smaller map or raise the server's cap");
  limits = InputLimits{};
  limits.max_document_bytes = 1000;
  ExpectError(ErrorCode::kResourceExhausted,
              [&] { Scene().AddOctoMap("shelf", shelf, Eigen::Isometry3d::Identity(), kMapField, limits); },
              "scene.octomaps[0].data holds " + std::to_string(shelf.size()) +
                  " bytes, more than the cap of 1000 bytes per document (InputLimits::max_document_bytes); send a "
                  "smaller map or raise the server's cap");
}

// octomap reads its header token by token across lines: "size N data" ends its header on that
// line, while a line-based reading would go on to the next "data" line, and the node stream
// octomap then reads would not be the one that was validated.
TEST(InputLimitsCollision, OctoMapHeaderLinesHoldOneKeyAndValue) {
  std::string shelf = ReadExample("scenes/shelf.bt");
  const std::size_t size_at = shelf.find("\nsize ") + 1;
  const std::size_t eol = shelf.find('\n', size_at);
  const std::string line = shelf.substr(size_at, eol - size_at) + " data";
  shelf.replace(size_at, eol - size_at, line);
  ExpectError(ErrorCode::kInvalidArgument,
              [&] { Scene().AddOctoMap("shelf", shelf, Eigen::Isometry3d::Identity(), kMapField); },
              "scene.octomaps[0].data is not a valid OctoMap file: its header line '" + line +
                  "' holds more than a key and its value");
  // A value octomap's stream cannot read ends its header: refused here too (found by fuzz_octomap;
  // octomap then refused the file itself).
  std::string junk = ReadExample("scenes/shelf.bt");
  const std::size_t res_at = junk.find("\nres ") + 1;
  junk.replace(res_at, junk.find('\n', res_at) - res_at, "res #0.1");
  ExpectError(ErrorCode::kInvalidArgument,
              [&] { Scene().AddOctoMap("shelf", junk, Eigen::Isometry3d::Identity(), kMapField); },
              "scene.octomaps[0].data is not a valid OctoMap file: its header line 'res #0.1' has no valid value");
}

TEST(InputLimitsCollision, PointCloudPointsAreCappedFirst) {
  PointCloudInsertion insertion;
  insertion.points = {0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9};
  InputLimits limits;
  limits.max_cloud_points = 2;
  ExpectError(ErrorCode::kResourceExhausted, [&] { Scene().InsertPointCloud(insertion, nullptr, limits); },
              "points holds 3 points (9 values), more than the cap of 2 points per insertion "
              "(InputLimits::max_cloud_points); send the cloud in parts or downsample it, or raise the server's cap");
  limits.max_cloud_points = 3;
  PointCloudInsertionStats stats;
  Scene().InsertPointCloud(insertion, &stats, limits);
  EXPECT_EQ(stats.points_inserted, 3u);
}

// A point far beyond max_range passed (its cut end lies in the map) but reached octomap as a
// float -inf, whose ray direction is NaN (UBSan: NaN converted to int in coordToKeyChecked;
// found by fuzz_request).
TEST(InputLimitsCollision, PointCloudRaysHaveABoundedLength) {
  PointCloudInsertion insertion;
  insertion.points = {-8.98846567431158e+307, 0.0, 0.0, 0.5, 0.0, 0.3};
  insertion.max_range = 2.0;
  ExpectError(ErrorCode::kInvalidArgument, [&] { Scene().InsertPointCloud(insertion); },
              "points[0..2] (point 0) = (-8.98846567431158e+307, 0, 0) lies 8.98846567431158e+307 m from "
              "sensor_origin; rays must be at most 1000000000 m long");
  // A diagonal ray across the whole key range of a 5 cm map: about 3 · 40000 cells, more than
  // octomap's ray buffer of 100000 keys (an assertion in octomap, a heap overflow without it;
  // found by fuzz_request).
  insertion.points = {1500.0, 1500.0, 1500.0};
  insertion.sensor_origin = Eigen::Vector3d(-500.0, -500.0, -500.0);
  insertion.max_range = 0.0;
  ExpectError(ErrorCode::kInvalidArgument, [&] { Scene().InsertPointCloud(insertion); },
              "points[0..2] (point 0) = (1500, 1500, 1500) is a ray across about 120003 cells of map 'points' "
              "(resolution 0.05 m); a ray may cross at most 99000 cells (octomap's ray buffer): use a shorter "
              "max_range or a coarser map");
  insertion.sensor_origin = Eigen::Vector3d::Zero();
  insertion.max_range = 2.0;
  insertion.points = {-1e6, 0.0, 0.0, 0.5, 0.0, 0.3};  // far, but a real ray: cut at max_range
  PointCloudInsertionStats stats;
  Scene().InsertPointCloud(insertion, &stats);
  EXPECT_EQ(stats.points_inserted, 2u);
}

}  // namespace
}  // namespace chasles
