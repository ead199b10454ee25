#pragma once
/// \file
/// CollisionChecker: self-collision under the allowed-collision matrix, robot vs scene (minus
/// the scene's allowed pairs), motion validation and clearance. Const and thread-safe: one instance serves all threads.

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "chasles/collision/scene.h"
#include "chasles/robot/path_constraints.h"
#include "chasles/robot/robot_model.h"

namespace chasles {

/// Options fixed when the checker is built.
struct CollisionOptions {
  /// Distance added around every robot shape against the scene [m]; >= 0: robot–obstacle
  /// contact closer than this is a collision. Self-collision is checked on the unpadded shapes
  /// (as MoveIt's link padding), so a padding wider than half the gap between adjacent links does
  /// not make the robot collide with itself.
  double padding = 0.0;
  /// Force the generic FCL path even when the fast sphere path applies (tests, reference).
  bool force_fcl = false;
  /// Fast path: with more than 32 scene primitives, index their bounding spheres in a static
  /// bounding-volume hierarchy built with the checker, so state checks, certified motions and
  /// Clearance visit only the primitives near the robot (or near the motion, in chunks of at
  /// most 0.2 m of sweep). The answers are the same either way (a certified motion may take a
  /// few more states, cut at chunk ends). Likewise, with more than 32 objects that FCL handles
  /// (meshes, ungridded maps; every object on the FCL path), only the ones near the robot are
  /// visited: listed by FCL's DynamicAABBTreeCollisionManager over their AABBs on the FCL path, by
  /// a hierarchy of their bounding spheres on the sphere path. false scans every object (tests,
  /// benchmarks).
  bool broad_phase = true;
  /// \throws Error(kInvalidArgument) naming the field.
  void Validate() const;
};

/// What a single check reports.
struct CollisionResult {
  bool in_collision = false;
  bool self_collision = false;   ///< the first contact found is robot–robot
  std::string link_a;            ///< first contact: a robot link
  std::string other;             ///< the other link, or the scene object / occupancy map name
  /// Set (with in_collision) when the state is free but breaks a path constraint of a checker
  /// made by WithPathConstraints: PathConstraints::Violation (which constraint, error and
  /// tolerance); link_a is then the constrained link and `other` is empty.
  std::string violation;
  /// A contact with an OctoMap checked on its voxel grid (the certified sphere path): the centre
  /// of the voxel touched, world frame [m].
  bool has_voxel = false;
  Eigen::Vector3d voxel = Eigen::Vector3d::Zero();
};

/// " (the voxel centred at (x, y, z) m)" for a contact with an OctoMap voxel, else "": for the
/// messages that name a contact.
std::string VoxelText(const CollisionResult& contact);

/// Per-caller counters (not shared between threads, so no contention).
struct CheckCounters {
  std::uint64_t state_checks = 0;
};

class CollisionChecker {
 public:
  /// Builds the checker for `robot` in `scene` (null = an empty scene).
  /// The scene's allowed pairs (Scene::allowed_collisions) are resolved here: a pair whose
  /// `other` is a robot link is added to the robot's ACM (that self pair is never checked); a
  /// pair whose `other` names scene objects or occupancy maps exempts link `link` from them in
  /// every query — IsValid, Check, IsMotionValid, IsMotionCertified and Clearance. An obstacle
  /// every link with geometry may touch is left out altogether.
  /// \throws Error(kInvalidArgument) when options are invalid, robot is null, or an allowed
  ///         pair does not resolve, e.g. `scene.allowed_collisions[0].link1 = 'hand' is not a
  ///         link of robot 'panda' (links: …)`, `scene.allowed_collisions[2].link2 = 'nope' is
  ///         neither a link of robot 'panda' nor an object or OctoMap of the scene (…)`.
  CollisionChecker(std::shared_ptr<const RobotModel> robot, std::shared_ptr<const Scene> scene,
                   CollisionOptions options = {});
  ~CollisionChecker();

  /// `base` that also requires `constraints` at every state: IsValid, Check, IsMotionValid,
  /// IsMotionCertified and IsCurveCertified reject a state or motion that leaves them (motions
  /// certified along their continuous path, PathConstraints::IsCurveSatisfied, whether or not
  /// collisions are certified). Shares base's geometry (no rebuild); Clearance is base's.
  /// \throws Error(kInvalidArgument) when `constraints` are for a robot with another number of joints.
  static std::shared_ptr<const CollisionChecker> WithPathConstraints(std::shared_ptr<const CollisionChecker> base,
                                                                     std::shared_ptr<const PathConstraints> constraints);
  /// The path constraints every check applies (null: none).
  const PathConstraints* path_constraints() const { return constraints_.get(); }
  CollisionChecker(const CollisionChecker&) = delete;
  CollisionChecker& operator=(const CollisionChecker&) = delete;

