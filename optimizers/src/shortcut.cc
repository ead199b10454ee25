#include "chasles/optimizers/shortcut.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include "chasles/robot/error.h"

namespace chasles {
namespace {


/// Uniform double in [0, 1) from the top 53 bits: identical on every standard library.
double Uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

/// Uniform integer in [0, n), n >= 1.
int UniformIndex(std::mt19937_64& rng, int n) {
  const int i = static_cast<int>(Uniform01(rng) * n);
  return std::min(i, n - 1);
}

/// Copies the path without consecutive exact duplicates. The last waypoint is kept bit-exact
/// (a trailing duplicate replaces the previous copy).
JointPath RemoveDuplicates(const JointPath& path) {
  JointPath out;
  out.reserve(path.size());
  for (const Eigen::VectorXd& q : path) {
    if (!out.empty() && q == out.back()) continue;
    out.push_back(q);
  }
  if (!out.empty()) out.back() = path.back();
  if (out.size() == 1 && path.size() > 1) {  // all identical: start and goal both kept
    out.push_back(path.back());
    out.front() = path.front();
  }
  return out;
}

/// A segment check: certified (no state on the segment collides) when the checker can,
/// otherwise discrete at max_step.
bool SegmentValid(const CollisionChecker& checker, const Eigen::VectorXd& a, const Eigen::VectorXd& b,
                  double max_step, CheckCounters* counters) {
  return checker.IsMotionFree(a, b, max_step, counters);
}

/// Greedy vertex reduction: from each kept waypoint, jump to the farthest later waypoint (at most
/// `max_skip` ahead) that the straight segment reaches validly (and not longer than the polyline
/// it replaces).
JointPath ReduceVertices(const JointPath& path, const CollisionChecker& checker, double max_step,
                         CheckCounters* counters, std::vector<char>* checked, int max_skip) {
  const int n = static_cast<int>(path.size());
  if (n < 3) {
    checked->assign(std::max(n - 1, 0), 0);
    return path;
  }
  checked->clear();
  // prefix[k] = polyline length from path[0] to path[k].
  std::vector<double> prefix(n, 0.0);
  for (int k = 1; k < n; ++k) prefix[k] = prefix[k - 1] + (path[k] - path[k - 1]).norm();
  JointPath out;
  out.push_back(path.front());
  int i = 0;
  while (i < n - 1) {
    int next = i + 1;
    char valid = 0;  // the kept input segment i → i + 1 was not checked here
    for (int j = std::min(n - 1, i + max_skip); j > i + 1; --j) {
      const double direct = (path[j] - path[i]).norm();
      if (direct > prefix[j] - prefix[i]) continue;  // rounding only; never lengthen
      if (SegmentValid(checker, path[i], path[j], max_step, counters)) {
        next = j;
        valid = 1;
        break;
      }
    }
    out.push_back(path[next]);
    checked->push_back(valid);
    i = next;
  }
  return out;
}

}  // namespace

double PathLength(const JointPath& path) {
  double length = 0.0;
  for (std::size_t k = 1; k < path.size(); ++k) length += (path[k] - path[k - 1]).norm();
  return length;
}

JointPath ShortcutPath(const JointPath& path, const CollisionChecker& checker,
                       const ShortcutOptions& options, CheckCounters* counters) {
  if (options.max_attempts < 0) {
    ThrowInvalid("shortcut max_attempts = " + std::to_string(options.max_attempts) + " must be >= 0");
  }
  if (options.stall_attempts < 0) {
    ThrowInvalid("shortcut stall_attempts = " + std::to_string(options.stall_attempts) + " must be >= 0");
  }
  if (!(options.stall_improvement >= 0.0 && options.stall_improvement < 1.0)) {
    ThrowInvalid("shortcut stall_improvement = " + FormatNumber(options.stall_improvement) + " must be in [0, 1)");
  }
  if (!(options.min_gain >= 0.0 && options.min_gain < 1.0)) {
    ThrowInvalid("shortcut min_gain = " + FormatNumber(options.min_gain) + " must be in [0, 1)");
  }
  if (!std::isfinite(options.max_step)) {
    ThrowInvalid("shortcut max_step = " + FormatNumber(options.max_step) + " must be finite");
  }
  if (!(options.max_step > 0.0)) {
    ThrowInvalid("shortcut max_step = " + FormatNumber(options.max_step) + " must be > 0");
  }
  const int dofs = checker.robot().num_dofs();
  for (std::size_t k = 0; k < path.size(); ++k) {
    if (path[k].size() != dofs) {
      ThrowInvalid("path[" + std::to_string(k) + "] has " + std::to_string(path[k].size()) +
                   " values, robot has " + std::to_string(dofs) + " joints");
    }
    for (int i = 0; i < dofs; ++i) {
      if (!std::isfinite(path[k][i])) {
        ThrowInvalid("path[" + std::to_string(k) + "][" + std::to_string(i) + "] = " + FormatNumber(path[k][i]) +
                     " must be finite");
      }
    }
  }
  if (path.size() < 3) return path;

  // checked[k]: segment current[k] → current[k + 1] passed SegmentValid in this call. On a
  // certifying checker every sub-segment of a checked segment is certified too (its states are
  // a subset, up to rounding of ~1e-16 rad), so a shortcut's head and tail pieces need no new
  // check; on the discrete path they are re-checked at their own states.
  std::vector<char> checked;
  const int all = static_cast<int>(path.size());
  JointPath current = ReduceVertices(RemoveDuplicates(path), checker, options.max_step, counters, &checked, all);
  const bool inherit = checker.certifies_motion();
  double length = PathLength(current);

  std::mt19937_64 rng(options.seed);
  bool changed = false;
  int stalled = 0;        // consecutive attempts that shortened the path by less than the threshold
  for (int attempt = 0; attempt < options.max_attempts; ++attempt) {
    if (options.stop && options.stop()) break;
    if (options.stall_attempts > 0 && stalled >= options.stall_attempts) break;
    const int segments = static_cast<int>(current.size()) - 1;
    if (segments < 2) break;  // a single straight segment cannot get shorter
    ++stalled;
    // Two different segments i < j, a point on each.
    int i = UniformIndex(rng, segments);
    int j = UniformIndex(rng, segments - 1);
    if (j >= i) ++j;
    if (j < i) std::swap(i, j);
    const double ui = Uniform01(rng);
    const double uj = Uniform01(rng);
    const Eigen::VectorXd qa = current[i] + ui * (current[i + 1] - current[i]);
    const Eigen::VectorXd qb = current[j] + uj * (current[j + 1] - current[j]);

    // Length of the stretch qa → current[i+1] → … → current[j] → qb that the shortcut replaces.
    double old_length = (current[i + 1] - qa).norm() + (qb - current[j]).norm();
    for (int k = i + 1; k < j; ++k) old_length += (current[k + 1] - current[k]).norm();
    const double new_length = (qb - qa).norm();
    if (!(new_length < old_length * (1.0 - 1e-9))) continue;  // not meaningfully shorter
    if (old_length - new_length < options.min_gain * length) continue;  // not worth its checks

    // qa and qb lie on valid segments; their pieces are new segments, checked unless they are
    // pieces of a segment certified above.
    const bool head_needed = !(qa == current[i]);
    const bool tail_needed = !(qb == current[j + 1]);
    if (!SegmentValid(checker, qa, qb, options.max_step, counters)) continue;
    if (head_needed && !(inherit && checked[i]) &&
        !SegmentValid(checker, current[i], qa, options.max_step, counters)) {
      continue;
    }
    if (tail_needed && !(inherit && checked[j]) &&
        !SegmentValid(checker, qb, current[j + 1], options.max_step, counters)) {
      continue;
    }

    JointPath next;
    std::vector<char> next_checked;
    next.reserve(current.size() + 2);
    next.insert(next.end(), current.begin(), current.begin() + i + 1);
    next_checked.insert(next_checked.end(), checked.begin(), checked.begin() + i);
    if (head_needed) {
      next.push_back(qa);
      next_checked.push_back(1);
    }
    if (tail_needed && !(head_needed && qb == qa)) {
      next.push_back(qb);
      next_checked.push_back(1);  // qa → qb
    }
    next_checked.push_back(1);  // the last new segment: qa/qb → current[j + 1] (or qa → qb)
    next.insert(next.end(), current.begin() + j + 1, current.end());
    next_checked.insert(next_checked.end(), checked.begin() + j + 1, checked.end());
    current = std::move(next);
    checked = std::move(next_checked);
    const double shorter = length - PathLength(current);
    if (shorter >= options.stall_improvement * length) stalled = 0;
    length -= shorter;
    changed = true;
  }
  // Shortcut points may have made waypoints redundant: drop those whose neighbours see each
  // other (a skip of one; longer jumps were what the shortcuts already tried).
  if (changed) current = ReduceVertices(current, checker, options.max_step, counters, &checked, 2);
  // Endpoints are never replaced above; assert that the contract holds bit for bit.
  current.front() = path.front();
  current.back() = path.back();
  return current;
}

}  // namespace chasles
