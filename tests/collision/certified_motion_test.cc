// CollisionChecker::IsMotionCertified: soundness against a dense re-check on random Panda
// segments in every example scene, agreement with the discrete check, the lever-arm bound, thin
// obstacles between samples, and the FCL-path / mesh fallback.

#include <algorithm>
#include <cmath>
#include <functional>
#include <iostream>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "chasles/collision/collision_checker.h"
#include "chasles/robot/error.h"
#include "test_util.h"

namespace chasles {
namespace {

Eigen::VectorXd Q1(double x) { return Eigen::VectorXd::Constant(1, x); }

Eigen::Isometry3d At(double x, double y, double z) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() << x, y, z;
  return t;
}

/// A valid random configuration (rejection sampling).
Eigen::VectorXd RandomValid(const CollisionChecker& c, std::mt19937_64& rng) {
  for (int i = 0; i < 100000; ++i) {
    Eigen::VectorXd q = test::RandomConfig(c.robot(), rng);
    if (c.IsValid(q)) return q;
  }
  ADD_FAILURE() << "no valid configuration found";
  return test::RandomConfig(c.robot(), rng);
}

Eigen::VectorXd RandomDir(int n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::VectorXd d(n);
  for (int i = 0; i < n; ++i) d[i] = u(rng);
  return d;
}

/// b = a + a random direction scaled to max-norm `len`, clamped into the limits.
Eigen::VectorXd Toward(const RobotModel& robot, const Eigen::VectorXd& a, const Eigen::VectorXd& dir, double len) {
  Eigen::VectorXd b = a + dir * (len / dir.cwiseAbs().maxCoeff());
  return b.cwiseMax(robot.lower_limits()).cwiseMin(robot.upper_limits());
}

TEST(CertifiedMotion, ThinSheetBetweenSamplesIsFound) {
  auto robot = test::SliderRobot(Shape::Sphere(0.0001));
  auto scene = std::make_shared<Scene>();
  // States of the 0.005 check sit at x = -1 + 0.005 i; the sheet spans [0.0022, 0.0028].
  scene->AddObject({"sheet", Shape::Box({0.0006, 1.0, 1.0}, At(0.0025, 0, 0))});
  CollisionChecker checker(robot, scene);
  ASSERT_TRUE(checker.certifies_motion());
  EXPECT_TRUE(checker.IsMotionValid(Q1(-1), Q1(1), 0.005));  // the gap the certified check closes
  EXPECT_FALSE(checker.IsMotionCertified(Q1(-1), Q1(1)));
  EXPECT_FALSE(checker.IsMotionCertified(Q1(1), Q1(-1)));
  EXPECT_TRUE(checker.IsMotionCertified(Q1(-1), Q1(-0.01)));
  EXPECT_TRUE(checker.IsMotionCertified(Q1(0.01), Q1(1)));
  // A start inside the sheet (checked by the advancement's first state, not before it).
  EXPECT_FALSE(checker.IsMotionCertified(Q1(0.0025), Q1(1)));
  EXPECT_FALSE(checker.IsMotionCertified(Q1(0.0025), Q1(0.0025)));
  // Free space: a prismatic joint has lever 1, so a free 2 m slide needs few states.
  CollisionChecker free_checker(robot, std::make_shared<Scene>());
  CheckCounters counters;
  EXPECT_TRUE(free_checker.IsMotionCertified(Q1(-1), Q1(1), &counters));
  EXPECT_EQ(counters.state_checks, 5u);  // b, 3 bisection probes (0.5 apart), one advancement state (at a)
  EXPECT_FALSE(checker.IsMotionCertified(Q1(-1), Q1(6)));  // b outside the limits
  EXPECT_THROW(checker.IsMotionCertified(Q1(-1), Eigen::VectorXd::Zero(2)), Error);
}

TEST(CertifiedCurve, ACurveThatDipsIntoAnObstacleBetweenItsEndsIsRejected) {
  // x(s) = -1 + 2s + 0.3 sin(πs)·… stays left of the sheet only if it never reaches x = 0.0022:
  // a parabola through x = -0.5 at both ends whose apex pokes 0.0025 into the sheet region.
  auto robot = test::SliderRobot(Shape::Sphere(0.0001));
  auto scene = std::make_shared<Scene>();
  scene->AddObject({"sheet", Shape::Box({0.0006, 1.0, 1.0}, At(0.0025, 0, 0))});
  CollisionChecker checker(robot, scene);
  ASSERT_TRUE(checker.certifies_motion());
  const auto parabola = [](double apex) {
    return [apex](double s, Eigen::VectorXd* q) { *q = Q1(-0.5 + 4.0 * (apex + 0.5) * s * (1.0 - s)); };
  };
  // |dx/ds| = 4 (apex + 0.5) |1 − 2s| <= 4 (apex + 0.5).
  const auto speed = [](double apex) { return Q1(4.0 * (apex + 0.5)); };
  EXPECT_FALSE(checker.IsCurveCertified(parabola(0.0025), speed(0.0025)));  // apex inside the sheet
  EXPECT_FALSE(checker.IsCurveCertified(parabola(0.003), speed(0.003)));    // through it and back
  EXPECT_TRUE(checker.IsCurveCertified(parabola(0.002), speed(0.002)));     // 0.2 mm short of it
  // Both ends are free (x = -0.5): a check of the chord alone would accept the motion.
  EXPECT_TRUE(checker.IsMotionCertified(Q1(-0.5), Q1(-0.5)));
  // A straight segment as a curve gives the segment's answer.
  const auto line = [](double a, double b) {
    return [a, b](double s, Eigen::VectorXd* q) { *q = Q1(a + s * (b - a)); };
  };
  EXPECT_FALSE(checker.IsCurveCertified(line(-1, 1), Q1(2)));
  EXPECT_TRUE(checker.IsCurveCertified(line(-1, -0.01), Q1(0.99)));
  EXPECT_THROW(checker.IsCurveCertified(line(-1, 1), Q1(-1)), Error);
  EXPECT_THROW(checker.IsCurveCertified(line(-1, 1), Eigen::VectorXd::Zero(2)), Error);
  // A curve that returns NaN is never certified.
  EXPECT_FALSE(checker.IsCurveCertified([](double, Eigen::VectorXd* q) { *q = Q1(std::nan("")); }, Q1(1)));
}

// The advancement skips a pair while the clearance it had when last evaluated, minus the
// most it can have shrunk since, cannot shorten the step (its free-until parameter). These
// place an obstacle far from where the motion starts, behind a stretch of tiny steps (a guard
// rail 0.5 mm beside the path), so it stays skipped for hundreds of states before it matters.
std::shared_ptr<Scene> GuardRailAndSheet(double sheet_x) {
  auto scene = std::make_shared<Scene>();
  scene->AddObject({"guard", Shape::Box({0.2, 0.002, 0.002}, At(-0.9, 0.0016, 0))});  // 0.5 mm from the path
  scene->AddObject({"sheet", Shape::Box({0.0006, 1.0, 1.0}, At(sheet_x, 0, 0))});
  return scene;
}

TEST(CertifiedMotion, APairSkippedForManyStatesIsEvaluatedBeforeItCanMatter) {
  auto robot = test::SliderRobot(Shape::Sphere(0.0001));
  CollisionChecker checker(robot, GuardRailAndSheet(0.9));
  ASSERT_TRUE(checker.certifies_motion());
  CheckCounters counters;
  EXPECT_FALSE(checker.IsMotionCertified(Q1(-1), Q1(1), &counters));
  EXPECT_GT(counters.state_checks, 200u);  // the guard rail took many small steps
  EXPECT_FALSE(checker.IsMotionCertified(Q1(1), Q1(-1)));
  EXPECT_TRUE(checker.IsMotionCertified(Q1(-1), Q1(0.899)));    // stops 0.6 mm short of the sheet
  EXPECT_FALSE(checker.IsMotionCertified(Q1(-1), Q1(0.8997)));  // ends 0.1 mm into it
  // The sheet just past the rail: skipped while the rail is passed, then evaluated again.
  CollisionChecker close(robot, GuardRailAndSheet(-0.79));
  EXPECT_FALSE(close.IsMotionCertified(Q1(-1), Q1(0)));
  EXPECT_TRUE(close.IsMotionCertified(Q1(-1), Q1(-0.7905)));  // 0.1 mm short
}

TEST(CertifiedCurve, AnObstacleLeftBehindIsCheckedAgainWhenTheCurveComesBack) {
  // From 0.85 (5 mm before the sheet) out past the guard rail (x ≈ -0.9) and back to x1: the
  // sheet's pair is evaluated at the start, skipped on the way out, and due again on the way back.
  auto robot = test::SliderRobot(Shape::Sphere(0.0001));
  CollisionChecker checker(robot, GuardRailAndSheet(0.9));
  const double pi = std::acos(-1.0);
  const auto out_and_back = [pi](double x1) {
    return [pi, x1](double s, Eigen::VectorXd* q) { *q = Q1(0.85 - 1.75 * std::sin(pi * s) + (x1 - 0.85) * s); };
  };
  // |dx/ds| <= 1.75π + |x1 − 0.85|.
  const auto speed = [pi](double x1) { return Q1(1.75 * pi + std::abs(x1 - 0.85)); };
  CheckCounters counters;
  EXPECT_FALSE(checker.IsCurveCertified(out_and_back(0.91), speed(0.91), &counters));  // back through the sheet
  EXPECT_GT(counters.state_checks, 200u);
  EXPECT_FALSE(checker.IsCurveCertified(out_and_back(0.8997), speed(0.8997)));  // back 0.1 mm into it
  EXPECT_TRUE(checker.IsCurveCertified(out_and_back(0.899), speed(0.899)));     // back to 0.6 mm short
}

TEST(CertifiedMotion, PandaHandThroughAThinPlateBetweenTheProbesIsRejected) {
  // A 0.3 mm plate across the path of a hand sphere at s = 0.93 (between the last probe, 7/8,
  // and the end), among the cage's obstacles: every probe state is free, the dense check finds
  // the plate, and the certified check must too although most of its pairs are being skipped —
  // and soon after its steps start shrinking towards the plate.
  auto panda = test::LoadRobot("panda");
  auto cage = test::LoadScene("scenes/cage.json");
  CollisionChecker cage_checker(panda, cage);
  const int hand = panda->FindLink("panda_hand");
  const Eigen::Vector3d sphere_centre(0, 0.015, 0.03);  // one of the hand's spheres, hand frame
  std::mt19937_64 rng(5);
  std::vector<Eigen::Isometry3d> poses;
  int tested = 0;
  for (int attempt = 0; attempt < 300 && tested < 5; ++attempt) {
    const Eigen::VectorXd a = RandomValid(cage_checker, rng);
    const Eigen::VectorXd b = Toward(*panda, a, RandomDir(7, rng), 1.0);
    const auto centre_at = [&](double s) {
      panda->ForwardKinematics(a + s * (b - a), &poses);
      return Eigen::Vector3d(poses[hand] * sphere_centre);
    };
    const Eigen::Vector3d p = centre_at(0.93);
    const Eigen::Vector3d v = centre_at(0.9301) - centre_at(0.9299);
    if (v.norm() < 1e-6) continue;
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), v.normalized()).toRotationMatrix();
    pose.translation() = p;
    auto scene = std::make_shared<Scene>(*cage);
    scene->AddObject({"plate", Shape::Box({0.06, 0.06, 0.0003}, pose)});
    CollisionChecker checker(panda, scene);
    bool probes_free = true;
    for (int i = 0; i <= 8; ++i) probes_free = probes_free && checker.IsValid(a + (i / 8.0) * (b - a));
    if (!probes_free || checker.IsMotionValid(a, b, 1e-4)) continue;
    ++tested;
    CheckCounters forward, backward;
    EXPECT_FALSE(checker.IsMotionCertified(a, b, &forward)) << "attempt " << attempt;
    EXPECT_FALSE(checker.IsMotionCertified(b, a, &backward)) << "attempt " << attempt;
    // The contact lookahead stops the creep towards the plate early: 27–44 states both ways
    // with it, 73–91 without (the steps shrink by a fixed fraction until they fall below 1e-7).
    EXPECT_LE(forward.state_checks + backward.state_checks, 60u) << "attempt " << attempt;
  }
  EXPECT_GE(tested, 3);
}

