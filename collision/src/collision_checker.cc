#include "chasles/collision/collision_checker.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <sstream>
#include <vector>

#include <fcl/fcl.h>
#include <fcl/geometry/octree/octree.h>
#include <octomap/OcTree.h>

#include "chasles/robot/error.h"
#include "fcl_geometry.h"
#include "forward_kinematics.h"
#include "occupancy_grid.h"
#include "primitives.h"
#include "sphere_cull.h"

// Design notes
// ------------
// * Forward kinematics (forward_kinematics.h) chains the joint transforms into column-major
//   frames on the stack (no allocation, no Eigen temporaries), only for links with geometry and
//   their ancestors; an AVX2 variant is chosen at run time (simd.h), bit-identical to the
//   baseline one. Tests cross-check it against RobotModel::ForwardKinematics.
// * Fast path (every robot shape a sphere, force_fcl off): spheres are kept as flat arrays
//   (link-frame centre, radius + padding), grouped per link with one bounding sphere per link.
//   Scene primitives are kept as flat records with their world->local transform precomputed;
//   tests are closed-form. Occupancy maps are expanded once, at construction, into a bit grid
//   of their finest voxels (occupancy_grid.h: FCL's own occupancy rule and box boundaries), and
//   each sphere is tested exactly against the occupied voxels overlapping its box. A map whose
//   obstacle voxels span more than OccupancyGrid::kMaxVoxels stays on FCL. Meshes still go
//   through FCL, with the robot spheres as fcl::Sphered. The link-bound culls of a state check
//   (against primitive bounds, and link against link for self pairs) are bit masks from one
//   structure-of-arrays kernel (sphere_cull.h): AVX2 when the CPU has it (simd.h), SSE2 or
//   plain C++ otherwise, all giving the same bits.
// * Fast-path order: primitives, occupancy maps (scene order), self, meshes. The FCL path checks
//   scene objects, then maps, then self, so for a scene of maps only both paths report the same
//   first contact.
// * FCL path: shared, immutable fcl geometries; every query calls the geometry+transform
//   overloads of fcl::collide / fcl::distance, which build their traversal state on the
//   stack. Nothing is mutated in const methods, so one checker serves all threads.
// * Certified advancement (CertifiedCurve): working memory is per thread and reused across
//   calls, and each link–primitive and self pair caches the curve parameter up to which it
//   cannot shorten a step (see "Pair skipping" there); the states, steps and answers are those
//   of evaluating every pair at every state.
// * Scene allowed collisions (Scene::allowed_collisions, MoveIt's ACM entries that come with a
//   scene) are resolved at construction: link–link pairs join the robot's ACM (they leave the
//   self-pair lists); link–obstacle pairs give the obstacle (Prim / SceneGeom `allowed`) a bit
//   set over the robot units the checks iterate — sphere links on the fast path, links on the FCL
//   path — and every robot-vs-obstacle loop skips the set bits (the primitive cull clears them
//   from its 64-link mask). Obstacles without allowances carry -1, so a scene without any costs
//   one predictable branch per obstacle; an obstacle every link may touch is dropped.
// * Contact semantics: shapes that touch (distance == 0 after padding) are in collision, as in
//   FCL's sphere–box test. With padding > 0 the FCL path compares fcl::distance <= padding.
//   Padding applies between the robot and the scene only; self pairs are checked on the
//   unpadded shapes (as MoveIt does), so the fast path subtracts 2·padding from padded radii.

namespace chasles {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

using detail::Apply;
using detail::Frame;

void ToRowMajor(const Eigen::Matrix3d& m, double* r) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r[3 * i + j] = m(i, j);
}

Eigen::Isometry3d ToIsometry(const Frame& f) {
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

 private:
  T stack_[N];
  std::vector<T> heap_;
  T* data_;
};

using detail::Prim;
using detail::SphereDistance;
using detail::SphereHits;
using detail::kPrimBox;
using detail::kPrimCapsule;
using detail::kPrimCylinder;
using detail::kPrimSphere;

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

}  // namespace

void CollisionOptions::Validate() const {
  if (!std::isfinite(padding) || padding < 0.0) {
    std::ostringstream os;
    os << "collision.padding = " << padding << " must be finite and >= 0";
    ThrowInvalid(os.str());
  }
}

struct CollisionChecker::Impl {
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
  std::vector<std::pair<int, int>> self_pairs;  // indices into slinks, not allowed by the ACM
  std::vector<Prim> prims;
  std::vector<double> prim_x, prim_y, prim_z, prim_bound;  // prims' bounding spheres, structure of arrays
  std::vector<std::shared_ptr<fcl::Sphered>> fcl_spheres;  // per sphere, radius + padding
  std::vector<std::shared_ptr<fcl::Sphered>> fcl_link_bounds;  // per sphere link, its bound
  std::vector<detail::OccupancyGrid> grids;  // gridded occupancy maps
  // Certified motion: lever[k * num_dofs + i] = R_ik, a bound on how far sphere k's centre
  // moves per unit of q_i [m/rad, or 1 for prismatic]. certifiable = fast path and no scene
  // geometry left to FCL (meshes, ungridded maps).
  int num_dofs = 0;
  std::vector<double> lever;
  std::vector<std::vector<char>> slink_dofs;  // per sphere link: dofs in its chain (1/0)
  // Self pairs in the advancement: pair p's per-sphere bounds start at self_pair_offset[p]
  // (first link's spheres, then the second's; self_pair_spheres in all), and
  // self_pair_unshared[2p + side] lists the dofs of that side's chain not in the other side's.
  std::vector<std::size_t> self_pair_offset;
  std::vector<std::vector<int>> self_pair_unshared;
  std::size_t self_pair_spheres = 0;
  // Pair p's |A|·|B| sphere pairs start at self_pair_grid[p] (self_pair_grid.back() in all).
  std::vector<std::size_t> self_pair_grid;
  bool certifiable = false;

