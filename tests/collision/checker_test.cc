// CollisionChecker behaviour: the allowed-collision matrix, motion validation, joint limits,
// meshes, the example scenes at the reference configurations, and concurrent use.

#include <atomic>
#include <random>
#include <thread>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "chasles/collision/collision_checker.h"
#include "chasles/collision/mesh.h"
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

// base (sphere at the origin) -> joint1 (z) -> link1 (sphere at x = 0.3) -> joint2 (z, at
// x = 0.3) -> link2 (sphere at x = 0.3 in its frame). At q2 = pi link2's sphere is back at the
// base sphere, which is neither its parent nor its child.
std::shared_ptr<const RobotModel> ThreeLinkArm(bool allow_base_link2, ShapeType shape = ShapeType::kSphere) {
  const auto make = [&](const Eigen::Isometry3d& pose) {
    return shape == ShapeType::kSphere ? Shape::Sphere(0.1, pose) : Shape::Box({0.2, 0.2, 0.2}, pose);
  };
  std::vector<Link> links(3);
  links[0].name = "base";
  links[0].collision = {make(Eigen::Isometry3d::Identity())};
  links[1].name = "link1";
  links[1].parent_joint = 0;
  links[1].collision = {make(At(0.3, 0, 0))};
  links[2].name = "link2";
  links[2].parent_joint = 1;
  links[2].collision = {make(At(0.3, 0, 0))};
  std::vector<Joint> joints(2);
  for (int i = 0; i < 2; ++i) {
    joints[i].name = "joint" + std::to_string(i + 1);
    joints[i].type = JointType::kRevolute;
    joints[i].parent_link = i;
    joints[i].child_link = i + 1;
    joints[i].limits = {-3.2, 3.2, 1.0, 0.0};
    joints[i].dof = i;
  }
  joints[1].origin = At(0.3, 0, 0);
  std::vector<std::pair<std::string, std::string>> allowed;
  if (allow_base_link2) allowed.emplace_back("base", "link2");
  return RobotModel::FromTree("arm", links, joints, allowed);
}

TEST(SelfCollision, ObeysTheAllowedCollisionMatrix) {
  for (ShapeType shape : {ShapeType::kSphere, ShapeType::kBox}) {
    for (bool force_fcl : {false, true}) {
      SCOPED_TRACE(::testing::Message() << "box=" << (shape == ShapeType::kBox) << " fcl=" << force_fcl);
      CollisionOptions options;
      options.force_fcl = force_fcl;
      auto scene = std::make_shared<Scene>();
      CollisionChecker strict(ThreeLinkArm(false, shape), scene, options);
      CollisionChecker allowed(ThreeLinkArm(true, shape), scene, options);
      EXPECT_EQ(strict.uses_fast_path(), shape == ShapeType::kSphere && !force_fcl);
      Eigen::VectorXd q(2);
      q << 0.0, 0.0;  // stretched out: spheres at x = 0, 0.3, 0.6, no contact
      EXPECT_TRUE(strict.IsValid(q));
      q << 0.0, 3.1;  // link2 folded back onto the base
      EXPECT_FALSE(strict.IsValid(q));
      const CollisionResult r = strict.Check(q);
      EXPECT_TRUE(r.in_collision);
      EXPECT_TRUE(r.self_collision);
      EXPECT_TRUE((r.link_a == "base" && r.other == "link2") || (r.link_a == "link2" && r.other == "base"))
          << r.link_a << " / " << r.other;
      EXPECT_TRUE(allowed.IsValid(q));
      EXPECT_FALSE(allowed.Check(q).in_collision);
      // Self contacts never count towards the clearance to the (empty) scene.
      EXPECT_EQ(strict.Clearance(q), std::numeric_limits<double>::infinity());
    }
  }
}

TEST(SelfCollision, ParentChildPairsAreAllowed) {
  // link1's sphere overlaps the base sphere when moved close: joint origin at the base, so
  // parent/child contact is expected and allowed.
  std::vector<Link> links(2);
  links[0].name = "base";
  links[0].collision = {Shape::Sphere(0.1)};
  links[1].name = "link1";
  links[1].parent_joint = 0;
  links[1].collision = {Shape::Sphere(0.1, At(0.05, 0, 0))};
  std::vector<Joint> joints(1);
  joints[0].name = "j";
  joints[0].type = JointType::kRevolute;
  joints[0].parent_link = 0;
  joints[0].child_link = 1;
  joints[0].limits = {-1, 1, 1, 0};
  joints[0].dof = 0;
  CollisionChecker checker(RobotModel::FromTree("two", links, joints), std::make_shared<Scene>());
  EXPECT_TRUE(checker.IsValid(Q1(0.3)));
}

