#include "chasles/collision/collision_checker.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iterator>
#include <limits>
#include <memory>
#include <sstream>
#include <vector>

#include <Eigen/Eigenvalues>
#include <fcl/fcl.h>
#include <fcl/geometry/octree/octree.h>
#include <octomap/OcTree.h>

#include "chasles/robot/error.h"
#include "checker_impl.h"
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
// * Broad phase (broad_phase.h, CollisionOptions::broad_phase): with more than 32 primitives a
//   static BVH over their bounding spheres is built with the checker. A state check gathers the
//   primitives whose bound's box overlaps the box around the link bounds (a superset of those
//   the cull would pass, in scene order, so the same first contact); the advancement cuts a
//   motion into chunks of at most 0.2 m of sweep and gathers, per chunk, those near the link
//   bounds grown by D_l times the chunk's length (no other can limit a step that ends by the
//   chunk's end, and steps are cut there); Clearance searches within 0.25 m of the link
//   bounds, then 2× wider until the best distance is inside the searched radius. Same answers
//   as scanning all (certified motions: the same verdicts, a few more states at chunk ends).
//   Objects FCL handles (meshes and ungridded maps on the fast path, every object on the FCL
//   path) get a broad phase too when there are more than 32: on the FCL path FCL's own, a
//   DynamicAABBTreeCollisionManager over their world AABBs; on the fast path, where that tree's
//   query would cost a third of a state check, a SphereBvh of their bounding spheres. A check
//   lists those near the robot's box (ascending, so the same first contact) and Clearance widens
//   that box as it does for primitives (WideningSearch, shared by both).
// * Fast-path order: primitives, occupancy maps (scene order), self, meshes. The FCL path checks
//   scene objects, then maps, then self, so for a scene of maps only both paths report the same
//   first contact.
// * FCL path: shared, immutable fcl geometries; every query calls the geometry+transform
//   overloads of fcl::collide / fcl::distance, which build their traversal state on the
//   stack. Nothing is mutated in const methods, so one checker serves all threads.
// * Certified advancement (CertifiedCurve, certified_motion.cc): working memory is per thread
//   and reused across calls, and each link–primitive and self pair caches the curve parameter up
//   to which it cannot shorten a step (see "Pair skipping" there); the states, steps and answers
//   are those of evaluating every pair at every state.
// * Scene allowed collisions (Scene::allowed_collisions, MoveIt's ACM entries that come with a
//   scene) are resolved at construction (allowed_pairs.cc): link–link pairs join the robot's
//   ACM (they leave the self-pair lists); link–obstacle pairs give the obstacle (Prim /
//   SceneGeom `allowed`) a bit set over the robot units the checks iterate — sphere links on the
//   fast path, links on the FCL path — and every robot-vs-obstacle loop skips the set bits (the
//   primitive cull clears them from its 64-link mask). Obstacles without allowances carry -1, so a scene without any costs
//   one predictable branch per obstacle; an obstacle every link may touch is dropped.
// * Contact semantics: shapes that touch (distance == 0 after padding) are in collision, as in
//   FCL's sphere–box test. With padding > 0 the FCL path compares fcl::distance <= padding.
//   Padding applies between the robot and the scene only; self pairs are checked on the
//   unpadded shapes (as MoveIt does), so the fast path subtracts 2·padding from padded radii.

