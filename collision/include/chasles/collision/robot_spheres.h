#pragma once
/// \file
/// A robot whose links are meshes, as spheres: every non-sphere collision shape of the robot
/// replaced by spheres that cover it (FitSpheres), so the robot is checked on the sphere path and
/// its motions are certified. Done once per robot (the server: once per uploaded robot).

#include <memory>
#include <string>

#include "chasles/collision/shape_spheres.h"
#include "chasles/collision/sphere_fit.h"
#include "chasles/robot/robot_model.h"

namespace chasles {

struct RobotSphereOptions {
  /// Per shape: the target reach outside it and the grid (SphereFitOptions::max_spheres is
  /// replaced by the link's budget below, shared by its shapes).
  SphereFitOptions fit;
  /// Spheres per link, shared among the link's shapes that are fitted (each gets at least one), >= 1.
  int max_spheres_per_link = 40;
  /// Shapes fitted at once, on threads of the call's own; 0: one per hardware thread. >= 0.
  int threads = 0;
  /// \throws Error(kInvalidArgument) naming the field.
  void Validate() const;
};

struct RobotSphereFit {
  /// The robot with every collision shape a sphere: the same links, joints, limits, inertias and
  /// allowed pairs; null when the robot has no mesh (nothing to fit: FitRobotSpheres leaves robots
  /// of primitives to the checker as they are).
  std::shared_ptr<const RobotModel> model;
  int shapes_fitted = 0;  ///< meshes, boxes, cylinders and capsules replaced
  int spheres = 0;        ///< collision spheres of the fitted model in all
  /// [m] a proven bound on how far the spheres reach outside the shapes they replace (the largest
  /// over the fitted shapes), and the link where it is reached.
  double reach = 0.0;
  std::string reach_link;
  double seconds = 0.0;  ///< time the fit took
};

/// When the robot has at least one mesh: every mesh, box, cylinder and capsule of it is covered
/// by spheres (FitShapeSpheres, each shape with its share of its link's budget, the shapes fitted
/// in parallel and the same shape with the same budget fitted once), spheres are kept. Self-collision
/// pairs stay as allowed; a fitted link can reach into a neighbour by up to `reach` more than its
/// shapes did, so a pair that touched within that margin now collides. The result does not depend
/// on `threads`.
/// \throws Error(kInvalidArgument) for invalid options or a mesh FitSpheres rejects (naming the
///         link and shape).
RobotSphereFit FitRobotSpheres(const RobotModel& robot, const RobotSphereOptions& options = {});

}  // namespace chasles