TEST(Limits, IsValidRejectsConfigurationsOutsideTheLimits) {
  CollisionChecker checker(test::SliderRobot(Shape::Sphere(0.1)), std::make_shared<Scene>());
  EXPECT_TRUE(checker.IsValid(Q1(4.9)));
  EXPECT_FALSE(checker.IsValid(Q1(5.1)));
  EXPECT_FALSE(checker.IsValid(Q1(NAN)));
  EXPECT_FALSE(checker.Check(Q1(5.1)).in_collision);  // Check ignores limits
  EXPECT_THROW(checker.IsValid(Eigen::VectorXd::Zero(2)), Error);
}

class Motion : public ::testing::TestWithParam<bool> {};

TEST_P(Motion, FindsAThinObstacleAndRespectsMaxStep) {
  CollisionOptions options;
  options.force_fcl = GetParam();
  auto robot = test::SliderRobot(Shape::Sphere(0.05));
  auto scene = std::make_shared<Scene>();
  scene->AddObject({"sheet", Shape::Box({0.002, 1.0, 1.0}, At(0.3, 0, 0))});
  CollisionChecker checker(robot, scene, options);
  ASSERT_TRUE(checker.IsValid(Q1(-1)));
  ASSERT_TRUE(checker.IsValid(Q1(1)));

  CheckCounters fine;
  EXPECT_FALSE(checker.IsMotionValid(Q1(-1), Q1(1), 0.01, &fine));
  EXPECT_LE(fine.state_checks, 201u);  // at most n + 1 = 201 states

  // States at -1, -0.5, 0, 0.5, 1 all miss the sheet (nearest 0.2 away): a coarse step misses it.
  CheckCounters coarse;
  EXPECT_TRUE(checker.IsMotionValid(Q1(-1), Q1(1), 0.5, &coarse));
  EXPECT_EQ(coarse.state_checks, 5u);

  // Without the sheet, every one of the n + 1 states is checked once.
  CollisionChecker free_checker(robot, std::make_shared<Scene>(), options);
  CheckCounters all;
  EXPECT_TRUE(free_checker.IsMotionValid(Q1(-1), Q1(1), 0.01, &all));
  EXPECT_EQ(all.state_checks, 201u);
  CheckCounters uneven;  // n = ceil(2 / 0.3) = 7 intervals
  EXPECT_TRUE(free_checker.IsMotionValid(Q1(-1), Q1(1), 0.3, &uneven));
  EXPECT_EQ(uneven.state_checks, 8u);
  CheckCounters zero;  // a == b: one interval, both endpoints
  EXPECT_TRUE(free_checker.IsMotionValid(Q1(0.2), Q1(0.2), 0.01, &zero));
  EXPECT_EQ(zero.state_checks, 2u);

  // An obstacle at the midpoint is found by the third check (b, a, then the middle).
  auto mid_scene = std::make_shared<Scene>();
  mid_scene->AddObject({"sheet", Shape::Box({0.002, 1.0, 1.0}, At(0.0, 0, 0))});
  CollisionChecker mid(robot, mid_scene, options);
  CheckCounters bisect;
  EXPECT_FALSE(mid.IsMotionValid(Q1(-1), Q1(1), 0.001, &bisect));
  EXPECT_EQ(bisect.state_checks, 3u);

  // Invalid endpoints: b is checked first.
  CheckCounters end;
  EXPECT_FALSE(checker.IsMotionValid(Q1(-1), Q1(0.3), 0.01, &end));
  EXPECT_EQ(end.state_checks, 1u);
  EXPECT_FALSE(checker.IsMotionValid(Q1(0.3), Q1(-1), 0.01));
  EXPECT_THROW(checker.IsMotionValid(Q1(-1), Q1(1), 0.0), Error);
  EXPECT_THROW(checker.IsMotionValid(Q1(-1), Q1(1), NAN), Error);
}

INSTANTIATE_TEST_SUITE_P(BothPaths, Motion, ::testing::Values(false, true));

const char kCubeObj[] =
    "v -0.1 -0.1 -0.1\nv 0.1 -0.1 -0.1\nv 0.1 0.1 -0.1\nv -0.1 0.1 -0.1\n"
    "v -0.1 -0.1 0.1\nv 0.1 -0.1 0.1\nv 0.1 0.1 0.1\nv -0.1 0.1 0.1\n"
    "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n";

