#pragma once
/// \file
/// The fast path's forward kinematics: the world frame of every link a check reads, chained
/// through the joints into column-major frames. Internal to chasles_collision (and its tests).
///
/// Only links with collision geometry and their ancestors get a frame (a bare tool frame at
/// the end of a chain is skipped). A joint's child = parent · (R0, p0) · motion, computed on
/// whole columns: p = ((P₀x₀ + P₁x₁) + P₂x₂) + P₃, parent·R0 column by column (a copy when R0
/// is the identity), then a revolute joint about ±x, ±y or ±z — every URDF and DH axis of the
/// example robots — turns two columns (12 products), a skew axis multiplies by Rodrigues'
/// matrix. sin/cos of all joints come first (SinCos), so they overlap in the pipeline. The
/// arithmetic is lane by lane in the order written, so the AVX2 variant (one instruction per
/// column) and the baseline one (SSE2 pairs, or scalar code off x86) give the same bits.

#include <cmath>
#include <cstddef>
#include <vector>

#include <Eigen/Geometry>

#include "chasles/robot/error.h"
#include "chasles/robot/robot_model.h"
#include "simd.h"
#include "sin_cos.h"

namespace chasles::detail {

/// Four doubles as one value (GCC vector extension): a frame column (x, y, z, unused).
/// Declared 16-byte aligned: that is what the baseline build gives the type, and the AVX2 code
/// must not assume more of values the baseline code placed.
typedef double Lanes __attribute__((vector_size(32), aligned(16)));

/// Rigid frame, column-major: rotation columns col[0..2] and the translation col[3]. Lane 3 of
/// each column is unused (kept 0).
struct alignas(32) Frame {
  Lanes col[4];
};

/// *y = R x + p, lane by lane: ((R₀x₀ + R₁x₁) + R₂x₂) + p.
__attribute__((always_inline)) inline void Transform(const Frame& f, double x0, double x1, double x2, Lanes* y) {
  *y = f.col[0] * x0 + f.col[1] * x1 + f.col[2] * x2 + f.col[3];
}

inline void Apply(const Frame& f, const double* x, double* y) {
  Lanes v;
  Transform(f, x[0], x[1], x[2], &v);
  y[0] = v[0];
  y[1] = v[1];
  y[2] = v[2];
}

/// Columns of a·b for the row-major 3×3 b: column j = (a₀·b₀ⱼ + a₁·b₁ⱼ) + a₂·b₂ⱼ.
__attribute__((always_inline)) inline void MulColumns(const Lanes* a, const double* b, Lanes* c) {
  for (int j = 0; j < 3; ++j) c[j] = a[0] * b[j] + a[1] * b[3 + j] + a[2] * b[6 + j];
}

/// Columns u, v turn by the angle with cosine c and sine s: u' = c·u + s·v, v' = c·v − s·u
/// (the frame times Rot(axis, angle) for the axis completing u, v).
template <int u, int v>
__attribute__((always_inline)) inline void TurnColumns(double c, double s, Lanes* m) {
  const Lanes mu = m[u], mv = m[v];
  m[u] = c * mu + s * mv;
  m[v] = c * mv - s * mu;
}

/// One joint of the FK program: child = parent · (R0, p0) · motion, where the motion is a
/// rotation by θ about `axis` (revolute), a translation by θ along it (prismatic) or nothing;
/// θ = q[dof], or multiplier · q[dof] + offset for a mimic joint.
struct FkJoint {
  int parent_link = -1;
  int child_link = -1;
  int dof = -1;
  int kind = 0;              // 0 fixed, 1 revolute, 2 prismatic
  bool mimic = false;
  double multiplier = 1.0, offset = 0.0;
  double Value(const Eigen::VectorXd& q) const { return mimic ? multiplier * q[dof] + offset : q[dof]; }
  bool r0_identity = false;  // R0 = I exactly: parent·R0 is parent, no product needed
  /// Revolute joints about a coordinate axis (±x, ±y, ±z exactly): the axis index, and the
  /// sign folded into sin q. Rot(±e_a, q) leaves column a of parent·R0 as it is and turns the
  /// other two (TurnColumns).
  int axis_index = -1;  // -1: a general axis, Rot(a, q) = c·I + s·[a]× + (1 − c)·a·aᵀ
  double axis_sign = 1.0;
  double axis[3];
  double r0[9], p0[3];  // R0 row-major
  double r0a[3];        // R0·axis: a prismatic joint's direction in the parent frame
};

/// The joints to chain, parents before children.
struct FkProgram {
  std::vector<FkJoint> joints;
  int root = -1;      // the link whose frame is the identity
  int num_links = 0;  // frames[] must hold this many
};

/// \throws Error(kInvalidArgument) when the robot has no root link.
inline FkProgram BuildFkProgram(const RobotModel& robot) {
  FkProgram program;
  const int num_links = robot.num_links();
  program.num_links = num_links;
  for (int l = 0; l < num_links && program.root < 0; ++l) {
    if (robot.links()[l].parent_joint < 0) program.root = l;
  }
  if (program.root < 0) ThrowInvalid("robot '" + robot.name() + "' has no root link");
  // Only frames something reads are computed: links with collision shapes and their ancestors.
  std::vector<bool> needed(num_links, false);
  for (int l = 0; l < num_links; ++l) {
    if (robot.links()[l].collision.empty()) continue;
    for (int link = l; link >= 0 && !needed[link];) {
      needed[link] = true;
      const int j = robot.links()[link].parent_joint;
      link = j < 0 ? -1 : robot.joints()[j].parent_link;
    }
  }
  // Topological order: repeatedly take joints whose parent link is placed.
  std::vector<bool> placed(num_links, false), used(robot.joints().size(), false);
  placed[program.root] = true;
  bool progress = true;
  while (progress) {
    progress = false;
    for (std::size_t j = 0; j < robot.joints().size(); ++j) {
      const Joint& joint = robot.joints()[j];
      if (used[j] || joint.parent_link < 0 || !placed[joint.parent_link]) continue;
      used[j] = true;
      placed[joint.child_link] = true;
      progress = true;
      if (!needed[joint.child_link]) continue;
      FkJoint f;
      f.parent_link = joint.parent_link;
      f.child_link = joint.child_link;
      f.dof = joint.dof;
      f.kind = joint.type == JointType::kFixed ? 0 : joint.type == JointType::kPrismatic ? 2 : 1;
      if (f.dof < 0) f.kind = 0;
      if (f.kind != 0 && joint.mimic) {
        f.mimic = true;
        f.multiplier = joint.mimic->multiplier;
        f.offset = joint.mimic->offset;
      }
      const Eigen::Matrix3d r0 = joint.origin.linear();
      const Eigen::Vector3d a = joint.axis.normalized();
      f.r0_identity = r0 == Eigen::Matrix3d::Identity();
      for (int i = 0; i < 3; ++i) {
        f.axis[i] = a[i];
        if (std::abs(a[i]) == 1.0 && a[(i + 1) % 3] == 0.0 && a[(i + 2) % 3] == 0.0) {
          f.axis_index = i;
          f.axis_sign = a[i];
        }
      }
      const Eigen::Vector3d r0a = r0 * a;
      for (int i = 0; i < 3; ++i) {
        for (int k = 0; k < 3; ++k) f.r0[3 * i + k] = r0(i, k);
        f.p0[i] = joint.origin.translation()[i];
        f.r0a[i] = r0a[i];
      }
      program.joints.push_back(f);
    }
  }
  return program;
}

/// The FK itself, inlined into each build variant below.
__attribute__((always_inline)) inline void ComputeFkBody(const FkProgram& program, const Eigen::VectorXd& q,
                                                         Frame* frames) {
  const std::vector<FkJoint>& fk = program.joints;
  // sin and cos of every revolute joint first: independent of each other and of the chain, so
  // they overlap in the pipeline instead of waiting between the chain's products.
  constexpr std::size_t kStackJoints = 64;
  double stack_sc[2 * kStackJoints];
  std::vector<double> heap_sc;
  double* sc = stack_sc;
  if (fk.size() > kStackJoints) {
    heap_sc.resize(2 * fk.size());
    sc = heap_sc.data();
  }
  for (std::size_t i = 0; i < fk.size(); ++i) {
    if (fk[i].kind == 1) SinCos(fk[i].Value(q), &sc[2 * i], &sc[2 * i + 1]);
  }
  Frame& base = frames[program.root];
  base.col[0] = Lanes{1.0, 0.0, 0.0, 0.0};
  base.col[1] = Lanes{0.0, 1.0, 0.0, 0.0};
  base.col[2] = Lanes{0.0, 0.0, 1.0, 0.0};
  base.col[3] = Lanes{0.0, 0.0, 0.0, 0.0};
  for (std::size_t i = 0; i < fk.size(); ++i) {
    const FkJoint& j = fk[i];
    const Frame& parent = frames[j.parent_link];
    Frame& child = frames[j.child_link];
    double local_p[3] = {j.p0[0], j.p0[1], j.p0[2]};
    if (j.kind == 2) {
      const double d = j.Value(q);
      for (int k = 0; k < 3; ++k) local_p[k] += j.r0a[k] * d;
    }
    Transform(parent, local_p[0], local_p[1], local_p[2], &child.col[3]);
    // child rotation = (parent · R0) · Rot(axis, q).
    if (j.r0_identity) {
      for (int k = 0; k < 3; ++k) child.col[k] = parent.col[k];
    } else {
      MulColumns(parent.col, j.r0, child.col);
    }
    if (j.kind != 1) continue;
    const double s = sc[2 * i], c = sc[2 * i + 1];
    switch (j.axis_index) {
      case 0:
        TurnColumns<1, 2>(c, j.axis_sign * s, child.col);
        break;
      case 1:
        TurnColumns<2, 0>(c, j.axis_sign * s, child.col);
        break;
      case 2:
        TurnColumns<0, 1>(c, j.axis_sign * s, child.col);
        break;
      default: {  // a general axis: Rot(a, q) = c·I + s·[a]× + (1 − c)·a·aᵀ
        const double* a = j.axis;
        const double t = 1.0 - c;
        const double rot[9] = {c + t * a[0] * a[0],        t * a[0] * a[1] - s * a[2], t * a[0] * a[2] + s * a[1],
                               t * a[1] * a[0] + s * a[2], c + t * a[1] * a[1],        t * a[1] * a[2] - s * a[0],
                               t * a[2] * a[0] - s * a[1], t * a[2] * a[1] + s * a[0], c + t * a[2] * a[2]};
        const Lanes m[3] = {child.col[0], child.col[1], child.col[2]};
        MulColumns(m, rot, child.col);
      }
    }
  }
}

/// The baseline build of the FK (SSE2 pairs on x86-64).
inline void ComputeFkBaseline(const FkProgram& program, const Eigen::VectorXd& q, Frame* frames) {
  ComputeFkBody(program, q, frames);
}

#ifdef CHASLES_SIMD_X86
/// The AVX2 build of the FK: one instruction per column operation.
__attribute__((target("avx2"))) inline void ComputeFkAvx2(const FkProgram& program, const Eigen::VectorXd& q,
                                                          Frame* frames) {
  ComputeFkBody(program, q, frames);
}
#endif

/// Fills frames[l] for every link l of the program (frames holds program.num_links).
/// Precondition: q.size() == the robot's num_dofs().
inline void ComputeFk(SimdLevel level, const FkProgram& program, const Eigen::VectorXd& q, Frame* frames) {
#ifdef CHASLES_SIMD_X86
  if (level == SimdLevel::kAvx2) return ComputeFkAvx2(program, q, frames);
#endif
  ComputeFkBaseline(program, q, frames);
}

}  // namespace chasles::detail
