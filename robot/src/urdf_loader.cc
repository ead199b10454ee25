// RobotModel::FromUrdf: URDF via urdfdom, SRDF via tinyxml.

#include <cmath>
#include <cstdlib>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include <console_bridge/console.h>
#include <tinyxml.h>
#include <urdf_parser/urdf_parser.h>

#include "chasles/robot/error.h"
#include "chasles/robot/robot_model.h"
#include "format.h"
#include "inertia_check.h"
#include "xml_scan.h"

namespace chasles {
namespace {

using robot_internal::FormatNumber;
using chasles::FormatNumber;

/// Collects the error messages urdfdom reports through console_bridge while it parses.
class ErrorCollector : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) errors.push_back(text);
  }
  std::vector<std::string> errors;
};

/// Parses `text` with tinyxml; on failure throws with the row, column and tinyxml's reason.
void ParseXmlOrThrow(const std::string& text, const char* what, TiXmlDocument* doc) {
  if (text.find_first_not_of(" \t\r\n") == std::string::npos) {
    ThrowInvalid(std::string(what) + ": document is empty");
  }
  doc->Parse(text.c_str(), nullptr, TIXML_ENCODING_UTF8);
  if (doc->Error()) {
    ThrowInvalid(std::string(what) + ": malformed XML at line " + std::to_string(doc->ErrorRow()) +
                 ", column " + std::to_string(doc->ErrorCol()) + ": " + doc->ErrorDesc());
  }
}

Eigen::Isometry3d ToIsometry(const urdf::Pose& pose) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(pose.position.x, pose.position.y, pose.position.z);
  Eigen::Quaterniond quat(pose.rotation.w, pose.rotation.x, pose.rotation.y, pose.rotation.z);
  if (quat.norm() > 0.0) t.linear() = quat.normalized().toRotationMatrix();
  return t;
}

Eigen::Vector3d ToVector(const urdf::Vector3& v) { return Eigen::Vector3d(v.x, v.y, v.z); }

void CheckPositive(double value, const std::string& what) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    ThrowInvalid(what + " = " + FormatNumber(value) + " must be > 0 and finite");
  }
}

/// A mesh the resolver does not have is recorded in *missing (all are reported together) and
/// its shape is left without a mesh.
Shape ConvertGeometry(const urdf::Collision& collision, const std::string& where, const RobotModel::MeshResolver& meshes,
                      std::vector<std::string>* missing) {
  const Eigen::Isometry3d pose = ToIsometry(collision.origin);
  if (!pose.matrix().allFinite()) ThrowInvalid(where + " origin must be finite");
  if (!collision.geometry) ThrowInvalid(where + " has no geometry");
  switch (collision.geometry->type) {
    case urdf::Geometry::SPHERE: {
      const auto& g = static_cast<const urdf::Sphere&>(*collision.geometry);
      CheckPositive(g.radius, where + " sphere radius");
      return Shape::Sphere(g.radius, pose);
    }
    case urdf::Geometry::BOX: {
      const auto& g = static_cast<const urdf::Box&>(*collision.geometry);
      CheckPositive(g.dim.x, where + " box size x");
      CheckPositive(g.dim.y, where + " box size y");
      CheckPositive(g.dim.z, where + " box size z");
      return Shape::Box(ToVector(g.dim), pose);
    }
    case urdf::Geometry::CYLINDER: {
      const auto& g = static_cast<const urdf::Cylinder&>(*collision.geometry);
      CheckPositive(g.radius, where + " cylinder radius");
      CheckPositive(g.length, where + " cylinder length");
      return Shape::Cylinder(g.radius, g.length, pose);
    }
    case urdf::Geometry::MESH: {
      const auto& g = static_cast<const urdf::Mesh&>(*collision.geometry);
      const std::shared_ptr<const TriangleMesh> mesh = meshes ? meshes(g.filename) : nullptr;
      if (!mesh) {
        missing->push_back(where.substr(where.find("link")) + " mesh filename '" + g.filename + "'");
        return Shape{};
      }
      const Eigen::Vector3d scale = ToVector(g.scale);
      CheckPositive(scale.x(), where + " mesh scale x");
      CheckPositive(scale.y(), where + " mesh scale y");
      CheckPositive(scale.z(), where + " mesh scale z");
      Shape shape;
      shape.type = ShapeType::kMesh;
      shape.pose = pose;
      if (scale == Eigen::Vector3d::Ones()) {
        shape.mesh = mesh;
      } else {
        auto scaled = std::make_shared<TriangleMesh>(*mesh);
        for (Eigen::Vector3d& v : scaled->vertices) v = v.cwiseProduct(scale);
        shape.mesh = std::move(scaled);
      }
      return shape;
    }
  }
  ThrowInvalid(where + " has an unknown geometry type");
}