  // FCL path.
  std::vector<RobotShape> shapes;
  std::vector<std::pair<int, int>> shape_pairs;  // indices into shapes
  // Scene objects that FCL handles: meshes and maps in the fast path, everything otherwise.
  std::vector<SceneGeom> scene_geoms;

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
      Apply(frames[slinks[li].link], slinks[li].bc, &lb[3 * li]);
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
      Apply(frames[L.link], x, &w[3 * k]);
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
  double FastClearance(const Frame* frames) const;
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

// Lever arms. A revolute joint turns everything below it about an axis through its child
// frame's origin, so a point x moves at most |x − o| per radian of that joint; |x − o| is
// bounded, by the triangle inequality, by the sphere centre's norm in its link frame plus the
// norms of the joint-origin translations between that link and the joint (a prismatic joint in
// between adds the largest |limit| to that length). A prismatic joint moves every point below
// it by exactly |Δq|. Summing over the chain, the centre's speed is at most Σ_i R_i |q̇_i|, so
// along any path |x(s1) − x(s0)| <= Σ_i R_i ∫|q̇_i| <= Σ_i R_i w_i (s1 − s0) when |dq_i/ds| <= w_i
// (a straight segment a→b: w = |b − a|).
void CollisionChecker::Impl::BuildLevers() {
  num_dofs = robot->num_dofs();
  const std::size_t ns = sx.size();
  lever.assign(ns * static_cast<std::size_t>(num_dofs), 0.0);
  slink_dofs.assign(slinks.size(), std::vector<char>(num_dofs, 0));
  for (std::size_t li = 0; li < slinks.size(); ++li) {
    for (int link = slinks[li].link; robot->links()[link].parent_joint >= 0;) {
      const Joint& j = robot->joints()[robot->links()[link].parent_joint];
      if (j.dof >= 0) slink_dofs[li][j.dof] = 1;
      link = j.parent_link;
    }
  }
  self_pair_offset.clear();
  self_pair_unshared.clear();
  self_pair_spheres = 0;
  self_pair_grid.assign(1, 0);
  for (const auto& pr : self_pairs) {
    self_pair_grid.push_back(self_pair_grid.back() +
                             static_cast<std::size_t>(slinks[pr.first].end - slinks[pr.first].begin) *
                                 static_cast<std::size_t>(slinks[pr.second].end - slinks[pr.second].begin));
    self_pair_offset.push_back(self_pair_spheres);
    for (int side = 0; side < 2; ++side) {
      const std::size_t li = side == 0 ? pr.first : pr.second;
      const std::vector<char>& other = slink_dofs[side == 0 ? pr.second : pr.first];
      std::vector<int> unshared;
      for (int i = 0; i < num_dofs; ++i) {
        if (!other[i]) unshared.push_back(i);
      }
      self_pair_unshared.push_back(std::move(unshared));
      self_pair_spheres += static_cast<std::size_t>(slinks[li].end - slinks[li].begin);
    }
  }
  for (const SphereLink& L : slinks) {
    for (int k = L.begin; k < L.end; ++k) {
      double* r = lever.data() + static_cast<std::size_t>(k) * num_dofs;
      double dist = std::sqrt(sx[k] * sx[k] + sy[k] * sy[k] + sz[k] * sz[k]);
      int link = L.link;
      while (robot->links()[link].parent_joint >= 0) {
        const Joint& j = robot->joints()[robot->links()[link].parent_joint];
        if (j.dof >= 0 && j.type != JointType::kFixed) {
          if (j.type == JointType::kPrismatic) {
            r[j.dof] += 1.0;
            const double reach = std::max(std::abs(j.limits.lower), std::abs(j.limits.upper));
            dist += std::isfinite(reach) ? reach : kInf;
          } else {
            r[j.dof] += dist;
          }
        }
        dist += j.origin.translation().norm();
        link = j.parent_link;
      }
    }
  }
}

void CollisionChecker::Impl::SweepBounds(const Eigen::VectorXd& w, double* out) const {
  const std::size_t ns = sx.size();
  for (std::size_t k = 0; k < ns; ++k) {
    const double* r = lever.data() + k * num_dofs;
    double d = 0.0;
    for (int i = 0; i < num_dofs; ++i) {
      if (r[i] != 0.0) d += w[i] * r[i];
    }
    out[k] = d;
  }
}

namespace {
constexpr int kMaxCertifiedStates = 20000;
constexpr double kProbeSpacing = 0.25;       // [rad] probe states before advancing, at most this apart
constexpr int kMaxProbeDepth = 10;           // (at most 1023 of them)
constexpr double kMinCertifiedStep = 1e-7;   // in s
constexpr double kMinGridMargin = 1e-5;      // [m]
constexpr double kMaxLinkGridMargin = 0.1;   // [m]
constexpr double kInitialGridMargin = 0.02;  // [m]
}  // namespace

namespace {

/// Per-thread working memory of CertifiedCurve, reused across calls: once a thread has run an
/// advancement for a robot and scene of this size, the next one allocates nothing.
struct AdvancementScratch {
  std::vector<double> D, Dl;         // sweep bound per sphere, its maximum per sphere link
  std::vector<double> PD, PDl;       // self pairs: the same over the unshared joints only
  std::vector<double> w, lb;         // world sphere centres (3 per sphere), link bound centres
  std::vector<char> placed, bound_placed;  // per sphere link: w / lb hold this state's values
  std::vector<double> margin;        // occupancy grids: last margin that held, per grid and sphere
  // Free-until parameters (see "Pair skipping" below).
  std::vector<double> prim_free;         // per primitive: the least of its links'
  std::vector<double> prim_link_free;    // per primitive and sphere link
  std::vector<double> prim_sphere_free;  // per primitive and sphere
  std::vector<double> self_free;         // per self pair
  std::vector<double> self_sphere_free;  // per self pair and pair of its spheres
  std::vector<Frame> frames;
  Eigen::VectorXd q;
  bool in_use = false;
};

/// Distance [m] taken off an evaluated clearance before it is cached as a lower bound. It is
/// far above the rounding of the distance computations (~1e-15 m at metre scale) and far below
/// any clearance that matters, so a pair skipped on its cached bound could not have shortened
/// the step had it been evaluated: the steps are exactly those of evaluating every pair.
constexpr double kFreeSlack = 1e-10;

/// Curve parameter up to which a pair whose clearance at s is at least d, approaching at no more
/// than rate v [m per unit of s], stays clear by the slack: s + (d − slack) / v.
inline double FreeUntil(double s, double d, double v) { return v > 0.0 ? s + (d - kFreeSlack) / v : kInf; }

}  // namespace

// Pair skipping. Every clearance the advancement evaluates shrinks at a bounded rate along the
// curve: sphere k's clearance to a primitive by at most D_k per unit of s, a self pair's by at
// most PD_k + PD_l. So a pair whose clearance was at least d at s0, shrinking at most at rate v,
// cannot shorten a step Δs taken at s while s + Δs <= s0 + d / v: its free-until parameter. It
// is cached per primitive and sphere (d the sphere's exact clearance), per primitive and link
// (the least of its spheres', or from the link's bounding sphere, which none of its spheres is
// closer than, with v = Dl >= D_k), per primitive (the least of its links'), and likewise per
// self pair and pair of their spheres; a slack of kFreeSlack is taken off d. The loops skip
// what cannot shorten the step, so after the first state only the pairs near enough to matter
// are evaluated again. A skipped pair could neither have changed the step nor found a contact
// (its clearance is positive), so the states visited, the steps and the answer are exactly
// those of evaluating every pair at every state. Occupancy grids keep their margin search at
// every state (its margins depend on the previous state's).
bool CollisionChecker::Impl::CertifiedCurve(const CollisionChecker::Curve& curve, const Eigen::VectorXd& speed,
                                            CheckCounters* counters) const {
  // The thread's scratch, or a fresh one when it is taken (a curve that runs a certified check).
  thread_local AdvancementScratch thread_scratch;
  std::unique_ptr<AdvancementScratch> own;
  AdvancementScratch* scratch = &thread_scratch;
  if (scratch->in_use) {
    own = std::make_unique<AdvancementScratch>();
    scratch = own.get();
  }
  struct Lease {
    AdvancementScratch* s;
    ~Lease() { s->in_use = false; }
  } lease{scratch};
  scratch->in_use = true;
  AdvancementScratch& m = *scratch;

  const std::size_t ns = sx.size();
  const std::size_t nl = slinks.size();
  const std::size_t np = self_pairs.size();
  m.D.resize(ns);
  m.Dl.assign(nl, 0.0);
  double* const D = m.D.data();
  double* const Dl = m.Dl.data();
  SweepBounds(speed, D);
  for (std::size_t li = 0; li < nl; ++li) {
    for (int k = slinks[li].begin; k < slinks[li].end; ++k) Dl[li] = std::max(Dl[li], D[k]);
  }
  for (std::size_t k = 0; k < ns; ++k) {
    if (!std::isfinite(D[k])) return false;
  }
  // Self pairs: joints in both links' chains move both spheres rigidly together and leave
  // their distance unchanged (d/dt |x_k − x_l| = (x_k − x_l)·(ω × (x_k − x_l)) / |·| = 0), so
  // the distance changes at most by the levers of the joints not shared, summed for both.
  m.PD.resize(self_pair_spheres);
  m.PDl.assign(2 * np, 0.0);
  for (std::size_t p = 0; p < np; ++p) {
    std::size_t at = self_pair_offset[p];
    for (int side = 0; side < 2; ++side) {
      const std::size_t li = side == 0 ? self_pairs[p].first : self_pairs[p].second;
      const std::vector<int>& unshared = self_pair_unshared[2 * p + side];
      for (int k = slinks[li].begin; k < slinks[li].end; ++k) {
        const double* r = lever.data() + static_cast<std::size_t>(k) * num_dofs;
        double d = 0.0;
        for (int i : unshared) {
          if (r[i] != 0.0) d += speed[i] * r[i];
        }
        if (!std::isfinite(d)) return false;
        m.PD[at++] = d;
        m.PDl[2 * p + side] = std::max(m.PDl[2 * p + side], d);
      }
    }
  }
  m.w.resize(3 * ns);
  m.lb.resize(3 * nl);
  m.placed.resize(nl);
  m.bound_placed.resize(nl);
  m.margin.assign(ns * grids.size(), kInitialGridMargin);
  // -inf: evaluate at the first state; allowed link–primitive pairs are never evaluated.
  const std::size_t nprims = prims.size();
  m.prim_free.assign(nprims, -kInf);
  m.prim_link_free.assign(nprims * nl, -kInf);
  m.prim_sphere_free.assign(nprims * ns, -kInf);
  for (std::size_t oi = 0; oi < nprims; ++oi) {
    if (const UnitSet* allowed = Allowed(prims[oi].allowed)) {
      for (std::size_t li = 0; li < nl; ++li) {
        if (allowed->Has(li)) m.prim_link_free[oi * nl + li] = kInf;
      }
    }
  }
  m.self_free.assign(np, -kInf);
  m.self_sphere_free.assign(self_pair_grid.back(), -kInf);
  m.frames.resize(num_links);
  m.q.resize(num_dofs);
  Frame* const frames = m.frames.data();
  double* const w = m.w.data();
  double* const lb = m.lb.data();
  // World centres of link li's bounding sphere / of its spheres, once per state, when needed.
  const auto bound = [&](std::size_t li) {
    if (!m.bound_placed[li]) {
      m.bound_placed[li] = 1;
      Apply(frames[slinks[li].link], slinks[li].bc, &lb[3 * li]);
    }
    return &lb[3 * li];
  };
  const auto place = [&](std::size_t li) { PlaceLinkSpheres(frames, li, w, m.placed.data()); };

  double s = 0.0;
  for (int state = 0;; ++state) {
    if (state >= kMaxCertifiedStates) return false;
    if (counters != nullptr) ++counters->state_checks;
    curve(s, &m.q);
    if (!m.q.allFinite()) return false;
    ComputeFk(m.q, frames);
    std::fill(m.placed.begin(), m.placed.end(), 0);
    std::fill(m.bound_placed.begin(), m.bound_placed.end(), 0);
    double step = 1.0 - s;
    // Scene primitives: exact clearances; a link whose bounding sphere is clear by more than
    // step·(its fastest sphere's bound) cannot shorten the step.
    for (std::size_t oi = 0; oi < nprims; ++oi) {
      if (m.prim_free[oi] >= s + step) continue;  // none of its pairs can shorten the step
      const Prim& o = prims[oi];
      double* const link_free = m.prim_link_free.data() + oi * nl;
      double* const sphere_free = m.prim_sphere_free.data() + oi * ns;
      double prim_until = kInf;
      for (std::size_t li = 0; li < nl; ++li) {
        if (link_free[li] >= s + step) {
          prim_until = std::min(prim_until, link_free[li]);
          continue;
        }
        const SphereLink& L = slinks[li];
        const double dl = SphereDistance(o, bound(li), L.br);
        if (dl > 0.0 && dl >= step * Dl[li]) {
          link_free[li] = FreeUntil(s, dl, Dl[li]);
          prim_until = std::min(prim_until, link_free[li]);
          continue;
        }
        place(li);
        double until = kInf;
        for (int k = L.begin; k < L.end; ++k) {
          if (sphere_free[k] < s + step) {
            const double d = SphereDistance(o, &w[3 * k], sr[k]);
            if (d <= 0.0) return false;
            if (d < step * D[k]) step = d / D[k];
            sphere_free[k] = FreeUntil(s, d, D[k]);
          }
          until = std::min(until, sphere_free[k]);
        }
        link_free[li] = until;
        prim_until = std::min(prim_until, until);
      }
      m.prim_free[oi] = prim_until;
    }
    // Self pairs: the distance shrinks at most at PD_k + PD_l (unshared joints only).
    for (std::size_t p = 0; p < np; ++p) {
      if (m.self_free[p] >= s + step) continue;
      const auto& pr = self_pairs[p];
      const double* pa = m.PD.data() + self_pair_offset[p];
      const double* pb = pa + (slinks[pr.first].end - slinks[pr.first].begin);
      const SphereLink& A = slinks[pr.first];
      const SphereLink& B = slinks[pr.second];
      const double* ca = bound(pr.first);
      const double* cb = bound(pr.second);
      const double dl = std::sqrt((ca[0] - cb[0]) * (ca[0] - cb[0]) + (ca[1] - cb[1]) * (ca[1] - cb[1]) +
                                  (ca[2] - cb[2]) * (ca[2] - cb[2])) -
                        A.br - B.br;
      const double vl = m.PDl[2 * p] + m.PDl[2 * p + 1];
      if (dl > 0.0 && dl >= step * vl) {
        m.self_free[p] = FreeUntil(s, dl, vl);
        continue;
      }
      place(pr.first);
      place(pr.second);
      double* sphere_free = m.self_sphere_free.data() + self_pair_grid[p];
      double until = kInf;
      for (int i = A.begin; i < A.end; ++i) {
        const double* xi = &w[3 * i];
        for (int k = B.begin; k < B.end; ++k, ++sphere_free) {
          if (*sphere_free < s + step) {
            const double* xk = &w[3 * k];
            const double e0 = xi[0] - xk[0], e1 = xi[1] - xk[1], e2 = xi[2] - xk[2];
            // Self pairs are unpadded (padding keeps the robot from the scene only).
            const double d = std::sqrt(e0 * e0 + e1 * e1 + e2 * e2) - sr[i] - sr[k] + 2.0 * options.padding;
            if (d <= 0.0) return false;
            const double v = pa[i - A.begin] + pb[k - B.begin];
            if (d < step * v) step = d / v;
            *sphere_free = FreeUntil(s, d, v);
          }
          until = std::min(until, *sphere_free);
        }
      }
      m.self_free[p] = until;
    }
    // Occupancy grids: a lower bound m on the clearance — the sphere grown by m misses every
    // occupied voxel — halving m from the last margin that held until it does.
    for (const SceneGeom& g : scene_geoms) {
      const detail::OccupancyGrid& grid = grids[g.grid];  // certifiable: every geom is a grid
      if (grid.num_blocks() == 0) continue;
      const double* gc = grid.center().data();
      const UnitSet* allowed = Allowed(g.allowed);
      for (std::size_t li = 0; li < nl; ++li) {
        if (allowed != nullptr && allowed->Has(li)) continue;
        const SphereLink& L = slinks[li];
        const double* c = bound(li);
        const double dg = std::sqrt((c[0] - gc[0]) * (c[0] - gc[0]) + (c[1] - gc[1]) * (c[1] - gc[1]) +
                                    (c[2] - gc[2]) * (c[2] - gc[2])) -
                          L.br - grid.radius();
        if (dg > 0.0 && dg >= step * Dl[li]) continue;
        if (Dl[li] > 0.0) {
          const double ml = std::min(step * Dl[li], kMaxLinkGridMargin);
          if (!grid.SphereHits(c, L.br + ml)) {
            if (ml < step * Dl[li]) step = ml / Dl[li];
            continue;
          }
        }
        place(li);
        for (int k = L.begin; k < L.end; ++k) {
          const double* x = &w[3 * k];
          const double need = step * D[k];
          if (need <= 0.0) {  // this sphere does not move
            if (grid.SphereHits(x, sr[k])) return false;
            continue;
          }
          double& last = m.margin[static_cast<std::size_t>(g.grid) * ns + k];
          double mk = std::min(need, 2.0 * last);
          while (grid.SphereHits(x, sr[k] + mk)) {
            if (mk < kMinGridMargin) {
              if (grid.SphereHits(x, sr[k])) return false;
              mk = 0.0;
              break;
            }
            mk *= 0.5;
          }
          last = std::max(mk, kMinGridMargin);
          if (mk < need) step = mk / D[k];
        }
      }
    }
    if (step >= 1.0 - s) return true;  // [s, 1] is clear
    if (!(step >= kMinCertifiedStep)) return false;  // grazing (or NaN): reject conservatively
    s += step;
    if (s >= 1.0) return true;
  }
}

void CollisionChecker::Impl::BuildFk() {
  fk = detail::BuildFkProgram(*robot);
  num_links = fk.num_links;
}

void CollisionChecker::Impl::ComputeFk(const Eigen::VectorXd& q, Frame* frames) const {
  detail::ComputeFk(simd, fk, q, frames);
}

bool CollisionChecker::Impl::FastCollide(const Frame* frames, CollisionResult* report) const {
  const std::size_t ns = sx.size();
  const std::size_t nl = slinks.size();
  const std::size_t padded = detail::CullPadded(nl);
  Scratch<double, 1024> w(3 * ns);        // world sphere centres, filled per link on first use
  Scratch<double, 256> lb(3 * nl);        // world link bounding centres
  Scratch<double, 256> soa(3 * padded);   // the same as structure of arrays, for the cull
  Scratch<char, 256> placed(nl);          // whether link li's sphere centres are in `w`
  double* const bx = &soa[0];
  double* const by = bx + padded;
  double* const bz = by + padded;
  PlaceLinkBounds(frames, &lb[0], &placed[0]);
  LinkBoundsSoa(&lb[0], kInf, bx);  // padding lanes at +inf overlap nothing
  const double* const br = link_bound_radius.data();
  const auto place = [&](std::size_t li) { PlaceLinkSpheres(frames, li, &w[0], &placed[0]); };
  const auto hit = [&](int link, const std::string& other, bool self) {
    if (report != nullptr) {
      report->in_collision = true;
      report->self_collision = self;
      report->link_a = robot->links()[link].name;
      report->other = other;
    }
    return true;
  };
  // Robot vs scene primitives. The link-bound vs obstacle-bound cull (sphere_cull.h) gives, per
  // primitive, a bit mask over (up to) 64 links at a time; only the set bits are visited, in
  // link order.
  const std::size_t nprims = prims.size();
  const std::size_t chunks = (nl + 63) / 64;
  Scratch<std::uint64_t, 256> masks(std::max(nprims, nl) * chunks);
  const auto link_chunk = [&](std::size_t chunk) {
    const std::size_t base = 64 * chunk;
    return detail::CullSpheres{bx + base, by + base, bz + base, br + base, std::min<std::size_t>(64, nl - base)};
  };
  for (std::size_t chunk = 0; chunk < chunks; ++chunk) {
    detail::OverlapMasks(simd, link_chunk(chunk), prim_x.data(), prim_y.data(), prim_z.data(),
                         prim_bound.data(), nprims, &masks[chunk * nprims]);
  }
  for (std::size_t oi = 0; oi < nprims; ++oi) {
    const Prim& o = prims[oi];
    for (std::size_t chunk = 0; chunk < chunks; ++chunk) {
      const std::size_t base = 64 * chunk;
      std::uint64_t mask = masks[chunk * nprims + oi];
      if (o.allowed >= 0) mask &= ~allowed_sets[o.allowed].words[chunk];
      while (mask != 0) {
        const std::size_t li = base + static_cast<std::size_t>(__builtin_ctzll(mask));
        mask &= mask - 1;
        const SphereLink& L = slinks[li];
        if (!SphereHits(o, &lb[3 * li], L.br)) continue;
        place(li);
        for (int k = L.begin; k < L.end; ++k) {
          if (SphereHits(o, &w[3 * k], sr[k])) return hit(L.link, scene->objects()[o.object].name, false);
        }
      }
    }
  }
  // A mesh, or a map too large to grid, through FCL, robot spheres as fcl::Sphered.
  const auto fcl_geom_hit = [&](const SceneGeom& g) {
    fcl::CollisionRequestd request;
    const UnitSet* allowed = Allowed(g.allowed);
    for (std::size_t li = 0; li < nl; ++li) {
      if (allowed != nullptr && allowed->Has(li)) continue;
      const SphereLink& L = slinks[li];
      const Eigen::Vector3d c(lb[3 * li], lb[3 * li + 1], lb[3 * li + 2]);
      if (!SpheresOverlap(c, L.br, g.center, g.radius)) continue;
      if (L.end - L.begin > 1) {  // one query with the link's bounding sphere first
        fcl::Transform3d tf = fcl::Transform3d::Identity();
        tf.translation() = c;
        fcl::CollisionResultd result;
        if (fcl::collide(fcl_link_bounds[li].get(), tf, g.g.geom.get(), g.tf, request, result) == 0) continue;
      }
      place(li);
      for (int k = L.begin; k < L.end; ++k) {
        const Eigen::Vector3d x(w[3 * k], w[3 * k + 1], w[3 * k + 2]);
        if (!SpheresOverlap(x, sr[k], g.center, g.radius)) continue;
        fcl::Transform3d tf = fcl::Transform3d::Identity();
        tf.translation() = x;
        fcl::CollisionResultd result;
        if (fcl::collide(fcl_spheres[k].get(), tf, g.g.geom.get(), g.tf, request, result) > 0) {
          return hit(L.link, g.name, false);
        }
      }
    }
    return false;
  };
  // Occupancy maps, in scene order: link bounding sphere against the map's bound, then against
  // the voxel grid, then every sphere of the link.
  for (const SceneGeom& g : scene_geoms) {
    if (!g.octree) continue;
    if (g.grid < 0) {
      if (fcl_geom_hit(g)) return true;
      continue;
    }
    const detail::OccupancyGrid& grid = grids[g.grid];
    if (grid.num_blocks() == 0) continue;
    const double* gc = grid.center().data();
    const UnitSet* allowed = Allowed(g.allowed);
    for (std::size_t li = 0; li < nl; ++li) {
      if (allowed != nullptr && allowed->Has(li)) continue;
      const SphereLink& L = slinks[li];
      const double* c = &lb[3 * li];
      const double d0 = c[0] - gc[0], d1 = c[1] - gc[1], d2 = c[2] - gc[2];
      const double rr = L.br + grid.radius();
      if (d0 * d0 + d1 * d1 + d2 * d2 > rr * rr) continue;
      if (L.end - L.begin > 1 && !grid.SphereHits(c, L.br)) continue;
      place(li);
      for (int k = L.begin; k < L.end; ++k) {
        if (grid.SphereHits(&w[3 * k], sr[k])) return hit(L.link, g.name, false);
      }
    }
  }
  // Self collision, pair by pair in self_pairs order: the same cull of every link against
  // every link, masked to the pairs (a, b) that are checked.
  if (!self_pairs.empty()) {
    for (std::size_t chunk = 0; chunk < chunks; ++chunk) {
      detail::OverlapMasks(simd, link_chunk(chunk), bx, by, bz, br, nl, &masks[chunk * nl]);
    }
  }
  for (std::size_t a = 0; a < nl && !self_pairs.empty(); ++a) {
    const SphereLink& A = slinks[a];
    for (std::size_t chunk = 0; chunk < chunks; ++chunk) {
      std::uint64_t mask = self_masks[a * chunks + chunk] & masks[chunk * nl + a];
      while (mask != 0) {
        const std::size_t b = 64 * chunk + static_cast<std::size_t>(__builtin_ctzll(mask));
        mask &= mask - 1;
        const SphereLink& B = slinks[b];
        const double* cb = &lb[3 * b];
        place(a);
        place(b);
        for (int i = A.begin; i < A.end; ++i) {
          const double* xi = &w[3 * i];
          // Cull sphere i against B's bounding sphere first.
          const double f0 = xi[0] - cb[0], f1 = xi[1] - cb[1], f2 = xi[2] - cb[2];
          const double rb = sr[i] + B.br;
          if (f0 * f0 + f1 * f1 + f2 * f2 > rb * rb) continue;
          for (int k = B.begin; k < B.end; ++k) {
            const double* xk = &w[3 * k];
            const double e0 = xi[0] - xk[0], e1 = xi[1] - xk[1], e2 = xi[2] - xk[2];
            const double r = sr[i] + sr[k] - 2.0 * options.padding;  // the unpadded spheres
            if (e0 * e0 + e1 * e1 + e2 * e2 <= r * r) {
              return hit(A.link, robot->links()[B.link].name, true);
            }
          }
        }
      }
    }
  }
  // Meshes through FCL.
  for (const SceneGeom& g : scene_geoms) {
    if (!g.octree && fcl_geom_hit(g)) return true;
  }
  return false;
}

double CollisionChecker::Impl::FastClearance(const Frame* frames) const {
  const std::size_t ns = sx.size();
  const std::size_t nl = slinks.size();
  Scratch<double, 1024> w(3 * ns);
  Scratch<double, 256> lb(3 * nl);
  Scratch<char, 256> placed(nl);
  PlaceLinkBounds(frames, &lb[0], &placed[0]);
  double best = kInf;
  // A link's bounding sphere is at most as far from an obstacle as any of its spheres, so a
  // (link, primitive) pair whose bound is no closer than the best distance so far cannot lower
  // it. Branch and bound: the pair with the smallest bound first (it sets a tight `best`), then
  // every other pair whose bound is below `best`.
  // The bounds, one primitive against every link at once (primitives.h), in pair p·padded + li.
  const std::size_t np = prims.size();
  const std::size_t padded = detail::CullPadded(nl);
  Scratch<double, 256> soa(3 * padded);  // link bounding centres, structure of arrays
  LinkBoundsSoa(&lb[0], 0.0, &soa[0]);    // padding lanes finite (their distances are not read)
  Scratch<double, 1024> bound(np * padded);
  std::size_t first = 0;
  for (std::size_t p = 0; p < np; ++p) {
    double* b = &bound[p * padded];
    detail::SphereDistances(simd, prims[p], &soa[0], &soa[padded], &soa[2 * padded], link_bound_radius.data(), nl, b);
    const UnitSet* allowed = Allowed(prims[p].allowed);
    for (std::size_t li = 0; li < nl; ++li) {
      if (allowed != nullptr && allowed->Has(li)) b[li] = kInf;
      if (b[li] < bound[first]) first = p * padded + li;
    }
  }
  const auto exact = [&](std::size_t pair) {
    const Prim& o = prims[pair / padded];
    const std::size_t li = pair % padded;
    const SphereLink& L = slinks[li];
    PlaceLinkSpheres(frames, li, &w[0], &placed[0]);
    for (int k = L.begin; k < L.end; ++k) best = std::min(best, SphereDistance(o, &w[3 * k], sr[k]));
  };
  if (nl * np > 0 && bound[first] < kInf) exact(first);
  for (std::size_t p = 0; p < np; ++p) {
    for (std::size_t li = 0; li < nl; ++li) {
      const std::size_t pair = p * padded + li;
      if (pair != first && bound[pair] < best) exact(pair);
    }
  }
  if (!scene_geoms.empty()) {
    for (std::size_t li = 0; li < nl; ++li) PlaceLinkSpheres(frames, li, &w[0], &placed[0]);
    fcl::DistanceRequestd request;
    for (const SceneGeom& g : scene_geoms) {
      const UnitSet* allowed = Allowed(g.allowed);
      for (std::size_t k = 0; k < ns; ++k) {
        if (allowed != nullptr && allowed->Has(slink_of[k])) continue;
        const Eigen::Vector3d x(w[3 * k], w[3 * k + 1], w[3 * k + 2]);
        // Lower bound from the bounding spheres: skip when it cannot improve on `best`.
        if ((x - g.center).norm() - sr[k] - g.radius >= best) continue;
        fcl::Transform3d tf = fcl::Transform3d::Identity();
        tf.translation() = x;
        fcl::DistanceResultd result;
        const double d = fcl::distance(fcl_spheres[k].get(), tf, g.g.geom.get(), g.tf, request, result);
        best = std::min(best, d);
      }
    }
  }
  return best <= 0.0 ? 0.0 : best;
}

bool CollisionChecker::Impl::FclCollide(const Frame* frames, CollisionResult* report) const {
  const std::size_t n = shapes.size();
  Scratch<fcl::Transform3d, 128> tf(n);
  Scratch<Eigen::Vector3d, 128> center(n);
  for (std::size_t i = 0; i < n; ++i) {
    tf[i] = ToIsometry(frames[shapes[i].link]) * shapes[i].local;
    center[i] = tf[i] * shapes[i].g.center;
  }
  const double pad = options.padding;
  const auto pair_hits = [&](const fcl::CollisionGeometryd* a, const fcl::Transform3d& ta,
                             const fcl::CollisionGeometryd* b, const fcl::Transform3d& tb) {
    if (pad > 0.0) {
      fcl::DistanceRequestd request;
      fcl::DistanceResultd result;
      return fcl::distance(a, ta, b, tb, request, result) <= pad;
    }
    fcl::CollisionRequestd request;
    fcl::CollisionResultd result;
    return fcl::collide(a, ta, b, tb, request, result) > 0;
  };
  const auto hit = [&](int link, const std::string& other, bool self) {
    if (report != nullptr) {
      report->in_collision = true;
      report->self_collision = self;
      report->link_a = robot->links()[link].name;
      report->other = other;
    }
    return true;
  };
  for (const SceneGeom& g : scene_geoms) {
    const UnitSet* allowed = Allowed(g.allowed);
    for (std::size_t i = 0; i < n; ++i) {
      if (allowed != nullptr && allowed->Has(shapes[i].link)) continue;
      if (!SpheresOverlap(center[i], shapes[i].g.radius + pad, g.center, g.radius)) continue;
      if (pair_hits(shapes[i].g.geom.get(), tf[i], g.g.geom.get(), g.tf)) {
        return hit(shapes[i].link, g.name, false);
      }
    }
  }
  for (const auto& pr : shape_pairs) {
    const RobotShape& a = shapes[pr.first];
    const RobotShape& b = shapes[pr.second];
    if (!SpheresOverlap(center[pr.first], a.g.radius + pad, center[pr.second], b.g.radius + pad)) continue;
    // Self pairs are checked on the unpadded shapes (padding keeps the robot from the scene).
    fcl::CollisionRequestd request;
    fcl::CollisionResultd result;
    if (fcl::collide(a.g.geom.get(), tf[pr.first], b.g.geom.get(), tf[pr.second], request, result) > 0) {
      return hit(a.link, robot->links()[b.link].name, true);
    }
  }
  return false;
}

double CollisionChecker::Impl::FclClearance(const Frame* frames) const {
  double best = kInf;
  fcl::DistanceRequestd request;
  for (const RobotShape& s : shapes) {
    const fcl::Transform3d tf = ToIsometry(frames[s.link]) * s.local;
    const Eigen::Vector3d c = tf * s.g.center;
    for (const SceneGeom& g : scene_geoms) {
      if (g.allowed >= 0 && allowed_sets[g.allowed].Has(s.link)) continue;
      if ((c - g.center).norm() - s.g.radius - g.radius - options.padding >= best) continue;
      fcl::DistanceResultd result;
      const double d = fcl::distance(s.g.geom.get(), tf, g.g.geom.get(), g.tf, request, result);
      best = std::min(best, d - options.padding);
    }
  }
  return best <= 0.0 ? 0.0 : best;
}

bool CollisionChecker::Impl::Collide(const Eigen::VectorXd& q, CollisionResult* report) const {
  Scratch<Frame, 64> frames(num_links);
  ComputeFk(q, &frames[0]);
  return fast ? FastCollide(&frames[0], report) : FclCollide(&frames[0], report);
}

namespace {

/// At most 20 names joined by ", ", then how many more; "none" when there are none.
template <typename Range, typename Name>
std::string NameList(const Range& items, Name name) {
  constexpr std::size_t kMaxNames = 20;
  std::string out;
  std::size_t n = 0;
  for (const auto& item : items) {
    if (n++ < kMaxNames) out += (out.empty() ? "" : ", ") + name(item);
  }
  if (n > kMaxNames) out += ", … (" + std::to_string(n - kMaxNames) + " more)";
  return n == 0 ? "none" : out;
}

/// The scene's allowed pairs resolved against a robot.
struct SceneAllowances {
  std::vector<char> self;                       // num_links² (1 = allowed); empty when no link–link pair
  std::vector<std::vector<char>> objects, maps;  // per scene object / map: links (1/0); empty = none
};

SceneAllowances ResolveSceneAllowances(const RobotModel& robot, const Scene& scene) {
  SceneAllowances out;
  const std::vector<AllowedCollision>& pairs = scene.allowed_collisions();
  if (pairs.empty()) return out;
  const int nl = robot.num_links();
  out.objects.resize(scene.objects().size());
  out.maps.resize(scene.occupancy_maps().size());
  const auto links = [&] { return NameList(robot.links(), [](const Link& l) { return l.name; }); };
  const auto obstacles = [&] {
    return "scene objects: " + NameList(scene.objects(), [](const SceneObject& o) { return o.name; }) +
           "; OctoMaps: " + NameList(scene.occupancy_maps(), [](const OccupancyMap& m) { return m.name; });
  };
  const auto allow = [nl](std::vector<char>* obstacle_links, int link) {
    if (obstacle_links->empty()) obstacle_links->assign(nl, 0);
    (*obstacle_links)[link] = 1;
  };
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const std::string field = "scene.allowed_collisions[" + std::to_string(i) + "]";
    const AllowedCollision& pair = pairs[i];
    const int a = robot.FindLink(pair.link);
    if (a < 0) {
      bool obstacle = false;
      for (const SceneObject& o : scene.objects()) obstacle = obstacle || o.name == pair.link;
      for (const OccupancyMap& m : scene.occupancy_maps()) obstacle = obstacle || m.name == pair.link;
      ThrowInvalid(field + ".link1 = '" + pair.link + "' is not a link of robot '" + robot.name() + "' (links: " +
                   links() + ")" +
                   (obstacle ? "; it names an obstacle of the scene: link1 must be the robot link, link2 the obstacle"
                             : ""));
    }
    bool found = false;
    const int b = robot.FindLink(pair.other);
    if (b >= 0) {
      if (out.self.empty()) out.self.assign(static_cast<std::size_t>(nl) * nl, 0);
      out.self[static_cast<std::size_t>(a) * nl + b] = out.self[static_cast<std::size_t>(b) * nl + a] = 1;
      found = true;
    }
    for (std::size_t j = 0; j < scene.objects().size(); ++j) {
      if (scene.objects()[j].name != pair.other) continue;
      allow(&out.objects[j], a);
      found = true;
    }
    for (std::size_t j = 0; j < scene.occupancy_maps().size(); ++j) {
      if (scene.occupancy_maps()[j].name != pair.other) continue;
      allow(&out.maps[j], a);
      found = true;
    }
    if (!found) {
      ThrowInvalid(field + ".link2 = '" + pair.other + "' is neither a link of robot '" + robot.name() +
                   "' nor an object or OctoMap of the scene (links: " + links() + "; " + obstacles() + ")");
    }
  }
  return out;
}

}  // namespace

