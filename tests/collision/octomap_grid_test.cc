// The fast path's occupancy-map test (a voxel bit grid built at construction) must give the same
// answers as FCL's fcl::OcTree traversal (force_fcl): which configurations are valid and which
// map is hit, on the example shelf map, on posed maps, on hand-built trees with pruned leaves
// and nodes between FCL's free and occupied thresholds, and at exact contact with a voxel face,
// edge and corner.

#include <cmath>
#include <iostream>
#include <random>

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include "chasles/collision/collision_checker.h"
#include "test_util.h"

namespace chasles {
namespace {

int NumSamples() {
  const char* env = std::getenv("CHASLES_TEST_SAMPLES");
  return env != nullptr ? std::atoi(env) : 5000;
}

/// A free-flying ball: three prismatic joints (x, y, z, in that order, limits ±20 m) carrying one
/// sphere, so q is the sphere centre in the world.
std::shared_ptr<const RobotModel> BallRobot(double radius) {
  std::vector<Link> links(4);
  links[0].name = "base";
  links[1].name = "slide_x";
  links[2].name = "slide_y";
  links[3].name = "ball";
  links[3].collision.push_back(Shape::Sphere(radius, Eigen::Isometry3d::Identity()));
  std::vector<Joint> joints(3);
  const Eigen::Vector3d axes[3] = {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ()};
  for (int i = 0; i < 3; ++i) {
    links[i + 1].parent_joint = i;
    joints[i].name = std::string("joint_") + "xyz"[i];
    joints[i].type = JointType::kPrismatic;
    joints[i].parent_link = i;
    joints[i].child_link = i + 1;
    joints[i].axis = axes[i];
    joints[i].limits = {-20.0, 20.0, 1.0, 0.0};
    joints[i].dof = i;
  }
  return RobotModel::FromTree("ball", links, joints);
}

Eigen::VectorXd At(double x, double y, double z) { return Eigen::Vector3d(x, y, z); }

std::shared_ptr<const octomap::OcTree> ShelfTree() {
  auto scene = test::LoadScene("scenes/shelf_octomap.json");
  return scene->occupancy_maps().at(0).tree;
}

Eigen::Isometry3d SomePose() {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::AngleAxisd(0.45, Eigen::Vector3d(0.2, -0.3, 1.0).normalized()).toRotationMatrix();
  pose.translation() << 0.07, -0.12, 0.04;
  return pose;
}

struct Agreement {
  int samples = 0;
  int valid = 0;
  int disagreements = 0;
  int map_contacts = 0;  ///< samples whose first contact is with a map
};

/// Compares the fast checker with the forced-FCL one at every q: IsValid, and the first contact
/// (in collision, self or not, and for a map contact which link and which map).
template <typename Sampler>
Agreement Compare(const std::shared_ptr<const RobotModel>& robot, const std::shared_ptr<const Scene>& scene,
                  int n, Sampler sample, double padding = 0.0) {
  CollisionOptions fast_options, fcl_options;
  fast_options.padding = fcl_options.padding = padding;
  fcl_options.force_fcl = true;
  const CollisionChecker fast(robot, scene, fast_options);
  const CollisionChecker fcl(robot, scene, fcl_options);
  EXPECT_TRUE(fast.uses_fast_path());
  EXPECT_EQ(fast.num_gridded_occupancy_maps(), static_cast<int>(scene->occupancy_maps().size()));
  Agreement result;
  for (int i = 0; i < n; ++i) {
    const Eigen::VectorXd q = sample();
    const bool a = fast.IsValid(q);
    const bool b = fcl.IsValid(q);
    const CollisionResult ca = fast.Check(q);
    const CollisionResult cb = fcl.Check(q);
    // Both paths check the maps (in scene order, links in order) before self collision, so a
    // map contact names the same link and map. Which self pair is named first depends on each
    // path's pair order (not on the maps), so only "self" is compared then.
    const bool same = a == b && ca.in_collision == cb.in_collision && ca.self_collision == cb.self_collision &&
                      (ca.self_collision || (ca.link_a == cb.link_a && ca.other == cb.other));
    if (!same) {
      ++result.disagreements;
      ADD_FAILURE() << "sample " << i << " q = " << q.transpose() << ": fast " << a << " " << ca.link_a << "/"
                    << ca.other << ", fcl " << b << " " << cb.link_a << "/" << cb.other
                    << ", fcl clearance " << fcl.Clearance(q);
    }
    ++result.samples;
    result.valid += a;
    result.map_contacts += ca.in_collision && !ca.self_collision;
  }
  return result;
}

// Random configurations are continuous, so none lands within rounding of an exact contact:
// every comparison below expects zero disagreements.

TEST(OccupancyGrid, PandaShelfMapMatchesFcl) {
  auto panda = test::LoadRobot("panda");
  auto scene = test::LoadScene("scenes/shelf_octomap.json");
  std::mt19937_64 rng(11);
  const int n = NumSamples();
  const Agreement r = Compare(panda, scene, n, [&] { return test::RandomConfig(*panda, rng); });
  EXPECT_EQ(r.disagreements, 0);
  EXPECT_GT(r.valid, n / 10);
  EXPECT_GT(r.map_contacts, n / 20);
}

TEST(OccupancyGrid, PandaShelfMapWithPaddingMatchesFcl) {
  // The FCL path pads through fcl::distance <= padding; the fast path grows the spheres.
  auto panda = test::LoadRobot("panda");
  auto scene = test::LoadScene("scenes/shelf_octomap.json");
  std::mt19937_64 rng(12);
  const int n = NumSamples() / 5;
  const Agreement r = Compare(panda, scene, n, [&] { return test::RandomConfig(*panda, rng); }, 0.01);
  EXPECT_EQ(r.disagreements, 0);
  // Padding grows the robot against the map only (self pairs are unpadded); map contacts are
  // compared on both paths.
  EXPECT_GT(r.map_contacts, n / 20);
  std::cout << "padded: " << r.valid << " valid, " << r.map_contacts << " map contacts of " << n << "\n";
}

TEST(OccupancyGrid, PosedMapsAndWhichMapIsHit) {
  auto panda = test::LoadRobot("panda");
  const auto tree = ShelfTree();
  // One rotated and translated map.
  auto posed = std::make_shared<Scene>();
  posed->AddOccupancyMap({"posed_shelf", tree, SomePose()});
  std::mt19937_64 rng(13);
  const int n = NumSamples();
  Agreement r = Compare(panda, posed, n, [&] { return test::RandomConfig(*panda, rng); });
  EXPECT_EQ(r.disagreements, 0);
  EXPECT_GT(r.valid, n / 10);
  // Two maps: the first contact must name the same map on both paths.
  auto two = std::make_shared<Scene>();
  Eigen::Isometry3d behind = Eigen::Isometry3d::Identity();
  behind.linear() = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  behind.translation() << 0.1, 0.0, -0.05;
  two->AddOccupancyMap({"shelf_behind", tree, behind});
  two->AddOccupancyMap({"shelf_posed", tree, SomePose()});
  r = Compare(panda, two, n, [&] { return test::RandomConfig(*panda, rng); });
  EXPECT_EQ(r.disagreements, 0);
  EXPECT_GT(r.map_contacts, n / 10);
}

// A small tree: pruned leaves of 16³, 8³ and 2³ voxels next to single voxels, "uncertain"
// voxels (between FCL's free threshold, log-odds 0, and the occupancy threshold) inside and
// next to occupied ones, and free voxels.
std::shared_ptr<octomap::OcTree> HandBuiltTree(double occupancy_threshold) {
  auto tree = std::make_shared<octomap::OcTree>(0.05);
  tree->setOccupancyThres(occupancy_threshold);
  const float occupied = 2.0f, uncertain = static_cast<float>(octomap::logodds(0.5 * (0.5 + occupancy_threshold)));
  const octomap::OcTreeKey origin = tree->coordToKey(0.0, 0.0, 0.0);  // 32768 on every axis
  const auto set = [&](int x, int y, int z, float v) {
    tree->setNodeValue(octomap::OcTreeKey(origin[0] + x, origin[1] + y, origin[2] + z), v);
  };
  const auto cube = [&](int x0, int y0, int z0, int size, float v) {
    for (int z = z0; z < z0 + size; ++z)
      for (int y = y0; y < y0 + size; ++y)
        for (int x = x0; x < x0 + size; ++x) set(x, y, z, v);
  };
  cube(0, 0, 0, 16, occupied);      // one 16³ leaf (depth 12) after pruning
  cube(16, 0, 0, 8, occupied);      // 8³ (depth 13)
  cube(-8, -8, 8, 8, occupied);     // 8³ at negative keys
  cube(-2, 20, 2, 2, occupied);     // 2³ (depth 15)
  cube(16, 8, 0, 8, uncertain);     // an uncertain 8³ leaf next to the occupied ones
  cube(24, 24, 24, 4, uncertain);   // an isolated uncertain 4³ leaf
  cube(-16, 0, 0, 8, -1.0f);        // free
  for (int i = 0; i < 40; ++i) {    // single voxels, occupied and uncertain, alternating
    set(-20 + i, 30 - i, (i * 7) % 24 - 6, i % 2 == 0 ? occupied : uncertain);
  }
  set(3, -10, 3, static_cast<float>(tree->getOccupancyThresLog()));  // exactly at the threshold
  tree->prune();
  return tree;
}

void ExpectPrunedLeaves(const octomap::OcTree& tree) {
  int big = 0;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (tree.isNodeOccupied(*it) && it.getDepth() <= 13) ++big;
  }
  EXPECT_GE(big, 3) << "the hand-built tree should hold pruned occupied leaves of 8³ voxels or more";
}

void CompareBallsAround(const std::shared_ptr<const Scene>& scene, std::uint64_t seed, int n, bool expect_mixed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.6, 2.0);
  for (double radius : {0.004, 0.03, 0.11}) {
    auto ball = BallRobot(radius);
    const Agreement r = Compare(ball, scene, n, [&] {
      const Eigen::Vector3d p(u(rng), u(rng), u(rng));
      return Eigen::VectorXd(SomePose() * (0.5 * p));  // around the tree, in either map pose
    });
    EXPECT_EQ(r.disagreements, 0) << "radius " << radius;
    if (expect_mixed) {
      EXPECT_GT(r.valid, 0) << "radius " << radius;
      EXPECT_LT(r.valid, n) << "radius " << radius;
    }
  }
}