/// urdfdom reads numbers with a stream that fails on "nan" and "inf" (and on overflow such as
/// "1e400"), logs an error and keeps 0, so `<mass value="nan"/>` would load as a massless link.
/// The mass and inertia attributes are read here first, as strtod reads them, and refused with
/// the link, the attribute and the value when they are not finite.
void CheckInertialNumbers(const TiXmlElement& robot) {
  for (const TiXmlElement* link = robot.FirstChildElement("link"); link != nullptr;
       link = link->NextSiblingElement("link")) {
    const TiXmlElement* inertial = link->FirstChildElement("inertial");
    if (inertial == nullptr) continue;
    const char* name = link->Attribute("name");
    const std::string where = std::string("urdf: link '") + (name ? name : "") + "' inertial";
    const auto check = [&where](const TiXmlElement* element, const char* attribute, const std::string& what,
                                const char* rule) {
      const char* text = element == nullptr ? nullptr : element->Attribute(attribute);
      if (text == nullptr) return;
      char* end = nullptr;
      const double value = std::strtod(text, &end);
      if (end == text) return;  // not a number at all: urdfdom names it
      while (*end == ' ' || *end == '\t' || *end == '\n' || *end == '\r') ++end;
      if (*end != '\0') return;
      if (!std::isfinite(value)) ThrowInvalid(where + " " + what + " = " + FormatNumber(value) + rule);
    };
    check(inertial->FirstChildElement("mass"), "value", "mass", " must be >= 0 and finite");
    const TiXmlElement* inertia = inertial->FirstChildElement("inertia");
    for (const char* component : {"ixx", "ixy", "ixz", "iyy", "iyz", "izz"}) {
      check(inertia, component, std::string("inertia ") + component, " must be finite");
    }
  }
}

/// urdfdom cannot read "nan", "inf" or "1e400" in <mimic multiplier= offset=> and says so
/// without naming the joint; they are read here first, as strtod reads them, and refused with
/// the joint, the attribute and the value. A multiplier of 0 is refused too: such a joint never
/// moves (it is a fixed joint at the offset).
void CheckMimicNumbers(const TiXmlElement& robot) {
  for (const TiXmlElement* joint = robot.FirstChildElement("joint"); joint != nullptr;
       joint = joint->NextSiblingElement("joint")) {
    const TiXmlElement* mimic = joint->FirstChildElement("mimic");
    if (mimic == nullptr) continue;
    const char* name = joint->Attribute("name");
    const std::string where = std::string("urdf: joint '") + (name ? name : "") + "' mimic";
    for (const char* attribute : {"multiplier", "offset"}) {
      const char* text = mimic->Attribute(attribute);
      if (text == nullptr) continue;  // defaults: multiplier 1, offset 0
      char* end = nullptr;
      const double value = std::strtod(text, &end);
      if (end == text) continue;  // not a number at all: urdfdom names it
      while (*end == ' ' || *end == '\t' || *end == '\n' || *end == '\r') ++end;
      if (*end != '\0') continue;
      const bool multiplier = std::string(attribute) == "multiplier";
      if (multiplier && (!std::isfinite(value) || value == 0.0)) {
        ThrowInvalid(where + " multiplier = " + FormatNumber(value) +
                     " must be finite and non-zero (a joint that never moves is a fixed joint)");
      }
      if (!multiplier && !std::isfinite(value)) {
        ThrowInvalid(where + " offset = " + FormatNumber(value) + " must be finite");
      }
    }
  }
}

