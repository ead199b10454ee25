#pragma once
/// \file
/// The pieces of a replanning stream (the Replan RPC) that are not gRPC: moving obstacles moved to
/// a later time origin, a straight stop at the acceleration limits, a trajectory's rest and
/// concatenation, and the first collision of a trajectory in a changed scene.

#include <string>

#include <Eigen/Core>
#include <google/protobuf/repeated_ptr_field.h>

#include "chasles/collision/collision_checker.h"
#include "chasles/optimizers/timed_trajectory.h"
#include "chasles/v1/chasles.pb.h"

namespace chasles {

/// `obstacles` with their waypoint times moved by −origin [s]: waypoints at or before the origin
/// are replaced by the pose at the origin (a waypoint at time 0), later ones keep their poses.
/// The interpolation between waypoints is unchanged (MovingObstacle::PoseAt). \throws
/// Error(kInvalidArgument) naming the field for invalid obstacles.
google::protobuf::RepeatedPtrField<v1::MovingObstacle> ShiftedMovingObstacles(
    const google::protobuf::RepeatedPtrField<v1::MovingObstacle>& obstacles, double origin);

/// A stop from (q, v) along v: q + v τ − ½ (v / T) τ² for τ in [0, T], with T = maxᵢ |vᵢ| / aᵢ
/// (the joint that needs longest sets it; every joint decelerates uniformly, so the path is the
/// straight segment from q to q + v T / 2 and no acceleration exceeds its limit). v = 0 gives
/// a zero-duration trajectory at q. \throws Error(kInvalidArgument) on sizes, non-finite values or
/// limits <= 0.
TimedTrajectory BrakingTrajectory(const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                                  const Eigen::VectorXd& max_acceleration);

/// The trajectory from time `from` [s] on, its time origin moved there (pieces cut exactly:
/// the piece holding `from` is re-expanded about it).
TimedTrajectory TrajectoryFrom(const TimedTrajectory& trajectory, double from);

/// `first` then `second` (which must start where `first` ends).
TimedTrajectory Concatenated(const TimedTrajectory& first, const TimedTrajectory& second);

/// The first time [s] at which `trajectory` (from `from` on) leaves `checker`'s free space,
/// with the contact, or "" when it stays free: consecutive states at most `max_step` [rad or m]
/// apart in every joint, each motion between them checked by IsMotionFree.
std::string FindTrajectoryCollision(const CollisionChecker& checker, const TimedTrajectory& trajectory, double from,
                                    double max_step);

}  // namespace chasles
