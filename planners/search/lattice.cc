#include "lattice.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace chasles {

CSpaceLattice::CSpaceLattice(Eigen::VectorXd anchor, Eigen::VectorXd resolution, const Eigen::VectorXd& lower,
                             const Eigen::VectorXd& upper)
    : anchor_(std::move(anchor)), resolution_(std::move(resolution)) {
  const int n = num_dims();
  lo_.resize(n);
  hi_.resize(n);
  word_.resize(n);
  shift_.resize(n);
  mask_.resize(n);
  int word = 0;
  int used = 0;  // bits used in the current word
  for (int i = 0; i < n; ++i) {
    // First and last k whose position (as Position computes it) lies within the limits; the
    // quotient is a close estimate, the loops settle rounding at the boundary.
    auto lo = static_cast<std::int64_t>(std::ceil((lower[i] - anchor_[i]) / resolution_[i]));
    while (Position(i, lo - 1) >= lower[i]) --lo;
    while (Position(i, lo) < lower[i]) ++lo;
    auto hi = static_cast<std::int64_t>(std::floor((upper[i] - anchor_[i]) / resolution_[i]));
    while (Position(i, hi + 1) <= upper[i]) ++hi;
    while (Position(i, hi) > upper[i]) --hi;
    lo_[i] = std::min<std::int64_t>(lo, 0);  // the anchor is a node even if rounding disagrees
    hi_[i] = std::max<std::int64_t>(hi, 0);
    const auto span = static_cast<std::uint64_t>(hi_[i] - lo_[i]);
    int bits = 1;
    while (bits < 63 && (span >> bits) != 0) ++bits;
    if (used + bits > 64) {
      ++word;
      used = 0;
    }
    word_[i] = word;
    shift_[i] = used;
    mask_[i] = (std::uint64_t{1} << bits) - 1;
    used += bits;
  }
  key_words_ = word + 1;
}

LatticeCoords CSpaceLattice::Nearest(const Eigen::VectorXd& q) const {
  LatticeCoords k(num_dims());
  for (int i = 0; i < num_dims(); ++i) {
    k[i] = std::clamp<std::int64_t>(std::llround((q[i] - anchor_[i]) / resolution_[i]), lo_[i], hi_[i]);
  }
  return k;
}

void CSpaceLattice::Position(const LatticeCoords& k, Eigen::VectorXd* q) const {
  q->resize(num_dims());
  for (int i = 0; i < num_dims(); ++i) (*q)[i] = Position(i, k[i]);
}

bool CSpaceLattice::InLimits(const LatticeCoords& k) const {
  for (int i = 0; i < num_dims(); ++i) {
    if (k[i] < lo_[i] || k[i] > hi_[i]) return false;
  }
  return true;
}

void CSpaceLattice::Pack(const LatticeCoords& k, std::uint64_t* key) const {
  std::fill(key, key + key_words_, 0);
  for (int i = 0; i < num_dims(); ++i) {
    key[word_[i]] |= static_cast<std::uint64_t>(k[i] - lo_[i]) << shift_[i];
  }
}

void CSpaceLattice::Unpack(const std::uint64_t* key, LatticeCoords* k) const {
  k->resize(num_dims());
  for (int i = 0; i < num_dims(); ++i) {
    (*k)[i] = lo_[i] + static_cast<std::int64_t>((key[word_[i]] >> shift_[i]) & mask_[i]);
  }
}

LatticeNodeTable::LatticeNodeTable(int key_words) : key_words_(key_words), slots_(1024, kNone) {}

std::uint64_t LatticeNodeTable::Hash(const std::uint64_t* key) const {
  // SplitMix64 finaliser over the words: packed coordinates differ in few low bits.
  std::uint64_t h = 0x9E3779B97F4A7C15ull;
  for (int w = 0; w < key_words_; ++w) {
    std::uint64_t x = h ^ key[w];
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    h = x ^ (x >> 31);
  }
  return h;
}

bool LatticeNodeTable::Equal(const std::uint64_t* a, const std::uint64_t* b) const {
  for (int w = 0; w < key_words_; ++w) {
    if (a[w] != b[w]) return false;
  }
  return true;
}

std::uint32_t LatticeNodeTable::Find(const std::uint64_t* key) const {
  const std::size_t mask = slots_.size() - 1;
  for (std::size_t s = Hash(key) & mask;; s = (s + 1) & mask) {
    const std::uint32_t node = slots_[s];
    if (node == kNone || Equal(this->key(node), key)) return node;
  }
}

std::uint32_t LatticeNodeTable::Add(const std::uint64_t* key, bool indexed) {
  const auto node = static_cast<std::uint32_t>(size());
  keys_.insert(keys_.end(), key, key + key_words_);
  if (!indexed) return node;
  if (2 * (indexed_ + 1) > slots_.size()) Grow();
  const std::size_t mask = slots_.size() - 1;
  std::size_t s = Hash(key) & mask;
  while (slots_[s] != kNone) s = (s + 1) & mask;
  slots_[s] = node;
  ++indexed_;
  return node;
}

void LatticeNodeTable::Grow() {
  std::vector<std::uint32_t> old(2 * slots_.size(), kNone);
  old.swap(slots_);
  const std::size_t mask = slots_.size() - 1;
  for (const std::uint32_t node : old) {
    if (node == kNone) continue;
    std::size_t s = Hash(key(node)) & mask;
    while (slots_[s] != kNone) s = (s + 1) & mask;
    slots_[s] = node;
  }
}

}  // namespace chasles
