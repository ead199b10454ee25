// Placeholder while the Ipopt formulation is written (replaced in the same branch of work).
#include "chasles/optimizers/collocation.h"

#include "chasles/robot/error.h"

namespace chasles {

CollocationResult OptimizeByCollocation(const TimedTrajectory&, const KinematicLimits&, const CollocationOptions&,
                                        const CollisionChecker*) {
  throw Error(ErrorCode::kFailedPrecondition, "collocation is not built yet");
}

}  // namespace chasles
