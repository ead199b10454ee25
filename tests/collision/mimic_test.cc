// Mimic joints in the collision checker: the fast path's FK against RobotModel's, the lever-arm
// bounds (a dof that drives several joints, a prismatic mimic in between) against measured
// sphere speeds and displacements along straight motions, two fingers driven by one coordinate
// through each other (a self pair whose distance that one coordinate changes), and certified
// motions of examples/robots/dual_arm.urdf against a dense re-check in a scene.

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>

#include <gtest/gtest.h>

#include "../../collision/src/forward_kinematics.h"
#include "chasles/collision/collision_checker.h"
#include "test_util.h"

namespace chasles {
namespace {

Eigen::Isometry3d At(double x, double y, double z) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() << x, y, z;
  return t;
}

Link SphereLink(const std::string& name, std::initializer_list<Eigen::Vector3d> centres, double radius) {
  Link link;
  link.name = name;
  for (const Eigen::Vector3d& c : centres) link.collision.push_back(Shape::Sphere(radius, At(c.x(), c.y(), c.z())));
  return link;
}

Joint MakeJoint(const std::string& name, JointType type, int parent, int child, const Eigen::Isometry3d& origin,
                const Eigen::Vector3d& axis, double lower, double upper) {
  Joint j;
  j.name = name;
  j.type = type;
  j.parent_link = parent;
  j.child_link = child;
  j.origin = origin;
  j.axis = axis;
  j.limits = {lower, upper, 1.0, 0.0};
  return j;
}

/// A chain in which one dof drives several joints: j3 (skew axis) = 2·j2 + 0.1 below j2; j5
/// (revolute) = 10·j4 (prismatic, metres) below j4; j6 (prismatic) = 0.05·j1 + 0.02 between
/// j3 and the revolute j7 (its travel lengthens j7's and the upper joints' lever arms).
std::shared_ptr<const RobotModel> CoupledRobot() {
  using V = Eigen::Vector3d;
  std::vector<Link> links = {
      SphereLink("base", {V(0, 0, 0.05)}, 0.1),
      SphereLink("l1", {V(0, 0, 0.1), V(0, 0, 0.2)}, 0.06),
      SphereLink("l2", {V(0.05, 0, 0), V(0.2, 0.02, 0), V(0.35, 0, 0.01)}, 0.05),
      SphereLink("l3", {V(0.1, 0, 0), V(0.25, -0.03, 0)}, 0.045),
      SphereLink("l4", {V(0.02, 0, 0.03)}, 0.03),
      SphereLink("l5", {V(0.05, 0.04, 0.02), V(0.1, -0.03, 0)}, 0.02),
      SphereLink("l6", {V(0, 0.02, 0.04)}, 0.03),
      SphereLink("l7", {V(0.1, 0.05, 0), V(0.15, 0, 0.02)}, 0.025),
  };
  Eigen::Isometry3d tilted = At(0.0, 0.0, 0.3);
  tilted.linear() = Eigen::AngleAxisd(0.3, V::UnitX()).toRotationMatrix();
  std::vector<Joint> joints = {
      MakeJoint("j1", JointType::kRevolute, 0, 1, At(0, 0, 0.1), V::UnitZ(), -2.0, 2.0),
      MakeJoint("j2", JointType::kRevolute, 1, 2, tilted, V::UnitY(), -1.0, 1.0),
      MakeJoint("j3", JointType::kRevolute, 2, 3, At(0.4, 0, 0), V(0, 1, 1).normalized(), -3.0, 3.0),
      MakeJoint("j4", JointType::kPrismatic, 3, 4, At(0.3, 0, 0), V::UnitX(), 0.0, 0.2),
      MakeJoint("j5", JointType::kRevolute, 4, 5, At(0.1, 0, 0.05), V::UnitX(), -3.0, 3.0),
      MakeJoint("j6", JointType::kPrismatic, 3, 6, At(0.2, 0, 0.05), V(0.2, 0.1, 1).normalized(), -0.5, 0.5),
      MakeJoint("j7", JointType::kRevolute, 6, 7, At(0.1, 0, 0), V::UnitZ(), -3.0, 3.0),
  };
  joints[2].mimic = JointMimic{1, 2.0, 0.1};
  joints[2].limits.velocity = 2.0;  // no faster than j2 allows: no velocity limit lowered
  joints[4].mimic = JointMimic{3, 10.0, 0.0};
  joints[4].limits.velocity = 10.0;
  joints[5].mimic = JointMimic{0, 0.05, 0.02};
  auto robot = RobotModel::FromTree("coupled", std::move(links), std::move(joints));
  EXPECT_EQ(robot->num_dofs(), 4);
  EXPECT_EQ(robot->num_moving_joints(), 7);
  EXPECT_TRUE(robot->load_warnings().empty());  // every mimic fits within its limits
  return robot;
}

std::vector<std::shared_ptr<const RobotModel>> Robots() { return {CoupledRobot(), test::LoadRobot("dual_arm")}; }

TEST(CertifiedMimic, FastPathFkIsTheRobotModelsFkInEveryBuildVariant) {
  std::mt19937_64 rng(3);
  std::vector<Eigen::Isometry3d> poses;
  for (const auto& robot : Robots()) {
    const detail::FkProgram program = detail::BuildFkProgram(*robot);
    std::vector<detail::Frame> base(program.num_links), other(program.num_links);
    for (int i = 0; i < 300; ++i) {
      const Eigen::VectorXd q = test::RandomConfig(*robot, rng);
      detail::ComputeFkBaseline(program, q, base.data());
      robot->ForwardKinematics(q, &poses);
      for (const detail::FkJoint& j : program.joints) {
        const int l = j.child_link;
        for (int r = 0; r < 3; ++r) {
          for (int c = 0; c < 3; ++c) ASSERT_NEAR(base[l].col[c][r], poses[l].linear()(r, c), 1e-14) << robot->name();
          ASSERT_NEAR(base[l].col[3][r], poses[l].translation()[r], 1e-14) << robot->name() << " link " << l;
        }
      }
      for (detail::SimdLevel level : {detail::SimdLevel::kScalar, detail::SimdLevel::kSse2, detail::SimdLevel::kAvx2}) {
        if (!detail::SimdLevelRuns(level)) continue;
        detail::ComputeFk(level, program, q, other.data());
        for (const detail::FkJoint& j : program.joints) {
          for (int c = 0; c < 4; ++c) {
            for (int r = 0; r < 3; ++r) ASSERT_EQ(other[j.child_link].col[c][r], base[j.child_link].col[c][r]);
          }
        }
      }
    }
  }
}

TEST(CertifiedMimic, LeverBoundsEveryDofsSpeedOfEverySphere) {
  // R_ik (SweepBounds of a unit step in dof i) against the speed of sphere k's centre measured
  // by central differences: never below it; and close to it somewhere (not vacuous).
  for (const auto& robot : Robots()) {
    CollisionChecker checker(robot, std::make_shared<Scene>());
    ASSERT_TRUE(checker.certifies_motion()) << robot->name();
    std::vector<Eigen::Vector3d> centres;
    std::vector<int> link_of;
    test::SphereCentres(*robot, &centres, &link_of);
    std::mt19937_64 rng(11);
    std::vector<Eigen::Isometry3d> lo, hi;
    double closest = 0.0;
    const double h = 1e-6;
    for (int trial = 0; trial < 300; ++trial) {
      const Eigen::VectorXd q = test::RandomConfig(*robot, rng);
      for (int i = 0; i < robot->num_dofs(); ++i) {
        const Eigen::VectorXd e = Eigen::VectorXd::Unit(robot->num_dofs(), i);
        const std::vector<double> R = checker.SweepBounds(q, q + e);
        ASSERT_EQ(R.size(), centres.size());
        robot->ForwardKinematics(q - h * e, &lo);
        robot->ForwardKinematics(q + h * e, &hi);
        for (std::size_t k = 0; k < centres.size(); ++k) {
          const double speed = (hi[link_of[k]] * centres[k] - lo[link_of[k]] * centres[k]).norm() / (2.0 * h);
          ASSERT_LE(speed, R[k] * (1.0 + 1e-6) + 1e-8)
              << robot->name() << " dof " << robot->dof_names()[i] << " sphere " << k << " trial " << trial;
          if (R[k] > 0.0) closest = std::max(closest, speed / R[k]);
        }
      }
    }
    EXPECT_GT(closest, 0.9) << robot->name();
  }
}

TEST(CertifiedMimic, SweepBoundHoldsAlongStraightMotions) {
  // Every sphere centre's displacement from a, sampled densely along a → b, is at most s·D_k.
  for (const auto& robot : Robots()) {
    CollisionChecker checker(robot, std::make_shared<Scene>());
    std::vector<Eigen::Vector3d> centres;
    std::vector<int> link_of;
    test::SphereCentres(*robot, &centres, &link_of);
    std::mt19937_64 rng(7);
    std::vector<Eigen::Isometry3d> p0, p1;
    double worst = 0.0;
    for (int seg = 0; seg < 200; ++seg) {
      const Eigen::VectorXd a = test::RandomConfig(*robot, rng);
      Eigen::VectorXd b = test::RandomConfig(*robot, rng);
      if (seg % 2) b = a + 0.05 * (b - a);  // short ones too
      const std::vector<double> D = checker.SweepBounds(a, b);
      ASSERT_EQ(D.size(), centres.size());
      robot->ForwardKinematics(a, &p0);
      const int samples = 200;
      for (int i = 1; i <= samples; ++i) {
        const double s = static_cast<double>(i) / samples;
        robot->ForwardKinematics(a + s * (b - a), &p1);
        for (std::size_t k = 0; k < centres.size(); ++k) {
          const double moved = (p1[link_of[k]] * centres[k] - p0[link_of[k]] * centres[k]).norm();
          ASSERT_LE(moved, s * D[k] + 1e-12) << robot->name() << " sphere " << k << " segment " << seg;
          if (D[k] > 0) worst = std::max(worst, moved / (s * D[k]));
        }
      }
    }
    EXPECT_GT(worst, 0.2) << robot->name();
    std::cout << "[ lever ] " << robot->name() << ": largest displacement / bound = " << worst << "\n";
  }
}

/// A hand with two fingers on one coordinate: finger a at y = +q, finger b (mimic, -1) at
/// y = -q, each a sphere of radius 0.01. They pass through each other at q = 0.
std::shared_ptr<const RobotModel> CrossingFingers() {
  using V = Eigen::Vector3d;
  std::vector<Link> links = {SphereLink("hand", {V(-0.1, 0, 0)}, 0.03), SphereLink("finger_a", {V(0, 0, 0)}, 0.01),
                             SphereLink("finger_b", {V(0, 0, 0)}, 0.01)};
  std::vector<Joint> joints = {MakeJoint("finger_a_joint", JointType::kPrismatic, 0, 1, At(0, 0, 0), V::UnitY(), -0.05, 0.05),
                               MakeJoint("finger_b_joint", JointType::kPrismatic, 0, 2, At(0, 0, 0), V::UnitY(), -0.05, 0.05)};
  joints[1].mimic = JointMimic{0, -1.0, 0.0};
  return RobotModel::FromTree("crossing", std::move(links), std::move(joints));
}

TEST(CertifiedMimic, FingersDrivenThroughEachOtherByOneCoordinateAreNeverCertified) {
  // The one coordinate drives a joint above each finger: it is in both links' chains, but it
  // changes their distance (at twice its rate), so it must count for the self pair.
  const auto robot = CrossingFingers();
  ASSERT_EQ(robot->num_dofs(), 1);
  CollisionChecker checker(robot, std::make_shared<Scene>());
  ASSERT_TRUE(checker.certifies_motion());
  const Eigen::VectorXd open = Eigen::VectorXd::Constant(1, 0.05), crossed = Eigen::VectorXd::Constant(1, -0.05);
  ASSERT_TRUE(checker.IsValid(open));
  ASSERT_TRUE(checker.IsValid(crossed));
  ASSERT_FALSE(checker.IsValid(Eigen::VectorXd::Zero(1)));
  EXPECT_FALSE(checker.IsMotionCertified(open, crossed));
  EXPECT_FALSE(checker.IsMotionCertified(crossed, open));
  EXPECT_FALSE(checker.IsMotionValid(open, crossed, 1e-3));
  // Closing to a gap of 2 mm is free and certified; closing to contact is not.
  const Eigen::VectorXd near = Eigen::VectorXd::Constant(1, 0.011);
  EXPECT_TRUE(checker.IsMotionCertified(open, near));
  EXPECT_FALSE(checker.IsMotionCertified(open, Eigen::VectorXd::Constant(1, 0.0099)));
  // A curve through the crossing (not only straight segments).
  EXPECT_FALSE(checker.IsCurveCertified([](double s, Eigen::VectorXd* q) { *q = Eigen::VectorXd::Constant(1, 0.05 - 0.1 * s); },
                                        Eigen::VectorXd::Constant(1, 0.1)));
}

/// Scenes for the dual arm: a table with a post between the arms and a shelf; a cluttered
/// space in front (boxes and spheres at hand height); no obstacles (self-collisions only).
std::shared_ptr<Scene> DualArmScene(const std::string& name) {
  auto scene = std::make_shared<Scene>();
  if (name == "table") {
    scene->AddObject({"table", Shape::Box({0.6, 1.2, 0.1}, At(0.75, 0.0, 0.4))});
    scene->AddObject({"post", Shape::Cylinder(0.04, 0.6, At(0.55, 0.0, 0.75))});
    scene->AddObject({"shelf", Shape::Box({0.3, 0.3, 0.03}, At(0.5, 0.45, 1.05))});
  } else if (name == "clutter") {
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> x(0.3, 0.9), y(-0.6, 0.6), z(0.4, 1.1);
    for (int i = 0; i < 12; ++i) {
      const std::string id = std::to_string(i);
      if (i % 2) {
        scene->AddObject({"box" + id, Shape::Box({0.08, 0.08, 0.08}, At(x(rng), y(rng), z(rng)))});
      } else {
        scene->AddObject({"ball" + id, Shape::Sphere(0.05, At(x(rng), y(rng), z(rng)))});
      }
    }
  }
  return scene;
}

class CertifiedMimicScenes : public ::testing::TestWithParam<const char*> {};

TEST_P(CertifiedMimicScenes, DualArmCertifiedMotionsAgreeWithADenseCheck) {
  auto robot = test::LoadRobot("dual_arm");
  auto scene = DualArmScene(GetParam());
  CollisionChecker checker(robot, scene);
  ASSERT_TRUE(checker.certifies_motion());
  CollisionOptions wide;
  wide.padding = 0.005;
  CollisionChecker padded(robot, scene, wide);
  std::mt19937_64 rng(13);
  const auto random_valid = [&] {
    for (int i = 0; i < 100000; ++i) {
      const Eigen::VectorXd q = test::RandomConfig(*robot, rng);
      if (checker.IsValid(q)) return q;
    }
    ADD_FAILURE() << "no valid configuration";
    return test::RandomConfig(*robot, rng);
  };
  const int n = robot->num_dofs();
  const auto toward = [&](const Eigen::VectorXd& from, const Eigen::VectorXd& dir, double length) {
    const Eigen::VectorXd to = from + dir * (length / dir.cwiseAbs().maxCoeff());
    return Eigen::VectorXd(to.cwiseMax(robot->lower_limits()).cwiseMin(robot->upper_limits()));
  };
  const auto random_dir = [&] {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Eigen::VectorXd d(n);
    for (int i = 0; i < n; ++i) d[i] = u(rng);
    return d;
  };
  int certified = 0, discrete_invalid = 0, clearly_free = 0, rejected_clearly_free = 0, near_contact = 0;
  const int kSegments = 300;
  for (int seg = 0; seg < kSegments; ++seg) {
    Eigen::VectorXd a = random_valid();
    std::uniform_real_distribution<double> len(0.02, 1.5);
    Eigen::VectorXd b = toward(a, random_dir(), len(rng));
    if (seg % 5 == 0) {  // the grippers alone, over their whole range
      b = a;
      b[6] = 0.04 - a[6];
      b[12] = 0.04 - a[12];
    } else if (seg % 5 >= 3) {
      // Near contact: a colliding state c, bisect a → c to within ~1e-9 of the contact, then a
      // short segment through that point in a random direction (it grazes or clips).
      Eigen::VectorXd c = test::RandomConfig(*robot, rng);
      for (int i = 0; i < 5000 && checker.IsValid(c); ++i) c = test::RandomConfig(*robot, rng);
      if (!checker.IsValid(c)) {
        Eigen::VectorXd lo = a, hi = c;
        for (int i = 0; i < 30; ++i) {
          const Eigen::VectorXd mid = 0.5 * (lo + hi);
          (checker.IsValid(mid) ? lo : hi) = mid;
        }
        const Eigen::VectorXd d = random_dir();
        std::uniform_real_distribution<double> short_len(0.005, 0.3);
        const double l = short_len(rng);
        a = toward(lo, -d, l);
        b = toward(lo, d, l);
        ++near_contact;
      }
    }
    const bool cert = checker.IsMotionCertified(a, b);
    const bool disc = checker.IsMotionValid(a, b, 0.005);
    if (cert) {
      ++certified;
      // Zero tolerance: never certified with a colliding state between the samples.
      ASSERT_TRUE(checker.IsMotionValid(a, b, 1e-4)) << GetParam() << ": certified but colliding, segment " << seg;
    }
    if (!disc) ++discrete_invalid;
    if (disc && padded.IsMotionValid(a, b, 0.001)) {
      ++clearly_free;
      if (!cert) ++rejected_clearly_free;
    }
  }
  std::cout << "[ dual_arm " << GetParam() << " ] " << kSegments << " segments (" << near_contact
            << " through a contact point): certified " << certified << ", discrete-invalid " << discrete_invalid
            << ", clearly free " << clearly_free << " of which rejected " << rejected_clearly_free << "\n";
  EXPECT_GT(certified, kSegments / 5);
  EXPECT_GT(near_contact, kSegments / 5);
  EXPECT_GT(discrete_invalid, kSegments / 20);  // the motions do run into things
  ASSERT_GT(clearly_free, 0);
  EXPECT_LE(rejected_clearly_free, clearly_free / 20);  // and free ones are certified
}

INSTANTIATE_TEST_SUITE_P(Scenes, CertifiedMimicScenes, ::testing::Values("table", "clutter", "empty"));

}  // namespace
}  // namespace chasles
