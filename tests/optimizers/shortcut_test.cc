// ShortcutPath and PathLength on a planar arm with one obstacle.

#include "chasles/optimizers/shortcut.h"

#include <cmath>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "chasles/robot/error.h"
#include "planar_fixture.h"
#include "test_util.h"

namespace chasles {
namespace {

using test::BitEqual;

constexpr double kStep = 0.005;

void ExpectEverySegmentValid(const JointPath& path, const CollisionChecker& checker) {
  for (std::size_t k = 0; k + 1 < path.size(); ++k) {
    EXPECT_TRUE(checker.IsMotionValid(path[k], path[k + 1], kStep)) << "segment " << k;
  }
}

bool SamePath(const JointPath& x, const JointPath& y) {
  if (x.size() != y.size()) return false;
  for (std::size_t k = 0; k < x.size(); ++k) {
    if (!BitEqual(x[k], y[k])) return false;
  }
  return true;
}

TEST(PathLength, SumsEuclideanSegmentLengths) {
  EXPECT_EQ(PathLength({}), 0.0);
  EXPECT_EQ(PathLength({Eigen::Vector2d(1, 1)}), 0.0);
  EXPECT_DOUBLE_EQ(PathLength({Eigen::Vector2d(0, 0), Eigen::Vector2d(3, 4), Eigen::Vector2d(3, 4),
                               Eigen::Vector2d(3, 0)}),
                   9.0);
}

TEST(Shortcut, ZigZagAroundAnObstacleGetsShorterAndStaysValid) {
  const auto checker = test::PlanarCheckerWithPost();
  const JointPath input = test::ZigZagAroundPost();
  // The premise: the zig-zag is valid, the straight line is not.
  ExpectEverySegmentValid(input, *checker);
  ASSERT_FALSE(checker->IsMotionValid(input.front(), input.back(), kStep));

  ShortcutOptions options;
  options.max_attempts = 200;
  options.seed = 7;
  CheckCounters counters;
  const JointPath out = ShortcutPath(input, *checker, options, &counters);
  EXPECT_GT(counters.state_checks, 0u);
  ASSERT_GE(out.size(), 3u);  // the obstacle forces a detour
  EXPECT_TRUE(BitEqual(out.front(), input.front()));
  EXPECT_TRUE(BitEqual(out.back(), input.back()));
  EXPECT_LT(PathLength(out), 0.8 * PathLength(input));
  ExpectEverySegmentValid(out, *checker);
  for (std::size_t k = 0; k + 1 < out.size(); ++k) EXPECT_FALSE(out[k] == out[k + 1]) << "duplicate at " << k;

  // Deterministic: the same seed gives the same path bit for bit.
  EXPECT_TRUE(SamePath(ShortcutPath(input, *checker, options), out));
  // Other seeds: also valid, exact at the ends and never longer; the seed is actually used.
  int differing = 0;
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    options.seed = seed;
    const JointPath other = ShortcutPath(input, *checker, options);
    differing += SamePath(other, out) ? 0 : 1;
    EXPECT_TRUE(BitEqual(other.front(), input.front()));
    EXPECT_TRUE(BitEqual(other.back(), input.back()));
    EXPECT_LE(PathLength(other), PathLength(input));
    ExpectEverySegmentValid(other, *checker);
  }
  EXPECT_GT(differing, 0) << "every seed gave the same path";
}

TEST(Shortcut, RandomShortcutsImproveOnVertexReductionAlone) {
  const auto checker = test::PlanarCheckerWithPost();
  const JointPath input = test::ZigZagAroundPost();
  ShortcutOptions options;
  options.max_attempts = 0;  // greedy vertex reduction only
  const JointPath reduced = ShortcutPath(input, *checker, options);
  EXPECT_LT(reduced.size(), input.size());
  EXPECT_LE(PathLength(reduced), PathLength(input));
  ExpectEverySegmentValid(reduced, *checker);
  options.max_attempts = 200;
  const JointPath shortened = ShortcutPath(input, *checker, options);
  EXPECT_LE(PathLength(shortened), PathLength(reduced));
}

TEST(Shortcut, StallEndsAttemptsThatNoLongerShortenThePath) {
  const auto checker = test::PlanarCheckerWithPost();
  const JointPath input = test::ZigZagAroundPost();
  ShortcutOptions options;
  options.max_attempts = 200;
  options.stall_attempts = 5;
  options.stall_improvement = 0.999;  // no single attempt shortens the path by 99.9%
  int polls = 0;
  options.stop = [&polls] { return ++polls < 0; };
  const JointPath out = ShortcutPath(input, *checker, options);
  EXPECT_EQ(polls, 6);  // five attempts, then the stall ends it at the sixth poll
  ExpectEverySegmentValid(out, *checker);
  // With no stall rule every attempt runs (the path keeps at least two segments around the post).
  options.stall_attempts = 0;
  polls = 0;
  ShortcutPath(input, *checker, options);
  EXPECT_EQ(polls, 200);
  // The pipeline's rule (10 attempts under 1%) stops early with fewer checks, and still
  // shortens the path beyond vertex reduction alone.
  options.stall_attempts = 10;
  options.stall_improvement = 0.01;
  options.stop = {};
  CheckCounters full_checks, early_checks;
  const JointPath reduced = ShortcutPath(input, *checker, ShortcutOptions{0, kStep, 1, 0, 0.0, 0.0, {}});
  const JointPath full = ShortcutPath(input, *checker, ShortcutOptions{200, kStep, 1, 0, 0.0, 0.0, {}}, &full_checks);
  const JointPath early = ShortcutPath(input, *checker, options, &early_checks);
  EXPECT_LT(early_checks.state_checks, full_checks.state_checks);
  EXPECT_LT(PathLength(early), PathLength(reduced));
  EXPECT_LE(PathLength(full), PathLength(reduced));
  ExpectEverySegmentValid(early, *checker);
  options.stall_attempts = -1;
  EXPECT_THROW(ShortcutPath(input, *checker, options), Error);
  options.stall_attempts = 1;
  options.stall_improvement = 1.0;
  EXPECT_THROW(ShortcutPath(input, *checker, options), Error);
}

TEST(Shortcut, MinGainLeavesSmallGainsUnchecked) {
  const auto checker = test::PlanarCheckerWithPost();
  const JointPath input = test::ZigZagAroundPost();
  ShortcutOptions reduce_only;
  reduce_only.max_attempts = 0;
  CheckCounters reduce_checks;
  const JointPath reduced = ShortcutPath(input, *checker, reduce_only, &reduce_checks);
  // No shortcut around the post gains 99 % of the path: none is checked, nothing changes
  // after the vertex reduction (and no final reduction runs).
  ShortcutOptions options;
  options.max_attempts = 200;
  options.min_gain = 0.99;
  CheckCounters checks;
  const JointPath out = ShortcutPath(input, *checker, options, &checks);
  EXPECT_EQ(checks.state_checks, reduce_checks.state_checks);
  EXPECT_TRUE(SamePath(out, reduced));
  // A small threshold still shortens the path, with fewer checks than checking every candidate.
  options.min_gain = 0.005;
  CheckCounters small_checks, all_checks;
  const JointPath small = ShortcutPath(input, *checker, options, &small_checks);
  options.min_gain = 0.0;
  ShortcutPath(input, *checker, options, &all_checks);
  EXPECT_LT(PathLength(small), PathLength(reduced));
  EXPECT_LT(small_checks.state_checks, all_checks.state_checks);
  ExpectEverySegmentValid(small, *checker);
  for (double bad : {-0.1, 1.0, std::numeric_limits<double>::quiet_NaN()}) {
    options.min_gain = bad;
    try {
      ShortcutPath(input, *checker, options);
      ADD_FAILURE() << "min_gain = " << bad << " was accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
      EXPECT_NE(std::string(e.what()).find("min_gain"), std::string::npos) << e.what();
    }
  }
}

TEST(Shortcut, EverySegmentOfTheResultIsCertifiedOnACertifyingChecker) {
  const auto checker = test::PlanarCheckerWithPost();
  ASSERT_TRUE(checker->certifies_motion());
  const JointPath input = test::ZigZagAroundPost();
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    ShortcutOptions options;
    options.max_attempts = 100;
    options.seed = seed;
    const JointPath out = ShortcutPath(input, *checker, options);
    // Head and tail pieces inherit their segment's certificate; an independent re-check of each
    // result segment must agree.
    for (std::size_t k = 0; k + 1 < out.size(); ++k) {
      EXPECT_TRUE(checker->IsMotionCertified(out[k], out[k + 1])) << "seed " << seed << " segment " << k;
    }
  }
}

