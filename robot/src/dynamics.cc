// Rigid-body dynamics of a RobotModel: recursive Newton–Euler (inverse dynamics), composite
// rigid body algorithm (mass matrix), Christoffel-symbol Coriolis matrix, forward dynamics.
//
// Frames: every quantity of link i is expressed in link i's frame. Joint j connects parent link
// p to child link c with the pose T_pc(q) = origin · motion(axis, q), written (R, r): R rotates
// child coordinates into parent coordinates and r is the child origin in the parent frame.
// Fixed joints are walked like moving joints with zero motion, so their child links' inertia is
// carried by the parent body exactly (no lumping step is needed).
//
// Mimic joints: the recursions run over every moving joint j with its value θ_j = m_j q_d + c_j
// (θ̇_j = m_j q̇_d, θ̈_j = m_j q̈_d; m_j = 1, c_j = 0 for an actuated joint). The constraint is
// linear, θ = A q + c with A(j, d) = m_j, so by virtual work the generalised force of dof d is
// Σ m_j τ_j over the joints it drives, M(q) = Aᵀ M_θ A, and ∂M/∂q_d = Aᵀ (Σ_j m_j ∂M_θ/∂θ_j) A.
//
// No heap allocation per call beyond the returned vector/matrix: per-link scratch lives in a
// thread_local workspace that grows to the largest robot seen by the thread.

#include "chasles/robot/dynamics.h"

#include <cassert>
#include <cmath>
#include <optional>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

