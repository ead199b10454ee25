// The fast sphere path must give the same answers as the generic FCL path (force_fcl) and as an
// independent brute-force reference built on RobotModel::ForwardKinematics.

#include <cmath>
#include <cstdint>
#include <iostream>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "chasles/collision/collision_checker.h"
#include "test_util.h"
// Internal kernels of the fast path, tested directly.
#include "../../collision/src/forward_kinematics.h"
#include "../../collision/src/primitives.h"
#include "../../collision/src/sin_cos.h"
#include "../../collision/src/sphere_cull.h"

namespace chasles {
namespace {

// Settable through the environment for longer runs.
int NumSamples() {
  const char* env = std::getenv("CHASLES_TEST_SAMPLES");
  return env != nullptr ? std::atoi(env) : 5000;
}

class FastVsFcl : public ::testing::TestWithParam<const char*> {};

TEST_P(FastVsFcl, SameAnswersOnRandomPandaConfigurations) {
  auto panda = test::LoadRobot("panda");
  auto scene = test::LoadScene(std::string("scenes/") + GetParam() + ".json");
  CollisionOptions fcl_options;
  fcl_options.force_fcl = true;
  const CollisionChecker fast(panda, scene);
  const CollisionChecker fcl(panda, scene, fcl_options);
  ASSERT_TRUE(fast.uses_fast_path());
  ASSERT_FALSE(fcl.uses_fast_path());
  std::mt19937_64 rng(2024);
  const int n = NumSamples();
  int valid = 0, near_contact = 0;
  double worst_clearance_error = 0.0;
  for (int i = 0; i < n; ++i) {
    const Eigen::VectorXd q = test::RandomConfig(*panda, rng);
    const bool a = fast.IsValid(q);
    const bool b = fcl.IsValid(q);
    const CollisionResult ca = fast.Check(q);
    const CollisionResult cb = fcl.Check(q);
    const double da = fast.Clearance(q);
    const double db = fcl.Clearance(q);
    worst_clearance_error = std::max(worst_clearance_error, std::abs(da - db));
    EXPECT_NEAR(da, db, 1e-6) << "sample " << i;
    if (a != b || ca.in_collision != cb.in_collision) {
      // Allowed only within 1e-9 of an environment contact, where the two tests' rounding may
      // fall on different sides of "touching".
      ++near_contact;
      EXPECT_LT(db, 1e-9) << "sample " << i << ": fast " << a << " fcl " << b << " (" << ca.link_a << "/"
                          << ca.other << " vs " << cb.link_a << "/" << cb.other << ")";
    }
    EXPECT_EQ(a, !ca.in_collision) << "limits are respected by sampling, so IsValid == !Check";
    valid += a;
  }
  // The scenes are meant to be neither empty nor full around the Panda.
  EXPECT_GT(valid, n / 10);
  EXPECT_LT(valid, n - n / 20);
  EXPECT_LE(near_contact, 2);
  RecordProperty("valid", valid);
  std::cout << GetParam() << ": " << valid << "/" << n << " valid, worst clearance difference "
            << worst_clearance_error << " m\n";
}

INSTANTIATE_TEST_SUITE_P(ExampleScenes, FastVsFcl, ::testing::Values("table", "shelf", "cage", "bin"));

// Distance from a point to a scene primitive (0 inside), written independently of the checker.
double PointDistance(const Shape& s, const Eigen::Vector3d& world) {
  const Eigen::Vector3d l = s.pose.inverse() * world;
  switch (s.type) {
    case ShapeType::kBox:
      return (l.cwiseAbs() - 0.5 * s.size).cwiseMax(0.0).norm();
    case ShapeType::kSphere:
      return std::max(l.norm() - s.radius, 0.0);
    case ShapeType::kCylinder:
      return std::hypot(std::max(std::hypot(l.x(), l.y()) - s.radius, 0.0),
                        std::max(std::abs(l.z()) - 0.5 * s.length, 0.0));
    case ShapeType::kCapsule: {
      const Eigen::Vector3d axis_point(0, 0, std::clamp(l.z(), -0.5 * s.length, 0.5 * s.length));
      return std::max((l - axis_point).norm() - s.radius, 0.0);
    }
    default:
      ADD_FAILURE() << "no meshes in the example scenes";
      return 0;
  }
}

// Padding keeps the robot from the scene, not from itself (MoveIt's link padding): on random
// Panda configurations with no scene, a 2 cm padding changes no self-collision answer on either
// path, while against the table it forbids states an independent check puts within 2 cm.
TEST(Padding, GrowsTheRobotAgainstTheSceneOnly) {
  auto panda = test::LoadRobot("panda");
  auto empty = std::make_shared<Scene>();
  auto table = test::LoadScene("scenes/table.json");
  CollisionOptions padded, padded_fcl, fcl;
  padded.padding = padded_fcl.padding = 0.02;
  padded_fcl.force_fcl = fcl.force_fcl = true;
  const CollisionChecker bare_self(panda, empty), fast_self(panda, empty, padded), fcl_self(panda, empty, padded_fcl);
  const CollisionChecker bare(panda, table, fcl), fast(panda, table, padded), fcl_padded(panda, table, padded_fcl);
  EXPECT_TRUE(fast_self.IsValid(test::PandaReady()));
  EXPECT_TRUE(fcl_self.IsValid(test::PandaReady()));
  std::mt19937_64 rng(31);
  int self_colliding = 0, within_padding = 0;
  for (int i = 0; i < NumSamples() / 5; ++i) {
    const Eigen::VectorXd q = test::RandomConfig(*panda, rng);
    const bool self_free = bare_self.IsValid(q);
    self_colliding += self_free ? 0 : 1;
    EXPECT_EQ(fast_self.IsValid(q), self_free) << "sample " << i;
    EXPECT_EQ(fcl_self.IsValid(q), self_free) << "sample " << i;
    if (!self_free) continue;
    // Against the table: invalid exactly when the bare robot is within the padding of it
    // (the unpadded FCL checker's clearance is the independent reference).
    const double clearance = bare.Clearance(q);
    if (std::abs(clearance - 0.02) < 1e-9) continue;  // rounding at the boundary
    const bool expected = clearance > 0.02;
    within_padding += clearance > 0.0 && clearance <= 0.02 ? 1 : 0;
    EXPECT_EQ(fast.IsValid(q), expected) << "sample " << i << " clearance " << clearance;
    EXPECT_EQ(fcl_padded.IsValid(q), expected) << "sample " << i << " clearance " << clearance;
  }
  EXPECT_GT(self_colliding, 0);  // the premise: self pairs are exercised
  EXPECT_GT(within_padding, 0);  // and so are states the padding alone forbids
}

TEST(FastPath, MatchesABruteForceReferenceBuiltOnRobotFk) {
  auto panda = test::LoadRobot("panda");
  const AllowedCollisionMatrix& acm = panda->allowed_collisions();
  std::mt19937_64 rng(77);
  std::vector<Eigen::Isometry3d> poses;
  for (const char* name : {"table", "shelf", "cage"}) {
    auto scene = test::LoadScene(std::string("scenes/") + name + ".json");
    const CollisionChecker checker(panda, scene);
    int mismatches = 0;
    for (int i = 0; i < 1000; ++i) {
      const Eigen::VectorXd q = test::RandomConfig(*panda, rng);
      panda->ForwardKinematics(q, &poses);
      double clearance = std::numeric_limits<double>::infinity();
      bool self = false;
      for (int l = 0; l < panda->num_links(); ++l) {
        for (const Shape& s : panda->links()[l].collision) {
          const Eigen::Vector3d c = poses[l] * s.pose.translation();
          for (const SceneObject& o : scene->objects()) {
            clearance = std::min(clearance, PointDistance(o.shape, c) - s.radius);
          }
          for (int m = l + 1; m < panda->num_links(); ++m) {
            if (acm.IsAllowed(l, m)) continue;
            for (const Shape& t : panda->links()[m].collision) {
              const Eigen::Vector3d d = poses[m] * t.pose.translation();
              self = self || (c - d).norm() <= s.radius + t.radius;
            }
          }
        }
      }
      const double got = checker.Clearance(q);
      EXPECT_NEAR(got, std::max(clearance, 0.0), 1e-9) << name << " sample " << i;
      const bool reference_valid = clearance > 1e-12 && !self;
      if (std::abs(clearance) > 1e-9 && checker.IsValid(q) != reference_valid) ++mismatches;
    }
    EXPECT_EQ(mismatches, 0) << name;
  }
}

// A robot whose joints take every branch of the fast path's FK: revolute about +x, −y, −z and
// a skew axis, prismatic along a skew axis, fixed joints with rotated origins, a link without
// geometry in the middle of the chain and a tool link without geometry at its end.
std::shared_ptr<const RobotModel> EveryAxisRobot() {
  const auto origin = [](double x, double y, double z, double roll, double pitch, double yaw) {
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                  Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                     .toRotationMatrix();
    t.translation() << x, y, z;
    return t;
  };
  const auto at = [](double x, double y, double z) {
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.translation() << x, y, z;
    return t;
  };
  std::vector<Link> links(8);
  const char* names[] = {"base", "l1", "l2_bare", "l3", "l4", "l5", "l6", "tool"};
  for (int i = 0; i < 8; ++i) {
    links[i].name = names[i];
    links[i].parent_joint = i - 1;
  }
  links[0].collision = {Shape::Sphere(0.05, at(0.1, 0, 0.05))};
  links[1].collision = {Shape::Sphere(0.04, at(0, 0.1, 0.2)), Shape::Sphere(0.03, at(0.05, 0, 0.3))};
  links[3].collision = {Shape::Sphere(0.04, at(0.2, 0.05, 0)), Shape::Sphere(0.02, at(0, 0, 0.1))};
  links[4].collision = {Shape::Sphere(0.03, at(0.1, 0, 0))};
  links[5].collision = {Shape::Sphere(0.03, at(0, 0.1, 0.05))};
  links[6].collision = {Shape::Sphere(0.02, at(0.05, 0.05, 0.05)), Shape::Sphere(0.02, at(-0.05, 0, 0.1))};
  struct Spec {
    JointType type;
    Eigen::Vector3d axis;
    Eigen::Isometry3d origin;
  };
  const std::vector<Spec> specs = {
      {JointType::kRevolute, Eigen::Vector3d::UnitX(), origin(0, 0, 0.3, 0.3, -0.2, 0.1)},
      {JointType::kRevolute, -Eigen::Vector3d::UnitY(), origin(0.1, 0.2, 0.3, 0, 0, 0)},
      {JointType::kRevolute, Eigen::Vector3d(0.3, 0.5, 0.8), origin(0, 0, 0.2, 1.0, 0.5, -0.4)},
      {JointType::kPrismatic, Eigen::Vector3d(0, 1, 1), origin(0.2, 0, 0, 0, 0.7, 0)},
      {JointType::kRevolute, -Eigen::Vector3d::UnitZ(), origin(0, 0.1, 0.1, -1.2, 0, 0.3)},
      {JointType::kFixed, Eigen::Vector3d::UnitZ(), origin(0.05, 0, 0.1, 0.2, 0.3, 0.4)},
      {JointType::kFixed, Eigen::Vector3d::UnitZ(), at(0, 0, 0.1)},
  };
  std::vector<Joint> joints;
  int dof = 0;
  for (int i = 0; i < 7; ++i) {
    Joint j;
    j.name = "j" + std::to_string(i + 1);
    j.type = specs[i].type;
    j.parent_link = i;
    j.child_link = i + 1;
    j.axis = specs[i].axis.normalized();
    j.origin = specs[i].origin;
    if (j.type != JointType::kFixed) {
      j.limits = j.type == JointType::kPrismatic ? JointLimits{-0.3, 0.3, 1.0, 0.0} : JointLimits{-7.0, 7.0, 1.0, 0.0};
      j.dof = dof++;
    }
    joints.push_back(j);
  }
  return RobotModel::FromTree("every_axis", links, joints);
}

TEST(FastPath, ForwardKinematicsMatchesTheRobotModelForEveryKindOfJoint) {
  auto robot = EveryAxisRobot();
  auto scene = std::make_shared<Scene>();
  std::mt19937_64 rng(31);
  std::uniform_real_distribution<double> u(-0.8, 0.8);
  for (int i = 0; i < 6; ++i) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() << u(rng), u(rng), u(rng) + 0.4;
    scene->AddObject({"ball" + std::to_string(i), Shape::Sphere(0.01, pose)});
  }
  const CollisionChecker checker(robot, scene);
  ASSERT_TRUE(checker.uses_fast_path());
  std::vector<Eigen::Isometry3d> poses;
  for (int i = 0; i < 2000; ++i) {
    const Eigen::VectorXd q = test::RandomConfig(*robot, rng);
    robot->ForwardKinematics(q, &poses);
    double clearance = std::numeric_limits<double>::infinity();
    for (int l = 0; l < robot->num_links(); ++l) {
      for (const Shape& s : robot->links()[l].collision) {
        const Eigen::Vector3d c = poses[l] * s.pose.translation();
        for (const SceneObject& o : scene->objects()) {
          clearance = std::min(clearance, (c - o.shape.pose.translation()).norm() - s.radius - o.shape.radius);
        }
      }
    }
    ASSERT_NEAR(checker.Clearance(q), std::max(clearance, 0.0), 1e-12) << "sample " << i;
  }
}

TEST(SphereCull, EveryKernelGivesTheScalarKernelsBits) {
  using detail::SimdLevel;
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> coord(-1.0, 1.0), radius(0.0, 0.5);
  int kernels_run = 0;
  for (SimdLevel kernel : {SimdLevel::kScalar, SimdLevel::kSse2, SimdLevel::kAvx2}) {
    if (!detail::SimdLevelRuns(kernel)) continue;
    ++kernels_run;
    for (std::size_t n : {1u, 2u, 3u, 4u, 5u, 9u, 31u, 63u, 64u}) {
      const std::size_t padded = detail::CullPadded(n);
      std::vector<double> x(padded, std::numeric_limits<double>::infinity()), y = x, z = x, r(padded, 0.0);
      for (std::size_t i = 0; i < n; ++i) {
        x[i] = coord(rng);
        y[i] = coord(rng);
        z[i] = coord(rng);
        r[i] = radius(rng);
      }
      // Queries: random ones, and exactly touching ones (3-4-5 triangles: d² = rr² exactly).
      std::vector<double> qx, qy, qz, qr;
      for (int j = 0; j < 20; ++j) {
        qx.push_back(coord(rng));
        qy.push_back(coord(rng));
        qz.push_back(coord(rng));
        qr.push_back(radius(rng));
      }
      x[0] = 0.0, y[0] = 0.0, z[0] = 0.0, r[0] = 0.25;
      for (double scale : {1.0, -1.0}) {
        qx.push_back(0.375 * scale);  // |(0.375, 0.5, 0)| = 0.625 = 0.25 + 0.375
        qy.push_back(0.5);
        qz.push_back(0.0);
        qr.push_back(0.375);
        qx.push_back(0.375 * scale);  // 2^-20 short of touching
        qy.push_back(0.5);
        qz.push_back(0.0);
        qr.push_back(0.375 - 0x1p-20);
      }
      const detail::CullSpheres spheres{x.data(), y.data(), z.data(), r.data(), n};
      std::vector<std::uint64_t> want(qx.size()), got(qx.size());
      detail::OverlapMasksScalar(spheres, qx.data(), qy.data(), qz.data(), qr.data(), qx.size(), want.data());
      detail::OverlapMasks(kernel, spheres, qx.data(), qy.data(), qz.data(), qr.data(), qx.size(), got.data());
      for (std::size_t j = 0; j < qx.size(); ++j) {
        ASSERT_EQ(got[j], want[j]) << "kernel " << static_cast<int>(kernel) << " n " << n << " query " << j;
        if (n < 64) {
          ASSERT_EQ(want[j] >> n, 0u) << "no bit past n";
        }
        for (std::size_t i = 0; i < n; ++i) {  // the scalar bits are the plain expression
          const double dx = x[i] - qx[j], dy = y[i] - qy[j], dz = z[i] - qz[j], rr = r[i] + qr[j];
          ASSERT_EQ((want[j] >> i) & 1, static_cast<std::uint64_t>(dx * dx + dy * dy + dz * dz <= rr * rr));
        }
      }
      ASSERT_EQ(want[20] & 1, 1u);  // touching counts
      ASSERT_EQ(want[21] & 1, 0u);
    }
  }
  EXPECT_GE(kernels_run, 1);
  std::cout << "[ cull ] kernels compared with the scalar one: " << kernels_run - 1
            << (detail::SimdLevelRuns(SimdLevel::kAvx2) ? " (AVX2 available)\n" : " (no AVX2 on this CPU)\n");
}

TEST(FastPathFk, EveryBuildVariantGivesTheSameBitsAndTheRobotModelsFrames) {
  using detail::SimdLevel;
  std::mt19937_64 rng(4);
  std::vector<Eigen::Isometry3d> poses;
  for (const auto& robot : {test::LoadRobot("panda"), EveryAxisRobot()}) {
    const detail::FkProgram program = detail::BuildFkProgram(*robot);
    std::vector<bool> computed(robot->num_links(), false);
    computed[program.root] = true;
    for (const detail::FkJoint& j : program.joints) computed[j.child_link] = true;
    std::vector<detail::Frame> base(program.num_links), other(program.num_links);
    for (int i = 0; i < 500; ++i) {
      const Eigen::VectorXd q = test::RandomConfig(*robot, rng);
      detail::ComputeFkBaseline(program, q, base.data());
      robot->ForwardKinematics(q, &poses);
      for (int l = 0; l < robot->num_links(); ++l) {
        if (!computed[l]) continue;
        for (int r = 0; r < 3; ++r) {
          for (int c = 0; c < 3; ++c) ASSERT_NEAR(base[l].col[c][r], poses[l].linear()(r, c), 1e-14) << robot->name();
          ASSERT_NEAR(base[l].col[3][r], poses[l].translation()[r], 1e-14) << robot->name();
        }
      }
      for (SimdLevel level : {SimdLevel::kScalar, SimdLevel::kSse2, SimdLevel::kAvx2}) {
        if (!detail::SimdLevelRuns(level)) continue;
        detail::ComputeFk(level, program, q, other.data());
        for (int l = 0; l < robot->num_links(); ++l) {
          if (!computed[l]) continue;
          for (int c = 0; c < 4; ++c) {
            for (int r = 0; r < 3; ++r) {
              ASSERT_EQ(other[l].col[c][r], base[l].col[c][r]) << robot->name() << " level " << static_cast<int>(level);
            }
          }
        }
      }
    }
    // Every link with geometry has a frame; a bare tool link at the end of a chain has none.
    for (int l = 0; l < robot->num_links(); ++l) {
      if (!robot->links()[l].collision.empty()) {
        EXPECT_TRUE(computed[l]) << robot->links()[l].name;
      }
    }
    if (robot->name() == "every_axis") {
      EXPECT_FALSE(computed[robot->FindLink("tool")]);
    }
  }
}

TEST(SphereDistances, EveryVariantGivesSphereDistancesBitsForEveryPrimitiveKind) {
  using detail::SimdLevel;
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> u(-1.0, 1.0), pos(0.01, 0.6);
  int compared = 0;
  for (int kind : {detail::kPrimSphere, detail::kPrimBox, detail::kPrimCylinder, detail::kPrimCapsule}) {
    for (int trial = 0; trial < 50; ++trial) {
      detail::Prim o{};
      o.kind = kind;
      const Eigen::Matrix3d rot = Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng)).normalized().toRotationMatrix();
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) o.rt[3 * i + j] = rot(j, i);
        o.p[i] = u(rng);
      }
      o.a = pos(rng);
      o.b = pos(rng);
      o.c = pos(rng);
      const std::size_t n = 1 + trial % 13;
      std::vector<double> x(detail::CullPadded(n)), y(x.size()), z(x.size()), r(x.size());
      for (std::size_t i = 0; i < n; ++i) {
        x[i] = 1.5 * u(rng);
        y[i] = 1.5 * u(rng);
        z[i] = 1.5 * u(rng);
        r[i] = 0.1 * pos(rng);
      }
      // Points on the primitive's axes and at its centre: zeros (and −0) in the local frame.
      x[0] = o.p[0], y[0] = o.p[1], z[0] = o.p[2];
      if (trial % 5 == 4) x[n - 1] = std::nan("");  // NaN propagates as in SphereDistance
      for (SimdLevel level : {SimdLevel::kScalar, SimdLevel::kSse2, SimdLevel::kAvx2}) {
        if (!detail::SimdLevelRuns(level)) continue;
        std::vector<double> out(x.size());
        detail::SphereDistances(level, o, x.data(), y.data(), z.data(), r.data(), n, out.data());
        for (std::size_t i = 0; i < n; ++i) {
          const double centre[3] = {x[i], y[i], z[i]};
          const double want = detail::SphereDistance(o, centre, r[i]);
          if (std::isnan(want)) {
            ASSERT_TRUE(std::isnan(out[i])) << "kind " << kind << " level " << static_cast<int>(level);
          } else {
            ASSERT_EQ(out[i], want) << "kind " << kind << " level " << static_cast<int>(level) << " i " << i;
          }
          ++compared;
        }
      }
    }
  }
  EXPECT_GT(compared, 1000);
}

