#include "chasles/server/convert.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <sstream>
#include <utility>

#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/io/zero_copy_stream_impl_lite.h>

#include "chasles/collision/mesh.h"
#include "chasles/optimizers/shortcut.h"
#include "chasles/robot/error.h"
#include "chasles/robot/kinematics.h"
#include "chasles/robot/mobile.h"
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


JointType JointTypeFromProto(v1::JointKind kind, const std::string& field) {
  switch (kind) {
    case v1::JOINT_KIND_UNSPECIFIED:
    case v1::REVOLUTE: return JointType::kRevolute;
    case v1::CONTINUOUS: return JointType::kContinuous;
    case v1::PRISMATIC: return JointType::kPrismatic;
    default: break;
  }
  ThrowInvalid(field + " = " + std::to_string(static_cast<int>(kind)) +
               " is not a joint kind (REVOLUTE, CONTINUOUS or PRISMATIC)");
}

JointLimits LimitsFromProto(const v1::JointLimits& limits, const std::string& field) {
  RequireFinite(limits.lower(), field + ".lower");
  RequireFinite(limits.upper(), field + ".upper");
  RequireFinite(limits.velocity(), field + ".velocity");
  RequireFinite(limits.effort(), field + ".effort");
  JointLimits out;
  out.lower = limits.lower();
  out.upper = limits.upper();
  out.velocity = limits.velocity();
  out.effort = limits.effort();
  return out;
}

void RequireNonNegative(double value, const std::string& field) {
  if (!(std::isfinite(value) && value >= 0.0)) {
    ThrowInvalid(field + " = " + FormatNumber(value) + " must be finite and >= 0");
  }
}

// One converter per primitive, shared by scenes and DH/PoE link geometry; `f` names the element.
Shape ShapeFromProto(const v1::Sphere& sphere, const std::string& f) {
  RequirePositive(sphere.radius(), f + ".radius");
  return Shape::Sphere(sphere.radius(), PoseFromProto(sphere.pose(), f + ".pose"));
}

Shape ShapeFromProto(const v1::Box& box, const std::string& f) {
  const Eigen::Vector3d size = VectorFromProto(box.size(), f + ".size");
  RequirePositive(size.x(), f + ".size.x");
  RequirePositive(size.y(), f + ".size.y");
  RequirePositive(size.z(), f + ".size.z");
  return Shape::Box(size, PoseFromProto(box.pose(), f + ".pose"));
}

Shape ShapeFromProto(const v1::Cylinder& cylinder, const std::string& f) {
  RequirePositive(cylinder.radius(), f + ".radius");
  RequirePositive(cylinder.length(), f + ".length");
  return Shape::Cylinder(cylinder.radius(), cylinder.length(), PoseFromProto(cylinder.pose(), f + ".pose"));
}

// Shape::Capsule takes the full length of the cylindrical part, as the proto does.
Shape ShapeFromProto(const v1::Capsule& capsule, const std::string& f) {
  RequirePositive(capsule.radius(), f + ".radius");
  RequirePositive(capsule.length(), f + ".length");
  return Shape::Capsule(capsule.radius(), capsule.length(), PoseFromProto(capsule.pose(), f + ".pose"));
}

/// Calls add(shape, field, name, kind, index) for every primitive of a Scene or LinkGeometry.
template <typename Message, typename Add>
void ForEachPrimitive(const Message& m, const std::string& field, Add add) {
  for (int i = 0; i < m.boxes_size(); ++i) {
    const std::string f = Indexed(field + ".boxes", i);
    add(ShapeFromProto(m.boxes(i), f), f, m.boxes(i).name(), "box", i);
  }
  for (int i = 0; i < m.spheres_size(); ++i) {
    const std::string f = Indexed(field + ".spheres", i);
    add(ShapeFromProto(m.spheres(i), f), f, m.spheres(i).name(), "sphere", i);
  }
  for (int i = 0; i < m.cylinders_size(); ++i) {
    const std::string f = Indexed(field + ".cylinders", i);
    add(ShapeFromProto(m.cylinders(i), f), f, m.cylinders(i).name(), "cylinder", i);
  }
  for (int i = 0; i < m.capsules_size(); ++i) {
    const std::string f = Indexed(field + ".capsules", i);
    add(ShapeFromProto(m.capsules(i), f), f, m.capsules(i).name(), "capsule", i);
  }
}

LinkProperties LinkPropertiesFromProto(const v1::LinkGeometry& link, const std::string& field) {
  LinkProperties out;
  ForEachPrimitive(link, field, [&out](Shape shape, const std::string&, const std::string&, const char*, int) {
    out.collision.push_back(std::move(shape));
  });
  if (link.has_inertial()) {
    const v1::Inertial& inertial = link.inertial();
    const std::string f = field + ".inertial";
    RequirePositive(inertial.mass(), f + ".mass");
    Inertial in;
    in.mass = inertial.mass();
    in.com = VectorFromProto(inertial.com(), f + ".com");
    const v1::InertiaTensor& t = inertial.inertia();
    const std::string tf = f + ".inertia";
    RequireFinite(t.ixx(), tf + ".ixx");
    RequireFinite(t.ixy(), tf + ".ixy");
    RequireFinite(t.ixz(), tf + ".ixz");
    RequireFinite(t.iyy(), tf + ".iyy");
    RequireFinite(t.iyz(), tf + ".iyz");
    RequireFinite(t.izz(), tf + ".izz");
    in.inertia << t.ixx(), t.ixy(), t.ixz(), t.ixy(), t.iyy(), t.iyz(), t.ixz(), t.iyz(), t.izz();
    out.inertial = in;
  }
  return out;
}

std::vector<std::pair<std::string, std::string>> PairsFromProto(
    const google::protobuf::RepeatedPtrField<v1::LinkPair>& pairs, const std::string& field) {
  std::vector<std::pair<std::string, std::string>> out;
  for (int i = 0; i < pairs.size(); ++i) {
    if (pairs[i].link1().empty() || pairs[i].link2().empty()) {
      ThrowInvalid(Indexed(field, i) + " must name two links (link1 and link2)");
    }
    out.emplace_back(pairs[i].link1(), pairs[i].link2());
  }
  return out;
}

/// Re-throws a robot-module error with the proto path: "dh.joints[2]…" → "robot.dh.joints[2]…".
/// Every mesh file costs a parse, however small it is.
void CheckMeshFileCount(std::size_t count, const std::string& field, const InputLimits& limits) {
  if (count > limits.max_mesh_files) {
    ThrowResourceExhausted(field + " holds " + std::to_string(count) + " mesh files, more than the cap of " +
                           std::to_string(limits.max_mesh_files) +
                           " (InputLimits::max_mesh_files); merge meshes or raise the server's cap");
  }
}

[[noreturn]] void RethrowWithField(const Error& e, const std::string& field, const std::string& kind) {
  const std::string what = e.what();
  if (what.rfind(field, 0) == 0) throw e;
  if (what.rfind(kind, 0) == 0) {
    // "robot.dh" + ".joints…" when field ends in the description name, else field + "." + what.
    const std::string parent = field.size() > kind.size() &&
                                       field.compare(field.size() - kind.size(), kind.size(), kind) == 0
                                   ? field.substr(0, field.size() - kind.size())
                                   : field + ".";
    throw Error(e.code(), parent + what);
  }
  throw Error(e.code(), field + ": " + what);
}