namespace chasles {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;
using Matrix6Xd = Eigen::Matrix<double, 6, Eigen::Dynamic>;
using Vector6 = Eigen::Matrix<double, 6, 1>;
using Matrix6 = Eigen::Matrix<double, 6, 6>;

/// Scratch state of one link during a sweep (all in the link's own frame).
struct LinkState {
  Matrix3d R;          ///< rotation child -> parent of the link's parent joint
  Vector3d r;          ///< link origin in the parent frame
  Vector3d w, dw, a;   ///< angular velocity, angular acceleration, linear acceleration of origin
  Vector3d f, n;       ///< force and moment (about the origin) the parent joint transmits
  // Composite rigid body (CRBA): mass, first moment m·c and rotational inertia about the origin.
  double cm;
  Vector3d ch;
  Matrix3d cI;
};

std::vector<LinkState>& Workspace(int num_links) {
  thread_local std::vector<LinkState> states;
  if (static_cast<int>(states.size()) < num_links) states.resize(num_links);
  return states;
}

bool IsPrismatic(const Joint& joint) { return joint.type == JointType::kPrismatic; }

/// Fills R, r of the child link of `joint` at joint value q (0 for fixed joints).
inline void JointTransform(const Joint& joint, double q, LinkState* child) {
  const Matrix3d& R0 = joint.origin.linear();
  switch (joint.type) {
    case JointType::kRevolute:
    case JointType::kContinuous: {
      const double c = std::cos(q), s = std::sin(q);
      if (joint.axis.z() == 1.0) {  // the common case (DH-style URDFs): R0 · Rz(q)
        child->R.col(0) = c * R0.col(0) + s * R0.col(1);
        child->R.col(1) = c * R0.col(1) - s * R0.col(0);
        child->R.col(2) = R0.col(2);
      } else {  // Rodrigues: c·1 + s·[a] + (1 − c)·a aᵀ
        const Vector3d& a = joint.axis;
        Matrix3d rot = (1.0 - c) * (a * a.transpose());
        rot.diagonal().array() += c;
        rot(0, 1) -= s * a.z();
        rot(1, 0) += s * a.z();
        rot(0, 2) += s * a.y();
        rot(2, 0) -= s * a.y();
        rot(1, 2) -= s * a.x();
        rot(2, 1) += s * a.x();
        child->R.noalias() = R0 * rot;
      }
      child->r = joint.origin.translation();
      break;
    }
    case JointType::kPrismatic:
      child->R = R0;
      child->r = joint.origin.translation() + R0 * (joint.axis * q);
      break;
    case JointType::kFixed:
      child->R = R0;
      child->r = joint.origin.translation();
      break;
  }
}

/// Mass properties of a link, zero when it has none.
struct MassProperties {
  double m = 0.0;
  Vector3d c = Vector3d::Zero();
  Matrix3d I = Matrix3d::Zero();  // about the com
};
inline MassProperties LinkMass(const Link& link) {
  MassProperties p;
  if (link.inertial) {
    p.m = link.inertial->mass;
    p.c = link.inertial->com;
    p.I = link.inertial->inertia;
  }
  return p;
}

/// [v]², i.e. the matrix of p ↦ v × (v × p).
inline Matrix3d SkewSquared(const Vector3d& v) {
  return v * v.transpose() - v.squaredNorm() * Matrix3d::Identity();
}
inline Matrix3d Skew3(const Vector3d& v) {
  Matrix3d s;
  s << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return s;
}

/// θ̇ (or θ̈) of a moving joint from q̇ (q̈) of the dof that drives it: m·q̇ for a mimic joint.
inline double Rate(const Joint& joint, double qd) { return joint.mimic ? joint.mimic->multiplier * qd : qd; }

/// Joint torque of the friction model: damping·q̇ + friction·sign(q̇) (sign(0) = 0).
inline double FrictionTorque(const Joint& joint, double qd) {
  const double sign = qd > 0.0 ? 1.0 : (qd < 0.0 ? -1.0 : 0.0);
  return joint.damping * qd + joint.friction * sign;
}

/// Recursive Newton–Euler. qd / qdd may be null (zero). Adds friction and armature terms when
/// asked. Returns τ.
Eigen::VectorXd Rnea(const RobotModel& robot, const Eigen::VectorXd& q, const Eigen::VectorXd* qd,
                     const Eigen::VectorXd* qdd, const Vector3d& gravity, bool friction, bool armature) {
  const int num_links = robot.num_links();
  const std::vector<Joint>& joints = robot.joints();
  const std::vector<Link>& links = robot.links();
  std::vector<LinkState>& s = Workspace(num_links);
  assert(q.size() == robot.num_dofs());

  const int root = robot.root_link();
  s[root].w.setZero();
  s[root].dw.setZero();
  s[root].a = -gravity;  // gravity as a fictitious upward acceleration of the base

  // Forward sweep: velocities and accelerations; each link's own inertial force.
  for (const Joint& joint : joints) {
    const LinkState& p = s[joint.parent_link];
    LinkState& c = s[joint.child_link];
    const double qj = joint.Position(q);
    const double vj = (joint.dof >= 0 && qd) ? Rate(joint, (*qd)[joint.dof]) : 0.0;
    const double aj = (joint.dof >= 0 && qdd) ? Rate(joint, (*qdd)[joint.dof]) : 0.0;
    JointTransform(joint, qj, &c);
    const Matrix3d Et = c.R.transpose();
    // Acceleration of the child origin as a point of the parent body, in child coordinates.
    c.a.noalias() = Et * (p.a + p.dw.cross(c.r) + p.w.cross(p.w.cross(c.r)));
    const Vector3d w_in = Et * p.w;
    const Vector3d dw_in = Et * p.dw;
    if (IsPrismatic(joint)) {
      c.w = w_in;
      c.dw = dw_in;
      c.a += 2.0 * w_in.cross(joint.axis * vj) + joint.axis * aj;
    } else {
      c.w = w_in + joint.axis * vj;
      c.dw = dw_in + joint.axis * aj + w_in.cross(joint.axis * vj);
    }
    const std::optional<Inertial>& in = links[joint.child_link].inertial;
    if (in) {
      const Vector3d acom = c.a + c.dw.cross(in->com) + c.w.cross(c.w.cross(in->com));
      c.f = in->mass * acom;
      c.n = in->inertia * c.dw + c.w.cross(in->inertia * c.w) + in->com.cross(c.f);
    } else {
      c.f.setZero();
      c.n.setZero();
    }
  }
  // The root link's own inertia never enters a joint torque.

  // Backward sweep: accumulate forces towards the root, project on the joint axes.
  Eigen::VectorXd tau = Eigen::VectorXd::Zero(robot.num_dofs());
  for (int j = static_cast<int>(joints.size()) - 1; j >= 0; --j) {
    const Joint& joint = joints[j];
    LinkState& c = s[joint.child_link];
    if (joint.dof >= 0) {
      double t = IsPrismatic(joint) ? joint.axis.dot(c.f) : joint.axis.dot(c.n);
      if (armature && qdd) t += joint.armature * Rate(joint, (*qdd)[joint.dof]);
      if (friction && qd) t += FrictionTorque(joint, Rate(joint, (*qd)[joint.dof]));
      // Virtual work: dof d does m_j·τ_j through each joint j it drives.
      tau[joint.dof] += joint.mimic ? joint.mimic->multiplier * t : t;
    }
    if (joint.parent_link != root) {
      LinkState& p = s[joint.parent_link];
      const Vector3d fp = c.R * c.f;
      p.f += fp;
      p.n += c.R * c.n + c.r.cross(fp);
    }
  }
  return tau;
}

/// Body Jacobians of every link at q with respect to the moving joints' values θ (6 × n each,
/// n = num_moving_joints(), rows (ω, v), link frame, about the link origin), concatenated:
/// columns [link·n, (link + 1)·n). Uses the workspace's R, r.
void BodyJacobians(const RobotModel& robot, const Eigen::VectorXd& q, Matrix6Xd* jac) {
  const int n = robot.num_moving_joints();
  const int num_links = robot.num_links();
  std::vector<LinkState>& s = Workspace(num_links);
  jac->setZero(6, static_cast<Eigen::Index>(num_links) * n);
  for (std::size_t ji = 0; ji < robot.joints().size(); ++ji) {
    const Joint& joint = robot.joints()[ji];
    const double qj = joint.Position(q);
    LinkState& c = s[joint.child_link];
    JointTransform(joint, qj, &c);
    const Matrix3d Et = c.R.transpose();
    auto Jp = jac->middleCols(static_cast<Eigen::Index>(joint.parent_link) * n, n);
    auto Jc = jac->middleCols(static_cast<Eigen::Index>(joint.child_link) * n, n);
    // Ad_{T_cp}: ω' = Eᵀω, v' = Eᵀ(v + ω × r).
    for (int k = 0; k < n; ++k) {
      const Vector3d w = Jp.col(k).head<3>();
      const Vector3d v = Jp.col(k).tail<3>();
      Jc.col(k).head<3>() = Et * w;
      Jc.col(k).tail<3>() = Et * (v + w.cross(c.r));
    }
    const int m = robot.moving_index(static_cast<int>(ji));
    if (m >= 0) {
      if (IsPrismatic(joint)) {
        Jc.col(m).tail<3>() = joint.axis;
      } else {
        Jc.col(m).head<3>() = joint.axis;
      }
    }
  }
}

/// The expansion matrix A (num_moving_joints × num_dofs): θ̇ = A q̇, A(m, dof of m) = multiplier.
Eigen::MatrixXd ExpansionMatrix(const RobotModel& robot) {
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(robot.num_moving_joints(), robot.num_dofs());
  for (int m = 0; m < robot.num_moving_joints(); ++m) {
    const Joint& joint = robot.joints()[robot.moving_joint(m)];
    A(m, joint.dof) = joint.multiplier();
  }
  return A;
}

/// Spatial inertia of a link about its origin, (ω, v) ordering.
Matrix6 SpatialInertia(const MassProperties& mp) {
  Matrix6 G;
  const Vector3d h = mp.m * mp.c;
  G.topLeftCorner<3, 3>() = mp.I - mp.m * SkewSquared(mp.c);
  G.topRightCorner<3, 3>() = Skew3(h);
  G.bottomLeftCorner<3, 3>() = Skew3(h).transpose();
  G.bottomRightCorner<3, 3>() = mp.m * Matrix3d::Identity();
  return G;
}

/// [ad_V] for V = (ω, v).
Matrix6 LieBracketMatrix(const Vector6& V) {
  Matrix6 ad = Matrix6::Zero();
  const Matrix3d W = Skew3(V.head<3>());
  ad.topLeftCorner<3, 3>() = W;
  ad.bottomLeftCorner<3, 3>() = Skew3(V.tail<3>());
  ad.bottomRightCorner<3, 3>() = W;
  return ad;
}

}  // namespace

