#include "chasles/planners/registry.h"

#include "chasles/robot/error.h"

namespace chasles {

void PlannerRegistry::Register(PlannerSpec spec, Factory factory) {
  const std::string id = spec.id;
  if (entries_.count(id) != 0) ThrowInvalid("planner '" + id + "' is already registered");
  entries_.emplace(id, Entry{std::move(spec), std::move(factory)});
}

const PlannerSpec& PlannerRegistry::Spec(const std::string& id) const {
  const auto it = entries_.find(id);
  if (it == entries_.end()) {
    std::string known;
    for (const auto& [name, entry] : entries_) known += (known.empty() ? "" : ", ") + name;
    throw Error(ErrorCode::kNotFound,
                "planner.planner_id = '" + id + "' is unknown (known: " + known + ")");
  }
  return it->second.spec;
}

std::unique_ptr<Planner> PlannerRegistry::Create(const std::string& id) const {
  Spec(id);  // throws the named NotFound error
  return entries_.at(id).factory();
}

std::vector<PlannerSpec> PlannerRegistry::List() const {
  std::vector<PlannerSpec> out;
  for (const auto& [name, entry] : entries_) out.push_back(entry.spec);
  return out;
}

std::vector<std::string> PlannerRegistry::Ids() const {
  std::vector<std::string> out;
  for (const auto& [name, entry] : entries_) out.push_back(name);
  return out;
}

void RegisterDefaultPlanners(PlannerRegistry* registry) {
  RegisterOmplPlanners(registry);
  RegisterSearchPlanners(registry);
  RegisterFieldPlanners(registry);
}

}  // namespace chasles
