#pragma once
/// \file
/// Internal to chasles_collision: CollisionChecker::Impl (what a checker builds once and every
/// query reads) and the small types it holds, shared by collision_checker.cc (construction and
/// state checks), clearance.cc (distances to the scene), certified_motion.cc (lever bounds and the
/// conservative advancement) and allowed_pairs.cc (the scene's allowed pairs resolved against a robot). See the design notes at
/// the top of collision_checker.cc.

#include <algorithm>
#include <cstdint>
#include <iterator>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>
#include <fcl/fcl.h>

#include "broad_phase.h"
#include "chasles/collision/collision_checker.h"
#include "fcl_geometry.h"
#include "forward_kinematics.h"
#include "occupancy_grid.h"
#include "primitives.h"
#include "simd.h"
#include "sphere_cull.h"

namespace chasles {
namespace detail {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

inline void ToRowMajor(const Eigen::Matrix3d& m, double* r) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r[3 * i + j] = m(i, j);
}

inline Eigen::Isometry3d ToIsometry(const Frame& f) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) t.linear()(i, j) = f.col[j][i];
    t.translation()[i] = f.col[3][i];
  }
  return t;
}

/// Stack buffer with heap fallback for unusually large robots.
template <typename T, std::size_t N>
class Scratch {
 public:
  explicit Scratch(std::size_t n) {
    if (n > N) {
      heap_.resize(n);
      data_ = heap_.data();
    } else {
      data_ = stack_;
    }
  }
  T& operator[](std::size_t i) { return data_[i]; }
  const T& operator[](std::size_t i) const { return data_[i]; }
  const T* data() const { return data_; }

 private:
  T stack_[N];
  std::vector<T> heap_;
  T* data_;
};


/// A link that carries spheres (fast path).
struct SphereLink {
  int link;
  int begin, end;    // range in the sphere arrays
  double bc[3];      // bounding-sphere centre, link frame
  double br;         // bounding-sphere radius (padding included)
};

struct RobotShape {  // FCL path: one link shape
  int link;
  FclGeom g;
  Eigen::Isometry3d local;  // shape pose in the link frame
};

struct SceneGeom {  // an FCL scene object (world pose fixed)
  std::string name;
  FclGeom g;
  Eigen::Isometry3d pose;
  fcl::Transform3d tf;
  Eigen::Vector3d center;  // bounding centre, world
  double radius;
  bool octree = false;
  int grid = -1;  // fast path: index into Impl::grids when this map is gridded
  int allowed = -1;  // index into Impl::allowed_sets of the links that may touch it, or -1
};

/// A set of robot units (sphere-link indices on the fast path, link indices on the FCL path) as
/// 64-bit words: bit i of words[i / 64].
struct UnitSet {
  std::vector<std::uint64_t> words;
  bool Has(std::size_t i) const { return ((words[i >> 6] >> (i & 63)) & 1u) != 0; }
};

inline bool SpheresOverlap(const Eigen::Vector3d& c1, double r1, const Eigen::Vector3d& c2, double r2) {
  const double r = r1 + r2;
  return (c1 - c2).squaredNorm() <= r * r;
}

/// The scene's allowed pairs resolved against a robot.
struct SceneAllowances {
  std::vector<char> self;                       // num_links² (1 = allowed); empty when no link–link pair
  std::vector<std::vector<char>> objects, maps;  // per scene object / map: links (1/0); empty = none
};

/// \throws Error(kInvalidArgument) when q does not have one value per joint of the robot,
///         naming `field`.
void CheckSize(const RobotModel& robot, const Eigen::VectorXd& q, const char* field);

/// \throws Error(kInvalidArgument) naming `field`, the index and the value, when speed (a bound
///         on |dq_i/ds| per joint) has the wrong size or a value that is not finite and >= 0.
void CheckSpeedBound(const RobotModel& robot, const Eigen::VectorXd& speed, const char* field);

/// Every q_i within the robot's limits (NaN is not).
bool WithinLimits(const RobotModel& robot, const Eigen::VectorXd& q);

/// Resolves scene.allowed_collisions against the robot.
/// \throws Error(kInvalidArgument) naming the entry, when a name is not a link of the robot
///         (link1) or neither a link nor an obstacle of the scene (link2).
SceneAllowances ResolveSceneAllowances(const RobotModel& robot, const Scene& scene);

}  // namespace detail

struct CollisionChecker::Impl {
  using Frame = detail::Frame;
  using Prim = detail::Prim;
  using SphereLink = detail::SphereLink;
  using RobotShape = detail::RobotShape;
  using SceneGeom = detail::SceneGeom;
  using UnitSet = detail::UnitSet;