bool HasInertia(const RobotModel& robot) {
  // Mass of the rigid body each moving joint drives: its child link plus every link attached to
  // that child through fixed joints only.
  const std::vector<Joint>& joints = robot.joints();
  const std::vector<Link>& links = robot.links();
  std::vector<double> body_mass(links.size(), 0.0);
  for (int j = static_cast<int>(joints.size()) - 1; j >= 0; --j) {
    const Joint& joint = joints[j];
    body_mass[joint.child_link] += LinkMass(links[joint.child_link]).m;
    if (joint.type == JointType::kFixed) body_mass[joint.parent_link] += body_mass[joint.child_link];
  }
  // Per dof: some joint it drives (its own or a mimic joint) carries mass.
  std::vector<char> massive(robot.num_dofs(), 0);
  for (const Joint& joint : joints) {
    if (joint.dof >= 0 && body_mass[joint.child_link] > 0.0) massive[joint.dof] = 1;
  }
  for (char m : massive) {
    if (!m) return false;
  }
  return true;
}

JointFriction DofFriction(const RobotModel& robot, int dof) {
  JointFriction out;
  for (const Joint& joint : robot.joints()) {
    if (joint.dof != dof) continue;
    const double m = joint.multiplier();
    out.damping += m * m * joint.damping;
    out.friction += std::abs(m) * joint.friction;
    out.armature += m * m * joint.armature;
  }
  return out;
}

