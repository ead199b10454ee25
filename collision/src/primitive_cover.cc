// Sphere covers of a cylinder and a capsule, and the exact reach of spheres over a box.
//
// Reach of a ball over a convex solid C. For any point p, dist(p, C) = max(0, max over unit u of
// u·p − h(u)), h the support function of C. So the farthest the ball B(c, ρ) reaches outside C is
//   max_{p ∈ B} dist(p, C) = max(0, max_u (u·c + ρ − h(u))) = max(0, ρ + sd(c)),
// sd the signed distance to C (negative inside: minus the distance to the boundary). Boxes,
// cylinders and capsules are convex and sd is closed-form for each: the reach is exact.
//
// Capsule (radius r, cylindrical part of length L along z). n >= 2 balls centred on the axis at
// z_i = −L/2 + i·s, s = L/(n − 1), of radius ρ = √(r² + s²/4): the slab |z − z_i| <= s/2 of the
// cylindrical part lies in ball i (its farthest points from the centre are on its rims, at
// √(r² + (s/2)²)), and each hemisphere lies in the ball at its centre (ρ >= r). Every centre is on
// the axis segment, sd = −r: the reach is ρ − r, exactly. One ball: the centre, radius L/2 + r,
// reach L/2.
//
// Cylinder (radius r, length L along z). The balls stand in rings about the axis: `count` centres
// at polar radius c and height z, at angles phase + 2πj/count (a ball on the axis is a ring of
// one). The centres fixed, the radii come from a partition of the cylinder into cells
// R ∈ [r0, r1], φ ∈ [φ0, φ1] (an arc of at most π/2), z ∈ [z0, z1]. The farthest point of a cell from
// a centre (c, ψ, zc) is found exactly: |p − centre|² = R² + c² − 2Rc·cos(φ − ψ) + (z − zc)² is
// largest at the φ of the arc with the least cos(φ − ψ) (−1 when the arc holds ψ + π, else one of
// its ends: cos is unimodal there), whatever R >= 0, then at an end of [r0, r1] (convex in R) and
// of [z0, z1]. Each cell goes to the centre with the least (farthest distance + sd(centre)), its
// cost; a ball's radius is the farthest distance of its cells. Every point of the cylinder is in a
// cell and every cell in its ball: the balls cover, and their reach, max of radius + sd(centre),
// is exact for them. Cells are split, highest cost first, until that cost is within a tolerance
// of the largest least cost seen at a single point (cells' middles): no radii on these centres
// reach less than that, so the radii are within the tolerance of the least the centres allow.
// Rounding: cell bounds are shared exactly between siblings, cos/sin and the arithmetic err by a
// few 1e-16 of the size, and the radii and the reach get a margin of 1e-9 of the size.
//
// The ring bound. A ring of m balls of radius ρ at polar radius c and height zc covers, for every
// φ, the points (R, z) with (R − c·cos(π/m))² + c²·sin²(π/m) + (z − zc)² <= ρ²: the ball nearest
// in angle is within π/m, and cos(φ − ψ) >= cos(π/m) with R, c >= 0. That is a disc in the (R, z)
// half-plane per ring, so the least reach of a layout of rings comes, up to the same tolerance, from
// the same branch and bound over (R, z) cells alone: exact per ring (the ring's balls are
// equivalent), conservative across rings (it ignores that a ring may fill another's gaps), and a
// thousand times cheaper. The search ranks layouts by it; the proof is the branch and bound above.
//
// Which centres, two families searched, the better kept:
//  - Rims, inner rings and axis: per cap a ring of m1 balls near the rim (depth e from the side,
//    a from the cap), a ring of m2 balls further in (polar radius c2, depth a2 from the cap), the
//    rings of the two caps turned by π/m from each other (one ring of 2m when they meet in z = 0),
//    and the other balls on the axis, spread evenly between depth d from each cap. For each
//    (m1, m2), the five depths by a pattern search (steps halved when no move improves), coarse
//    for all, then fine for the best few.
//  - Mid-plane rings, for flat cylinders: rings in z = 0, from the rim inwards, each the ring that
//    covers (by the ring bound) the widest annulus of the full thickness per ball for a target
//    reach, then a ball on the axis if needed; the target is the least (by bisection) whose rings
//    fit the budget.
// With the budget met at the target reach, the budget is bisected down to the fewest spheres that
// still meet it (near the family found for the whole budget).

