#pragma once
/// \file
/// `chasles-bench --section clutter`: the panda_table request in scenes that grow while the
/// planning problem does not (issue 24): N distant 5 cm boxes on a ring 1.6–3 m from the arm's
/// base, then clutter near the path as a curve.

#include <string>
#include <vector>

namespace chasles {

struct ClutterBenchOptions {
  std::string examples_dir;  ///< holds requests/panda_table.json and scenes/table.json
  std::vector<int> distant = {0, 100, 1000, 10000, 100000};  ///< extra boxes out of reach
  std::vector<int> near = {0, 10, 30, 100, 300};  ///< extra 2 cm boxes in the arm's workspace
  /// distant 5 cm cubes as meshes (FCL geometry: FCL's broad phase); at most the server's
  /// max_mesh_files per scene
  std::vector<int> distant_meshes = {1, 100, 1000};
  int repeats = 5;  ///< Plan calls per scene; medians
};

/// Prints two markdown tables (distant clutter against the empty scene; near clutter) to stdout.
/// \throws std::runtime_error when an example file is missing or an RPC fails.
void BenchClutter(const ClutterBenchOptions& options);

}  // namespace chasles