Eigen::VectorXd InverseDynamics(const RobotModel& robot, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                const Eigen::VectorXd& qdd, const DynamicsOptions& options) {
  assert(qd.size() == robot.num_dofs() && qdd.size() == robot.num_dofs());
  return Rnea(robot, q, &qd, &qdd, options.gravity, options.include_friction, /*armature=*/true);
}

PathTorque PathTorqueCoefficients(const RobotModel& robot, const Eigen::VectorXd& q, const Eigen::VectorXd& dq,
                                  const Eigen::VectorXd& ddq, const Eigen::Vector3d& gravity) {
  PathTorque out;
  PathTorqueCoefficients(robot, q, dq, ddq, gravity, &out);
  return out;
}

void PathTorqueCoefficients(const RobotModel& robot, const Eigen::VectorXd& q, const Eigen::VectorXd& dq,
                            const Eigen::VectorXd& ddq, const Eigen::Vector3d& gravity, PathTorque* result) {
  // Three Newton–Euler sweeps sharing each joint's transform: A (q̇ = 0, q̈ = q′, no gravity),
  // B (q̇ = q′, q̈ = q″, no gravity) and C (at rest, gravity); B uses LinkState's w, dw, a, f, n.
  struct Extra {
    Vector3d dwA, aA, fA, nA, aC, fC, nC;
  };
  const int num_links = robot.num_links();
  const std::vector<Joint>& joints = robot.joints();
  const std::vector<Link>& links = robot.links();
  std::vector<LinkState>& s = Workspace(num_links);
  thread_local std::vector<Extra> extra;
  if (static_cast<int>(extra.size()) < num_links) extra.resize(num_links);
  assert(q.size() == robot.num_dofs() && dq.size() == robot.num_dofs() && ddq.size() == robot.num_dofs());

  const int root = robot.root_link();
  s[root].w.setZero();
  s[root].dw.setZero();
  s[root].a.setZero();
  extra[root].dwA.setZero();
  extra[root].aA.setZero();
  extra[root].aC = -gravity;
  for (const Joint& joint : joints) {
    const LinkState& p = s[joint.parent_link];
    const Extra& pe = extra[joint.parent_link];
    LinkState& c = s[joint.child_link];
    Extra& ce = extra[joint.child_link];
    const double d1 = joint.dof >= 0 ? Rate(joint, dq[joint.dof]) : 0.0;
    const double d2 = joint.dof >= 0 ? Rate(joint, ddq[joint.dof]) : 0.0;
    JointTransform(joint, joint.Position(q), &c);
    const Matrix3d Et = c.R.transpose();
    c.a.noalias() = Et * (p.a + p.dw.cross(c.r) + p.w.cross(p.w.cross(c.r)));
    ce.aA.noalias() = Et * (pe.aA + pe.dwA.cross(c.r));
    ce.aC.noalias() = Et * pe.aC;
    const Vector3d w_in = Et * p.w;
    const Vector3d dw_in = Et * p.dw;
    const Vector3d dwA_in = Et * pe.dwA;
    if (IsPrismatic(joint)) {
      c.w = w_in;
      c.dw = dw_in;
      c.a += 2.0 * w_in.cross(joint.axis * d1) + joint.axis * d2;
      ce.dwA = dwA_in;
      ce.aA += joint.axis * d1;
    } else {
      c.w = w_in + joint.axis * d1;
      c.dw = dw_in + joint.axis * d2 + w_in.cross(joint.axis * d1);
      ce.dwA = dwA_in + joint.axis * d1;
    }
    const std::optional<Inertial>& in = links[joint.child_link].inertial;
    if (in) {
      c.f = in->mass * (c.a + c.dw.cross(in->com) + c.w.cross(c.w.cross(in->com)));
      c.n = in->inertia * c.dw + c.w.cross(in->inertia * c.w) + in->com.cross(c.f);
      ce.fA = in->mass * (ce.aA + ce.dwA.cross(in->com));
      ce.nA = in->inertia * ce.dwA + in->com.cross(ce.fA);
      ce.fC = in->mass * ce.aC;
      ce.nC = in->com.cross(ce.fC);
    } else {
      c.f.setZero();
      c.n.setZero();
      ce.fA.setZero();
      ce.nA.setZero();
      ce.fC.setZero();
      ce.nC.setZero();
    }
  }
  PathTorque& out = *result;
  out.a.setZero(robot.num_dofs());
  out.b.setZero(robot.num_dofs());
  out.c.setZero(robot.num_dofs());
  for (int j = static_cast<int>(joints.size()) - 1; j >= 0; --j) {
    const Joint& joint = joints[j];
    LinkState& c = s[joint.child_link];
    Extra& ce = extra[joint.child_link];
    if (joint.dof >= 0) {
      const bool prismatic = IsPrismatic(joint);
      double ta = joint.axis.dot(prismatic ? ce.fA : ce.nA);
      double tb = joint.axis.dot(prismatic ? c.f : c.n);
      const double tc = joint.axis.dot(prismatic ? ce.fC : ce.nC);
      ta += joint.armature * Rate(joint, dq[joint.dof]);
      tb += joint.armature * Rate(joint, ddq[joint.dof]);
      const double m = joint.mimic ? joint.mimic->multiplier : 1.0;
      out.a[joint.dof] += m * ta;
      out.b[joint.dof] += m * tb;
      out.c[joint.dof] += m * tc;
    }
    if (joint.parent_link != root) {
      LinkState& p = s[joint.parent_link];
      Extra& pe = extra[joint.parent_link];
      const Vector3d fp = c.R * c.f, fpA = c.R * ce.fA, fpC = c.R * ce.fC;
      p.f += fp;
      p.n += c.R * c.n + c.r.cross(fp);
      pe.fA += fpA;
      pe.nA += c.R * ce.nA + c.r.cross(fpA);
      pe.fC += fpC;
      pe.nC += c.R * ce.nC + c.r.cross(fpC);
    }
  }
}

