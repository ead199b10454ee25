#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "chasles/robot/error.h"
#include "chasles/robot/kinematics.h"
#include "checker_impl.h"

// Certified motion: the lever-arm bounds built with the checker (BuildLevers), the sweep bounds
// D_k of a curve (SweepBounds) and the conservative advancement (CertifiedCurve) behind
// CollisionChecker::IsMotionCertified / IsCurveCertified.

namespace chasles {

using detail::kInf;

// Lever arms (PointLevers of each sphere centre). A revolute joint turns everything below it
// about an axis through its child frame's origin, so a point x moves at most its distance from
// the axis per radian of that joint. A prismatic joint moves every point below it by exactly
// |Δq|. Summing over the chain, the centre's speed is at most Σ_i R_i |q̇_i|, so along any path |x(s1) − x(s0)| <= Σ_i R_i ∫|q̇_i| <= Σ_i R_i w_i (s1 − s0) when |dq_i/ds| <= w_i
// (a straight segment a→b: w = |b − a|).
// Mimic joints: the sum runs over the moving joints j (θ_j = m_j q_d + c_j), |θ̇_j| = |m_j| |q̇_d|,
// so joint j adds |m_j| R_j to the bound of the dof d that drives it; a prismatic mimic joint
// in between adds its largest |θ| over d's limits.
void CollisionChecker::Impl::BuildLevers() {
  num_dofs = robot->num_dofs();
  num_moving = robot->num_moving_joints();
  const std::size_t ns = sx.size();
  lever.assign(ns * static_cast<std::size_t>(num_moving), 0.0);
  lever_dof.assign(num_moving, -1);
  for (int m = 0; m < num_moving; ++m) lever_dof[m] = robot->joints()[robot->moving_joint(m)].dof;
  slink_moving.assign(slinks.size(), std::vector<char>(num_moving, 0));
  for (std::size_t li = 0; li < slinks.size(); ++li) {
    for (int link = slinks[li].link; robot->links()[link].parent_joint >= 0;) {
      const int ji = robot->links()[link].parent_joint;
      const int m = robot->moving_index(ji);
      if (m >= 0) slink_moving[li][m] = 1;
      link = robot->joints()[ji].parent_link;
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
      const std::vector<char>& other = slink_moving[side == 0 ? pr.second : pr.first];
      std::vector<int> unshared;
      for (int i = 0; i < num_moving; ++i) {
        if (!other[i]) unshared.push_back(i);
      }
      self_pair_unshared.push_back(std::move(unshared));
      self_pair_spheres += static_cast<std::size_t>(slinks[li].end - slinks[li].begin);
    }
  }
  for (const SphereLink& L : slinks) {
    for (int k = L.begin; k < L.end; ++k) {
      const Eigen::VectorXd r = PointLevers(*robot, L.link, Eigen::Vector3d(sx[k], sy[k], sz[k]));
      std::copy(r.data(), r.data() + num_moving, lever.data() + static_cast<std::size_t>(k) * num_moving);
    }
  }
  self_pair_lever_max.clear();
  for (const auto& pr : self_pairs) {
    for (int side = 0; side < 2; ++side) {
      const SphereLink& L = slinks[side == 0 ? pr.first : pr.second];
      const std::vector<int>& unshared = self_pair_unshared[self_pair_lever_max.size()];
      std::vector<double> most(unshared.size(), 0.0);
      for (std::size_t j = 0; j < unshared.size(); ++j) {
        for (int k = L.begin; k < L.end; ++k) {
          most[j] = std::max(most[j], lever[static_cast<std::size_t>(k) * num_moving + unshared[j]]);
        }
      }
      self_pair_lever_max.push_back(std::move(most));
    }
  }
}

void CollisionChecker::Impl::SweepBounds(const Eigen::VectorXd& w, double* out) const {
  const std::size_t ns = sx.size();
  for (std::size_t k = 0; k < ns; ++k) {
    const double* r = lever.data() + k * num_moving;
    double d = 0.0;
    for (int i = 0; i < num_moving; ++i) {
      if (r[i] != 0.0) d += w[lever_dof[i]] * r[i];
    }
    out[k] = d;
  }
}

namespace {
constexpr int kMaxCertifiedStates = 20000;
// [rad] probe states before advancing, at most this apart. Probes only reject (a colliding
// probe is a real contact), so the spacing changes the cost, never the answer. Callgrind, 4
// scenes x 20 queries (bench pipeline): 0.25 1052.9M (planning 129.4M), 0.35 1040.4M (128.7M),
// 0.5 1042.6M (124.9M), 0.75 1046.8M (124.1M; shortcutting +2 %).
constexpr double kProbeSpacing = 0.5;
constexpr int kMaxProbeDepth = 10;           // (at most 1023 of them)
constexpr double kMinCertifiedStep = 1e-7;   // in s
// A step is at most this times the one before it. Any shorter step is as safe, and the cap lets
// the pairs whose cached free-until already covers it be skipped before the pair that limits the
// step has been evaluated (without it, a state evaluates every pair until one shortens the step
// from the whole rest of the curve). Measured by callgrind on 20 shelf queries: 1 (never grow)
// 555M instructions, none 490M, 2 426M, 1.25 419M, 1.1 418M with 3 % more states; 1.25 keeps the
// states' median.
constexpr double kMaxStepGrowth = 1.25;
// Contact lookahead. An advancement never steps into a contact: on a curve through an obstacle
// it creeps up to it, each step a fixed fraction shorter (the limiting pair's distance shrinks
// at its true rate v, the step is distance / D with D >= v), until the step falls below
// kMinCertifiedStep — 160 states on average for the Panda's rejected motions, all of them real
// contacts (checked: a colliding state within 1e-5 of where the creep stopped). Once the step is
// below 1/kLookaheadShrink of the largest so far and still shrinking, the contact is predicted
// where the steps' geometric series sums, s + Δ_k / (1 − Δ_k / Δ_{k−1}), and one state a little
// beyond it is checked: a collision there rejects the curve (a contact proves it), otherwise the
// advancement goes on unchanged and probes again once the step has halved. Steps, and so the
// answer, are exactly those without the lookahead.
constexpr double kLookaheadShrink = 4.0;
constexpr double kLookaheadRearm = 2.0;
constexpr double kLookaheadBeyond = 1.05;
constexpr double kChunkReach = 0.2;          // [m] broad phase: sweep bound of one chunk of a curve
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
  std::vector<char> pd_ready;        // per self pair: its spheres' PD are summed
  std::vector<double> w, lb;         // world sphere centres (3 per sphere), link bound centres
  std::vector<char> placed, bound_placed;  // per sphere link: w / lb hold this state's values
  std::vector<double> margin;        // occupancy grids: last margin that held, per grid and sphere
  // Free-until parameters (see "Pair skipping" below).
  std::vector<double> prim_free;         // per primitive: the least of its links'
  std::vector<double> prim_link_free;    // per primitive and sphere link
  std::vector<double> prim_sphere_free;  // per primitive and sphere
  std::vector<double> self_free;         // per self pair
  std::vector<double> self_sphere_free;  // per self pair and pair of its spheres
  std::vector<detail::Frame> frames;
  std::vector<std::uint32_t> near;  // broad phase: the prims near the current chunk
  std::vector<double> grow;          // broad phase: per sphere link, D_l times the chunk's length
  Eigen::VectorXd q, probe;
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
  // Joints, not dofs: a dof that drives a joint above each link (a finger and its mimic) moves
  // them relative to each other, and is counted on both sides.
  // Per side, a bound on its spheres' rates from the side's largest lever per joint (not less
  // than the largest of the spheres' own sums, so the link-level test stays sound); the spheres'
  // own rates PD are summed (and its sphere pairs' free-until cleared) when the pair is first
  // evaluated sphere by sphere. Most pairs never are, and a pair's steps are those of any rate
  // bound at the link level (a pair it passes could not have shortened the step).
  m.PD.resize(self_pair_spheres);
  m.PDl.assign(2 * np, 0.0);
  m.pd_ready.assign(np, 0);
  for (std::size_t ps = 0; ps < 2 * np; ++ps) {
    const std::vector<int>& unshared = self_pair_unshared[ps];
    const double* most = self_pair_lever_max[ps].data();
    double d = 0.0;
    for (std::size_t j = 0; j < unshared.size(); ++j) {
      if (most[j] != 0.0) d += speed[lever_dof[unshared[j]]] * most[j];
    }
    if (!std::isfinite(d)) return false;
    m.PDl[ps] = d;
  }
  // Pair p's sphere rates: the distance shrinks at most by the levers of the joints not shared.
  const auto pair_rates = [&](std::size_t p) {
    std::size_t at = self_pair_offset[p];
    for (int side = 0; side < 2; ++side) {
      const std::size_t li = side == 0 ? self_pairs[p].first : self_pairs[p].second;
      const std::vector<int>& unshared = self_pair_unshared[2 * p + side];
      for (int k = slinks[li].begin; k < slinks[li].end; ++k) {
        const double* r = lever.data() + static_cast<std::size_t>(k) * num_moving;
        double d = 0.0;
        for (int i : unshared) {
          if (r[i] != 0.0) d += speed[lever_dof[i]] * r[i];
        }
        m.PD[at++] = d;
      }
    }
    std::fill(m.self_sphere_free.begin() + static_cast<std::ptrdiff_t>(self_pair_grid[p]),
              m.self_sphere_free.begin() + static_cast<std::ptrdiff_t>(self_pair_grid[p + 1]), -kInf);
    m.pd_ready[p] = 1;
  };
  m.w.resize(3 * ns);
  m.lb.resize(3 * nl);
  m.placed.resize(nl);
  m.bound_placed.resize(nl);
  m.margin.assign(ns * grids.size(), kInitialGridMargin);
  m.frames.resize(num_links);
  m.q.resize(num_dofs);
  Frame* const frames = m.frames.data();
  // The prims the advancement visits, and their pair caches. Without the broad phase: all of
  // them, for the whole curve. With it, the curve goes in chunks [s0, s1] over which no sphere
  // moves more than kChunkReach: a chunk visits the prims near the link bounds at s0 grown by
  // D_l·(s1 − s0) — any other is farther from sphere k than D_k·(s1 − s) at every s of the chunk,
  // so it cannot limit a step that ends by s1, and steps are cut at s1.
  std::size_t nprims = prims.size();
  const std::uint32_t* near = nullptr;  // nullptr: every prim, in order
  double chunk_end = 1.0;
  double max_rate = 0.0;
  for (std::size_t li = 0; li < nl; ++li) max_rate = std::max(max_rate, Dl[li]);
  const auto prim_at = [&](std::size_t oi) -> const Prim& { return prims[near != nullptr ? near[oi] : oi]; };
  const auto reset_prims = [&] {
    // -inf: evaluate at the next state; allowed link–primitive pairs are never evaluated.
    m.prim_free.assign(nprims, -kInf);
    m.prim_link_free.assign(nprims * nl, -kInf);
    m.prim_sphere_free.assign(nprims * ns, -kInf);
    for (std::size_t oi = 0; oi < nprims; ++oi) {
      if (const UnitSet* allowed = Allowed(prim_at(oi).allowed)) {
        for (std::size_t li = 0; li < nl; ++li) {
          if (allowed->Has(li)) m.prim_link_free[oi * nl + li] = kInf;
        }
      }
    }
  };
  // At state s (frames computed): the chunk from s, its prims gathered.
  const auto start_chunk = [&](double s) {
    const double length = max_rate * (1.0 - s) <= kChunkReach ? 1.0 - s : kChunkReach / max_rate;
    chunk_end = s + length;
    m.grow.resize(nl);
    for (std::size_t li = 0; li < nl; ++li) m.grow[li] = Dl[li] * length;
    PlaceLinkBounds(frames, m.lb.data(), m.placed.data());
    PrimsNear(m.lb.data(), m.grow.data(), 0.0, &m.near);
    nprims = m.near.size();
    near = m.near.data();
    reset_prims();
  };
  if (!prim_broad_phase) reset_prims();
  m.self_free.assign(np, -kInf);
  m.self_sphere_free.resize(self_pair_grid.back());  // a pair's part set with its rates
  double* const w = m.w.data();
  double* const lb = m.lb.data();
  // World centres of link li's bounding sphere / of its spheres, once per state, when needed.
  const auto bound = [&](std::size_t li) {
    if (!m.bound_placed[li]) {
      m.bound_placed[li] = 1;
      detail::Apply(frames[slinks[li].link], slinks[li].bc, &lb[3 * li]);
    }
    return &lb[3 * li];
  };
  const auto place = [&](std::size_t li) { PlaceLinkSpheres(frames, li, w, m.placed.data()); };

