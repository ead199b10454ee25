#pragma once
/// \file
/// What an iterative trajectory optimiser (collocation in Ipopt, B-spline smoothing in NLopt)
/// reports about its solve.

#include <string>

namespace chasles {

struct OptimizerReport {
  /// The solver met its tolerances and the result, after any time scaling, meets every limit.
  /// False: `trajectory` must not be used (the caller falls back to an exact parameterisation).
  bool ok = false;
  std::string status;            ///< the solver's own status word, e.g. "Solve_Succeeded", "NLOPT_XTOL_REACHED"
  std::string message;           ///< what happened, in a sentence (why not ok)
  int iterations = 0;            ///< solver iterations (Ipopt) or objective evaluations (NLopt)
  double solve_seconds = 0.0;    ///< wall time of the solve [s]
  double constraint_violation = 0.0;  ///< final max constraint violation (solver's unscaled measure)
  double objective = 0.0;        ///< final objective value
  /// ≥ 1: the solved trajectory was slowed by this factor afterwards so that it meets the
  /// limits between knots exactly (1 = not needed).
  double time_scale = 1.0;
  /// Along a path: an upper bound [rad] on the distance from the result to the path, from exact
  /// polynomial ranges (<= the corridor when ok); -1 when not measured.
  double path_deviation = -1.0;
};

}  // namespace chasles