TEST(SinCos, WithinTwoUlpOfLibmAndExactlyLibmBeyondItsRange) {
  std::mt19937_64 rng(12);
  for (double range : {1e-8, 0.7, 3.2, 7.0, 100.0, 1e5}) {
    std::uniform_real_distribution<double> u(-range, range);
    double worst = 0.0;
    for (int i = 0; i < 200000; ++i) {
      const double x = u(rng);
      double s, c;
      detail::SinCos(x, &s, &c);
      worst = std::max({worst, std::abs(s - std::sin(x)), std::abs(c - std::cos(x))});
    }
    EXPECT_LE(worst, 2.3e-16) << "|x| <= " << range;
  }
  // Quadrant boundaries and their neighbours.
  for (int k = -8; k <= 8; ++k) {
    for (double dx : {-1e-9, 0.0, 1e-9}) {
      const double x = k * std::acos(-1.0) / 4 + dx;
      double s, c;
      detail::SinCos(x, &s, &c);
      EXPECT_NEAR(s, std::sin(x), 2.3e-16) << x;
      EXPECT_NEAR(c, std::cos(x), 2.3e-16) << x;
    }
  }
  for (double x : {1e5 + 1.0, -3e7, 1e300}) {
    double s, c;
    detail::SinCos(x, &s, &c);
    EXPECT_EQ(s, std::sin(x));
    EXPECT_EQ(c, std::cos(x));
  }
  double s, c;
  detail::SinCos(std::nan(""), &s, &c);
  EXPECT_TRUE(std::isnan(s) && std::isnan(c));
}

