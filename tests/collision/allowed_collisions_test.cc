// Scene allowed collisions (Scene::allowed_collisions, MoveIt's allowed collision matrix that
// comes with a scene): a link may touch the objects, maps and links it is allowed to, on the fast
// sphere path and the FCL path alike, in IsValid/Check, IsMotionValid, IsMotionCertified and
// Clearance; every other link still collides; names that do not resolve are named errors.

#include <functional>
#include <limits>
#include <memory>
#include <random>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include "chasles/collision/collision_checker.h"
#include "chasles/collision/proximity.h"
#include "chasles/robot/error.h"
#include "test_util.h"

namespace chasles {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

Eigen::Isometry3d At(double x, double y, double z) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() << x, y, z;
  return t;
}

/// Two links, "left" and "right", sliding along the world x axis on the same line (siblings
/// under "base", so the robot's own ACM does not allow them to touch). Each carries a ball of
/// radius 0.1 at its origin and one of 0.06 at z = 0.12: at x = q it spans x ∈ [q − 0.1, q + 0.1].
std::shared_ptr<const RobotModel> TwinSliders() {
  Link base;
  base.name = "base";
  const auto slider = [](const char* name, int joint) {
    Link l;
    l.name = name;
    l.parent_joint = joint;
    l.collision = {Shape::Sphere(0.1), Shape::Sphere(0.06, At(0, 0, 0.12))};
    return l;
  };
  Joint left;
  left.name = "slide_left";
  left.type = JointType::kPrismatic;
  left.parent_link = 0;
  left.child_link = 1;
  left.axis = Eigen::Vector3d::UnitX();
  left.limits = {-5.0, 5.0, 1.0, 0.0};
  left.dof = 0;
  Joint right = left;
  right.name = "slide_right";
  right.child_link = 2;
  right.dof = 1;
  return RobotModel::FromTree("twin_sliders", {base, slider("left", 0), slider("right", 1)}, {left, right});
}

Eigen::VectorXd Q(double left, double right) {
  Eigen::VectorXd q(2);
  q << left, right;
  return q;
}

/// A 0.2 m (x) by 1 m by 1 m slab centred at x: a ball centre touches it from x − 0.2 on.
SceneObject Slab(const std::string& name, double x) { return {name, Shape::Box({0.2, 1.0, 1.0}, At(x, 0, 0))}; }

/// A 0.2 m cube as a triangle mesh centred at x.
SceneObject CubeMesh(const std::string& name, double x) { return {name, test::CubeMeshShape(0.1, At(x, 0, 0))}; }

/// An occupancy map whose occupied voxels fill x ∈ [1, 1.1], y ∈ [−0.1, 0.1], z ∈ [−0.1, 0.2]:
/// 0.1 m voxels, or with `far` 1 cm voxels plus one more 7 m away, so that the map is too large
/// to grid and stays on FCL's octree traversal on the fast path too.
OccupancyMap Wall(const std::string& name, bool far) {
  const double res = far ? 0.01 : 0.1;
  const int n = far ? 10 : 1;  // voxels per 0.1 m
  auto tree = std::make_shared<octomap::OcTree>(res);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < 2 * n; ++j) {
      for (int k = 0; k < 3 * n; ++k) {
        const double x = 1.0 + (i + 0.5) * res, y = -0.1 + (j + 0.5) * res, z = -0.1 + (k + 0.5) * res;
        tree->setNodeValue(octomap::point3d(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)), 2.0f);
      }
    }
  }
  if (far) tree->setNodeValue(octomap::point3d(7.005f, 7.005f, 7.005f), 2.0f);
  return {name, tree, Eigen::Isometry3d::Identity()};
}

CollisionOptions Options(bool force_fcl) {
  CollisionOptions options;
  options.force_fcl = force_fcl;
  return options;
}

const char* PathName(bool force_fcl) { return force_fcl ? "FCL path" : "fast path"; }

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument) << e.what();
    return e.what();
  }
  ADD_FAILURE() << "no error thrown";
  return "";
}

