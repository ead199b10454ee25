// FitSpheres: a conservative sphere decomposition of a triangle mesh on a voxel grid.
//
// Method. A grid of cubic voxels (edge h) covers the mesh's bounding box plus a padding. The
// elements to cover are closed boxes:
//  - surface: for each voxel whose closed cube a triangle touches, the sub-cubes (kSub per edge)
//    a triangle touches, by an exact separating-axis test with an outward slack for rounding;
//  - enclosed (closed meshes only): whole voxels that no triangle touches, that a flood fill from
//    the grid's border through untouched voxels does not reach, and whose ray parity is odd; and
//    the untouched sub-cubes of touched voxels whose ray parity is odd.
// Coverage: every point of a triangle lies in a closed sub-cube the triangle touches, which is an
// element. A point p the mesh encloses, not in a touched voxel, lies in an untouched voxel V: V is
// not reached by the flood fill (a chain of untouched, face-adjacent closed cubes from the border
// to V is a path from outside the mesh's bounding box to p that crosses no triangle, so p would be
// outside), and V's parity is odd (V's closed cube is connected and touches no triangle, so the
// parity is the same at each of its points). A point p the mesh encloses in a touched voxel lies
// in a touched sub-cube or in an untouched one, whose parity is likewise that of p: odd. So every
// point of the solid lies in an element. (A row whose parity cannot be decided makes all its
// candidates elements.) A ball contains a box iff it contains the box's farthest corner from its
// centre, so a ball that passes that test (with a margin for rounding) contains the element
// whole: coverage is exact.
// Closedness welds vertices within 1e-12 of the extent (a single-precision export may leave the
// two copies of a seam vertex 1e-17 apart); that is far below the slack of the surface test and
// the margins of the parity test, so both see the welded, closed mesh.
//
// Distances. For each voxel W, d(W) is an upper bound on the distance from W's centre to the
// solid: 0 for an enclosed voxel, the distance to a triangle touching W for a surface voxel, and
// for the others a chamfer propagation d(W) <= d(N) + |c(W) − c(N)| over the 26 neighbours (the
// triangle inequality keeps it an upper bound), carrying N's nearest triangle along as W's
// witness and finally tightened to the exact distance to that witness. Every point of W's cube is
// within U(W) = d(W) + (√3/2)·h of the solid.
//
// Choice. For a nominal R, a candidate ball sits at each voxel centre with, as radius, its
// clearance in the cubes whose centres have d <= R (the distance to the nearest other cube, or to
// the grid's outside: a separable transform, exact). A greedy sweep along the grid's longest axis
// takes the first uncovered element and, among the balls that contain it, the one covering the
// most uncovered sub-cubes (an enclosed voxel counts as kSub³), scored over the kScored widest
// (on a lattice when they are wide, always with the widest); each chosen ball shrinks to the
// farthest corner of the elements it covered. The nominal R is bisected between a value the
// budget fails and one it meets; each doubling of R gets its own grid (coarser when the cap
// requires, padded so the balls fit). From the cover the bisection settles on, every ball whose
// elements all lie in other kept balls is then dropped, in the order chosen: a ball chosen early
// for the first uncovered element is often covered over by later ones (on the UR5's cylinder
// meshes, 203 of 259 balls are kept, at the same reach). Letting the greedy choose twice the
// budget and pruning down to it instead gives, with a budget of 32, the same 203 balls and reach,
// and fits up to 1.7× slower. The last resort is one ball around all vertices, also
// returned whenever its reach is smaller.
//
// Reach, proven per final ball as the smaller of two bounds: the largest U of the cubes it meets,
// and a branch and bound over an octree of its bounding cube, where a cell with centre q and
// half-edge e is bounded by b(q) + min(√3·e, |q − centre| + radius) — b(q) being 0 in an enclosed
// voxel, else the least of d(N) + |q − c(N)| and the exact distance from q to N's witness over the
// 27 voxels N about q (the distance to the solid is 1-Lipschitz). Cells are split, widest bound
// first, until that bound is within kTolerance voxels of the largest b seen at a point of the ball
// or below the bound already reported. The reported reach is the largest of these, plus the
// rounding margins.
// (Voxel cover with inscribed balls follows the spirit of sphere-tree builders such as Hubbard,
// "Approximating polyhedra with spheres for time-critical collision detection", ACM TOG 1996, and
// Bradshaw & O'Sullivan, "Adaptive medial-axis approximation for sphere-tree construction", ACM
// TOG 2004; the triangle-box test is the separating-axis test of Akenine-Möller, "Fast 3D
// triangle-box overlap testing", JGT 2001. Written from the ideas, no code taken.)

#include "chasles/collision/sphere_fit.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "chasles/robot/error.h"

namespace chasles {
namespace {

using Eigen::Vector3d;

constexpr int kSub = 4;                              // sub-cubes per voxel edge: kSub³ = 64 bits
constexpr std::uint64_t kWholeVoxel = ~std::uint64_t{0};
constexpr int kPad = 2;                              // voxels around the bounding box
constexpr double kVoxelsPerReach = 6.0;              // h >= max_reach / this
constexpr std::size_t kScored = 32;                  // balls scored per choice of the greedy
constexpr int kLatticeDivisions = 8;                 // their lattice: the widest ball's radius / this
constexpr double kNominalBelow = 0.5;                // nominal R tried down to max_reach − this · h
constexpr int kBisections = 3;                       // of the nominal R between fail and pass
constexpr double kTolerance = 0.1;                   // of BallReach, in voxels
constexpr double kWeld = 1e-12;                      // vertices within this of the extent are welded
constexpr int kParityTries = 32;                     // rays per row before giving up on parity
constexpr int kMinVoxelsPerAxis = 4, kMaxVoxelsPerAxis = 256;
constexpr double kInf = std::numeric_limits<double>::infinity();
const double kHalfDiagonal = 0.5 * std::sqrt(3.0);

int PopCount(std::uint64_t bits) {  // SWAR: no call into libgcc when the target lacks popcnt
  bits -= (bits >> 1) & 0x5555555555555555ULL;
  bits = (bits & 0x3333333333333333ULL) + ((bits >> 2) & 0x3333333333333333ULL);
  bits = (bits + (bits >> 4)) & 0x0f0f0f0f0f0f0f0fULL;
  return static_cast<int>((bits * 0x0101010101010101ULL) >> 56);
}
int LowestBit(std::uint64_t bits) { return __builtin_ctzll(bits); }

/// The voxel grid: voxel (i, j, k) is the closed cube origin + h·([i, i+1] × [j, j+1] × [k, k+1]).
/// Geometry is handled in grid-local coordinates (mesh frame minus origin).
struct Grid {
  Vector3d origin = Vector3d::Zero();  // [m], mesh frame
  double h = 0.0;                      // [m] voxel edge
  int n[3] = {0, 0, 0};

