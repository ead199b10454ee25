// The broad phase over scene primitives (CollisionOptions::broad_phase) must not change any
// answer: the same checks on the same cluttered scenes, with it and without it (every primitive
// scanned), agree exactly — state checks and their first contact, Clearance to the last bit, and
// the verdicts of certified motions — including touching and just-separated obstacles.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "chasles/collision/collision_checker.h"
#include "chasles/collision/proximity.h"
#include "test_util.h"
#include "../../collision/src/broad_phase.h"

namespace chasles {
namespace {

Eigen::Isometry3d RandomPose(std::mt19937_64& rng, double r_min, double r_max, double z_min, double z_max) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double angle = 2.0 * M_PI * u(rng);
  const double radius = r_min + (r_max - r_min) * u(rng);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() << radius * std::cos(angle), radius * std::sin(angle), z_min + (z_max - z_min) * u(rng);
  pose.linear() = Eigen::Quaterniond(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5).normalized().toRotationMatrix();
  return pose;
}

/// n 5 cm boxes on a ring 1.6–3 m from the Panda's base, out of its reach.
void AddFarRing(Scene* scene, int n, std::mt19937_64* rng) {
  for (int i = 0; i < n; ++i) {
    scene->AddObject({"far" + std::to_string(i), Shape::Box({0.05, 0.05, 0.05}, RandomPose(*rng, 1.6, 3.0, 0.0, 1.5))});
  }
}

/// `near` primitives of every kind (sizes 0.01–max_size m) within the Panda's reach and `far`
/// 5 cm boxes on a ring 1.6–3 m out (as the clutter), plus the table.
std::shared_ptr<Scene> ClutteredScene(std::uint64_t seed, int near, int far, double max_size = 0.12) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> size(0.01, max_size);
  auto scene = test::LoadScene("scenes/table.json");
  for (int i = 0; i < near; ++i) {
    const Eigen::Isometry3d pose = RandomPose(rng, 0.25, 0.9, 0.0, 1.1);
    const std::string name = "near" + std::to_string(i);
    switch (i % 4) {
      case 0: scene->AddObject({name, Shape::Box({size(rng), size(rng), size(rng)}, pose)}); break;
      case 1: scene->AddObject({name, Shape::Sphere(0.5 * size(rng), pose)}); break;
      case 2: scene->AddObject({name, Shape::Cylinder(0.5 * size(rng), size(rng), pose)}); break;
      default: scene->AddObject({name, Shape::Capsule(0.5 * size(rng), size(rng), pose)}); break;
    }
  }
  AddFarRing(scene.get(), far, &rng);
  return scene;
}

/// A point `distance` beyond the link origin farthest from the base at q (where the robot's
/// query box ends): straight up from it, or outward along its direction from the base.
Eigen::Isometry3d BeyondTheOuterLink(const RobotModel& robot, const Eigen::VectorXd& q, bool up, double distance) {
  std::vector<Eigen::Isometry3d> poses;
  robot.ForwardKinematics(q, &poses);
  std::size_t outer = 0;
  for (std::size_t l = 0; l < poses.size(); ++l) {
    if (poses[l].translation().norm() > poses[outer].translation().norm()) outer = l;
  }
  const Eigen::Vector3d tip = poses[outer].translation();
  const Eigen::Vector3d out = up ? Eigen::Vector3d(0.0, 0.0, 1.0) : Eigen::Vector3d(tip.normalized());
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = tip + distance * out;
  return pose;
}

struct Pair {
  std::unique_ptr<CollisionChecker> indexed, scanned;
};

Pair Checkers(const std::shared_ptr<const RobotModel>& robot, const std::shared_ptr<const Scene>& scene,
              double padding = 0.0) {
  CollisionOptions with, without;
  with.padding = without.padding = padding;
  without.broad_phase = false;
  return {std::make_unique<CollisionChecker>(robot, scene, with),
          std::make_unique<CollisionChecker>(robot, scene, without)};
}

