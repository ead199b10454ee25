#pragma once
/// \file
/// RobotModel: a kinematic tree with joint limits, link collision geometry and inertia, and
/// forward kinematics in product-of-exponentials form (Lynch & Park, Modern Robotics, ch. 4).
/// Twists are (ω, v). SI units and radians throughout.

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "chasles/robot/geometry.h"
#include "chasles/robot/input_limits.h"
#include "chasles/robot/joint.h"

namespace chasles {

/// What kind of robot a model is: which motions its configuration coordinates describe, and so
/// which planners apply (an arm's joints move freely; a car's (x, y, θ) do not).
enum class RobotKind {
  kArm,            ///< a kinematic tree on a fixed base (URDF, DH, PoE)
  kPlanar,         ///< a rigid body in SE(2), holonomic: (x, y, θ)
  kDubinsCar,      ///< a car-like SE(2) body that drives forwards only: (x, y, θ), turning radius
  kReedsSheppCar,  ///< a car-like SE(2) body that drives forwards and backwards
  kFreeFlyer,      ///< a rigid body in SE(3) (a drone): (x, y, z, yaw, pitch, roll)
};
/// "arm", "planar", "dubins_car", "reeds_shepp_car", "free_flyer".
const char* ToString(RobotKind kind);
inline bool IsCar(RobotKind kind) { return kind == RobotKind::kDubinsCar || kind == RobotKind::kReedsSheppCar; }

/// Motion constraints beyond joint limits.
struct MotionModel {
  RobotKind kind = RobotKind::kArm;
  double turning_radius = 0.0;  ///< cars: minimum turning radius [m] > 0
};

/// Mass properties of a link, expressed in the link frame.
struct Inertial {
  double mass = 0.0;                                   ///< [kg]
  Eigen::Vector3d com = Eigen::Vector3d::Zero();       ///< centre of mass [m]
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();   ///< about the com, link-frame axes [kg·m²]
};

struct Link {
  std::string name;
  int parent_joint = -1;          ///< -1 for the root link
  std::vector<Shape> collision;   ///< poses in the link frame
  std::optional<Inertial> inertial;
};

/// Pairs of links that may touch and are never collision-checked against each other.
/// Symmetric. Thread-safe to read.
class AllowedCollisionMatrix {
 public:
  AllowedCollisionMatrix() = default;
  explicit AllowedCollisionMatrix(int num_links);
  void Allow(int link_a, int link_b);
  bool IsAllowed(int link_a, int link_b) const;
  int num_links() const { return num_links_; }

 private:
  int num_links_ = 0;
  std::vector<bool> allowed_;
};

/// An immutable robot. Thread-safe to read from many threads at once.
class RobotModel {
 public:
  /// Builds a model from URDF text and optional SRDF text.
  /// Order: joints() are the URDF joints in depth-first order from the root link (children in
  /// document order); links() are the root followed by the child link of each joint in that
  /// order (link i + 1 is the child of joint i). Continuous joints get limits [-π, π].
  /// Mesh collision geometry is looked up in `meshes` by the URDF `filename` attribute
  /// (already parsed, e.g. by ParseMesh); the URDF `scale` is applied on top.
  /// Allowed collisions = SRDF `disable_collisions` pairs + every parent/child link pair.
  /// Before any XML parser runs, both texts are checked against `limits` (max_document_bytes,
  /// max_xml_depth) and the URDF's <link>/<joint> elements are counted (max_links for each,
  /// max_dofs for joints that are not fixed).
  /// A moving joint with `<mimic joint= multiplier= offset=>` gets no configuration coordinate:
  /// its value is multiplier · (the followed joint's) + offset (chains resolved; see FromTree).
  /// \throws Error(kInvalidArgument) naming the element for malformed URDF/SRDF (unparsable XML,
  ///         a NUL byte, SRDF naming an unknown link when strict_srdf, a mesh that is not in `meshes`, limits with
  ///         lower > upper, velocity <= 0, non-finite numbers, negative mass, an inertia with a
  ///         negative principal moment, planar/floating joints, a mimic naming an unknown or fixed
  ///         joint, a mimic multiplier that is 0 or not finite).
  /// \throws Error(kResourceExhausted) when a text is beyond `limits`, e.g.
  ///         `urdf nests XML elements 100000 deep, more than the cap of 64 (InputLimits::max_xml_depth); …`.
  /// SRDF entries that name a link the URDF lacks (published SRDFs routinely keep pairs of
  /// links a variant of the robot no longer has) are skipped, each reported in load_warnings(),
  /// as MoveIt does; with `strict_srdf` they are an error instead.
  /// Collision meshes missing from `meshes` are all named in one error.
  static std::shared_ptr<const RobotModel> FromUrdf(
      std::string_view urdf, std::string_view srdf = {},
      const std::map<std::string, std::shared_ptr<const TriangleMesh>>& meshes = {},
      const InputLimits& limits = {}, bool strict_srdf = false);

