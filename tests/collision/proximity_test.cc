// ObstacleProximity against analytic answers: a sphere link vs a box, a sphere, an occupancy map
// of a box, a mesh; contact; max_distance; link order and obstacle names; threads. And the
// checker's per-group clearance bounds against ObstacleProximity's per-link FCL distances.

#include <cmath>
#include <memory>
#include <random>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include "chasles/collision/collision_checker.h"
#include "chasles/collision/proximity.h"
#include "chasles/robot/error.h"
#include "test_util.h"

namespace chasles {
namespace {

using test::SliderRobot;

Eigen::Isometry3d At(double x, double y, double z) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(x, y, z);
  return t;
}

Eigen::VectorXd Q(double x) { return Eigen::VectorXd::Constant(1, x); }

constexpr double kTol = 1e-9;

void ExpectNear(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double tol) {
  EXPECT_NEAR((a - b).norm(), 0.0, tol) << "got (" << a.transpose() << "), expected (" << b.transpose() << ")";
}

TEST(ProximityTest, SphereLinkToBoxFaceAndEdge) {
  // Sphere r = 0.1 sliding along x; box 0.4 × 0.4 × 0.4 centred at (1, 0, 0): face at x = 0.8.
  auto robot = SliderRobot(Shape::Sphere(0.1));
  auto scene = std::make_shared<Scene>();
  scene->AddObject({"crate", Shape::Box(Eigen::Vector3d(0.4, 0.4, 0.4), At(1.0, 0.0, 0.0))});
  const ObstacleProximity proximity(robot, scene);
  ASSERT_EQ(proximity.links(), std::vector<int>{1});

  const std::vector<LinkProximity> r = proximity.Query(Q(0.2));
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].link, 1);
  EXPECT_EQ(r[0].obstacle, 0);
  EXPECT_EQ(r[0].obstacle_name, "crate");
  EXPECT_NEAR(r[0].distance, 0.8 - 0.2 - 0.1, kTol);
  ExpectNear(r[0].link_point, Eigen::Vector3d(0.3, 0.0, 0.0), kTol);
  ExpectNear(r[0].obstacle_point, Eigen::Vector3d(0.8, 0.0, 0.0), kTol);

  // The sphere offset in y and z on its link: nearest to the box's edge at (0.8, 0.2, z).
  Link base;
  base.name = "base";
  Link mover;
  mover.name = "mover";
  mover.parent_joint = 0;
  mover.collision.push_back(Shape::Sphere(0.1, At(0.0, 0.5, 0.1)));
  Joint j;
  j.name = "slide_x";
  j.type = JointType::kPrismatic;
  j.parent_link = 0;
  j.child_link = 1;
  j.axis = Eigen::Vector3d::UnitX();
  j.limits = {-5.0, 5.0, 1.0, 0.0};
  j.dof = 0;
  const ObstacleProximity offset(RobotModel::FromTree("offset", {base, mover}, {j}), scene);
  const LinkProximity e = offset.Query(Q(0.5))[0];
  // Centre (0.5, 0.5, 0.1); the nearest box point is (0.8, 0.2, 0.1): distance √0.18 − 0.1.
  const Eigen::Vector3d centre(0.5, 0.5, 0.1), box_point(0.8, 0.2, 0.1);
  EXPECT_NEAR(e.distance, std::sqrt(0.18) - 0.1, kTol);
  ExpectNear(e.obstacle_point, box_point, kTol);
  ExpectNear(e.link_point, centre + 0.1 * (box_point - centre).normalized(), kTol);
}

TEST(ProximityTest, SphereLinkToRotatedBox) {
  // A box rotated 45° about z: its corner points at the sphere.
  auto robot = SliderRobot(Shape::Sphere(0.1));
  auto scene = std::make_shared<Scene>();
  Eigen::Isometry3d pose = At(2.0, 0.0, 0.0);
  pose.linear() = Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  scene->AddObject({"diamond", Shape::Box(Eigen::Vector3d(0.5, 0.5, 0.5), pose)});
  const LinkProximity r = ObstacleProximity(robot, scene).Query(Q(0.0))[0];
  const double corner = 2.0 - 0.25 * std::sqrt(2.0);
  EXPECT_NEAR(r.distance, corner - 0.1, 1e-9);
  ExpectNear(r.obstacle_point, Eigen::Vector3d(corner, 0.0, 0.0), 1e-9);
  ExpectNear(r.link_point, Eigen::Vector3d(0.1, 0.0, 0.0), 1e-9);
}