void ExpectSameStateAnswers(const Pair& c, const Eigen::VectorXd& q, const std::string& where) {
  const CollisionResult a = c.indexed->Check(q);
  const CollisionResult b = c.scanned->Check(q);
  EXPECT_EQ(a.in_collision, b.in_collision) << where;
  EXPECT_EQ(a.self_collision, b.self_collision) << where;
  EXPECT_EQ(a.link_a, b.link_a) << where;
  EXPECT_EQ(a.other, b.other) << where;
  EXPECT_EQ(c.indexed->IsValid(q), c.scanned->IsValid(q)) << where;
  // Bit for bit: the same pairs' distances, the least of them.
  const double da = c.indexed->Clearance(q), db = c.scanned->Clearance(q);
  EXPECT_TRUE(da == db) << where << ": clearance " << da << " with the broad phase, " << db << " without";
}

TEST(BroadPhase, SameAnswersOnRandomClutteredScenesAndStates) {
  auto panda = test::LoadRobot("panda");
  int collisions = 0, free_states = 0, certified = 0, rejected = 0;
  std::uint64_t indexed_states = 0, scanned_states = 0;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    // Few large obstacles, or many small ones (then some lie near the edge of any query box).
    const auto scene = seed % 2 == 1 ? ClutteredScene(seed, 40, 400) : ClutteredScene(seed, 400, 400, 0.04);
    for (double padding : {0.0, 0.01}) {
      const Pair c = Checkers(panda, scene, padding);
      ASSERT_TRUE(c.indexed->certifies_motion());
      std::mt19937_64 rng(100 + seed);
      Eigen::VectorXd previous = test::RandomConfig(*panda, rng);
      for (int i = 0; i < 150; ++i) {
        const Eigen::VectorXd q = test::RandomConfig(*panda, rng);
        const std::string where = "seed " + std::to_string(seed) + " padding " + std::to_string(padding) +
                                  " state " + std::to_string(i);
        ExpectSameStateAnswers(c, q, where);
        (c.scanned->IsValid(q) ? free_states : collisions) += 1;
        // Certified motions between consecutive states: the same verdict (the broad phase cuts
        // a long motion into chunks of at most 0.2 m of sweep, each step ending by its chunk's
        // end, so the states may differ).
        CheckCounters ca, cb;
        const bool ma = c.indexed->IsMotionCertified(previous, q, &ca);
        const bool mb = c.scanned->IsMotionCertified(previous, q, &cb);
        EXPECT_EQ(ma, mb) << where;
        indexed_states += ca.state_checks;
        scanned_states += cb.state_checks;
        (mb ? certified : rejected) += 1;
        previous = q;
      }
    }
  }
  // The scenes are neither empty nor full around the arm, and both verdicts occur.
  EXPECT_GT(collisions, 100);
  EXPECT_GT(free_states, 100);
  EXPECT_GT(certified, 10);
  EXPECT_GT(rejected, 100);
  // The chunks' cuts add few states.
  EXPECT_LE(indexed_states, scanned_states + scanned_states / 2);
}

TEST(BroadPhase, TouchingAndJustSeparatedObstacles) {
  // A ball just beyond a link (the hand, or the link farthest from the base: where the robot's
  // query box ends), grown to exactly the clearance it had (touching) and a hair less or more,
  // among 300 distant boxes: both checkers must agree on every one.
  auto panda = test::LoadRobot("panda");
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int touching_collides = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const Eigen::VectorXd q = test::RandomConfig(*panda, rng);
    const Eigen::Isometry3d pose = BeyondTheOuterLink(*panda, q, trial % 3 == 0, 0.15 + 0.1 * u(rng));
    const double r0 = 0.02;
    auto probe = ClutteredScene(50 + trial, 0, 300);
    probe->AddObject({"ball", Shape::Sphere(r0, pose)});
    const double d = Checkers(panda, probe).scanned->Clearance(q);
    if (!(d > 1e-6 && d < 1.0)) continue;  // in contact already, or the table is nearer
    for (double grow : {d * (1.0 - 1e-12), d, d * (1.0 + 1e-12), d + 1e-9}) {
      auto scene = ClutteredScene(50 + trial, 0, 300);
      scene->AddObject({"ball", Shape::Sphere(r0 + grow, pose)});
      const Pair c = Checkers(panda, scene);
      ExpectSameStateAnswers(c, q, "trial " + std::to_string(trial) + " grow " + std::to_string(grow));
      if (grow == d) touching_collides += c.scanned->IsValid(q) ? 0 : 1;
    }
  }
  EXPECT_GT(touching_collides, 10) << "too few trials reached the touching case";
}