  const RobotModel& robot() const { return *robot_; }
  const Scene& scene() const { return *scene_; }
  const std::shared_ptr<const RobotModel>& robot_ptr() const { return robot_; }
  /// The options the checker was built with (padding, force_fcl).
  const CollisionOptions& options() const;

  /// True when q is inside the joint limits and collision-free (self and scene).
  /// Precondition: q.size() == robot().num_dofs().
  bool IsValid(const Eigen::VectorXd& q, CheckCounters* counters = nullptr) const;

  /// Like IsValid but reports the first contact found (limits are not checked).
  CollisionResult Check(const Eigen::VectorXd& q) const;

  /// Checks the straight joint-space segment a→b at states no more than `max_step`
  /// (max-norm over joints, [rad] or [m]) apart, endpoints included, in bisection order so
  /// a collision is found early. Returns true when every state is valid.
  bool IsMotionValid(const Eigen::VectorXd& a, const Eigen::VectorXd& b, double max_step,
                     CheckCounters* counters = nullptr) const;

  /// Certified motion check: true only when NO state on the straight joint-space segment
  /// q(s) = a + s·(b − a), s ∈ [0, 1], is invalid (outside the limits, self collision under the
  /// ACM, or contact with the scene other than an allowed pair, padding included) — no sampling
  /// gap. Allowed link–obstacle pairs do not shorten the advancement steps.
  /// When certifies_motion() (fast sphere path, scene of primitives and gridded occupancy maps
  /// only): conservative advancement. Every robot sphere k has, per joint i of its chain, a lever
  /// arm R_ik [m per rad] bounding how far its centre moves per unit of q_i (prismatic: 1), so
  /// from s to s + Δs its centre moves at most D_k·Δs, D_k = Σ_i |b_i − a_i|·R_ik [m] (a mimic
  /// joint driven by q_i adds |multiplier| times its own lever to R_ik). At each
  /// evaluated state the exact sphere–primitive clearances d_k, sphere–sphere self distances
  /// s_kl (both net of padding) and, for occupancy maps, a lower bound m on the clearance
  /// (the sphere grown by m misses every occupied voxel) give the next step
  /// Δs = min(d_k / D_k, s_kl / (D'_k + D'_l)), where D' sums only the joints not shared by
  /// the two links' chains (shared joints move both spheres rigidly: their distance is
  /// unchanged; a coordinate that drives a different joint above each link, such as a finger and
  /// its mimic, is not shared); a distance <= 0 is a collision. b is checked exactly with IsValid and a against
  /// the limits (the limit box is convex; the advancement's first state is a full check of a),
  /// then, on a
  /// segment longer than 0.25 in some joint, interior states in bisection order until they are
  /// at most 0.25 apart, so a segment cutting through an obstacle is rejected quickly; then the
  /// advancement runs from a.
  /// Conservative: returns false when Δs falls below 1e-7 or more than 20000 states would be
  /// evaluated (a motion that grazes an obstacle within rounding is rejected), so false does not
  /// prove a collision. While the steps shrink towards a contact, one state just beyond where
  /// they would sum up to is checked now and then (a collision there ends the check early; the
  /// steps and the answer are the same without it).
  /// Otherwise (FCL path, or a scene with meshes or an occupancy map too large to grid) it falls
  /// back to the discrete IsMotionValid(a, b, 0.005) and certifies nothing.
  /// `counters->state_checks` counts the evaluated states. Precondition: sizes == num_dofs().
  bool IsMotionCertified(const Eigen::VectorXd& a, const Eigen::VectorXd& b,
                         CheckCounters* counters = nullptr) const;

  /// The motion check of the planners and the pipeline: IsMotionCertified when
  /// certifies_motion() (no state on the segment is invalid), else IsMotionValid(a, b, max_step)
  /// (the states at most max_step apart are valid).
  bool IsMotionFree(const Eigen::VectorXd& a, const Eigen::VectorXd& b, double max_step,
                    CheckCounters* counters = nullptr) const {
    return certifies_motion() ? IsMotionCertified(a, b, counters) : IsMotionValid(a, b, max_step, counters);
  }

  /// A joint-space curve q(s), s ∈ [0, 1]: writes q(s) (num_dofs values) into *q.
  using Curve = std::function<void(double s, Eigen::VectorXd* q)>;

