#pragma once
/// \file
/// Internal to planners/search: a C-space lattice anchored at the start configuration and a
/// hash table of its nodes keyed on packed lattice coordinates.

#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace chasles {

/// Integer lattice coordinates k ∈ Z^n of one node.
using LatticeCoords = std::vector<std::int64_t>;

/// The lattice q(k) = anchor + k ⊙ resolution, k ∈ Z^n. Nodes are indexed inside the box of
/// coordinates whose positions lie within the joint limits; coordinates inside the box are
/// packed into key_words() 64-bit words (each coordinate in the fewest bits that span its range).
class CSpaceLattice {
 public:
  /// Largest number of lattice steps across one joint's range.
  static constexpr double kMaxCellsPerJoint = 1073741824.0;  // 2^30

  /// Preconditions: equal sizes; resolution > 0 and finite; lower <= anchor <= upper; every
  /// (upper − lower) / resolution <= kMaxCellsPerJoint.
  CSpaceLattice(Eigen::VectorXd anchor, Eigen::VectorXd resolution, const Eigen::VectorXd& lower,
                const Eigen::VectorXd& upper);

  int num_dims() const { return static_cast<int>(anchor_.size()); }
  const Eigen::VectorXd& resolution() const { return resolution_; }

  /// The node within the limits nearest to q: round((q − anchor) / resolution) per coordinate,
  /// clamped to the limits' range (a q at a limit can round to a position just past it).
  LatticeCoords Nearest(const Eigen::VectorXd& q) const;
  /// anchor_i + k_i · resolution_i (the same arithmetic for every caller, so positions repeat
  /// bit for bit). Coordinate 0 is the anchor itself.
  double Position(int i, std::int64_t k) const { return anchor_[i] + static_cast<double>(k) * resolution_[i]; }
  void Position(const LatticeCoords& k, Eigen::VectorXd* q) const;

  /// True when every k_i's position lies within joint i's limits (exactly as Position computes
  /// it): k is then in the indexed box and can be packed.
  bool InLimits(const LatticeCoords& k) const;

  int key_words() const { return key_words_; }
  /// Precondition: InLimits(k). Writes key_words() words.
  void Pack(const LatticeCoords& k, std::uint64_t* key) const;
  void Unpack(const std::uint64_t* key, LatticeCoords* k) const;

 private:
  Eigen::VectorXd anchor_;
  Eigen::VectorXd resolution_;
  std::vector<std::int64_t> lo_, hi_;  ///< lattice range within the joint limits: the indexed box
  std::vector<int> word_, shift_;      ///< where each coordinate is packed
  std::vector<std::uint64_t> mask_;
  int key_words_ = 1;
};

/// Nodes in insertion order (index 0, 1, …) with their packed keys, and an open-addressing
/// hash index from key to node. A node may be appended without indexing it (a goal that
/// shares the start's cell): it then has a key but Find never returns it.
class LatticeNodeTable {
 public:
  static constexpr std::uint32_t kNone = 0xFFFFFFFFu;

  explicit LatticeNodeTable(int key_words);

  /// The indexed node with this key, or kNone.
  std::uint32_t Find(const std::uint64_t* key) const;
  /// Appends a node and returns its index. Preconditions: when `indexed`, Find(key) == kNone;
  /// `key` does not point into this table.
  std::uint32_t Add(const std::uint64_t* key, bool indexed = true);
  const std::uint64_t* key(std::uint32_t node) const { return &keys_[static_cast<std::size_t>(node) * key_words_]; }
  std::size_t size() const { return keys_.size() / key_words_; }

 private:
  std::uint64_t Hash(const std::uint64_t* key) const;
  bool Equal(const std::uint64_t* a, const std::uint64_t* b) const;
  void Grow();

  int key_words_;
  std::vector<std::uint64_t> keys_;   ///< key_words_ words per node
  std::vector<std::uint32_t> slots_;  ///< node index or kNone; size a power of two
  std::size_t indexed_ = 0;
};

}  // namespace chasles
