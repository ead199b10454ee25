#include "chasles/robot/robot_model.h"

#include <algorithm>
#include <cmath>
#include <tuple>
#include <unordered_map>

#include "chasles/robot/error.h"
#include "format.h"

namespace chasles {

using robot_internal::FormatNumber;
using chasles::FormatNumber;

// ---------------------------------------------------------------------------------------------
// AllowedCollisionMatrix

AllowedCollisionMatrix::AllowedCollisionMatrix(int num_links)
    : num_links_(num_links),
      allowed_(static_cast<size_t>(num_links) * static_cast<size_t>(num_links), false) {}

void AllowedCollisionMatrix::Allow(int link_a, int link_b) {
  if (link_a < 0 || link_b < 0 || link_a >= num_links_ || link_b >= num_links_) {
    ThrowInvalid("AllowedCollisionMatrix::Allow(" + std::to_string(link_a) + ", " +
                 std::to_string(link_b) + "): link indices must be within [0, " +
                 std::to_string(num_links_) + ")");
  }
  allowed_[static_cast<size_t>(link_a) * num_links_ + link_b] = true;
  allowed_[static_cast<size_t>(link_b) * num_links_ + link_a] = true;
}

bool AllowedCollisionMatrix::IsAllowed(int link_a, int link_b) const {
  if (link_a < 0 || link_b < 0 || link_a >= num_links_ || link_b >= num_links_) return false;
  return allowed_[static_cast<size_t>(link_a) * num_links_ + link_b];
}

// ---------------------------------------------------------------------------------------------
// Construction

const char* ToString(RobotKind kind) {
  switch (kind) {
    case RobotKind::kArm: return "arm";
    case RobotKind::kPlanar: return "planar";
    case RobotKind::kDubinsCar: return "dubins_car";
    case RobotKind::kReedsSheppCar: return "reeds_shepp_car";
    case RobotKind::kFreeFlyer: return "free_flyer";
  }
  return "unknown";
}

namespace {

bool AllFinite(const Eigen::Isometry3d& t) { return t.matrix().allFinite(); }

std::string JointLabel(const std::string& robot, size_t index, const std::string& name) {
  return "robot '" + robot + "': joint[" + std::to_string(index) + "] '" + name + "'";
}

std::string Interval(double lower, double upper) {
  return "[" + FormatNumber(lower) + ", " + FormatNumber(upper) + "]";
}

/// Mimic joints (Joint::mimic): validates them, resolves chains (afterwards every mimic follows
/// an actuated joint, multiplier and offset composed) and narrows the actuated joints' limits
/// so that their mimic joints stay within theirs, appending a warning for each narrowing that
/// `warnings` does not hold yet (a model rebuilt from a model's joints repeats none).
/// Precondition: limits and axes already checked (continuous joints at [-π, π]).
void ResolveMimicJoints(const std::string& robot, std::vector<Joint>* joints_in, std::vector<std::string>* warnings) {
  std::vector<Joint>& joints = *joints_in;
  const int nj = static_cast<int>(joints.size());
  bool any = false;
  for (int j = 0; j < nj; ++j) {
    Joint& joint = joints[j];
    if (!joint.mimic) continue;
    if (joint.type == JointType::kFixed) {  // a fixed joint does not move: nothing to follow
      joint.mimic.reset();
      continue;
    }
    any = true;
    const std::string label = JointLabel(robot, j, joint.name);
    const JointMimic& m = *joint.mimic;
    if (m.joint < 0 || m.joint >= nj || m.joint == j) {
      ThrowInvalid(label + " mimic.joint = " + std::to_string(m.joint) + " must be the index of another joint, within [0, " +
                   std::to_string(nj) + ")");
    }
    const Joint& followed = joints[m.joint];
    if (followed.type == JointType::kFixed) {
      ThrowInvalid(label + " mimics joint[" + std::to_string(m.joint) + "] '" + followed.name +
                   "', which is fixed; a mimic joint must follow a revolute, continuous or prismatic joint");
    }
    if (!std::isfinite(m.multiplier) || m.multiplier == 0.0) {
      ThrowInvalid(label + " mimic multiplier = " + FormatNumber(m.multiplier) +
                   " must be finite and non-zero (a joint that never moves is a fixed joint)");
    }
    if (!std::isfinite(m.offset)) ThrowInvalid(label + " mimic offset = " + FormatNumber(m.offset) + " must be finite");
  }
  if (!any) return;

  // Chains: follow each mimic to the actuated joint at the end, composing θ = m·θ' + c.
  std::vector<JointMimic> resolved(nj);
  for (int j = 0; j < nj; ++j) {
    if (!joints[j].mimic) continue;
    JointMimic r = *joints[j].mimic;
    std::vector<int> path{j};
    while (joints[r.joint].mimic) {
      if (std::find(path.begin(), path.end(), r.joint) != path.end()) {
        std::string cycle;
        for (int k : path) cycle += "'" + joints[k].name + "' -> ";
        ThrowInvalid(JointLabel(robot, j, joints[j].name) + " follows a cycle of mimic joints (" + cycle + "'" +
                     joints[r.joint].name + "'); a chain of mimic joints must end at a joint that is not a mimic");
      }
      path.push_back(r.joint);
      const JointMimic& next = *joints[r.joint].mimic;
      r.offset += r.multiplier * next.offset;
      r.multiplier *= next.multiplier;
      r.joint = next.joint;
    }
    if (!std::isfinite(r.multiplier) || r.multiplier == 0.0 || !std::isfinite(r.offset)) {
      ThrowInvalid(JointLabel(robot, j, joints[j].name) + " follows joint '" + joints[r.joint].name +
                   "' through a chain of mimic joints with multiplier " + FormatNumber(r.multiplier) + " and offset " +
                   FormatNumber(r.offset) + "; both must be finite and the multiplier non-zero");
    }
    resolved[j] = r;
  }
  const auto warn = [warnings](std::string text) {
    if (std::find(warnings->begin(), warnings->end(), text) == warnings->end()) warnings->push_back(std::move(text));
  };
  for (int j = 0; j < nj; ++j) {
    if (!joints[j].mimic) continue;
    Joint& joint = joints[j];
    joint.mimic = resolved[j];
    const JointMimic& r = resolved[j];
    Joint& actuated = joints[r.joint];
    const std::string relation = "'" + joint.name + "' = " + FormatNumber(r.multiplier) + " · '" + actuated.name +
                                 "' + " + FormatNumber(r.offset);
    JointLimits& lim = actuated.limits;
    if (joint.type != JointType::kContinuous) {
      // θ = m·q + c ∈ [lo, hi]  ⇔  q within the preimage.
      double pre_lo = (joint.limits.lower - r.offset) / r.multiplier;
      double pre_hi = (joint.limits.upper - r.offset) / r.multiplier;
      if (pre_lo > pre_hi) std::swap(pre_lo, pre_hi);
      const double lower = std::max(lim.lower, pre_lo);
      const double upper = std::min(lim.upper, pre_hi);
      if (!(lower <= upper)) {
        ThrowInvalid(JointLabel(robot, j, joint.name) + " is a mimic joint (" + relation + ") and no value of '" +
                     actuated.name + "' within " + Interval(lim.lower, lim.upper) + " keeps it within its limits " +
                     Interval(joint.limits.lower, joint.limits.upper));
      }
      if (lower != lim.lower || upper != lim.upper) {
        warn("robot '" + robot + "': joint '" + actuated.name + "' limits " + Interval(lim.lower, lim.upper) +
             " narrowed to " + Interval(lower, upper) + " so that its mimic joint " + relation + " stays within " +
             Interval(joint.limits.lower, joint.limits.upper));
        lim.lower = lower;
        lim.upper = upper;
      }
    }
    const double velocity = joint.limits.velocity / std::abs(r.multiplier);
    if (velocity < lim.velocity) {
      warn("robot '" + robot + "': joint '" + actuated.name + "' velocity limit " + FormatNumber(lim.velocity) +
           " lowered to " + FormatNumber(velocity) + " so that its mimic joint " + relation +
           " stays within its velocity limit " + FormatNumber(joint.limits.velocity));
      lim.velocity = velocity;
    }
  }
}

}  // namespace

std::shared_ptr<const RobotModel> RobotModel::FromTree(
    std::string name, std::vector<Link> links, std::vector<Joint> joints,
    const std::vector<std::pair<std::string, std::string>>& allowed_pairs, MotionModel motion,
    std::vector<std::string> load_warnings) {
  const int num_links = static_cast<int>(links.size());
  if (num_links == 0) ThrowInvalid("robot '" + name + "': has no links");

  std::unordered_map<std::string, int> link_index;
  for (int i = 0; i < num_links; ++i) {
    if (links[i].name.empty()) {
      ThrowInvalid("robot '" + name + "': link[" + std::to_string(i) + "] has an empty name");
    }
    if (!link_index.emplace(links[i].name, i).second) {
      ThrowInvalid("robot '" + name + "': link[" + std::to_string(i) + "] name '" + links[i].name +
                   "' is used by link[" + std::to_string(link_index[links[i].name]) +
                   "] too; link names must be unique");
    }
    links[i].parent_joint = -1;
  }

  // Every link except one (the root) is the child of exactly one joint.
  std::unordered_map<std::string, size_t> joint_index;
  for (size_t j = 0; j < joints.size(); ++j) {
    Joint& joint = joints[j];
    const std::string label = JointLabel(name, j, joint.name);
    if (joint.name.empty()) ThrowInvalid(label + " has an empty name");
    if (!joint_index.emplace(joint.name, j).second) {
      ThrowInvalid(label + " name is used by joint[" + std::to_string(joint_index[joint.name]) +
                   "] too; joint names must be unique");
    }
    for (const auto& [field, value] : {std::pair<const char*, int>{"parent_link", joint.parent_link},
                                       std::pair<const char*, int>{"child_link", joint.child_link}}) {
      if (value < 0 || value >= num_links) {
        ThrowInvalid(label + " " + field + " = " + std::to_string(value) +
                     " must be within [0, " + std::to_string(num_links) + ")");
      }
    }
    if (joint.parent_link == joint.child_link) {
      ThrowInvalid(label + " parent_link = child_link = " + std::to_string(joint.child_link) +
                   " must differ");
    }
    Link& child = links[joint.child_link];
    if (child.parent_joint >= 0) {
      ThrowInvalid(label + " child link '" + child.name + "' is already the child of joint[" +
                   std::to_string(child.parent_joint) + "] '" + joints[child.parent_joint].name +
                   "'; a link has at most one parent joint");
    }
    child.parent_joint = static_cast<int>(j);
    if (!AllFinite(joint.origin)) ThrowInvalid(label + " origin must be finite");
  }
  int root = -1;
  for (int i = 0; i < num_links; ++i) {
    if (links[i].parent_joint >= 0) continue;
    if (root >= 0) {
      ThrowInvalid("robot '" + name + "': links '" + links[root].name + "' and '" + links[i].name +
                   "' both have no parent joint; the tree must have exactly one root link");
    }
    root = i;
  }
  if (root < 0) ThrowInvalid("robot '" + name + "': every link has a parent joint (a cycle); the tree needs a root link");

  // Topological order: a joint's parent link is the root or the child of an earlier joint.
  for (size_t j = 0; j < joints.size(); ++j) {
    const Joint& joint = joints[j];
    const int parent_joint = links[joint.parent_link].parent_joint;
    if (joint.parent_link != root && parent_joint >= static_cast<int>(j)) {
      ThrowInvalid(JointLabel(name, j, joint.name) + " parent link '" + links[joint.parent_link].name +
                   "' is the child of a later joint[" + std::to_string(parent_joint) +
                   "]; joints must be in topological order");
    }
  }

  // Axes and limits.
  for (size_t j = 0; j < joints.size(); ++j) {
    Joint& joint = joints[j];
    if (joint.type == JointType::kFixed) {
      joint.dof = -1;
      continue;
    }
    const std::string label = JointLabel(name, j, joint.name);
    const double norm = joint.axis.norm();
    if (!joint.axis.allFinite() || !(norm > 1e-12)) {
      ThrowInvalid(label + " axis = (" + FormatNumber(joint.axis.x()) + " " +
                   FormatNumber(joint.axis.y()) + " " + FormatNumber(joint.axis.z()) +
                   ") must be finite and non-zero");
    }
    joint.axis /= norm;
    JointLimits& lim = joint.limits;
    if (joint.type == JointType::kContinuous) {
      lim.lower = -M_PI;
      lim.upper = M_PI;
    }
    if (!std::isfinite(lim.lower)) ThrowInvalid(label + " limit lower = " + FormatNumber(lim.lower) + " must be finite");
    if (!std::isfinite(lim.upper)) ThrowInvalid(label + " limit upper = " + FormatNumber(lim.upper) + " must be finite");
    if (lim.lower > lim.upper) {
      ThrowInvalid(label + " limit lower = " + FormatNumber(lim.lower) + " > upper = " +
                   FormatNumber(lim.upper));
    }
    if (!(lim.velocity > 0.0) || !std::isfinite(lim.velocity)) {
      ThrowInvalid(label + " limit velocity = " + FormatNumber(lim.velocity) + " must be > 0 and finite");
    }
    if (!(lim.effort >= 0.0) || !std::isfinite(lim.effort)) {
      ThrowInvalid(label + " limit effort = " + FormatNumber(lim.effort) + " must be >= 0 and finite");
    }
  }

  ResolveMimicJoints(name, &joints, &load_warnings);

  std::shared_ptr<RobotModel> model(new RobotModel());
  model->name_ = std::move(name);
  model->links_ = std::move(links);
  model->joints_ = std::move(joints);
  model->root_ = root;
  model->motion_ = motion;
  model->load_warnings_ = std::move(load_warnings);
  model->Finalize(allowed_pairs);
  return model;
}

void RobotModel::Finalize(const std::vector<std::pair<std::string, std::string>>& allowed_pairs) {
  const int nl = static_cast<int>(links_.size());
  const int nj = static_cast<int>(joints_.size());

  dof_joints_.clear();
  dof_names_.clear();
  moving_joints_.clear();
  moving_index_.assign(nj, -1);
  for (int j = 0; j < nj; ++j) {
    if (joints_[j].type == JointType::kFixed) {
      joints_[j].dof = -1;
      continue;
    }
    moving_index_[j] = static_cast<int>(moving_joints_.size());
    moving_joints_.push_back(j);
    if (joints_[j].mimic) continue;
    joints_[j].dof = static_cast<int>(dof_joints_.size());
    dof_joints_.push_back(j);
    dof_names_.push_back(joints_[j].name);
  }
  // A mimic joint follows an actuated joint (ResolveMimicJoints): it is driven by that dof.
  for (Joint& joint : joints_) {
    if (joint.mimic) joint.dof = joints_[joint.mimic->joint].dof;
  }
  const int nd = num_dofs();
  const int nm = num_moving_joints();
  lower_.resize(nd);
  upper_.resize(nd);
  velocity_.resize(nd);
  effort_.resize(nd);
  for (int d = 0; d < nd; ++d) {
    const JointLimits& lim = joints_[dof_joints_[d]].limits;
    lower_[d] = lim.lower;
    upper_[d] = lim.upper;
    velocity_[d] = lim.velocity;
    effort_[d] = lim.effort;
  }

  // Allowed collisions: every joint's parent/child pair (fixed joints too) + the given pairs.
  acm_ = AllowedCollisionMatrix(nl);
  for (const Joint& joint : joints_) acm_.Allow(joint.parent_link, joint.child_link);
  // One index for the pairs (FindLink per pair would cost links × pairs on large inputs).
  std::unordered_map<std::string_view, int> link_index;
  if (!allowed_pairs.empty()) {
    for (int i = 0; i < nl; ++i) link_index.emplace(links_[i].name, i);
  }
  const auto find = [&link_index](const std::string& name) {
    const auto it = link_index.find(name);
    return it == link_index.end() ? -1 : it->second;
  };
  for (size_t i = 0; i < allowed_pairs.size(); ++i) {
    const int a = find(allowed_pairs[i].first);
    const int b = find(allowed_pairs[i].second);
    for (const auto& [which, index, link_name] :
         {std::tuple<const char*, int, const std::string&>{"first", a, allowed_pairs[i].first},
          std::tuple<const char*, int, const std::string&>{"second", b, allowed_pairs[i].second}}) {
      if (index < 0) {
        ThrowInvalid("robot '" + name_ + "': allowed_pairs[" + std::to_string(i) + "]." + which +
                     " = '" + link_name + "' is not a link of the robot");
      }
    }
    acm_.Allow(a, b);
  }

  // Home poses (joints are in topological order, so parents come first).
  home_.assign(nl, Eigen::Isometry3d::Identity());
  parent_moving_of_link_.assign(nl, -1);
  for (int j = 0; j < nj; ++j) {
    const Joint& joint = joints_[j];
    home_[joint.child_link] = home_[joint.parent_link] * joint.origin;
    home_[joint.child_link].makeAffine();
    parent_moving_of_link_[joint.child_link] =
        moving_index_[j] >= 0 ? moving_index_[j] : parent_moving_of_link_[joint.parent_link];
  }

  // Space screw axes at q = 0 (Modern Robotics: revolute ω = R·axis, v = −ω × p;
  // prismatic ω = 0, v = R·axis).
  screws_.assign(nm, Eigen::Matrix<double, 6, 1>::Zero());
  screw_w_cross_v_.assign(nm, Eigen::Vector3d::Zero());
  moving_prismatic_.assign(nm, 0);
  parent_moving_of_moving_.assign(nm, -1);
  moving_dof_.assign(nm, -1);
  moving_multiplier_.assign(nm, 1.0);
  moving_offset_.assign(nm, 0.0);
  moving_mimic_.assign(nm, 0);
  for (int m = 0; m < nm; ++m) {
    const Joint& joint = joints_[moving_joints_[m]];
    const Eigen::Isometry3d& frame = home_[joint.child_link];
    const Eigen::Vector3d dir = frame.linear() * joint.axis;
    Eigen::Matrix<double, 6, 1>& s = screws_[m];
    if (joint.type == JointType::kPrismatic) {
      s.head<3>().setZero();
      s.tail<3>() = dir;
      moving_prismatic_[m] = 1;
    } else {
      s.head<3>() = dir;
      s.tail<3>() = -dir.cross(frame.translation());
      screw_w_cross_v_[m] = dir.cross(Eigen::Vector3d(s.tail<3>()));
    }
    parent_moving_of_moving_[m] = parent_moving_of_link_[joint.parent_link];
    moving_dof_[m] = joint.dof;
    if (joint.mimic) {
      moving_mimic_[m] = 1;
      moving_multiplier_[m] = joint.mimic->multiplier;
      moving_offset_[m] = joint.mimic->offset;
    }
  }

  // Chains: moving joints that move each link, root to tip.
  chains_.assign(nl, {});
  for (int j = 0; j < nj; ++j) {
    const Joint& joint = joints_[j];
    std::vector<int> chain = chains_[joint.parent_link];
    if (moving_index_[j] >= 0) chain.push_back(moving_index_[j]);
    chains_[joint.child_link] = std::move(chain);
  }
}

int RobotModel::FindLink(std::string_view name) const {
  for (size_t i = 0; i < links_.size(); ++i) {
    if (links_[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

// ---------------------------------------------------------------------------------------------
// Forward kinematics

namespace {

/// A rigid transform without the homogeneous row: 12 doubles, no alignment requirement.
struct Rigid {
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
};

constexpr int kStackDofs = 64;

}  // namespace

void RobotModel::ForwardKinematics(const Eigen::VectorXd& q,
                                   std::vector<Eigen::Isometry3d>* poses) const {
  const int nl = static_cast<int>(links_.size());
  const int nm = num_moving_joints();
  if (static_cast<int>(poses->size()) != nl) poses->resize(nl, Eigen::Isometry3d::Identity());

  Rigid stack_buffer[kStackDofs];
  Rigid* prefix = stack_buffer;
  if (nm > kStackDofs) {
    thread_local std::vector<Rigid> heap_buffer;
    if (static_cast<int>(heap_buffer.size()) < nm) heap_buffer.resize(nm);
    prefix = heap_buffer.data();
  }

  // prefix[d] = prefix[nearest moving ancestor of d] · e^[S_d] θ_d  (closed-form Rodrigues),
  // d over the moving joints.
  for (int d = 0; d < nm; ++d) {
    const Eigen::Matrix<double, 6, 1>& s = screws_[d];
    const double qi = q[moving_dof_[d]];
    const double theta = moving_mimic_[d] ? moving_multiplier_[d] * qi + moving_offset_[d] : qi;
    Rigid e;
    if (moving_prismatic_[d]) {
      e.R.setIdentity();
      e.t = s.tail<3>() * theta;
    } else {
      const double sn = std::sin(theta);
      const double cs = std::cos(theta);
      const double vc = 1.0 - cs;
      const double wx = s[0], wy = s[1], wz = s[2];
      const double xyv = wx * wy * vc, xzv = wx * wz * vc, yzv = wy * wz * vc;
      e.R(0, 0) = cs + wx * wx * vc;
      e.R(0, 1) = xyv - wz * sn;
      e.R(0, 2) = xzv + wy * sn;
      e.R(1, 0) = xyv + wz * sn;
      e.R(1, 1) = cs + wy * wy * vc;
      e.R(1, 2) = yzv - wx * sn;
      e.R(2, 0) = xzv - wy * sn;
      e.R(2, 1) = yzv + wx * sn;
      e.R(2, 2) = cs + wz * wz * vc;
      // p = (Iθ + (1 − cos θ)[ω] + (θ − sin θ)[ω]²) v with ω·v = 0 (zero-pitch screw).
      e.t = sn * s.tail<3>() + vc * screw_w_cross_v_[d];
    }
    const int parent = parent_moving_of_moving_[d];
    if (parent < 0) {
      prefix[d] = e;
    } else {
      const Rigid& p = prefix[parent];
      prefix[d].R.noalias() = p.R * e.R;
      prefix[d].t.noalias() = p.R * e.t;
      prefix[d].t += p.t;
    }
  }

  // T_link = prefix(nearest moving ancestor) · M_link.
  for (int l = 0; l < nl; ++l) {
    Eigen::Isometry3d& out = (*poses)[l];
    const Eigen::Isometry3d& m = home_[l];
    const int d = parent_moving_of_link_[l];
    if (d < 0) {
      out = m;
      continue;
    }
    const Rigid& p = prefix[d];
    out.linear().noalias() = p.R * m.linear();
    out.translation().noalias() = p.R * m.translation();
    out.translation() += p.t;
  }
}

void RobotModel::ForwardKinematicsByChaining(const Eigen::VectorXd& q,
                                             std::vector<Eigen::Isometry3d>* poses) const {
  poses->assign(links_.size(), Eigen::Isometry3d::Identity());
  for (const Joint& joint : joints_) {
    Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
    switch (joint.type) {
      case JointType::kRevolute:
      case JointType::kContinuous:
        motion.linear() = Eigen::AngleAxisd(joint.Position(q), joint.axis).toRotationMatrix();
        break;
      case JointType::kPrismatic:
        motion.translation() = joint.axis * joint.Position(q);
        break;
      case JointType::kFixed:
        break;
    }
    (*poses)[joint.child_link] = (*poses)[joint.parent_link] * joint.origin * motion;
  }
}

// ---------------------------------------------------------------------------------------------
// Validation

void RobotModel::ValidateConfiguration(const Eigen::VectorXd& q, const std::string& field) const {
  if (q.size() != num_dofs()) {
    ThrowInvalid(field + " has " + std::to_string(q.size()) + " values, robot '" + name_ + "' has " +
                 std::to_string(num_dofs()) + " joints");
  }
  for (int i = 0; i < q.size(); ++i) {
    const double x = q[i];
    if (!std::isfinite(x)) {
      ThrowInvalid(field + "[" + std::to_string(i) + "] = " + FormatNumber(x) + " must be finite");
    }
    if (x < lower_[i] || x > upper_[i]) {
      // The limits exactly (a rounded limit can make an outside value look inside).
      ThrowInvalid(field + "[" + std::to_string(i) + "] = " + FormatNumber(x) + " must be within [" +
                   FormatNumber(lower_[i]) + ", " + FormatNumber(upper_[i]) + "] (joint '" + dof_names_[i] +
                   "')");
    }
  }
}

}  // namespace chasles
