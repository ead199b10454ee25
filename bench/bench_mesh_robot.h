#pragma once
/// \file
/// `chasles-bench --section mesh_robot` (issue 25): a robot shipped with mesh collision geometry
/// (examples/robots/ur5_meshes) against the hand-made sphere model of the same arm
/// (ur5_spheres) on the same problems, over gRPC: the meshes covered by spheres at upload
/// (default) and kept exact (UrdfRobot.exact_meshes).

#include <cstdint>
#include <string>

namespace chasles {

struct MeshRobotBenchOptions {
  std::string examples_dir;  ///< holds robots/ur5_meshes.urdf, its STL files and robots/ur5_spheres.urdf
  int queries = 50;          ///< seeded start/goal pairs, free for every model
  double budget = 1.0;       ///< planning budget per request [s]
  std::uint64_t seed = 1;
};

/// Prints a markdown table to stdout. \throws std::runtime_error when a file is missing or an RPC fails.
void BenchMeshRobot(const MeshRobotBenchOptions& options);

}  // namespace chasles