double DefaultedInRange(double value, double fallback, double lo_exclusive, double hi, const std::string& field) {
  const double v = value == 0.0 ? fallback : value;
  if (!(v > lo_exclusive && v <= hi)) {
    ThrowInvalid(field + " = " + FormatNumber(value) + " must be within (" + FormatNumber(lo_exclusive) + ", " +
                 FormatNumber(hi) + "] (0 = " + FormatNumber(fallback) + ")");
  }
  return v;
}

}  // namespace

void ToProto(const Eigen::VectorXd& v, google::protobuf::RepeatedField<double>* out) {
  out->Reserve(out->size() + static_cast<int>(v.size()));
  for (Eigen::Index i = 0; i < v.size(); ++i) out->Add(v[i]);
}

void PoseToProto(const Eigen::Isometry3d& pose, v1::Pose* out) {
  out->mutable_position()->set_x(pose.translation().x());
  out->mutable_position()->set_y(pose.translation().y());
  out->mutable_position()->set_z(pose.translation().z());
  Eigen::Quaterniond q(pose.rotation());
  q.normalize();
  if (q.w() < 0) q.coeffs() *= -1.0;  // one of the two equal quaternions, for stable output
  out->mutable_orientation()->set_x(q.x());
  out->mutable_orientation()->set_y(q.y());
  out->mutable_orientation()->set_z(q.z());
  out->mutable_orientation()->set_w(q.w());
}

Eigen::VectorXd JointValuesFromProto(const google::protobuf::RepeatedField<double>& values, const RobotModel& robot,
                                     const std::string& field) {
  RequireJointCount(values.size(), robot, field);
  return PositionsFromProto(values, field);
}

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

Eigen::Quaterniond QuaternionFromProto(const v1::Quaternion& q, const std::string& field) {
  RequireFinite(q.x(), field + ".x");
  RequireFinite(q.y(), field + ".y");
  RequireFinite(q.z(), field + ".z");
  RequireFinite(q.w(), field + ".w");
  if (q.x() == 0.0 && q.y() == 0.0 && q.z() == 0.0 && q.w() == 0.0) return Eigen::Quaterniond::Identity();
  Eigen::Quaterniond quat(q.w(), q.x(), q.y(), q.z());
  const double norm = quat.norm();
  if (std::abs(norm - 1.0) > 1e-3) {
    ThrowInvalid(field + " has norm " + FormatNumber(norm) +
                 ", must be a unit quaternion (norm 1 within 1e-3) or all zero for identity");
  }
  return quat.normalized();
}

Eigen::Isometry3d PoseFromProto(const v1::Pose& pose, const std::string& field) {
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.translation() = VectorFromProto(pose.position(), field + ".position");
  out.linear() = QuaternionFromProto(pose.orientation(), field + ".orientation").toRotationMatrix();
  return out;
}

std::shared_ptr<const PathConstraints> PathConstraintsFromProto(const v1::PathConstraints& constraints,
                                                                std::shared_ptr<const RobotModel> robot,
                                                                const std::string& field) {
  std::vector<OrientationConstraintSpec> orientation;
  for (int i = 0; i < constraints.orientation_size(); ++i) {
    const v1::OrientationConstraint& c = constraints.orientation(i);
    const std::string f = Indexed(field + ".orientation", i);
    OrientationConstraintSpec spec;
    spec.link = LinkFromProto(*robot, c.link(), f + ".link");
    spec.orientation = QuaternionFromProto(c.orientation(), f + ".orientation");
    spec.tolerance = VectorFromProto(c.tolerance(), f + ".tolerance");
    spec.parameterization = c.parameterization() == v1::OrientationConstraint::ROTATION_VECTOR
                                ? OrientationParameterization::kRotationVector
                                : OrientationParameterization::kXyzEulerAngles;
    orientation.push_back(spec);
  }
  std::vector<PositionConstraintSpec> position;
  for (int i = 0; i < constraints.position_size(); ++i) {
    const v1::PositionConstraint& c = constraints.position(i);
    const std::string f = Indexed(field + ".position", i);
    PositionConstraintSpec spec;
    spec.link = LinkFromProto(*robot, c.link(), f + ".link");
    spec.point = VectorFromProto(c.point(), f + ".point");
    spec.region = PoseFromProto(c.region(), f + ".region");
    spec.half_extents = VectorFromProto(c.half_extents(), f + ".half_extents");
    position.push_back(spec);
  }
  return std::make_shared<const PathConstraints>(std::move(robot), std::move(orientation), std::move(position), field);
}

DhDescription DhFromProto(const v1::DhRobot& dh, const std::string& field) {
  DhDescription out;
  out.name = dh.name();
  switch (dh.convention()) {
    case v1::DhRobot::CONVENTION_UNSPECIFIED:
    case v1::DhRobot::STANDARD: out.convention = DhConvention::kStandard; break;
    case v1::DhRobot::MODIFIED: out.convention = DhConvention::kModified; break;
    default:
      ThrowInvalid(field + ".convention = " + std::to_string(static_cast<int>(dh.convention())) +
                   " is not STANDARD or MODIFIED");
  }
  for (int i = 0; i < dh.joints_size(); ++i) {
    const v1::DhJoint& joint = dh.joints(i);
    const std::string f = Indexed(field + ".joints", i);
    DhJoint j;
    j.name = joint.name();
    j.type = JointTypeFromProto(joint.type(), f + ".type");
    RequireFinite(joint.a(), f + ".a");
    RequireFinite(joint.alpha(), f + ".alpha");
    RequireFinite(joint.d(), f + ".d");
    RequireFinite(joint.theta_offset(), f + ".theta_offset");
    j.a = joint.a();
    j.alpha = joint.alpha();
    j.d = joint.d();
    j.theta_offset = joint.theta_offset();
    j.limits = LimitsFromProto(joint.limits(), f + ".limits");
    RequireNonNegative(joint.damping(), f + ".damping");
    RequireNonNegative(joint.friction(), f + ".friction");
    RequireNonNegative(joint.armature(), f + ".armature");
    j.damping = joint.damping();
    j.friction = joint.friction();
    j.armature = joint.armature();
    j.link = LinkPropertiesFromProto(joint.link(), f + ".link");
    out.joints.push_back(std::move(j));
  }
  if (dh.has_base()) out.base = PoseFromProto(dh.base(), field + ".base");
  if (dh.has_tool()) out.tool = PoseFromProto(dh.tool(), field + ".tool");
  out.base_link = LinkPropertiesFromProto(dh.base_link(), field + ".base_link");
  out.allowed_collisions = PairsFromProto(dh.allowed_collisions(), field + ".allowed_collisions");
  return out;
}