  std::size_t size() const { return static_cast<std::size_t>(n[0]) * n[1] * n[2]; }
  std::size_t Index(int i, int j, int k) const { return (static_cast<std::size_t>(k) * n[1] + j) * n[0] + i; }
  /// The voxel holding local coordinate x on `axis`, clamped to the grid.
  int Cell(double x, int axis) const {
    return static_cast<int>(std::clamp(std::floor(x / h), 0.0, static_cast<double>(n[axis] - 1)));
  }
  Vector3d Centre(int i, int j, int k) const { return h * Vector3d(i + 0.5, j + 0.5, k + 0.5); }
};

/// Separating-axis test of a triangle, given relative to a cube's centre, against the cube
/// [−e, e]³: the cube's 3 face normals, the triangle's normal and the 9 cross products of their
/// edges. False only when one of the axes separates them; a zero axis (a degenerate triangle)
/// never separates, and a segment or point is still tested exactly by the remaining axes.
bool TriangleTouchesCube(const Vector3d& a, const Vector3d& b, const Vector3d& c, double e) {
  for (int i = 0; i < 3; ++i) {
    if (std::min({a[i], b[i], c[i]}) > e || std::max({a[i], b[i], c[i]}) < -e) return false;
  }
  const auto separates = [&](const Vector3d& axis) {
    const double pa = axis.dot(a), pb = axis.dot(b), pc = axis.dot(c);
    const double r = e * axis.cwiseAbs().sum();
    return std::min({pa, pb, pc}) > r || std::max({pa, pb, pc}) < -r;
  };
  const Vector3d edges[3] = {b - a, c - b, a - c};
  if (separates(edges[0].cross(edges[1]))) return false;
  for (const Vector3d& f : edges) {
    if (separates(Vector3d(0.0, -f.z(), f.y())) || separates(Vector3d(f.z(), 0.0, -f.x())) ||
        separates(Vector3d(-f.y(), f.x(), 0.0))) {
      return false;
    }
  }
  return true;
}

Vector3d NearestOnSegment(const Vector3d& p, const Vector3d& a, const Vector3d& b) {
  const Vector3d d = b - a;
  const double dd = d.squaredNorm();
  const double t = dd > 0.0 ? std::clamp((p - a).dot(d) / dd, 0.0, 1.0) : 0.0;
  return a + t * d;
}

/// |p − q| for a point q of triangle (a, b, c) nearest p (up to rounding): an upper bound on
/// the distance from p to the triangle by construction, whatever the triangle's shape.
double TriangleDistanceBound(const Vector3d& p, const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  const Vector3d normal = (b - a).cross(c - a);
  const double nn = normal.squaredNorm();
  if (nn > 0.0) {
    const Vector3d q = p - normal * ((p - a).dot(normal) / nn);
    if ((b - a).cross(q - a).dot(normal) >= 0.0 && (c - b).cross(q - b).dot(normal) >= 0.0 &&
        (a - c).cross(q - c).dot(normal) >= 0.0) {
      return (p - q).norm();
    }
  }
  return std::min({(p - NearestOnSegment(p, a, b)).norm(), (p - NearestOnSegment(p, b, c)).norm(),
                   (p - NearestOnSegment(p, c, a)).norm()});
}

void ValidateMesh(const TriangleMesh& mesh) {
  if (mesh.triangles.empty()) ThrowInvalid("mesh has no triangles; a sphere fit needs at least one");
  const long num_vertices = static_cast<long>(mesh.vertices.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const int index = mesh.triangles[t][k];
      if (index < 0 || index >= num_vertices) {
        ThrowInvalid("mesh.triangles[" + std::to_string(t) + "][" + std::to_string(k) + "] = " +
                     std::to_string(index) + " is out of range [0, " + std::to_string(num_vertices) + ")");
      }
    }
  }
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    const Vector3d& p = mesh.vertices[v];
    if (!p.allFinite()) {
      ThrowInvalid("mesh.vertices[" + std::to_string(v) + "] = (" + FormatNumber(p.x()) + ", " + FormatNumber(p.y()) +
                   ", " + FormatNumber(p.z()) + ") must be finite");
    }
  }
}

/// True when every edge, between vertices welded when within `weld_distance` of each other (max
/// norm, to a first vertex of their cluster in (x, y, z) order; a mesh exported in single precision may place the
/// seam's two copies of a vertex 1e-17 apart), is shared by an even number of triangles: the
/// welded triangles then bound (mod 2), and ray parity is the same for every ray.
bool IsClosed(const TriangleMesh& mesh, double weld_distance) {
  std::vector<int> order(mesh.vertices.size());
  for (std::size_t v = 0; v < order.size(); ++v) order[v] = static_cast<int>(v);
  const auto less = [&](int a, int b) {
    const Vector3d &p = mesh.vertices[a], &q = mesh.vertices[b];
    return p.x() != q.x() ? p.x() < q.x() : p.y() != q.y() ? p.y() < q.y() : p.z() < q.z();
  };
  std::sort(order.begin(), order.end(), less);
  std::vector<int> weld(order.size());
  for (std::size_t s = 0; s < order.size(); ++s) {
    const Vector3d& p = mesh.vertices[order[s]];
    weld[order[s]] = order[s];
    // Exact copies are adjacent in this order; near ones are looked for among the 64 before (a
    // weld missed only makes the mesh open, which is always safe).
    for (std::size_t r = s; r-- > 0 && r + 64 >= s && mesh.vertices[order[r]].x() >= p.x() - weld_distance;) {
      const int o = order[r];
      if (weld[o] == o && (mesh.vertices[o] - p).cwiseAbs().maxCoeff() <= weld_distance) {
        weld[order[s]] = o;
        break;
      }
    }
  }
  std::vector<std::uint64_t> edges;
  edges.reserve(3 * mesh.triangles.size());
  for (const Eigen::Vector3i& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      const std::uint64_t a = weld[t[k]], b = weld[t[(k + 1) % 3]];
      if (a != b) edges.push_back(std::min(a, b) << 32 | std::max(a, b));
    }
  }
  std::sort(edges.begin(), edges.end());
  for (std::size_t s = 0; s < edges.size();) {
    std::size_t e = s;
    while (e < edges.size() && edges[e] == edges[s]) ++e;
    if ((e - s) % 2 != 0) return false;
    s = e;
  }
  return true;
}

/// The state of the fit on the grid.
struct Voxels {
  std::vector<std::uint64_t> elements;  // sub-cubes to cover (kWholeVoxel for an enclosed voxel)
  std::vector<std::uint8_t> touched;    // a triangle touches the voxel's closed cube
  std::vector<std::uint8_t> outside;    // reached by the flood fill from the border
  std::vector<std::uint8_t> inside;     // enclosed: the whole closed cube lies in the solid
  std::vector<int> witness;             // a triangle at distance(centre) of the centre, or −1
  std::vector<double> reach;            // U: bound on the distance from the cube to the solid [m]
};

/// Marks the sub-cubes each triangle touches and bounds the touched voxels' centre distances.
void MarkSurface(const Grid& grid, const std::vector<Vector3d>& local, const TriangleMesh& mesh, double slack,
                 Voxels* voxels, std::vector<double>* distance) {
  const double hs = grid.h / kSub;
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Vector3d &a = local[t[0]], &b = local[t[1]], &c = local[t[2]];
    const Vector3d lo = a.cwiseMin(b).cwiseMin(c).array() - slack, hi = a.cwiseMax(b).cwiseMax(c).array() + slack;
    int c0[3], c1[3];
    for (int axis = 0; axis < 3; ++axis) {
      c0[axis] = grid.Cell(lo[axis], axis);
      c1[axis] = grid.Cell(hi[axis], axis);
    }
    for (int k = c0[2]; k <= c1[2]; ++k) {
      for (int j = c0[1]; j <= c1[1]; ++j) {
        for (int i = c0[0]; i <= c1[0]; ++i) {
          const Vector3d centre = grid.Centre(i, j, k);
          if (!TriangleTouchesCube(a - centre, b - centre, c - centre, 0.5 * grid.h + slack)) continue;
          const int cell[3] = {i, j, k};
          int s0[3], s1[3];
          for (int axis = 0; axis < 3; ++axis) {
            const double base = cell[axis] * kSub;
            s0[axis] = static_cast<int>(std::clamp(std::floor(lo[axis] / hs) - base, 0.0, kSub - 1.0));
            s1[axis] = static_cast<int>(std::clamp(std::floor(hi[axis] / hs) - base, 0.0, kSub - 1.0));
          }
          std::uint64_t bits = 0;
          for (int sz = s0[2]; sz <= s1[2]; ++sz) {
            for (int sy = s0[1]; sy <= s1[1]; ++sy) {
              for (int sx = s0[0]; sx <= s1[0]; ++sx) {
                const Vector3d sub = hs * Vector3d(i * kSub + sx + 0.5, j * kSub + sy + 0.5, k * kSub + sz + 0.5);
                if (TriangleTouchesCube(a - sub, b - sub, c - sub, 0.5 * hs + slack)) {
                  bits |= std::uint64_t{1} << (sx + kSub * (sy + kSub * sz));
                }
              }
            }
          }
          if (bits == 0) continue;
          const std::size_t v = grid.Index(i, j, k);
          voxels->elements[v] |= bits;
          voxels->touched[v] = 1;
          const double d = TriangleDistanceBound(centre, a, b, c);
          if (d < (*distance)[v]) {
            (*distance)[v] = d;
            voxels->witness[v] = static_cast<int>(&t - mesh.triangles.data());
          }
        }
      }
    }
  }
}

