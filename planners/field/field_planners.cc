// The field family: potential_field and wavefront (see potential_field.cc and wavefront.cc).
#include "chasles/planners/registry.h"
#include "field.h"

namespace chasles {

void RegisterFieldPlanners(PlannerRegistry* registry) {
  for (PlannerSpec spec : {field::PotentialFieldSpec(), field::WavefrontSpec()}) {
    const PlannerSpec copy = spec;
    const bool wavefront = spec.id == "wavefront";
    registry->Register(std::move(spec), [copy, wavefront] {
      return wavefront ? field::MakeWavefrontPlanner(copy) : field::MakePotentialFieldPlanner(copy);
    });
  }
}

}  // namespace chasles