PoeDescription PoeFromProto(const v1::PoeRobot& poe, const std::string& field) {
  PoeDescription out;
  out.name = poe.name();
  if (poe.has_home()) out.home = PoseFromProto(poe.home(), field + ".home");
  out.body_frame = poe.body_frame();
  for (int i = 0; i < poe.joints_size(); ++i) {
    const v1::PoeJoint& joint = poe.joints(i);
    const std::string f = Indexed(field + ".joints", i);
    PoeJoint j;
    j.name = joint.name();
    j.type = JointTypeFromProto(joint.type(), f + ".type");
    j.screw.head<3>() = VectorFromProto(joint.screw().angular(), f + ".screw.angular");
    j.screw.tail<3>() = VectorFromProto(joint.screw().linear(), f + ".screw.linear");
    j.limits = LimitsFromProto(joint.limits(), f + ".limits");
    RequireNonNegative(joint.damping(), f + ".damping");
    RequireNonNegative(joint.friction(), f + ".friction");
    RequireNonNegative(joint.armature(), f + ".armature");
    j.damping = joint.damping();
    j.friction = joint.friction();
    j.armature = joint.armature();
    if (joint.has_link_home()) j.link_home = PoseFromProto(joint.link_home(), f + ".link_home");
    j.link = LinkPropertiesFromProto(joint.link(), f + ".link");
    out.joints.push_back(std::move(j));
  }
  out.base_link = LinkPropertiesFromProto(poe.base_link(), field + ".base_link");
  out.allowed_collisions = PairsFromProto(poe.allowed_collisions(), field + ".allowed_collisions");
  return out;
}

MobileDescription MobileFromProto(const v1::MobileRobot& mobile, const std::string& field) {
  MobileDescription out;
  out.name = mobile.name();
  switch (mobile.kind()) {
    case v1::MobileRobot::KIND_UNSPECIFIED:
    case v1::MobileRobot::PLANAR: out.kind = RobotKind::kPlanar; break;
    case v1::MobileRobot::DUBINS_CAR: out.kind = RobotKind::kDubinsCar; break;
    case v1::MobileRobot::REEDS_SHEPP_CAR: out.kind = RobotKind::kReedsSheppCar; break;
    case v1::MobileRobot::FREE_FLYER: out.kind = RobotKind::kFreeFlyer; break;
    default:
      ThrowInvalid(field + ".kind = " + std::to_string(static_cast<int>(mobile.kind())) +
                   " is not PLANAR, DUBINS_CAR, REEDS_SHEPP_CAR or FREE_FLYER");
  }
  out.workspace_min = VectorFromProto(mobile.workspace_min(), field + ".workspace_min");
  out.workspace_max = VectorFromProto(mobile.workspace_max(), field + ".workspace_max");
  out.turning_radius = mobile.turning_radius();
  if (mobile.max_tilt() != 0.0) out.max_tilt = mobile.max_tilt();
  out.linear_velocity = mobile.linear_velocity() == 0.0 ? 1.0 : mobile.linear_velocity();
  out.angular_velocity = mobile.angular_velocity() == 0.0 ? 1.0 : mobile.angular_velocity();
  out.body = LinkPropertiesFromProto(mobile.body(), field + ".body");
  return out;
}

std::shared_ptr<const RobotModel> RobotFromProto(const v1::RobotModel& robot, const std::string& field,
                                                 const InputLimits& limits) {
  if (robot.description_case() == v1::RobotModel::kMobile) {
    MobileDescription mobile = MobileFromProto(robot.mobile(), field + ".mobile");
    if (mobile.name.empty()) mobile.name = robot.name();
    try {
      return RobotFromMobile(mobile);
    } catch (const Error& e) {
      RethrowWithField(e, field + ".mobile", "mobile");
    }
  }
  if (robot.description_case() == v1::RobotModel::kDh) {
    DhDescription dh = DhFromProto(robot.dh(), field + ".dh");
    if (dh.name.empty()) dh.name = robot.name();
    try {
      return RobotFromDh(dh, limits);
    } catch (const Error& e) {
      RethrowWithField(e, field + ".dh", "dh");
    }
  }
  if (robot.description_case() == v1::RobotModel::kPoe) {
    PoeDescription poe = PoeFromProto(robot.poe(), field + ".poe");
    if (poe.name.empty()) poe.name = robot.name();
    try {
      return RobotFromPoe(poe, limits);
    } catch (const Error& e) {
      RethrowWithField(e, field + ".poe", "poe");
    }
  }
  if (robot.description_case() != v1::RobotModel::kUrdf) {
    ThrowInvalid(field + " has no description: set " + field + ".urdf, " + field + ".dh, " + field + ".poe or " +
                 field + ".mobile");
  }
  const v1::UrdfRobot& urdf = robot.urdf();
  if (urdf.urdf().empty()) ThrowInvalid(field + ".urdf.urdf is empty: it must hold the URDF XML text");
  CheckMeshFileCount(static_cast<std::size_t>(urdf.mesh_files_size()), field + ".urdf.mesh_files", limits);
  // Only the meshes collision geometry names are parsed, each once, when the loader meets it:
  // visual meshes may be sent along (a whole meshes folder) and are never read.
  std::map<std::string, std::shared_ptr<const TriangleMesh>> parsed;
  const auto resolve = [&](const std::string& name) -> std::shared_ptr<const TriangleMesh> {
    const auto done = parsed.find(name);
    if (done != parsed.end()) return done->second;
    const auto it = urdf.mesh_files().find(name);
    if (it == urdf.mesh_files().end()) return nullptr;
    return parsed[name] = ParseMesh(it->second, Eigen::Vector3d::Ones(), field + ".urdf.mesh_files['" + name + "']", limits);
  };
  try {
    return RobotModel::FromUrdfResolvingMeshes(urdf.urdf(), urdf.srdf(), resolve, limits, urdf.strict_srdf());
  } catch (const Error& e) {
    const std::string what = e.what();
    // Prefix the proto field unless the robot module already named it.
    if (what.rfind(field, 0) == 0) throw;
    // "urdf: …" / "srdf: …" from the loader become "robot.urdf.urdf: …" / "robot.urdf.srdf: …".
    if (what.rfind("urdf", 0) == 0 || what.rfind("srdf", 0) == 0) throw Error(e.code(), field + ".urdf." + what);
    throw Error(e.code(), field + ".urdf: " + what);
  }
}

int LinkFromProto(const RobotModel& robot, const std::string& name, const std::string& field) {
  if (name.empty()) {
    const int tool = robot.FindLink("tool");
    return tool >= 0 ? tool : robot.num_links() - 1;
  }
  const int link = robot.FindLink(name);
  if (link >= 0) return link;
  std::string known;
  for (const Link& l : robot.links()) known += (known.empty() ? "" : ", ") + l.name;
  ThrowInvalid(field + " = '" + name + "' is not a link of robot '" + robot.name() + "'; known links: " + known);
}

IkRequest IkRequestFromProto(const v1::InverseKinematicsRequest& request, const RobotModel& robot) {
  IkRequest ik;
  ik.link = LinkFromProto(robot, request.link(), "link");
  ik.target = PoseFromProto(request.pose(), "pose");
  ik.position_tolerance = DefaultedInRange(request.position_tolerance(), 1e-4, 0.0, 0.1, "position_tolerance");
  ik.orientation_tolerance =
      DefaultedInRange(request.orientation_tolerance(), 1e-3, 0.0, 0.5, "orientation_tolerance");
  switch (request.method()) {
    case v1::InverseKinematicsRequest::METHOD_UNSPECIFIED:
    case v1::InverseKinematicsRequest::DAMPED_LEAST_SQUARES: ik.method = IkMethod::kDampedLeastSquares; break;
    case v1::InverseKinematicsRequest::NEWTON_RAPHSON: ik.method = IkMethod::kNewtonRaphson; break;
    default:
      ThrowInvalid("method = " + std::to_string(static_cast<int>(request.method())) +
                   " is not DAMPED_LEAST_SQUARES or NEWTON_RAPHSON");
  }
  const double damping = request.damping() == 0.0 ? 0.05 : request.damping();
  RequireInRange(damping, 0.0, 10.0, "damping");
  ik.damping = damping;
  if (request.max_solutions() > 64) {
    ThrowInvalid("max_solutions = " + std::to_string(request.max_solutions()) + " must be at most 64 (0 = 1)");
  }
  ik.max_solutions = request.max_solutions() == 0 ? 1 : static_cast<int>(request.max_solutions());
  ik.time_budget = DefaultedInRange(request.time_budget(), 0.05, 0.0, 60.0, "time_budget");
  ik.seed = request.seed() == 0 ? 1 : request.seed();
  if (request.initial_guess_size() > 0) {
    RequireJointCount(request.initial_guess_size(), robot, "initial_guess");
    ik.initial_guess = PositionsFromProto(request.initial_guess(), "initial_guess");
    robot.ValidateConfiguration(ik.initial_guess, "initial_guess");
  }
  return ik;
}