/// Flood fill (6-connected) from the grid's border through untouched voxels.
void FloodOutside(const Grid& grid, Voxels* voxels) {
  std::vector<std::size_t> queue;
  const auto visit = [&](int i, int j, int k) {
    const std::size_t v = grid.Index(i, j, k);
    if (voxels->touched[v] || voxels->outside[v]) return;
    voxels->outside[v] = 1;
    queue.push_back(v);
  };
  for (int k = 0; k < grid.n[2]; ++k) {
    for (int j = 0; j < grid.n[1]; ++j) {
      for (int i = 0; i < grid.n[0]; ++i) {
        const bool border =
            i == 0 || j == 0 || k == 0 || i == grid.n[0] - 1 || j == grid.n[1] - 1 || k == grid.n[2] - 1;
        if (border) visit(i, j, k);
      }
    }
  }
  for (std::size_t head = 0; head < queue.size(); ++head) {
    const std::size_t v = queue[head];
    const int i = static_cast<int>(v % grid.n[0]), j = static_cast<int>(v / grid.n[0] % grid.n[1]),
              k = static_cast<int>(v / grid.n[0] / grid.n[1]);
    if (i > 0) visit(i - 1, j, k);
    if (i + 1 < grid.n[0]) visit(i + 1, j, k);
    if (j > 0) visit(i, j - 1, k);
    if (j + 1 < grid.n[1]) visit(i, j + 1, k);
    if (k > 0) visit(i, j, k - 1);
    if (k + 1 < grid.n[2]) visit(i, j, k + 1);
  }
}

/// For a closed mesh: the untouched voxels the flood fill did not reach, by ray parity per grid
/// row (a line along x through the row's cross-section). A triangle is decided only when clearly
/// crossed (its three yz edge functions share a sign by a margin far above rounding: the line
/// crosses its interior transversally) or clearly missed (two have opposite signs by that margin,
/// or its yz box misses the line); otherwise the line moves within the cross-section and the row
/// is tried again. Odd voxels become elements with distance 0; a row never decided makes its
/// voxels elements with a propagated distance (covered, and honestly bounded).
void MarkEnclosed(const Grid& grid, const std::vector<Vector3d>& local, const TriangleMesh& mesh, double slack,
                  Voxels* voxels, std::vector<double>* distance) {
  const int rows = grid.n[1] * grid.n[2];
  std::vector<std::uint8_t> needed(rows, 0);
  bool any = false;
  for (int r = 0; r < rows; ++r) {
    const std::size_t base = static_cast<std::size_t>(r) * grid.n[0];
    for (int i = 0; i < grid.n[0] && !needed[r]; ++i) {
      if (!voxels->outside[base + i]) needed[r] = 1;  // an untouched inner voxel, or a touched one
    }
    any = any || needed[r];
  }
  if (!any) return;
  // Triangles per needed row, by their yz boxes (compressed rows).
  std::vector<int> start(rows + 1, 0), list;
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<int> fill;
    if (pass == 1) {
      for (int r = 0; r < rows; ++r) start[r + 1] += start[r];
      list.resize(start[rows]);
      fill.assign(start.begin(), start.end() - 1);
    }
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      const Eigen::Vector3i& tri = mesh.triangles[t];
      const Vector3d &a = local[tri[0]], &b = local[tri[1]], &c = local[tri[2]];
      const int j0 = grid.Cell(std::min({a.y(), b.y(), c.y()}) - slack, 1);
      const int j1 = grid.Cell(std::max({a.y(), b.y(), c.y()}) + slack, 1);
      const int k0 = grid.Cell(std::min({a.z(), b.z(), c.z()}) - slack, 2);
      const int k1 = grid.Cell(std::max({a.z(), b.z(), c.z()}) + slack, 2);
      for (int k = k0; k <= k1; ++k) {
        for (int j = j0; j <= j1; ++j) {
          const int r = j + grid.n[1] * k;
          if (!needed[r]) continue;
          if (pass == 0) {
            ++start[r + 1];
          } else {
            list[fill[r]++] = static_cast<int>(t);
          }
        }
      }
    }
  }
  std::vector<double> crossings;
  const double h = grid.h, hs = h / kSub;
  // The x of the crossings of the line (y, z) = (py, pz) along x with the row's triangles, sorted;
  // false when the line passes too near an edge, a vertex or a triangle's plane to decide.
  const auto cast = [&](int r, double py, double pz) {
    crossings.clear();
    for (int s = start[r]; s < start[r + 1]; ++s) {
      const Eigen::Vector3i& tri = mesh.triangles[list[s]];
      const Vector3d &a = local[tri[0]], &b = local[tri[1]], &c = local[tri[2]];
      const double ay = a.y() - py, az = a.z() - pz, by = b.y() - py, bz = b.z() - pz, cy = c.y() - py,
                   cz = c.z() - pz;
      if (std::max({ay, by, cy}) < -slack || std::min({ay, by, cy}) > slack || std::max({az, bz, cz}) < -slack ||
          std::min({az, bz, cz}) > slack) {
        continue;
      }
      // Edge functions: twice the signed yz areas of (line, b, c), (line, c, a), (line, a, b).
      const double wa = by * cz - bz * cy, wb = cy * az - cz * ay, wc = ay * bz - az * by;
      // Margins far above the rounding of the products and of the vertices' local coordinates.
      const double la = std::abs(ay) + std::abs(az), lb = std::abs(by) + std::abs(bz);
      const double lc = std::abs(cy) + std::abs(cz);
      const double ta = 1e-9 * (std::abs(by * cz) + std::abs(bz * cy)) + slack * (lb + lc);
      const double tb = 1e-9 * (std::abs(cy * az) + std::abs(cz * ay)) + slack * (lc + la);
      const double tc = 1e-9 * (std::abs(ay * bz) + std::abs(az * by)) + slack * (la + lb);
      const int positive = (wa > ta) + (wb > tb) + (wc > tc), negative = (wa < -ta) + (wb < -tb) + (wc < -tc);
      if (positive == 3 || negative == 3) {
        const double sum = wa + wb + wc;
        crossings.push_back(a.x() + (wb * (b.x() - a.x()) + wc * (c.x() - a.x())) / sum);
      } else if (positive == 0 || negative == 0) {
        return false;  // the line passes near an edge or a vertex, or in the triangle's plane
      }
    }
    std::sort(crossings.begin(), crossings.end());
    return true;
  };
  // The line's offset within a cross-section cell: its centre first, then a low-discrepancy walk
  // over its middle 80 %.
  const auto offset = [](int attempt, double* u, double* w) {
    *u = attempt == 0 ? 0.5 : 0.1 + 0.8 * std::fmod(0.5 + attempt * 0.7548776662466927, 1.0);
    *w = attempt == 0 ? 0.5 : 0.1 + 0.8 * std::fmod(0.5 + attempt * 0.5698402909980532, 1.0);
  };
  for (int r = 0; r < rows; ++r) {
    if (!needed[r]) continue;
    const int j = r % grid.n[1], k = r / grid.n[1];
    const std::size_t base = static_cast<std::size_t>(r) * grid.n[0];
    bool decided = false, inner = false, surface = false;
    for (int i = 0; i < grid.n[0]; ++i) {
      inner = inner || (!voxels->touched[base + i] && !voxels->outside[base + i]);
      surface = surface || voxels->touched[base + i];
    }
    if (inner) {
      for (int attempt = 0; attempt < kParityTries && !decided; ++attempt) {
        double u, w;
        offset(attempt, &u, &w);
        decided = cast(r, (j + u) * h, (k + w) * h);
      }
      std::size_t before = 0;
      for (int i = 0; i < grid.n[0]; ++i) {
        const std::size_t v = base + i;
        if (voxels->touched[v] || voxels->outside[v]) continue;
        if (!decided) {
          voxels->elements[v] = kWholeVoxel;
          continue;
        }
        // A crossing lies in a touched cube, so more than h/2 from this untouched voxel's centre.
        const double x = (i + 0.5) * h;
        while (before < crossings.size() && crossings[before] < x) ++before;
        if ((crossings.size() - before) % 2 == 1) {
          voxels->elements[v] = kWholeVoxel;
          voxels->inside[v] = 1;
          (*distance)[v] = 0.0;
          voxels->witness[v] = -1;
        }
      }
    }
    if (!surface) continue;
    // The untouched sub-cubes of touched voxels, by the same parity on lines through the centres
    // of the sub-cubes' cross-sections: an untouched closed sub-cube is connected and touches no
    // triangle, so its parity is that of any of its points; odd ones become elements too.
    for (int sk = 0; sk < kSub; ++sk) {
      for (int sj = 0; sj < kSub; ++sj) {
        bool known = false;
        for (int attempt = 0; attempt < kParityTries && !known; ++attempt) {
          double u, w;
          offset(attempt, &u, &w);
          known = cast(r, (j * kSub + sj + u) * hs, (k * kSub + sk + w) * hs);
        }
        std::size_t before = 0;
        for (int i = 0; i < grid.n[0]; ++i) {
          const std::size_t v = base + i;
          if (!voxels->touched[v]) continue;
          for (int sx = 0; sx < kSub; ++sx) {
            const std::uint64_t bit = std::uint64_t{1} << (sx + kSub * (sj + kSub * sk));
            if (voxels->elements[v] & bit) continue;
            // Never decided: an element anyway (covered, and the reach is bounded wherever it is).
            bool odd = true;
            if (known) {
              const double x = (i * kSub + sx + 0.5) * hs;
              while (before < crossings.size() && crossings[before] < x) ++before;
              odd = (crossings.size() - before) % 2 == 1;
            }
            if (odd) voxels->elements[v] |= bit;
          }
        }
      }
    }
  }
}

