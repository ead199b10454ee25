// Placeholder while the NLopt formulation is written (replaced in the same branch of work).
#include "chasles/optimizers/spline_smoothing.h"

#include "chasles/robot/error.h"

namespace chasles {

SplineResult SmoothWithBSpline(const TimedTrajectory&, const KinematicLimits&, const SplineOptions&,
                               const CollisionChecker*) {
  throw Error(ErrorCode::kFailedPrecondition, "spline smoothing is not built yet");
}

}  // namespace chasles