TEST(AllowedCollisions, OnlyTheNamedLinkMayTouchABox) {
  auto robot = TwinSliders();
  auto plain = std::make_shared<Scene>();
  plain->AddObject(Slab("target_box", 2.0));
  plain->AddObject(Slab("wall", 4.0));
  auto allowed = std::make_shared<Scene>(*plain);
  allowed->AllowCollision("left", "target_box");
  for (bool force_fcl : {false, true}) {
    SCOPED_TRACE(PathName(force_fcl));
    const CollisionChecker without(robot, plain, Options(force_fcl));
    const CollisionChecker with(robot, allowed, Options(force_fcl));
    ASSERT_EQ(with.uses_fast_path(), !force_fcl);
    // left inside the box: a collision, unless allowed.
    EXPECT_FALSE(without.IsValid(Q(2.0, -3.0)));
    const CollisionResult contact = without.Check(Q(2.0, -3.0));
    EXPECT_EQ(contact.link_a, "left");
    EXPECT_EQ(contact.other, "target_box");
    EXPECT_TRUE(with.IsValid(Q(2.0, -3.0)));
    EXPECT_TRUE(with.IsValid(Q(1.8, -3.0)));  // touching the face
    EXPECT_FALSE(with.Check(Q(2.0, -3.0)).in_collision);
    // right in the same box still collides.
    EXPECT_FALSE(with.IsValid(Q(-3.0, 2.0)));
    const CollisionResult right = with.Check(Q(-3.0, 2.0));
    EXPECT_TRUE(right.in_collision);
    EXPECT_FALSE(right.self_collision);
    EXPECT_EQ(right.link_a, "right");
    EXPECT_EQ(right.other, "target_box");
    // left against the wall (not allowed) still collides; so do left and right in each other.
    EXPECT_FALSE(with.IsValid(Q(3.9, -3.0)));
    EXPECT_EQ(with.Check(Q(3.9, -3.0)).other, "wall");
    EXPECT_TRUE(with.Check(Q(0.0, 0.05)).self_collision);
    // Discrete motions: left through its box passes, right through it does not.
    EXPECT_FALSE(without.IsMotionValid(Q(0.0, -3.0), Q(3.0, -3.0), 0.01));
    EXPECT_TRUE(with.IsMotionValid(Q(0.0, -3.0), Q(3.0, -3.0), 0.01));
    EXPECT_FALSE(with.IsMotionValid(Q(0.0, -3.0), Q(4.0, -3.0), 0.01));
    EXPECT_FALSE(with.IsMotionValid(Q(-3.0, 0.0), Q(-3.0, 3.0), 0.01));
  }
}

TEST(AllowedCollisions, PandaAtTheTableFastAndFclPathsAgreeWithAPerLinkReference) {
  // The hand may touch the table top: a configuration is valid iff it is valid without the
  // table top and no other link touches the table top (per-link distances by ObstacleProximity).
  auto panda = test::LoadRobot("panda");
  auto table = test::LoadScene("scenes/table.json");
  const std::set<std::string> hand = {"panda_hand", "panda_link7"};
  auto allowed = std::make_shared<Scene>(*table);
  for (const std::string& link : hand) allowed->AllowCollision(link, "table_top");
  auto without_top = std::make_shared<Scene>();
  auto only_top = std::make_shared<Scene>();
  for (const SceneObject& o : table->objects()) (o.name == "table_top" ? only_top : without_top)->AddObject(o);
  ASSERT_EQ(only_top->objects().size(), 1u);

  const CollisionChecker fast(panda, allowed);
  const CollisionChecker fcl(panda, allowed, Options(true));
  const CollisionChecker plain(panda, table);
  const CollisionChecker reference_rest(panda, without_top);
  const ObstacleProximity top(panda, only_top);
  ASSERT_TRUE(fast.uses_fast_path());

  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> jitter(-0.4, 0.4);
  Eigen::VectorXd on_table(7);
  on_table << 0.0, 1.2, 0.0, -0.5, 0.0, 1.5, 0.785;  // the hand rests on the table top
  int valid_only_when_allowed = 0, hand_on_table = 0, others_on_table = 0;
  for (int i = 0; i < 2000; ++i) {
    Eigen::VectorXd q = test::RandomConfig(*panda, rng);
    if (i % 4 != 0) {  // mostly near the table top
      for (int j = 0; j < 7; ++j) q[j] = on_table[j] + jitter(rng);
      q = q.cwiseMax(panda->lower_limits()).cwiseMin(panda->upper_limits());
    }
    bool others_clear = true, hand_touches = false;
    for (const LinkProximity& p : top.Query(q)) {
      if (p.distance > 0.0) continue;
      if (hand.count(panda->links()[p.link].name) > 0) {
        hand_touches = true;
      } else {
        others_clear = false;
      }
    }
    const bool expected = others_clear && reference_rest.IsValid(q);
    ASSERT_EQ(fast.IsValid(q), expected) << "configuration " << i;
    ASSERT_EQ(fcl.IsValid(q), expected) << "configuration " << i;
    const CollisionResult a = fast.Check(q), b = fcl.Check(q);
    ASSERT_EQ(a.in_collision, !expected) << "configuration " << i;
    ASSERT_EQ(b.in_collision, !expected) << "configuration " << i;
    for (const CollisionResult* r : {&a, &b}) {
      if (r->other == "table_top") {
        EXPECT_EQ(hand.count(r->link_a), 0u) << r->link_a << ", configuration " << i;
      }
    }
    if (expected && !plain.IsValid(q)) ++valid_only_when_allowed;
    if (expected && hand_touches) ++hand_on_table;
    if (!others_clear) ++others_on_table;
  }
  EXPECT_GT(valid_only_when_allowed, 50);
  EXPECT_GT(hand_on_table, 50);
  EXPECT_GT(others_on_table, 50);
}

