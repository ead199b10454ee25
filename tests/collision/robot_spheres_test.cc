// FitRobotSpheres (issue 25, "any URDF at sphere speed"): a robot whose links are meshes becomes
// the same robot with spheres covering them. Checked against the meshes themselves: every mesh
// vertex inside a sphere of its link, every configuration where the mesh robot collides (on the
// FCL path, an implementation of its own) colliding for the spheres too, and the spheres too
// cautious only within the reach the fit reports.

#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "chasles/collision/collision_checker.h"
#include "chasles/collision/mesh.h"
#include "chasles/collision/robot_spheres.h"
#include "chasles/robot/error.h"
#include "test_util.h"

namespace chasles {
namespace {

/// examples/robots/ur5_meshes: the example UR5 with its collision cylinders shipped as binary
/// STL meshes (what users upload: a URDF whose links are meshes), parsed as the server parses
/// them.
std::shared_ptr<const RobotModel> MeshUr5() {
  const std::string urdf = test::ReadFile(test::ExamplePath("robots/ur5_meshes.urdf"));
  std::map<std::string, std::shared_ptr<const TriangleMesh>> meshes;
  for (const char* link : {"base_link", "shoulder_link", "upper_arm_link", "forearm_link", "wrist_1_link",
                           "wrist_2_link", "wrist_3_link"}) {
    const std::string file = std::string(link) + "_0.stl";
    meshes["package://ur5_meshes/" + file] =
        ParseMesh(test::ReadFile(test::ExamplePath("robots/ur5_meshes/" + file)), Eigen::Vector3d::Ones(), file);
  }
  return RobotModel::FromUrdf(urdf, test::ReadFile(test::ExamplePath("robots/ur5_meshes.srdf")), meshes);
}

TEST(RobotSpheres, EveryMeshVertexIsInsideASphereOfItsLink) {
  const auto robot = MeshUr5();
  const RobotSphereFit fit = FitRobotSpheres(*robot);
  ASSERT_NE(fit.model, nullptr);
  EXPECT_EQ(fit.model->num_dofs(), robot->num_dofs());
  EXPECT_EQ(fit.model->num_links(), robot->num_links());
  EXPECT_EQ(fit.shapes_fitted, 7);  // the seven meshes
  EXPECT_GT(fit.reach, 0.0);
  EXPECT_LE(fit.reach, 0.02);
  std::printf("[ fit ] %d shapes → %d spheres, reach %.4f m (link '%s'), %.3f s\n", fit.shapes_fitted, fit.spheres,
              fit.reach, fit.reach_link.c_str(), fit.seconds);
  int spheres = 0;
  for (int l = 0; l < robot->num_links(); ++l) {
    const Link& exact = robot->links()[l];
    const Link& fitted = fit.model->links()[l];
    EXPECT_EQ(exact.name, fitted.name);
    for (const Shape& s : fitted.collision) {
      ASSERT_EQ(s.type, ShapeType::kSphere) << fitted.name;
      ++spheres;
    }
    EXPECT_LE(fitted.collision.size(), RobotSphereOptions().max_spheres_per_link + 2u) << fitted.name;  // + kept spheres
    for (const Shape& shape : exact.collision) {
      if (shape.type != ShapeType::kMesh) continue;
      for (const Eigen::Vector3d& v : shape.mesh->vertices) {
        const Eigen::Vector3d x = shape.pose * v;
        bool inside = false;
        for (const Shape& s : fitted.collision) inside = inside || (x - s.pose.translation()).norm() <= s.radius;
        EXPECT_TRUE(inside) << fitted.name << " vertex " << x.transpose();
      }
    }
  }
  EXPECT_EQ(spheres, fit.spheres);
  // Allowed pairs as the robot had them.
  for (int a = 0; a < robot->num_links(); ++a) {
    for (int b = 0; b < robot->num_links(); ++b) {
      EXPECT_EQ(fit.model->allowed_collisions().IsAllowed(a, b), robot->allowed_collisions().IsAllowed(a, b));
    }
  }
}

TEST(RobotSpheres, WhereTheMeshesCollideTheSpheresDoAndOnlyWithinTheReachElsewhere) {
  const auto robot = MeshUr5();
  const RobotSphereFit fit = FitRobotSpheres(*robot);
  ASSERT_NE(fit.model, nullptr);
  const auto scene = test::LoadScene("scenes/shelf.json");
  CollisionOptions fcl_options;
  fcl_options.force_fcl = true;
  const CollisionChecker exact(robot, scene, fcl_options);
  const CollisionChecker spheres(fit.model, scene);
  ASSERT_TRUE(spheres.certifies_motion());  // the fitted robot is on the sphere path
  std::mt19937_64 rng(3);
  int exact_hits = 0, sphere_only = 0;
  for (int i = 0; i < 1500; ++i) {
    const Eigen::VectorXd q = test::RandomConfig(*robot, rng);
    const bool e = exact.Check(q).in_collision;
    const bool s = spheres.Check(q).in_collision;
    exact_hits += e;
    if (e) {
      EXPECT_TRUE(s) << "the meshes collide where the spheres do not at q = " << q.transpose();
    }
    if (s && !e) {
      ++sphere_only;
      // Too cautious only near contact: the meshes are within the reach of something (the scene,
      // or a link they may not touch). Self distances are not measured by Clearance, so only
      // scene-only contacts are held to it.
      if (!spheres.Check(q).self_collision) {
        EXPECT_LE(exact.Clearance(q), fit.reach + 1e-9) << q.transpose();
      }
    }
  }
  EXPECT_GT(exact_hits, 100);  // the check means something
  std::printf("[ fit ] %d of 1500 configurations collide for the meshes; %d more for the spheres\n", exact_hits,
              sphere_only);
}

TEST(RobotSpheres, TheSrdfsNeverPairsDoNotTouchOnTheExactMeshes) {
  // ur5_meshes.srdf disables wrist_1/wrist_3 and forearm/wrist_2 as never touching (as MoveIt's
  // Setup Assistant would). Checked on the exact meshes (FCL) with every other pair allowed, so
  // the only contact that can be reported is the pair's own, at 5,000 random configurations.
  const auto exact = MeshUr5();
  for (const auto& [a, b] : {std::pair<std::string, std::string>{"wrist_1_link", "wrist_3_link"},
                             std::pair<std::string, std::string>{"forearm_link", "wrist_2_link"}}) {
    std::string srdf = "<robot name=\"ur5_meshes\">\n";
    for (int i = 0; i < exact->num_links(); ++i) {
      for (int j = i + 1; j < exact->num_links(); ++j) {
        const std::string& li = exact->links()[i].name;
        const std::string& lj = exact->links()[j].name;
        if ((li == a && lj == b) || (li == b && lj == a)) continue;
        srdf += "  <disable_collisions link1=\"" + li + "\" link2=\"" + lj + "\"/>\n";
      }
    }
    srdf += "</robot>\n";
    std::map<std::string, std::shared_ptr<const TriangleMesh>> meshes;
    for (const Link& link : exact->links()) {
      for (const Shape& shape : link.collision) {
        if (shape.type == ShapeType::kMesh) meshes["package://ur5_meshes/" + link.name + "_0.stl"] = shape.mesh;
      }
    }
    const auto pair_only = RobotModel::FromUrdf(test::ReadFile(test::ExamplePath("robots/ur5_meshes.urdf")), srdf, meshes);
    const CollisionChecker checker(pair_only, std::make_shared<Scene>());
    std::mt19937_64 rng(9);
    for (int k = 0; k < 5000; ++k) {
      const Eigen::VectorXd q = test::RandomConfig(*pair_only, rng);
      ASSERT_FALSE(checker.Check(q).in_collision) << a << " / " << b << " touch at q = " << q.transpose();
    }
  }
}

TEST(RobotSpheres, ARobotWithoutMeshesIsLeftAsItIs) {
  EXPECT_EQ(FitRobotSpheres(*test::LoadRobot("ur5")).model, nullptr);    // cylinders and spheres
  EXPECT_EQ(FitRobotSpheres(*test::LoadRobot("panda")).model, nullptr);  // spheres
}

TEST(RobotSpheres, BadOptionsAreRefusedByName) {
  const auto robot = MeshUr5();
  RobotSphereOptions options;
  options.max_spheres_per_link = 0;
  try {
    FitRobotSpheres(*robot, options);
    ADD_FAILURE() << "accepted max_spheres_per_link = 0";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("max_spheres_per_link = 0"), std::string::npos) << e.what();
  }
  options = RobotSphereOptions();
  options.fit.max_reach = std::nan("");
  EXPECT_THROW(FitRobotSpheres(*robot, options), Error);
}

}  // namespace
}  // namespace chasles