namespace chasles {
namespace {

using detail::kInf;
using detail::CheckSize;
using detail::RobotShape;
using detail::SceneGeom;
using detail::Scratch;
using detail::SphereLink;
using detail::SpheresOverlap;
using detail::ToIsometry;
using detail::ToRowMajor;
using detail::UnitSet;
using detail::Apply;
using detail::Frame;
using detail::Prim;
using detail::SphereDistance;
using detail::SphereHits;
using detail::kPrimBox;
using detail::kPrimCapsule;
using detail::kPrimCylinder;
using detail::kPrimSphere;

}  // namespace

void CollisionOptions::Validate() const {
  if (!std::isfinite(padding) || padding < 0.0) {
    std::ostringstream os;
    os << "collision.padding = " << padding << " must be finite and >= 0";
    ThrowInvalid(os.str());
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
  // With the broad phase, only the prims near the robot's box, their bounds gathered.
  std::size_t nprims = prims.size();
  const std::uint32_t* near = nullptr;  // nullptr: every prim, in order
  const double* px = prim_x.data();
  const double* py = prim_y.data();
  const double* pz = prim_z.data();
  const double* pr = prim_bound.data();
  thread_local std::vector<std::uint32_t> near_list;
  thread_local std::vector<double> near_bounds;
  thread_local GatherHistory history;
  if (prim_broad_phase && !ScanInstead(&history)) {
    PrimsNear(&lb[0], nullptr, 0.0, &near_list);
    Gathered(&history, near_list.size());
    nprims = near_list.size();
    near = near_list.data();
    near_bounds.resize(4 * nprims);
    for (std::size_t j = 0; j < nprims; ++j) {
      near_bounds[j] = prim_x[near[j]];
      near_bounds[nprims + j] = prim_y[near[j]];
      near_bounds[2 * nprims + j] = prim_z[near[j]];
      near_bounds[3 * nprims + j] = prim_bound[near[j]];
    }
    px = near_bounds.data();
    py = px + nprims;
    pz = py + nprims;
    pr = pz + nprims;
  }
  const std::size_t chunks = (nl + 63) / 64;
  Scratch<std::uint64_t, 256> masks(std::max(nprims, nl) * chunks);
  const auto link_chunk = [&](std::size_t chunk) {
    const std::size_t base = 64 * chunk;
    return detail::CullSpheres{bx + base, by + base, bz + base, br + base, std::min<std::size_t>(64, nl - base)};
  };
  for (std::size_t chunk = 0; chunk < chunks; ++chunk) {
    detail::OverlapMasks(simd, link_chunk(chunk), px, py, pz, pr, nprims, &masks[chunk * nprims]);
  }
  for (std::size_t j = 0; j < nprims; ++j) {
    const std::size_t oi = near != nullptr ? near[j] : j;
    const Prim& o = prims[oi];
    for (std::size_t chunk = 0; chunk < chunks; ++chunk) {
      const std::size_t base = 64 * chunk;
      std::uint64_t mask = masks[chunk * nprims + j];
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
  // Meshes and maps near the robot (GeomsNear: their broad phase when there are many), in scene order.
  thread_local std::vector<std::uint32_t> geoms_near;
  geoms_near.clear();
  if (!scene_geoms.empty()) GeomsNear(LinkBoundsBox(&lb[0], nullptr, 0.0), &geoms_near);
  // Occupancy maps, in scene order: link bounding sphere against the map's bound, then against
  // the voxel grid, then every sphere of the link.
  for (const std::uint32_t gi : geoms_near) {
    const SceneGeom& g = scene_geoms[gi];
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
        int voxel[3];
        if (grid.SphereHits(&w[3 * k], sr[k], voxel)) {
          if (report != nullptr) {
            report->has_voxel = true;
            report->voxel = grid.VoxelCentre(voxel);
          }
          return hit(L.link, g.name, false);
        }
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
  for (const std::uint32_t gi : geoms_near) {
    if (!scene_geoms[gi].octree && fcl_geom_hit(scene_geoms[gi])) return true;
  }
  return false;
}

bool CollisionChecker::Impl::FclCollide(const Frame* frames, CollisionResult* report) const {
  const std::size_t n = shapes.size();
  Scratch<fcl::Transform3d, 128> tf(n);
  Scratch<Eigen::Vector3d, 128> center(n);
  PlaceShapes(frames, &tf[0], &center[0]);
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
  thread_local std::vector<std::uint32_t> geoms_near;
  GeomsNear(ShapesBox(center.data(), 0.0), &geoms_near);
  for (const std::uint32_t gi : geoms_near) {
    const SceneGeom& g = scene_geoms[gi];
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

bool CollisionChecker::Impl::Collide(const Eigen::VectorXd& q, CollisionResult* report) const {
  Scratch<Frame, 64> frames(num_links);
  ComputeFk(q, &frames[0]);
  return fast ? FastCollide(&frames[0], report) : FclCollide(&frames[0], report);
}


CollisionChecker::CollisionChecker(std::shared_ptr<const RobotModel> robot, std::shared_ptr<const Scene> scene,
                                   CollisionOptions options)
    : robot_(std::move(robot)), scene_(std::move(scene)), impl_(std::make_shared<Impl>()) {
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
  const detail::SceneAllowances scene_allowed = detail::ResolveSceneAllowances(*robot_, *scene_);
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
      // A link of many spheres (a mesh covered at upload: 30–40) goes in groups of at most
      // Impl::kMaxSpheresPerBound, each with its own bounding sphere — sphere links of the same link,
      // never paired with each other — so a long link near an obstacle evaluates the spheres of
      // the groups near it, not all of them. Groups are runs along the centres' principal axis.
      const int first_of_link = static_cast<int>(m.sx.size());
      std::vector<int> order(shapes.size());
      for (std::size_t k = 0; k < order.size(); ++k) order[k] = static_cast<int>(k);
      const int groups =
          static_cast<int>((shapes.size() + Impl::kMaxSpheresPerBound - 1) / Impl::kMaxSpheresPerBound);
      if (groups > 1) {
        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
        for (const Shape& s : shapes) mean += s.pose.translation();
        mean /= static_cast<double>(shapes.size());
        Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
        for (const Shape& s : shapes) {
          const Eigen::Vector3d d = s.pose.translation() - mean;
          scatter += d * d.transpose();
        }
        const Eigen::Vector3d axis = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(scatter).eigenvectors().col(2);
        std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
          return shapes[static_cast<std::size_t>(a)].pose.translation().dot(axis) <
                 shapes[static_cast<std::size_t>(b)].pose.translation().dot(axis);
        });
      }
      const std::size_t per_group = (shapes.size() + static_cast<std::size_t>(groups) - 1) / static_cast<std::size_t>(groups);
      for (std::size_t from = 0; from < order.size(); from += per_group) {
        SphereLink L;
        L.link = l;
        L.begin = static_cast<int>(m.sx.size());
        Eigen::Vector3d lo = Eigen::Vector3d::Constant(kInf), hi = Eigen::Vector3d::Constant(-kInf);
        for (std::size_t i = from; i < std::min(order.size(), from + per_group); ++i) {
          const Shape& s = shapes[static_cast<std::size_t>(order[i])];
          const Eigen::Vector3d c = s.pose.translation();
          m.sx.push_back(c.x());
          m.sy.push_back(c.y());
          m.sz.push_back(c.z());
          m.sr.push_back(s.radius + pad);
          m.slink_of.push_back(static_cast<int>(m.slinks.size()));
          m.sphere_source.push_back(first_of_link + order[i]);
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
          break;
        case ShapeType::kBox:
          p.kind = kPrimBox;
          p.a = 0.5 * s.size.x();
          p.b = 0.5 * s.size.y();
          p.c = 0.5 * s.size.z();
          break;
        case ShapeType::kCylinder:
          p.kind = kPrimCylinder;
          p.a = s.radius;
          p.b = 0.5 * s.length;
          break;
        default:
          p.kind = kPrimCapsule;
          p.a = s.radius;
          p.b = 0.5 * s.length;
          break;
      }
      p.bound = BoundingRadius(s);
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
  if (m.options.broad_phase && m.prims.size() > Impl::kBroadPhasePrims) {
    m.prim_broad_phase = true;
    m.prim_bvh = detail::SphereBvh(m.prim_x.data(), m.prim_y.data(), m.prim_z.data(), m.prim_bound.data(),
                                   m.prims.size());
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

  if (m.options.broad_phase && m.scene_geoms.size() > Impl::kBroadPhasePrims) m.BuildGeomBroadPhase();

  if (m.fast) {
    m.certifiable = true;
    for (const SceneGeom& g : m.scene_geoms) m.certifiable = m.certifiable && g.octree && g.grid >= 0;
  }
}

void CollisionChecker::Impl::BuildGeomBroadPhase() {
  geom_broad_phase = true;
  if (fast) {
    std::vector<double> x, y, z, r;
    for (const SceneGeom& g : scene_geoms) {
      x.push_back(g.center.x());
      y.push_back(g.center.y());
      z.push_back(g.center.z());
      r.push_back(g.radius);
    }
    geom_bvh = detail::SphereBvh(x.data(), y.data(), z.data(), r.data(), scene_geoms.size());
    return;
  }
  std::vector<fcl::CollisionObjectd*> objects;
  for (std::size_t i = 0; i < scene_geoms.size(); ++i) {
    const SceneGeom& g = scene_geoms[i];
    geom_objects.push_back(std::make_unique<fcl::CollisionObjectd>(g.g.geom, g.tf));  // computes its AABB
    geom_objects.back()->setUserData(reinterpret_cast<void*>(static_cast<std::uintptr_t>(i + 1)));
    objects.push_back(geom_objects.back().get());
  }
  geom_manager = std::make_unique<fcl::DynamicAABBTreeCollisionManagerd>();
  geom_manager->registerObjects(objects);
  geom_manager->setup();
}

void CollisionChecker::Impl::GeomsNear(const detail::Box3& box, std::vector<std::uint32_t>* out) const {
  out->clear();
  if (!geom_broad_phase) {
    for (std::size_t i = 0; i < scene_geoms.size(); ++i) out->push_back(static_cast<std::uint32_t>(i));
    return;
  }
  if (box.Empty()) return;  // no robot shape
  if (geom_manager == nullptr) {
    geom_bvh.Overlapping(box, out);
    return;
  }
  // The query is an axis-aligned box object: FCL's tree reports the leaves whose AABB overlaps
  // the query's, with the leaf first. One box per thread, resized per query.
  thread_local const std::shared_ptr<fcl::Boxd> shape = std::make_shared<fcl::Boxd>(1.0, 1.0, 1.0);
  thread_local fcl::CollisionObjectd query(shape);
  shape->side = fcl::Vector3d(box.hi[0] - box.lo[0], box.hi[1] - box.lo[1], box.hi[2] - box.lo[2]);
  shape->computeLocalAABB();
  query.setTransform(fcl::Matrix3d::Identity(), fcl::Vector3d(0.5 * (box.lo[0] + box.hi[0]),
                                                              0.5 * (box.lo[1] + box.hi[1]),
                                                              0.5 * (box.lo[2] + box.hi[2])));
  query.computeAABB();
  const fcl::CollisionCallBack<double> collect = [](fcl::CollisionObjectd* leaf, fcl::CollisionObjectd*,
                                                    void* data) {
    static_cast<std::vector<std::uint32_t>*>(data)->push_back(
        static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(leaf->getUserData()) - 1));
    return false;  // all of them
  };
  geom_manager->collide(&query, out, collect);
  std::sort(out->begin(), out->end());
}

CollisionChecker::~CollisionChecker() = default;

std::shared_ptr<const CollisionChecker> CollisionChecker::WithPathConstraints(
    std::shared_ptr<const CollisionChecker> base, std::shared_ptr<const PathConstraints> constraints) {
  if (!base) ThrowInvalid("WithPathConstraints: no checker");
  if (!constraints || constraints->empty()) return base;
  if (constraints->robot().num_dofs() != base->robot().num_dofs()) {
    ThrowInvalid("WithPathConstraints: the constraints are for robot '" + constraints->robot().name() + "' (" +
                 std::to_string(constraints->robot().num_dofs()) + " joints), the checker's robot '" +
                 base->robot().name() + "' has " + std::to_string(base->robot().num_dofs()));
  }
  std::shared_ptr<CollisionChecker> out(new CollisionChecker());
  out->robot_ = base->robot_;
  out->scene_ = base->scene_;
  out->impl_ = base->impl_;
  out->constraints_ = std::move(constraints);
  return out;
}

bool CollisionChecker::uses_fast_path() const { return impl_->fast; }

int CollisionChecker::num_gridded_occupancy_maps() const { return static_cast<int>(impl_->grids.size()); }

void detail::CheckSize(const RobotModel& robot, const Eigen::VectorXd& q, const char* field) {
  if (q.size() != robot.num_dofs()) {
    ThrowInvalid(std::string(field) + " has " + std::to_string(q.size()) + " values, robot '" +
                 robot.name() + "' has " + std::to_string(robot.num_dofs()) + " joints");
  }
}

void detail::CheckSpeedBound(const RobotModel& robot, const Eigen::VectorXd& speed, const char* field) {
  CheckSize(robot, speed, field);
  for (int i = 0; i < speed.size(); ++i) {
    if (!std::isfinite(speed[i]) || speed[i] < 0.0) {
      ThrowInvalid(std::string(field) + "[" + std::to_string(i) + "] = " + FormatNumber(speed[i]) +
                   " must be finite and >= 0");
    }
  }
}

bool detail::WithinLimits(const RobotModel& robot, const Eigen::VectorXd& q) {
  const Eigen::VectorXd& lo = robot.lower_limits();
  const Eigen::VectorXd& hi = robot.upper_limits();
  for (Eigen::Index i = 0; i < q.size(); ++i) {
    if (!(q[i] >= lo[i] && q[i] <= hi[i])) return false;  // NaN fails too
  }
  return true;
}

bool CollisionChecker::IsValid(const Eigen::VectorXd& q, CheckCounters* counters) const {
  CheckSize(*robot_, q, "q");
  if (counters != nullptr) ++counters->state_checks;
  if (!detail::WithinLimits(*robot_, q)) return false;
  if (constraints_ && !constraints_->Satisfied(q)) return false;
  return !impl_->Collide(q, nullptr);
}

CollisionResult CollisionChecker::Check(const Eigen::VectorXd& q) const {
  CheckSize(*robot_, q, "q");
  CollisionResult result;
  impl_->Collide(q, &result);
  if (!result.in_collision && constraints_) {
    int link = -1;
    result.violation = constraints_->Violation(q, &link);
    if (!result.violation.empty()) {
      result.in_collision = true;
      result.link_a = robot_->links()[link].name;
    }
  }
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
  if (constraints_) {
    std::uint64_t states = 0;
    const bool kept = constraints_->IsSegmentSatisfied(a, b, &states);
    if (counters != nullptr) counters->state_checks += states;
    if (!kept) return false;
  }
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

const CollisionOptions& CollisionChecker::options() const { return impl_->options; }

std::string VoxelText(const CollisionResult& contact) {
  if (!contact.has_voxel) return "";
  char text[128];
  std::snprintf(text, sizeof text, " (the voxel centred at (%.4g, %.4g, %.4g) m)", contact.voxel.x(), contact.voxel.y(),
                contact.voxel.z());
  return text;
}

}  // namespace chasles