#include "primitive_cover.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

namespace chasles {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kMargin = 1e-9;            // of the shape's size, on radii and on the reach
constexpr double kSearchTolerance = 1e-3;   // of the size: ring bound's cell costs in the search
constexpr double kProofTolerance = 2e-4;    // of the size: cell costs of the proof
constexpr int kSearchSplits = 2000;         // cell splits per ring bound
constexpr int kProofSplits = 200000;        // cell splits of the proof (a bound on its memory)
constexpr int kCentreScan = 96;             // polar radii tried per ring of the mid-plane family
constexpr int kInnerCounts[] = {0, 2, 3, 4, 6};  // balls per inner ring tried
constexpr int kRefined = 4;                 // families refined finely
constexpr int kMaxSpheres = 128;            // per cylinder: the families gain little beyond

struct Cylinder {
  double radius;
  double half;  // half the length [m]
  double size() const { return radius + half; }
};

double SignedDistance(const Cylinder& cylinder, double radial, double z) {
  const double dr = radial - cylinder.radius, dz = std::abs(z) - cylinder.half;
  if (dr <= 0.0 && dz <= 0.0) return std::max(dr, dz);
  return std::hypot(std::max(dr, 0.0), std::max(dz, 0.0));
}

struct Ring {
  int count;      // balls, at angles phase + 2πj/count
  double radial;  // [m] polar radius of the centres; 0 for a ball on the axis (count 1)
  double z;       // [m]
  double phase;   // [rad]
};
using Layout = std::vector<Ring>;  // symmetric about z = 0

// ---- The proof: cells of the whole cylinder against every centre ----

struct Centre {
  double radial, cos_angle, sin_angle, z;
  double offset;  // signed distance to the cylinder: the ball reaches radius + offset outside it
};

struct Cell {
  double r0, r1, p0, p1, z0, z1;
  double cos0, sin0, cos1, sin1;
  double cost = kInf;  // least (farthest distance + offset) over the centres
  double far = 0.0;    // farthest distance to that centre
  int centre = -1;
  bool operator<(const Cell& other) const { return cost < other.cost; }
};

Cell MakeCell(double r0, double r1, double p0, double p1, double z0, double z1) {
  return {r0, r1, p0, p1, z0, z1, std::cos(p0), std::sin(p0), std::cos(p1), std::sin(p1)};
}

double FarthestSquared(const Cell& cell, const Centre& c) {
  // The least cos(φ − ψ) over the arc: −1 when the arc (< π) holds the direction opposite the
  // centre's, −(cos ψ, sin ψ); else at one of its ends.
  const bool opposite = cell.sin0 * c.cos_angle - cell.cos0 * c.sin_angle >= 0.0 &&
                        c.sin_angle * cell.cos1 - c.cos_angle * cell.sin1 >= 0.0;
  const double least = opposite ? -1.0
                                : std::min(cell.cos0 * c.cos_angle + cell.sin0 * c.sin_angle,
                                           cell.cos1 * c.cos_angle + cell.sin1 * c.sin_angle);
  const double twice = 2.0 * c.radial * least;
  const double dz = std::max(std::abs(cell.z0 - c.z), std::abs(cell.z1 - c.z));
  return std::max(cell.r0 * (cell.r0 - twice), cell.r1 * (cell.r1 - twice)) + c.radial * c.radial + dz * dz;
}

std::vector<Centre> Centres(const Cylinder& cylinder, const Layout& layout) {
  std::vector<Centre> centres;
  for (const Ring& ring : layout) {
    const double offset = SignedDistance(cylinder, ring.radial, ring.z);
    for (int j = 0; j < ring.count; ++j) {
      const double angle = ring.phase + 2.0 * M_PI * j / ring.count;
      centres.push_back(
          {ring.radial, ring.radial > 0.0 ? std::cos(angle) : 1.0, ring.radial > 0.0 ? std::sin(angle) : 0.0, ring.z, offset});
    }
  }
  return centres;
}

/// Per centre, the radius its cells need (0 when it got none), by the branch and bound of the
/// file comment over the whole cylinder.
std::vector<double> ProveCover(const Cylinder& cylinder, const std::vector<Centre>& centres, double tolerance) {
  std::vector<Cell> heap;
  double lower = 0.0;  // the largest least cost at a point
  const auto add = [&](Cell cell) {
    for (std::size_t i = 0; i < centres.size(); ++i) {
      const double far = std::sqrt(FarthestSquared(cell, centres[i]));
      if (far + centres[i].offset < cell.cost) {
        cell.cost = far + centres[i].offset;
        cell.far = far;
        cell.centre = static_cast<int>(i);
      }
    }
    // The cell's middle (R, φ and z halfway; the arc's middle direction is the sum of its ends').
    const double radial = 0.5 * (cell.r0 + cell.r1), z = 0.5 * (cell.z0 + cell.z1);
    const double cx = cell.cos0 + cell.cos1, sx = cell.sin0 + cell.sin1, norm = std::hypot(cx, sx);
    const double x = radial * cx / norm, y = radial * sx / norm;
    double point = kInf;
    for (const Centre& c : centres) {
      const double dx = x - c.radial * c.cos_angle, dy = y - c.radial * c.sin_angle, dz = z - c.z;
      point = std::min(point, std::sqrt(dx * dx + dy * dy + dz * dz) + c.offset);
    }
    lower = std::max(lower, point);
    heap.push_back(cell);
    std::push_heap(heap.begin(), heap.end());
  };
  const int slabs = std::clamp(static_cast<int>(std::ceil(2.0 * cylinder.half / cylinder.radius)), 1, 64);
  for (int a = 0; a < 4; ++a) {
    for (int s = 0; s < slabs; ++s) {
      const double z0 = -cylinder.half + 2.0 * cylinder.half * s / slabs;
      const double z1 = s + 1 == slabs ? cylinder.half : -cylinder.half + 2.0 * cylinder.half * (s + 1) / slabs;
      add(MakeCell(0.0, cylinder.radius, 0.5 * M_PI * a, 0.5 * M_PI * (a + 1), z0, z1));
    }
  }
  for (int splits = 0; splits < kProofSplits && heap.front().cost > lower + tolerance; ++splits) {
    std::pop_heap(heap.begin(), heap.end());
    const Cell cell = heap.back();
    heap.pop_back();
    const double dr = cell.r1 - cell.r0, dp = cell.r1 * (cell.p1 - cell.p0), dz = cell.z1 - cell.z0;
    Cell a = cell, b = cell;
    a.cost = b.cost = kInf;
    if (dr >= dp && dr >= dz) {
      a.r1 = b.r0 = 0.5 * (cell.r0 + cell.r1);
    } else if (dp >= dz) {
      a.p1 = b.p0 = 0.5 * (cell.p0 + cell.p1);
      a.cos1 = b.cos0 = std::cos(a.p1);
      a.sin1 = b.sin0 = std::sin(a.p1);
    } else {
      a.z1 = b.z0 = 0.5 * (cell.z0 + cell.z1);
    }
    add(a);
    add(b);
  }
  std::vector<double> radii(centres.size(), 0.0);
  for (const Cell& cell : heap) radii[cell.centre] = std::max(radii[cell.centre], cell.far);
  return radii;
}

// ---- The ring bound, for the search ----

/// The least reach, by the ring bound and within the search tolerance, of balls on the layout's
/// rings: a branch and bound over cells of the (R, z) half-plane, z >= 0 (the layout is symmetric).
double RingBound(const Cylinder& cylinder, const Layout& layout) {
  if (layout.empty()) return kInf;
  struct Disc {
    double u, extra, z, offset;  // centre (u, z) in the half-plane, c²·sin²(π/m), signed distance
  };
  struct Cell2 {
    double r0, r1, z0, z1, cost;
    bool operator<(const Cell2& other) const { return cost < other.cost; }
  };
  std::vector<Disc> discs;
  for (const Ring& ring : layout) {
    if (ring.z < 0.0) continue;  // its mirror does the same for z >= 0
    const double half_angle = M_PI / ring.count, along = ring.radial * std::sin(half_angle);
    discs.push_back({ring.radial * std::cos(half_angle), along * along, ring.z, SignedDistance(cylinder, ring.radial, ring.z)});
  }
  std::vector<Cell2> heap;
  double lower = 0.0;
  const auto add = [&](Cell2 cell) {
    cell.cost = kInf;
    const double rm = 0.5 * (cell.r0 + cell.r1), zm = 0.5 * (cell.z0 + cell.z1);
    double point = kInf;
    for (const Disc& d : discs) {
      const double dr = std::max(std::abs(cell.r0 - d.u), std::abs(cell.r1 - d.u));
      const double dz = std::max(std::abs(cell.z0 - d.z), std::abs(cell.z1 - d.z));
      cell.cost = std::min(cell.cost, std::sqrt(dr * dr + dz * dz + d.extra) + d.offset);
      point = std::min(point, std::sqrt((rm - d.u) * (rm - d.u) + (zm - d.z) * (zm - d.z) + d.extra) + d.offset);
    }
    lower = std::max(lower, point);
    heap.push_back(cell);
    std::push_heap(heap.begin(), heap.end());
  };
  const int slabs = std::clamp(static_cast<int>(std::ceil(cylinder.half / cylinder.radius)), 1, 64);
  for (int s = 0; s < slabs; ++s) {
    add({0.0, cylinder.radius, cylinder.half * s / slabs, s + 1 == slabs ? cylinder.half : cylinder.half * (s + 1) / slabs, 0.0});
  }
  const double tolerance = kSearchTolerance * cylinder.size();
  for (int splits = 0; splits < kSearchSplits && heap.front().cost > lower + tolerance; ++splits) {
    std::pop_heap(heap.begin(), heap.end());
    const Cell2 cell = heap.back();
    heap.pop_back();
    Cell2 a = cell, b = cell;
    if (cell.r1 - cell.r0 >= cell.z1 - cell.z0) {
      a.r1 = b.r0 = 0.5 * (cell.r0 + cell.r1);
    } else {
      a.z1 = b.z0 = 0.5 * (cell.z0 + cell.z1);
    }
    add(a);
    add(b);
  }
  return heap.front().cost;
}

// ---- Rims, inner rings and axis ----

struct Family {
  int rim = 0;    // balls per rim ring
  int inner = 0;  // balls per inner ring
  int axis = 0;   // balls on the axis
};

/// The depths of a family's balls, as fractions of their ranges (see Limits).
using Depths = std::array<double, 5>;  // rim from the side, rim from the cap, inner radius, inner from the cap, axis from the cap

/// The range of each depth: [0, limit].
Depths Limits(const Cylinder& cylinder) {
  return {cylinder.radius, cylinder.half, cylinder.radius, cylinder.half, cylinder.half};
}

/// A ring at height z and its mirror at −z turned by π/count, or one ring of twice as many when
/// they meet in z = 0.
void AddMirrored(Layout* layout, int count, double radial, double z) {
  if (count == 0) return;
  if (z <= 0.0) {
    layout->push_back({2 * count, radial, 0.0, 0.0});
    return;
  }
  layout->push_back({count, radial, z, 0.0});
  layout->push_back({count, radial, -z, M_PI / count});
}

Layout FamilyLayout(const Cylinder& cylinder, const Family& family, const Depths& x) {
  const Depths limit = Limits(cylinder);
  Layout layout;
  AddMirrored(&layout, family.rim, cylinder.radius - x[0] * limit[0], cylinder.half - x[1] * limit[1]);
  AddMirrored(&layout, family.inner, x[2] * limit[2], cylinder.half - x[3] * limit[3]);
  if (family.axis == 1) layout.push_back({1, 0.0, 0.0, 0.0});
  for (int i = 0; family.axis > 1 && i < family.axis; ++i) {
    const double end = cylinder.half - x[4] * limit[4];
    layout.push_back({1, 0.0, -end + 2.0 * end * i / (family.axis - 1), 0.0});
  }
  return layout;
}

struct Candidate {
  Layout layout;
  double reach = kInf;  // by the ring bound
  Family family;
  Depths depths{};
};

/// Pattern search over the depths the family uses, from `from->depths`, steps halved from
/// `first` while above `last`.
void Refine(const Cylinder& cylinder, Candidate* from, double first, double last) {
  const Family& f = from->family;
  const bool used[5] = {f.rim > 0, f.rim > 0, f.inner > 0, f.inner > 0, f.axis > 1};
  if (from->reach == kInf) from->reach = RingBound(cylinder, FamilyLayout(cylinder, f, from->depths));
  for (double step = first; step >= last;) {
    bool moved = false;
    for (int i = 0; i < 5; ++i) {
      if (!used[i]) continue;
      for (double sign : {1.0, -1.0}) {
        Depths y = from->depths;
        y[i] = std::clamp(y[i] + sign * step, 0.0, 1.0);
        if (y[i] == from->depths[i]) continue;
        const double reach = RingBound(cylinder, FamilyLayout(cylinder, f, y));
        if (reach < from->reach) {
          from->reach = reach;
          from->depths = y;
          moved = true;
        }
      }
    }
    if (!moved) step *= 0.5;
  }
  from->layout = FamilyLayout(cylinder, f, from->depths);
}

// ---- Mid-plane rings ----

/// Rings in z = 0 covering the cylinder for a target reach (see the file comment); empty when
/// more than `budget` balls would be needed.
Layout DiscLayout(const Cylinder& cylinder, double reach, int budget) {
  const double r = cylinder.radius, h = cylinder.half;
  Layout layout;
  int used = 0;
  double outer = r;  // [0, outer] is left to cover
  while (outer > 0.0) {
    const double axis_radius = reach + std::min(h, r);  // a ball on the axis, at that reach
    if (outer * outer + h * h <= axis_radius * axis_radius) {
      if (used + 1 > budget) return {};
      layout.push_back({1, 0.0, 0.0, 0.0});
      break;
    }
    Ring best{0, 0.0, 0.0, 0.0};
    double best_inner = outer, best_score = kInf;
    for (int m = 2; used + m <= budget; ++m) {
      const double sin_a = std::sin(M_PI / m), cos_a = std::cos(M_PI / m);
      for (int s = 1; s <= kCentreScan; ++s) {
        const double radial = r * s / kCentreScan;
        const double rho = reach + std::min(h, r - radial);
        const double w2 = rho * rho - radial * radial * sin_a * sin_a - h * h;
        if (w2 < 0.0) continue;
        const double w = std::sqrt(w2);
        if (radial * cos_a + w < outer) continue;
        const double inner = std::max(0.0, radial * cos_a - w);
        if (inner >= outer) continue;
        const double score = m / (outer * outer - inner * inner);
        if (score < best_score) {
          best_score = score;
          best = {m, radial, 0.0, layout.size() % 2 == 1 ? M_PI / m : 0.0};
          best_inner = inner;
        }
      }
    }
    if (best.count == 0) return {};
    layout.push_back(best);
    used += best.count;
    outer = best_inner;
  }
  return layout;
}

Candidate SearchDisc(const Cylinder& cylinder, int budget) {
  // One ball on the axis bounds the bisection from above.
  double fail = 0.0, pass = std::hypot(cylinder.radius, cylinder.half) - std::min(cylinder.radius, cylinder.half);
  Layout layout = DiscLayout(cylinder, pass, budget);
  if (layout.empty()) return {};
  for (int step = 0; step < 24; ++step) {
    const double mid = 0.5 * (fail + pass);
    Layout tried = DiscLayout(cylinder, mid, budget);
    if (tried.empty()) {
      fail = mid;
    } else {
      pass = mid;
      layout = std::move(tried);
    }
  }
  Candidate out;
  out.reach = RingBound(cylinder, layout);
  out.layout = std::move(layout);
  return out;
}

/// The best layout found for `budget` balls. With `near` (the family found for a larger budget),
/// only families like it, scaled to this budget, are tried.
Candidate Search(const Cylinder& cylinder, int budget, const Candidate* near) {
  Candidate best = SearchDisc(cylinder, budget);
  const double depth = std::min(cylinder.radius, cylinder.half);
  const Depths start = {0.25 * depth / cylinder.radius, 0.25 * depth / cylinder.half, 0.35, 0.7, 0.8 * depth / cylinder.half};
  std::vector<Candidate> coarse;
  for (int rim = 0; 2 * rim <= budget; rim = rim == 0 ? 2 : rim + 1) {
    for (int inner : kInnerCounts) {
      const int axis = budget - 2 * (rim + inner);
      if (axis < 0) continue;
      if (near != nullptr) {
        const int guess = static_cast<int>(std::lround(static_cast<double>(near->family.rim) * budget /
                                                       (2 * near->family.rim + 2 * near->family.inner + near->family.axis)));
        if (std::abs(rim - guess) > 2 || (inner != 0 && inner != near->family.inner)) continue;
      }
      Candidate c;
      c.family = {rim, inner, axis};
      c.depths = near != nullptr && near->family.inner == inner ? near->depths : start;
      Refine(cylinder, &c, 0.25, 0.03);
      coarse.push_back(std::move(c));
    }
  }
  const std::size_t refined = std::min<std::size_t>(kRefined, coarse.size());
  std::partial_sort(coarse.begin(), coarse.begin() + refined, coarse.end(),
                    [](const Candidate& a, const Candidate& b) { return a.reach < b.reach; });
  for (std::size_t k = 0; k < refined; ++k) {
    Refine(cylinder, &coarse[k], 0.03, 0.002);
    if (coarse[k].reach < best.reach) best = coarse[k];
  }
  return best;
}

}  // namespace