TEST(AllowedCollisions, OccupancyMapsGriddedAndOnFcl) {
  auto robot = TwinSliders();
  for (bool far : {false, true}) {
    auto plain = std::make_shared<Scene>();
    plain->AddOccupancyMap(Wall("cloud", far));
    auto allowed = std::make_shared<Scene>(*plain);
    allowed->AllowCollision("left", "cloud");
    for (bool force_fcl : {false, true}) {
      SCOPED_TRACE(std::string(PathName(force_fcl)) + (far ? ", map too large to grid" : ", gridded map"));
      const CollisionChecker without(robot, plain, Options(force_fcl));
      const CollisionChecker with(robot, allowed, Options(force_fcl));
      EXPECT_EQ(with.num_gridded_occupancy_maps(), force_fcl || far ? 0 : 1);
      EXPECT_FALSE(without.IsValid(Q(1.05, -3.0)));
      EXPECT_EQ(without.Check(Q(1.05, -3.0)).other, "cloud");
      EXPECT_TRUE(with.IsValid(Q(1.05, -3.0)));
      EXPECT_FALSE(with.IsValid(Q(-3.0, 1.05)));
      const CollisionResult right = with.Check(Q(-3.0, 1.05));
      EXPECT_EQ(right.link_a, "right");
      EXPECT_EQ(right.other, "cloud");
      EXPECT_TRUE(with.IsMotionValid(Q(0.0, -3.0), Q(2.0, -3.0), 0.01));
      EXPECT_FALSE(with.IsMotionValid(Q(-3.0, 0.0), Q(-3.0, 2.0), 0.01));
    }
  }
}

TEST(AllowedCollisions, MeshObject) {
  auto robot = TwinSliders();
  auto plain = std::make_shared<Scene>();
  plain->AddObject(CubeMesh("crate", 1.0));
  auto allowed = std::make_shared<Scene>(*plain);
  allowed->AllowCollision("right", "crate");
  for (bool force_fcl : {false, true}) {
    SCOPED_TRACE(PathName(force_fcl));
    const CollisionChecker without(robot, plain, Options(force_fcl));
    const CollisionChecker with(robot, allowed, Options(force_fcl));
    EXPECT_FALSE(with.certifies_motion());  // a mesh some link may touch stays on FCL
    EXPECT_FALSE(without.IsValid(Q(-3.0, 1.0)));
    EXPECT_TRUE(with.IsValid(Q(-3.0, 1.0)));
    EXPECT_FALSE(with.IsValid(Q(1.0, -3.0)));
    EXPECT_EQ(with.Check(Q(1.0, -3.0)).link_a, "left");
    EXPECT_EQ(with.Check(Q(1.0, -3.0)).other, "crate");
    EXPECT_TRUE(with.IsMotionCertified(Q(-3.0, 0.0), Q(-3.0, 2.0)));  // the discrete fallback
    EXPECT_FALSE(with.IsMotionCertified(Q(0.0, -3.0), Q(2.0, -3.0)));
  }
}