  const RobotModel* robot = nullptr;
  const Scene* scene = nullptr;
  CollisionOptions options;
  int num_links = 0;
  detail::FkProgram fk;  // forward_kinematics.h
  bool fast = false;

  // Fast path.
  std::vector<SphereLink> slinks;
  // slinks[i].br, contiguous, padded with 0 to detail::CullPadded(slinks.size()) for the cull.
  std::vector<double> link_bound_radius;
  // Self pairs as bit sets: bit b % 64 of self_masks[a * ⌈n/64⌉ + b / 64] when (a, b), a < b,
  // is in self_pairs (the cull visits them in the same order as the list).
  std::vector<std::uint64_t> self_masks;
  detail::SimdLevel simd = detail::BestSimdLevel();  // for the culls and the FK
  std::vector<double> sx, sy, sz, sr;          // link-frame centres, radius + padding
  std::vector<int> slink_of;                   // sphere -> index into slinks
  std::vector<int> sphere_source;              // sphere -> its index in link order, then shape order
  std::vector<std::pair<int, int>> self_pairs;  // indices into slinks, not allowed by the ACM
  std::vector<Prim> prims;
  std::vector<double> prim_x, prim_y, prim_z, prim_bound;  // prims' bounding spheres, structure of arrays
  // Broad phase (broad_phase.h) over the prims' bounding spheres, built when there are more than
  // kBroadPhasePrims of them: the checks then visit only the prims whose bound's box overlaps
  // the robot's (or a motion's swept) box; with fewer, scanning them all is cheaper.
  static constexpr std::size_t kBroadPhasePrims = 32;
  /// Spheres per sphere link at most: a link with more is split into groups along its principal
  /// axis, each with its own bounding sphere (CollisionChecker's constructor).
  static constexpr std::size_t kMaxSpheresPerBound = 8;
  static constexpr double kClearanceSearchRadius = 0.25;  // [m] first radius Clearance searches
  // When a gather lists at least 1/8 of the prims (clutter all around the robot), scanning them
  // all (one SIMD cull) costs less than the hierarchy's walk and the sort: the thread then scans
  // for this checker's next kScanStates queries of that kind before it gathers again. Either
  // way the same prims are met in the same order, so the answers do not change.
  static constexpr int kScanStates = 63;
  struct GatherHistory {
    const Impl* checker = nullptr;
    int scan = 0;  // queries left to scan
  };
  /// Whether this query should scan every prim instead of gathering (see kScanStates).
  bool ScanInstead(GatherHistory* h) const {
    if (h->checker != this) *h = {this, 0};
    if (h->scan == 0) return false;
    --h->scan;
    return true;
  }
  void Gathered(GatherHistory* h, std::size_t listed) const {
    if (8 * listed >= prims.size()) h->scan = kScanStates;
  }
  bool prim_broad_phase = false;
  detail::SphereBvh prim_bvh;
  /// *out = the prims whose bounding sphere's box overlaps the box around every sphere link's
  /// bounding sphere (centres lb, 3 per link) grown by grow[li] (nullptr: 0) plus `margin`, in
  /// scene order. Every prim within `margin` of some link's bounding sphere grown by grow[li] is
  /// listed. Needs prim_broad_phase.
  void PrimsNear(const double* lb, const double* grow, double margin, std::vector<std::uint32_t>* out) const {
    prim_bvh.Overlapping(LinkBoundsBox(lb, grow, margin), out);
  }
  /// The box around every sphere link's bounding sphere (centres lb, 3 per link) grown by
  /// grow[li] (nullptr: 0) plus `margin`.
  detail::Box3 LinkBoundsBox(const double* lb, const double* grow, double margin) const {
    detail::Box3 box = detail::Box3::None();
    for (std::size_t li = 0; li < slinks.size(); ++li) {
      box.Include(&lb[3 * li], slinks[li].br + (grow != nullptr ? grow[li] : 0.0) + margin);
    }
    return box;
  }
  std::vector<std::shared_ptr<fcl::Sphered>> fcl_spheres;  // per sphere, radius + padding
  std::vector<std::shared_ptr<fcl::Sphered>> fcl_link_bounds;  // per sphere link, its bound
  std::vector<detail::OccupancyGrid> grids;  // gridded occupancy maps
  // Certified motion, per moving joint m (RobotModel::moving_joint: actuated and mimic joints):
  // lever[k * num_moving + m] = |multiplier_m|·R_km, a bound on how far sphere k's centre moves
  // through joint m per unit of the dof that drives it, lever_dof[m] [m/rad, or |multiplier|
  // for prismatic]. A dof that drives several joints of a chain (a mimic joint below its
  // actuated joint) moves the sphere at most at the sum. certifiable = fast path and no scene
  // geometry left to FCL (meshes, ungridded maps).
  int num_dofs = 0;
  int num_moving = 0;
  std::vector<double> lever;
  std::vector<int> lever_dof;
  std::vector<std::vector<char>> slink_moving;  // per sphere link: moving joints in its chain (1/0)
  // Self pairs in the advancement: pair p's per-sphere bounds start at self_pair_offset[p]
  // (first link's spheres, then the second's; self_pair_spheres in all), and
  // self_pair_unshared[2p + side] lists the moving joints of that side's chain not in the other
  // side's (a joint, not a dof: a dof driving a joint above each link — two fingers — moves
  // them apart).
  std::vector<std::size_t> self_pair_offset;
  std::vector<std::vector<int>> self_pair_unshared;
  // self_pair_lever_max[2p + side][j]: the largest lever of that side's spheres about joint
  // self_pair_unshared[2p + side][j], so Σ_j w·max bounds every sphere's rate on that side.
  std::vector<std::vector<double>> self_pair_lever_max;
  std::size_t self_pair_spheres = 0;
  // Pair p's |A|·|B| sphere pairs start at self_pair_grid[p] (self_pair_grid.back() in all).
  std::vector<std::size_t> self_pair_grid;
  bool certifiable = false;