TEST(ProximityTest, SphereLinkToSphereObstacleAndTheNearestOfTwo) {
  auto robot = SliderRobot(Shape::Sphere(0.1));
  auto scene = std::make_shared<Scene>();
  scene->AddObject({"far_ball", Shape::Sphere(0.2, At(3.0, 0.0, 0.0))});
  scene->AddObject({"ball", Shape::Sphere(0.2, At(2.0, 0.3, 0.0))});
  const ObstacleProximity proximity(robot, scene);
  for (const double x : {0.0, 1.0, 1.7}) {
    const LinkProximity r = proximity.Query(Q(x))[0];
    const Eigen::Vector3d c(x, 0.0, 0.0), o(2.0, 0.3, 0.0);
    EXPECT_EQ(r.obstacle_name, "ball") << "x = " << x;
    EXPECT_EQ(r.obstacle, 1);
    EXPECT_NEAR(r.distance, (o - c).norm() - 0.3, kTol);
    ExpectNear(r.link_point, c + 0.1 * (o - c).normalized(), kTol);
    ExpectNear(r.obstacle_point, o + 0.2 * (c - o).normalized(), kTol);
  }
  // Past the near ball, the far one is nearer.
  EXPECT_EQ(proximity.Query(Q(2.9))[0].obstacle_name, "far_ball");
}

TEST(ProximityTest, AnObstacleTheSceneAllowsTheLinkToTouchIsNotSeen) {
  auto robot = SliderRobot(Shape::Sphere(0.1));
  auto scene = std::make_shared<Scene>();
  scene->AddObject({"far_ball", Shape::Sphere(0.2, At(3.0, 0.0, 0.0))});
  scene->AddObject({"ball", Shape::Sphere(0.2, At(2.0, 0.3, 0.0))});
  scene->AllowCollision("mover", "ball");
  scene->AllowCollision("base", "far_ball");  // another link's allowance changes nothing here
  const ObstacleProximity proximity(robot, scene);
  const LinkProximity r = proximity.Query(Q(1.9))[0];
  EXPECT_EQ(r.obstacle_name, "far_ball");
  EXPECT_NEAR(r.distance, 3.0 - 1.9 - 0.3, kTol);
}

TEST(ProximityTest, BeyondMaxDistanceIsNone) {
  auto robot = SliderRobot(Shape::Sphere(0.1));
  auto scene = std::make_shared<Scene>();
  scene->AddObject({"crate", Shape::Box(Eigen::Vector3d(0.4, 0.4, 0.4), At(1.0, 0.0, 0.0))});
  const ObstacleProximity proximity(robot, scene);
  const LinkProximity none = proximity.Query(Q(0.0), 0.5)[0];  // true distance 0.7
  EXPECT_FALSE(none.found());
  EXPECT_EQ(none.obstacle, -1);
  EXPECT_TRUE(none.obstacle_name.empty());
  EXPECT_TRUE(std::isinf(none.distance));
  EXPECT_EQ(none.link, 1);
  const LinkProximity within = proximity.Query(Q(0.0), 0.71)[0];
  ASSERT_TRUE(within.found());
  EXPECT_NEAR(within.distance, 0.7, kTol);
  // An empty scene: none for every link.
  EXPECT_FALSE(ObstacleProximity(robot, nullptr).Query(Q(0.0))[0].found());
}

TEST(ProximityTest, ContactAndOverlapAreZeroWithAContactPoint) {
  // Dimensions exact in binary, so "touching" is exact: sphere r = 0.25; box face at x = 0.75;
  // ball surface at x = -0.75.
  auto robot = SliderRobot(Shape::Sphere(0.25));
  auto scene = std::make_shared<Scene>();
  scene->AddObject({"crate", Shape::Box(Eigen::Vector3d(0.5, 0.5, 0.5), At(1.0, 0.0, 0.0))});
  scene->AddObject({"ball", Shape::Sphere(0.25, At(-1.0, 0.0, 0.0))});
  const ObstacleProximity proximity(robot, scene);
  for (const double x : {0.5, 0.625, 1.0, -0.5, -0.75, -1.0}) {  // touching, overlapping, inside
    const LinkProximity r = proximity.Query(Q(x))[0];
    ASSERT_TRUE(r.found()) << "x = " << x;
    EXPECT_EQ(r.distance, 0.0) << "x = " << x;
    EXPECT_EQ(r.obstacle_name, x > 0 ? "crate" : "ball");
    EXPECT_TRUE(r.link_point.allFinite());
    EXPECT_TRUE(r.obstacle_point.allFinite());
    // The reported point lies in the link sphere (up to rounding).
    EXPECT_LE((r.link_point - Eigen::Vector3d(x, 0, 0)).norm(), 0.25 + 1e-6) << "x = " << x;
  }
  // Just apart: a small positive distance.
  EXPECT_NEAR(proximity.Query(Q(0.4375))[0].distance, 0.0625, kTol);
}

