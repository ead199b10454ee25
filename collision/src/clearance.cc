#include <algorithm>
#include <cstdint>
#include <vector>

#include <fcl/fcl.h>

#include "checker_impl.h"
#include "forward_kinematics.h"
#include "primitives.h"
#include "sphere_cull.h"

// Clearance: the distance from the robot to the scene at one state (CollisionChecker::Clearance),
// and per clearance group (sphere link) a lower bound on its own, for MeasureTrajectory's bound on
// a trajectory's minimum clearance. The fast path is a branch and bound over (link, primitive)
// pairs on their bounding spheres (PrimClearance), widened through the broad phase when there are
// many primitives, plus FCL distances for meshes and ungridded maps; the FCL path is FCL's
// distance for every shape.

namespace chasles {

using detail::Frame;
using detail::kInf;
using detail::Prim;
using detail::SceneGeom;
using detail::Scratch;
using detail::SphereDistance;
using detail::SphereLink;
using detail::UnitSet;
using detail::CheckSize;
using detail::RobotShape;

double CollisionChecker::Impl::PrimClearance(const Frame* frames, const std::uint32_t* which, std::size_t count,
                                             const double* soa, double* w, char* placed, double best,
                                             double* group_lower) const {
  const std::size_t nl = slinks.size();
  const std::size_t padded = detail::CullPadded(nl);
  // A link's bounding sphere is at most as far from an obstacle as any of its spheres, so a
  // (link, primitive) pair whose bound is no closer than the best distance so far cannot lower
  // it. Branch and bound: the pair with the smallest bound first (it sets a tight `best`), then
  // every other pair whose bound is below `best`.
  // The bounds, one primitive against every link at once (primitives.h), in pair p·padded + li.
  Scratch<double, 1024> bound(count * padded);
  std::size_t first = 0;
  const auto prim = [&](std::size_t p) -> const Prim& { return prims[which != nullptr ? which[p] : p]; };
  for (std::size_t p = 0; p < count; ++p) {
    double* b = &bound[p * padded];
    detail::SphereDistances(simd, prim(p), &soa[0], &soa[padded], &soa[2 * padded], link_bound_radius.data(), nl, b);
    const UnitSet* allowed = Allowed(prim(p).allowed);
    for (std::size_t li = 0; li < nl; ++li) {
      if (allowed != nullptr && allowed->Has(li)) b[li] = kInf;
      if (b[li] < bound[first]) first = p * padded + li;
    }
  }
  const auto exact = [&](std::size_t pair) {
    const Prim& o = prim(pair / padded);
    const std::size_t li = pair % padded;
    const SphereLink& L = slinks[li];
    PlaceLinkSpheres(frames, li, w, placed);
    double link = kInf;
    for (int k = L.begin; k < L.end; ++k) link = std::min(link, SphereDistance(o, &w[3 * k], sr[k]));
    bound[pair] = link;  // exact now (no less than the bound it replaces)
    best = std::min(best, link);
  };
  if (nl * count > 0 && bound[first] < best) exact(first);
  for (std::size_t p = 0; p < count; ++p) {
    for (std::size_t li = 0; li < nl; ++li) {
      const std::size_t pair = p * padded + li;
      if (pair != first && bound[pair] < best) exact(pair);
    }
  }
  if (group_lower != nullptr) {
    for (std::size_t p = 0; p < count; ++p) {
      for (std::size_t li = 0; li < nl; ++li) group_lower[li] = std::min(group_lower[li], bound[p * padded + li]);
    }
  }
  return best;
}

double CollisionChecker::Impl::FastClearance(const Frame* frames, double* group_lower) const {
  const std::size_t ns = sx.size();
  const std::size_t nl = slinks.size();
  Scratch<double, 1024> w(3 * ns);
  Scratch<double, 256> lb(3 * nl);
  Scratch<char, 256> placed(nl);
  PlaceLinkBounds(frames, &lb[0], &placed[0]);
  const std::size_t padded = detail::CullPadded(nl);
  Scratch<double, 256> soa(3 * padded);  // link bounding centres, structure of arrays
  LinkBoundsSoa(&lb[0], 0.0, &soa[0]);    // padding lanes finite (their distances are not read)
  double best = kInf;
  if (group_lower != nullptr) std::fill(group_lower, group_lower + nl, kInf);
  thread_local GatherHistory history;
  if (!prim_broad_phase || ScanInstead(&history)) {
    best = PrimClearance(frames, nullptr, prims.size(), &soa[0], &w[0], &placed[0], kInf, group_lower);
  } else {
    // Prims within `radius` of the link bounds first; a prim outside that box is farther than
    // `radius` from every link, so once the best distance is at most `radius` it is final.
    double unvisited = kInf;  // every prim not visited is farther than this from every link
    WideningSearch(
        kClearanceSearchRadius, prims.size(), &best,
        [&](double radius, std::vector<std::uint32_t>* near) {
          PrimsNear(&lb[0], nullptr, radius, near);
          if (radius == kClearanceSearchRadius) Gathered(&history, near->size());
          unvisited = near->size() == prims.size() ? kInf : radius;
          return true;
        },
        [&](const std::uint32_t* fresh, std::size_t count) {
          best = PrimClearance(frames, fresh, count, &soa[0], &w[0], &placed[0], best, group_lower);
        });
    if (group_lower != nullptr) {
      for (std::size_t li = 0; li < nl; ++li) group_lower[li] = std::min(group_lower[li], unvisited);
    }
  }
  if (!scene_geoms.empty()) {
    for (std::size_t li = 0; li < nl; ++li) PlaceLinkSpheres(frames, li, &w[0], &placed[0]);
    fcl::DistanceRequestd request;
    const auto geom_clearance = [&](const SceneGeom& g) {
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
    };
    SearchGeomsNear([&](double radius) { return LinkBoundsBox(&lb[0], nullptr, radius); }, &best, geom_clearance);
    // A link's clearance to the maps is no less than the clearance itself (the maps' spheres
    // are skipped on bounds against `best`, so that is all that is known per link).
    if (group_lower != nullptr) {
      for (std::size_t li = 0; li < nl; ++li) group_lower[li] = std::min(group_lower[li], best);
    }
  }
  if (group_lower != nullptr) {
    for (std::size_t li = 0; li < nl; ++li) group_lower[li] = std::max(0.0, group_lower[li]);
  }
  return best <= 0.0 ? 0.0 : best;
}

double CollisionChecker::Impl::FclClearance(const Frame* frames) const {
  const std::size_t n = shapes.size();
  Scratch<fcl::Transform3d, 128> tf(n);
  Scratch<Eigen::Vector3d, 128> center(n);
  PlaceShapes(frames, &tf[0], &center[0]);
  double best = kInf;
  fcl::DistanceRequestd request;
  const auto geom_clearance = [&](const SceneGeom& g) {
    for (std::size_t i = 0; i < n; ++i) {
      const RobotShape& s = shapes[i];
      if (g.allowed >= 0 && allowed_sets[g.allowed].Has(s.link)) continue;
      if ((center[i] - g.center).norm() - s.g.radius - g.radius - options.padding >= best) continue;
      fcl::DistanceResultd result;
      const double d = fcl::distance(s.g.geom.get(), tf[i], g.g.geom.get(), g.tf, request, result);
      best = std::min(best, d - options.padding);
    }
  };
  SearchGeomsNear([&](double radius) { return ShapesBox(center.data(), radius); }, &best, geom_clearance);
  return best <= 0.0 ? 0.0 : best;
}

double CollisionChecker::Clearance(const Eigen::VectorXd& q) const {
  CheckSize(*robot_, q, "q");
  Scratch<Frame, 64> frames(impl_->num_links);
  impl_->ComputeFk(q, &frames[0]);
  return impl_->fast ? impl_->FastClearance(&frames[0]) : impl_->FclClearance(&frames[0]);
}

int CollisionChecker::num_clearance_groups() const {
  return impl_->fast ? static_cast<int>(impl_->slinks.size()) : 1;
}

std::vector<int> CollisionChecker::clearance_group_links() const {
  if (!impl_->fast) return {-1};
  std::vector<int> out;
  for (const auto& L : impl_->slinks) out.push_back(L.link);
  return out;
}

double CollisionChecker::Clearance(const Eigen::VectorXd& q, Eigen::VectorXd* group_lower) const {
  CheckSize(*robot_, q, "q");
  Scratch<Frame, 64> frames(impl_->num_links);
  impl_->ComputeFk(q, &frames[0]);
  group_lower->resize(num_clearance_groups());
  if (!impl_->fast) {
    (*group_lower)[0] = impl_->FclClearance(&frames[0]);
    return (*group_lower)[0];
  }
  return impl_->FastClearance(&frames[0], group_lower->data());
}

}  // namespace chasles
