#pragma once
// Internal to collision/: a two-level bit grid of the obstacle voxels of one OctoMap, for exact
// sphere tests without FCL's octree traversal. Included only by collision_checker.cc.
//
// Which voxels are obstacles: exactly those FCL's sphere–OcTree collision reaches
// (fcl/narrowphase/detail/traversal/octree/octree_solver-inl.h, OcTreeShapeIntersectRecurse,
// with a default CollisionRequest, i.e. enable_cost off):
//   * a leaf (a node without children, at any depth — pruned leaves included) is an obstacle
//     when log-odds >= the tree's occupancy threshold (fcl::OcTree::isNodeOccupied, the same
//     test as octomap's isNodeOccupied);
//   * FCL descends into an inner node only when it is neither "free" (log-odds <= 0, FCL's
//     fixed free threshold) nor "uncertain" (not occupied and not free). Leaves below an inner
//     node that stops the descent are never obstacles, even when their own log-odds pass the
//     occupancy threshold (possible with a threshold below 0.5 or inner values that are not the
//     maximum of their children).
// Nodes between the free and occupied thresholds ("uncertain") are therefore not obstacles.
//
// Geometry: a leaf at depth d covers 2^(16-d) finest voxels per axis. Voxel boundaries are
// computed the way FCL computes its node boxes — the root box is ±2^16·resolution/2 and every
// child splits its parent at (min + max)·0.5 — so a voxel face lies at the very same double as
// the face of the FCL box that contains it.
//
// Storage: finest voxels are grouped in 8×8×8 blocks. A dense index over the blocks of the
// obstacles' bounding box holds -1 for an empty block or the position of the block's 512 bits
// (eight 64-bit words, one per z slice; bit x + 8·y) in `blocks_`. A pruned leaf of 8 or more
// voxels fills whole blocks (the grid origin is aligned to 8 voxels, and such leaves to their
// size).

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include <Eigen/Geometry>
#include <octomap/OcTree.h>

namespace chasles {
namespace detail {

class OccupancyGrid {
 public:
  /// Largest bounding box of obstacle voxels that is gridded (2^28 voxels: at most 2^19 blocks,
  /// 2 MiB of index and 32 MiB of bits when every block is occupied). Larger maps stay on FCL.
  static constexpr std::uint64_t kMaxVoxels = std::uint64_t{1} << 28;
  static constexpr int kDepth = 16;  // octomap::OcTree's fixed depth

  enum class Status { kBuilt, kEmpty, kTooLarge };