std::shared_ptr<const octomap::OcTree> BoxMap(double resolution, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  auto tree = std::make_shared<octomap::OcTree>(resolution);
  for (double x = lo.x() + resolution / 2; x < hi.x(); x += resolution) {
    for (double y = lo.y() + resolution / 2; y < hi.y(); y += resolution) {
      for (double z = lo.z() + resolution / 2; z < hi.z(); z += resolution) {
        tree->updateNode(octomap::point3d(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)), true);
      }
    }
  }
  return tree;
}

TEST(ProximityTest, SphereLinkToOccupancyMapOfABox) {
  // Voxels of 0.1 m filling [0.6, 1.0] × [-0.2, 0.2] × [-0.2, 0.2], the map placed 1 m up in y and
  // back down (its pose counts).
  auto robot = SliderRobot(Shape::Sphere(0.1));
  auto scene = std::make_shared<Scene>();
  scene->AddObject({"ball", Shape::Sphere(0.2, At(-3.0, 0.0, 0.0))});
  const auto tree = BoxMap(0.1, Eigen::Vector3d(0.6, -1.2, -0.2), Eigen::Vector3d(1.0, -0.8, 0.2));
  scene->AddOccupancyMap({"voxels", tree, At(0.0, 1.0, 0.0)});
  const ObstacleProximity proximity(robot, scene);

  const LinkProximity r = proximity.Query(Q(0.0))[0];
  ASSERT_TRUE(r.found());
  EXPECT_EQ(r.obstacle_name, "voxels");
  EXPECT_EQ(r.obstacle, 1);  // after the one scene object
  EXPECT_NEAR(r.distance, 0.5, 1e-6);  // map boxes are float-rounded
  ExpectNear(r.link_point, Eigen::Vector3d(0.1, 0.0, 0.0), 1e-6);
  EXPECT_NEAR(r.obstacle_point.x(), 0.6, 1e-6);
  EXPECT_NEAR(r.obstacle_point.y(), 0.0, 1e-6);
  EXPECT_NEAR(r.obstacle_point.z(), 0.0, 1e-6);

  // Beyond the box's far side, the other way.
  const LinkProximity back = proximity.Query(Q(1.5))[0];
  EXPECT_NEAR(back.distance, 0.4, 1e-6);
  ExpectNear(back.link_point, Eigen::Vector3d(1.4, 0.0, 0.0), 1e-6);
  ExpectNear(back.obstacle_point, Eigen::Vector3d(1.0, 0.0, 0.0), 1e-6);

  // Inside the voxels: contact.
  const LinkProximity inside = proximity.Query(Q(0.8))[0];
  EXPECT_EQ(inside.distance, 0.0);
  EXPECT_TRUE(inside.link_point.allFinite());
  // Beyond max_distance: none (and the octree traversal is pruned by it).
  EXPECT_FALSE(proximity.Query(Q(0.0), 0.45)[0].found());
}

/// A 0.4 m cube as a triangle mesh centred on its origin.
Shape CubeMesh(const Eigen::Isometry3d& pose) { return test::CubeMeshShape(0.2, pose); }

TEST(ProximityTest, MeshObstacleMatchesTheBox) {
  // The 0.4 m crate as a mesh: same distance and points as the primitive (world frame).
  const Shape shape = CubeMesh(At(1.0, 0.1, 0.0));
  auto scene = std::make_shared<Scene>();
  scene->AddObject({"crate_mesh", shape});
  const LinkProximity r = ObstacleProximity(SliderRobot(Shape::Sphere(0.1)), scene).Query(Q(0.2))[0];
  EXPECT_NEAR(r.distance, 0.5, 1e-6);
  ExpectNear(r.link_point, Eigen::Vector3d(0.3, 0.0, 0.0), 1e-6);
  ExpectNear(r.obstacle_point, Eigen::Vector3d(0.8, 0.0, 0.0), 1e-6);
}

TEST(ProximityTest, MeshLinkToSphereObstacle) {
  // The cube as the link's shape, offset on the link; a ball ahead of it.
  auto robot = SliderRobot(CubeMesh(At(0.0, 0.0, 0.5)));
  auto scene = std::make_shared<Scene>();
  scene->AddObject({"ball", Shape::Sphere(0.1, At(1.0, 0.0, 0.5))});
  const LinkProximity r = ObstacleProximity(robot, scene).Query(Q(-0.3))[0];
  EXPECT_NEAR(r.distance, 1.0 - (-0.3 + 0.2) - 0.1, 1e-6);
  ExpectNear(r.link_point, Eigen::Vector3d(-0.1, 0.0, 0.5), 1e-6);
  ExpectNear(r.obstacle_point, Eigen::Vector3d(0.9, 0.0, 0.5), 1e-6);
}