TEST(AllowedCollisions, CertifiedMotionPassesAllowedObstaclesAndStopsAtOthers) {
  auto robot = TwinSliders();
  // left may touch the slab at x ∈ [0.9, 1.1] and the map at x ∈ [1, 1.1]; the wall at
  // x ∈ [2.9, 3.1] is an obstacle for both.
  auto walls_only = std::make_shared<Scene>();
  walls_only->AddObject(Slab("wall", 3.0));
  auto scene = std::make_shared<Scene>();
  scene->AddObject(Slab("target_box", 1.0));
  scene->AddObject(Slab("wall", 3.0));
  scene->AddOccupancyMap(Wall("cloud", false));
  scene->AllowCollision("left", "target_box");
  scene->AllowCollision("left", "cloud");
  const CollisionChecker checker(robot, scene);
  const CollisionChecker reference(robot, walls_only);
  ASSERT_TRUE(checker.certifies_motion());
  EXPECT_TRUE(checker.IsMotionCertified(Q(0.0, -3.0), Q(2.0, -3.0)));
  EXPECT_TRUE(checker.IsMotionCertified(Q(2.0, -3.0), Q(0.0, -3.0)));
  EXPECT_TRUE(checker.IsMotionCertified(Q(1.0, -3.0), Q(2.7, -3.0)));  // starting inside the box
  EXPECT_FALSE(checker.IsMotionCertified(Q(0.0, -3.0), Q(2.9, -3.0)));  // b touches the wall
  EXPECT_FALSE(checker.IsMotionCertified(Q(0.0, -3.0), Q(4.0, -3.0)));  // through the wall
  EXPECT_FALSE(checker.IsMotionCertified(Q(-3.0, 0.0), Q(-3.0, 2.0)));  // right may not
  // The allowed obstacles do not shorten the advancement: the same states as without them
  // (right stands still, so the obstacles it may not touch do not shorten it either).
  for (const auto& [a, b] : {std::make_pair(Q(0.0, -3.0), Q(2.5, -3.0)), std::make_pair(Q(-1.0, -4.0), Q(2.7, -4.0))}) {
    CheckCounters with_counters, reference_counters;
    EXPECT_EQ(checker.IsMotionCertified(a, b, &with_counters), reference.IsMotionCertified(a, b, &reference_counters));
    EXPECT_EQ(with_counters.state_checks, reference_counters.state_checks);
  }
}

TEST(AllowedCollisions, ObstacleEveryLinkMayTouchIsLeftOut) {
  auto robot = TwinSliders();
  auto scene = std::make_shared<Scene>();
  scene->AddObject(CubeMesh("crate", 1.0));
  scene->AddOccupancyMap(Wall("cloud", false));
  scene->AddObject(Slab("wall", 3.0));
  for (const char* link : {"left", "right"}) {
    scene->AllowCollision(link, "crate");
    scene->AllowCollision(link, "cloud");
  }
  for (bool force_fcl : {false, true}) {
    SCOPED_TRACE(PathName(force_fcl));
    const CollisionChecker checker(robot, scene, Options(force_fcl));
    EXPECT_EQ(checker.certifies_motion(), !force_fcl);  // no mesh left for FCL
    EXPECT_EQ(checker.num_gridded_occupancy_maps(), 0);
    EXPECT_TRUE(checker.IsValid(Q(1.0, -3.0)));
    EXPECT_TRUE(checker.IsValid(Q(-3.0, 1.05)));
    EXPECT_FALSE(checker.IsValid(Q(-3.0, 3.0)));
    EXPECT_NEAR(checker.Clearance(Q(1.0, 1.5)), 1.3, 1e-9);  // right to the wall: 2.9 − 1.6
  }
}

TEST(AllowedCollisions, LinkPairFromTheSceneDisablesASelfCollision) {
  auto robot = TwinSliders();
  auto plain = std::make_shared<Scene>();
  plain->AddObject(Slab("wall", 3.0));
  auto allowed = std::make_shared<Scene>(*plain);
  allowed->AllowCollision("right", "left");
  for (bool force_fcl : {false, true}) {
    SCOPED_TRACE(PathName(force_fcl));
    const CollisionChecker without(robot, plain, Options(force_fcl));
    const CollisionChecker with(robot, allowed, Options(force_fcl));
    const CollisionResult self = without.Check(Q(0.5, 0.6));
    EXPECT_TRUE(self.self_collision);
    EXPECT_TRUE(with.IsValid(Q(0.5, 0.6)));
    EXPECT_TRUE(with.IsValid(Q(0.5, 0.5)));
    EXPECT_FALSE(with.IsValid(Q(0.5, 2.9)));  // the wall is still there
    // Crossing each other.
    EXPECT_FALSE(without.IsMotionValid(Q(-1.0, 1.0), Q(1.0, -1.0), 0.01));
    EXPECT_TRUE(with.IsMotionValid(Q(-1.0, 1.0), Q(1.0, -1.0), 0.01));
    EXPECT_FALSE(without.IsMotionCertified(Q(-1.0, 1.0), Q(1.0, -1.0)));
    EXPECT_TRUE(with.IsMotionCertified(Q(-1.0, 1.0), Q(1.0, -1.0)));
    EXPECT_EQ(with.certifies_motion(), !force_fcl);
  }
  // The robot's own ACM is unchanged.
  EXPECT_FALSE(robot->allowed_collisions().IsAllowed(1, 2));
}