TEST(OccupancyGrid, HandBuiltTreeWithPrunedAndUncertainNodesMatchesFcl) {
  auto tree = HandBuiltTree(0.7);
  ExpectPrunedLeaves(*tree);
  for (const Eigen::Isometry3d& pose : {Eigen::Isometry3d(Eigen::Isometry3d::Identity()), SomePose()}) {
    auto scene = std::make_shared<Scene>();
    scene->AddOccupancyMap({"hand_built", tree, pose});
    CompareBallsAround(scene, 21, NumSamples(), true);
  }
  // Uncertain voxels are not obstacles; occupied ones (pruned or not, or exactly at the
  // threshold) are. Ball centres at voxel centres, far from anything else.
  auto scene = std::make_shared<Scene>();
  scene->AddOccupancyMap({"hand_built", tree, Eigen::Isometry3d::Identity()});
  for (bool force_fcl : {false, true}) {
    CollisionOptions options;
    options.force_fcl = force_fcl;
    const CollisionChecker checker(BallRobot(0.01), scene, options);
    EXPECT_TRUE(checker.IsValid(At(1.3, 1.3, 1.3))) << "isolated uncertain 4³ leaf, force_fcl " << force_fcl;
    EXPECT_FALSE(checker.IsValid(At(0.4, 0.4, 0.4))) << "16³ leaf, force_fcl " << force_fcl;
    EXPECT_FALSE(checker.IsValid(At(0.175, -0.475, 0.175))) << "voxel at the threshold, force_fcl " << force_fcl;
  }
}