  /// Certified check of a curve, e.g. one polynomial piece of a timed trajectory: true only when
  /// no state q(s), s ∈ [0, 1], collides (self under the ACM, or the scene other than an allowed
  /// pair, padding included). `speed_bound[i]` must bound |dq_i/ds| over all of [0, 1] (for a
  /// piece of duration T: T·max|q̇_i| over it); the advancement of IsMotionCertified then
  /// holds unchanged, with D_k = Σ_i speed_bound_i·R_ik — the centre of sphere k moves at most
  /// Σ_i R_ik ∫|q̇_i| along any path. Joint limits are NOT checked here (a curve's range is the
  /// caller's: VerifyTrajectory checks it exactly at each polynomial's extrema). Up to 7
  /// interior probe states first (bisection order, no closer than 0.005 by the speed bound), then
  /// the advancement from s = 0. Same conservatism as IsMotionCertified (false when a step
  /// falls below 1e-7 or more than 20000 states would be evaluated, or q(s) is not finite).
  /// When !certifies_motion() it checks states at s = i/n with n = ⌈max_i speed_bound_i /
  /// 0.005⌉ (no joint moves more than 0.005 between them, by the bound) and certifies nothing.
  /// \throws Error(kInvalidArgument) when speed_bound has the wrong size or a value that is not
  ///         finite and >= 0.
  bool IsCurveCertified(const Curve& curve, const Eigen::VectorXd& speed_bound,
                        CheckCounters* counters = nullptr) const;

  /// True when IsMotionCertified is certified (see there) rather than the discrete fallback.
  bool certifies_motion() const;

  /// Diagnostics for tests: D_k [m] for the segment a→b, one per robot collision sphere in link
  /// order then shape order — a bound on how far each sphere centre moves along the segment.
  /// Empty when !certifies_motion().
  std::vector<double> SweepBounds(const Eigen::VectorXd& a, const Eigen::VectorXd& b) const;

  /// Smallest distance [m] between the robot and the scene at q (0 when in contact; +inf for
  /// an empty scene). Self-distance is not included, nor is the distance of an allowed
  /// link–obstacle pair (Scene::allowed_collisions): a link touching an object it may touch
  /// leaves the clearance to the other pairs (+inf when no other pair remains).
  double Clearance(const Eigen::VectorXd& q) const;

  /// Clearance(q), and in *group_lower one value per clearance group (num_clearance_groups()):
  /// on the fast path the robot's spheres in the groups the checker bounds them by (a link's
  /// spheres, a long link's in several groups), else one group of everything. Each value is a
  /// lower bound [m] on that group's own clearance (exact for the groups near the scene, a
  /// bounding-sphere bound for the others); the least of them is the clearance.
  double Clearance(const Eigen::VectorXd& q, Eigen::VectorXd* group_lower) const;
  int num_clearance_groups() const;
  /// The robot link (index into RobotModel::links()) of each clearance group; -1 for the one
  /// group off the fast path.
  std::vector<int> clearance_group_links() const;

  /// Per clearance group, the largest D_k of its spheres when |dq_i/ds| <= speed_i (see
  /// IsMotionCertified): no sphere centre of the group moves more than that per unit of s.
  /// Empty when !certifies_motion().
  /// \throws Error(kInvalidArgument) when speed has the wrong size or a value that is not finite
  ///         and >= 0 (`speed[2] = -1 must be finite and >= 0`).
  Eigen::VectorXd GroupSweepBounds(const Eigen::VectorXd& speed) const;

  /// True when the fast sphere path is used: every robot shape is a sphere and force_fcl is
  /// off. Then self checks, robot–primitive checks and robot–occupancy-map checks bypass FCL's
  /// generic machinery (exact sphere–primitive and sphere–voxel tests, same answers as FCL up
  /// to rounding at exact contact); meshes always go through FCL, and so does Clearance()
  /// against meshes and occupancy maps.
  bool uses_fast_path() const;

  /// Fast path: how many occupancy maps were expanded into a voxel bit grid at construction
  /// (the others — whose occupied voxels span a box of more than 2^28 finest voxels — are
  /// checked through FCL's octree traversal, and maps every link may touch are left out).
  /// 0 on the FCL path.
  int num_gridded_occupancy_maps() const;

 private:
  struct Impl;
  std::shared_ptr<const RobotModel> robot_;
  std::shared_ptr<const Scene> scene_;
  std::shared_ptr<Impl> impl_;  // shared by the checkers WithPathConstraints makes
  std::shared_ptr<const PathConstraints> constraints_;
  CollisionChecker() = default;
};

}  // namespace chasles
