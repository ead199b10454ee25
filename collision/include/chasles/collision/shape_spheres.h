#pragma once
/// \file
/// One collision shape as spheres: a proven cover of the shape's solid with a proven bound on how
/// far the spheres reach outside it (FitRobotSpheres fits every shape of a robot with this).

#include "chasles/collision/sphere_fit.h"
#include "chasles/robot/geometry.h"

namespace chasles {

/// Covers `shape` (in its own frame: `shape.pose` is not applied) with at most
/// `options.max_spheres` spheres. Guarantee: every point of the shape's solid lies inside (or on)
/// a sphere, and `reach` bounds the distance from any point of any sphere to the solid. How:
///  - sphere: itself, reach 0;
///  - capsule: spheres on its axis, at both ends and evenly between (closed form); the reach is
///    exact: √(radius² + spacing²/4) − radius;
///  - cylinder: rings of spheres about its axis — a ring near each rim and spheres on the axis,
///    or for a flat cylinder rings in its mid-plane — whose radii come from a partition of the
///    cylinder into cells each inside a sphere; the reach is exact for the spheres returned
///    (radius + signed distance of the centre, the exact reach of a ball over a convex solid);
///  - box: FitSpheres on its 12 triangles, the reach then computed exactly as for the cylinder;
///  - mesh: FitSpheres.
/// Capsules and cylinders get the fewest spheres found that reach at most `options.max_reach`,
/// else the least reach found with max_spheres (a cylinder at most 128: its layouts gain little
/// beyond); `max_voxels_per_axis` applies to boxes and meshes. About 10–50 ms for a cylinder of 40
/// spheres, 150 ms for 128. Thread-safe (no state).
/// \throws Error(kInvalidArgument) for invalid options (SphereFitOptions::Validate), a size that
///         is not finite and > 0 (a capsule's length may be 0), or a mesh FitSpheres rejects.
FittedSpheres FitShapeSpheres(const Shape& shape, const SphereFitOptions& options = {});

}  // namespace chasles