TEST(OccupancyGrid, FclsInnerNodeRuleIsMatched) {
  // With an occupancy threshold below 0.5, a voxel with log-odds in [threshold, 0] is occupied
  // by octomap's (and FCL's) leaf test, but FCL stops at its parent, whose log-odds (the
  // children's maximum) is <= 0, FCL's fixed free threshold: FCL never reports it. The same
  // holds for log-odds exactly 0 with the default threshold 0.5.
  for (double threshold : {0.4, 0.5}) {
    auto tree = std::make_shared<octomap::OcTree>(0.05);
    tree->setOccupancyThres(threshold);
    const float hidden = threshold < 0.5 ? static_cast<float>(octomap::logodds(0.45)) : 0.0f;
    tree->setNodeValue(octomap::point3d(1.025f, 0.025f, 0.025f), hidden);
    tree->setNodeValue(octomap::point3d(0.025f, 0.025f, 0.025f), 2.0f);
    const octomap::OcTreeNode* node = tree->search(1.025, 0.025, 0.025);
    ASSERT_NE(node, nullptr);
    ASSERT_TRUE(tree->isNodeOccupied(node));
    auto scene = std::make_shared<Scene>();
    scene->AddOccupancyMap({"map", tree, Eigen::Isometry3d::Identity()});
    for (bool force_fcl : {false, true}) {
      CollisionOptions options;
      options.force_fcl = force_fcl;
      const CollisionChecker checker(BallRobot(0.01), scene, options);
      EXPECT_TRUE(checker.IsValid(At(1.025, 0.025, 0.025))) << threshold << " force_fcl " << force_fcl;
      EXPECT_FALSE(checker.IsValid(At(0.025, 0.025, 0.025))) << threshold << " force_fcl " << force_fcl;
    }
    CompareBallsAround(scene, 22, NumSamples() / 5, false);
  }
  // A map where FCL reaches no obstacle at all is gridded as empty.
  auto tree = std::make_shared<octomap::OcTree>(0.05);
  tree->setNodeValue(octomap::point3d(0.025f, 0.025f, 0.025f), 0.0f);
  auto scene = std::make_shared<Scene>();
  scene->AddOccupancyMap({"map", tree, Eigen::Isometry3d::Identity()});
  const CollisionChecker checker(BallRobot(0.1), scene);
  EXPECT_EQ(checker.num_gridded_occupancy_maps(), 1);
  EXPECT_TRUE(checker.IsValid(At(0.025, 0.025, 0.025)));
}