std::vector<AttachedObject> AttachedObjectsFromProto(const google::protobuf::RepeatedPtrField<v1::AttachedObject>& objects,
                                                     const RobotModel& robot, const std::string& field) {
  std::vector<AttachedObject> out;
  for (int i = 0; i < objects.size(); ++i) {
    const v1::AttachedObject& object = objects.Get(i);
    const std::string f = Indexed(field, i);
    AttachedObject attached;
    attached.name = object.name();
    attached.link = LinkFromProto(robot, object.link(), f + ".link");
    ForEachPrimitive(object, f, [&attached](Shape shape, const std::string&, const std::string&, const char*, int) {
      attached.shapes.push_back(std::move(shape));
    });
    attached.touch_links.assign(object.touch_links().begin(), object.touch_links().end());
    attached.mass = object.mass();
    if (object.has_center_of_mass()) {
      attached.center_of_mass = VectorFromProto(object.center_of_mass(), f + ".center_of_mass");
    }
    out.push_back(std::move(attached));
  }
  return out;
}

std::vector<Shape> MovingObstacleShapesFromProto(const v1::MovingObstacle& obstacle, const std::string& field) {
  std::vector<Shape> shapes;
  ForEachPrimitive(obstacle, field, [&shapes](Shape shape, const std::string&, const std::string&, const char*, int) {
    shapes.push_back(std::move(shape));
  });
  return shapes;
}

void IkResultToProto(const IkResult& result, const IkRequest& ik, const RobotModel& robot,
                     v1::InverseKinematicsResponse* response) {
  response->set_solved(!result.solutions.empty());
  response->set_message(result.message);
  for (const std::string& name : robot.dof_names()) response->add_joint_names(name);
  for (const Eigen::VectorXd& q : result.solutions) {
    ToProto(q, response->add_solutions()->mutable_positions());
    const Jacobian J = SpaceJacobian(robot, q, ik.link);
    response->add_manipulability(Manipulability(J));
    response->add_singular(IsSingular(J));
  }
  response->set_best_position_error(result.best_position_error);
  response->set_best_orientation_error(result.best_orientation_error);
  response->set_attempts(static_cast<std::uint32_t>(std::max(0, result.attempts)));
  response->set_seconds(result.seconds);
}

PointCloudInsertion PointCloudInsertionFromProto(const v1::UpdateSceneRequest& request) {
  PointCloudInsertion insertion;
  insertion.octomap = request.octomap();
  insertion.points.assign(request.points().begin(), request.points().end());
  const v1::Vector3& origin = request.sensor_origin();
  insertion.sensor_origin = Eigen::Vector3d(origin.x(), origin.y(), origin.z());
  insertion.max_range = request.max_range();
  insertion.resolution = request.resolution();
  return insertion;
}

std::shared_ptr<const Scene> SceneFromProto(const v1::Scene& proto, const std::string& field, const InputLimits& limits) {
  // Counted before anything is built: every object costs a record in the scene, the checker
  // and the broad phase.
  const std::size_t objects = static_cast<std::size_t>(proto.boxes_size()) + proto.spheres_size() +
                              proto.cylinders_size() + proto.capsules_size() + proto.meshes_size() +
                              proto.octomaps_size();
  if (objects > limits.max_scene_objects) {
    ThrowResourceExhausted(field + " holds " + std::to_string(objects) + " objects (" +
                           std::to_string(proto.boxes_size()) + " boxes, " + std::to_string(proto.spheres_size()) +
                           " spheres, " + std::to_string(proto.cylinders_size()) + " cylinders, " +
                           std::to_string(proto.capsules_size()) + " capsules, " +
                           std::to_string(proto.meshes_size()) + " meshes, " + std::to_string(proto.octomaps_size()) +
                           " octomaps), more than the cap of " + std::to_string(limits.max_scene_objects) +
                           " (InputLimits::max_scene_objects, --max-scene-objects); merge objects into meshes or "
                           "an OctoMap, or raise the server's cap");
  }
  auto scene = std::make_shared<Scene>();
  ForEachPrimitive(proto, field,
                   [&scene](Shape shape, const std::string& f, const std::string& name, const char* kind, int i) {
                     scene->AddObject({ObjectName(name, kind, i), std::move(shape)}, f);
                   });
  CheckMeshFileCount(static_cast<std::size_t>(proto.meshes_size()), field + ".meshes", limits);
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
    if (mesh.data().empty()) ThrowInvalid(f + ".data is empty: it must hold STL, OBJ or COLLADA bytes");
    Shape shape;
    shape.type = ShapeType::kMesh;
    shape.mesh = ParseMesh(mesh.data(), scale, f + ".data", limits);
    shape.pose = PoseFromProto(mesh.pose(), f + ".pose");
    scene->AddObject({ObjectName(mesh.name(), "mesh", i), std::move(shape)}, f);
  }
  for (int i = 0; i < proto.octomaps_size(); ++i) {
    const v1::OctoMap& map = proto.octomaps(i);
    const std::string f = Indexed(field + ".octomaps", i);
    if (map.data().empty()) ThrowInvalid(f + ".data is empty: it must hold .bt or .ot OcTree bytes");
    scene->AddOctoMap(ObjectName(map.name(), "octomap", i), map.data(), PoseFromProto(map.pose(), f + ".pose"),
                      f + ".data", limits);
  }
  // Only empty names are rejected here: link1 and a link2 that names no object may be robot
  // links, which the CollisionChecker resolves against the robot the scene is used with.
  for (int i = 0; i < proto.allowed_collisions_size(); ++i) {
    const v1::LinkPair& pair = proto.allowed_collisions(i);
    scene->AllowCollision(pair.link1(), pair.link2(), Indexed(field + ".allowed_collisions", i));
  }
  return scene;
}

PoseGoalSpec PoseGoalFromProto(const v1::PoseGoal& goal, const RobotModel& robot, const std::string& field) {
  PoseGoalSpec spec;
  spec.link = LinkFromProto(robot, goal.link(), field + ".link");
  spec.pose = PoseFromProto(goal.pose(), field + ".pose");
  spec.position_tolerance =
      DefaultedInRange(goal.position_tolerance(), 1e-4, 0.0, 0.1, field + ".position_tolerance");
  spec.orientation_tolerance =
      DefaultedInRange(goal.orientation_tolerance(), 1e-3, 0.0, 0.5, field + ".orientation_tolerance");
  if (goal.max_goal_states() > 64) {
    ThrowInvalid(field + ".max_goal_states = " + std::to_string(goal.max_goal_states()) +
                 " must be at most 64 (0 = 4)");
  }
  spec.max_goal_states = goal.max_goal_states() == 0 ? 4 : static_cast<int>(goal.max_goal_states());
  const double ik_budget = goal.ik_time_budget() == 0.0 ? 0.2 : goal.ik_time_budget();
  if (!(std::isfinite(ik_budget) && ik_budget > 0.0)) {
    ThrowInvalid(field + ".ik_time_budget = " + FormatNumber(goal.ik_time_budget()) +
                 " must be finite and > 0 s (0 = 0.2 s)");
  }
  spec.ik_time_budget = ik_budget;
  return spec;
}