/// Chamfer propagation over the 26 neighbours, one forward and one backward raster pass: each
/// update d(W) = min(d(W), d(N) + |c(W) − c(N)|) keeps d an upper bound (triangle inequality).
void PropagateDistance(const Grid& grid, const std::vector<Vector3d>& local, const TriangleMesh& mesh,
                       std::vector<double>* distance, std::vector<int>* witness) {
  struct Step {
    int di, dj, dk;
    double length;
  };
  std::vector<Step> back;  // neighbours earlier in raster order
  for (int dk = -1; dk <= 1; ++dk) {
    for (int dj = -1; dj <= 1; ++dj) {
      for (int di = -1; di <= 1; ++di) {
        if (dk < 0 || (dk == 0 && (dj < 0 || (dj == 0 && di < 0)))) {
          back.push_back({di, dj, dk, grid.h * std::sqrt(double(di * di + dj * dj + dk * dk))});
        }
      }
    }
  }
  std::vector<double>& d = *distance;
  const auto relax = [&](int i, int j, int k, int sign) {
    const std::size_t v = grid.Index(i, j, k);
    double& here = d[v];
    for (const Step& s : back) {
      const int a = i + sign * s.di, b = j + sign * s.dj, c = k + sign * s.dk;
      if (a < 0 || b < 0 || c < 0 || a >= grid.n[0] || b >= grid.n[1] || c >= grid.n[2]) continue;
      const std::size_t n = grid.Index(a, b, c);
      if (d[n] + s.length < here) here = d[n] + s.length, (*witness)[v] = (*witness)[n];
    }
  };
  for (int k = 0; k < grid.n[2]; ++k) {
    for (int j = 0; j < grid.n[1]; ++j) {
      for (int i = 0; i < grid.n[0]; ++i) relax(i, j, k, 1);
    }
  }
  for (int k = grid.n[2] - 1; k >= 0; --k) {
    for (int j = grid.n[1] - 1; j >= 0; --j) {
      for (int i = grid.n[0] - 1; i >= 0; --i) relax(i, j, k, -1);
    }
  }
  // The witness's own distance: still the distance to a point of the solid, and much tighter than
  // the chain of steps far from the surface.
  for (int k = 0; k < grid.n[2]; ++k) {
    for (int j = 0; j < grid.n[1]; ++j) {
      for (int i = 0; i < grid.n[0]; ++i) {
        const std::size_t v = grid.Index(i, j, k);
        const int t = (*witness)[v];
        if (t < 0) continue;
        const Eigen::Vector3i& tri = mesh.triangles[t];
        d[v] = std::min(d[v], TriangleDistanceBound(grid.Centre(i, j, k), local[tri[0]], local[tri[1]], local[tri[2]]));
      }
    }
  }
}

/// Squared clearance, in voxel units, of each voxel centre in A (the cubes whose `value` is <=
/// `limit`): the squared distance to the nearest cube outside A or outside the grid, exactly. Per axis
/// an offset of d voxels contributes φ(d) = (|d| − 1/2)² (0 for d = 0), so the minimum over cubes
/// separates into three one-dimensional passes.
void Clearance(const Grid& grid, const std::vector<double>& value, double limit, std::vector<double>* squared) {
  std::vector<double>& g = *squared;
  const int nx = grid.n[0];
  for (std::size_t row = 0; row < grid.size() / nx; ++row) {
    const std::size_t base = row * nx;
    int last = -1;
    for (int i = 0; i < nx; ++i) {
      if (!(value[base + i] <= limit)) last = i;
      g[base + i] = i - last;  // offset to the nearest cube outside A on the left
    }
    last = nx;
    for (int i = nx - 1; i >= 0; --i) {
      if (!(value[base + i] <= limit)) last = i;
      const double d = std::min(g[base + i], static_cast<double>(last - i));
      g[base + i] = d == 0.0 ? 0.0 : (d - 0.5) * (d - 0.5);
    }
  }
  std::vector<double> line;
  const auto pass = [&](int axis) {
    const int n = grid.n[axis];
    const std::size_t stride = axis == 1 ? nx : static_cast<std::size_t>(nx) * grid.n[1];
    line.resize(n);
    for (std::size_t first = 0; first < grid.size(); ++first) {
      if (axis == 1 && first / nx % grid.n[1] != 0) continue;
      if (axis == 2 && first >= stride) break;
      for (int p = 0; p < n; ++p) line[p] = g[first + p * stride];
      for (int p = 0; p < n; ++p) {
        double best = line[p];
        for (int s = 1;; ++s) {
          const double phi = (s - 0.5) * (s - 0.5);
          if (phi >= best) break;
          // Beyond the grid (at −1 and n) counts as outside A.
          if (p - s >= 0) best = std::min(best, phi + line[p - s]);
          if (p - s == -1 || p + s == n) best = std::min(best, phi);
          if (p + s < n) best = std::min(best, phi + line[p + s]);
        }
        g[first + p * stride] = best;
      }
    }
  };
  pass(1);
  pass(2);
}