TEST(OccupancyGrid, TouchingAndJustMissingAFaceAnEdgeAndACorner) {
  // One voxel [0, 0.25]³ (resolution 0.25: every coordinate below is exact in binary), and ball
  // centres at exactly the ball radius from its face, edge or corner (3-4-5 and 1-2-2 triples).
  auto tree = std::make_shared<octomap::OcTree>(0.25);
  tree->setNodeValue(octomap::point3d(0.125f, 0.125f, 0.125f), 2.0f);
  auto scene = std::make_shared<Scene>();
  scene->AddOccupancyMap({"voxel", tree, Eigen::Isometry3d::Identity()});
  struct Case {
    const char* what;
    Eigen::Vector3d contact;  // closest point of the voxel
    Eigen::Vector3d offset;   // from the contact to the ball centre; |offset| = radius
  };
  const Case cases[] = {
      {"+x face", {0.25, 0.125, 0.125}, {0.125, 0.0, 0.0}},
      {"-z face", {0.1, 0.2, 0.0}, {0.0, 0.0, -0.125}},
      {"x-y edge", {0.25, 0.25, 0.125}, {0.1875, 0.25, 0.0}},
      {"-y-z edge", {0.0625, 0.0, 0.0}, {0.0, -0.25, -0.1875}},
      {"+++ corner", {0.25, 0.25, 0.25}, {0.125, 0.25, 0.25}},
      {"--- corner", {0.0, 0.0, 0.0}, {-0.25, -0.125, -0.25}},
  };
  for (const Case& c : cases) {
    const double radius = c.offset.norm();
    ASSERT_EQ(radius * radius, c.offset.squaredNorm()) << c.what << ": the radius must be exact";
    for (double padding : {0.0, radius / 2}) {
      auto ball = BallRobot(radius - padding);
      CollisionOptions fast_options, fcl_options;
      fast_options.padding = fcl_options.padding = padding;
      fcl_options.force_fcl = true;
      const CollisionChecker fast(ball, scene, fast_options);
      const CollisionChecker fcl(ball, scene, fcl_options);
      ASSERT_EQ(fast.num_gridded_occupancy_maps(), 1);
      const Eigen::Vector3d touching = c.contact + c.offset;
      // Touching is a collision (as for primitives), on both paths: with exact binary
      // coordinates neither path rounds.
      EXPECT_FALSE(fast.IsValid(touching)) << c.what << " padding " << padding;
      EXPECT_FALSE(fcl.IsValid(touching)) << c.what << " padding " << padding << " (FCL)";
      for (double eps : {1e-9, 1e-6}) {
        const Eigen::Vector3d out = c.contact + (1 + eps) * c.offset;
        const Eigen::Vector3d in = c.contact + (1 - eps) * c.offset;
        EXPECT_TRUE(fast.IsValid(out)) << c.what << " padding " << padding << " eps " << eps;
        EXPECT_FALSE(fast.IsValid(in)) << c.what << " padding " << padding << " eps " << eps;
        EXPECT_TRUE(fcl.IsValid(out)) << c.what << " padding " << padding << " eps " << eps;
        EXPECT_FALSE(fcl.IsValid(in)) << c.what << " padding " << padding << " eps " << eps;
      }
    }
  }
}