ParameterValues PlannerParametersFromProto(const v1::PlannerConfig& config, const PlannerSpec& spec,
                                           const std::string& field) {
  ParameterValues values;
  // Sorted, so the first error reported does not depend on hash-map order.
  std::map<std::string, const v1::ParameterValue*> parameters;
  for (const auto& entry : config.parameters()) parameters[entry.first] = &entry.second;
  for (const auto& [name, value_ptr] : parameters) {
    const v1::ParameterValue& value = *value_ptr;
    const std::string f = field + ".parameters['" + name + "']";
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
    values[name] = number;
  }
  ResolveParameters(spec, values);  // throws naming the parameter
  return values;
}

Eigen::VectorXd ConfigurationFromProto(const google::protobuf::RepeatedField<double>& values, const RobotModel& robot,
                                       const std::string& field, double bounds_tolerance,
                                       std::vector<std::string>* warnings) {
  RequireJointCount(values.size(), robot, field);
  Eigen::VectorXd q = PositionsFromProto(values, field);
  if (warnings != nullptr) ClampOntoLimits(robot, bounds_tolerance, field, &q, warnings);
  robot.ValidateConfiguration(q, field);
  return q;
}

double PaddingFromProto(double padding, const std::string& field) {
  if (!(padding >= 0.0 && padding <= 0.5)) {
    ThrowInvalid(field + " = " + FormatNumber(padding) + " must be in [0, 0.5] m");
  }
  return padding;
}

std::vector<std::string> RobotWarnings(const RobotModel& robot, const std::string& field) {
  std::vector<std::string> out;
  for (const std::string& warning : robot.load_warnings()) {
    const bool from_file = warning.rfind("urdf", 0) == 0 || warning.rfind("srdf", 0) == 0;
    out.push_back(from_file ? field + ".urdf." + warning : field + ": " + warning);
  }
  return out;
}

void ClampOntoLimits(const RobotModel& robot, double tolerance, const std::string& field, Eigen::VectorXd* q,
                     std::vector<std::string>* warnings) {
  for (int i = 0; i < q->size() && i < robot.num_dofs(); ++i) {
    double& x = (*q)[i];
    const double lo = robot.lower_limits()[i], hi = robot.upper_limits()[i];
    // A continuous joint has no limit: a value outside the range it is planned in ([-π, π]) is
    // the same angle as its equivalent inside, which is used instead.
    if (robot.joints()[robot.dof_joint(i)].type == JointType::kContinuous && std::isfinite(x) &&
        (x < lo - tolerance || x > hi + tolerance)) {
      const double wrapped = std::max(lo, std::min(hi, std::remainder(x, 2.0 * M_PI)));
      warnings->push_back(field + "[" + std::to_string(i) + "] = " + FormatNumber(x) + " on continuous joint '" +
                          robot.dof_names()[i] + "' is the angle " + FormatNumber(wrapped) +
                          " of the range it is planned in [" + FormatNumber(lo) + ", " + FormatNumber(hi) +
                          "]: wrapped");
      x = wrapped;
      continue;
    }
    const bool below = x < lo && x >= lo - tolerance;
    const bool above = x > hi && x <= hi + tolerance;
    if (!below && !above) continue;  // inside, NaN, or too far out: ValidateConfiguration decides
    const double limit = below ? lo : hi;
    char by[32];  // how far out, to 3 digits (the value and the limit are exact)
    std::snprintf(by, sizeof by, "%.3g", below ? lo - x : x - hi);
    warnings->push_back(field + "[" + std::to_string(i) + "] = " + FormatNumber(x) + " is " + by +
                        (below ? " below its lower" : " above its upper") +
                        " limit " + FormatNumber(limit) + " (joint '" + robot.dof_names()[i] +
                        "'), within bounds_tolerance " + FormatNumber(tolerance) + ": clamped onto the limit");
    x = limit;
  }
}

double BoundsToleranceFromProto(double value) {
  RequireInRange(value, 0.0, 0.01, "bounds_tolerance");
  return value == 0.0 ? kDefaultBoundsTolerance : value;
}

PlanQuery PlanQueryFromProto(const v1::PlanRequest& request, std::shared_ptr<const CollisionChecker> checker,
                             const PlannerRegistry& registry, RequestSettings* settings) {
  const RobotModel& robot = checker->robot();
  PlanQuery query;
  query.checker = std::move(checker);
  if (request.has_path_constraints()) {
    query.checker = CollisionChecker::WithPathConstraints(
        query.checker, PathConstraintsFromProto(request.path_constraints(), query.checker->robot_ptr(), "path_constraints"));
  }

  // Budget: 0 = 5 s, else (0, 600].
  double budget = request.time_budget();
  if (budget == 0.0) budget = 5.0;
  if (!(budget > 0.0 && budget <= 600.0)) {
    ThrowInvalid("time_budget = " + FormatNumber(request.time_budget()) + " must be within (0, 600] s (0 = 5 s)");
  }
  settings->time_budget = budget;

  const double bounds_tolerance = BoundsToleranceFromProto(request.bounds_tolerance());
  query.start = ConfigurationFromProto(request.start().positions(), robot, "start.positions", bounds_tolerance,
                                       &settings->warnings);
  if (request.target_case() == v1::PlanRequest::kPoseGoal) {
    query.pose_goal = PoseGoalFromProto(request.pose_goal(), robot, "pose_goal");
  } else {
    query.goal = ConfigurationFromProto(request.goal().positions(), robot, "goal.positions", bounds_tolerance,
                                        &settings->warnings);

    const double tolerance = request.goal().tolerance();
    RequireInRange(tolerance, 0.0, 0.1, "goal.tolerance");
    query.goal_tolerance = tolerance == 0.0 ? 1e-3 : tolerance;
  }
  if (request.has_gravity()) query.gravity = VectorFromProto(request.gravity(), "gravity");

  // Planner and its parameters (types checked here, ranges by ResolveParameters).
  query.planner_id = request.planner().planner_id().empty() ? "rrt_connect" : request.planner().planner_id();
  query.parameters = PlannerParametersFromProto(request.planner(), registry.Spec(query.planner_id), "planner");

  query.seed = request.seed() == 0 ? 1 : request.seed();

  const double resolution = request.collision_resolution() == 0.0 ? 0.005 : request.collision_resolution();
  RequireInRange(resolution, 1e-4, 0.1, "collision_resolution");
  query.collision_resolution = resolution;

  const v1::TrajectoryOptions& trajectory = request.trajectory();
  const double period = trajectory.sample_period() == 0.0 ? 0.01 : trajectory.sample_period();
  RequireInRange(period, 1e-4, 1.0, "trajectory.sample_period");
  query.sample_period = period;
  query.knots_replace_samples = trajectory.knots_only() && trajectory.sample_period() == 0.0;

  if (trajectory.shortcut_attempts() < -1) {
    ThrowInvalid("trajectory.shortcut_attempts = " + std::to_string(trajectory.shortcut_attempts()) +
                 " must be -1 (off), 0 (default 100) or > 0");
  }
  query.shortcut_attempts = trajectory.shortcut_attempts() == 0 ? 100 : trajectory.shortcut_attempts();
  query.shortcut_stall = trajectory.shortcut_attempts() == 0 ? 10 : 0;  // a number the client named runs in full
  // A repair after a failed verification gets min(0.5 s, time_budget) of its own (VerificationRepair).
  if (std::isfinite(request.time_budget()) && request.time_budget() > 0.0) {
    query.repair_budget = std::min(query.repair_budget, request.time_budget());
  }

  query.trajectory = TrajectorySpecFromProto(trajectory, robot, "trajectory");
  query.Validate(registry);
  return query;
}