/// Calls visit(index, di, dj, dk) for every voxel whose cube meets the ball of radius `radius`
/// (voxel units) about the centre of voxel `centre`, within the grid.
template <typename Visit>
void ForVoxelsInBall(const Grid& grid, const int centre[3], double radius, Visit visit) {
  const double r2 = radius * radius;
  const int span = static_cast<int>(std::ceil(radius + 0.5));
  const auto near = [](int d) {
    const double x = std::max(std::abs(d) - 0.5, 0.0);
    return x * x;
  };
  for (int dk = std::max(-span, -centre[2]); dk <= std::min(span, grid.n[2] - 1 - centre[2]); ++dk) {
    const double zz = near(dk);
    if (zz > r2) continue;
    for (int dj = std::max(-span, -centre[1]); dj <= std::min(span, grid.n[1] - 1 - centre[1]); ++dj) {
      const double yy = zz + near(dj);
      if (yy > r2) continue;
      const int dx = static_cast<int>(std::floor(std::sqrt(r2 - yy) + 0.5));
      const std::size_t row = grid.Index(0, centre[1] + dj, centre[2] + dk);
      for (int di = std::max(-dx, -centre[0]); di <= std::min(dx, grid.n[0] - 1 - centre[0]); ++di) {
        visit(row + centre[0] + di, di, dj, dk);
      }
    }
  }
}

/// Squared farthest-corner distances, per sub-cube index along one axis, of the sub-cubes of a
/// voxel `d` voxels from a ball's centre voxel (voxel units, from the centre voxel's centre).
void SubCubeFar(int d, double far[kSub]) {
  for (int s = 0; s < kSub; ++s) {
    const double lo = d - 0.5 + static_cast<double>(s) / kSub, hi = d - 0.5 + static_cast<double>(s + 1) / kSub;
    far[s] = std::max(lo * lo, hi * hi);
  }
}

/// The sub-cubes of the voxel at offset d (voxel units) whose farthest corner is within the ball
/// of squared radius r2 about the centre voxel's centre (up to rounding: Cover measures what it
/// took), as a mask.
std::uint64_t BallMask(int di, int dj, int dk, double r2) {
  static_assert(kSub == 4, "one nibble per row of sub-cubes");
  double fx[kSub], fy[kSub], fz[kSub];
  SubCubeFar(di, fx);
  SubCubeFar(dj, fy);
  SubCubeFar(dk, fz);
  std::uint64_t mask = 0;
  for (int sz = 0; sz < kSub; ++sz) {
    const double tz = r2 - fz[sz];
    if (tz < 0.0) continue;
    for (int sy = 0; sy < kSub; ++sy) {
      const double t = tz - fy[sy];
      if (t < 0.0) continue;
      const std::uint64_t row = static_cast<std::uint64_t>(fx[0] <= t) | static_cast<std::uint64_t>(fx[1] <= t) << 1 |
                                static_cast<std::uint64_t>(fx[2] <= t) << 2 | static_cast<std::uint64_t>(fx[3] <= t) << 3;
      mask |= row << (kSub * (sy + kSub * sz));
    }
  }
  return mask;
}

/// The elements of `bits` (sub-cubes of the voxel at offset d) inside the ball of squared radius
/// r2 (voxel units), and the largest squared farthest-corner distance among them (computed).
std::uint64_t CoveredBits(std::uint64_t bits, int di, int dj, int dk, double r2, double* far2) {
  const double whole = (std::abs(di) + 0.5) * (std::abs(di) + 0.5) + (std::abs(dj) + 0.5) * (std::abs(dj) + 0.5) +
                       (std::abs(dk) + 0.5) * (std::abs(dk) + 0.5);
  *far2 = 0.0;
  if (whole <= r2 && bits == kWholeVoxel) {
    *far2 = whole;
    return bits;
  }
  const std::uint64_t covered = whole <= r2 ? bits : bits & BallMask(di, dj, dk, r2);
  if (covered == 0) return 0;
  double fx[kSub], fy[kSub], fz[kSub];
  SubCubeFar(di, fx);
  SubCubeFar(dj, fy);
  SubCubeFar(dk, fz);
  for (std::uint64_t rest = covered; rest != 0; rest &= rest - 1) {
    const int b = LowestBit(rest);
    *far2 = std::max(*far2, fx[b % kSub] + fy[b / kSub % kSub] + fz[b / (kSub * kSub)]);
  }
  return covered;
}

/// Per grid row (along x), prefix sums of the uncovered sub-cubes: prefix[row·(n0 + 1) + i] counts
/// those of the row's first i voxels.
void UpdatePrefix(const Grid& grid, const std::vector<std::uint64_t>& elements, std::size_t row,
                  std::vector<std::uint32_t>* prefix) {
  const std::size_t n0 = grid.n[0], base = row * n0, out = row * (n0 + 1);
  (*prefix)[out] = 0;
  for (std::size_t i = 0; i < n0; ++i) (*prefix)[out + i + 1] = (*prefix)[out + i] + PopCount(elements[base + i]);
}

/// Number of uncovered sub-cubes the ball (voxel `v`, radius in voxel units) would cover: per row
/// of the ball, the voxels wholly inside by the prefix sums, the others sub-cube by sub-cube.
std::uint64_t Gain(const Grid& grid, const std::vector<std::uint64_t>& elements,
                   const std::vector<std::uint32_t>& prefix, std::size_t v, double radius) {
  const int centre[3] = {static_cast<int>(v % grid.n[0]), static_cast<int>(v / grid.n[0] % grid.n[1]),
                         static_cast<int>(v / grid.n[0] / grid.n[1])};
  const double r2 = radius * radius;
  const int span = static_cast<int>(std::ceil(radius + 0.5));
  const auto near = [](int d) {
    const double x = std::max(std::abs(d) - 0.5, 0.0);
    return x * x;
  };
  const auto far = [](int d) { return (std::abs(d) + 0.5) * (std::abs(d) + 0.5); };
  const int n0 = grid.n[0];
  std::uint64_t gain = 0;
  for (int dk = std::max(-span, -centre[2]); dk <= std::min(span, grid.n[2] - 1 - centre[2]); ++dk) {
    const double zz = near(dk);
    if (zz > r2) continue;
    for (int dj = std::max(-span, -centre[1]); dj <= std::min(span, grid.n[1] - 1 - centre[1]); ++dj) {
      const double yy = zz + near(dj);
      if (yy > r2) continue;
      const int dx = static_cast<int>(std::floor(std::sqrt(r2 - yy) + 0.5));
      const double full = far(dj) + far(dk);
      const int fx = full <= r2 ? std::min(dx, static_cast<int>(std::floor(std::sqrt(r2 - full) - 0.5))) : -1;
      const std::size_t row = static_cast<std::size_t>(centre[2] + dk) * grid.n[1] + centre[1] + dj;
      const std::size_t base = row * n0;
      const int lo = std::max(-dx, -centre[0]), hi = std::min(dx, n0 - 1 - centre[0]);
      int inner_lo = lo, inner_hi = lo - 1;
      if (fx >= 0) {
        inner_lo = std::max(-fx, lo);
        inner_hi = std::min(fx, hi);
        if (inner_lo <= inner_hi) {
          gain += prefix[row * (n0 + 1) + centre[0] + inner_hi + 1] - prefix[row * (n0 + 1) + centre[0] + inner_lo];
        } else {
          inner_lo = lo, inner_hi = lo - 1;
        }
      }
      // The partly covered voxels: [lo, inner_lo) and (inner_hi, hi], skipped when empty.
      const std::uint32_t* sums = prefix.data() + row * (n0 + 1) + centre[0];
      const auto partial = [&](int from, int to) {
        if (from > to || sums[to + 1] == sums[from]) return;
        for (int di = from; di <= to; ++di) {
          const std::uint64_t bits = elements[base + centre[0] + di];
          if (bits != 0) gain += PopCount(bits & BallMask(di, dj, dk, r2));
        }
      };
      if (inner_lo <= inner_hi) {
        partial(lo, inner_lo - 1);
        partial(inner_hi + 1, hi);
      } else {
        partial(lo, hi);
      }
    }
  }
  return gain;
}