  // FCL path.
  std::vector<RobotShape> shapes;
  std::vector<std::pair<int, int>> shape_pairs;  // indices into shapes
  // Scene objects that FCL handles: meshes and maps in the fast path, everything otherwise.
  std::vector<SceneGeom> scene_geoms;
  // A broad phase over them, built when there are more than kBroadPhasePrims, so the checks
  // visit only those near the robot's box. On the FCL path, FCL's own: a dynamic AABB tree of
  // their world AABBs (geom_objects[i] is scene_geoms[i], user data i + 1). On the fast path,
  // where a state check costs ~0.4 µs and the tree's traversal ~0.15 µs, the SphereBvh of
  // their bounding spheres (~0.03 µs).
  bool geom_broad_phase = false;
  std::vector<std::unique_ptr<fcl::CollisionObjectd>> geom_objects;
  std::unique_ptr<fcl::DynamicAABBTreeCollisionManagerd> geom_manager;
  detail::SphereBvh geom_bvh;
  void BuildGeomBroadPhase();
  /// *out = the indices of the scene_geoms whose bound (FCL path: world AABB; fast path: the
  /// box of their bounding sphere) overlaps `box` (touching counts), ascending, so checks meet
  /// them in scene order; every index without a broad phase.
  void GeomsNear(const detail::Box3& box, std::vector<std::uint32_t>* out) const;
  /// The box around every FCL-path robot shape's bounding sphere (world centres, one per
  /// shape), padded, grown by `margin`.
  detail::Box3 ShapesBox(const Eigen::Vector3d* center, double margin) const {
    detail::Box3 box = detail::Box3::None();
    for (std::size_t i = 0; i < shapes.size(); ++i) {
      box.Include(center[i].data(), shapes[i].g.radius + options.padding + margin);
    }
    return box;
  }
  /// The widening search Clearance makes, for prims and for scene_geoms alike: gather(radius,
  /// &near) lists, ascending, every item that may lie within `radius` of the robot (false:
  /// there is no robot to search around); evaluate(fresh, count) may lower *best over the listed
  /// items no narrower round listed. The radius starts at `radius` and doubles until *best <=
  /// radius (an item not listed is farther than that, so it cannot lower *best) or every one of
  /// `total` items was listed.
  template <typename Gather, typename Evaluate>
  static void WideningSearch(double radius, std::size_t total, const double* best, const Gather& gather,
                             const Evaluate& evaluate) {
    thread_local std::vector<std::uint32_t> near, done, fresh;
    done.clear();
    for (;; radius *= 2.0) {
      if (!gather(radius, &near)) return;
      fresh.clear();
      std::set_difference(near.begin(), near.end(), done.begin(), done.end(), std::back_inserter(fresh));
      evaluate(fresh.data(), fresh.size());
      if (*best <= radius || near.size() == total) return;
      done.swap(near);
    }
  }
  /// Clearance over the scene_geoms: visit(g) may lower *best, for the geoms near
  /// box_at(radius) (WideningSearch from *best, or kClearanceSearchRadius while it is +inf). A
  /// geom whose bound misses box_at(radius) is farther than `radius` from every robot shape.
  /// Without a broad phase: every geom, once.
  template <typename BoxAt, typename Visit>
  void SearchGeomsNear(const BoxAt& box_at, double* best, const Visit& visit) const {
    if (!geom_broad_phase) {
      for (const SceneGeom& g : scene_geoms) visit(g);
      return;
    }
    WideningSearch(
        *best < detail::kInf ? *best : kClearanceSearchRadius, scene_geoms.size(), best,
        [&](double radius, std::vector<std::uint32_t>* near) {
          const detail::Box3 box = box_at(radius);
          if (box.Empty()) return false;  // no robot shape
          GeomsNear(box, near);
          return true;
        },
        [&](const std::uint32_t* fresh, std::size_t count) {
          for (std::size_t j = 0; j < count; ++j) visit(scene_geoms[fresh[j]]);
        });
  }
  // Link–obstacle pairs the scene allows (see the design notes): Prim::allowed and
  // SceneGeom::allowed index into this.
  std::vector<UnitSet> allowed_sets;
  const UnitSet* Allowed(int set) const { return set < 0 ? nullptr : &allowed_sets[set]; }