/// urdfdom joins a joint's parent and child links with owning pointers before it checks that
/// the links form a tree, so a joint whose child is its own parent, or joints that form a
/// cycle, leak the whole parsed model on every request (found by fuzzing). The joint graph is
/// checked here first, in linear time.
void CheckJointGraph(const TiXmlElement& robot) {
  struct Edge {
    std::string parent, joint;
  };
  std::unordered_map<std::string, Edge> parent_of;  // child link -> its parent link and joint
  std::vector<std::string> children;                // in document order, for deterministic messages
  for (const TiXmlElement* e = robot.FirstChildElement("joint"); e != nullptr; e = e->NextSiblingElement("joint")) {
    const TiXmlElement* parent = e->FirstChildElement("parent");
    const TiXmlElement* child = e->FirstChildElement("child");
    const char* name = e->Attribute("name");
    const char* parent_link = parent ? parent->Attribute("link") : nullptr;
    const char* child_link = child ? child->Attribute("link") : nullptr;
    if (name == nullptr || parent_link == nullptr || child_link == nullptr) continue;  // urdfdom names it
    const std::string where = std::string("urdf: joint '") + name + "'";
    if (std::string(parent_link) == child_link) {
      ThrowInvalid(where + " parent = child = '" + child_link + "'; a joint joins two different links");
    }
    const auto [it, added] = parent_of.emplace(child_link, Edge{parent_link, name});
    if (!added) {
      ThrowInvalid(where + " child = '" + child_link + "' is already the child of joint '" + it->second.joint +
                   "'; a link has at most one parent joint");
    }
    children.push_back(child_link);
  }
  // Walk up from every link; meeting the current walk again is a cycle.
  std::unordered_map<std::string, int> state;  // 1: on the current walk, 2: leads to a root
  for (const std::string& start : children) {
    std::vector<const std::string*> walk;
    const std::string* link = &start;
    while (true) {
      int& s = state[*link];
      if (s == 2) break;
      if (s == 1) {
        ThrowInvalid("urdf: joint '" + parent_of.at(*link).joint + "' closes a cycle of joints through link '" +
                     *link + "'; the links must form a tree");
      }
      s = 1;
      walk.push_back(link);
      const auto up = parent_of.find(*link);
      if (up == parent_of.end()) break;
      link = &up->second.parent;
    }
    for (const std::string* l : walk) state[*l] = 2;
  }
}

}  // namespace

std::shared_ptr<const RobotModel> RobotModel::FromUrdf(
    std::string_view urdf_text, std::string_view srdf_text,
    const std::map<std::string, std::shared_ptr<const TriangleMesh>>& meshes, const InputLimits& limits,
    bool strict_srdf) {
  return FromUrdfResolvingMeshes(
      urdf_text, srdf_text,
      [&meshes](const std::string& filename) -> std::shared_ptr<const TriangleMesh> {
        const auto it = meshes.find(filename);
        return it == meshes.end() ? nullptr : it->second;
      },
      limits, strict_srdf);
}