FittedSpheres CoverCylinder(double radius, double length, double max_reach, int max_spheres) {
  const Cylinder cylinder{radius, 0.5 * length};
  max_spheres = std::min(max_spheres, kMaxSpheres);
  Candidate best = Search(cylinder, max_spheres, nullptr);
  if (best.reach <= max_reach) {
    // The fewest balls that still meet the target.
    const Candidate whole = best;
    int fail = 0, pass = max_spheres;
    while (pass - fail > 1) {
      const int mid = (fail + pass) / 2;
      Candidate tried = Search(cylinder, mid, &whole);
      if (tried.reach <= max_reach) {
        pass = mid;
        best = std::move(tried);
      } else {
        fail = mid;
      }
    }
  }
  // The proof: the whole cylinder against every centre.
  const std::vector<Centre> centres = Centres(cylinder, best.layout);
  const std::vector<double> radii = ProveCover(cylinder, centres, kProofTolerance * cylinder.size());
  const double margin = kMargin * cylinder.size() + std::numeric_limits<double>::min();
  FittedSpheres out;
  double reach = 0.0;
  for (std::size_t i = 0; i < centres.size(); ++i) {
    if (radii[i] <= 0.0) continue;  // no cell: not needed
    const Centre& c = centres[i];
    out.centres.emplace_back(c.radial * c.cos_angle, c.radial * c.sin_angle, c.z);
    out.radii.push_back(radii[i] + margin);
    reach = std::max(reach, out.radii.back() + c.offset);
  }
  out.reach = reach + margin;
  return out;
}

