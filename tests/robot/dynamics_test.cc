// Tests of robot/dynamics.h: the planar 2R against its closed form (Lynch & Park §8.1), and on
// the example robots plus a random branching tree with prismatic and fixed joints the identities
// RNEA = M q̈ + c + g, c = C q̇, Ṁ − 2C skew, g = ∂V/∂q, ForwardDynamics ∘ InverseDynamics = id,
// energy conservation of a torque-free simulation, and the friction/armature terms.
// Seeded: CHASLES_TEST_SEED, CHASLES_TEST_CASES.

#include <cmath>
#include <cstdlib>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include "chasles/robot/dynamics.h"
#include "chasles/robot/robot_model.h"
#include "test_util.h"

namespace chasles {
namespace {

using Eigen::MatrixXd;
using Eigen::Vector3d;
using Eigen::VectorXd;
using testing::LoadExampleRobot;

unsigned Seed() {
  const char* s = std::getenv("CHASLES_TEST_SEED");
  return s != nullptr ? static_cast<unsigned>(std::strtoul(s, nullptr, 10)) : 20240611u;
}
int Cases(int fallback) {
  const char* s = std::getenv("CHASLES_TEST_CASES");
  return s != nullptr ? std::max(1, std::atoi(s)) : fallback;
}

VectorXd Uniform(std::mt19937& rng, int n, double lo, double hi) {
  std::uniform_real_distribution<double> u(lo, hi);
  VectorXd v(n);
  for (int i = 0; i < n; ++i) v[i] = u(rng);
  return v;
}

/// Random configuration within the joint limits (continuous or ±2π limits clipped to ±π).
VectorXd RandomQ(const RobotModel& robot, std::mt19937& rng) {
  VectorXd q(robot.num_dofs());
  for (int i = 0; i < robot.num_dofs(); ++i) {
    const double lo = std::max(robot.lower_limits()[i], -M_PI);
    const double hi = std::min(robot.upper_limits()[i], M_PI);
    q[i] = std::uniform_real_distribution<double>(lo, hi)(rng);
  }
  return q;
}

/// A copy of `robot` with every joint's damping, friction and armature replaced.
std::shared_ptr<const RobotModel> WithJointTerms(const RobotModel& robot, double damping, double friction,
                                                 double armature) {
  std::vector<Joint> joints = robot.joints();
  for (Joint& j : joints) {
    if (j.dof < 0) continue;
    j.damping = damping * (1 + j.dof);
    j.friction = friction * (1 + j.dof);
    j.armature = armature * (1 + j.dof);
  }
  return RobotModel::FromTree(robot.name(), robot.links(), joints);
}

/// A random branching tree: revolute, prismatic and fixed joints, random origins, axes and
/// physically valid inertias.
std::shared_ptr<const RobotModel> RandomTree(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto random_unit = [&] { Vector3d v(u(rng), u(rng), u(rng)); return Vector3d(v.normalized()); };
  auto random_inertial = [&] {
    Inertial in;
    in.mass = 0.5 + std::abs(u(rng));
    in.com = 0.2 * Vector3d(u(rng), u(rng), u(rng));
    const Vector3d d(0.01 + 0.02 * std::abs(u(rng)), 0.01 + 0.02 * std::abs(u(rng)), 0.01 + 0.02 * std::abs(u(rng)));
    // Principal moments from a box-like body (triangle inequalities hold), random orientation.
    const Vector3d moments(d.y() + d.z(), d.x() + d.z(), d.x() + d.y());
    const Eigen::Matrix3d R = Eigen::AngleAxisd(M_PI * u(rng), random_unit()).toRotationMatrix();
    in.inertia = R * moments.asDiagonal() * R.transpose();
    return in;
  };
  // parent link of each joint and its type; link i + 1 is the child of joint i.
  const std::vector<std::pair<int, JointType>> spec = {
      {0, JointType::kRevolute}, {1, JointType::kPrismatic}, {2, JointType::kFixed},
      {3, JointType::kRevolute}, {1, JointType::kRevolute},  {5, JointType::kContinuous},
      {4, JointType::kRevolute}};
  std::vector<Link> links(spec.size() + 1);
  std::vector<Joint> joints(spec.size());
  links[0].name = "base";
  for (size_t i = 0; i < spec.size(); ++i) {
    Link& link = links[i + 1];
    link.name = "link" + std::to_string(i + 1);
    link.parent_joint = static_cast<int>(i);
    link.inertial = random_inertial();
    Joint& j = joints[i];
    j.name = "joint" + std::to_string(i + 1);
    j.type = spec[i].second;
    j.parent_link = spec[i].first;
    j.child_link = static_cast<int>(i + 1);
    j.origin = Eigen::Isometry3d::Identity();
    j.origin.linear() = Eigen::AngleAxisd(M_PI * u(rng), random_unit()).toRotationMatrix();
    j.origin.translation() = 0.3 * Vector3d(u(rng), u(rng), u(rng));
    j.axis = random_unit();
    j.limits = {j.type == JointType::kPrismatic ? -0.5 : -M_PI, j.type == JointType::kPrismatic ? 0.5 : M_PI, 1.0, 10.0};
  }
  return RobotModel::FromTree("random_tree", links, joints);
}

/// Potential energy −Σ m gᵀ p_com in the base frame.
double PotentialEnergy(const RobotModel& robot, const VectorXd& q, const Vector3d& gravity) {
  std::vector<Eigen::Isometry3d> poses;
  robot.ForwardKinematics(q, &poses);
  double v = 0.0;
  for (int l = 0; l < robot.num_links(); ++l) {
    const auto& in = robot.links()[l].inertial;
    if (in) v -= in->mass * gravity.dot(poses[l] * in->com);
  }
  return v;
}

struct Case {
  std::string name;
  std::shared_ptr<const RobotModel> robot;
};

std::vector<Case> Robots() {
  std::mt19937 rng(Seed());
  return {{"planar_2r", LoadExampleRobot("planar_2r")},
          {"ur5", LoadExampleRobot("ur5")},
          {"panda", LoadExampleRobot("panda")},
          {"random_tree", RandomTree(rng)}};
}

double RelErr(const VectorXd& a, const VectorXd& b) { return (a - b).norm() / std::max(1.0, b.norm()); }
double RelErr(const MatrixXd& a, const MatrixXd& b) { return (a - b).norm() / std::max(1.0, b.norm()); }

// --- planar 2R closed form ---------------------------------------------------------------

TEST(DynamicsTest, Planar2RMatchesClosedForm) {
  auto robot = LoadExampleRobot("planar_2r");
  ASSERT_TRUE(HasInertia(*robot));
  // Uniform rods (examples/robots/planar_2r.urdf): m1 = 1, L1 = 1, m2 = 0.8, L2 = 0.8, radius 0.05.
  const double m1 = 1.0, L1 = 1.0, m2 = 0.8, L2 = 0.8, rad = 0.05;
  const double r1 = L1 / 2, r2 = L2 / 2;
  const double I1 = m1 * (3 * rad * rad + L1 * L1) / 12, I2 = m2 * (3 * rad * rad + L2 * L2) / 12;
  const double grav = 9.81;
  DynamicsOptions in_plane;
  in_plane.gravity = Vector3d(0, -grav, 0);  // Modern Robotics §8.1: gravity along −y
  in_plane.include_friction = false;
  std::mt19937 rng(Seed());
  for (int t = 0; t < Cases(200); ++t) {
    const VectorXd q = Uniform(rng, 2, -M_PI, M_PI), qd = Uniform(rng, 2, -3, 3), qdd = Uniform(rng, 2, -5, 5);
    const double c2 = std::cos(q[1]), s2 = std::sin(q[1]), c1 = std::cos(q[0]), c12 = std::cos(q[0] + q[1]);
    MatrixXd M(2, 2);
    M(0, 0) = I1 + I2 + m1 * r1 * r1 + m2 * (L1 * L1 + r2 * r2 + 2 * L1 * r2 * c2);
    M(0, 1) = M(1, 0) = I2 + m2 * (r2 * r2 + L1 * r2 * c2);
    M(1, 1) = I2 + m2 * r2 * r2;
    VectorXd c(2);
    c << -m2 * L1 * r2 * s2 * (2 * qd[0] * qd[1] + qd[1] * qd[1]), m2 * L1 * r2 * s2 * qd[0] * qd[0];
    VectorXd g(2);
    g << (m1 * r1 + m2 * L1) * grav * c1 + m2 * r2 * grav * c12, m2 * r2 * grav * c12;
    // Closed-form Christoffel C (Lynch & Park): h = −m2 L1 r2 s2.
    const double h = -m2 * L1 * r2 * s2;
    MatrixXd C(2, 2);
    C << h * qd[1], h * (qd[0] + qd[1]), -h * qd[0], 0.0;

    EXPECT_LT(RelErr(MassMatrix(*robot, q), M), 1e-12) << "q = " << q.transpose();
    EXPECT_LT(RelErr(CoriolisTorques(*robot, q, qd), c), 1e-12);
    EXPECT_LT(RelErr(CoriolisMatrix(*robot, q, qd), C), 1e-12);
    EXPECT_LT(RelErr(GravityTorques(*robot, q, in_plane.gravity), g), 1e-12);
    EXPECT_LT(RelErr(InverseDynamics(*robot, q, qd, qdd, in_plane), VectorXd(M * qdd + c + g)), 1e-12);
    // Default gravity (−z) is normal to the plane of motion: no gravity torque.
    EXPECT_LT(GravityTorques(*robot, q).norm(), 1e-12);
  }
}

// --- identities on every robot ---------------------------------------------------------

TEST(DynamicsTest, MassMatrixIsSymmetricPositiveDefinite) {
  for (const Case& rc : Robots()) {
    SCOPED_TRACE(rc.name);
    std::mt19937 rng(Seed());
    for (int t = 0; t < Cases(100); ++t) {
      const VectorXd q = RandomQ(*rc.robot, rng);
      const MatrixXd M = MassMatrix(*rc.robot, q);
      ASSERT_EQ(M.rows(), rc.robot->num_dofs());
      EXPECT_LT((M - M.transpose()).norm(), 1e-12 * M.norm());
      Eigen::SelfAdjointEigenSolver<MatrixXd> eig(M);
      EXPECT_GT(eig.eigenvalues().minCoeff(), 1e-8) << "q = " << q.transpose();
    }
  }
}

TEST(DynamicsTest, InverseDynamicsEqualsMassMatrixPlusBiasTerms) {
  for (const Case& rc : Robots()) {
    SCOPED_TRACE(rc.name);
    const RobotModel& robot = *rc.robot;
    const int n = robot.num_dofs();
    std::mt19937 rng(Seed() + 1);
    DynamicsOptions options;
    options.include_friction = false;
    for (int t = 0; t < Cases(100); ++t) {
      const VectorXd q = RandomQ(robot, rng), qd = Uniform(rng, n, -2, 2), qdd = Uniform(rng, n, -4, 4);
      options.gravity = Uniform(rng, 3, -10, 10);
      const MatrixXd M = MassMatrix(robot, q);
      const VectorXd c = CoriolisTorques(robot, q, qd);
      const VectorXd g = GravityTorques(robot, q, options.gravity);
      const VectorXd tau = InverseDynamics(robot, q, qd, qdd, options);
      EXPECT_LT(RelErr(tau, VectorXd(M * qdd + c + g)), 1e-9) << "q = " << q.transpose();
      // Gravity torques are RNEA at rest; Coriolis torques are RNEA without gravity or q̈.
      EXPECT_LT(RelErr(g, InverseDynamics(robot, q, VectorXd::Zero(n), VectorXd::Zero(n), options)), 1e-12);
      DynamicsOptions no_gravity = options;
      no_gravity.gravity.setZero();
      EXPECT_LT(RelErr(c, InverseDynamics(robot, q, qd, VectorXd::Zero(n), no_gravity)), 1e-12);
      // M's column k is the torque for a unit q̈_k at rest without gravity.
      const int k = t % n;
      EXPECT_LT(RelErr(VectorXd(M.col(k)), InverseDynamics(robot, q, VectorXd::Zero(n), VectorXd::Unit(n, k), no_gravity)),
                1e-12);
    }
  }
}

TEST(DynamicsTest, PathTorqueCoefficientsAreTheMassMatrixCoriolisAndGravityTerms) {
  for (const Case& rc : Robots()) {
    SCOPED_TRACE(rc.name);
    const RobotModel& robot = *rc.robot;
    const int n = robot.num_dofs();
    std::mt19937 rng(Seed() + 7);
    DynamicsOptions rigid;
    rigid.include_friction = false;
    for (int t = 0; t < Cases(50); ++t) {
      const VectorXd q = RandomQ(robot, rng), d1 = Uniform(rng, n, -1, 1), d2 = Uniform(rng, n, -3, 3);
      rigid.gravity = Uniform(rng, 3, -10, 10);
      const PathTorque path = PathTorqueCoefficients(robot, q, d1, d2, rigid.gravity);
      // Against the composite-rigid-body mass matrix and the separate recursions.
      const MatrixXd M = MassMatrix(robot, q);
      EXPECT_LT(RelErr(path.a, VectorXd(M * d1)), 1e-12);
      EXPECT_LT(RelErr(path.b, VectorXd(M * d2 + CoriolisTorques(robot, q, d1))), 1e-12);
      EXPECT_LT(RelErr(path.c, GravityTorques(robot, q, rigid.gravity)), 1e-12);
      // And τ = a s̈ + b ṡ² + c is InverseDynamics at q̇ = q′ṡ, q̈ = q′s̈ + q″ṡ².
      const double sd = std::uniform_real_distribution<double>(0.0, 2.0)(rng);
      const double sdd = std::uniform_real_distribution<double>(-5.0, 5.0)(rng);
      const VectorXd tau = InverseDynamics(robot, q, d1 * sd, d1 * sdd + d2 * (sd * sd), rigid);
      EXPECT_LT(RelErr(VectorXd(path.a * sdd + path.b * (sd * sd) + path.c), tau), 1e-12);
    }
  }
}

TEST(DynamicsTest, CoriolisMatrixIsChristoffelConsistent) {
  for (const Case& rc : Robots()) {
    SCOPED_TRACE(rc.name);
    const RobotModel& robot = *rc.robot;
    const int n = robot.num_dofs();
    std::mt19937 rng(Seed() + 2);
    for (int t = 0; t < Cases(50); ++t) {
      const VectorXd q = RandomQ(robot, rng), qd = Uniform(rng, n, -2, 2);
      const MatrixXd C = CoriolisMatrix(robot, q, qd);
      const VectorXd c = CoriolisTorques(robot, q, qd);
      EXPECT_LT(RelErr(VectorXd(C * qd), c), 1e-9);
      // Ṁ by central differences along q̇.
      const double h = 1e-6;
      const MatrixXd Mdot = (MassMatrix(robot, q + h * qd) - MassMatrix(robot, q - h * qd)) / (2 * h);
      const MatrixXd N = Mdot - 2 * C;
      EXPECT_LT((N + N.transpose()).norm(), 1e-6 * std::max(1.0, Mdot.norm())) << "q = " << q.transpose();
      // Christoffel symbols are symmetric in their last two indices: C(q, x) y = C(q, y) x.
      const VectorXd x = Uniform(rng, n, -1, 1), y = Uniform(rng, n, -1, 1);
      EXPECT_LT(RelErr(VectorXd(CoriolisMatrix(robot, q, x) * y), VectorXd(CoriolisMatrix(robot, q, y) * x)), 1e-9);
    }
  }
}

TEST(DynamicsTest, GravityTorquesAreThePotentialGradient) {
  for (const Case& rc : Robots()) {
    SCOPED_TRACE(rc.name);
    const RobotModel& robot = *rc.robot;
    const int n = robot.num_dofs();
    std::mt19937 rng(Seed() + 3);
    for (int t = 0; t < Cases(30); ++t) {
      const VectorXd q = RandomQ(robot, rng);
      const Vector3d gravity = Uniform(rng, 3, -10, 10);
      VectorXd grad(n);
      const double h = 1e-6;
      for (int i = 0; i < n; ++i) {
        grad[i] = (PotentialEnergy(robot, q + h * VectorXd::Unit(n, i), gravity) -
                   PotentialEnergy(robot, q - h * VectorXd::Unit(n, i), gravity)) / (2 * h);
      }
      EXPECT_LT(RelErr(GravityTorques(robot, q, gravity), grad), 1e-7);
    }
  }
}

TEST(DynamicsTest, ForwardDynamicsInvertsInverseDynamics) {
  for (const Case& rc : Robots()) {
    SCOPED_TRACE(rc.name);
    auto robot = WithJointTerms(*rc.robot, 0.3, 0.2, 0.05);
    const int n = robot->num_dofs();
    std::mt19937 rng(Seed() + 4);
    for (int t = 0; t < Cases(100); ++t) {
      DynamicsOptions options;
      options.include_friction = t % 2 == 0;
      const VectorXd q = RandomQ(*robot, rng), qd = Uniform(rng, n, -2, 2), qdd = Uniform(rng, n, -4, 4);
      const VectorXd tau = InverseDynamics(*robot, q, qd, qdd, options);
      EXPECT_LT(RelErr(ForwardDynamics(*robot, q, qd, tau, options), qdd), 1e-9);
      const VectorXd tau2 = Uniform(rng, n, -20, 20);
      EXPECT_LT(RelErr(InverseDynamics(*robot, q, qd, ForwardDynamics(*robot, q, qd, tau2, options), options), tau2), 1e-9);
    }
  }
}

TEST(DynamicsTest, TorqueFreeSimulationConservesEnergy) {
  for (const Case& rc : Robots()) {
    SCOPED_TRACE(rc.name);
    const RobotModel& robot = *rc.robot;
    const int n = robot.num_dofs();
    std::mt19937 rng(Seed() + 5);
    DynamicsOptions options;
    options.include_friction = false;
    const VectorXd zero = VectorXd::Zero(n);
    auto energy = [&](const VectorXd& q, const VectorXd& qd) {
      return 0.5 * qd.dot(MassMatrix(robot, q) * qd) + PotentialEnergy(robot, q, options.gravity);
    };
    for (int t = 0; t < std::max(1, Cases(100) / 50); ++t) {
      VectorXd q = RandomQ(robot, rng), qd = Uniform(rng, n, -1, 1);
      const double e0 = energy(q, qd);
      // Energy scale: kinetic energy plus the largest potential swing Σ m |g| (|p| + reach).
      double scale = 0.5 * qd.dot(MassMatrix(robot, q) * qd);
      for (const Link& link : robot.links()) scale += link.inertial ? link.inertial->mass * 9.81 : 0.0;
      // RK4 error at dt = 1 ms on these arms is ~1e-7 of the scale; a wrong c or g drifts by
      // percent.
      const double dt = 1e-3;
      double max_drift = 0.0;
      for (int step = 0; step < 2000; ++step) {  // 2 s, RK4
        auto f = [&](const VectorXd& qq, const VectorXd& vv) { return ForwardDynamics(robot, qq, vv, zero, options); };
        const VectorXd k1q = qd, k1v = f(q, qd);
        const VectorXd k2q = qd + 0.5 * dt * k1v, k2v = f(q + 0.5 * dt * k1q, k2q);
        const VectorXd k3q = qd + 0.5 * dt * k2v, k3v = f(q + 0.5 * dt * k2q, k3q);
        const VectorXd k4q = qd + dt * k3v, k4v = f(q + dt * k3q, k4q);
        q += dt / 6 * (k1q + 2 * k2q + 2 * k3q + k4q);
        qd += dt / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
        if (step % 100 == 99) max_drift = std::max(max_drift, std::abs(energy(q, qd) - e0));
      }
      ASSERT_TRUE(q.allFinite() && qd.allFinite());
      EXPECT_LT(max_drift / scale, 1e-5) << "drift " << max_drift << " J of scale " << scale << " J";
      EXPECT_GT(qd.norm(), 0.0);
    }
  }
}

TEST(DynamicsTest, FrictionAndArmatureTermsAreExactlyAsDocumented) {
  for (const Case& rc : Robots()) {
    SCOPED_TRACE(rc.name);
    auto robot = WithJointTerms(*rc.robot, 0.3, 0.2, 0.05);
    const int n = robot->num_dofs();
    std::mt19937 rng(Seed() + 6);
    for (int t = 0; t < Cases(50); ++t) {
      const VectorXd q = RandomQ(*robot, rng), qdd = Uniform(rng, n, -4, 4);
      VectorXd qd = Uniform(rng, n, -2, 2);
      qd[t % n] = 0.0;  // sign(0) = 0: no Coulomb term
      DynamicsOptions with, without;
      without.include_friction = false;
      VectorXd expected_friction(n), armature(n);
      for (int i = 0; i < n; ++i) {
        const Joint& j = robot->joints()[robot->dof_joint(i)];
        const double sign = qd[i] > 0 ? 1.0 : (qd[i] < 0 ? -1.0 : 0.0);
        expected_friction[i] = j.damping * qd[i] + j.friction * sign;
        armature[i] = j.armature;
      }
      const VectorXd tau_with = InverseDynamics(*robot, q, qd, qdd, with);
      const VectorXd tau_without = InverseDynamics(*robot, q, qd, qdd, without);
      EXPECT_LT((tau_with - tau_without - expected_friction).norm(), 1e-12 * std::max(1.0, tau_with.norm()));
      // Armature: on M's diagonal and as armature·q̈ in τ, compared with the model without it.
      const auto bare = WithJointTerms(*rc.robot, 0.0, 0.0, 0.0);
      const MatrixXd dM = MassMatrix(*robot, q) - MassMatrix(*bare, q);
      EXPECT_LT((dM - MatrixXd(armature.asDiagonal())).norm(), 1e-12);
      const VectorXd dtau = tau_without - InverseDynamics(*bare, q, qd, qdd, without);
      EXPECT_LT((dtau - VectorXd(armature.cwiseProduct(qdd))).norm(), 1e-11);
      // Friction is not part of the Coriolis or gravity terms.
      EXPECT_LT(RelErr(CoriolisTorques(*robot, q, qd), CoriolisTorques(*bare, q, qd)), 1e-12);
    }
  }
}

// --- URDF data and validation ------------------------------------------------------------

TEST(DynamicsTest, ExampleRobotsCarryInertiaAndFriction) {
  for (const std::string name : {"planar_2r", "ur5", "panda"}) {
    SCOPED_TRACE(name);
    auto robot = LoadExampleRobot(name);
    EXPECT_TRUE(HasInertia(*robot));
    for (const Link& link : robot->links()) {
      if (!link.inertial) continue;
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(link.inertial->inertia);
      const Vector3d e = eig.eigenvalues();  // ascending
      EXPECT_GT(e[0], 0.0) << link.name;
      EXPECT_GE(e[0] + e[1], e[2]) << link.name << ": triangle inequality";
    }
    for (int i = 0; i < robot->num_dofs(); ++i) {
      const Joint& j = robot->joints()[robot->dof_joint(i)];
      EXPECT_GT(j.damping, 0.0) << j.name;
      EXPECT_GT(j.friction, 0.0) << j.name;
    }
  }
  const auto panda = LoadExampleRobot("panda");
  EXPECT_DOUBLE_EQ(panda->links()[panda->FindLink("panda_link4")].inertial->mass, 3.587895);
  EXPECT_DOUBLE_EQ(panda->joints()[panda->dof_joint(0)].damping, 0.1);
}

const char* kOneJoint = R"(<robot name="one">
  <link name="base"/>
  <joint name="j" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" velocity="1" effort="1"/>%s</joint>
  <link name="arm">%s</link>
</robot>)";

std::string OneJoint(const std::string& dynamics, const std::string& inertial) {
  char buf[1024];
  std::snprintf(buf, sizeof(buf), kOneJoint, dynamics.c_str(), inertial.c_str());
  return buf;
}

TEST(DynamicsTest, UrdfDynamicsIsValidated) {
  const std::string inertial =
      R"(<inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>)";
  testing::ExpectInvalid([&] { RobotModel::FromUrdf(OneJoint(R"(<dynamics damping="-1"/>)", inertial)); },
                         "urdf: joint 'j' dynamics damping = -1 must be >= 0 and finite");
  testing::ExpectInvalid([&] { RobotModel::FromUrdf(OneJoint(R"(<dynamics friction="-0.5"/>)", inertial)); },
                         "urdf: joint 'j' dynamics friction = -0.5 must be >= 0 and finite");
  auto robot = RobotModel::FromUrdf(OneJoint(R"(<dynamics damping="0.25" friction="0.5"/>)", inertial));
  EXPECT_EQ(robot->joints()[0].damping, 0.25);
  EXPECT_EQ(robot->joints()[0].friction, 0.5);
  EXPECT_TRUE(HasInertia(*robot));
  // Without <dynamics>: no friction. Without <inertial>: no inertia.
  auto bare = RobotModel::FromUrdf(OneJoint("", ""));
  EXPECT_EQ(bare->joints()[0].damping, 0.0);
  EXPECT_EQ(bare->joints()[0].friction, 0.0);
  EXPECT_FALSE(HasInertia(*bare));
}

TEST(DynamicsTest, HasInertiaCountsMassBehindFixedJoints) {
  // The moving link itself is massless but carries a massive link through a fixed joint.
  const std::string urdf = R"(<robot name="r">
    <link name="base"/>
    <joint name="j" type="revolute"><parent link="base"/><child link="a"/><axis xyz="0 0 1"/>
      <limit lower="-1" upper="1" velocity="1" effort="1"/></joint>
    <link name="a"/>
    <joint name="f" type="fixed"><parent link="a"/><child link="b"/><origin xyz="0.5 0 0"/></joint>
    <link name="b"><inertial><mass value="2"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>
  </robot>)";
  auto robot = RobotModel::FromUrdf(urdf);
  EXPECT_TRUE(HasInertia(*robot));
  // The fixed link's inertia is seen by the joint: I = 0.1 + 2 · 0.5².
  EXPECT_NEAR(MassMatrix(*robot, VectorXd::Zero(1))(0, 0), 0.1 + 2 * 0.25, 1e-14);
}

}  // namespace
}  // namespace chasles