CollisionChecker::CollisionChecker(std::shared_ptr<const RobotModel> robot, std::shared_ptr<const Scene> scene,
                                   CollisionOptions options)
    : robot_(std::move(robot)), scene_(std::move(scene)), impl_(std::make_unique<Impl>()) {
  if (!robot_) ThrowInvalid("collision checker: robot is null");
  if (!scene_) scene_ = std::make_shared<Scene>();
  options.Validate();
  Impl& m = *impl_;
  m.robot = robot_.get();
  m.scene = scene_.get();
  m.options = options;
  m.BuildFk();
  const double pad = options.padding;
  const auto& links = robot_->links();
  const int num_links = robot_->num_links();
  const AllowedCollisionMatrix& acm = robot_->allowed_collisions();
  const SceneAllowances scene_allowed = ResolveSceneAllowances(*robot_, *scene_);
  const auto allowed = [&](int a, int b) {
    return a == b || (acm.num_links() == num_links && acm.IsAllowed(a, b)) ||
           (!scene_allowed.self.empty() && scene_allowed.self[static_cast<std::size_t>(a) * num_links + b]);
  };

  bool all_spheres = true;
  for (const Link& l : links) {
    for (const Shape& s : l.collision) all_spheres = all_spheres && s.type == ShapeType::kSphere;
  }
  m.fast = all_spheres && !options.force_fcl;

  // Robot geometry and self pairs.
  if (m.fast) {
    for (int l = 0; l < num_links; ++l) {
      const auto& shapes = links[l].collision;
      if (shapes.empty()) continue;
      SphereLink L;
      L.link = l;
      L.begin = static_cast<int>(m.sx.size());
      Eigen::Vector3d lo = Eigen::Vector3d::Constant(kInf), hi = Eigen::Vector3d::Constant(-kInf);
      for (const Shape& s : shapes) {
        const Eigen::Vector3d c = s.pose.translation();
        m.sx.push_back(c.x());
        m.sy.push_back(c.y());
        m.sz.push_back(c.z());
        m.sr.push_back(s.radius + pad);
        m.slink_of.push_back(static_cast<int>(m.slinks.size()));
        m.fcl_spheres.push_back(std::make_shared<fcl::Sphered>(s.radius + pad));
        lo = lo.cwiseMin(c);
        hi = hi.cwiseMax(c);
      }
      L.end = static_cast<int>(m.sx.size());
      const Eigen::Vector3d bc = 0.5 * (lo + hi);
      double br = 0.0;
      for (int k = L.begin; k < L.end; ++k) {
        br = std::max(br, (Eigen::Vector3d(m.sx[k], m.sy[k], m.sz[k]) - bc).norm() + m.sr[k]);
      }
      for (int i = 0; i < 3; ++i) L.bc[i] = bc[i];
      L.br = br;
      m.slinks.push_back(L);
      m.link_bound_radius.push_back(br);
      m.fcl_link_bounds.push_back(std::make_shared<fcl::Sphered>(br));
    }
    const std::size_t nl = m.slinks.size();
    m.link_bound_radius.resize(detail::CullPadded(nl), 0.0);
    const std::size_t words = (nl + 63) / 64;
    m.self_masks.assign(nl * words, 0);
    for (std::size_t a = 0; a < nl; ++a) {
      for (std::size_t b = a + 1; b < nl; ++b) {
        if (allowed(m.slinks[a].link, m.slinks[b].link)) continue;
        m.self_pairs.emplace_back(a, b);
        m.self_masks[a * words + b / 64] |= std::uint64_t{1} << (b % 64);
      }
    }
    m.BuildLevers();
  } else {
    for (int l = 0; l < num_links; ++l) {
      for (const Shape& s : links[l].collision) {
        RobotShape r;
        r.link = l;
        r.g = MakeGeom(s);
        r.local = s.pose;
        m.shapes.push_back(std::move(r));
      }
    }
    for (std::size_t a = 0; a < m.shapes.size(); ++a) {
      for (std::size_t b = a + 1; b < m.shapes.size(); ++b) {
        if (!allowed(m.shapes[a].link, m.shapes[b].link)) m.shape_pairs.emplace_back(a, b);
      }
    }
  }

  // The links an obstacle may touch as a set over the units the checks iterate (sphere links
  // or links with geometry): -1 when none of them, kAllUnits when all of them (the obstacle
  // cannot collide and does not limit clearance, so it is left out).
  constexpr int kAllUnits = -2;
  const auto allowed_set = [&](const std::vector<std::vector<char>>& per_obstacle, std::size_t i) {
    if (per_obstacle.empty() || per_obstacle[i].empty()) return -1;
    const std::vector<char>& by_link = per_obstacle[i];
    const std::size_t units = m.fast ? m.slinks.size() : static_cast<std::size_t>(num_links);
    UnitSet set;
    set.words.assign((units + 63) / 64, 0);
    bool any = false, all = true;
    for (std::size_t u = 0; u < units; ++u) {
      const int link = m.fast ? m.slinks[u].link : static_cast<int>(u);
      if (!m.fast && links[link].collision.empty()) continue;
      if (by_link[link]) {
        set.words[u >> 6] |= std::uint64_t{1} << (u & 63);
        any = true;
      } else {
        all = false;
      }
    }
    if (all) return kAllUnits;
    if (!any) return -1;
    m.allowed_sets.push_back(std::move(set));
    return static_cast<int>(m.allowed_sets.size()) - 1;
  };

  // Scene objects: primitives on the fast path, FCL geometry otherwise (and for meshes).
  for (std::size_t oi = 0; oi < scene_->objects().size(); ++oi) {
    const SceneObject& o = scene_->objects()[oi];
    const int allowed_links = allowed_set(scene_allowed.objects, oi);
    if (allowed_links == kAllUnits) continue;
    if (m.fast && o.shape.type != ShapeType::kMesh) {
      const Shape& s = o.shape;
      Prim p{};
      p.object = static_cast<int>(oi);
      p.allowed = allowed_links;
      ToRowMajor(s.pose.linear().transpose(), p.rt);
      for (int i = 0; i < 3; ++i) p.p[i] = s.pose.translation()[i];
      switch (s.type) {
        case ShapeType::kSphere:
          p.kind = kPrimSphere;
          p.a = s.radius;
          p.bound = s.radius;
          break;
        case ShapeType::kBox:
          p.kind = kPrimBox;
          p.a = 0.5 * s.size.x();
          p.b = 0.5 * s.size.y();
          p.c = 0.5 * s.size.z();
          p.bound = 0.5 * s.size.norm();
          break;
        case ShapeType::kCylinder:
          p.kind = kPrimCylinder;
          p.a = s.radius;
          p.b = 0.5 * s.length;
          p.bound = std::hypot(p.a, p.b);
          break;
        default:
          p.kind = kPrimCapsule;
          p.a = s.radius;
          p.b = 0.5 * s.length;
          p.bound = p.a + p.b;
          break;
      }
      m.prims.push_back(p);
      m.prim_x.push_back(p.p[0]);
      m.prim_y.push_back(p.p[1]);
      m.prim_z.push_back(p.p[2]);
      m.prim_bound.push_back(p.bound);
      continue;
    }
    SceneGeom g;
    g.name = o.name;
    g.g = MakeGeom(o.shape);
    g.pose = o.shape.pose;
    g.tf = o.shape.pose;
    g.center = g.pose * g.g.center;
    g.radius = g.g.radius;
    g.allowed = allowed_links;
    m.scene_geoms.push_back(std::move(g));
  }
  for (std::size_t mi = 0; mi < scene_->occupancy_maps().size(); ++mi) {
    const OccupancyMap& map = scene_->occupancy_maps()[mi];
    const int allowed_links = allowed_set(scene_allowed.maps, mi);
    if (allowed_links == kAllUnits) continue;
    SceneGeom g;
    g.name = map.name;
    g.octree = true;
    g.allowed = allowed_links;
    g.g.geom = std::make_shared<fcl::OcTreed>(map.tree);
    // Bound only the occupied leaves (the tree's root box is far larger).
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(kInf), hi = Eigen::Vector3d::Constant(-kInf);
    for (auto it = map.tree->begin_leafs(), end = map.tree->end_leafs(); it != end; ++it) {
      if (!map.tree->isNodeOccupied(*it)) continue;
      const double h = 0.5 * it.getSize();
      const Eigen::Vector3d c(it.getX(), it.getY(), it.getZ());
      lo = lo.cwiseMin(c - Eigen::Vector3d::Constant(h));
      hi = hi.cwiseMax(c + Eigen::Vector3d::Constant(h));
    }
    if (!(lo.array() <= hi.array()).all()) continue;  // nothing occupied: no obstacle
    g.pose = map.pose;
    g.tf = map.pose;
    g.center = map.pose * (0.5 * (lo + hi));
    g.radius = 0.5 * (hi - lo).norm();
    if (m.fast) {
      detail::OccupancyGrid grid;
      switch (grid.Build(*map.tree, map.pose)) {
        // g.center/g.radius keep bounding every occupied leaf: Clearance's fcl::distance
        // traversal may reach leaves the collision traversal (and so the grid) does not.
        case detail::OccupancyGrid::Status::kBuilt:
        case detail::OccupancyGrid::Status::kEmpty:  // FCL's collision traversal reaches no obstacle
          g.grid = static_cast<int>(m.grids.size());
          m.grids.push_back(std::move(grid));
          break;
        case detail::OccupancyGrid::Status::kTooLarge:  // stays on FCL
          break;
      }
    }
    m.scene_geoms.push_back(std::move(g));
  }

  if (m.fast) {
    m.certifiable = true;
    for (const SceneGeom& g : m.scene_geoms) m.certifiable = m.certifiable && g.octree && g.grid >= 0;
  }
}

