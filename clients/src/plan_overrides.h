#pragma once
/// \file
/// Command-line overrides of a chasles.v1.PlanRequest's planner, budget, seed, sample period,
/// padding and planning group, shared by `chasles plan` and `chasles import-moveit` (users need not edit the JSON).

#include <cstdint>
#include <optional>
#include <string>

#include "chasles/v1/chasles.pb.h"

namespace chasles::cli {

/// Each set field replaces the request's; unset fields leave it alone.
struct PlanOverrides {
  std::optional<std::string> planner_id;  ///< --planner ID -> planner.planner_id (non-empty)
  std::optional<double> time_budget;      ///< --budget S -> time_budget [s], in (0, 600]
  std::optional<std::uint64_t> seed;      ///< --seed N -> seed, a whole number >= 0 (0 = seed 1)
  std::optional<double> sample_period;    ///< --sample-period S -> trajectory.sample_period [s], in [1e-4, 1]
  std::optional<double> padding;          ///< --padding M -> padding [m], in [0, 0.5]
  std::optional<std::string> group;       ///< --group NAME -> group (an SRDF planning group)

  bool empty() const { return !planner_id && !time_budget && !seed && !sample_period && !padding && !group; }
};

/// The usage lines of the six flags.
extern const char kPlanOverridesUsage[];

/// True for --planner, --budget, --seed, --sample-period, --padding and --group.
bool IsPlanOverrideFlag(const std::string& flag);

/// Stores `value` of `flag` (one IsPlanOverrideFlag accepts) in `overrides`.
/// \throws std::invalid_argument naming the flag, the value and the rule, e.g.
///   `--budget '0' must be a number of seconds in (0, 600]`.
void SetPlanOverride(const std::string& flag, const std::string& value, PlanOverrides* overrides);

/// Writes the set overrides into `request`.
void ApplyPlanOverrides(const PlanOverrides& overrides, v1::PlanRequest* request);

}  // namespace chasles::cli
