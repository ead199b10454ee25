#include "plan_overrides.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

namespace chasles::cli {

const char kPlanOverridesUsage[] =
    "  --planner ID           planner id (chasles planners lists them); sets planner.planner_id\n"
    "  --budget S             planning time budget [s], in (0, 600]; sets time_budget\n"
    "  --seed N               seed of every random choice, a whole number >= 0 (0 = 1); sets seed\n"
    "  --sample-period S      period of the returned samples [s], in [0.0001, 1]; sets\n"
    "                         trajectory.sample_period\n"
    "  --padding M            safety margin around every robot shape [m], in [0, 0.5]; sets\n"
    "                         padding (0 = none)\n"
    "  --group NAME           plan only this SRDF planning group's joints (upload-robot lists\n"
    "                         the groups), the others held at the start; sets group\n";

namespace {

[[noreturn]] void Invalid(const std::string& flag, const std::string& value, const std::string& rule) {
  throw std::invalid_argument(flag + " '" + value + "' must be " + rule);
}

/// A finite number in [low, high] (or (low, high] when `open_low`), else Invalid with `rule`.
double Number(const std::string& flag, const std::string& text, double low, bool open_low, double high,
              const std::string& rule) {
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(text.c_str(), &end);
  const bool parsed = !text.empty() && end != text.c_str() && *end == '\0' && errno == 0 && std::isfinite(value);
  if (!parsed || (open_low ? !(value > low) : !(value >= low)) || !(value <= high)) Invalid(flag, text, rule);
  return value;
}

}  // namespace

bool IsPlanOverrideFlag(const std::string& flag) {
  return flag == "--planner" || flag == "--budget" || flag == "--seed" || flag == "--sample-period" ||
         flag == "--padding" || flag == "--group";
}

void SetPlanOverride(const std::string& flag, const std::string& value, PlanOverrides* overrides) {
  if (flag == "--planner") {
    if (value.empty() || value.find_first_of(" \t\r\n") != std::string::npos) {
      Invalid(flag, value, "a planner id without spaces (chasles planners lists them)");
    }
    overrides->planner_id = value;
  } else if (flag == "--budget") {
    overrides->time_budget = Number(flag, value, 0.0, true, 600.0, "a number of seconds in (0, 600]");
  } else if (flag == "--seed") {
    // strtoull accepts a sign and wraps negative numbers: digits only.
    const bool digits = !value.empty() && value.find_first_not_of("0123456789") == std::string::npos;
    errno = 0;
    const unsigned long long seed = digits ? std::strtoull(value.c_str(), nullptr, 10) : 0;
    if (!digits || errno == ERANGE) Invalid(flag, value, "a whole number in [0, 18446744073709551615] (0 = 1)");
    overrides->seed = seed;
  } else if (flag == "--sample-period") {
    overrides->sample_period = Number(flag, value, 1e-4, false, 1.0, "a number of seconds in [0.0001, 1]");
  } else if (flag == "--padding") {
    overrides->padding = Number(flag, value, 0.0, false, 0.5, "a number of metres in [0, 0.5]");
  } else if (flag == "--group") {
    if (value.empty()) Invalid(flag, value, "the name of one of the robot's SRDF planning groups");
    overrides->group = value;
  } else {
    throw std::logic_error("SetPlanOverride: '" + flag + "' is not an override flag");
  }
}

void ApplyPlanOverrides(const PlanOverrides& overrides, v1::PlanRequest* request) {
  if (overrides.planner_id) request->mutable_planner()->set_planner_id(*overrides.planner_id);
  if (overrides.time_budget) request->set_time_budget(*overrides.time_budget);
  if (overrides.seed) request->set_seed(*overrides.seed);
  if (overrides.sample_period) request->mutable_trajectory()->set_sample_period(*overrides.sample_period);
  if (overrides.padding) request->set_padding(*overrides.padding);
  if (overrides.group) request->set_group(*overrides.group);
}

}  // namespace chasles::cli