  double last_step = kInf;  // the step taken from the previous state
  double peak_step = 0.0;   // the largest step taken
  double probe_below = kInf;  // lookahead: the next probe once the step is below this
  double s = 0.0;
  for (int state = 0;; ++state) {
    if (state >= kMaxCertifiedStates) return false;
    if (counters != nullptr) ++counters->state_checks;
    curve(s, &m.q);
    if (!m.q.allFinite()) return false;
    ComputeFk(m.q, frames);
    // A new chunk when this state ends the last one (or nearly: a last step shorter than twice
    // the smallest step allowed is not taken).
    if (prim_broad_phase && (state == 0 || s >= chunk_end - 2.0 * kMinCertifiedStep)) start_chunk(s);
    std::fill(m.placed.begin(), m.placed.end(), 0);
    std::fill(m.bound_placed.begin(), m.bound_placed.end(), 0);
    const double limit = (prim_broad_phase ? chunk_end : 1.0) - s;
    double step = std::min(limit, kMaxStepGrowth * last_step);
    // Scene primitives: exact clearances; a link whose bounding sphere is clear by more than
    // step·(its fastest sphere's bound) cannot shorten the step.
    for (std::size_t oi = 0; oi < nprims; ++oi) {
      if (m.prim_free[oi] >= s + step) continue;  // none of its pairs can shorten the step
      const Prim& o = prim_at(oi);
      double* const link_free = m.prim_link_free.data() + oi * nl;
      double* const sphere_free = m.prim_sphere_free.data() + oi * ns;
      double prim_until = kInf;
      for (std::size_t li = 0; li < nl; ++li) {
        if (link_free[li] >= s + step) {
          prim_until = std::min(prim_until, link_free[li]);
          continue;
        }
        const SphereLink& L = slinks[li];
        const double dl = detail::SphereDistance(o, bound(li), L.br);
        if (dl > 0.0 && dl >= step * Dl[li]) {
          link_free[li] = FreeUntil(s, dl, Dl[li]);
          prim_until = std::min(prim_until, link_free[li]);
          continue;
        }
        place(li);
        double until = kInf;
        for (int k = L.begin; k < L.end; ++k) {
          if (sphere_free[k] < s + step) {
            const double d = detail::SphereDistance(o, &w[3 * k], sr[k]);
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
      if (!m.pd_ready[p]) pair_rates(p);
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
    if (step >= 1.0 - s) return true;  // [s, 1] is clear (the last chunk ends at 1)
    if (!(step >= kMinCertifiedStep)) return false;  // grazing (or NaN): reject conservatively
    peak_step = std::max(peak_step, step);
    if (step < last_step && step < probe_below && step * kLookaheadShrink < peak_step) {
      probe_below = step / kLookaheadRearm;
      const double ahead = s + kLookaheadBeyond * step / (1.0 - step / last_step);
      if (ahead < 1.0) {
        if (counters != nullptr) ++counters->state_checks;
        curve(ahead, &m.probe);
        if (m.probe.allFinite() && Collide(m.probe, nullptr)) return false;
      }
    }
    // A step cut at the chunk's end says nothing of the clearance: the next may grow from the
    // larger of it and the step before.
    last_step = step < limit ? step : std::max(step, last_step);
    s += step;
    if (s >= 1.0) return true;
  }
}

bool CollisionChecker::certifies_motion() const { return impl_->certifiable; }

bool CollisionChecker::IsMotionCertified(const Eigen::VectorXd& a, const Eigen::VectorXd& b,
                                         CheckCounters* counters) const {
  detail::CheckSize(*robot_, a, "a");
  detail::CheckSize(*robot_, b, "b");
  if (!impl_->certifiable) return IsMotionValid(a, b, 0.005, counters);
  // a's collision check is the advancement's first state, which evaluates every pair at s = 0.
  if (!IsValid(b, counters) || !detail::WithinLimits(*robot_, a)) return false;
  // The straight segment as a curve: IsCurveCertified's probes, then the advancement (a and b
  // are finite here, inside the limits).
  const Eigen::VectorXd delta = b - a;
  return IsCurveCertified([&](double s, Eigen::VectorXd* q) { *q = a + s * delta; }, delta.cwiseAbs(), counters);
}

bool CollisionChecker::IsCurveCertified(const Curve& curve, const Eigen::VectorXd& speed_bound,
                                        CheckCounters* counters) const {
  detail::CheckSpeedBound(*robot_, speed_bound, "speed_bound");
  if (constraints_) {
    std::uint64_t states = 0;
    const bool kept = constraints_->IsCurveSatisfied(curve, speed_bound, &states);
    if (counters != nullptr) counters->state_checks += states;
    if (!kept) return false;
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

Eigen::VectorXd CollisionChecker::GroupSweepBounds(const Eigen::VectorXd& speed) const {
  detail::CheckSpeedBound(*robot_, speed, "speed");
  if (!impl_->certifiable) return {};
  std::vector<double> sphere(impl_->sx.size());
  impl_->SweepBounds(speed, sphere.data());
  Eigen::VectorXd out = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(impl_->slinks.size()));
  for (std::size_t li = 0; li < impl_->slinks.size(); ++li) {
    for (int k = impl_->slinks[li].begin; k < impl_->slinks[li].end; ++k) out[li] = std::max(out[li], sphere[k]);
  }
  return out;
}

std::vector<double> CollisionChecker::SweepBounds(const Eigen::VectorXd& a, const Eigen::VectorXd& b) const {
  detail::CheckSize(*robot_, a, "a");
  detail::CheckSize(*robot_, b, "b");
  if (!impl_->certifiable) return {};
  std::vector<double> grouped(impl_->sx.size()), out(impl_->sx.size());
  impl_->SweepBounds((b - a).cwiseAbs(), grouped.data());
  for (std::size_t k = 0; k < grouped.size(); ++k) out[static_cast<std::size_t>(impl_->sphere_source[k])] = grouped[k];
  return out;
}

}  // namespace chasles