TEST(BroadPhase, FarClutterChangesNoAnswer) {
  // 2000 boxes out of the arm's reach: every state check and certified motion answers as in the
  // scene without them (the far boxes may only add advancement states on long motions, whose
  // swept bound reaches them).
  auto panda = test::LoadRobot("panda");
  const auto table = test::LoadScene("scenes/table.json");
  const auto cluttered = ClutteredScene(9, 0, 2000);
  const CollisionChecker plain(panda, table);
  const CollisionChecker indexed(panda, cluttered);
  std::mt19937_64 rng(11);
  for (int i = 0; i < 100; ++i) {
    const Eigen::VectorXd a = test::RandomConfig(*panda, rng);
    const Eigen::VectorXd b = test::RandomConfig(*panda, rng);
    EXPECT_EQ(plain.IsValid(a), indexed.IsValid(a)) << i;
    EXPECT_EQ(plain.Check(a).other, indexed.Check(a).other) << i;
    EXPECT_EQ(plain.Clearance(a), indexed.Clearance(a)) << i;
    EXPECT_EQ(plain.IsMotionCertified(a, b), indexed.IsMotionCertified(a, b)) << i;
  }
  // Only the far ring: the nearest box is beyond Clearance's first search radius, which must
  // widen until it finds it.
  auto ring = std::make_shared<Scene>();
  std::mt19937_64 ring_rng(12);
  AddFarRing(ring.get(), 500, &ring_rng);
  const Pair c = Checkers(panda, ring);
  for (int i = 0; i < 50; ++i) {
    const Eigen::VectorXd q = test::RandomConfig(*panda, rng);
    const double d = c.scanned->Clearance(q);
    EXPECT_GT(d, 0.3) << i;
    EXPECT_TRUE(c.indexed->Clearance(q) == d) << i << ": " << c.indexed->Clearance(q) << " vs " << d;
  }
}

TEST(BroadPhase, CertifiedMotionMeetsAnObstacleOnlyItsSweepReaches) {
  // A motion whose hand reaches out, at s = 0.6, 0.2 m beyond the box around every link origin
  // at its start, and a 1 cm ball there; 300 far boxes turn the broad phase on. The motion collides, so
  // neither checker may certify it: the ball lies outside the robot's box at the start, so it is
  // found only if the motion's prims are gathered from its sweep, chunk by chunk, with no step
  // jumping past the end of its chunk. (Joint changes of at most 0.5 rad: one probe, at s = 0.5.)
  auto panda = test::LoadRobot("panda");
  const int hand = panda->FindLink("panda_hand");
  ASSERT_GE(hand, 0);
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  std::vector<Eigen::Isometry3d> start_poses, poses;
  int caught = 0;
  for (int trial = 0; trial < 20000 && caught < 30; ++trial) {
    const Eigen::VectorXd a = test::RandomConfig(*panda, rng);
    Eigen::VectorXd b = a;
    for (int i = 0; i < b.size(); ++i) {
      b[i] = std::clamp(a[i] + u(rng), panda->lower_limits()[i], panda->upper_limits()[i]);
    }
    const Eigen::VectorXd middle = a + 0.6 * (b - a);
    panda->ForwardKinematics(a, &start_poses);
    panda->ForwardKinematics(middle, &poses);
    // Outside the box around the start's link origins by 0.2 m along some axis.
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e9), hi = Eigen::Vector3d::Constant(-1e9);
    for (const Eigen::Isometry3d& p : start_poses) {
      lo = lo.cwiseMin(p.translation());
      hi = hi.cwiseMax(p.translation());
    }
    const Eigen::Vector3d x = poses[hand].translation();
    if (!((x - hi).maxCoeff() > 0.2 || (lo - x).maxCoeff() > 0.2)) continue;
    Eigen::Isometry3d at = Eigen::Isometry3d::Identity();
    at.translation() = poses[hand].translation();
    auto scene = ClutteredScene(60 + trial, 0, 300);
    scene->AddObject({"ball", Shape::Sphere(0.01, at)});
    const Pair c = Checkers(panda, scene);
    // Only motions whose ends and probe are free and whose s = 0.6 is not.
    if (!c.scanned->IsValid(a) || !c.scanned->IsValid(b) || !c.scanned->IsValid(a + 0.5 * (b - a)) ||
        c.scanned->IsValid(middle)) {
      continue;
    }
    EXPECT_FALSE(c.scanned->IsMotionCertified(a, b)) << trial;
    EXPECT_FALSE(c.indexed->IsMotionCertified(a, b)) << trial;
    ++caught;
  }
  EXPECT_GE(caught, 20);
}

