#include "chasles/server/convert_cartesian.h"

#include <cstdint>
#include <string>

#include "chasles/server/convert.h"

namespace chasles {

CartesianSpec CartesianSpecFromProto(const v1::CartesianPathRequest& request, const RobotModel& robot) {
  CartesianSpec spec;
  spec.link = LinkFromProto(robot, request.link(), "link");
  for (int i = 0; i < request.waypoints_size(); ++i) {
    spec.waypoints.push_back(PoseFromProto(request.waypoints(i), "waypoints[" + std::to_string(i) + "]"));
  }
  const auto defaulted = [](double value, double fallback) { return value == 0.0 ? fallback : value; };
  spec.max_step = defaulted(request.max_step(), 0.01);
  spec.max_rotation_step = defaulted(request.max_rotation_step(), 0.05);
  spec.max_joint_jump = defaulted(request.max_joint_jump(), 0.2);
  spec.jump_threshold = request.jump_threshold();
  spec.line_tolerance = defaulted(request.line_tolerance(), 5e-4);
  spec.position_tolerance = defaulted(request.position_tolerance(), 1e-4);
  spec.orientation_tolerance = defaulted(request.orientation_tolerance(), 1e-3);
  spec.check_collisions = !request.ignore_collisions();
  spec.collision_resolution = defaulted(request.collision_resolution(), 0.005);
  spec.Validate(robot);  // throws naming the proto field
  return spec;
}

void CartesianResultToProto(const CartesianPathResult& result, const RobotModel& robot,
                            v1::CartesianPathResponse* response) {
  switch (result.stop) {
    case CartesianStop::kComplete: response->set_stop(v1::CartesianPathResponse::COMPLETE); break;
    case CartesianStop::kStartInvalid: response->set_stop(v1::CartesianPathResponse::START_INVALID); break;
    case CartesianStop::kUnreachable: response->set_stop(v1::CartesianPathResponse::UNREACHABLE); break;
    case CartesianStop::kJointJump: response->set_stop(v1::CartesianPathResponse::JOINT_JUMP); break;
    case CartesianStop::kRelativeJump: response->set_stop(v1::CartesianPathResponse::RELATIVE_JUMP); break;
    case CartesianStop::kCollision: response->set_stop(v1::CartesianPathResponse::COLLISION); break;
    case CartesianStop::kCancelled: response->set_stop(v1::CartesianPathResponse::CANCELLED); break;
  }
  response->set_message(result.message);
  response->set_fraction(result.fraction);
  response->set_steps(static_cast<std::uint32_t>(result.steps));
  response->set_waypoints_reached(static_cast<std::uint32_t>(result.waypoints_reached));
  for (const std::string& name : robot.dof_names()) response->add_joint_names(name);
  for (const Eigen::VectorXd& q : result.path) {
    v1::JointState* state = response->add_path();
    for (Eigen::Index i = 0; i < q.size(); ++i) state->add_positions(q[i]);
  }
  response->set_max_position_error(result.max_position_error);
  response->set_max_orientation_error(result.max_orientation_error);
  response->set_max_line_deviation(result.max_line_deviation);
  response->set_max_line_rotation_deviation(result.max_line_rotation_deviation);
}

v1::OptimizeRequest CartesianTimingRequest(const v1::CartesianPathRequest& request,
                                           const v1::CartesianPathResponse& response) {
  v1::OptimizeRequest out;
  out.set_robot_id(response.robot_id());
  out.set_scene_id(response.scene_id());
  *out.mutable_path() = response.path();
  *out.mutable_options() = request.options();
  if (!request.options().has_max_deviation()) out.mutable_options()->set_max_deviation(0.001);
  out.set_collision_resolution(request.collision_resolution());
  out.set_time_budget(request.time_budget());
  if (request.has_gravity()) *out.mutable_gravity() = request.gravity();
  out.set_request_id(response.request_id());
  out.set_padding(request.padding());
  return out;
}

}  // namespace chasles