  /// Builds the grid of `tree` placed at `pose` (map -> world). kEmpty: FCL would report no
  /// collision with this map, ever; kTooLarge: nothing was built (use FCL).
  Status Build(const octomap::OcTree& tree, const Eigen::Isometry3d& pose) {
    blocks_.clear();
    index_.clear();
    const octomap::OcTreeNode* root = tree.getRoot();
    occupied_log_odds_ = tree.getOccupancyThresLog();  // fcl::OcTree's occupancy_threshold_log_odds
    leaves_.clear();
    if (root != nullptr) Collect(tree, root, 0, 0, 0, 0);
    if (leaves_.empty()) return Status::kEmpty;
    // Bounding box of the obstacle leaves in key units [lo, hi), aligned to 8.
    std::uint32_t lo[3] = {~0u, ~0u, ~0u}, hi[3] = {0, 0, 0};
    for (const Leaf& l : leaves_) {
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], l.k[a]);
        hi[a] = std::max(hi[a], l.k[a] + (1u << l.level));
      }
    }
    std::uint64_t voxels = 1;
    for (int a = 0; a < 3; ++a) {
      lo[a] &= ~7u;
      hi[a] = (hi[a] + 7u) & ~7u;
      n_[a] = static_cast<int>(hi[a] - lo[a]);
      nb_[a] = n_[a] / 8;
      voxels *= static_cast<std::uint64_t>(n_[a]);
    }
    if (voxels > kMaxVoxels) {
      leaves_.clear();
      leaves_.shrink_to_fit();
      return Status::kTooLarge;
    }
    // Voxel boundaries along each axis, as FCL computes them.
    const double delta = (1 << kDepth) * tree.getResolution() / 2;  // fcl::OcTree::getRootBV
    for (int a = 0; a < 3; ++a) {
      bnd_[a].resize(n_[a] + 1);
      for (int i = 0; i <= n_[a]; ++i) bnd_[a][i] = Boundary(lo[a] + i, delta);
    }
    inv_res_ = 1.0 / tree.getResolution();
    // Fill.
    index_.assign(static_cast<std::size_t>(nb_[0]) * nb_[1] * nb_[2], -1);
    for (const Leaf& l : leaves_) {
      const int size = 1 << l.level;
      const int x0 = static_cast<int>(l.k[0] - lo[0]), y0 = static_cast<int>(l.k[1] - lo[1]),
                z0 = static_cast<int>(l.k[2] - lo[2]);
      if (size >= 8) {
        for (int bz = z0 / 8; bz < (z0 + size) / 8; ++bz)
          for (int by = y0 / 8; by < (y0 + size) / 8; ++by)
            for (int bx = x0 / 8; bx < (x0 + size) / 8; ++bx) Block(bx, by, bz).fill(~std::uint64_t{0});
      } else {
        std::array<std::uint64_t, 8>& b = Block(x0 / 8, y0 / 8, z0 / 8);
        for (int z = z0; z < z0 + size; ++z)
          for (int y = y0; y < y0 + size; ++y)
            for (int x = x0; x < x0 + size; ++x) b[z & 7] |= std::uint64_t{1} << ((x & 7) + 8 * (y & 7));
      }
    }
    leaves_.clear();
    leaves_.shrink_to_fit();
    // World -> map.
    const Eigen::Matrix3d rt = pose.linear().transpose();
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) rt_[3 * i + j] = rt(i, j);
      p_[i] = pose.translation()[i];
    }
    // World bounding sphere of the gridded box.
    const Eigen::Vector3d bl(bnd_[0].front(), bnd_[1].front(), bnd_[2].front());
    const Eigen::Vector3d bh(bnd_[0].back(), bnd_[1].back(), bnd_[2].back());
    center_ = pose * (0.5 * (bl + bh));
    radius_ = 0.5 * (bh - bl).norm() * (1.0 + 1e-12);
    return Status::kBuilt;
  }

  /// The world centre of voxel (i, j, k) of SphereHits: the middle of its FCL box, placed by the
  /// map's pose.
  Eigen::Vector3d VoxelCentre(const int* voxel) const {
    double c[3];
    for (int a = 0; a < 3; ++a) c[a] = 0.5 * (bnd_[a][voxel[a]] + bnd_[a][voxel[a] + 1]);
    // rt_ is the map's rotation transposed: world = rtᵀ c + p.
    return {rt_[0] * c[0] + rt_[3] * c[1] + rt_[6] * c[2] + p_[0], rt_[1] * c[0] + rt_[4] * c[1] + rt_[7] * c[2] + p_[1],
            rt_[2] * c[0] + rt_[5] * c[1] + rt_[8] * c[2] + p_[2]};
  }

  /// World bounding sphere of every obstacle voxel.
  const Eigen::Vector3d& center() const { return center_; }
  double radius() const { return radius_; }
  std::size_t num_blocks() const { return blocks_.size(); }

  /// True when the sphere (world centre x, radius r >= 0) touches or overlaps an obstacle
  /// voxel: squared distance from the centre to the voxel box <= r², as FCL's sphere–box test.
  /// With `voxel`, the first voxel found touching it (per-axis indices, for VoxelCentre).
  bool SphereHits(const double* x, double r, int* voxel = nullptr) const {
    if (blocks_.empty()) return false;
    const double d0 = x[0] - p_[0], d1 = x[1] - p_[1], d2 = x[2] - p_[2];
    const double c[3] = {rt_[0] * d0 + rt_[1] * d1 + rt_[2] * d2, rt_[3] * d0 + rt_[4] * d1 + rt_[5] * d2,
                         rt_[6] * d0 + rt_[7] * d1 + rt_[8] * d2};
    // Voxel range per axis: voxel i overlaps [c - r, c + r] iff bnd[i + 1] >= c - r and
    // bnd[i] <= c + r (closed: touching counts).
    int lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      const std::vector<double>& b = bnd_[a];
      const int n = n_[a];
      const double a0 = c[a] - r, a1 = c[a] + r;
      if (!(a1 >= b[0] && a0 <= b[n])) return false;  // outside, or NaN
      int i = static_cast<int>(std::clamp(std::floor((a0 - b[0]) * inv_res_), 0.0, n - 1.0));
      while (i > 0 && b[i] >= a0) --i;
      while (b[i + 1] < a0) ++i;
      int j = static_cast<int>(std::clamp(std::floor((a1 - b[0]) * inv_res_), 0.0, n - 1.0));
      while (j < n - 1 && b[j + 1] <= a1) ++j;
      while (b[j] > a1) --j;
      lo[a] = i;
      hi[a] = j;
    }
    // Squared per-axis distance from the centre to each voxel slab in range.
    const int span0 = hi[0] - lo[0] + 1, span1 = hi[1] - lo[1] + 1, span2 = hi[2] - lo[2] + 1;
    constexpr int kStack = 768;
    double stack[kStack];
    std::vector<double> heap;
    double* e = stack;
    if (span0 + span1 + span2 > kStack) {
      heap.resize(span0 + span1 + span2);
      e = heap.data();
    }
    double* ex = e;
    double* ey = e + span0;
    double* ez = ey + span1;
    const auto fill = [&](int a, double* out) {
      const std::vector<double>& b = bnd_[a];
      for (int i = lo[a]; i <= hi[a]; ++i) {
        const double t = std::max(std::max(b[i] - c[a], c[a] - b[i + 1]), 0.0);
        out[i - lo[a]] = t * t;
      }
    };
    fill(0, ex);
    fill(1, ey);
    fill(2, ez);
    const double r2 = r * r;
    for (int bz = lo[2] >> 3; bz <= hi[2] >> 3; ++bz) {
      const int z0 = std::max(lo[2], 8 * bz), z1 = std::min(hi[2], 8 * bz + 7);
      for (int by = lo[1] >> 3; by <= hi[1] >> 3; ++by) {
        const int y0 = std::max(lo[1], 8 * by), y1 = std::min(hi[1], 8 * by + 7);
        const std::int32_t* row = &index_[(static_cast<std::size_t>(bz) * nb_[1] + by) * nb_[0]];
        for (int bx = lo[0] >> 3; bx <= hi[0] >> 3; ++bx) {
          const std::int32_t id = row[bx];
          if (id < 0) continue;
          const int x0 = std::max(lo[0], 8 * bx), x1 = std::min(hi[0], 8 * bx + 7);
          // Bits x0..x1 (block-local) in every byte, bytes y0..y1.
          const std::uint64_t xbyte = (0xFFu >> (7 - (x1 - 8 * bx))) & (0xFFu << (x0 - 8 * bx));
          const std::uint64_t ymask = (~std::uint64_t{0} >> (8 * (7 - (y1 - 8 * by)))) &
                                      (~std::uint64_t{0} << (8 * (y0 - 8 * by)));
          const std::uint64_t mask = xbyte * 0x0101010101010101ull & ymask;
          const std::array<std::uint64_t, 8>& blk = blocks_[id];
          for (int z = z0; z <= z1; ++z) {
            const std::uint64_t w = blk[z & 7] & mask;
            if (w == 0) continue;
            const double ezz = ez[z - lo[2]];
            if (ezz > r2) continue;
            for (int y = y0; y <= y1; ++y) {
              std::uint64_t bits = (w >> (8 * (y & 7))) & 0xFFu;
              if (bits == 0) continue;
              const double eyz = ezz + ey[y - lo[1]];
              if (eyz > r2) continue;
              while (bits != 0) {
                const int x = 8 * bx + __builtin_ctzll(bits);
                bits &= bits - 1;
                if (eyz + ex[x - lo[0]] <= r2) {
                  if (voxel != nullptr) {
                    voxel[0] = x;
                    voxel[1] = y;
                    voxel[2] = z;
                  }
                  return true;
                }
              }
            }
          }
        }
      }
    }
    return false;
  }

 private:
  struct Leaf {
    std::uint32_t k[3];  // key of the leaf's lowest corner voxel
    int level;           // 16 - depth: the leaf spans 2^level voxels per axis
  };

  // Mirrors OcTreeShapeIntersectRecurse's decisions (see the file comment).
  void Collect(const octomap::OcTree& tree, const octomap::OcTreeNode* node, int depth, std::uint32_t kx,
               std::uint32_t ky, std::uint32_t kz) {
    const double log_odds = node->getLogOdds();
    if (!tree.nodeHasChildren(node)) {
      if (log_odds >= occupied_log_odds_) leaves_.push_back({{kx, ky, kz}, kDepth - depth});
      return;
    }
    const bool occupied = log_odds >= occupied_log_odds_;
    const bool free = log_odds <= 0.0;  // fcl::OcTree's free_threshold_log_odds
    if (free || !occupied) return;      // free, or uncertain without enable_cost
    const std::uint32_t half = 1u << (kDepth - depth - 1);
    for (unsigned i = 0; i < 8; ++i) {
      if (!tree.nodeChildExists(node, i)) continue;
      Collect(tree, tree.getNodeChild(node, i), depth + 1, kx + ((i & 1) ? half : 0), ky + ((i & 2) ? half : 0),
              kz + ((i & 4) ? half : 0));
    }
  }

  // Boundary between finest voxels k - 1 and k (k in [0, 2^16]), split as FCL splits boxes.
  static double Boundary(std::uint32_t k, double delta) {
    std::uint32_t lo = 0, hi = 1u << kDepth;
    double blo = -delta, bhi = delta;
    if (k == lo) return blo;
    if (k == hi) return bhi;
    for (;;) {
      const std::uint32_t mid = (lo + hi) / 2;
      const double bm = (blo + bhi) * 0.5;
      if (k == mid) return bm;
      if (k < mid) {
        hi = mid;
        bhi = bm;
      } else {
        lo = mid;
        blo = bm;
      }
    }
  }

  std::array<std::uint64_t, 8>& Block(int bx, int by, int bz) {
    std::int32_t& id = index_[(static_cast<std::size_t>(bz) * nb_[1] + by) * nb_[0] + bx];
    if (id < 0) {
      id = static_cast<std::int32_t>(blocks_.size());
      blocks_.push_back({});
    }
    return blocks_[id];
  }

  double occupied_log_odds_ = 0.0;
  std::vector<Leaf> leaves_;  // build scratch
  int n_[3] = {0, 0, 0};      // voxels per axis (multiple of 8)
  int nb_[3] = {0, 0, 0};     // blocks per axis
  std::vector<double> bnd_[3];
  double inv_res_ = 0.0;
  std::vector<std::int32_t> index_;
  std::vector<std::array<std::uint64_t, 8>> blocks_;
  double rt_[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  double p_[3] = {0, 0, 0};
  Eigen::Vector3d center_ = Eigen::Vector3d::Zero();
  double radius_ = 0.0;
};

}  // namespace detail
}  // namespace chasles