std::string CubeAsciiStl() {
  // Two triangles per face of the cube [-0.1, 0.1]^3 (normals left zero; assimp recomputes).
  const double c[8][3] = {{-.1, -.1, -.1}, {.1, -.1, -.1}, {.1, .1, -.1}, {-.1, .1, -.1},
                          {-.1, -.1, .1},  {.1, -.1, .1},  {.1, .1, .1},  {-.1, .1, .1}};
  const int f[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                        {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
  std::ostringstream s;
  s << "solid cube\n";
  for (const auto& t : f) {
    s << "facet normal 0 0 0\nouter loop\n";
    for (int k : t) s << "vertex " << c[k][0] << " " << c[k][1] << " " << c[k][2] << "\n";
    s << "endloop\nendfacet\n";
  }
  s << "endsolid cube\n";
  return s.str();
}

TEST(Mesh, ParsesObjAndStlAndNamesErrors) {
  for (const std::string& bytes : {std::string(kCubeObj), CubeAsciiStl()}) {
    auto mesh = ParseMesh(bytes, Eigen::Vector3d(1, 2, 1), "scene.meshes[0].data");
    EXPECT_EQ(mesh->triangles.size(), 12u);
    EXPECT_EQ(mesh->vertices.size(), 8u);  // identical vertices joined
    double max_y = 0;
    for (const auto& v : mesh->vertices) max_y = std::max(max_y, v.y());
    EXPECT_NEAR(max_y, 0.2, 1e-6);  // scale applied
  }
  try {
    ParseMesh("this is not a mesh at all", Eigen::Vector3d::Ones(), "scene.meshes[2].data");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("scene.meshes[2].data"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ParseMesh("", Eigen::Vector3d::Ones(), "m"), Error);
  EXPECT_THROW(ParseMesh(kCubeObj, Eigen::Vector3d(1, 0, 1), "m"), Error);
}

/// A COLLADA document as CAD tools write them: Z_UP, millimetres, the geometry placed by a node
/// transform. Expected vertices by hand: the box [0, 100] × [0, 200] × [0, 300] mm moved by
/// (10, 0, 0) mm is [0.01, 0.11] × [0, 0.2] × [0, 0.3] m with z still up (the up axis is not turned).
std::string BoxDae(const std::string& up_axis) {
  std::string positions;
  for (int i = 0; i < 8; ++i) {
    positions += std::to_string((i & 1) ? 100 : 0) + " " + std::to_string((i & 2) ? 200 : 0) + " " +
                 std::to_string((i & 4) ? 300 : 0) + " ";
  }
  // 12 triangles of the cube over corner indices (bit 0 = x, bit 1 = y, bit 2 = z).
  const char* triangles = "0 2 1 1 2 3 4 5 6 5 7 6 0 1 4 1 5 4 2 6 3 3 6 7 0 4 2 2 4 6 1 3 5 3 7 5";
  return std::string(R"(<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="millimeter" meter="0.001"/><up_axis>)") + up_axis + R"(</up_axis></asset>
  <library_geometries>
    <geometry id="box" name="box"><mesh>
      <source id="box-pos"><float_array id="box-pos-array" count="24">)" + positions + R"(</float_array>
        <technique_common><accessor source="#box-pos-array" count="8" stride="3">
          <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
        </accessor></technique_common></source>
      <vertices id="box-vtx"><input semantic="POSITION" source="#box-pos"/></vertices>
      <triangles count="12"><input semantic="VERTEX" source="#box-vtx" offset="0"/><p>)" + triangles + R"(</p></triangles>
    </mesh></geometry>
  </library_geometries>
  <library_visual_scenes>
    <visual_scene id="scene"><node id="part"><translate>10 0 0</translate>
      <instance_geometry url="#box"/></node></visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
)";
}

TEST(Mesh, ParsesColladaWithItsUnitsAndNodeTransformAndKeepsItsAxes) {
  for (const std::string up : {"Z_UP", "Y_UP"}) {
    const auto mesh = ParseMesh(BoxDae(up), Eigen::Vector3d::Ones(), "robot.urdf.mesh_files['box.dae']");
    ASSERT_EQ(mesh->triangles.size(), 12u) << up;
    // assimp keeps vertices in single precision: 0.3 is 0.30000001 (float), hence 1e-7.
    constexpr double kFloat = 1e-7;
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e9), hi = -lo;
    for (const Eigen::Vector3d& v : mesh->vertices) {
      lo = lo.cwiseMin(v);
      hi = hi.cwiseMax(v);
    }
    EXPECT_NEAR(lo.x(), 0.01, kFloat) << up;
    EXPECT_NEAR(lo.y(), 0.0, kFloat) << up;
    EXPECT_NEAR(lo.z(), 0.0, kFloat) << up;
    EXPECT_NEAR(hi.x(), 0.11, kFloat) << up;
    EXPECT_NEAR(hi.y(), 0.2, kFloat) << up;
    EXPECT_NEAR(hi.z(), 0.3, kFloat) << up;
  }
  // A COLLADA document that is not one is named as COLLADA, with the field.
  try {
    ParseMesh("<?xml version=\"1.0\"?><COLLADA version=\"1.4.1\"><library_geometries>", Eigen::Vector3d::Ones(), "m.dae");
    FAIL();
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("m.dae is not a readable COLLADA mesh"));
  }
}

