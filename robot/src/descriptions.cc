#include "chasles/robot/descriptions.h"

#include <cmath>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "chasles/robot/error.h"
#include "chasles/robot/lie_group.h"
#include "inertia_check.h"

// Both front ends translate a description into RobotModel::FromTree links and joints. A Joint
// turns its child frame about (or slides it along) `axis` through the child frame's origin,
// so each internal link frame is placed on its joint axis; geometry and inertia given in the
// description's frame are re-expressed in that internal frame.
//
// DH, standard: T_i = Rz(θ_off + q) Tz(d) Tx(a) Rx(α) = [Rz(θ_off) Tz(d)] · Rz(q) · [Tx(a) Rx(α)]
//   (Rz(q) commutes with Rz(θ_off) Tz(d)). Internal link i = DH frame i−1 · Rz(θ_off) Tz(d) · Rz(q),
//   i.e. DH frame i = link i · Tx(a_i) Rx(α_i). Joint i origin = Tx(a_{i−1}) Rx(α_{i−1}) Rz(θ_off,i)
//   Tz(d_i) (the first one prefixed by `base`); prismatic joints slide Tz(q) at the same place.
// DH, modified: T_i = Rx(α) Tx(a) Rz(θ_off) Tz(d) · Rz(q): internal link i = DH frame i exactly.
// PoE: link i at the foot of the perpendicular from link_home's origin to the screw axis (revolute)
//   or at link_home (prismatic), with link_home's orientation; the tool link at M.

namespace chasles {
namespace {

constexpr double kSe3Tolerance = 1e-6;    // orthonormality of rotation parts
constexpr double kScrewTolerance = 1e-6;  // |ω| = 1, ω·v = 0, |v| = 1

std::string Num(double x) { return FormatNumber(x); }

std::string Vec(const Eigen::VectorXd& v) {
  std::string s = "(";
  for (int i = 0; i < v.size(); ++i) s += (i ? " " : "") + Num(v[i]);
  return s + ")";
}

Eigen::Isometry3d RotX(double angle) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  const double c = std::cos(angle), s = std::sin(angle);
  t.linear() << 1, 0, 0, 0, c, -s, 0, s, c;
  return t;
}

Eigen::Isometry3d RotZ(double angle) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  const double c = std::cos(angle), s = std::sin(angle);
  t.linear() << c, -s, 0, s, c, 0, 0, 0, 1;
  return t;
}

Eigen::Isometry3d Trans(double x, double y, double z) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(x, y, z);
  return t;
}

void CheckFinite(double value, const std::string& field) {
  if (!std::isfinite(value)) ThrowInvalid(field + " = " + Num(value) + " must be finite");
}

void CheckNonNegative(double value, const std::string& field) {
  if (!(value >= 0.0) || !std::isfinite(value)) {
    ThrowInvalid(field + " = " + Num(value) + " must be >= 0 and finite");
  }
}

void CheckPositive(double value, const std::string& field) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    ThrowInvalid(field + " = " + Num(value) + " must be > 0 and finite");
  }
}

