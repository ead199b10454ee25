// Potential-field and wavefront planners (issue 4). Placeholder until the field family lands.
#include "chasles/planners/registry.h"

namespace chasles {

void RegisterFieldPlanners(PlannerRegistry* /*registry*/) {}

}  // namespace chasles