TEST(Shortcut, StopEndsRandomShortcutsWithAValidPath) {
  const auto checker = test::PlanarCheckerWithPost();
  const JointPath input = test::ZigZagAroundPost();
  ShortcutOptions options;
  options.max_attempts = 0;
  const JointPath reduced = ShortcutPath(input, *checker, options);
  // Stopped before the first attempt: exactly the vertex reduction, even with many attempts.
  options.max_attempts = 200;
  int polls = 0;
  options.stop = [&polls] { return ++polls > 0; };
  const JointPath stopped = ShortcutPath(input, *checker, options);
  EXPECT_EQ(polls, 1);
  ASSERT_EQ(stopped.size(), reduced.size());
  for (size_t i = 0; i < stopped.size(); ++i) EXPECT_EQ(stopped[i], reduced[i]);
  ExpectEverySegmentValid(stopped, *checker);
  // Stopped after a few attempts: still valid, endpoints exact.
  polls = 0;
  options.stop = [&polls] { return ++polls > 5; };
  const JointPath partial = ShortcutPath(input, *checker, options);
  EXPECT_EQ(polls, 6);
  EXPECT_EQ(partial.front(), input.front());
  EXPECT_EQ(partial.back(), input.back());
  ExpectEverySegmentValid(partial, *checker);
}