/// Checks that `t` is a rigid transform and returns it with an exactly orthonormal rotation
/// (inputs within the tolerance are projected; exact inputs are returned unchanged).
Eigen::Isometry3d CheckSe3(const Eigen::Isometry3d& t, const std::string& field) {
  const Eigen::Matrix4d& m = t.matrix();
  if (!m.allFinite()) ThrowInvalid(field + " is not in SE(3): it has non-finite entries");
  if (m.row(3) != Eigen::RowVector4d(0, 0, 0, 1)) {
    ThrowInvalid(field + " is not in SE(3): bottom row is " + Vec(m.row(3).transpose()) +
                 ", must be (0 0 0 1)");
  }
  const Eigen::Matrix3d r = t.linear();
  const double error = (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (error > kSe3Tolerance) {
    ThrowInvalid(field + " is not in SE(3): rotation part is not orthonormal (max |RᵀR − I| = " +
                 Num(error) + " > 1e-6)");
  }
  const double det = r.determinant();
  if (det < 0.0) {
    ThrowInvalid(field + " is not in SE(3): rotation part has det = " + Num(det));
  }
  Eigen::Isometry3d out = t;
  if (error > 1e-14) out.linear() = Eigen::Quaterniond(r).normalized().toRotationMatrix();
  return out;
}

std::string TypeName(JointType type) {
  switch (type) {
    case JointType::kRevolute: return "revolute";
    case JointType::kContinuous: return "continuous";
    case JointType::kPrismatic: return "prismatic";
    case JointType::kFixed: return "fixed";
  }
  return "unknown";
}

void CheckJointCommon(JointType type, const JointLimits& lim, double damping, double friction,
                      double armature, const std::string& field) {
  if (type != JointType::kRevolute && type != JointType::kContinuous &&
      type != JointType::kPrismatic) {
    ThrowInvalid(field + ".type = " + TypeName(type) +
                 " must be revolute, continuous or prismatic");
  }
  const std::string lf = field + ".limits";
  if (type != JointType::kContinuous) {
    if (!std::isfinite(lim.lower)) ThrowInvalid(lf + " lower = " + Num(lim.lower) + " must be finite");
    if (!std::isfinite(lim.upper)) ThrowInvalid(lf + " upper = " + Num(lim.upper) + " must be finite");
    if (lim.lower > lim.upper) {
      ThrowInvalid(lf + " lower = " + Num(lim.lower) + " > upper = " + Num(lim.upper));
    }
  }
  if (!(lim.velocity > 0.0) || !std::isfinite(lim.velocity)) {
    ThrowInvalid(lf + " velocity = " + Num(lim.velocity) + " must be > 0 and finite");
  }
  if (!(lim.effort >= 0.0) || !std::isfinite(lim.effort)) {
    ThrowInvalid(lf + " effort = " + Num(lim.effort) + " must be >= 0 and finite");
  }
  CheckNonNegative(damping, field + ".damping");
  CheckNonNegative(friction, field + ".friction");
  CheckNonNegative(armature, field + ".armature");
}

/// Validates `props` (given in frame F) and builds a link whose frame is L, with
/// `link_from_given` = T_LF.
Link MakeLink(const std::string& name, const LinkProperties& props,
              const Eigen::Isometry3d& link_from_given, const std::string& field) {
  Link link;
  link.name = name;
  for (size_t k = 0; k < props.collision.size(); ++k) {
    const Shape& shape = props.collision[k];
    const std::string sf = field + ".collision[" + std::to_string(k) + "]";
    switch (shape.type) {
      case ShapeType::kSphere:
        CheckPositive(shape.radius, sf + " radius");
        break;
      case ShapeType::kBox:
        for (int a = 0; a < 3; ++a) CheckPositive(shape.size[a], sf + " size[" + std::to_string(a) + "]");
        break;
      case ShapeType::kCylinder:
      case ShapeType::kCapsule:
        CheckPositive(shape.radius, sf + " radius");
        CheckPositive(shape.length, sf + " length");
        break;
      case ShapeType::kMesh:
        if (!shape.mesh) ThrowInvalid(sf + " is a mesh shape without a mesh");
        break;
    }
    Shape moved = shape;
    moved.pose = link_from_given * CheckSe3(shape.pose, sf + ".pose");
    link.collision.push_back(std::move(moved));
  }
  if (props.inertial) {
    const Inertial& in = *props.inertial;
    const std::string inf = field + ".inertial";
    CheckNonNegative(in.mass, inf + " mass");
    if (!in.com.allFinite()) ThrowInvalid(inf + " com = " + Vec(in.com) + " must be finite");
    if (!in.inertia.allFinite()) ThrowInvalid(inf + " inertia must be finite");
    const double asym = (in.inertia - in.inertia.transpose()).cwiseAbs().maxCoeff();
    if (asym > 1e-9 * std::max(1.0, in.inertia.cwiseAbs().maxCoeff())) {
      ThrowInvalid(inf + " inertia must be symmetric (max |I − Iᵀ| = " + Num(asym) + ")");
    }
    const Eigen::Matrix3d& i3 = in.inertia;
    robot_internal::CheckInertiaPositiveSemidefinite(
        0.5 * (i3 + i3.transpose()), inf + " inertia",
        "(ixx " + Num(i3(0, 0)) + ", iyy " + Num(i3(1, 1)) + ", izz " + Num(i3(2, 2)) + ", ixy " + Num(i3(0, 1)) +
            ", ixz " + Num(i3(0, 2)) + ", iyz " + Num(i3(1, 2)) + ")");
    Inertial out;
    out.mass = in.mass;
    const Eigen::Matrix3d r = link_from_given.linear();
    out.com = link_from_given * in.com;
    out.inertia = r * in.inertia * r.transpose();
    link.inertial = out;
  }
  return link;
}

Joint MakeJoint(const std::string& name, JointType type, int parent, int child,
                const Eigen::Isometry3d& origin, const Eigen::Vector3d& axis,
                const JointLimits& limits, double damping, double friction, double armature) {
  Joint joint;
  joint.name = name;
  joint.type = type;
  joint.parent_link = parent;
  joint.child_link = child;
  joint.origin = origin;
  joint.axis = axis;
  joint.limits = limits;
  joint.damping = damping;
  joint.friction = friction;
  joint.armature = armature;
  return joint;
}

/// Joint names: the given ones or "joint<i+1>", unique, and not the reserved "tool_joint".
std::vector<std::string> JointNames(const std::vector<std::string>& given, const std::string& field) {
  std::vector<std::string> names;
  for (size_t i = 0; i < given.size(); ++i) {
    names.push_back(given[i].empty() ? "joint" + std::to_string(i + 1) : given[i]);
    const std::string& name = names.back();
    const std::string nf = field + "[" + std::to_string(i) + "].name";
    if (name == "tool_joint") {
      ThrowInvalid(nf + " = 'tool_joint' is reserved for the fixed joint of the tool link");
    }
    for (size_t k = 0; k < i; ++k) {
      if (names[k] == name) {
        ThrowInvalid(nf + " = '" + name + "' is used by " + field + "[" + std::to_string(k) +
                     "] too; joint names must be unique");
      }
    }
  }
  return names;
}

void CheckAllowedPairs(const std::vector<std::pair<std::string, std::string>>& pairs,
                       const std::vector<Link>& links, const std::string& field) {
  std::set<std::string> names;
  for (const Link& link : links) names.insert(link.name);
  for (size_t i = 0; i < pairs.size(); ++i) {
    for (const auto& [which, name] : {std::pair<const char*, const std::string&>{"first", pairs[i].first},
                                      std::pair<const char*, const std::string&>{"second", pairs[i].second}}) {
      if (names.count(name) == 0) {
        ThrowInvalid(field + "[" + std::to_string(i) + "]." + which + " = '" + name +
                     "' is not a link (links are base_link, link1 … link" +
                     std::to_string(links.size() - 2) + ", tool)");
      }
    }
  }
}

/// A DH table or PoE list of n joints makes n degrees of freedom and n + 2 links.
void CheckSize(std::size_t joints, const InputLimits& limits, const std::string& field) {
  if (joints > static_cast<std::size_t>(limits.max_dofs)) {
    ThrowResourceExhausted(field + " has " + std::to_string(joints) + " joints, more than the cap of " +
                           std::to_string(limits.max_dofs) +
                           " degrees of freedom (InputLimits::max_dofs); send a smaller robot or raise the server's cap");
  }
  if (joints + 2 > static_cast<std::size_t>(limits.max_links)) {
    ThrowResourceExhausted(field + " has " + std::to_string(joints) + " joints, so " + std::to_string(joints + 2) +
                           " links, more than the cap of " + std::to_string(limits.max_links) +
                           " (InputLimits::max_links); send a smaller robot or raise the server's cap");
  }
}

}  // namespace