TEST(Mesh, SphereVsMeshObstacleOnBothPaths) {
  Shape cube;
  cube.type = ShapeType::kMesh;
  cube.mesh = ParseMesh(kCubeObj, Eigen::Vector3d::Ones(), "scene.meshes[0].data");
  cube.pose = At(1, 0, 0);
  auto scene = std::make_shared<Scene>();
  scene->AddObject({"cube", cube});
  for (bool force_fcl : {false, true}) {
    CollisionOptions options;
    options.force_fcl = force_fcl;
    CollisionChecker checker(test::SliderRobot(Shape::Sphere(0.1)), scene, options);
    EXPECT_NEAR(checker.Clearance(Q1(0.5)), 0.3, 1e-6);
    EXPECT_TRUE(checker.IsValid(Q1(0.79)));
    EXPECT_FALSE(checker.IsValid(Q1(0.81)));
    EXPECT_EQ(checker.Check(Q1(0.9)).other, "cube");
  }
}

TEST(ExampleScenes, ReferenceConfigurationsAreCollisionFree) {
  auto panda = test::LoadRobot("panda");
  for (const char* name : {"table", "shelf", "cage", "bin", "shelf_octomap"}) {
    SCOPED_TRACE(name);
    auto scene = test::LoadScene(std::string("scenes/") + name + ".json");
    EXPECT_FALSE(scene->empty());
    for (bool force_fcl : {false, true}) {
      CollisionOptions options;
      options.force_fcl = force_fcl;
      CollisionChecker checker(panda, scene, options);
      const CollisionResult r = checker.Check(test::PandaReady());
      EXPECT_FALSE(r.in_collision) << r.link_a << " / " << r.other;
      EXPECT_TRUE(checker.IsValid(test::PandaReady()));
      EXPECT_GT(checker.Clearance(test::PandaReady()), 0.05);
    }
  }
  std::ifstream ur5_file(test::ExamplePath("robots/ur5.urdf"));
  if (!ur5_file) GTEST_SKIP() << "examples/robots/ur5.urdf is not there yet";
  auto ur5 = test::LoadRobot("ur5");
  for (const char* name : {"table", "shelf", "cage", "shelf_octomap"}) {
    SCOPED_TRACE(name);
    CollisionChecker checker(ur5, test::LoadScene(std::string("scenes/") + name + ".json"));
    EXPECT_FALSE(checker.uses_fast_path());
    const CollisionResult r = checker.Check(test::Ur5Up());
    EXPECT_FALSE(r.in_collision) << r.link_a << " / " << r.other;
    EXPECT_TRUE(checker.IsValid(test::Ur5Up()));
    EXPECT_GT(checker.Clearance(test::Ur5Up()), 0.05);
  }
}

TEST(Concurrency, TwoThreadsAgreeWithSequentialAnswers) {
  auto panda = test::LoadRobot("panda");
  for (bool force_fcl : {false, true}) {
    CollisionOptions options;
    options.force_fcl = force_fcl;
    const CollisionChecker checker(panda, test::LoadScene("scenes/shelf.json"), options);
    std::mt19937_64 rng(5);
    const int n = force_fcl ? 1000 : 4000;
    std::vector<Eigen::VectorXd> qs;
    for (int i = 0; i < n; ++i) qs.push_back(test::RandomConfig(*panda, rng));
    std::vector<char> expected(n);
    std::vector<double> expected_clearance(n);
    int valid = 0;
    for (int i = 0; i < n; ++i) {
      expected[i] = checker.IsValid(qs[i]);
      expected_clearance[i] = checker.Clearance(qs[i]);
      valid += expected[i];
    }
    EXPECT_GT(valid, n / 10);
    EXPECT_LT(valid, n - n / 10);
    std::atomic<int> mismatches{0};
    const auto work = [&](int offset) {
      for (int k = 0; k < 3 * n; ++k) {
        const int i = (k + offset) % n;
        if (static_cast<char>(checker.IsValid(qs[i])) != expected[i]) ++mismatches;
        if (k % 8 == 0 && checker.Clearance(qs[i]) != expected_clearance[i]) ++mismatches;
      }
    };
    std::thread t1(work, 0), t2(work, n / 2);
    t1.join();
    t2.join();
    EXPECT_EQ(mismatches.load(), 0);
  }
}

}  // namespace
}  // namespace chasles
