// FitRobotSpheres (issue 25, "any URDF at sphere speed"): a robot whose links are meshes becomes
// the same robot with spheres covering them. Checked against the meshes themselves: every mesh
// vertex inside a sphere of its link, every configuration where the mesh robot collides (on the
// FCL path, an implementation of its own) colliding for the spheres too, and the spheres too
// cautious only within the reach the fit reports. A robot of cylinders, a thin disc, a capsule, a
// box and a mesh at turned poses: dense points of every shape inside its link's spheres, the
// spheres within the reach of their link's shapes (exact distances written in the test), the
// same shape fitted once, and the same fit whatever the thread count; the Baxter's arm within 1 cm.

#include <algorithm>
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
#include "solid_points.h"
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

/// A root link with `links` hung from it by fixed joints.
std::shared_ptr<const RobotModel> StarRobot(const std::vector<Link>& links) {
  std::vector<Link> all(1);
  all[0].name = "root";
  std::vector<Joint> joints;
  for (const Link& link : links) {
    all.push_back(link);
    all.back().parent_joint = static_cast<int>(joints.size());
    Joint joint;
    joint.name = link.name + "_joint";
    joint.parent_link = 0;
    joint.child_link = static_cast<int>(all.size()) - 1;
    joints.push_back(joint);
  }
  return RobotModel::FromTree("star", all, joints);
}

Eigen::Isometry3d Pose(double x, double y, double z, double roll, double pitch, double yaw) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() << x, y, z;
  pose.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                   Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                      .toRotationMatrix();
  return pose;
}

Link MakeLink(const std::string& name, std::vector<Shape> shapes) {
  Link link;
  link.name = name;
  link.collision = std::move(shapes);
  return link;
}

/// Exact distance from a point of the link frame to the shape's solid (a mesh here is a cube of
/// CubeMeshShape).
double ShapeDistance(const Shape& shape, const Eigen::Vector3d& in_link) {
  const Eigen::Vector3d p = shape.pose.inverse() * in_link;
  switch (shape.type) {
    case ShapeType::kSphere:
      return std::max(p.norm() - shape.radius, 0.0);
    case ShapeType::kCylinder:
      return test::CylinderDistance(p, shape.radius, shape.length);
    case ShapeType::kCapsule:
      return test::CapsuleDistance(p, shape.radius, shape.length);
    case ShapeType::kBox:
      return test::BoxDistance(p, shape.size);
    case ShapeType::kMesh:
      return test::BoxDistance(p, Eigen::Vector3d::Constant(2.0 * shape.mesh->vertices[7].x()));
  }
  return 0.0;
}

/// Points of the shape's solid in the link frame.
std::vector<Eigen::Vector3d> ShapePoints(const Shape& shape, std::mt19937_64& rng) {
  std::vector<Eigen::Vector3d> points;
  switch (shape.type) {
    case ShapeType::kSphere:
      break;
    case ShapeType::kCylinder:
      points = test::CylinderPoints(shape.radius, shape.length, 20000, rng);
      break;
    case ShapeType::kCapsule:
      points = test::CapsulePoints(shape.radius, shape.length, 20000, rng);
      break;
    case ShapeType::kBox:
      points = test::BoxPoints(shape.size, 20000, rng);
      break;
    case ShapeType::kMesh:
      points = test::BoxPoints(Eigen::Vector3d::Constant(2.0 * shape.mesh->vertices[7].x()), 20000, rng);
      break;
  }
  for (Eigen::Vector3d& p : points) p = shape.pose * p;
  return points;
}

/// Every shape of every link of `exact` covered by the spheres of its link in `fit`, and every
/// sphere within `fit.reach` of its link's shapes (2,000 points on each sphere's surface).
void CheckRobotFit(const RobotModel& exact, const RobotSphereFit& fit, int budget) {
  ASSERT_NE(fit.model, nullptr);
  std::mt19937_64 rng(7);
  for (int l = 0; l < exact.num_links(); ++l) {
    const Link& shapes = exact.links()[l];
    const Link& spheres = fit.model->links()[l];
    SCOPED_TRACE(shapes.name);
    int kept = 0;
    for (const Shape& s : shapes.collision) kept += s.type == ShapeType::kSphere;
    EXPECT_LE(static_cast<int>(spheres.collision.size()), budget + kept);
    for (const Shape& s : spheres.collision) ASSERT_EQ(s.type, ShapeType::kSphere);
    for (const Shape& shape : shapes.collision) {
      for (const Eigen::Vector3d& p : ShapePoints(shape, rng)) {
        const bool inside = std::any_of(spheres.collision.begin(), spheres.collision.end(), [&](const Shape& s) {
          return (p - s.pose.translation()).norm() <= s.radius;
        });
        ASSERT_TRUE(inside) << "point " << p.transpose() << " of a shape of type " << static_cast<int>(shape.type);
      }
    }
    const double golden = M_PI * (3.0 - std::sqrt(5.0));
    for (const Shape& s : spheres.collision) {
      for (int i = 0; i < 2000; ++i) {
        const double z = 1.0 - 2.0 * (i + 0.5) / 2000, ring = std::sqrt(1.0 - z * z);
        const Eigen::Vector3d p =
            s.pose.translation() + s.radius * Eigen::Vector3d(ring * std::cos(golden * i), ring * std::sin(golden * i), z);
        double nearest = std::numeric_limits<double>::infinity();
        for (const Shape& shape : shapes.collision) nearest = std::min(nearest, ShapeDistance(shape, p));
        ASSERT_LE(nearest, fit.reach + 1e-12) << "point " << p.transpose() << " of a sphere";
      }
    }
  }
}