std::shared_ptr<const RobotModel> RobotFromDh(const DhDescription& dh, const InputLimits& limits) {
  const bool standard = dh.convention == DhConvention::kStandard;
  if (dh.convention != DhConvention::kStandard && dh.convention != DhConvention::kModified) {
    ThrowInvalid("dh.convention = " + std::to_string(static_cast<int>(dh.convention)) +
                 " must be standard or modified");
  }
  if (dh.joints.empty()) ThrowInvalid("dh.joints is empty; a DH table needs at least one joint");
  CheckSize(dh.joints.size(), limits, "dh.joints");
  const Eigen::Isometry3d base = CheckSe3(dh.base, "dh.base");
  const Eigen::Isometry3d tool = CheckSe3(dh.tool, "dh.tool");
  std::vector<std::string> given;
  for (const DhJoint& j : dh.joints) given.push_back(j.name);
  const std::vector<std::string> names = JointNames(given, "dh.joints");

  std::vector<Link> links;
  std::vector<Joint> joints;
  links.push_back(MakeLink("base_link", dh.base_link, Eigen::Isometry3d::Identity(), "dh.base_link"));
  // prev_distal: the part of the previous row that follows its joint motion (standard only).
  Eigen::Isometry3d prev_distal = base;
  for (size_t i = 0; i < dh.joints.size(); ++i) {
    const DhJoint& j = dh.joints[i];
    const std::string field = "dh.joints[" + std::to_string(i) + "]";
    CheckFinite(j.a, field + ".a");
    CheckFinite(j.alpha, field + ".alpha");
    CheckFinite(j.d, field + ".d");
    CheckFinite(j.theta_offset, field + ".theta_offset");
    CheckJointCommon(j.type, j.limits, j.damping, j.friction, j.armature, field);

    Eigen::Isometry3d origin;
    Eigen::Isometry3d link_from_dh = Eigen::Isometry3d::Identity();
    if (standard) {
      origin = prev_distal * RotZ(j.theta_offset) * Trans(0, 0, j.d);
      link_from_dh = Trans(j.a, 0, 0) * RotX(j.alpha);
      prev_distal = link_from_dh;
    } else {
      origin = (i == 0 ? base : Eigen::Isometry3d::Identity()) * RotX(j.alpha) * Trans(j.a, 0, 0) *
               RotZ(j.theta_offset) * Trans(0, 0, j.d);
    }
    const int child = static_cast<int>(links.size());
    links.push_back(MakeLink("link" + std::to_string(i + 1), j.link, link_from_dh, field + ".link"));
    joints.push_back(MakeJoint(names[i], j.type, child - 1, child, origin, Eigen::Vector3d::UnitZ(),
                               j.limits, j.damping, j.friction, j.armature));
  }
  const int last = static_cast<int>(links.size()) - 1;
  links.push_back(MakeLink("tool", {}, Eigen::Isometry3d::Identity(), "dh.tool"));
  joints.push_back(MakeJoint("tool_joint", JointType::kFixed, last, last + 1,
                             (standard ? prev_distal : Eigen::Isometry3d::Identity()) * tool,
                             Eigen::Vector3d::UnitZ(), JointLimits{}, 0.0, 0.0, 0.0));
  CheckAllowedPairs(dh.allowed_collisions, links, "dh.allowed_collisions");
  return RobotModel::FromTree(dh.name.empty() ? "dh_robot" : dh.name, std::move(links),
                              std::move(joints), dh.allowed_collisions);
}