TEST(AllowedCollisions, ClearanceIgnoresAllowedPairs) {
  auto robot = TwinSliders();
  auto plain = std::make_shared<Scene>();
  plain->AddObject(Slab("target_box", 2.0));
  plain->AddObject(CubeMesh("crate", -2.0));
  auto allowed = std::make_shared<Scene>(*plain);
  allowed->AllowCollision("left", "target_box");
  allowed->AllowCollision("right", "crate");
  for (bool force_fcl : {false, true}) {
    SCOPED_TRACE(PathName(force_fcl));
    const CollisionChecker without(robot, plain, Options(force_fcl));
    const CollisionChecker with(robot, allowed, Options(force_fcl));
    constexpr double kTol = 1e-9;
    // Balls span x ∈ [q − 0.1, q + 0.1]; the box x ∈ [1.9, 2.1], the crate x ∈ [−2.1, −1.9].
    // left at 1.5 is 0.3 from the box, right at −1.5 0.3 from the crate.
    EXPECT_NEAR(without.Clearance(Q(1.5, -1.5)), 0.3, kTol);
    // With the allowances: left is 3.3 from the crate (1.4 + 1.9), right 3.3 from the box.
    EXPECT_NEAR(with.Clearance(Q(1.5, -1.5)), 3.3, kTol);
    // In contact with what it may touch: the clearance is to the other pairs.
    EXPECT_NEAR(with.Clearance(Q(2.0, -1.5)), 3.3, kTol);  // right (−1.4) to the box (1.9)
    EXPECT_EQ(without.Clearance(Q(2.0, -1.5)), 0.0);
    // Both in contact with their own obstacle and nothing else: no pair is left.
    auto lone = std::make_shared<Scene>();
    lone->AddObject(Slab("target_box", 2.0));
    lone->AllowCollision("left", "target_box");
    const CollisionChecker only(robot, lone, Options(force_fcl));
    EXPECT_NEAR(only.Clearance(Q(2.0, -1.0)), 2.8, kTol);  // right: 1.9 − (−0.9)
    auto both = std::make_shared<Scene>(*lone);
    both->AllowCollision("right", "target_box");
    EXPECT_EQ(CollisionChecker(robot, both, Options(force_fcl)).Clearance(Q(2.0, 2.0)), kInf);
  }
}

TEST(AllowedCollisions, NamesThatDoNotResolveAreNamedErrors) {
  auto robot = TwinSliders();
  auto scene = std::make_shared<Scene>();
  scene->AddObject(Slab("target_box", 2.0));
  scene->AddOccupancyMap(Wall("cloud", false));
  const auto build = [&](const std::vector<std::pair<std::string, std::string>>& pairs) {
    auto s = std::make_shared<Scene>(*scene);
    for (const auto& [a, b] : pairs) s->AllowCollision(a, b);
    return ErrorOf([&] { CollisionChecker checker(robot, s); });
  };
  std::string e = build({{"left", "target_box"}, {"hand", "target_box"}});
  EXPECT_NE(e.find("scene.allowed_collisions[1].link1 = 'hand' is not a link of robot 'twin_sliders' "
                   "(links: base, left, right)"),
            std::string::npos)
      << e;
  e = build({{"left", "cloud"}, {"left", "right"}, {"right", "nope"}});
  EXPECT_NE(e.find("scene.allowed_collisions[2].link2 = 'nope' is neither a link of robot 'twin_sliders' nor "
                   "an object or OctoMap of the scene"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("scene objects: target_box; OctoMaps: cloud"), std::string::npos) << e;
  // The pair the wrong way round: link1 must be the robot link.
  e = build({{"target_box", "left"}});
  EXPECT_NE(e.find("scene.allowed_collisions[0].link1 = 'target_box' is not a link of robot 'twin_sliders'"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("link1 must be the robot link"), std::string::npos) << e;
  // An object of another scene is not an object of this one.
  e = build({{"left", "wall"}});
  EXPECT_NE(e.find("scene.allowed_collisions[0].link2 = 'wall'"), std::string::npos) << e;
  // The scene itself only rejects empty names.
  Scene s;
  e = ErrorOf([&] { s.AllowCollision("", "target_box"); });
  EXPECT_EQ(e, "scene.allowed_collisions[0].link1 is empty: it must name a robot link");
  s.AllowCollision("anything", "goes");
  e = ErrorOf([&] { s.AllowCollision("left", "", "scene.allowed_collisions[7]"); });
  EXPECT_NE(e.find("scene.allowed_collisions[7].link2 is empty"), std::string::npos) << e;
  ASSERT_EQ(s.allowed_collisions().size(), 1u);
  EXPECT_EQ(s.allowed_collisions()[0].link, "anything");
  EXPECT_EQ(s.allowed_collisions()[0].other, "goes");
}

}  // namespace
}  // namespace chasles
