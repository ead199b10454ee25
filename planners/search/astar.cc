// Weighted A* over a C-space lattice (issue 4). Placeholder until the search family lands.
#include "chasles/planners/registry.h"

namespace chasles {

void RegisterSearchPlanners(PlannerRegistry* /*registry*/) {}

}  // namespace chasles
