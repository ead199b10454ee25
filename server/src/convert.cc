#include "chasles/server/convert.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <utility>

#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/io/zero_copy_stream_impl_lite.h>

#include "chasles/collision/mesh.h"
#include "chasles/optimizers/shortcut.h"
#include "chasles/robot/error.h"
#include "chasles/server/content_hash.h"

namespace chasles {
namespace {

std::string Indexed(const std::string& field, int index) {
  return field + "[" + std::to_string(index) + "]";
}

void RequireFinite(double value, const std::string& field) {
  if (!std::isfinite(value)) ThrowInvalid(field + " = " + FormatNumber(value) + " must be finite");
}

void RequirePositive(double value, const std::string& field) {
  if (!(std::isfinite(value) && value > 0.0)) {
    ThrowInvalid(field + " = " + FormatNumber(value) + " must be finite and > 0");
  }
}

Eigen::Vector3d VectorFromProto(const v1::Vector3& v, const std::string& field) {
  RequireFinite(v.x(), field + ".x");
  RequireFinite(v.y(), field + ".y");
  RequireFinite(v.z(), field + ".z");
  return Eigen::Vector3d(v.x(), v.y(), v.z());
}

void RequireInRange(double value, double lo, double hi, const std::string& field) {
  if (!(value >= lo && value <= hi)) {
    ThrowInvalid(field + " = " + FormatNumber(value) + " must be within [" + FormatNumber(lo) + ", " +
                 FormatNumber(hi) + "]");
  }
}

Eigen::VectorXd PositionsFromProto(const google::protobuf::RepeatedField<double>& values,
                                   const std::string& field) {
  Eigen::VectorXd q(values.size());
  for (int i = 0; i < values.size(); ++i) {
    RequireFinite(values[i], Indexed(field, i));
    q[i] = values[i];
  }
  return q;
}

void RequireJointCount(int count, const RobotModel& robot, const std::string& field) {
  if (count != robot.num_dofs()) {
    ThrowInvalid(field + " has " + std::to_string(count) + " values, robot '" + robot.name() + "' has " +
                 std::to_string(robot.num_dofs()) + " joints");
  }
}

std::string ObjectName(const std::string& name, const char* kind, int index) {
  return name.empty() ? std::string(kind) + "[" + std::to_string(index) + "]" : name;
}

void ToProto(const Eigen::VectorXd& v, google::protobuf::RepeatedField<double>* out) {
  out->Reserve(static_cast<int>(v.size()));
  for (Eigen::Index i = 0; i < v.size(); ++i) out->Add(v[i]);
}

}  // namespace

std::string ProtoContentId(const google::protobuf::Message& message) {
  std::string bytes;
  {
    google::protobuf::io::StringOutputStream stream(&bytes);
    google::protobuf::io::CodedOutputStream coded(&stream);
    coded.SetSerializationDeterministic(true);
    message.SerializeToCodedStream(&coded);
  }
  // The type name keeps a robot and a scene with equal bytes (e.g. both empty) apart.
  return ContentId(message.GetTypeName() + '\0' + bytes);
}

Eigen::Isometry3d PoseFromProto(const v1::Pose& pose, const std::string& field) {
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.translation() = VectorFromProto(pose.position(), field + ".position");
  const v1::Quaternion& q = pose.orientation();
  const std::string qfield = field + ".orientation";
  RequireFinite(q.x(), qfield + ".x");
  RequireFinite(q.y(), qfield + ".y");
  RequireFinite(q.z(), qfield + ".z");
  RequireFinite(q.w(), qfield + ".w");
  if (q.x() == 0.0 && q.y() == 0.0 && q.z() == 0.0 && q.w() == 0.0) return out;  // identity
  Eigen::Quaterniond quat(q.w(), q.x(), q.y(), q.z());
  const double norm = quat.norm();
  if (std::abs(norm - 1.0) > 1e-3) {
    ThrowInvalid(qfield + " has norm " + FormatNumber(norm) +
                 ", must be a unit quaternion (norm 1 within 1e-3) or all zero for identity");
  }
  out.linear() = quat.normalized().toRotationMatrix();
  return out;
}

std::shared_ptr<const RobotModel> RobotFromProto(const v1::RobotModel& robot, const std::string& field) {
  if (robot.description_case() != v1::RobotModel::kUrdf) {
    ThrowInvalid(field + " has no description: set " + field + ".urdf");
  }
  const v1::UrdfRobot& urdf = robot.urdf();
  if (urdf.urdf().empty()) ThrowInvalid(field + ".urdf.urdf is empty: it must hold the URDF XML text");
  std::map<std::string, std::shared_ptr<const TriangleMesh>> meshes;
  // Sorted iteration keeps error messages deterministic.
  std::map<std::string, const std::string*> files;
  for (const auto& [name, bytes] : urdf.mesh_files()) files[name] = &bytes;
  for (const auto& [name, bytes] : files) {
    meshes[name] = ParseMesh(*bytes, Eigen::Vector3d::Ones(), field + ".urdf.mesh_files['" + name + "']");
  }
  try {
    return RobotModel::FromUrdf(urdf.urdf(), urdf.srdf(), meshes);
  } catch (const Error& e) {
    const std::string what = e.what();
    // Prefix the proto field unless the robot module already named it.
    if (what.rfind(field, 0) == 0) throw;
    // "urdf: …" / "srdf: …" from the loader become "robot.urdf.urdf: …" / "robot.urdf.srdf: …".
    if (what.rfind("urdf", 0) == 0 || what.rfind("srdf", 0) == 0) throw Error(e.code(), field + ".urdf." + what);
    throw Error(e.code(), field + ".urdf: " + what);
  }
}

std::shared_ptr<const Scene> SceneFromProto(const v1::Scene& proto, const std::string& field) {
  auto scene = std::make_shared<Scene>();
  for (int i = 0; i < proto.boxes_size(); ++i) {
    const v1::Box& box = proto.boxes(i);
    const std::string f = Indexed(field + ".boxes", i);
    const Eigen::Vector3d size = VectorFromProto(box.size(), f + ".size");
    RequirePositive(size.x(), f + ".size.x");
    RequirePositive(size.y(), f + ".size.y");
    RequirePositive(size.z(), f + ".size.z");
    scene->AddObject({ObjectName(box.name(), "box", i), Shape::Box(size, PoseFromProto(box.pose(), f + ".pose"))}, f);
  }
  for (int i = 0; i < proto.spheres_size(); ++i) {
    const v1::Sphere& sphere = proto.spheres(i);
    const std::string f = Indexed(field + ".spheres", i);
    RequirePositive(sphere.radius(), f + ".radius");
    scene->AddObject({ObjectName(sphere.name(), "sphere", i),
                      Shape::Sphere(sphere.radius(), PoseFromProto(sphere.pose(), f + ".pose"))}, f);
  }
  for (int i = 0; i < proto.cylinders_size(); ++i) {
    const v1::Cylinder& cylinder = proto.cylinders(i);
    const std::string f = Indexed(field + ".cylinders", i);
    RequirePositive(cylinder.radius(), f + ".radius");
    RequirePositive(cylinder.length(), f + ".length");
    scene->AddObject({ObjectName(cylinder.name(), "cylinder", i),
                      Shape::Cylinder(cylinder.radius(), cylinder.length(),
                                      PoseFromProto(cylinder.pose(), f + ".pose"))}, f);
  }
  for (int i = 0; i < proto.capsules_size(); ++i) {
    const v1::Capsule& capsule = proto.capsules(i);
    const std::string f = Indexed(field + ".capsules", i);
    RequirePositive(capsule.radius(), f + ".radius");
    RequirePositive(capsule.length(), f + ".length");
    // Shape::Capsule takes the full length of the cylindrical part, as the proto does.
    scene->AddObject({ObjectName(capsule.name(), "capsule", i),
                      Shape::Capsule(capsule.radius(), capsule.length(),
                                     PoseFromProto(capsule.pose(), f + ".pose"))}, f);
  }
  for (int i = 0; i < proto.meshes_size(); ++i) {
    const v1::Mesh& mesh = proto.meshes(i);
    const std::string f = Indexed(field + ".meshes", i);
    Eigen::Vector3d scale = VectorFromProto(mesh.scale(), f + ".scale");
    if (scale.isZero(0.0)) {
      scale = Eigen::Vector3d::Ones();
    } else {
      RequirePositive(scale.x(), f + ".scale.x");
      RequirePositive(scale.y(), f + ".scale.y");
      RequirePositive(scale.z(), f + ".scale.z");
    }
    if (mesh.data().empty()) ThrowInvalid(f + ".data is empty: it must hold STL or OBJ bytes");
    Shape shape;
    shape.type = ShapeType::kMesh;
    shape.mesh = ParseMesh(mesh.data(), scale, f + ".data");
    shape.pose = PoseFromProto(mesh.pose(), f + ".pose");
    scene->AddObject({ObjectName(mesh.name(), "mesh", i), std::move(shape)}, f);
  }
  for (int i = 0; i < proto.octomaps_size(); ++i) {
    const v1::OctoMap& map = proto.octomaps(i);
    const std::string f = Indexed(field + ".octomaps", i);
    if (map.data().empty()) ThrowInvalid(f + ".data is empty: it must hold .bt or .ot OcTree bytes");
    scene->AddOctoMap(ObjectName(map.name(), "octomap", i), map.data(), PoseFromProto(map.pose(), f + ".pose"),
                      f + ".data");
  }
  return scene;
}

PlanQuery PlanQueryFromProto(const v1::PlanRequest& request, std::shared_ptr<const CollisionChecker> checker,
                             const PlannerRegistry& registry, RequestSettings* settings) {
  const RobotModel& robot = checker->robot();
  PlanQuery query;
  query.checker = std::move(checker);

  // Budget: 0 = 5 s, else (0, 600].
  double budget = request.time_budget();
  if (budget == 0.0) budget = 5.0;
  if (!(budget > 0.0 && budget <= 600.0)) {
    ThrowInvalid("time_budget = " + FormatNumber(request.time_budget()) + " must be within (0, 600] s (0 = 5 s)");
  }
  settings->time_budget = budget;

  RequireJointCount(request.start().positions_size(), robot, "start.positions");
  query.start = PositionsFromProto(request.start().positions(), "start.positions");
  robot.ValidateConfiguration(query.start, "start.positions");
  RequireJointCount(request.goal().positions_size(), robot, "goal.positions");
  query.goal = PositionsFromProto(request.goal().positions(), "goal.positions");
  robot.ValidateConfiguration(query.goal, "goal.positions");

  const double tolerance = request.goal().tolerance();
  RequireInRange(tolerance, 0.0, 0.1, "goal.tolerance");
  query.goal_tolerance = tolerance == 0.0 ? 1e-3 : tolerance;

  // Planner and its parameters (types checked here, ranges by ResolveParameters).
  query.planner_id = request.planner().planner_id().empty() ? "rrt_connect" : request.planner().planner_id();
  const PlannerSpec& spec = registry.Spec(query.planner_id);
  // Sorted, so the first error reported does not depend on hash-map order.
  std::map<std::string, const v1::ParameterValue*> parameters;
  for (const auto& entry : request.planner().parameters()) parameters[entry.first] = &entry.second;
  for (const auto& [name, value_ptr] : parameters) {
    const v1::ParameterValue& value = *value_ptr;
    const std::string f = "planner.parameters['" + name + "']";
    const ParameterSpec* param = spec.Find(name);
    double number = 0.0;
    switch (value.value_case()) {
      case v1::ParameterValue::kDoubleValue:
        number = value.double_value();
        if (param != nullptr && param->type == ParameterType::kBool) {
          ThrowInvalid(f + " is a bool parameter of planner '" + spec.id + "': set bool_value");
        }
        break;
      case v1::ParameterValue::kIntValue:
        number = static_cast<double>(value.int_value());
        if (param != nullptr && param->type == ParameterType::kBool) {
          ThrowInvalid(f + " is a bool parameter of planner '" + spec.id + "': set bool_value");
        }
        break;
      case v1::ParameterValue::kBoolValue:
        number = value.bool_value() ? 1.0 : 0.0;
        if (param != nullptr && param->type != ParameterType::kBool) {
          ThrowInvalid(f + " = " + (value.bool_value() ? "true" : "false") + " must be a number (parameter of "
                       "planner '" + spec.id + "')");
        }
        break;
      default:
        ThrowInvalid(f + " has no value: set double_value, int_value or bool_value");
    }
    query.parameters[name] = number;
  }
  ResolveParameters(spec, query.parameters);  // throws naming the parameter

  query.seed = request.seed() == 0 ? 1 : request.seed();

  const double resolution = request.collision_resolution() == 0.0 ? 0.005 : request.collision_resolution();
  RequireInRange(resolution, 1e-4, 0.1, "collision_resolution");
  query.collision_resolution = resolution;

  const v1::TrajectoryOptions& trajectory = request.trajectory();
  const double period = trajectory.sample_period() == 0.0 ? 0.01 : trajectory.sample_period();
  RequireInRange(period, 1e-4, 1.0, "trajectory.sample_period");
  query.sample_period = period;

  if (trajectory.shortcut_attempts() < -1) {
    ThrowInvalid("trajectory.shortcut_attempts = " + std::to_string(trajectory.shortcut_attempts()) +
                 " must be -1 (off), 0 (default 100) or > 0");
  }
  query.shortcut_attempts = trajectory.shortcut_attempts() == 0 ? 100 : trajectory.shortcut_attempts();

  if (trajectory.max_velocity_size() > 0) {
    RequireJointCount(trajectory.max_velocity_size(), robot, "trajectory.max_velocity");
    query.max_velocity.resize(robot.num_dofs());
    for (int i = 0; i < trajectory.max_velocity_size(); ++i) {
      const double v = trajectory.max_velocity(i);
      RequirePositive(v, Indexed("trajectory.max_velocity", i));
      query.max_velocity[i] = std::min(v, robot.velocity_limits()[i]);
    }
  }
  if (trajectory.max_acceleration_size() > 0) {
    RequireJointCount(trajectory.max_acceleration_size(), robot, "trajectory.max_acceleration");
    query.max_acceleration.resize(robot.num_dofs());
    for (int i = 0; i < trajectory.max_acceleration_size(); ++i) {
      const double a = trajectory.max_acceleration(i);
      RequirePositive(a, Indexed("trajectory.max_acceleration", i));
      query.max_acceleration[i] = a;
    }
  }
  query.Validate(registry);
  return query;
}

v1::PlanOutcome OutcomeToProto(PlanOutcomeCode code) {
  switch (code) {
    case PlanOutcomeCode::kSuccess: return v1::SUCCESS;
    case PlanOutcomeCode::kNoPathWithinBudget: return v1::NO_PATH_WITHIN_BUDGET;
    case PlanOutcomeCode::kStartInCollision: return v1::START_IN_COLLISION;
    case PlanOutcomeCode::kGoalInCollision: return v1::GOAL_IN_COLLISION;
    case PlanOutcomeCode::kVerificationFailed: return v1::VERIFICATION_FAILED;
    case PlanOutcomeCode::kApproximateOnly: return v1::APPROXIMATE_ONLY;
    case PlanOutcomeCode::kCancelled:
    case PlanOutcomeCode::kDeadlineExceeded: return v1::PLAN_OUTCOME_UNSPECIFIED;
  }
  return v1::PLAN_OUTCOME_UNSPECIFIED;
}

void PlanOutcomeToProto(const PlanOutcome& outcome, const PlanQuery& query, v1::PlanResponse* response) {
  const RobotModel& robot = query.checker->robot();
  response->set_outcome(OutcomeToProto(outcome.code));
  response->set_message(outcome.message);

  v1::StageTimings* timings = response->mutable_timings();
  timings->set_validate(outcome.seconds.validate);
  timings->set_plan(outcome.seconds.plan);
  timings->set_shortcut(outcome.seconds.shortcut);
  timings->set_parameterize(outcome.seconds.parameterize);
  timings->set_verify(outcome.seconds.verify);
  timings->set_total(outcome.seconds.total);

  v1::PlannerStatistics* stats = response->mutable_statistics();
  stats->set_graph_states(outcome.graph_states);
  stats->set_collision_checks(outcome.state_checks);
  stats->set_raw_waypoints(static_cast<std::uint32_t>(outcome.raw_path.size()));
  stats->set_path_length(outcome.path.empty() ? 0.0 : PathLength(outcome.path));

  v1::Verification* verification = response->mutable_verification();
  verification->set_states_checked(static_cast<std::uint32_t>(std::max(0, outcome.verification.states_checked)));
  verification->set_max_joint_step(query.collision_resolution);
  verification->set_max_velocity_ratio(outcome.verification.max_velocity_ratio);
  verification->set_max_acceleration_ratio(outcome.verification.max_acceleration_ratio);

  if (outcome.code != PlanOutcomeCode::kSuccess) return;  // nothing unverified leaves the server
  for (const Eigen::VectorXd& q : outcome.path) ToProto(q, response->add_path()->mutable_positions());
  v1::JointTrajectory* trajectory = response->mutable_trajectory();
  for (const std::string& name : robot.dof_names()) trajectory->add_joint_names(name);
  for (const TrajectorySample& sample : outcome.samples) {
    v1::TrajectoryPoint* point = trajectory->add_points();
    point->set_time_from_start(sample.t);
    ToProto(sample.q, point->mutable_positions());
    ToProto(sample.qd, point->mutable_velocities());
    ToProto(sample.qdd, point->mutable_accelerations());
  }
  response->set_duration(outcome.trajectory.duration());
}

void PlannerSpecToProto(const PlannerSpec& spec, v1::PlannerDescription* description) {
  description->set_id(spec.id);
  description->set_description(spec.description);
  description->set_optimizing(spec.optimizing);
  for (const ParameterSpec& param : spec.parameters) {
    v1::ParameterDescription* out = description->add_parameters();
    out->set_name(param.name);
    out->set_description(param.description);
    switch (param.type) {
      case ParameterType::kDouble: out->set_type(v1::ParameterDescription::DOUBLE); break;
      case ParameterType::kInt: out->set_type(v1::ParameterDescription::INT); break;
      case ParameterType::kBool: out->set_type(v1::ParameterDescription::BOOL); break;
    }
    out->set_default_value(param.default_value);
    out->set_min(param.min);
    out->set_max(param.max);
  }
}

}  // namespace chasles