/// Removes what the ball covers from `elements`; returns the radius (voxel units) that the
/// elements it covered need, and the count covered.
double Cover(const Grid& grid, std::vector<std::uint64_t>* elements, std::size_t v, double radius,
             std::uint64_t* count, std::vector<std::uint32_t>* prefix) {
  const int centre[3] = {static_cast<int>(v % grid.n[0]), static_cast<int>(v / grid.n[0] % grid.n[1]),
                         static_cast<int>(v / grid.n[0] / grid.n[1])};
  double needed2 = 0.0;
  ForVoxelsInBall(grid, centre, radius, [&](std::size_t w, int di, int dj, int dk) {
    if ((*elements)[w] == 0) return;
    double far2;
    const std::uint64_t covered = CoveredBits((*elements)[w], di, dj, dk, radius * radius, &far2);
    if (covered == 0) return;
    (*elements)[w] &= ~covered;
    *count += PopCount(covered);
    needed2 = std::max(needed2, far2);
  });
  const int span = static_cast<int>(std::ceil(radius + 0.5));
  for (int k = std::max(0, centre[2] - span); k <= std::min(grid.n[2] - 1, centre[2] + span); ++k) {
    for (int j = std::max(0, centre[1] - span); j <= std::min(grid.n[1] - 1, centre[1] + span); ++j) {
      UpdatePrefix(grid, *elements, static_cast<std::size_t>(k) * grid.n[1] + j, prefix);
    }
  }
  return std::sqrt(needed2);
}

struct Ball {
  std::size_t voxel;
  double radius;  // voxel units, as needed by the elements it covers
};

/// Drops, in the order they were chosen, the balls whose every element also lies in another kept
/// ball. The greedy chooses a ball for the first uncovered element, so a ball chosen early is often
/// covered over by those chosen after it. An element's count is its balls containing it whole
/// (the voxel's elements all inside: one count per voxel) plus those containing its sub-cube.
void DropRedundant(const Grid& grid, const std::vector<std::uint64_t>& initial, std::vector<Ball>* balls) {
  std::vector<std::int32_t> slot(grid.size(), -1);
  // Counts are 32-bit: a budget (max_spheres) has no upper bound, and a count that wrapped
  // would drop a ball still needed.
  std::vector<std::uint32_t> whole;               // per slot
  std::vector<std::int32_t> partial_of;           // per slot: its row of `partial`, or -1
  std::vector<std::array<std::uint32_t, 64>> partial;
  // Visits the elements of each voxel ball `b` contains (radius with a relative 1e-12 above the
  // needed one, far below the 1e-9·h rounding margin the fitted radius gets).
  const auto for_held = [&](const Ball& ball, auto visit) {
    const int centre[3] = {static_cast<int>(ball.voxel % grid.n[0]), static_cast<int>(ball.voxel / grid.n[0] % grid.n[1]),
                           static_cast<int>(ball.voxel / grid.n[0] / grid.n[1])};
    const double radius = ball.radius * (1.0 + 1e-12);
    ForVoxelsInBall(grid, centre, radius, [&](std::size_t w, int di, int dj, int dk) {
      if (initial[w] == 0) return;
      double far2;
      const std::uint64_t bits = CoveredBits(initial[w], di, dj, dk, radius * radius, &far2);
      if (bits != 0) visit(w, bits);
    });
  };
  for (const Ball& ball : *balls) {
    for_held(ball, [&](std::size_t w, std::uint64_t bits) {
      if (slot[w] < 0) {
        slot[w] = static_cast<std::int32_t>(whole.size());
        whole.push_back(0);
        partial_of.push_back(-1);
      }
      const std::int32_t s = slot[w];
      if (bits == initial[w]) {
        ++whole[s];
        return;
      }
      if (partial_of[s] < 0) {
        partial_of[s] = static_cast<std::int32_t>(partial.size());
        partial.emplace_back().fill(0);
      }
      for (std::uint64_t rest = bits; rest != 0; rest &= rest - 1) ++partial[partial_of[s]][LowestBit(rest)];
    });
  }
  std::vector<Ball> kept;
  for (const Ball& ball : *balls) {
    bool redundant = true;
    for_held(ball, [&](std::size_t w, std::uint64_t bits) {
      if (!redundant) return;
      const std::int32_t s = slot[w];
      if (whole[s] >= 2) return;
      for (std::uint64_t rest = bits; rest != 0 && redundant; rest &= rest - 1) {
        redundant = whole[s] + (partial_of[s] < 0 ? 0 : partial[partial_of[s]][LowestBit(rest)]) >= 2;
      }
    });
    if (!redundant) {
      kept.push_back(ball);
      continue;
    }
    for_held(ball, [&](std::size_t w, std::uint64_t bits) {
      const std::int32_t s = slot[w];
      if (bits == initial[w]) {
        --whole[s];
        return;
      }
      for (std::uint64_t rest = bits; rest != 0; rest &= rest - 1) --partial[partial_of[s]][LowestBit(rest)];
    });
  }
  *balls = std::move(kept);
}