TEST(CertifiedCurve, FallsBackToDiscreteStatesWhenTheCheckerCannotCertify) {
  auto robot = test::SliderRobot(Shape::Sphere(0.0001));
  auto scene = std::make_shared<Scene>();
  scene->AddObject({"sheet", Shape::Box({0.0006, 1.0, 1.0}, At(0.0025, 0, 0))});
  CollisionOptions fcl;
  fcl.force_fcl = true;
  CollisionChecker checker(robot, scene, fcl);
  ASSERT_FALSE(checker.certifies_motion());
  CheckCounters counters;
  // 2 m at 0.005: 401 states, s = i/400 → x = -1 + 0.005 i misses the sheet, as the discrete
  // check does.
  EXPECT_TRUE(checker.IsCurveCertified([](double s, Eigen::VectorXd* q) { *q = Q1(-1 + 2 * s); }, Q1(2), &counters));
  EXPECT_EQ(counters.state_checks, 401u);
  EXPECT_FALSE(checker.IsCurveCertified([](double s, Eigen::VectorXd* q) { *q = Q1(0.0025 * s); }, Q1(0.0025)));
}

// A speed bound that is not one value per joint, finite and >= 0 is rejected naming the field,
// the index and the value — by IsCurveCertified and by GroupSweepBounds alike.
TEST(CertifiedCurve, BadSpeedBoundsAreRejectedNamingFieldIndexAndValue) {
  auto panda = test::LoadRobot("panda");
  CollisionChecker checker(panda, test::LoadScene("scenes/shelf.json"));
  const CollisionChecker::Curve still = [](double, Eigen::VectorXd* q) { *q = test::PandaReady(); };
  const auto expect = [](const std::function<void()>& call, const std::string& message) {
    try {
      call();
      ADD_FAILURE() << "no Error thrown; expected: " << message;
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument) << e.what();
      EXPECT_EQ(std::string(e.what()), message);
    }
  };
  Eigen::VectorXd negative = Eigen::VectorXd::Zero(panda->num_dofs());
  negative[2] = -1.0;
  Eigen::VectorXd nan = Eigen::VectorXd::Zero(panda->num_dofs());
  nan[4] = std::nan("");
  const Eigen::VectorXd short_bound = Eigen::VectorXd::Zero(3);
  const std::string joints = std::to_string(panda->num_dofs());
  expect([&] { checker.IsCurveCertified(still, negative); }, "speed_bound[2] = -1 must be finite and >= 0");
  expect([&] { checker.IsCurveCertified(still, nan); }, "speed_bound[4] = nan must be finite and >= 0");
  expect([&] { checker.IsCurveCertified(still, short_bound); },
         "speed_bound has 3 values, robot '" + panda->name() + "' has " + joints + " joints");
  expect([&] { checker.GroupSweepBounds(negative); }, "speed[2] = -1 must be finite and >= 0");
  expect([&] { checker.GroupSweepBounds(nan); }, "speed[4] = nan must be finite and >= 0");
  expect([&] { checker.GroupSweepBounds(short_bound); },
         "speed has 3 values, robot '" + panda->name() + "' has " + joints + " joints");
  // A valid bound: one value per clearance group, each the largest of its spheres' sweep bounds.
  const Eigen::VectorXd speed = Eigen::VectorXd::Constant(panda->num_dofs(), 0.5);
  const Eigen::VectorXd groups = checker.GroupSweepBounds(speed);
  ASSERT_EQ(groups.size(), checker.num_clearance_groups());
  const std::vector<double> spheres = checker.SweepBounds(Eigen::VectorXd::Zero(panda->num_dofs()), speed);
  EXPECT_NEAR(groups.maxCoeff(), *std::max_element(spheres.begin(), spheres.end()), 1e-12);
}