TEST(BroadPhase, CertifiedSlideMeetsABallAnywhereAlongIt) {
  // A 1 cm ball on a prismatic slider, sliding 1 m along x, past a 5 mm ball on its line at
  // x = X (X from 0.02 to 0.98), among 40 far boxes that turn the broad phase on: the slide
  // collides for every X, so no checker may certify it — a ball that the box around the slider
  // at a chunk's start misses (not grown by the chunk's sweep), or that lies past a chunk's end
  // (a step not cut there), would be stepped over. With the ball 1e-6 m off the line the slide
  // is free and both certify it.
  const auto slider = test::SliderRobot(Shape::Sphere(0.01, Eigen::Isometry3d::Identity()));
  Eigen::VectorXd a(1), b(1);
  a << 0.0;
  b << 1.0;
  int refused = 0, certified = 0;
  for (int i = 2; i <= 98; ++i) {
    const double x = 0.01 * i;
    for (const double gap : {-1e-4, 1e-6}) {
      auto scene = std::make_shared<Scene>();
      std::mt19937_64 rng(70 + i);
      AddFarRing(scene.get(), 40, &rng);
      Eigen::Isometry3d at = Eigen::Isometry3d::Identity();
      at.translation() << x, 0.015 + gap, 0.0;  // touching at gap 0
      scene->AddObject({"ball", Shape::Sphere(0.005, at)});
      const Pair c = Checkers(slider, scene);
      ASSERT_TRUE(c.indexed->certifies_motion());
      const bool expected = gap > 0.0;
      EXPECT_EQ(c.scanned->IsMotionCertified(a, b), expected) << "x " << x << " gap " << gap;
      EXPECT_EQ(c.indexed->IsMotionCertified(a, b), expected) << "x " << x << " gap " << gap;
      (expected ? certified : refused) += 1;
    }
  }
  EXPECT_EQ(refused, 97);
  EXPECT_EQ(certified, 97);
}

TEST(BroadPhase, ObstacleProximityGivesTheSameNearestObstacles) {
  // The potential field's distance queries: per link, the same nearest obstacle, distance and
  // points with the broad phase as without, for short, medium and unbounded reach.
  auto panda = test::LoadRobot("panda");
  int found = 0;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const auto scene = ClutteredScene(seed, 60, 500);
    const ObstacleProximity indexed(panda, scene);
    const ObstacleProximity scanned(panda, scene, /*broad_phase=*/false);
    std::mt19937_64 rng(300 + seed);
    std::vector<LinkProximity> a, b;
    for (int i = 0; i < 40; ++i) {
      const Eigen::VectorXd q = test::RandomConfig(*panda, rng);
      for (double reach : {0.05, 0.3, std::numeric_limits<double>::infinity()}) {
        indexed.Query(q, reach, &a);
        scanned.Query(q, reach, &b);
        ASSERT_EQ(a.size(), b.size());
        for (std::size_t k = 0; k < a.size(); ++k) {
          const std::string where = "seed " + std::to_string(seed) + " state " + std::to_string(i) + " reach " +
                                    std::to_string(reach) + " link " + std::to_string(a[k].link);
          EXPECT_EQ(a[k].obstacle, b[k].obstacle) << where;
          EXPECT_TRUE(a[k].distance == b[k].distance || (std::isnan(a[k].distance) && std::isnan(b[k].distance)))
              << where << ": " << a[k].distance << " vs " << b[k].distance;
          if (a[k].obstacle >= 0 && a[k].obstacle == b[k].obstacle) {
            EXPECT_TRUE(a[k].link_point == b[k].link_point) << where;
            EXPECT_TRUE(a[k].obstacle_point == b[k].obstacle_point) << where;
            ++found;
          }
        }
      }
    }
  }
  EXPECT_GT(found, 500);
}