  /// The mesh of a URDF mesh filename (as written in the URDF), or null when it was not supplied.
  using MeshResolver = std::function<std::shared_ptr<const TriangleMesh>(const std::string& filename)>;
  /// FromUrdf asking `meshes` for each collision mesh as it is met, so a caller holding mesh
  /// bytes parses only the meshes collision geometry uses (visual meshes are never read). An
  /// exception from the resolver propagates unchanged.
  static std::shared_ptr<const RobotModel> FromUrdfResolvingMeshes(std::string_view urdf, std::string_view srdf,
                                                                   const MeshResolver& meshes,
                                                                   const InputLimits& limits = {},
                                                                   bool strict_srdf = false);

  const std::string& name() const { return name_; }
  /// Configuration coordinates: one per actuated joint (moving, not a mimic joint).
  int num_dofs() const { return static_cast<int>(dof_joints_.size()); }
  int num_links() const { return static_cast<int>(links_.size()); }
  const std::vector<Link>& links() const { return links_; }
  const std::vector<Joint>& joints() const { return joints_; }
  /// Names of the actuated joints (moving, not mimic) in configuration-vector order: the order of joints().
  /// For FromUrdf that is a depth-first traversal of the tree from the root link, the child
  /// joints of a link visited in URDF document order (so for a serial arm: root to tip).
  const std::vector<std::string>& dof_names() const { return dof_names_; }
  /// Index into joints() of the joint that drives configuration entry `dof`.
  int dof_joint(int dof) const { return dof_joints_[dof]; }
  const Eigen::VectorXd& lower_limits() const { return lower_; }
  const Eigen::VectorXd& upper_limits() const { return upper_; }
  const Eigen::VectorXd& velocity_limits() const { return velocity_; }
  const Eigen::VectorXd& effort_limits() const { return effort_; }
  const AllowedCollisionMatrix& allowed_collisions() const { return acm_; }
  const MotionModel& motion() const { return motion_; }
  RobotKind kind() const { return motion_.kind; }
  /// Index of the root link (the base frame of every pose). FromUrdf puts it at 0.
  int root_link() const { return root_; }
  /// Index of a link by name, or -1.
  int FindLink(std::string_view name) const;

  /// The PoE factors are the moving joints: every joint that is not fixed, mimic joints
  /// included, in joints() order. Moving joint m has value θ_m = multiplier · q[dof] + offset
  /// (joints()[moving_joint(m)].Position(q)). Without mimic joints, moving joint m is
  /// configuration entry m.
  int num_moving_joints() const { return static_cast<int>(moving_joints_.size()); }
  /// Index into joints() of moving joint `m`.
  int moving_joint(int m) const { return moving_joints_[m]; }
  /// Index among the moving joints of joints()[joint], -1 for a fixed joint.
  int moving_index(int joint) const { return moving_index_[joint]; }
  /// True when some joint is a mimic joint (num_moving_joints() > num_dofs()).
  bool has_mimic_joints() const { return num_moving_joints() != num_dofs(); }

  /// Space screw axis S_m = (ω, v) of moving joint `m`, at q = 0.
  const Eigen::Matrix<double, 6, 1>& space_screw_axis(int m) const { return screws_[m]; }
  /// Pose of `link` in the base (root link) frame at q = 0 (the PoE "M").
  const Eigen::Isometry3d& home_pose(int link) const { return home_[link]; }
  /// Moving joints that move `link`, root to tip (the PoE product order). Configuration entry
  /// d moves the link through each of them that it drives (joints()[moving_joint(m)].dof == d).
  const std::vector<int>& link_chain(int link) const { return chains_[link]; }