TEST(CertifiedMotion, AStartInSelfCollisionIsRejected) {
  // a is checked by the advancement's first state (every pair at s = 0), self pairs included.
  auto panda = test::LoadRobot("panda");
  CollisionChecker checker(panda, std::make_shared<Scene>());
  std::mt19937_64 rng(5);
  int found = 0;
  for (int i = 0; i < 20000 && found < 20; ++i) {
    const Eigen::VectorXd q = test::RandomConfig(*panda, rng);
    if (checker.IsValid(q)) continue;
    ++found;
    const Eigen::VectorXd b = RandomValid(checker, rng);
    EXPECT_FALSE(checker.IsMotionCertified(q, b)) << "start " << q.transpose();
    EXPECT_FALSE(checker.IsMotionCertified(q, q));
  }
  EXPECT_EQ(found, 20);
}

TEST(CertifiedMotion, LeverArmBoundHoldsAlongSegments) {
  auto panda = test::LoadRobot("panda");
  CollisionChecker checker(panda, std::make_shared<Scene>());
  ASSERT_TRUE(checker.uses_fast_path());
  ASSERT_TRUE(checker.certifies_motion());
  std::vector<Eigen::Vector3d> centres;
  std::vector<int> link_of;
  test::SphereCentres(*panda, &centres, &link_of);
  std::mt19937_64 rng(7);
  std::vector<Eigen::Isometry3d> p0, p1;
  double worst = 0.0;  // largest displacement / bound seen
  for (int seg = 0; seg < 300; ++seg) {
    const Eigen::VectorXd a = test::RandomConfig(*panda, rng);
    const Eigen::VectorXd b = seg % 2 ? test::RandomConfig(*panda, rng)
                                      : Toward(*panda, a, RandomDir(7, rng), 0.1);
    const std::vector<double> D = checker.SweepBounds(a, b);
    ASSERT_EQ(D.size(), centres.size());
    panda->ForwardKinematics(a, &p0);
    for (int i = 1; i <= 50; ++i) {
      const double s = i / 50.0;
      panda->ForwardKinematics(a + s * (b - a), &p1);
      for (std::size_t k = 0; k < centres.size(); ++k) {
        const double moved = (p1[link_of[k]] * centres[k] - p0[link_of[k]] * centres[k]).norm();
        ASSERT_LE(moved, s * D[k] + 1e-12) << "sphere " << k << " segment " << seg;
        if (D[k] > 0) worst = std::max(worst, moved / (s * D[k]));
      }
    }
  }
  EXPECT_GT(worst, 0.2);  // the bound is not vacuous
  std::cout << "[ lever ] largest displacement / bound = " << worst << "\n";
}