CollisionChecker::~CollisionChecker() = default;

bool CollisionChecker::uses_fast_path() const { return impl_->fast; }

int CollisionChecker::num_gridded_occupancy_maps() const { return static_cast<int>(impl_->grids.size()); }

namespace {
void CheckSize(const RobotModel& robot, const Eigen::VectorXd& q, const char* field) {
  if (q.size() != robot.num_dofs()) {
    ThrowInvalid(std::string(field) + " has " + std::to_string(q.size()) + " values, robot '" +
                 robot.name() + "' has " + std::to_string(robot.num_dofs()) + " joints");
  }
}

bool WithinLimits(const RobotModel& robot, const Eigen::VectorXd& q) {
  const Eigen::VectorXd& lo = robot.lower_limits();
  const Eigen::VectorXd& hi = robot.upper_limits();
  for (Eigen::Index i = 0; i < q.size(); ++i) {
    if (!(q[i] >= lo[i] && q[i] <= hi[i])) return false;  // NaN fails too
  }
  return true;
}
}  // namespace

bool CollisionChecker::IsValid(const Eigen::VectorXd& q, CheckCounters* counters) const {
  CheckSize(*robot_, q, "q");
  if (counters != nullptr) ++counters->state_checks;
  if (!WithinLimits(*robot_, q)) return false;
  return !impl_->Collide(q, nullptr);
}