/// Greedy cover of `initial` (copied into `work`) by candidate balls (radius² `clearance2` per
/// voxel centre, voxel units), swept along the grid's longest axis: the first uncovered element in
/// sweep order gets, among the balls that contain it, the one covering the most uncovered
/// sub-cubes (scored over the kScored largest, on a lattice when the balls are wide, and always
/// the widest). False when the budget is not met or no candidate contains an element.
/// `margin` is the rounding margin in voxel units; `prefix_work` holds the row sums Gain uses.
bool GreedyCover(const Grid& grid, const std::vector<std::uint64_t>& initial, const std::vector<double>& clearance2,
                 double margin, int max_balls, std::vector<Ball>* balls, std::vector<std::uint64_t>* work,
                 std::vector<std::uint32_t>* prefix_work) {
  std::vector<std::uint64_t>& elements = *work;
  elements.assign(initial.begin(), initial.end());
  balls->clear();
  double largest = 0.0;
  for (double c : clearance2) largest = std::max(largest, c);
  const auto radius_at = [&](std::size_t v) { return std::sqrt(clearance2[v]) - 2.0 * margin; };
  // Voxels holding elements, in sweep order: the longest axis outermost.
  int axes[3] = {0, 1, 2};
  std::sort(axes, axes + 3, [&](int a, int b) { return grid.n[a] < grid.n[b]; });
  std::vector<std::size_t> sweep;
  int at[3];
  for (at[axes[2]] = 0; at[axes[2]] < grid.n[axes[2]]; ++at[axes[2]]) {
    for (at[axes[1]] = 0; at[axes[1]] < grid.n[axes[1]]; ++at[axes[1]]) {
      for (at[axes[0]] = 0; at[axes[0]] < grid.n[axes[0]]; ++at[axes[0]]) {
        const std::size_t v = grid.Index(at[0], at[1], at[2]);
        if (elements[v] != 0) sweep.push_back(v);
      }
    }
  }
  const int span = static_cast<int>(std::ceil(std::sqrt(largest))) + 1;
  const int stride = std::max(1, span / kLatticeDivisions);
  std::vector<std::uint32_t>& prefix = *prefix_work;
  prefix.resize(grid.size() / grid.n[0] * (grid.n[0] + 1));
  for (std::size_t row = 0; row < grid.size() / grid.n[0]; ++row) UpdatePrefix(grid, elements, row, &prefix);
  std::vector<double> far_axis[3];
  std::vector<std::pair<double, std::size_t>> covering;
  for (std::size_t next = 0; next < sweep.size();) {
    if (elements[sweep[next]] == 0) {
      ++next;
      continue;
    }
    if (static_cast<int>(balls->size()) == max_balls) return false;
    const std::size_t e = sweep[next];
    const int w[3] = {static_cast<int>(e % grid.n[0]), static_cast<int>(e / grid.n[0] % grid.n[1]),
                      static_cast<int>(e / grid.n[0] / grid.n[1])};
    const int b = LowestBit(elements[e]);
    const int sub[3] = {b % kSub, b / kSub % kSub, b / (kSub * kSub)};
    // Balls containing sub-cube b of voxel e: all on the lattice, and the largest at full resolution.
    covering.clear();
    std::size_t widest = grid.size();
    double widest_radius = 0.0;
    // far_axis[axis][t + span]: the squared farthest extent, along the axis, of the sub-cube from
    // the centre of a voxel t voxels before its own.
    for (int axis = 0; axis < 3; ++axis) {
      far_axis[axis].resize(2 * span + 1);
      for (int t = -span; t <= span; ++t) {
        double far[kSub];
        SubCubeFar(t, far);
        far_axis[axis][t + span] = far[sub[axis]];
      }
    }
    for (int k = std::max(0, w[2] - span); k <= std::min(grid.n[2] - 1, w[2] + span); ++k) {
      const double fz = far_axis[2][w[2] - k + span];
      if (fz > largest) continue;
      for (int j = std::max(0, w[1] - span); j <= std::min(grid.n[1] - 1, w[1] + span); ++j) {
        const double fyz = fz + far_axis[1][w[1] - j + span];
        if (fyz > largest) continue;
        for (int i = std::max(0, w[0] - span); i <= std::min(grid.n[0] - 1, w[0] + span); ++i) {
          const std::size_t v = grid.Index(i, j, k);
          const double far2 = fyz + far_axis[0][w[0] - i + span];
          if (far2 > clearance2[v]) continue;
          const double r = radius_at(v);
          if (r <= 0.0 || far2 > r * r) continue;
          if (r > widest_radius) widest_radius = r, widest = v;
          if ((i - w[0]) % stride == 0 && (j - w[1]) % stride == 0 && (k - w[2]) % stride == 0) {
            covering.emplace_back(r, v);
          }
        }
      }
    }
    if (widest == grid.size()) return false;
    covering.emplace_back(widest_radius, widest);
    if (covering.size() > kScored) {
      std::nth_element(covering.begin(), covering.begin() + kScored, covering.end(), std::greater<>());
      covering.resize(kScored);
    }
    std::size_t chosen = widest;
    std::uint64_t best = 0;
    for (const auto& [r, v] : covering) {
      const std::uint64_t gain = Gain(grid, elements, prefix, v, r);
      if (gain > best) best = gain, chosen = v;
    }
    std::uint64_t count = 0;
    const double needed = Cover(grid, &elements, chosen, radius_at(chosen), &count, &prefix);
    balls->push_back({chosen, needed});
  }
  return true;
}

struct Level {
  Grid grid;
  Voxels voxels;
  std::vector<double> distance;  // [m] d: bound on the distance from each voxel centre to the solid
  std::vector<Vector3d> local;   // the mesh's vertices in grid-local coordinates
  double margin = 0.0;        // [m] for rounding
  double needed_reach = 0.0;  // [m] the largest d of a voxel holding elements (a nominal R floor)
};

/// The grid and its elements for targets R in [low, high]: voxel edge low / kVoxelsPerReach (or
/// coarser, to keep the padded grid within `cap` voxels per axis), padded by high so that A_high
/// fits.
Level BuildLevel(const TriangleMesh& mesh, const Vector3d& lo, const Vector3d& hi, double low, double high,
                 double magnitude, bool closed, int cap) {
  Level level;
  Grid& grid = level.grid;
  const Vector3d extent = hi - lo;
  grid.h = std::max(low / kVoxelsPerReach, (extent.maxCoeff() + 2.0 * high) / cap * (1.0 + 1e-9));
  const int pad = kPad + static_cast<int>(std::ceil(high / grid.h));
  for (int axis = 0; axis < 3; ++axis) {
    const int core = std::clamp(static_cast<int>(std::ceil(extent[axis] / grid.h)), 1, cap);
    grid.n[axis] = core + 2 * pad;
    grid.origin[axis] = lo[axis] - pad * grid.h - 0.5 * (core * grid.h - extent[axis]);
  }
  // Rounding: local coordinates are off by about 1e-16 of the grid's size, mesh-frame centres by
  // about 1e-16 of the coordinates' magnitude; these margins are far above both.
  const double slack = 1e-9 * grid.h;
  level.margin = 1e-9 * grid.h + 1e-12 * magnitude;

  std::vector<Vector3d>& local = level.local;
  local.resize(mesh.vertices.size());
  for (std::size_t v = 0; v < local.size(); ++v) local[v] = mesh.vertices[v] - grid.origin;

  const std::size_t size = grid.size();
  Voxels& voxels = level.voxels;
  voxels.elements.assign(size, 0);
  voxels.touched.assign(size, 0);
  voxels.outside.assign(size, 0);
  voxels.inside.assign(size, 0);
  voxels.witness.assign(size, -1);
  std::vector<double> distance(size, kInf);
  MarkSurface(grid, local, mesh, slack, &voxels, &distance);
  FloodOutside(grid, &voxels);
  if (closed) MarkEnclosed(grid, local, mesh, slack, &voxels, &distance);
  PropagateDistance(grid, local, mesh, &distance, &voxels.witness);
  voxels.reach.resize(size);
  for (std::size_t v = 0; v < size; ++v) {
    voxels.reach[v] = distance[v] + kHalfDiagonal * grid.h + level.margin;
    if (voxels.elements[v] != 0) level.needed_reach = std::max(level.needed_reach, distance[v]);
  }
  level.distance = std::move(distance);
  return level;
}

/// An upper bound on the distance from point q (grid-local) to the solid: 0 in an enclosed voxel;
/// else the least, over the 27 voxels N about q's voxel, of d(N) + |q − c(N)| and of the exact
/// distance from q to N's witness triangle — each the distance to a point of the solid or a bound
/// on it (triangle inequality), wherever q is.
double PointBound(const Level& level, const TriangleMesh& mesh, const Vector3d& q) {
  const Grid& grid = level.grid;
  int c[3];
  bool in_grid = true;
  for (int axis = 0; axis < 3; ++axis) {
    in_grid = in_grid && q[axis] >= 0.0 && q[axis] <= grid.n[axis] * grid.h;
    c[axis] = grid.Cell(q[axis], axis);
  }
  if (in_grid && level.voxels.inside[grid.Index(c[0], c[1], c[2])]) return 0.0;
  double best = kInf;
  int seen[27];
  int num_seen = 0;
  for (int k = std::max(0, c[2] - 1); k <= std::min(grid.n[2] - 1, c[2] + 1); ++k) {
    for (int j = std::max(0, c[1] - 1); j <= std::min(grid.n[1] - 1, c[1] + 1); ++j) {
      for (int i = std::max(0, c[0] - 1); i <= std::min(grid.n[0] - 1, c[0] + 1); ++i) {
        const std::size_t v = grid.Index(i, j, k);
        best = std::min(best, level.distance[v] + (q - grid.Centre(i, j, k)).norm());
        const int t = level.voxels.witness[v];
        if (t < 0 || std::find(seen, seen + num_seen, t) != seen + num_seen) continue;
        seen[num_seen++] = t;
        const Eigen::Vector3i& tri = mesh.triangles[t];
        best = std::min(best, TriangleDistanceBound(q, level.local[tri[0]], level.local[tri[1]], level.local[tri[2]]));
      }
    }
  }
  return best;
}