/// A cube of half side h as a triangle mesh at `pose`.
SceneObject MeshCube(const std::string& name, double h, const Eigen::Isometry3d& pose) {
  return {name, test::CubeMeshShape(h, pose)};
}

TEST(BroadPhase, FclBroadPhaseGivesTheSameAnswersForMeshesAndOnTheFclPath) {
  // Objects FCL handles: meshes on the fast path, and every object on the FCL path (force_fcl).
  // With more than 32 of them FCL's dynamic AABB tree lists those near the robot; the answers
  // (first contact, validity, Clearance to the last bit) must be those of visiting them all.
  auto panda = test::LoadRobot("panda");
  int collisions = 0, free_states = 0;
  for (std::uint64_t seed = 1; seed <= 2; ++seed) {
    std::mt19937_64 rng(400 + seed);
    std::uniform_real_distribution<double> half(0.01, 0.06);
    auto scene = ClutteredScene(seed, 12, 150);  // primitives: geoms on the FCL path
    for (int i = 0; i < 30; ++i) scene->AddObject(MeshCube("mesh" + std::to_string(i), half(rng),
                                                           RandomPose(rng, 0.25, 0.9, 0.0, 1.1)));
    for (int i = 0; i < 60; ++i) scene->AddObject(MeshCube("farmesh" + std::to_string(i), 0.03,
                                                           RandomPose(rng, 1.6, 3.0, 0.0, 1.5)));
    for (const bool force_fcl : {false, true}) {
      for (const double padding : {0.0, 0.01}) {
        CollisionOptions with, without;
        with.padding = without.padding = padding;
        with.force_fcl = without.force_fcl = force_fcl;
        without.broad_phase = false;
        const Pair c{std::make_unique<CollisionChecker>(panda, scene, with),
                     std::make_unique<CollisionChecker>(panda, scene, without)};
        ASSERT_EQ(c.indexed->uses_fast_path(), !force_fcl);
        std::mt19937_64 qrng(500 + seed);
        for (int i = 0; i < (force_fcl ? 40 : 80); ++i) {
          const Eigen::VectorXd q = test::RandomConfig(*panda, qrng);
          ExpectSameStateAnswers(c, q, "seed " + std::to_string(seed) + (force_fcl ? " fcl" : " fast") +
                                           " padding " + std::to_string(padding) + " state " + std::to_string(i));
          (c.scanned->IsValid(q) ? free_states : collisions) += 1;
        }
      }
    }
    // Only the far meshes: Clearance must widen its search until it meets the nearest one.
    auto ring = std::make_shared<Scene>();
    for (int i = 0; i < 60; ++i) ring->AddObject(MeshCube("far" + std::to_string(i), 0.03,
                                                          RandomPose(rng, 1.6, 3.0, 0.0, 1.5)));
    const Pair r = Checkers(panda, ring);
    for (int i = 0; i < 20; ++i) {
      const Eigen::VectorXd q = test::RandomConfig(*panda, rng);
      const double d = r.scanned->Clearance(q);
      EXPECT_GT(d, 0.3) << i;
      EXPECT_TRUE(r.indexed->Clearance(q) == d) << i << ": " << r.indexed->Clearance(q) << " vs " << d;
    }
  }
  EXPECT_GT(collisions, 50);
  EXPECT_GT(free_states, 50);
}

