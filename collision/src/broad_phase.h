#pragma once
/// \file
/// The collision checker's broad phase over scene primitives: a static bounding-volume hierarchy
/// of their bounding spheres (axis-aligned boxes, median splits), built once with the checker.
/// A query box lists the primitives whose bounding sphere's box overlaps it, so a check costs
/// what lies near the robot rather than what the scene holds. Internal to chasles_collision.

#include <algorithm>
#include <cstdint>
#include <limits>
#include <numeric>
#include <vector>

namespace chasles::detail {

/// An axis-aligned box [lo, hi].
struct Box3 {
  double lo[3];
  double hi[3];

  /// The box holding nothing (lo = +inf, hi = −inf), for Include to grow.
  static Box3 None() {
    Box3 box;
    for (int a = 0; a < 3; ++a) {
      box.lo[a] = std::numeric_limits<double>::infinity();
      box.hi[a] = -std::numeric_limits<double>::infinity();
    }
    return box;
  }
  /// Grows the box to hold the sphere (centre c, radius r).
  void Include(const double* c, double r) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], c[a] - r);
      hi[a] = std::max(hi[a], c[a] + r);
    }
  }
  bool Empty() const { return !(lo[0] <= hi[0] && lo[1] <= hi[1] && lo[2] <= hi[2]); }
};

class SphereBvh {
 public:
  /// Leaves hold at most this many spheres.
  static constexpr std::uint32_t kLeafSize = 8;

  SphereBvh() = default;

  /// Spheres (x[i], y[i], z[i]) with radii r[i], i < n.
  SphereBvh(const double* x, const double* y, const double* z, const double* r, std::size_t n) {
    boxes_.assign(n, Box3::None());
    for (std::size_t i = 0; i < n; ++i) {
      const double c[3] = {x[i], y[i], z[i]};
      boxes_[i].Include(c, r[i]);
    }
    order_.resize(n);
    std::iota(order_.begin(), order_.end(), 0u);
    if (n == 0) return;
    nodes_.emplace_back();
    BuildInto(0, 0, static_cast<std::uint32_t>(n));
  }

  std::size_t size() const { return boxes_.size(); }

  /// Appends to *out (cleared first), in ascending order, every sphere whose box overlaps
  /// `query` (touching counts).
  void Overlapping(const Box3& query, std::vector<std::uint32_t>* out) const {
    out->clear();
    if (nodes_.empty()) return;
    std::uint32_t stack[64];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& node = nodes_[stack[--top]];
      if (!Overlap(node.box, query)) continue;
      if (node.left == kLeaf) {
        for (std::uint32_t k = node.begin; k < node.end; ++k) {
          if (Overlap(boxes_[order_[k]], query)) out->push_back(order_[k]);
        }
        continue;
      }
      stack[top++] = node.left;
      stack[top++] = node.left + 1;
    }
    std::sort(out->begin(), out->end());
  }

 private:
  static constexpr std::uint32_t kLeaf = 0;  // the root is node 0, so no child is node 0

  struct Node {
    Box3 box;
    std::uint32_t begin = 0, end = 0;  // range in order_ (leaves)
    std::uint32_t left = kLeaf;        // children left and left + 1; kLeaf for a leaf
  };

  static bool Overlap(const Box3& a, const Box3& b) {
    return a.lo[0] <= b.hi[0] && b.lo[0] <= a.hi[0] && a.lo[1] <= b.hi[1] && b.lo[1] <= a.hi[1] &&
           a.lo[2] <= b.hi[2] && b.lo[2] <= a.hi[2];
  }

  /// Builds the subtree over order_[begin, end) into the reserved node `index`; children are
  /// adjacent slots. Depth is at most log2(n / kLeafSize) + 1 (median splits), so the query's
  /// stack of 64 suffices for any scene that fits in memory.
  void BuildInto(std::uint32_t index, std::uint32_t begin, std::uint32_t end) {
    Box3 box = boxes_[order_[begin]];
    for (std::uint32_t k = begin + 1; k < end; ++k) {
      const Box3& b = boxes_[order_[k]];
      for (int a = 0; a < 3; ++a) {
        box.lo[a] = std::min(box.lo[a], b.lo[a]);
        box.hi[a] = std::max(box.hi[a], b.hi[a]);
      }
    }
    nodes_[index].box = box;
    nodes_[index].begin = begin;
    nodes_[index].end = end;
    if (end - begin <= kLeafSize) return;
    int axis = 0;
    for (int a = 1; a < 3; ++a) {
      if (box.hi[a] - box.lo[a] > box.hi[axis] - box.lo[axis]) axis = a;
    }
    const std::uint32_t mid = begin + (end - begin) / 2;
    std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                     [&](std::uint32_t i, std::uint32_t j) {
                       return boxes_[i].lo[axis] + boxes_[i].hi[axis] < boxes_[j].lo[axis] + boxes_[j].hi[axis];
                     });
    const std::uint32_t left = static_cast<std::uint32_t>(nodes_.size());
    nodes_.emplace_back();
    nodes_.emplace_back();
    nodes_[index].left = left;
    BuildInto(left, begin, mid);
    BuildInto(left + 1, mid, end);
  }

  std::vector<Box3> boxes_;          // per sphere
  std::vector<std::uint32_t> order_;  // sphere indices, leaves' ranges contiguous
  std::vector<Node> nodes_;           // node 0 is the root
};

}  // namespace chasles::detail
