#pragma once
// Sphere covers of convex primitives computed from their geometry instead of a voxel grid
// (FitShapeSpheres uses them; see primitive_cover.cc for the proofs).

#include <Eigen/Core>

#include "chasles/collision/sphere_fit.h"

namespace chasles {

/// Covers the solid cylinder of `radius` and `length` (> 0, axis z, centred on the origin) with
/// at most `max_spheres` balls (and at most 128): the fewest found whose reach is within
/// `max_reach`, else the smallest reach found with max_spheres. Proven cover; the reach is exact
/// for the balls returned. About 10–50 ms for 40 balls, 150 ms for 128.
FittedSpheres CoverCylinder(double radius, double length, double max_reach, int max_spheres);

/// Covers the capsule of `radius` whose cylindrical part has `length` (>= 0, axis z, centred)
/// with balls on its axis: the fewest whose reach is within `max_reach`, else max_spheres.
/// Closed form, proven cover, exact reach.
FittedSpheres CoverCapsule(double radius, double length, double max_reach, int max_spheres);

/// The exact reach of `spheres` outside the box of `size` (centred on the origin, axis-aligned):
/// the largest over the spheres of max(0, radius + signed distance of the centre to the box), plus
/// a rounding margin.
double BoxReach(const Eigen::Vector3d& size, const FittedSpheres& spheres);

}  // namespace chasles
