#pragma once
/// \file
/// `chasles-bench --section cartesian` (issue 18): Cartesian moves of the Panda's TCP in the table
/// scene — random straight lines (length and turn drawn per case) from random free starts —
/// through ComputeCartesianPath, then timed as the CartesianPath RPC times them. In-run baseline:
/// the same lines solved state by state with unseeded IK (random restarts, as a Cartesian move
/// without a seed would be), its time and the joint jumps it makes.

#include <cstdint>
#include <string>

namespace chasles {

struct CartesianBenchOptions {
  std::string examples_dir;  ///< holds robots/panda.urdf, .srdf and scenes/table.json
  int cases = 100;           ///< random lines
  int repeats = 3;           ///< timed runs per line (the median is kept)
  std::uint64_t seed = 1;
};

/// Prints markdown tables to stdout.
void BenchCartesian(const CartesianBenchOptions& options);

/// `chasles-bench --section carry` (issue 18): examples/requests/panda_carry_rod.json (a 40 cm rod
/// in the gripper, carried across a block) with `cases` random start/goal pairs on either side of
/// the block, as Plan RPCs to an in-process server, carrying the rod and bare; every trajectory
/// re-checked at 0.002 rad steps on a checker of the rod's exact box (FCL).
void BenchCarry(const CartesianBenchOptions& options);

}  // namespace chasles
