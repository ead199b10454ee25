#pragma once
/// \file
/// PlannerRegistry: planners by id. Built in main and passed down; no singletons.

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "chasles/planners/planner.h"

namespace chasles {

class PlannerRegistry {
 public:
  using Factory = std::function<std::unique_ptr<Planner>()>;

  /// \throws Error(kInvalidArgument) when the id is already registered.
  void Register(PlannerSpec spec, Factory factory);
  /// \throws Error(kNotFound): `planner 'foo' is unknown (known: prm, rrt, …)`.
  std::unique_ptr<Planner> Create(const std::string& id) const;
  /// \throws Error(kNotFound) like Create.
  const PlannerSpec& Spec(const std::string& id) const;
  std::vector<PlannerSpec> List() const;  ///< sorted by id
  std::vector<std::string> Ids() const;

 private:
  struct Entry {
    PlannerSpec spec;
    Factory factory;
  };
  std::map<std::string, Entry> entries_;
};

/// planners/ompl: prm, prm_star, lazy_prm_star, rrt, rrt_star, informed_rrt_star, rrt_connect,
/// bit_star (sampling planners through OMPL; cars through OMPL's Dubins / Reeds–Shepp spaces).
void RegisterOmplPlanners(PlannerRegistry* registry);
/// planners/search: astar (weighted A* over a C-space lattice with lazy edge validation).
void RegisterSearchPlanners(PlannerRegistry* registry);
/// planners/field: potential_field (attractive + repulsive potential, gradient descent with
/// random-walk escapes) and wavefront (navigation function on a grid of at most 3 coordinates).
void RegisterFieldPlanners(PlannerRegistry* registry);
/// Every family above.
void RegisterDefaultPlanners(PlannerRegistry* registry);

}  // namespace chasles
