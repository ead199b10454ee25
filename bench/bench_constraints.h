#pragma once
/// \file
/// `chasles-bench --section constraints` (issue 18, path constraints): carrying a glass upright
/// between the shelf's compartments (examples/requests/panda_shelf_glass.json's scene and
/// constraint) on `cases` start/goal pairs drawn by IK, as Plan RPCs to an in-process server: in
/// OMPL's projected state space and with projected joint-space samples, at the example's 0.1 rad
/// and at 0.01 rad, and without the constraint (the in-run baseline). Every trajectory is
/// re-checked at 0.002 rad steps with the hand's orientation from the URDF joints chained.

#include <cstdint>
#include <string>

namespace chasles {

struct ConstraintsBenchOptions {
  std::string examples_dir;  ///< holds robots/panda.urdf, .srdf and requests/panda_shelf_glass.json
  int cases = 20;            ///< start/goal pairs
  double budget = 5.0;       ///< per plan [s]
  std::uint64_t seed = 1;
};

/// Prints a markdown table to stdout.
void BenchConstraints(const ConstraintsBenchOptions& options);

}  // namespace chasles
