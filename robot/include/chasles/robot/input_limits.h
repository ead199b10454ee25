#pragma once
/// \file
/// InputLimits: the size caps a server applies to untrusted documents (URDF/SRDF text, robot
/// descriptions, mesh and OctoMap bytes, point clouds) before it spends memory or time on them.
/// One value, built once (e.g. from server flags) and passed down to every parser; no globals.
/// An input beyond a cap is refused with Error(kResourceExhausted) naming the field, the size
/// found, the cap and the InputLimits field that sets it.

#include <cstddef>

namespace chasles {

struct InputLimits {
  /// [bytes] of one document: URDF or SRDF text, one mesh file, one OctoMap file.
  /// Default 64 MiB.
  std::size_t max_document_bytes = std::size_t{64} << 20;
  /// [elements] of XML element nesting in URDF and SRDF text (the root element is depth 1).
  /// Real URDFs nest fewer than 10 deep (robot > link > collision > geometry > mesh = 5).
  /// Default 64.
  int max_xml_depth = 64;
  /// [links] of one robot (URDF links, DH/PoE joints + 2). Default 10000.
  int max_links = 10000;
  /// [degrees of freedom] of one robot (its non-fixed joints). Default 512.
  int max_dofs = 512;
  /// [triangles] of one mesh file. Default 2,000,000 (a 100 MB binary STL).
  std::size_t max_mesh_triangles = 2'000'000;
  /// [vertices] of one mesh file, as the file holds them (an STL repeats each vertex per
  /// triangle). Default 6,000,000 (3 per triangle of max_mesh_triangles).
  std::size_t max_mesh_vertices = 6'000'000;
  /// [files] of mesh files in one robot (UrdfRobot.mesh_files) or one scene (Scene.meshes).
  /// Each costs a parse even when tiny (assimp's OBJ reader sets up a 16 MB buffer per file,
  /// about 7 ms). Default 1000.
  std::size_t max_mesh_files = 1000;
  /// [nodes] of one OctoMap OcTree file (inner nodes and leaves; a node costs about 30 bytes
  /// once read). Default 10,000,000.
  std::size_t max_octomap_nodes = 10'000'000;
  /// [points] of one point-cloud insertion (one ray each). Default 2,000,000.
  std::size_t max_cloud_points = 2'000'000;
  /// [objects] of one scene: primitives, meshes and OctoMaps together. A primitive costs about
  /// 0.5 KB once checked (scene record, checker record, broad-phase node); 1,000,000 of them
  /// arrive in a ~100 MB message. Default 1,000,000.
  std::size_t max_scene_objects = 1'000'000;

  /// \throws Error(kInvalidArgument) naming the first field that is not > 0, e.g.
  ///         `input_limits.max_xml_depth = 0 must be > 0`.
  void Validate() const;
};

}  // namespace chasles