TEST(CertifiedMotion, LeverBoundsEveryJointsSpeedOfEverySphere) {
  // R_ik, the bound on how fast sphere k's centre moves per unit of joint i, against the speed
  // measured by central differences at random configurations: never below it, on the Panda and
  // on a slider arm (a revolute joint on a tilted axis, above a prismatic one). The bound uses the distance from
  // each joint's axis where the chain runs along it, so it must also come close to the speeds
  // somewhere (not vacuous).
  std::vector<std::shared_ptr<const RobotModel>> robots = {test::LoadRobot("panda")};
  {
    Link base, carriage, arm;
    base.name = "base";
    carriage.name = "carriage";
    carriage.parent_joint = 0;
    arm.name = "arm";
    arm.parent_joint = 1;
    Eigen::Isometry3d at = Eigen::Isometry3d::Identity();
    at.translation() << 0.3, 0.1, 0.2;
    arm.collision.push_back(Shape::Sphere(0.05, at));
    carriage.collision.push_back(Shape::Sphere(0.05, Eigen::Isometry3d::Identity()));
    Joint slide, turn;
    slide.name = "slide";
    slide.type = JointType::kPrismatic;
    slide.parent_link = 0;
    slide.child_link = 1;
    slide.axis = Eigen::Vector3d::UnitX();
    slide.limits = {-1.0, 2.0, 1.0, 0.0};
    slide.dof = 0;
    turn.name = "turn";
    turn.type = JointType::kRevolute;
    turn.parent_link = 1;
    turn.child_link = 2;
    turn.origin.translation() << 0.0, 0.0, 0.4;
    turn.axis = Eigen::Vector3d(0.0, 1.0, 1.0).normalized();
    turn.limits = {-3.0, 3.0, 1.0, 0.0};
    turn.dof = 1;
    robots.push_back(RobotModel::FromTree("slider_arm", {base, carriage, arm}, {slide, turn}));
  }
  for (const auto& robot : robots) {
    CollisionChecker checker(robot, std::make_shared<Scene>());
    ASSERT_TRUE(checker.certifies_motion()) << robot->name();
    std::vector<Eigen::Vector3d> centres;
    std::vector<int> link_of;
    test::SphereCentres(*robot, &centres, &link_of);
    std::mt19937_64 rng(11);
    std::vector<Eigen::Isometry3d> lo, hi;
    double closest = 0.0;  // largest speed / bound seen
    const double h = 1e-6;
    for (int trial = 0; trial < 300; ++trial) {
      const Eigen::VectorXd q = test::RandomConfig(*robot, rng);
      for (int i = 0; i < robot->num_dofs(); ++i) {
        const Eigen::VectorXd e = Eigen::VectorXd::Unit(robot->num_dofs(), i);
        const std::vector<double> R = checker.SweepBounds(q, q + e);  // R[k] = R_ik
        robot->ForwardKinematics(q - h * e, &lo);
        robot->ForwardKinematics(q + h * e, &hi);
        for (std::size_t k = 0; k < centres.size(); ++k) {
          const double speed = (hi[link_of[k]] * centres[k] - lo[link_of[k]] * centres[k]).norm() / (2.0 * h);
          ASSERT_LE(speed, R[k] * (1.0 + 1e-6) + 1e-8)
              << robot->name() << " joint " << i << " sphere " << k << " trial " << trial;
          if (R[k] > 0.0) closest = std::max(closest, speed / R[k]);
        }
      }
    }
    EXPECT_GT(closest, 0.9) << robot->name();
  }
}