TEST(OctoMapScene, FastAndFclPathsAgreeAndTheMapIsConservative) {
  auto panda = test::LoadRobot("panda");
  auto octo = test::LoadScene("scenes/shelf_octomap.json");
  auto shelf = test::LoadScene("scenes/shelf.json");
  CollisionOptions fcl_options;
  fcl_options.force_fcl = true;
  const CollisionChecker fast(panda, octo);
  const CollisionChecker fcl(panda, octo, fcl_options);
  const CollisionChecker primitives(panda, shelf);
  ASSERT_TRUE(fast.uses_fast_path());
  std::mt19937_64 rng(31);
  int both_valid = 0, only_primitives_valid = 0;
  for (int i = 0; i < 1000; ++i) {
    const Eigen::VectorXd q = test::RandomConfig(*panda, rng);
    const bool a = fast.IsValid(q);
    EXPECT_EQ(a, fcl.IsValid(q)) << "sample " << i;
    if (i % 10 == 0) {
      EXPECT_NEAR(fast.Clearance(q), fcl.Clearance(q), 1e-6) << "sample " << i;
    }
    // The map covers every primitive, so a configuration valid against the map is valid
    // against the primitives.
    const bool p = primitives.IsValid(q);
    if (a) {
      EXPECT_TRUE(p) << "sample " << i;
    }
    both_valid += a && p;
    only_primitives_valid += p && !a;
  }
  EXPECT_GT(both_valid, 100);
  std::cout << "octomap: " << both_valid << " valid in both, " << only_primitives_valid
            << " valid only against the primitives (the map is up to a voxel larger)\n";
}

}  // namespace
}  // namespace chasles