std::shared_ptr<const RobotModel> PrimitivesRobot() {
  return StarRobot({
      MakeLink("torso", {test::CubeMeshShape(0.03, Pose(0.0, 0.0, 0.5, 0.0, 0.0, 0.3))}),
      MakeLink("upper_arm", {Shape::Cylinder(0.06, 0.2722, Pose(0.1, 0.0, 0.1361, 0.4, 0.0, 0.0))}),
      MakeLink("forearm", {Shape::Cylinder(0.06, 0.2722, Pose(-0.2, 0.3, 0.0, 0.0, 1.2, 0.5))}),
      MakeLink("sonar_ring", {Shape::Cylinder(0.085, 0.01, Pose(0.0, 0.0, 0.8, 0.0, 0.0, 0.0))}),
      MakeLink("hand", {Shape::Capsule(0.04, 0.1, Pose(0.0, 0.05, 0.0, 1.57, 0.0, 0.0)),
                        Shape::Box({0.1, 0.05, 0.02}, Pose(0.0, 0.0, 0.1, 0.0, 0.2, 0.0)),
                        Shape::Sphere(0.03, Pose(0.05, 0.0, 0.0, 0.0, 0.0, 0.0))}),
  });
}

TEST(RobotSpheres, PrimitivesAndMeshesAreCoveredInTheirLinksFrames) {
  const auto robot = PrimitivesRobot();
  RobotSphereOptions options;
  const RobotSphereFit fit = FitRobotSpheres(*robot, options);
  ASSERT_NE(fit.model, nullptr);
  EXPECT_EQ(fit.shapes_fitted, 6);  // the mesh, three cylinders, the capsule and the box; the sphere is kept
  std::printf("[ fit ] %d shapes → %d spheres, reach %.4f m (link '%s'), %.3f s\n", fit.shapes_fitted, fit.spheres,
              fit.reach, fit.reach_link.c_str(), fit.seconds);
  CheckRobotFit(*robot, fit, options.max_spheres_per_link);
  // The kept sphere is as it was; the hand's capsule and box shared its budget (20 each).
  const Link& hand = fit.model->links()[robot->FindLink("hand")];
  EXPECT_LE(hand.collision.size(), 41u);
  // The same cylinder on two links is one fit: the same spheres in each shape's frame.
  const Link& upper = fit.model->links()[robot->FindLink("upper_arm")];
  const Link& fore = fit.model->links()[robot->FindLink("forearm")];
  ASSERT_EQ(upper.collision.size(), fore.collision.size());
  const Eigen::Isometry3d upper_pose = robot->links()[robot->FindLink("upper_arm")].collision[0].pose;
  const Eigen::Isometry3d fore_pose = robot->links()[robot->FindLink("forearm")].collision[0].pose;
  for (std::size_t i = 0; i < upper.collision.size(); ++i) {
    EXPECT_EQ(upper.collision[i].radius, fore.collision[i].radius);
    EXPECT_LT((upper_pose.inverse() * upper.collision[i].pose.translation() -
               fore_pose.inverse() * fore.collision[i].pose.translation())
                  .norm(),
              1e-12);
  }
}

TEST(RobotSpheres, TheFitDoesNotDependOnTheThreads) {
  const auto robot = PrimitivesRobot();
  RobotSphereOptions one, two;
  one.threads = 1;
  two.threads = 2;
  const RobotSphereFit a = FitRobotSpheres(*robot, one), b = FitRobotSpheres(*robot, two);
  EXPECT_EQ(a.reach, b.reach);
  EXPECT_EQ(a.reach_link, b.reach_link);
  ASSERT_EQ(a.spheres, b.spheres);
  for (int l = 0; l < robot->num_links(); ++l) {
    const auto& x = a.model->links()[l].collision;
    const auto& y = b.model->links()[l].collision;
    ASSERT_EQ(x.size(), y.size());
    for (std::size_t i = 0; i < x.size(); ++i) {
      EXPECT_EQ(x[i].radius, y[i].radius);
      EXPECT_EQ(x[i].pose.translation(), y[i].pose.translation());
    }
  }
  RobotSphereOptions bad;
  bad.threads = -1;
  EXPECT_THROW(FitRobotSpheres(*robot, bad), Error);
}

TEST(RobotSpheres, TheBaxterArmWithinOneCentimetre) {
  // The published Baxter URDF's arm: ten cylinders (its collision geometry as written), and a
  // small mesh on the torso so that the robot is fitted.
  const double lengths[] = {0.2722, 0.12, 0.107, 0.273, 0.10, 0.088, 0.272, 0.10, 0.165};
  std::vector<Link> links = {MakeLink("torso", {test::CubeMeshShape(0.005, Eigen::Isometry3d::Identity())})};
  for (std::size_t i = 0; i < std::size(lengths); ++i) {
    links.push_back(MakeLink("arm_" + std::to_string(i), {Shape::Cylinder(0.06, lengths[i], Pose(0, 0, 0.5 * lengths[i], 0, 0, 0))}));
  }
  links.push_back(MakeLink("hand", {Shape::Cylinder(0.04, 0.0464, Pose(0, 0, -0.0232, 0, 0, 0))}));
  const auto robot = StarRobot(links);
  const RobotSphereFit fit = FitRobotSpheres(*robot);
  std::printf("[ fit ] %d shapes → %d spheres, reach %.4f m (link '%s'), %.3f s\n", fit.shapes_fitted, fit.spheres,
              fit.reach, fit.reach_link.c_str(), fit.seconds);
  EXPECT_EQ(fit.shapes_fitted, 11);
  EXPECT_LE(fit.reach, 0.01);
  CheckRobotFit(*robot, fit, RobotSphereOptions().max_spheres_per_link);
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