  void BuildFk();
  void ComputeFk(const Eigen::VectorXd& q, Frame* frames) const;
  bool FastCollide(const Frame* frames, CollisionResult* report) const;
  /// World centres of every sphere link's bounding sphere into lb (3 per link); marks every
  /// link's spheres as not yet placed.
  void PlaceLinkBounds(const Frame* frames, double* lb, char* placed) const {
    for (std::size_t li = 0; li < slinks.size(); ++li) {
      detail::Apply(frames[slinks[li].link], slinks[li].bc, &lb[3 * li]);
      placed[li] = 0;
    }
  }
  /// World centres of link li's spheres into w (3 per sphere), once per state.
  void PlaceLinkSpheres(const Frame* frames, std::size_t li, double* w, char* placed) const {
    if (placed[li]) return;
    placed[li] = 1;
    const SphereLink& L = slinks[li];
    for (int k = L.begin; k < L.end; ++k) {
      const double x[3] = {sx[k], sy[k], sz[k]};
      detail::Apply(frames[L.link], x, &w[3 * k]);
    }
  }
  /// The link bounding centres `lb` (3 per link) as structure of arrays: x, y, z rows of
  /// detail::CullPadded(nl) each in `soa`, the lanes past the last link set to `fill`.
  void LinkBoundsSoa(const double* lb, double fill, double* soa) const {
    const std::size_t nl = slinks.size();
    const std::size_t padded = detail::CullPadded(nl);
    for (std::size_t li = 0; li < padded; ++li) {
      for (std::size_t axis = 0; axis < 3; ++axis) soa[axis * padded + li] = li < nl ? lb[3 * li + axis] : fill;
    }
  }
  /// The clearance; with `group_lower` (slinks.size() values), per sphere link a lower bound on
  /// its own clearance, the least of them the clearance.
  double FastClearance(const Frame* frames, double* group_lower = nullptr) const;
  /// The smallest distance between the link spheres (world centres placed on demand into w;
  /// link bounds in soa, as LinkBoundsSoa) and the `count` prims listed in `which` (nullptr:
  /// prims 0..count-1), by branch and bound, or `best` when none of them is nearer (pairs
  /// whose bound is not below it are skipped); +inf when none and best = +inf. With
  /// `group_lower`, lowers each sphere link's entry to its distance from these prims, exact
  /// where the pair was evaluated, else the pair's bound (no less than the result).
  double PrimClearance(const Frame* frames, const std::uint32_t* which, std::size_t count, const double* soa,
                       double* w, char* placed, double best = detail::kInf, double* group_lower = nullptr) const;
  /// Each FCL-path robot shape's world transform and bounding centre (n = shapes.size() each).
  void PlaceShapes(const Frame* frames, fcl::Transform3d* tf, Eigen::Vector3d* center) const {
    for (std::size_t i = 0; i < shapes.size(); ++i) {
      tf[i] = detail::ToIsometry(frames[shapes[i].link]) * shapes[i].local;
      center[i] = tf[i] * shapes[i].g.center;
    }
  }
  bool FclCollide(const Frame* frames, CollisionResult* report) const;
  double FclClearance(const Frame* frames) const;
  bool Collide(const Eigen::VectorXd& q, CollisionResult* report) const;
  void BuildLevers();
  /// D_k = Σ_i w_i·R_ik: how far sphere k's centre can move per unit of the curve parameter
  /// when |dq_i/ds| <= w_i.
  void SweepBounds(const Eigen::VectorXd& w, double* out) const;
  /// Conservative advancement along q(s), s ∈ [0, 1], with |dq_i/ds| <= w_i (see
  /// IsCurveCertified); joint limits are the caller's.
  bool CertifiedCurve(const CollisionChecker::Curve& curve, const Eigen::VectorXd& speed,
                      CheckCounters* counters) const;
};

}  // namespace chasles