FittedSpheres CoverCapsule(double radius, double length, double max_reach, int max_spheres) {
  // n balls, spacing s = L/(n − 1), reach √(r² + s²/4) − r; one ball: reach L/2.
  const double margin = kMargin * (radius + 0.5 * length) + std::numeric_limits<double>::min();
  int count = max_spheres;
  if (0.5 * length <= max_reach) {
    count = 1;
  } else {
    const double half_spacing = std::sqrt(max_reach * (2.0 * radius + max_reach));  // √((r + δ)² − r²)
    const double needed = std::ceil(length / (2.0 * half_spacing) - 1e-12) + 1.0;
    count = static_cast<int>(std::min<double>(max_spheres, std::max(2.0, needed)));
  }
  FittedSpheres out;
  if (count == 1) {
    out.centres = {Eigen::Vector3d::Zero()};
    out.radii = {0.5 * length + radius + margin};
    out.reach = 0.5 * length + 2.0 * margin;
    return out;
  }
  const double spacing = length / (count - 1);
  const double ball = std::hypot(radius, 0.5 * spacing) + margin;
  for (int i = 0; i < count; ++i) {
    out.centres.emplace_back(0.0, 0.0, i + 1 == count ? 0.5 * length : -0.5 * length + i * spacing);
    out.radii.push_back(ball);
  }
  out.reach = ball - radius + margin;
  return out;
}

double BoxReach(const Eigen::Vector3d& size, const FittedSpheres& spheres) {
  const Eigen::Vector3d half = 0.5 * size;
  double reach = 0.0;
  for (std::size_t i = 0; i < spheres.centres.size(); ++i) {
    const Eigen::Vector3d q = spheres.centres[i].cwiseAbs() - half;
    const double signed_distance = q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
    reach = std::max(reach, spheres.radii[i] + signed_distance);
  }
  return reach + kMargin * half.sum() + std::numeric_limits<double>::min();
}

}  // namespace chasles