std::shared_ptr<const RobotModel> RobotFromPoe(const PoeDescription& poe, const InputLimits& limits) {
  if (poe.joints.empty()) ThrowInvalid("poe.joints is empty; a PoE description needs at least one joint");
  CheckSize(poe.joints.size(), limits, "poe.joints");
  const Eigen::Isometry3d home = CheckSe3(poe.home, "poe.home");
  std::vector<std::string> given;
  for (const PoeJoint& j : poe.joints) given.push_back(j.name);
  const std::vector<std::string> names = JointNames(given, "poe.joints");
  const Matrix6d ad_home = Adjoint(home);

  std::vector<Link> links;
  std::vector<Joint> joints;
  links.push_back(MakeLink("base_link", poe.base_link, Eigen::Isometry3d::Identity(), "poe.base_link"));
  Eigen::Isometry3d prev_frame = Eigen::Isometry3d::Identity();  // home pose of the parent link
  for (size_t i = 0; i < poe.joints.size(); ++i) {
    const PoeJoint& j = poe.joints[i];
    const std::string field = "poe.joints[" + std::to_string(i) + "]";
    CheckJointCommon(j.type, j.limits, j.damping, j.friction, j.armature, field);
    if (!j.screw.allFinite()) ThrowInvalid(field + ".screw = " + Vec(j.screw) + " must be finite");
    const Eigen::Vector3d w = j.screw.head<3>();
    const Eigen::Vector3d v = j.screw.tail<3>();
    const std::string sf = field + ".screw: ";
    const bool prismatic = j.type == JointType::kPrismatic;
    if (prismatic) {
      if (w.norm() > kScrewTolerance) {
        ThrowInvalid(sf + "|ω| = " + Num(w.norm()) + " must be 0 for a prismatic joint");
      }
      if (std::abs(v.norm() - 1.0) > kScrewTolerance) {
        ThrowInvalid(sf + "ω = 0 and |v| = " + Num(v.norm()) + " must be 1 for a prismatic joint");
      }
    } else {
      if (std::abs(w.norm() - 1.0) > kScrewTolerance) {
        ThrowInvalid(sf + "|ω| = " + Num(w.norm()) + " must be 1 for a " + TypeName(j.type) + " joint");
      }
      const double pitch = w.dot(v);
      if (std::abs(pitch) > kScrewTolerance) {
        ThrowInvalid(sf + "ω·v = " + Num(pitch) + " must be 0 for a " + TypeName(j.type) +
                     " joint (a pure rotation; screws with nonzero pitch are not supported)");
      }
    }
    // Space screw axis at home.
    const Vector6d s = poe.body_frame ? Vector6d(ad_home * j.screw) : j.screw;
    Eigen::Isometry3d given_frame = Eigen::Isometry3d::Identity();
    if (j.link_home) given_frame = CheckSe3(*j.link_home, field + ".link_home");

    Eigen::Isometry3d frame = given_frame;  // internal link frame at home, on the joint axis
    Eigen::Vector3d axis_space;
    if (prismatic) {
      axis_space = s.tail<3>().normalized();
    } else {
      const double n = s.head<3>().norm();
      axis_space = s.head<3>() / n;
      const Eigen::Vector3d point = axis_space.cross(Eigen::Vector3d(s.tail<3>() / n));  // nearest the origin
      const Eigen::Vector3d h = given_frame.translation();
      frame.translation() = point + axis_space * axis_space.dot(h - point);
    }
    // Without link_home the link is described in the default frame itself.
    if (!j.link_home) given_frame = frame;
    const Eigen::Vector3d axis_local = frame.linear().transpose() * axis_space;
    const Eigen::Isometry3d origin = prev_frame.inverse() * frame;
    const int child = static_cast<int>(links.size());
    links.push_back(MakeLink("link" + std::to_string(i + 1), j.link, frame.inverse() * given_frame,
                             field + ".link"));
    joints.push_back(MakeJoint(names[i], j.type, child - 1, child, origin, axis_local, j.limits,
                               j.damping, j.friction, j.armature));
    prev_frame = frame;
  }
  const int last = static_cast<int>(links.size()) - 1;
  links.push_back(MakeLink("tool", {}, Eigen::Isometry3d::Identity(), "poe.tool"));
  joints.push_back(MakeJoint("tool_joint", JointType::kFixed, last, last + 1,
                             prev_frame.inverse() * home, Eigen::Vector3d::UnitZ(), JointLimits{},
                             0.0, 0.0, 0.0));
  CheckAllowedPairs(poe.allowed_collisions, links, "poe.allowed_collisions");
  return RobotModel::FromTree(poe.name.empty() ? "poe_robot" : poe.name, std::move(links),
                              std::move(joints), poe.allowed_collisions);
}

}  // namespace chasles