namespace {

Eigen::VectorXd PositiveJointValues(const google::protobuf::RepeatedField<double>& values, const RobotModel& robot,
                                    const std::string& field) {
  if (values.empty()) return {};
  RequireJointCount(values.size(), robot, field);
  Eigen::VectorXd out(values.size());
  for (int i = 0; i < values.size(); ++i) {
    RequirePositive(values[i], Indexed(field, i));
    out[i] = values[i];
  }
  return out;
}

/// 0 = fallback; else within (0, 600].
double BudgetFromProto(double value, double fallback, const std::string& field) {
  if (value == 0.0) return fallback;
  if (!(std::isfinite(value) && value > 0.0 && value <= 600.0)) {
    ThrowInvalid(field + " = " + FormatNumber(value) + " must be within (0, 600] s (0 = " + FormatNumber(fallback) + " s)");
  }
  return value;
}

}  // namespace

TrajectorySpec TrajectorySpecFromProto(const v1::TrajectoryOptions& options, const RobotModel& robot,
                                       const std::string& field) {
  TrajectorySpec spec;
  if (options.max_velocity_size() > 0) {
    spec.max_velocity = PositiveJointValues(options.max_velocity(), robot, field + ".max_velocity")
                            .cwiseMin(robot.velocity_limits());
  }
  spec.max_acceleration = PositiveJointValues(options.max_acceleration(), robot, field + ".max_acceleration");
  spec.max_jerk = PositiveJointValues(options.max_jerk(), robot, field + ".max_jerk");
  spec.max_effort = PositiveJointValues(options.max_effort(), robot, field + ".max_effort");
  switch (options.post_processing()) {
    case v1::TrajectoryOptions::POST_PROCESSING_UNSPECIFIED: spec.method = PostProcessing::kAuto; break;
    case v1::TrajectoryOptions::TOPP: spec.method = PostProcessing::kTimeOptimal; break;
    case v1::TrajectoryOptions::COLLOCATION: spec.method = PostProcessing::kCollocation; break;
    case v1::TrajectoryOptions::SPLINE: spec.method = PostProcessing::kSpline; break;
    case v1::TrajectoryOptions::NONE: spec.method = PostProcessing::kNone; break;
    default:
      ThrowInvalid(field + ".post_processing = " + std::to_string(options.post_processing()) +
                   " is not one of TOPP, COLLOCATION, SPLINE, NONE");
  }
  if (options.has_max_deviation()) {
    RequireInRange(options.max_deviation(), 0.0, 1.0, field + ".max_deviation");
    spec.max_deviation = options.max_deviation();
  }
  const auto weight = [](double w, const std::string& name) {
    if (!(std::isfinite(w) && w >= 0.0)) ThrowInvalid(name + " = " + FormatNumber(w) + " must be finite and >= 0");
    return w;
  };
  const v1::CollocationOptions& c = options.collocation();
  const std::string cf = field + ".collocation";
  // Proto defaults mapped here (0 = 50 knots, 0 = 500 iterations, corridor unset = the
  // trajectory's max_deviation); the rules are CollocationOptions::Validate's.
  spec.collocation.knots = c.knots() == 0 ? 50 : c.knots();
  spec.collocation.jerk_weight = c.jerk_weight();
  if (c.has_clearance()) spec.collocation.clearance = c.clearance();
  spec.collocation.max_iterations = c.max_iterations() == 0 ? 500 : c.max_iterations();
  spec.collocation.time_budget = BudgetFromProto(c.time_budget(), 60.0, cf + ".time_budget");
  if (c.path_mode() != v1::CollocationOptions::ALONG_PATH && c.path_mode() != v1::CollocationOptions::FREE) {
    ThrowInvalid(cf + ".path_mode = " + std::to_string(c.path_mode()) + " is not one of ALONG_PATH, FREE");
  }
  spec.collocation_free = c.path_mode() == v1::CollocationOptions::FREE;
  {
    CollocationOptions checked = spec.collocation;
    if (c.has_corridor()) checked.corridor = c.corridor();
    checked.Validate(cf + ".");
  }
  if (c.has_corridor()) spec.collocation_corridor = c.corridor();

  const v1::SplineOptions& b = options.spline();
  const std::string sf = field + ".spline";
  spec.spline.degree = b.degree() == 0 ? 3 : b.degree();
  if (spec.spline.degree != 3 && spec.spline.degree != 5) {
    ThrowInvalid(sf + ".degree = " + std::to_string(b.degree()) + " must be 3 or 5 (0 = 3)");
  }
  if (b.control_points() != 0 && b.control_points() < spec.spline.degree + 1) {
    ThrowInvalid(sf + ".control_points = " + std::to_string(b.control_points()) + " must be >= degree + 1 = " +
                 std::to_string(spec.spline.degree + 1) + " (0 = chosen from the path)");
  }
  if (b.control_points() > 500) {
    ThrowInvalid(sf + ".control_points = " + std::to_string(b.control_points()) + " must be at most 500");
  }
  spec.spline.control_points = b.control_points();
  spec.spline.jerk_weight = weight(b.jerk_weight(), sf + ".jerk_weight");
  if (b.has_clearance()) spec.spline.clearance = weight(b.clearance(), sf + ".clearance");
  if (b.max_deviation() != 0.0) {
    if (!(std::isfinite(b.max_deviation()) && b.max_deviation() > 0.0)) {
      ThrowInvalid(sf + ".max_deviation = " + FormatNumber(b.max_deviation()) + " must be finite and > 0 (0 = 0.1)");
    }
    spec.spline.max_deviation = b.max_deviation();
  }
  if (!b.algorithm().empty()) {
    if (b.algorithm() != "slsqp" && b.algorithm() != "mma") {
      ThrowInvalid(sf + ".algorithm = '" + b.algorithm() + "' must be 'slsqp' or 'mma'");
    }
    spec.spline.algorithm = b.algorithm();
  }
  if (b.max_evaluations() < 0) {
    ThrowInvalid(sf + ".max_evaluations = " + std::to_string(b.max_evaluations()) + " must be >= 1 (0 = 2000)");
  }
  spec.spline.max_evaluations = b.max_evaluations() == 0 ? 2000 : b.max_evaluations();
  spec.spline.time_budget = BudgetFromProto(b.time_budget(), 5.0, sf + ".time_budget");
  return spec;
}

