#include "chasles/planners/planner.h"

#include <cmath>
#include <sstream>

#include "chasles/robot/error.h"

namespace chasles {

const ParameterSpec* PlannerSpec::Find(const std::string& name) const {
  for (const auto& p : parameters) {
    if (p.name == name) return &p;
  }
  return nullptr;
}

bool PlannerSpec::Supports(RobotKind kind) const {
  for (RobotKind k : robot_kinds) {
    if (k == kind) return true;
  }
  return false;
}

void CheckRobotKind(const PlannerSpec& spec, const RobotModel& robot, const std::vector<std::string>& alternatives) {
  if (spec.Supports(robot.kind())) return;
  std::string message = "planner '" + spec.id + "' does not plan for " + ToString(robot.kind()) + " robots (robot '" +
                        robot.name() + "'): " + spec.refusal_reason;
  if (!alternatives.empty()) {
    message += "; planners for " + std::string(ToString(robot.kind())) + ":";
    for (size_t i = 0; i < alternatives.size(); ++i) message += (i == 0 ? " " : ", ") + alternatives[i];
  }
  throw Error(ErrorCode::kFailedPrecondition, message);
}

ParameterValues ResolveParameters(const PlannerSpec& spec, const ParameterValues& values) {
  ParameterValues resolved;
  for (const auto& p : spec.parameters) resolved[p.name] = p.default_value;
  for (const auto& [name, value] : values) {
    const std::string field = "planner.parameters['" + name + "']";
    const ParameterSpec* p = spec.Find(name);
    // `name[i]` of a per-joint parameter.
    const auto bracket = name.find('[');
    if (p == nullptr && bracket != std::string::npos && bracket > 0 && name.back() == ']') {
      const ParameterSpec* base = spec.Find(name.substr(0, bracket));
      const std::string index = name.substr(bracket + 1, name.size() - bracket - 2);
      const bool digits = !index.empty() && index.size() <= 6 &&
                          index.find_first_not_of("0123456789") == std::string::npos;
      if (base != nullptr && base->per_joint && digits) p = base;
    }
    if (p == nullptr) {
      std::string known;
      for (const auto& q : spec.parameters) known += (known.empty() ? "" : ", ") + q.name;
      ThrowInvalid(field + " is not a parameter of planner '" + spec.id + "' (known: " +
                   (known.empty() ? "none" : known) + ")");
    }
    if (!std::isfinite(value)) ThrowInvalid(field + " = " + FormatNumber(value) + " must be finite");
    if (p->type != ParameterType::kDouble && value != std::floor(value)) {
      ThrowInvalid(field + " = " + FormatNumber(value) + " must be " +
                   (p->type == ParameterType::kBool ? "0 or 1 (bool)" : "an integer"));
    }
    if (value < p->min || value > p->max) {
      ThrowInvalid(field + " = " + FormatNumber(value) + " must be within [" + FormatNumber(p->min) +
                   ", " + FormatNumber(p->max) + "] (planner '" + spec.id + "')");
    }
    resolved[name] = value;
  }
  return resolved;
}

const char* ToString(PlanStatus status) {
  switch (status) {
    case PlanStatus::kExactSolution: return "exact solution";
    case PlanStatus::kApproximateSolution: return "approximate solution";
    case PlanStatus::kNoSolution: return "no solution";
    case PlanStatus::kInvalidStart: return "invalid start";
    case PlanStatus::kInvalidGoal: return "invalid goal";
    case PlanStatus::kCancelled: return "cancelled";
    case PlanStatus::kDeadlineExceeded: return "deadline exceeded";
    case PlanStatus::kLocalMinimum: return "local minimum";
    case PlanStatus::kLatticeExhausted: return "no path on the lattice";
  }
  return "unknown";
}

}  // namespace chasles