// Two sliders stacked: link "a" moves along x, link "b" (child) along y; the base has no geometry.
std::shared_ptr<const RobotModel> TwoLinkSlider() {
  Link base, a, b;
  base.name = "base";
  a.name = "a";
  a.parent_joint = 0;
  a.collision.push_back(Shape::Sphere(0.1));
  b.name = "b";
  b.parent_joint = 1;
  b.collision.push_back(Shape::Sphere(0.05, At(0.0, 0.0, 1.0)));
  Joint jx, jy;
  jx.name = "x";
  jx.type = JointType::kPrismatic;
  jx.parent_link = 0;
  jx.child_link = 1;
  jx.axis = Eigen::Vector3d::UnitX();
  jx.limits = {-5.0, 5.0, 1.0, 0.0};
  jx.dof = 0;
  jy = jx;
  jy.name = "y";
  jy.parent_link = 1;
  jy.child_link = 2;
  jy.axis = Eigen::Vector3d::UnitY();
  jy.dof = 1;
  return RobotModel::FromTree("xy", {base, a, b}, {jx, jy});
}

TEST(ProximityTest, OneEntryPerLinkWithGeometryInLinkOrder) {
  auto scene = std::make_shared<Scene>();
  scene->AddObject({"low", Shape::Sphere(0.1, At(0.0, 0.0, -1.0))});
  scene->AddObject({"high", Shape::Sphere(0.1, At(0.0, 0.0, 2.0))});
  const ObstacleProximity proximity(TwoLinkSlider(), scene);
  ASSERT_EQ(proximity.links(), (std::vector<int>{1, 2}));
  const std::vector<LinkProximity> r = proximity.Query(Eigen::Vector2d(0.0, 0.0));
  ASSERT_EQ(r.size(), 2u);
  EXPECT_EQ(r[0].link, 1);
  EXPECT_EQ(r[0].obstacle_name, "low");
  EXPECT_NEAR(r[0].distance, 0.8, kTol);
  EXPECT_EQ(r[1].link, 2);
  EXPECT_EQ(r[1].obstacle_name, "high");
  EXPECT_NEAR(r[1].distance, 0.85, kTol);
  ExpectNear(r[1].link_point, Eigen::Vector3d(0.0, 0.0, 1.05), kTol);
  ExpectNear(r[1].obstacle_point, Eigen::Vector3d(0.0, 0.0, 1.9), kTol);
  // Moving y moves only link b.
  const std::vector<LinkProximity> moved = proximity.Query(Eigen::Vector2d(0.0, 0.5));
  EXPECT_NEAR(moved[0].distance, 0.8, kTol);
  EXPECT_NEAR(moved[1].distance, std::hypot(0.5, 1.0) - 0.15, kTol);
}

TEST(ProximityTest, BuiltFromACheckerAndQueriedFromThreads) {
  auto robot = TwoLinkSlider();
  auto scene = std::make_shared<Scene>();
  scene->AddObject({"crate", Shape::Box(Eigen::Vector3d(0.4, 0.4, 0.4), At(1.0, 0.0, 0.0))});
  scene->AddOccupancyMap({"voxels", BoxMap(0.1, Eigen::Vector3d(-1.0, -0.2, 0.8), Eigen::Vector3d(-0.6, 0.2, 1.2)),
                          Eigen::Isometry3d::Identity()});
  auto checker = std::make_shared<const CollisionChecker>(robot, scene);
  const ObstacleProximity proximity(checker);
  std::vector<Eigen::VectorXd> qs;
  std::vector<std::vector<LinkProximity>> expected;
  for (int i = 0; i < 40; ++i) {
    qs.push_back(Eigen::Vector2d(-1.5 + 0.075 * i, 0.02 * i - 0.4));
    expected.push_back(proximity.Query(qs.back(), 2.0));
  }
  std::vector<int> mismatches(4, 0);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      std::vector<LinkProximity> out;
      for (int rep = 0; rep < 5; ++rep) {
        for (std::size_t i = 0; i < qs.size(); ++i) {
          proximity.Query(qs[i], 2.0, &out);
          for (std::size_t k = 0; k < out.size(); ++k) {
            if (out[k].distance != expected[i][k].distance || out[k].obstacle != expected[i][k].obstacle ||
                out[k].link_point != expected[i][k].link_point) {
              ++mismatches[t];
            }
          }
        }
      }
    });
  }
  for (std::thread& t : threads) t.join();
  EXPECT_EQ(mismatches, std::vector<int>(4, 0));
  // The query agrees with the checker: a zero distance exactly where the checker collides.
  for (const Eigen::VectorXd& q : qs) {
    double nearest = std::numeric_limits<double>::infinity();
    for (const LinkProximity& r : proximity.Query(q)) nearest = std::min(nearest, r.distance);
    EXPECT_NEAR(nearest, checker->Clearance(q), 1e-6) << q.transpose();
  }
}