void QualityToProto(const TrajectoryQuality& quality, v1::TrajectoryQuality* out) {
  out->set_duration(quality.duration);
  out->set_max_velocity_ratio(quality.max_velocity_ratio);
  out->set_max_acceleration_ratio(quality.max_acceleration_ratio);
  out->set_max_jerk_ratio(quality.max_jerk_ratio);
  out->set_max_jerk(quality.max_jerk);
  out->set_max_effort_ratio(quality.max_effort_ratio);
  out->set_max_deviation(quality.max_deviation);
  out->set_min_clearance(std::isfinite(quality.min_clearance) ? quality.min_clearance
                                                              : std::numeric_limits<double>::max());
  out->set_jerk_integral(quality.jerk_integral);
  out->set_max_constraint_ratio(quality.max_constraint_ratio);
}

void OptimizerToProto(const OptimizerSummary& summary, v1::OptimizerStatistics* out) {
  out->set_requested(ToString(summary.requested));
  out->set_used(ToString(summary.used));
  out->set_fell_back(summary.fell_back);
  out->set_message(summary.message);
  out->set_solver_status(summary.report.status);
  out->set_iterations(summary.report.iterations);
  out->set_solve_seconds(summary.report.solve_seconds);
  out->set_constraint_violation(summary.report.constraint_violation);
  out->set_time_scale(summary.report.time_scale);
  out->set_blends(summary.time_optimal.blends);
  out->set_blends_tightened(summary.time_optimal.blends_tightened);
  out->set_duration_ratio_to_topp(summary.duration_ratio_to_topp);
  out->set_topp_duration(summary.topp_duration);
  // Of the returned trajectory only: a collocation result that fell back says nothing of it.
  out->set_path_deviation(summary.used == PostProcessing::kCollocation ? summary.report.path_deviation : -1.0);
}

void VerificationToProto(const VerificationReport& report, double max_joint_step, v1::Verification* out) {
  out->set_states_checked(static_cast<std::uint32_t>(std::max(0, report.states_checked)));
  out->set_max_joint_step(max_joint_step);
  out->set_max_velocity_ratio(report.max_velocity_ratio);
  out->set_max_acceleration_ratio(report.max_acceleration_ratio);
  out->set_max_jerk_ratio(report.max_jerk_ratio);
  out->set_max_effort_ratio(report.max_effort_ratio);
  out->set_collision_guarantee(report.collision_guarantee);
  out->set_collision_guarantee_reason(report.collision_guarantee_reason);
}

void SamplesToProto(const std::vector<TrajectorySample>& samples, const RobotModel& robot,
                    v1::JointTrajectory* trajectory) {
  for (const std::string& name : robot.dof_names()) trajectory->add_joint_names(name);
  for (const TrajectorySample& sample : samples) {
    v1::TrajectoryPoint* point = trajectory->add_points();
    point->set_time_from_start(sample.t);
    ToProto(sample.q, point->mutable_positions());
    ToProto(sample.qd, point->mutable_velocities());
    ToProto(sample.qdd, point->mutable_accelerations());
    if (sample.effort.size() > 0) ToProto(sample.effort, point->mutable_efforts());
  }
}

OptimizeQuery OptimizeQueryFromProto(const v1::OptimizeRequest& request, std::shared_ptr<const CollisionChecker> checker,
                                     RequestSettings* settings, double* input_duration) {
  const RobotModel& robot = checker->robot();
  OptimizeQuery query;
  query.checker = std::move(checker);
  if (request.has_path_constraints()) {
    query.checker = CollisionChecker::WithPathConstraints(
        query.checker, PathConstraintsFromProto(request.path_constraints(), query.checker->robot_ptr(), "path_constraints"));
  }
  settings->time_budget = BudgetFromProto(request.time_budget(), 10.0, "time_budget");
  *input_duration = 0.0;
  const bool has_path = request.path_size() > 0;
  const bool has_trajectory = request.trajectory().points_size() > 0;
  if (has_path == has_trajectory) {
    ThrowInvalid(has_path ? "give either path or trajectory, not both"
                          : "path and trajectory are both empty: give the path to optimise");
  }
  Eigen::VectorXd first_velocity, last_velocity;
  if (has_path) {
    for (int k = 0; k < request.path_size(); ++k) {
      const std::string f = "path[" + std::to_string(k) + "].positions";
      RequireJointCount(request.path(k).positions_size(), robot, f);
      query.path.push_back(PositionsFromProto(request.path(k).positions(), f));
    }
  } else {
    const v1::JointTrajectory& input = request.trajectory();
    double previous = -std::numeric_limits<double>::infinity();
    for (int k = 0; k < input.points_size(); ++k) {
      const v1::TrajectoryPoint& point = input.points(k);
      const std::string f = "trajectory.points[" + std::to_string(k) + "]";
      RequireJointCount(point.positions_size(), robot, f + ".positions");
      query.path.push_back(PositionsFromProto(point.positions(), f + ".positions"));
      const double t = point.time_from_start();
      if (!(std::isfinite(t) && t >= previous)) {
        ThrowInvalid(f + ".time_from_start = " + FormatNumber(t) + " must be finite and not before the previous point's");
      }
      previous = t;
    }
    *input_duration = input.points(input.points_size() - 1).time_from_start() - input.points(0).time_from_start();
    const auto velocity_of = [&](int k) -> Eigen::VectorXd {
      const v1::TrajectoryPoint& point = input.points(k);
      if (point.velocities_size() == 0) return {};
      const std::string f = "trajectory.points[" + std::to_string(k) + "].velocities";
      RequireJointCount(point.velocities_size(), robot, f);
      return PositionsFromProto(point.velocities(), f);
    };
    first_velocity = velocity_of(0);
    last_velocity = velocity_of(input.points_size() - 1);
  }
  query.trajectory = TrajectorySpecFromProto(request.options(), robot, "options");
  if (request.has_gravity()) query.trajectory.gravity = VectorFromProto(request.gravity(), "gravity");
  if (request.start_velocity_size() > 0) {
    query.trajectory.start_velocity = JointValuesFromProto(request.start_velocity(), robot, "start_velocity");
  } else if (first_velocity.size() > 0 && !first_velocity.isZero(0.0)) {
    query.trajectory.start_velocity = first_velocity;
  }
  if (request.end_velocity_size() > 0) {
    query.trajectory.end_velocity = JointValuesFromProto(request.end_velocity(), robot, "end_velocity");
  } else if (last_velocity.size() > 0 && !last_velocity.isZero(0.0)) {
    query.trajectory.end_velocity = last_velocity;
  }
  const double period = request.options().sample_period() == 0.0 ? 0.01 : request.options().sample_period();
  RequireInRange(period, 1e-4, 1.0, "options.sample_period");
  query.sample_period = period;
  query.knots_replace_samples = request.options().knots_only() && request.options().sample_period() == 0.0;
  const double resolution = request.collision_resolution() == 0.0 ? 0.005 : request.collision_resolution();
  RequireInRange(resolution, 1e-4, 0.1, "collision_resolution");
  query.collision_resolution = resolution;
  return query;
}

v1::PlanOutcome StageCodeToProto(TrajectoryStageCode code) {
  switch (code) {
    case TrajectoryStageCode::kSuccess: return v1::SUCCESS;
    case TrajectoryStageCode::kInfeasibleLimits: return v1::INFEASIBLE_LIMITS;
    case TrajectoryStageCode::kVerificationFailed: return v1::VERIFICATION_FAILED;
  }
  return v1::PLAN_OUTCOME_UNSPECIFIED;
}