class CertifiedScenes : public ::testing::TestWithParam<const char*> {};

TEST_P(CertifiedScenes, NeverCertifiesACollidingSegment) {
  auto panda = test::LoadRobot("panda");
  auto scene = test::LoadScene(std::string("scenes/") + GetParam());
  CollisionChecker checker(panda, scene);
  ASSERT_TRUE(checker.certifies_motion());
  CollisionOptions wide;
  wide.padding = 0.005;  // "clearly free": valid with 5 mm padding at a 0.001 check
  CollisionChecker padded(panda, scene, wide);
  std::mt19937_64 rng(11);
  int certified = 0, discrete_valid = 0, rejected_discrete_valid = 0;
  int clearly_free = 0, rejected_clearly_free = 0, discrete_invalid = 0;
  std::uint64_t long_free_states = 0, long_free_discrete = 0;
  int long_free = 0, grazing = 0, near_contact = 0;
  const int kSegments = 2000;
  for (int seg = 0; seg < kSegments; ++seg) {
    Eigen::VectorXd a = RandomValid(checker, rng);
    const bool is_long = seg % 4 == 0;
    std::uniform_real_distribution<double> len(is_long ? 0.5 : 0.01, is_long ? 2.0 : 0.3);
    Eigen::VectorXd b = Toward(*panda, a, RandomDir(7, rng), len(rng));
    if (seg % 4 >= 2) {
      for (int i = 0; i < 1000 && checker.IsValid(b); ++i) b = Toward(*panda, a, RandomDir(7, rng), len(rng));
    }
    if (seg % 4 >= 2 && !checker.IsValid(b)) {
      // Near-contact segment: bisect a→b down to a valid state p within ~1e-6 rad of a contact,
      // then pass through p in a random direction — these graze or clip the obstacle.
      Eigen::VectorXd lo = a, hi = b;
      for (int i = 0; i < 30; ++i) {
        const Eigen::VectorXd mid = 0.5 * (lo + hi);
        (checker.IsValid(mid) ? lo : hi) = mid;
      }
      ++near_contact;
      if (seg % 4 == 2) {
        const Eigen::VectorXd d = RandomDir(7, rng);
        const double l = len(rng);
        a = Toward(*panda, lo, -d, l);
        b = Toward(*panda, lo, d, l);
      } else {
        // A chord between two nearby contact-side points, shorter than 0.005: both ends valid,
        // and on a locally convex C-obstacle the interior dips into it between the samples.
        const Eigen::VectorXd hit = hi;
        Eigen::VectorXd lo2 = Toward(*panda, a, RandomDir(7, rng), 0.003), hi2 = hit;
        if (checker.IsValid(lo2)) {
          for (int i = 0; i < 30; ++i) {
            const Eigen::VectorXd mid = 0.5 * (lo2 + hi2);
            (checker.IsValid(mid) ? lo2 : hi2) = mid;
          }
          a = lo;
          b = lo2;
        }
      }
    }
    CheckCounters cert_counters, disc_counters;
    const bool cert = checker.IsMotionCertified(a, b, &cert_counters);
    const bool disc = checker.IsMotionValid(a, b, 0.005, &disc_counters);
    // Dense re-check: every state 1e-4 rad apart.
    const bool dense = disc && checker.IsMotionValid(a, b, 1e-4);
    if (disc && !dense) ++grazing;
    if (cert) {
      ++certified;
      // Zero tolerance: the certified check never accepts a segment with a colliding state.
      ASSERT_TRUE(disc) << GetParam() << " segment " << seg;
      ASSERT_TRUE(dense) << GetParam() << " segment " << seg;
    }
    if (!disc) ++discrete_invalid;
    if (disc) {
      ++discrete_valid;
      if (!cert) ++rejected_discrete_valid;
      if (padded.IsMotionValid(a, b, 0.001)) {
        ++clearly_free;
        if (!cert) ++rejected_clearly_free;
      }
      if (is_long && cert) {
        ++long_free;
        long_free_states += cert_counters.state_checks;
        long_free_discrete += disc_counters.state_checks;
      }
    }
  }
  std::cout << "[ " << GetParam() << " ] " << kSegments << " segments: certified " << certified
            << ", discrete(0.005)-valid " << discrete_valid << " of which rejected by the certified check "
            << rejected_discrete_valid << "; clearly free " << clearly_free << " of which rejected "
            << rejected_clearly_free << "; discrete-invalid " << discrete_invalid
            << "; discrete-valid but colliding at 1e-4 " << grazing << "; near-contact segments "
            << near_contact << "\n"
            << "[ " << GetParam() << " ] free long segments: " << long_free << ", states per segment certified "
            << (long_free ? double(long_free_states) / long_free : 0.0) << " vs discrete 0.005 "
            << (long_free ? double(long_free_discrete) / long_free : 0.0) << "\n";
  EXPECT_GT(certified, kSegments / 10);
  EXPECT_GT(near_contact, kSegments / 10);  // many segments start or pass within 1e-9 rad of a contact
  EXPECT_GT(discrete_invalid, kSegments / 50);  // the scene is in the way sometimes
  ASSERT_GT(clearly_free, 0);
  EXPECT_LE(rejected_clearly_free, clearly_free / 20);  // rejects at most 5 % of clearly free
}