CollisionResult CollisionChecker::Check(const Eigen::VectorXd& q) const {
  CheckSize(*robot_, q, "q");
  CollisionResult result;
  impl_->Collide(q, &result);
  return result;
}

bool CollisionChecker::IsMotionValid(const Eigen::VectorXd& a, const Eigen::VectorXd& b, double max_step,
                                     CheckCounters* counters) const {
  CheckSize(*robot_, a, "a");
  CheckSize(*robot_, b, "b");
  if (!std::isfinite(max_step) || max_step <= 0.0) {
    std::ostringstream os;
    os << "max_step = " << max_step << " must be finite and > 0";
    ThrowInvalid(os.str());
  }
  // Order: b, then a (both with joint limits), then the interior states (inside the limits
  // because the joint-limit box is convex) coarse to fine: all odd multiples of the largest
  // power-of-two stride first, then of half that stride, and so on — a bisection order that
  // needs no queue.
  if (!IsValid(b, counters) || !IsValid(a, counters)) return false;
  const double span = (b - a).cwiseAbs().maxCoeff();
  if (!std::isfinite(span)) return false;
  const double steps = std::ceil(span / max_step);
  if (steps > 1e9) ThrowInvalid("motion needs more than 1e9 checks at max_step; raise max_step");
  const long n = std::max(1L, static_cast<long>(steps));
  long stride = 1;
  while (stride < n) stride <<= 1;
  Eigen::VectorXd q(a.size());
  for (stride >>= 1; stride >= 1; stride >>= 1) {
    for (long i = stride; i < n; i += 2 * stride) {
      const double t = static_cast<double>(i) / static_cast<double>(n);
      q = a + t * (b - a);
      if (counters != nullptr) ++counters->state_checks;
      if (impl_->Collide(q, nullptr)) return false;
    }
  }
  return true;
}