TEST(OccupancyGrid, MapsTooLargeToGridStayOnFcl) {
  // Two voxels 7 m apart at 1 cm: their box holds 700³ > 2^28 voxels.
  auto tree = std::make_shared<octomap::OcTree>(0.01);
  tree->setNodeValue(octomap::point3d(0.005f, 0.005f, 0.005f), 2.0f);
  tree->setNodeValue(octomap::point3d(6.995f, 6.995f, 6.995f), 2.0f);
  auto scene = std::make_shared<Scene>();
  scene->AddOccupancyMap({"large", tree, Eigen::Isometry3d::Identity()});
  scene->AddOccupancyMap({"small", HandBuiltTree(0.7), Eigen::Isometry3d::Identity()});
  auto ball = BallRobot(0.02);
  const CollisionChecker fast(ball, scene);
  EXPECT_EQ(fast.num_gridded_occupancy_maps(), 1);
  EXPECT_FALSE(fast.IsValid(At(7.0, 7.0, 7.0)));
  EXPECT_FALSE(fast.IsValid(At(-0.01, 0.0, 0.0)));
  EXPECT_TRUE(fast.IsValid(At(3.0, 3.0, 3.0)));
  EXPECT_EQ(fast.Check(At(7.0, 7.0, 7.0)).other, "large");
}

}  // namespace
}  // namespace chasles

namespace chasles {
namespace {

// Issue 22, item 2: a contact with a map names the voxel. A ball touching one of two voxels of a
// posed map reports the centre octomap itself gives that voxel (keyToCoord of coordToKey), placed
// by the map's pose; the messages carry it, in metres.
TEST(OccupancyGrid, AContactNamesTheVoxelItTouches) {
  auto tree = std::make_shared<octomap::OcTree>(0.1);
  const octomap::point3d a(1.03f, 2.07f, 0.42f), b(-0.55f, 0.31f, 0.12f);
  tree->setNodeValue(a, 2.0f);
  tree->setNodeValue(b, 2.0f);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  pose.translation() << 0.5, -0.2, 0.1;
  auto scene = std::make_shared<Scene>();
  scene->AddOccupancyMap({"sensed", tree, pose});
  const CollisionChecker checker(BallRobot(0.02), scene);
  ASSERT_EQ(checker.num_gridded_occupancy_maps(), 1);
  for (const octomap::point3d& p : {a, b}) {
    const octomap::point3d centre = tree->keyToCoord(tree->coordToKey(p));
    const Eigen::Vector3d world = pose * Eigen::Vector3d(centre.x(), centre.y(), centre.z());
    const CollisionResult contact = checker.Check(world);  // the ball's centre at the voxel's
    ASSERT_TRUE(contact.in_collision);
    EXPECT_EQ(contact.other, "sensed");
    ASSERT_TRUE(contact.has_voxel);
    // octomap's coordinates are floats (point3d): equal to its rounding (~1e-7 at 2 m).
    EXPECT_LT((contact.voxel - world).norm(), 1e-6);
    char expected[96];
    std::snprintf(expected, sizeof expected, "(the voxel centred at (%.4g, %.4g, %.4g) m)", world.x(), world.y(), world.z());
    EXPECT_NE(VoxelText(contact).find(expected), std::string::npos) << VoxelText(contact);
  }
  // Primitives and free states carry none.
  EXPECT_FALSE(checker.Check(At(5.0, 5.0, 5.0)).has_voxel);
  EXPECT_EQ(VoxelText(checker.Check(At(5.0, 5.0, 5.0))), "");
}

}  // namespace
}  // namespace chasles