std::shared_ptr<const RobotModel> RobotModel::FromUrdfResolvingMeshes(std::string_view urdf_text,
                                                                      std::string_view srdf_text,
                                                                      const MeshResolver& meshes,
                                                                      const InputLimits& limits, bool strict_srdf) {
  // 0. Sizes first, before any parser (tinyxml recurses once per nesting level): document
  //    bytes, element nesting, and the links, joints and moving joints the document declares.
  const robot_internal::XmlScan scan =
      robot_internal::CheckXmlText(urdf_text, "urdf", limits.max_document_bytes, limits.max_xml_depth);
  if (scan.links > static_cast<std::size_t>(limits.max_links)) {
    ThrowResourceExhausted("urdf declares " + std::to_string(scan.links) + " links, more than the cap of " +
                           std::to_string(limits.max_links) + " (InputLimits::max_links); send a smaller robot or raise the server's cap");
  }
  if (scan.joints > static_cast<std::size_t>(limits.max_links)) {
    ThrowResourceExhausted("urdf declares " + std::to_string(scan.joints) + " joints, more than the cap of " +
                           std::to_string(limits.max_links) + " (InputLimits::max_links bounds joints too); send a smaller robot or raise the server's cap");
  }
  if (scan.moving_joints > static_cast<std::size_t>(limits.max_dofs)) {
    ThrowResourceExhausted("urdf declares " + std::to_string(scan.moving_joints) +
                           " joints that are not fixed, more than the cap of " + std::to_string(limits.max_dofs) +
                           " degrees of freedom (InputLimits::max_dofs); send a smaller robot or raise the server's cap");
  }
  if (!srdf_text.empty()) {
    robot_internal::CheckXmlText(srdf_text, "srdf", limits.max_document_bytes, limits.max_xml_depth);
  }
  const std::string urdf_string(urdf_text);

  // 1. Well-formed XML? tinyxml tells where it is not.
  TiXmlDocument urdf_doc;
  ParseXmlOrThrow(urdf_string, "urdf", &urdf_doc);

  if (urdf_doc.RootElement() != nullptr) {
    CheckInertialNumbers(*urdf_doc.RootElement());
    CheckMimicNumbers(*urdf_doc.RootElement());
    CheckJointGraph(*urdf_doc.RootElement());
  }

  // 2. urdfdom builds the model; its own complaints go through console_bridge (a process-global
  //    handler, hence the lock).
  urdf::ModelInterfaceSharedPtr model;
  {
    static std::mutex console_mutex;
    std::lock_guard<std::mutex> lock(console_mutex);
    ErrorCollector collector;
    console_bridge::useOutputHandler(&collector);
    try {
      model = urdf::parseURDF(urdf_string);
    } catch (const std::exception& e) {
      collector.errors.push_back(e.what());
      model.reset();
    }
    console_bridge::restorePreviousOutputHandler();
    // urdfdom may log an error and still return a model with a default in place of what it
    // could not read: an error either way.
    if (!model || !collector.errors.empty()) {
      ThrowInvalid("urdf: " + (collector.errors.empty() ? std::string("urdfdom could not parse the model")
                                                        : collector.errors.front()));
    }
  }
  const std::string robot_name = model->getName();
  if (!model->getRoot()) ThrowInvalid("urdf: robot '" + robot_name + "' has no root link");

  // 3. Children of each link in document order (urdfdom keeps joints in a name-sorted map).
  std::unordered_map<std::string, std::vector<urdf::JointConstSharedPtr>> child_joints;
  const TiXmlElement* robot_element = urdf_doc.RootElement();
  for (const TiXmlElement* e = robot_element->FirstChildElement("joint"); e != nullptr;
       e = e->NextSiblingElement("joint")) {
    const char* name = e->Attribute("name");
    if (name == nullptr) continue;
    urdf::JointConstSharedPtr joint = model->getJoint(name);
    if (joint) child_joints[joint->parent_link_name].push_back(joint);
  }

  // 4. Depth-first traversal from the root: link i + 1 is the child of joint i.
  std::vector<Link> links;
  std::vector<Joint> joints;
  std::unordered_map<std::string, int> link_index;

  std::vector<std::string> missing_meshes;  // every collision mesh not supplied, reported together
  auto add_link = [&](const urdf::Link& ulink) {
    Link link;
    link.name = ulink.name;
    for (size_t c = 0; c < ulink.collision_array.size(); ++c) {
      const std::string where = "urdf: link '" + ulink.name + "' collision[" + std::to_string(c) + "]";
      link.collision.push_back(ConvertGeometry(*ulink.collision_array[c], where, meshes, &missing_meshes));
    }
    if (ulink.inertial) {
      const urdf::Inertial& in = *ulink.inertial;
      const std::string where = "urdf: link '" + ulink.name + "' inertial";
      if (!(in.mass >= 0.0) || !std::isfinite(in.mass)) {
        ThrowInvalid(where + " mass = " + FormatNumber(in.mass) + " must be >= 0 and finite");
      }
      const Eigen::Isometry3d frame = ToIsometry(in.origin);
      Eigen::Matrix3d inertia;
      inertia << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
      if (!frame.matrix().allFinite()) ThrowInvalid(where + " origin must be finite");
      const std::string given = "(ixx " + FormatNumber(in.ixx) + ", iyy " + FormatNumber(in.iyy) + ", izz " +
                                FormatNumber(in.izz) + ", ixy " + FormatNumber(in.ixy) + ", ixz " +
                                FormatNumber(in.ixz) + ", iyz " + FormatNumber(in.iyz) + ")";
      if (!inertia.allFinite()) ThrowInvalid(where + " inertia = " + given + " must be finite");
      robot_internal::CheckInertiaPositiveSemidefinite(inertia, where + " inertia", given);
      Inertial inertial;
      inertial.mass = in.mass;
      inertial.com = frame.translation();
      inertial.inertia = frame.linear() * inertia * frame.linear().transpose();
      link.inertial = inertial;
    }
    link_index[link.name] = static_cast<int>(links.size());
    links.push_back(std::move(link));
  };

  // Iterative (an explicit stack: a long chain must not overflow the call stack), in the order
  // of a recursive depth-first walk: a child's subtree right after the child, siblings in
  // document order.
  struct Visit {
    const urdf::Link* link;
    const std::vector<urdf::JointConstSharedPtr>* children;  // null: none
    std::size_t next = 0;
  };
  auto children_of = [&](const urdf::Link& link) -> const std::vector<urdf::JointConstSharedPtr>* {
    const auto it = child_joints.find(link.name);
    return it == child_joints.end() ? nullptr : &it->second;
  };
  // Moving joints with <mimic>: (index into joints, the urdfdom description), resolved once
  // every joint has its index.
  std::vector<std::pair<std::size_t, std::shared_ptr<const urdf::JointMimic>>> mimics;
  add_link(*model->getRoot());
  std::vector<Visit> stack{{model->getRoot().get(), children_of(*model->getRoot())}};
  while (!stack.empty()) {
    Visit& top = stack.back();
    if (top.children == nullptr || top.next == top.children->size()) {
      stack.pop_back();
      continue;
    }
    const urdf::Link& parent = *top.link;
    const urdf::JointConstSharedPtr& ujoint = (*top.children)[top.next++];
    const std::string where = "urdf: joint '" + ujoint->name + "'";
    Joint joint;
    joint.name = ujoint->name;
    switch (ujoint->type) {
      case urdf::Joint::REVOLUTE: joint.type = JointType::kRevolute; break;
      case urdf::Joint::CONTINUOUS: joint.type = JointType::kContinuous; break;
      case urdf::Joint::PRISMATIC: joint.type = JointType::kPrismatic; break;
      case urdf::Joint::FIXED: joint.type = JointType::kFixed; break;
      case urdf::Joint::PLANAR:
        ThrowInvalid(where + " has type planar; only revolute, continuous, prismatic and fixed joints are supported");
      case urdf::Joint::FLOATING:
        ThrowInvalid(where + " has type floating; only revolute, continuous, prismatic and fixed joints are supported");
      default:
        ThrowInvalid(where + " has an unknown type; only revolute, continuous, prismatic and fixed joints are supported");
    }
    joint.origin = ToIsometry(ujoint->parent_to_joint_origin_transform);
    if (!joint.origin.matrix().allFinite()) ThrowInvalid(where + " origin must be finite");
    joint.axis = ToVector(ujoint->axis);
    if (joint.type != JointType::kFixed) {
      if (!joint.axis.allFinite() || !(joint.axis.norm() > 1e-12)) {
        ThrowInvalid(where + " axis = (" + FormatNumber(joint.axis.x()) + " " +
                     FormatNumber(joint.axis.y()) + " " + FormatNumber(joint.axis.z()) +
                     ") must be finite and non-zero");
      }
      joint.axis.normalize();
      if (!ujoint->limits) {
        ThrowInvalid(where + " has no <limit>; limit velocity must be > 0 and finite");
      }
      const urdf::JointLimits& ul = *ujoint->limits;
      joint.limits.velocity = ul.velocity;
      joint.limits.effort = ul.effort;
      if (joint.type == JointType::kContinuous) {
        joint.limits.lower = -M_PI;
        joint.limits.upper = M_PI;
      } else {
        joint.limits.lower = ul.lower;
        joint.limits.upper = ul.upper;
        if (!std::isfinite(ul.lower)) ThrowInvalid(where + " limit lower = " + FormatNumber(ul.lower) + " must be finite");
        if (!std::isfinite(ul.upper)) ThrowInvalid(where + " limit upper = " + FormatNumber(ul.upper) + " must be finite");
        if (ul.lower > ul.upper) {
          ThrowInvalid(where + " limit lower = " + FormatNumber(ul.lower) + " > upper = " +
                       FormatNumber(ul.upper));
        }
      }
      if (!(ul.velocity > 0.0) || !std::isfinite(ul.velocity)) {
        ThrowInvalid(where + " limit velocity = " + FormatNumber(ul.velocity) + " must be > 0 and finite");
      }
      if (!(ul.effort >= 0.0) || !std::isfinite(ul.effort)) {
        ThrowInvalid(where + " limit effort = " + FormatNumber(ul.effort) + " must be >= 0 and finite");
      }
    }
    if (ujoint->dynamics) {
      // <dynamics damping=".." friction=".."/>: viscous [N·m·s/rad] and Coulomb [N·m] friction.
      const urdf::JointDynamics& ud = *ujoint->dynamics;
      if (!(ud.damping >= 0.0) || !std::isfinite(ud.damping)) {
        ThrowInvalid(where + " dynamics damping = " + FormatNumber(ud.damping) + " must be >= 0 and finite");
      }
      if (!(ud.friction >= 0.0) || !std::isfinite(ud.friction)) {
        ThrowInvalid(where + " dynamics friction = " + FormatNumber(ud.friction) + " must be >= 0 and finite");
      }
      joint.damping = ud.damping;
      joint.friction = ud.friction;
    }
    // <mimic> on a fixed joint means nothing (it does not move) and is ignored.
    if (ujoint->mimic && joint.type != JointType::kFixed) mimics.emplace_back(joints.size(), ujoint->mimic);
    urdf::LinkConstSharedPtr child = model->getLink(ujoint->child_link_name);
    if (!child) ThrowInvalid(where + " child = '" + ujoint->child_link_name + "' is not a link");
    if (link_index.count(child->name) != 0) {
      ThrowInvalid(where + " child = '" + child->name + "' is already in the tree; a link has one parent joint");
    }
    joint.parent_link = link_index.at(parent.name);
    add_link(*child);
    joint.child_link = link_index.at(child->name);
    joints.push_back(std::move(joint));
    stack.push_back({child.get(), children_of(*child)});
  }
  if (!missing_meshes.empty()) {
    std::string list;
    for (std::size_t i = 0; i < missing_meshes.size() && i < 50; ++i) list += (i ? "; " : "") + missing_meshes[i];
    if (missing_meshes.size() > 50) list += "; and " + std::to_string(missing_meshes.size() - 50) + " more";
    ThrowInvalid("urdf: " + std::to_string(missing_meshes.size()) + " collision mesh" +
                 (missing_meshes.size() == 1 ? " is" : "es are") + " not in the supplied meshes: " + list);
  }

  // 5. Mimic joints: the followed joint by name; FromTree resolves chains and narrows limits.
  if (!mimics.empty()) {
    std::unordered_map<std::string, int> joint_index;
    for (std::size_t j = 0; j < joints.size(); ++j) joint_index.emplace(joints[j].name, static_cast<int>(j));
    for (const auto& [j, umimic] : mimics) {
      const std::string where = "urdf: joint '" + joints[j].name + "'";
      const auto it = joint_index.find(umimic->joint_name);
      if (it == joint_index.end()) {
        ThrowInvalid(where + " mimics joint '" + umimic->joint_name + "', which is not a joint of robot '" + robot_name +
                     "'; a mimic joint must follow a revolute, continuous or prismatic joint of the robot");
      }
      if (it->second == static_cast<int>(j)) {
        ThrowInvalid(where + " mimics itself; a mimic joint must follow another joint");
      }
      if (joints[it->second].type == JointType::kFixed) {
        ThrowInvalid(where + " mimics joint '" + umimic->joint_name +
                     "', which is fixed; a mimic joint must follow a revolute, continuous or prismatic joint");
      }
      if (!std::isfinite(umimic->multiplier) || umimic->multiplier == 0.0) {
        ThrowInvalid(where + " mimic multiplier = " + FormatNumber(umimic->multiplier) +
                     " must be finite and non-zero (a joint that never moves is a fixed joint)");
      }
      if (!std::isfinite(umimic->offset)) {
        ThrowInvalid(where + " mimic offset = " + FormatNumber(umimic->offset) + " must be finite");
      }
      joints[j].mimic = JointMimic{it->second, umimic->multiplier, umimic->offset};
    }
  }

  // 6. SRDF: pairs of links whose collisions are never checked. A pair naming a link the URDF
  //    lacks is skipped with a warning (an error when strict_srdf).
  std::vector<std::pair<std::string, std::string>> allowed_pairs;
  std::vector<std::string> warnings;
  if (!srdf_text.empty()) {
    TiXmlDocument srdf_doc;
    ParseXmlOrThrow(std::string(srdf_text), "srdf", &srdf_doc);
    const TiXmlElement* root = srdf_doc.RootElement();
    if (root == nullptr || std::string(root->Value()) != "robot") {
      ThrowInvalid(std::string("srdf: root element is <") + (root ? root->Value() : "") +
                   ">, expected <robot>");
    }
    int index = 0;
    for (const TiXmlElement* e = root->FirstChildElement("disable_collisions"); e != nullptr;
         e = e->NextSiblingElement("disable_collisions"), ++index) {
      std::string names[2];
      std::string unknown;
      for (int k = 0; k < 2; ++k) {
        const std::string attribute = k == 0 ? "link1" : "link2";
        const std::string where = "srdf: disable_collisions[" + std::to_string(index) + "] " + attribute;
        const char* value = e->Attribute(attribute.c_str());
        if (value == nullptr) ThrowInvalid(where + " is missing");
        names[k] = value;
        if (unknown.empty() && link_index.find(names[k]) == link_index.end()) {
          unknown = where + " = '" + names[k] + "' is not a link of robot '" + robot_name + "'";
        }
      }
      if (!unknown.empty()) {
        if (strict_srdf) ThrowInvalid(unknown);
        warnings.push_back(unknown + "; the pair is skipped");
        continue;
      }
      allowed_pairs.emplace_back(names[0], names[1]);
    }
  }

  return FromTree(robot_name, std::move(links), std::move(joints), allowed_pairs, {}, std::move(warnings));
}

}  // namespace chasles