Eigen::MatrixXd MassMatrix(const RobotModel& robot, const Eigen::VectorXd& q) {
  assert(q.size() == robot.num_dofs());
  const int n = robot.num_moving_joints();  // M_θ over the moving joints; = M without mimics
  const std::vector<Joint>& joints = robot.joints();
  const std::vector<Link>& links = robot.links();
  std::vector<LinkState>& s = Workspace(robot.num_links());

  // Link transforms and each link's own inertia about its origin.
  for (int l = 0; l < robot.num_links(); ++l) {
    const std::optional<Inertial>& in = links[l].inertial;
    if (in) {
      s[l].cm = in->mass;
      s[l].ch = in->mass * in->com;
      s[l].cI = in->inertia - in->mass * SkewSquared(in->com);
    } else {
      s[l].cm = 0.0;
      s[l].ch.setZero();
      s[l].cI.setZero();
    }
  }
  for (const Joint& joint : joints) JointTransform(joint, joint.Position(q), &s[joint.child_link]);

  // Composite inertias, tip to root: I_p += R I_c Rᵀ − m[r]² − [r][h'] − [h'][r], h' = R h.
  for (int j = static_cast<int>(joints.size()) - 1; j >= 0; --j) {
    const Joint& joint = joints[j];
    const LinkState& c = s[joint.child_link];
    LinkState& p = s[joint.parent_link];
    const Vector3d h = c.R * c.ch;
    const Matrix3d rx = Skew3(c.r);
    const Matrix3d hx = Skew3(h);
    p.cI += c.R * c.cI * c.R.transpose() - c.cm * rx * rx - rx * hx - hx * rx;
    p.ch += c.cm * c.r + h;
    p.cm += c.cm;
  }

  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n, n);
  for (std::size_t ji = 0; ji < joints.size(); ++ji) {
    const Joint& joint = joints[ji];
    const int mj = robot.moving_index(static_cast<int>(ji));
    if (mj < 0) continue;
    const LinkState& c = s[joint.child_link];
    // Force (n, f) the composite body needs for a unit acceleration of this joint.
    Vector3d f, m;
    if (IsPrismatic(joint)) {
      f = c.cm * joint.axis;
      m = c.ch.cross(joint.axis);
    } else {
      f = joint.axis.cross(c.ch);
      m = c.cI * joint.axis;
    }
    M(mj, mj) = (IsPrismatic(joint) ? joint.axis.dot(f) : joint.axis.dot(m)) + joint.armature;
    // Carry it towards the root; each moving ancestor joint sees its projection.
    int link = joint.child_link;
    while (link != robot.root_link()) {
      const LinkState& l = s[link];
      f = l.R * f;
      m = l.R * m + l.r.cross(f);
      const int parent_link = joints[links[link].parent_joint].parent_link;
      link = parent_link;
      if (link == robot.root_link()) break;
      const Joint& up = joints[links[link].parent_joint];
      const int mu = robot.moving_index(links[link].parent_joint);
      if (mu >= 0) {
        const double v = IsPrismatic(up) ? up.axis.dot(f) : up.axis.dot(m);
        M(mj, mu) = v;
        M(mu, mj) = v;
      }
    }
  }
  if (!robot.has_mimic_joints()) return M;
  const Eigen::MatrixXd A = ExpansionMatrix(robot);
  return A.transpose() * M * A;
}