INSTANTIATE_TEST_SUITE_P(ExampleScenes, CertifiedScenes,
                         ::testing::Values("table.json", "shelf.json", "cage.json", "shelf_octomap.json"),
                         [](const auto& info) {
                           std::string n = info.param;
                           return n.substr(0, n.find('.'));
                         });

TEST(CertifiedMotion, FallsBackToTheDiscreteCheckOnTheFclPath) {
  auto panda = test::LoadRobot("panda");
  auto scene = test::LoadScene("scenes/shelf.json");
  CollisionOptions options;
  options.force_fcl = true;
  CollisionChecker fcl(panda, scene, options);
  EXPECT_FALSE(fcl.certifies_motion());
  EXPECT_TRUE(fcl.SweepBounds(test::PandaReady(), test::PandaReady()).empty());
  std::mt19937_64 rng(3);
  for (int seg = 0; seg < 40; ++seg) {
    const Eigen::VectorXd a = RandomValid(fcl, rng);
    const Eigen::VectorXd b = Toward(*panda, a, RandomDir(7, rng), 0.3);
    CheckCounters c1, c2;
    EXPECT_EQ(fcl.IsMotionCertified(a, b, &c1), fcl.IsMotionValid(a, b, 0.005, &c2));
    EXPECT_EQ(c1.state_checks, c2.state_checks);
  }
  // A mesh in the scene: the fast path stays, but motion is not certified (discrete fallback).
  auto mesh_scene = std::make_shared<Scene>();
  Shape tri;
  tri.type = ShapeType::kMesh;
  auto mesh = std::make_shared<TriangleMesh>();
  mesh->vertices = {{1.0, 1.0, 0.0}, {1.1, 1.0, 0.0}, {1.0, 1.1, 0.0}};
  mesh->triangles = {{0, 1, 2}};
  tri.mesh = mesh;
  mesh_scene->AddObject({"tri", tri});
  CollisionChecker with_mesh(panda, mesh_scene);
  EXPECT_TRUE(with_mesh.uses_fast_path());
  EXPECT_FALSE(with_mesh.certifies_motion());
  CheckCounters c1, c2;
  const Eigen::VectorXd a = test::PandaReady();
  Eigen::VectorXd b = a;
  b[0] += 0.5;
  EXPECT_EQ(with_mesh.IsMotionCertified(a, b, &c1), with_mesh.IsMotionValid(a, b, 0.005, &c2));
  EXPECT_EQ(c1.state_checks, c2.state_checks);
}

}  // namespace
}  // namespace chasles