TEST(Shortcut, FreeSpaceCollapsesToOneSegmentAndDropsDuplicatesAndCollinearPoints) {
  const auto checker = test::PlanarCheckerWithPost();
  // Folded elbow: the whole region is free, so start and goal connect directly.
  const JointPath input{Eigen::Vector2d(0.1, 2.5), Eigen::Vector2d(0.2, 2.5), Eigen::Vector2d(0.2, 2.5),
                        Eigen::Vector2d(0.3, 2.5), Eigen::Vector2d(0.7, 2.6), Eigen::Vector2d(0.5, 2.5)};
  const JointPath out = ShortcutPath(input, *checker, ShortcutOptions{});
  ASSERT_EQ(out.size(), 2u);
  EXPECT_TRUE(BitEqual(out[0], input.front()));
  EXPECT_TRUE(BitEqual(out[1], input.back()));
  // Two waypoints or fewer come back unchanged.
  const JointPath two{Eigen::Vector2d(0.1, 2.5), Eigen::Vector2d(0.2, 2.5)};
  EXPECT_TRUE(SamePath(ShortcutPath(two, *checker, ShortcutOptions{}), two));
}

template <typename F>
std::string ErrorMessage(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    return e.what();
  }
  return "<no error>";
}

TEST(Shortcut, OptionAndPathValidation) {
  const auto checker = test::PlanarCheckerWithPost();
  const JointPath path = test::ZigZagAroundPost();
  ShortcutOptions options;
  options.max_attempts = -1;
  EXPECT_EQ(ErrorMessage([&] { ShortcutPath(path, *checker, options); }),
            "shortcut max_attempts = -1 must be >= 0");
  options = ShortcutOptions{};
  options.max_step = 0.0;
  EXPECT_EQ(ErrorMessage([&] { ShortcutPath(path, *checker, options); }), "shortcut max_step = 0 must be > 0");
  options.max_step = std::nan("");
  EXPECT_EQ(ErrorMessage([&] { ShortcutPath(path, *checker, options); }), "shortcut max_step = nan must be finite");
  JointPath bad = path;
  bad[3] = Eigen::Vector3d(0, 0, 0);
  EXPECT_EQ(ErrorMessage([&] { ShortcutPath(bad, *checker, ShortcutOptions{}); }),
            "path[3] has 3 values, robot has 2 joints");
  bad = path;
  bad[2][1] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(ErrorMessage([&] { ShortcutPath(bad, *checker, ShortcutOptions{}); }), "path[2][1] = inf must be finite");
}

}  // namespace
}  // namespace chasles