Eigen::VectorXd CoriolisTorques(const RobotModel& robot, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
  assert(qd.size() == robot.num_dofs());
  return Rnea(robot, q, &qd, nullptr, Vector3d::Zero(), /*friction=*/false, /*armature=*/false);
}

Eigen::MatrixXd CoriolisMatrix(const RobotModel& robot, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
  // Exact: M = Σ_l J_lᵀ G_l J_l over links l (body Jacobians J_l, spatial inertias G_l about the
  // link origins), and ∂J_l/∂q_k has column i equal to [ad_{J_l,i}] J_l,k when dof i is a proper
  // ancestor of dof k on l's chain, else 0 (differentiate J_b,i = Ad_{e^{-[B_n]q_n}···e^{-[B_i+1]q_i+1}} B_i).
  // From ∂M/∂q_k the Christoffel symbols Γ_ijk = ½(∂M_ij/∂q_k + ∂M_ik/∂q_j − ∂M_jk/∂q_i) give
  // C_ij = Σ_k Γ_ijk q̇_k.
  //
  // With mimic joints this runs over the moving joints (n of them): ∂M_θ/∂θ_k, then
  // ∂M/∂q_d = Aᵀ (Σ_k A(k, d) ∂M_θ/∂θ_k) A.
  assert(q.size() == robot.num_dofs() && qd.size() == robot.num_dofs());
  const int n = robot.num_moving_joints();
  const std::vector<Link>& links = robot.links();
  Matrix6Xd jac;
  BodyJacobians(robot, q, &jac);

  std::vector<Eigen::MatrixXd> dM(n, Eigen::MatrixXd::Zero(n, n));
  Eigen::Matrix<double, 6, Eigen::Dynamic> dJ(6, n), GJ(6, n);
  for (int l = 0; l < robot.num_links(); ++l) {
    const MassProperties mp = LinkMass(links[l]);
    if (mp.m == 0.0 && mp.I.isZero(0.0)) continue;
    const std::vector<int>& chain = robot.link_chain(l);
    if (chain.empty()) continue;
    const auto J = jac.middleCols(static_cast<Eigen::Index>(l) * n, n);
    GJ.noalias() = SpatialInertia(mp) * J;
    for (size_t kk = 0; kk < chain.size(); ++kk) {
      const int k = chain[kk];
      dJ.setZero();
      for (size_t ii = 0; ii < kk; ++ii) {
        const int i = chain[ii];
        dJ.col(i).noalias() = LieBracketMatrix(J.col(i)) * J.col(k);
      }
      const Eigen::MatrixXd term = dJ.transpose() * GJ;
      dM[k] += term + term.transpose();
    }
  }

  const int nd = robot.num_dofs();
  if (robot.has_mimic_joints()) {
    const Eigen::MatrixXd A = ExpansionMatrix(robot);
    std::vector<Eigen::MatrixXd> dMq(nd, Eigen::MatrixXd::Zero(n, n));
    for (int k = 0; k < n; ++k) {
      const Joint& joint = robot.joints()[robot.moving_joint(k)];
      dMq[joint.dof] += joint.multiplier() * dM[k];
    }
    for (int d = 0; d < nd; ++d) dMq[d] = A.transpose() * dMq[d] * A;
    dM = std::move(dMq);
  }

  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(nd, nd);
  for (int k = 0; k < nd; ++k) {
    if (qd[k] == 0.0) continue;
    for (int i = 0; i < nd; ++i) {
      for (int j = 0; j < nd; ++j) {
        C(i, j) += 0.5 * (dM[k](i, j) + dM[j](i, k) - dM[i](j, k)) * qd[k];
      }
    }
  }
  return C;
}

Eigen::VectorXd GravityTorques(const RobotModel& robot, const Eigen::VectorXd& q, const Eigen::Vector3d& gravity) {
  return Rnea(robot, q, nullptr, nullptr, gravity, /*friction=*/false, /*armature=*/false);
}

Eigen::VectorXd ForwardDynamics(const RobotModel& robot, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                const Eigen::VectorXd& tau, const DynamicsOptions& options) {
  assert(tau.size() == robot.num_dofs());
  // τ − (c + g + friction) is τ minus the inverse dynamics at q̈ = 0.
  const Eigen::VectorXd bias = Rnea(robot, q, &qd, nullptr, options.gravity, options.include_friction, false);
  return MassMatrix(robot, q).ldlt().solve(tau - bias);
}

}  // namespace chasles