/// A proven upper bound on the distance from any point of the ball (grid-local centre, radius
/// [m]) to the solid, by branch and bound over an octree of its bounding cube: a cell with centre
/// q and half-edge e meeting the ball is bounded by PointBound(q) plus the farthest its points in
/// the ball can be from q (1-Lipschitz distance). The widest cell is split until its bound is
/// below `floor` (a bound already reported), within `tolerance` of the largest PointBound seen at
/// a point of the ball, or a work limit is hit; the widest remaining bound is returned.
double BallReach(const Level& level, const TriangleMesh& mesh, const Vector3d& centre, double radius, double floor,
                 double tolerance) {
  struct Cell {
    double bound;
    Vector3d q;
    double e;
    bool operator<(const Cell& other) const { return bound < other.bound; }
  };
  std::vector<Cell> heap;
  double seen = 0.0;
  const double sqrt3 = std::sqrt(3.0);
  const auto push = [&](const Vector3d& q, double e) {
    const Vector3d gap = ((q - centre).cwiseAbs().array() - e).max(0.0).matrix();
    if (gap.squaredNorm() > radius * radius) return;
    const double f = PointBound(level, mesh, q), from_centre = (q - centre).norm();
    if (from_centre <= radius) seen = std::max(seen, f);
    heap.push_back({f + std::min(sqrt3 * e, from_centre + radius), q, e});
    std::push_heap(heap.begin(), heap.end());
  };
  push(centre, radius);
  double result = heap.empty() ? PointBound(level, mesh, centre) + radius : heap.front().bound;
  for (int splits = 0; !heap.empty(); ++splits) {
    const Cell top = heap.front();
    result = top.bound;
    if (top.bound <= floor || top.bound <= seen + tolerance || splits >= 20000) break;
    std::pop_heap(heap.begin(), heap.end());
    heap.pop_back();
    const double e = 0.5 * top.e;
    for (int corner = 0; corner < 8; ++corner) {
      push(top.q + e * Vector3d(corner & 1 ? 1.0 : -1.0, corner & 2 ? 1.0 : -1.0, corner & 4 ? 1.0 : -1.0), e);
    }
    if (heap.empty()) break;  // no part of the cell was in the ball after all
  }
  return result;
}

}  // namespace

void SphereFitOptions::Validate() const {
  if (!std::isfinite(max_reach) || max_reach <= 0.0) {
    ThrowInvalid("sphere_fit.max_reach = " + FormatNumber(max_reach) + " must be finite and > 0");
  }
  if (max_spheres < 1) ThrowInvalid("sphere_fit.max_spheres = " + std::to_string(max_spheres) + " must be >= 1");
  if (max_voxels_per_axis < kMinVoxelsPerAxis || max_voxels_per_axis > kMaxVoxelsPerAxis) {
    ThrowInvalid("sphere_fit.max_voxels_per_axis = " + std::to_string(max_voxels_per_axis) + " must be within [" +
                 std::to_string(kMinVoxelsPerAxis) + ", " + std::to_string(kMaxVoxelsPerAxis) + "]");
  }
}

FittedSpheres FitSpheres(const TriangleMesh& mesh, const SphereFitOptions& options) {
  options.Validate();
  ValidateMesh(mesh);

  // The bounding box of the vertices the triangles use.
  Vector3d lo = Vector3d::Constant(kInf), hi = Vector3d::Constant(-kInf);
  for (const Eigen::Vector3i& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      lo = lo.cwiseMin(mesh.vertices[t[k]]);
      hi = hi.cwiseMax(mesh.vertices[t[k]]);
    }
  }
  const double magnitude = std::max(lo.cwiseAbs().maxCoeff(), hi.cwiseAbs().maxCoeff());
  // Welding within 1e-12 of the extent moves vertices far less than the margins of the surface
  // and parity tests (1e-9 of a voxel, and a voxel is at least 1/256 of the extent), so those
  // tests see the welded mesh: closed, and its enclosed volume is what they find.
  const bool closed = IsClosed(mesh, kWeld * (hi - lo).maxCoeff());

  // Last resort: one ball about the bounding box's centre through the farthest vertex. Its points
  // are within its radius of the centre, which is within min |c − v| of a vertex of the solid.
  FittedSpheres last;
  {
    const Vector3d centre = 0.5 * (lo + hi);
    double radius = 0.0, nearest = kInf;
    for (const Eigen::Vector3i& t : mesh.triangles) {
      for (int k = 0; k < 3; ++k) {
        const double d = (mesh.vertices[t[k]] - centre).norm();
        radius = std::max(radius, d);
        nearest = std::min(nearest, d);
      }
    }
    const double margin = 1e-12 * (magnitude + radius) + std::numeric_limits<double>::min();
    last.centres = {centre};
    last.radii = {radius + margin};
    last.reach = radius + nearest + 2.0 * margin;
  }

  // Levels of R in [low, 2·low), each on a grid fine enough for it and padded so the balls fit.
  std::vector<Ball> balls, best;
  for (double low = options.max_reach; low < last.reach; low *= 2.0) {
    const Level level = BuildLevel(mesh, lo, hi, low, 2.0 * low, magnitude, closed, options.max_voxels_per_axis);
    const Grid& grid = level.grid;
    std::vector<double> clearance2(grid.size());
    std::vector<std::uint64_t> work;
    std::vector<std::uint32_t> prefix;
    // Candidate balls for a nominal R: centred at voxel centres, as wide as the cubes whose centres
    // are within R of the solid allow. The proven reach comes from BallReach afterwards.
    const auto attempt = [&](double nominal) {
      Clearance(grid, level.distance, nominal, &clearance2);
      return GreedyCover(grid, level.voxels.elements, clearance2, level.margin / grid.h, options.max_spheres, &balls,
                         &work, &prefix);
    };
    double fail = std::max(level.needed_reach, low - kNominalBelow * grid.h), pass = 2.0 * low;
    if (attempt(fail)) {
      best = balls;
    } else if (!attempt(pass)) {
      continue;
    } else {
      best = balls;
      for (int step = 0; step < kBisections; ++step) {
        const double mid = 0.5 * (fail + pass);
        if (attempt(mid)) {
          pass = mid;
          best = balls;
        } else {
          fail = mid;
        }
      }
    }
    DropRedundant(grid, level.voxels.elements, &best);
    FittedSpheres out;
    for (const Ball& ball : best) {
      const int at[3] = {static_cast<int>(ball.voxel % grid.n[0]), static_cast<int>(ball.voxel / grid.n[0] % grid.n[1]),
                         static_cast<int>(ball.voxel / grid.n[0] / grid.n[1])};
      const double radius = ball.radius * grid.h + level.margin;
      out.centres.push_back(grid.origin + grid.Centre(at[0], at[1], at[2]));
      out.radii.push_back(radius);
      // Two bounds, each proven: the largest U of the cubes the ball meets (within the grid), and
      // the branch and bound on the mesh's distance.
      double cubes = 0.0;
      const double r = radius / grid.h * (1.0 + 1e-9);
      bool in_grid = true;
      for (int axis = 0; axis < 3; ++axis) in_grid = in_grid && at[axis] + 0.5 - r >= 0.0 && at[axis] + 0.5 + r <= grid.n[axis];
      ForVoxelsInBall(grid, at, r, [&](std::size_t w, int, int, int) { cubes = std::max(cubes, level.voxels.reach[w]); });
      if (!in_grid) cubes = kInf;
      if (cubes > out.reach) {
        out.reach = std::max(out.reach, std::min(cubes, BallReach(level, mesh, grid.Centre(at[0], at[1], at[2]),
                                                                  radius * (1.0 + 1e-9), out.reach, kTolerance * grid.h)));
      }
    }
    out.reach += 2.0 * level.margin;
    return out.reach <= last.reach ? out : last;
  }
  return last;
}

}  // namespace chasles