static void LimitsToProto(const KinematicLimits& limits, v1::TrajectoryLimits* out) {
  ToProto(limits.max_velocity, out->mutable_max_velocity());
  ToProto(limits.max_acceleration, out->mutable_max_acceleration());
  ToProto(limits.max_jerk, out->mutable_max_jerk());
  ToProto(limits.max_effort, out->mutable_max_effort());
}

static void RepairToProto(const VerificationRepair& repair, v1::VerificationRepair* out) {
  out->set_failure(repair.failure);
  for (const std::string& action : repair.actions) out->add_actions(action);
  out->set_repaired(repair.repaired);
}

bool KnotsToProto(const TimedTrajectory& trajectory, const std::vector<std::string>& joint_names,
                  v1::TrajectoryKnots* out) {
  out->Clear();
  if (trajectory.empty() || trajectory.degree() > 2) return false;
  const int n = trajectory.num_dofs();
  for (const std::string& name : joint_names) out->add_joint_names(name);
  const auto add = [&](double t, const TrajectorySample& state) {
    out->add_times(t);
    for (int j = 0; j < n; ++j) out->add_positions(state.q[j]);
    for (int j = 0; j < n; ++j) out->add_velocities(state.qd[j]);
  };
  for (const TimedTrajectory::Piece& piece : trajectory.pieces()) {
    if (piece.duration <= 0.0) continue;
    add(piece.t0, piece.State(0.0));
  }
  add(trajectory.duration(), trajectory.Evaluate(trajectory.duration()));
  return true;
}

void OptimizeOutcomeToProto(const OptimizeOutcome& outcome, const OptimizeQuery& query, v1::OptimizeResponse* response,
                            bool knots) {
  response->set_outcome(StageCodeToProto(outcome.code));
  response->set_message(outcome.message);
  const TrajectoryStageResult& stage = outcome.stage;
  v1::StageTimings* timings = response->mutable_timings();
  timings->set_parameterize(stage.parameterize_seconds);
  timings->set_optimize(stage.optimize_seconds);
  timings->set_verify(stage.verify_seconds);
  timings->set_quality(stage.quality_seconds);
  timings->set_sample(outcome.sample_seconds);
  timings->set_repair(stage.repair.seconds);
  timings->set_total(outcome.total_seconds);
  if (stage.repair.attempted()) RepairToProto(stage.repair, response->mutable_repair());
  VerificationToProto(stage.verification, std::min(0.005, query.collision_resolution), response->mutable_verification());
  OptimizerToProto(stage.optimizer, response->mutable_optimizer());
  if (outcome.code != TrajectoryStageCode::kSuccess) return;
  QualityToProto(stage.quality, response->mutable_quality());
  LimitsToProto(stage.limits, response->mutable_limits());
  SamplesToProto(outcome.samples, query.checker->robot(), response->mutable_trajectory());
  if (knots) KnotsToProto(stage.trajectory, query.checker->robot().dof_names(), response->mutable_knots());
  response->set_duration(stage.trajectory.duration());
}

v1::PlanOutcome OutcomeToProto(PlanOutcomeCode code) {
  switch (code) {
    case PlanOutcomeCode::kSuccess: return v1::SUCCESS;
    case PlanOutcomeCode::kNoPathWithinBudget: return v1::NO_PATH_WITHIN_BUDGET;
    case PlanOutcomeCode::kStartInCollision: return v1::START_IN_COLLISION;
    case PlanOutcomeCode::kGoalInCollision: return v1::GOAL_IN_COLLISION;
    case PlanOutcomeCode::kStartViolatesConstraints: return v1::START_VIOLATES_CONSTRAINTS;
    case PlanOutcomeCode::kGoalViolatesConstraints: return v1::GOAL_VIOLATES_CONSTRAINTS;
    case PlanOutcomeCode::kGoalUnreachable: return v1::GOAL_UNREACHABLE;
    case PlanOutcomeCode::kVerificationFailed: return v1::VERIFICATION_FAILED;
    case PlanOutcomeCode::kApproximateOnly: return v1::APPROXIMATE_ONLY;
    case PlanOutcomeCode::kLocalMinimum: return v1::LOCAL_MINIMUM;
    case PlanOutcomeCode::kNoPathOnLattice: return v1::NO_PATH_ON_LATTICE;
    case PlanOutcomeCode::kInfeasibleLimits: return v1::INFEASIBLE_LIMITS;
    case PlanOutcomeCode::kCancelled:
    case PlanOutcomeCode::kDeadlineExceeded: return v1::PLAN_OUTCOME_UNSPECIFIED;
  }
  return v1::PLAN_OUTCOME_UNSPECIFIED;
}

void PlanOutcomeToProto(const PlanOutcome& outcome, const PlanQuery& query, v1::PlanResponse* response, bool knots) {
  const RobotModel& robot = query.checker->robot();
  response->set_outcome(OutcomeToProto(outcome.code));
  response->set_message(outcome.message);

  v1::StageTimings* timings = response->mutable_timings();
  timings->set_validate(outcome.seconds.validate);
  timings->set_plan(outcome.seconds.plan);
  timings->set_shortcut(outcome.seconds.shortcut);
  timings->set_parameterize(outcome.seconds.parameterize);
  timings->set_verify(outcome.seconds.verify);
  timings->set_optimize(outcome.seconds.optimize);
  timings->set_quality(outcome.seconds.quality);
  timings->set_sample(outcome.seconds.sample);
  timings->set_repair(outcome.seconds.repair);
  timings->set_total(outcome.seconds.total);
  if (outcome.repair.attempted()) RepairToProto(outcome.repair, response->mutable_repair());

  v1::PlannerStatistics* stats = response->mutable_statistics();
  stats->set_graph_states(outcome.graph_states);
  stats->set_collision_checks(outcome.state_checks);
  stats->set_raw_waypoints(static_cast<std::uint32_t>(outcome.raw_path.size()));
  stats->set_path_length(outcome.path.empty() ? 0.0 : PathLength(outcome.path));
  stats->set_suboptimality_bound(outcome.suboptimality_bound);

  VerificationToProto(outcome.verification, std::min(0.005, query.collision_resolution),
                      response->mutable_verification());
  OptimizerToProto(outcome.optimizer, response->mutable_optimizer());

  if (outcome.code != PlanOutcomeCode::kSuccess) return;  // nothing unverified leaves the server
  for (const Eigen::VectorXd& q : outcome.path) ToProto(q, response->add_path()->mutable_positions());
  SamplesToProto(outcome.samples, robot, response->mutable_trajectory());
  if (knots) KnotsToProto(outcome.trajectory, robot.dof_names(), response->mutable_knots());
  QualityToProto(outcome.quality, response->mutable_quality());
  LimitsToProto(outcome.limits, response->mutable_limits());
  response->set_duration(outcome.trajectory.duration());
  if (query.pose_goal && outcome.goal.size() > 0) {
    ToProto(outcome.goal, response->mutable_reached_goal()->mutable_positions());
    response->set_goal_manipulability(outcome.goal_manipulability);
  }
}

void PlannerSpecToProto(const PlannerSpec& spec, v1::PlannerDescription* description) {
  description->set_id(spec.id);
  description->set_description(spec.description);
  description->set_optimizing(spec.optimizing);
  for (RobotKind kind : spec.robot_kinds) description->add_robot_kinds(ToString(kind));
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
    out->set_per_joint(param.per_joint);
  }
}

}  // namespace chasles
