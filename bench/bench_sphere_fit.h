#pragma once
/// \file
/// `chasles-bench --section sphere_fit` (issue 25): how long covering a robot's shapes by spheres
/// takes at upload (FitRobotSpheres, once per robot) and how far the spheres reach: the Baxter's
/// published collision geometry (20 cylinders; its 2 collision meshes, which are not shipped, as
/// boxes), the example UR5 as meshes and a Fetch-like robot of boxes; then each distinct shape
/// alone.

#include <string>
#include <vector>

namespace chasles {

struct SphereFitBenchOptions {
  std::string examples_dir;        ///< holds robots/ur5_meshes.urdf and its STL files
  std::vector<std::string> urdfs;  ///< more robots to fit, their collision meshes as 0.1 m boxes
  int repeats = 5;                 ///< runs per robot and per shape (medians), >= 1
};

/// Prints markdown tables to stdout. \throws std::runtime_error when a file is missing.
void BenchSphereFit(const SphereFitBenchOptions& options);

}  // namespace chasles