bool CollisionChecker::certifies_motion() const { return impl_->certifiable; }

bool CollisionChecker::IsMotionCertified(const Eigen::VectorXd& a, const Eigen::VectorXd& b,
                                         CheckCounters* counters) const {
  CheckSize(*robot_, a, "a");
  CheckSize(*robot_, b, "b");
  if (!impl_->certifiable) return IsMotionValid(a, b, 0.005, counters);
  if (!IsValid(b, counters) || !IsValid(a, counters)) return false;
  // The straight segment as a curve: IsCurveCertified's probes, then the advancement (a and b
  // are finite here, inside the limits).
  const Eigen::VectorXd delta = b - a;
  return IsCurveCertified([&](double s, Eigen::VectorXd* q) { *q = a + s * delta; }, delta.cwiseAbs(), counters);
}

bool CollisionChecker::IsCurveCertified(const Curve& curve, const Eigen::VectorXd& speed_bound,
                                        CheckCounters* counters) const {
  CheckSize(*robot_, speed_bound, "speed_bound");
  for (int i = 0; i < speed_bound.size(); ++i) {
    if (!std::isfinite(speed_bound[i]) || speed_bound[i] < 0.0) {
      ThrowInvalid("speed_bound[" + std::to_string(i) + "] = " + FormatNumber(speed_bound[i]) +
                   " must be finite and >= 0");
    }
  }
  if (impl_->certifiable) {
    // Probes first, in bisection order, until they are at most kProbeSpacing apart in every
    // joint (by the speed bound), so a curve through an obstacle is rejected here rather than by
    // the advancement creeping up to the contact. Shorter curves get none: they mostly certify
    // (verification spans, shortcut pieces), where probes are pure overhead.
    const double span = speed_bound.maxCoeff();
    Eigen::VectorXd q(robot_->num_dofs());
    for (int level = 1; level <= kMaxProbeDepth && span / (1 << (level - 1)) > kProbeSpacing; ++level) {
      const int n = 1 << level;
      for (int i = 1; i < n; i += 2) {
        curve(static_cast<double>(i) / n, &q);
        if (counters != nullptr) ++counters->state_checks;
        if (!q.allFinite() || impl_->Collide(q, nullptr)) return false;
      }
    }
    return impl_->CertifiedCurve(curve, speed_bound, counters);
  }
  // Discrete fallback: states no more than 0.005 apart in every joint, in order.
  const double span = speed_bound.maxCoeff();
  const double steps = std::ceil(span / 0.005);
  if (steps > 1e9) ThrowInvalid("curve needs more than 1e9 checks at 0.005; split it");
  const long n = std::max(1L, static_cast<long>(steps));
  Eigen::VectorXd q(robot_->num_dofs());
  for (long i = 0; i <= n; ++i) {
    curve(static_cast<double>(i) / static_cast<double>(n), &q);
    if (counters != nullptr) ++counters->state_checks;
    if (!q.allFinite() || impl_->Collide(q, nullptr)) return false;
  }
  return true;
}

std::vector<double> CollisionChecker::SweepBounds(const Eigen::VectorXd& a, const Eigen::VectorXd& b) const {
  CheckSize(*robot_, a, "a");
  CheckSize(*robot_, b, "b");
  if (!impl_->certifiable) return {};
  std::vector<double> out(impl_->sx.size());
  impl_->SweepBounds((b - a).cwiseAbs(), out.data());
  return out;
}

double CollisionChecker::Clearance(const Eigen::VectorXd& q) const {
  CheckSize(*robot_, q, "q");
  Scratch<Frame, 64> frames(impl_->num_links);
  impl_->ComputeFk(q, &frames[0]);
  return impl_->fast ? impl_->FastClearance(&frames[0]) : impl_->FclClearance(&frames[0]);
}

const CollisionOptions& CollisionChecker::options() const { return impl_->options; }

}  // namespace chasles