  /// Forward kinematics of every link by PoE: T_link = e^[S_a]θ_a ··· e^[S_k]θ_k M_link over
  /// the link's chain, θ the moving joints' values at q.
  /// `poses` is resized to num_links(). Precondition: q.size() == num_dofs().
  void ForwardKinematics(const Eigen::VectorXd& q, std::vector<Eigen::Isometry3d>* poses) const;

  /// Reference FK that chains the URDF joint transforms (origin · motion(axis, q)) link by link.
  /// Slower; kept to cross-check the PoE form.
  void ForwardKinematicsByChaining(const Eigen::VectorXd& q,
                                   std::vector<Eigen::Isometry3d>* poses) const;

  /// Validates a configuration supplied by a caller.
  /// \throws Error(kInvalidArgument), e.g. `start.positions has 6 values, robot 'ur5' has 7 joints`,
  ///         `start.positions[2] = nan must be finite`,
  ///         `start.positions[1] = 3.5 must be within [-3.141592653589793, 3.141592653589793] (joint 'shoulder')`.
  void ValidateConfiguration(const Eigen::VectorXd& q, const std::string& field) const;

  /// Builds a model directly from links and joints (used by URDF/DH/PoE front ends and tests).
  /// Joints must be in topological order (a joint's parent link is the root or the child of an
  /// earlier joint). A moving joint with `mimic` follows joints[mimic->joint] (any joint of the
  /// list, before or after it): chains are resolved (θ_c = m₂(m₁θ_a + c₁) + c₂), and the
  /// actuated joint's position limits are intersected with the preimage of every (non-continuous)
  /// mimic joint's, its velocity limit with the mimic's velocity limit / |multiplier|; each
  /// narrowing is reported in load_warnings().
  /// \throws Error(kInvalidArgument) when the tree is malformed, a mimic follows itself, an
  /// unknown or a fixed joint, or forms a cycle, its (composed) multiplier is 0 or not finite,
  /// its offset not finite, or no value of the actuated joint keeps it within its limits.
  /// `load_warnings`: what the front end skipped while reading the description (load_warnings()).
  static std::shared_ptr<const RobotModel> FromTree(std::string name, std::vector<Link> links,
                                                    std::vector<Joint> joints,
                                                    const std::vector<std::pair<std::string, std::string>>& allowed_pairs = {},
                                                    MotionModel motion = {},
                                                    std::vector<std::string> load_warnings = {});

  /// What was skipped while reading the description, one sentence each (e.g. SRDF pairs naming
  /// links the URDF lacks); empty for a description read in full.
  const std::vector<std::string>& load_warnings() const { return load_warnings_; }

 private:
  RobotModel() = default;
  void Finalize(const std::vector<std::pair<std::string, std::string>>& allowed_pairs);

  std::string name_;
  std::vector<Link> links_;
  std::vector<Joint> joints_;
  std::vector<int> dof_joints_;
  std::vector<std::string> dof_names_;
  Eigen::VectorXd lower_, upper_, velocity_, effort_;
  AllowedCollisionMatrix acm_;
  MotionModel motion_;
  // Per moving joint m (PoE factor), in joints() order.
  std::vector<int> moving_joints_;  ///< joint index of each moving joint
  std::vector<int> moving_index_;   ///< per joint: its moving index, -1 if fixed
  std::vector<Eigen::Matrix<double, 6, 1>> screws_;
  std::vector<Eigen::Isometry3d> home_;
  std::vector<std::vector<int>> chains_;  ///< per link: moving joints, root to tip
  std::vector<int> parent_moving_of_link_;    ///< nearest moving ancestor joint, -1 if none
  std::vector<int> parent_moving_of_moving_;  ///< nearest moving ancestor of each moving joint, -1 if none
  std::vector<Eigen::Vector3d> screw_w_cross_v_;  ///< ω × v of each moving joint (FK hot path)
  std::vector<char> moving_prismatic_;            ///< 1 for prismatic moving joints
  std::vector<int> moving_dof_;                   ///< θ_m = mult · q[dof] + offset
  std::vector<double> moving_multiplier_, moving_offset_;
  std::vector<char> moving_mimic_;                ///< 1 for mimic joints (else θ_m = q[dof] exactly)
  int root_ = 0;
  std::vector<std::string> load_warnings_;
};

}  // namespace chasles