TEST(BroadPhase, FclObjectsJustWithinAndBeyondThePadding) {
  // A mesh cube just beyond the link farthest from the base (where the robot's query box ends),
  // among 60 far mesh cubes, with the padding set to exactly its clearance (touching) and a hair
  // less or more: with and without FCL's broad phase, fast path and FCL path, the same answers.
  auto panda = test::LoadRobot("panda");
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int touching_collides = 0;
  for (int trial = 0; trial < 30; ++trial) {
    const Eigen::VectorXd q = test::RandomConfig(*panda, rng);
    const Eigen::Isometry3d pose = BeyondTheOuterLink(*panda, q, trial % 3 == 0, 0.1 + 0.1 * u(rng));
    auto scene = std::make_shared<Scene>();
    std::mt19937_64 far_rng(900 + trial);
    for (int i = 0; i < 60; ++i) scene->AddObject(MeshCube("far" + std::to_string(i), 0.03,
                                                           RandomPose(far_rng, 1.6, 3.0, 0.0, 1.5)));
    scene->AddObject(MeshCube("cube", 0.02, pose));
    for (const bool force_fcl : {false, true}) {
      CollisionOptions plain;
      plain.force_fcl = force_fcl;
      const double d = CollisionChecker(panda, scene, plain).Clearance(q);
      if (!(d > 1e-4 && d < 0.5)) continue;  // in contact already
      for (const double padding : {d * (1.0 - 1e-9), d, d * (1.0 + 1e-9)}) {
        CollisionOptions with = plain, without = plain;
        with.padding = without.padding = padding;
        without.broad_phase = false;
        const Pair c{std::make_unique<CollisionChecker>(panda, scene, with),
                     std::make_unique<CollisionChecker>(panda, scene, without)};
        ExpectSameStateAnswers(c, q, "trial " + std::to_string(trial) + (force_fcl ? " fcl" : " fast") +
                                         " padding " + std::to_string(padding));
        if (padding > d) touching_collides += c.scanned->IsValid(q) ? 0 : 1;
      }
    }
  }
  EXPECT_GT(touching_collides, 20) << "too few trials reached the touching case";
}

TEST(SphereBvh, ListsExactlyTheOverlappingBoxesInOrder) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-5.0, 5.0), r(0.0, 0.5);
  for (std::size_t n : {0u, 1u, 7u, 8u, 9u, 100u, 1000u}) {
    std::vector<double> x(n), y(n), z(n), rad(n);
    for (std::size_t i = 0; i < n; ++i) {
      x[i] = u(rng);
      y[i] = u(rng);
      z[i] = u(rng);
      rad[i] = r(rng);
    }
    const detail::SphereBvh bvh(x.data(), y.data(), z.data(), rad.data(), n);
    EXPECT_EQ(bvh.size(), n);
    std::vector<std::uint32_t> got;
    for (int t = 0; t < 200; ++t) {
      detail::Box3 box;
      for (int a = 0; a < 3; ++a) {
        const double c = u(rng), h = 0.1 * std::abs(u(rng));
        box.lo[a] = c - h;
        box.hi[a] = c + h;
      }
      if (t == 0 && n > 0) {  // a box that only touches sphere 0's box
        box.lo[0] = x[0] + rad[0];
        box.hi[0] = box.lo[0] + 1.0;
        box.lo[1] = y[0] - 0.1;
        box.hi[1] = y[0] + 0.1;
        box.lo[2] = z[0] - 0.1;
        box.hi[2] = z[0] + 0.1;
      }
      bvh.Overlapping(box, &got);
      std::vector<std::uint32_t> want;
      for (std::size_t i = 0; i < n; ++i) {
        if (x[i] - rad[i] <= box.hi[0] && box.lo[0] <= x[i] + rad[i] && y[i] - rad[i] <= box.hi[1] &&
            box.lo[1] <= y[i] + rad[i] && z[i] - rad[i] <= box.hi[2] && box.lo[2] <= z[i] + rad[i]) {
          want.push_back(static_cast<std::uint32_t>(i));
        }
      }
      EXPECT_EQ(got, want) << "n " << n << " query " << t;
      if (t == 0 && n > 0) {
        EXPECT_FALSE(got.empty() || got.front() != 0) << "touching boxes overlap";
      }
    }
  }
}

}  // namespace
}  // namespace chasles