// CollisionChecker::Clearance(q, &groups): each clearance group's value is a lower bound on its
// link's FCL distance to the scene (ObstacleProximity, a second implementation), the least of
// them is Clearance(q), and the link nearest the scene gets its distance. Panda in the shelf
// (primitives), in 300 random boxes (the prims' broad phase) and in the shelf's occupancy map.
TEST(ProximityTest, ClearanceGroupsBoundEachLinksFclDistance) {
  auto panda = test::LoadRobot("panda");
  auto clutter = std::make_shared<Scene>();
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> xy(-1.2, 1.2), z(0.0, 1.4), size(0.02, 0.1);
  for (int i = 0; i < 300; ++i) {
    const Eigen::Vector3d c(xy(rng), xy(rng), z(rng));
    if (c.head<2>().norm() < 0.35) continue;  // leave the robot's column free
    clutter->AddObject({"box" + std::to_string(i),
                        Shape::Box(Eigen::Vector3d(size(rng), size(rng), size(rng)), At(c.x(), c.y(), c.z()))});
  }
  const std::vector<std::pair<const char*, std::shared_ptr<Scene>>> scenes = {
      {"shelf", test::LoadScene("scenes/shelf.json")},
      {"clutter", clutter},
      {"shelf_octomap", test::LoadScene("scenes/shelf_octomap.json")}};
  for (const auto& [name, scene] : scenes) {
    const CollisionChecker checker(panda, scene);
    ASSERT_TRUE(checker.uses_fast_path()) << name;
    const ObstacleProximity proximity(panda, scene);
    const std::vector<int> group_link = checker.clearance_group_links();
    ASSERT_EQ(static_cast<int>(group_link.size()), checker.num_clearance_groups());
    Eigen::VectorXd groups;
    int tight = 0, states = 0;
    for (int trial = 0; trial < 150; ++trial) {
      const Eigen::VectorXd q = test::RandomConfig(*panda, rng);
      const double clearance = checker.Clearance(q, &groups);
      ASSERT_EQ(groups.size(), checker.num_clearance_groups());
      EXPECT_EQ(groups.minCoeff(), clearance) << name << " trial " << trial;
      EXPECT_EQ(clearance, checker.Clearance(q)) << name << " trial " << trial;
      if (clearance <= 0.0) continue;
      ++states;
      double nearest = std::numeric_limits<double>::infinity();
      for (const LinkProximity& link : proximity.Query(q)) {
        double least = std::numeric_limits<double>::infinity();  // over the link's groups
        for (std::size_t g = 0; g < group_link.size(); ++g) {
          if (group_link[g] == link.link) least = std::min(least, groups[static_cast<Eigen::Index>(g)]);
        }
        EXPECT_LE(least, link.distance + 1e-9) << name << " trial " << trial << " link " << link.link;
        nearest = std::min(nearest, link.distance);
      }
      EXPECT_NEAR(clearance, nearest, 1e-6) << name << " trial " << trial;
      // Groups far from the scene may keep only a bounding-sphere bound, but some groups other
      // than the nearest are bounded above the clearance (else there is no gain over it).
      int above = 0;
      for (Eigen::Index g = 0; g < groups.size(); ++g) above += groups[g] > clearance + 1e-3 ? 1 : 0;
      if (above > 0) ++tight;
    }
    EXPECT_GT(states, 50) << name;
    if (scene->occupancy_maps().empty()) {
      EXPECT_GT(tight, states / 2) << name;
    }
  }
}

TEST(ProximityTest, BadArgumentsAreRejected) {
  const ObstacleProximity proximity(SliderRobot(Shape::Sphere(0.1)), nullptr);
  EXPECT_THROW(proximity.Query(Eigen::Vector2d(0, 0)), Error);
  EXPECT_THROW(proximity.Query(Q(0.0), 0.0), Error);
  EXPECT_THROW(proximity.Query(Q(0.0), std::nan("")), Error);
  EXPECT_THROW(ObstacleProximity(std::shared_ptr<const CollisionChecker>()), Error);
}

}  // namespace
}  // namespace chasles
