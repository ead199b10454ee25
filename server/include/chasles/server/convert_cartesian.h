#pragma once
/// \file
/// Conversion of the CartesianPath messages (a Cartesian move, its result, the Optimize request
/// that times it). Internal to server/; errors name the proto field like convert.h.

#include "chasles/pipeline/cartesian_path.h"
#include "chasles/robot/robot_model.h"
#include "chasles/v1/chasles.pb.h"

namespace chasles {

/// A CartesianPathRequest's move with the proto's defaults (link, waypoints, steps, jump tests,
/// tolerances, collision checking). \throws Error(kInvalidArgument) naming the field.
CartesianSpec CartesianSpecFromProto(const v1::CartesianPathRequest& request, const RobotModel& robot);

/// Fills stop, message, fraction, steps, waypoints_reached, joint_names, path and the pose
/// figures of a CartesianPathResponse.
void CartesianResultToProto(const CartesianPathResult& result, const RobotModel& robot,
                            v1::CartesianPathResponse* response);

/// The Optimize request that times a Cartesian path: the response's states as its path, the
/// request's options (max_deviation absent = 0.001 rad), resolution, budget, gravity and padding.
v1::OptimizeRequest CartesianTimingRequest(const v1::CartesianPathRequest& request,
                                           const v1::CartesianPathResponse& response);

}  // namespace chasles
