// DH and PoE robot descriptions: forward kinematics against closed forms and independent
// products, agreement of the URDF / DH / PoE UR5, geometry placement, and every validation rule.
#include "chasles/robot/descriptions.h"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

#include <gtest/gtest.h>

#include "chasles/robot/error.h"
#include "test_util.h"

namespace chasles {
namespace {

using testing::ExpectInvalid;
using testing::LoadExampleRobot;

constexpr double kPi = M_PI;

// ---------------------------------------------------------------------------------------------
// Independent reference formulas (written out, not shared with the implementation).

/// Standard DH: Rz(θ) Tz(d) Tx(a) Rx(α) as the textbook matrix.
Eigen::Isometry3d DhStandard(double a, double alpha, double d, double theta) {
  const double ct = std::cos(theta), st = std::sin(theta), ca = std::cos(alpha), sa = std::sin(alpha);
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.matrix().topRows<3>() << ct, -st * ca, st * sa, a * ct,
                             st, ct * ca, -ct * sa, a * st,
                             0, sa, ca, d;
  return t;
}

/// Modified DH (Craig eq. 3.6): Rx(α_{i−1}) Tx(a_{i−1}) Rz(θ) Tz(d).
Eigen::Isometry3d DhModified(double a, double alpha, double d, double theta) {
  const double ct = std::cos(theta), st = std::sin(theta), ca = std::cos(alpha), sa = std::sin(alpha);
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.matrix().topRows<3>() << ct, -st, 0, a,
                             st * ca, ct * ca, -sa, -sa * d,
                             st * sa, ct * sa, ca, ca * d;
  return t;
}

Eigen::Matrix3d Hat(const Eigen::Vector3d& w) {
  Eigen::Matrix3d m;
  m << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return m;
}

/// e^{[S]θ} (Modern Robotics eq. 3.88, and pure translation for ω = 0).
Eigen::Isometry3d ExpScrew(const Vector6d& s, double theta) {
  const Eigen::Vector3d w = s.head<3>(), v = s.tail<3>();
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  if (w.norm() < 1e-12) {
    t.translation() = v * theta;
    return t;
  }
  const Eigen::Matrix3d W = Hat(w), I = Eigen::Matrix3d::Identity();
  t.linear() = I + std::sin(theta) * W + (1 - std::cos(theta)) * W * W;
  t.translation() = (I * theta + (1 - std::cos(theta)) * W + (theta - std::sin(theta)) * W * W) * v;
  return t;
}

Matrix6d Ad(const Eigen::Isometry3d& t) {
  Matrix6d m = Matrix6d::Zero();
  m.topLeftCorner<3, 3>() = t.linear();
  m.bottomRightCorner<3, 3>() = t.linear();
  m.bottomLeftCorner<3, 3>() = Hat(t.translation()) * t.linear();
  return m;
}

Vector6d Screw(double wx, double wy, double wz, double vx, double vy, double vz) {
  Vector6d s;
  s << wx, wy, wz, vx, vy, vz;
  return s;
}

Eigen::Isometry3d Pose(double x, double y, double z, double qx = 0, double qy = 0, double qz = 0,
                       double qw = 1) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::Quaterniond(qw, qx, qy, qz).normalized().toRotationMatrix();
  t.translation() = Eigen::Vector3d(x, y, z);
  return t;
}

double PoseError(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.matrix() - b.matrix()).cwiseAbs().maxCoeff();
}

Eigen::VectorXd RandomConfiguration(std::mt19937_64& rng, int n, double range = kPi) {
  std::uniform_real_distribution<double> u(-range, range);
  Eigen::VectorXd q(n);
  for (int i = 0; i < n; ++i) q[i] = u(rng);
  return q;
}

std::vector<Eigen::Isometry3d> Fk(const RobotModel& model, const Eigen::VectorXd& q) {
  std::vector<Eigen::Isometry3d> poses;
  model.ForwardKinematics(q, &poses);
  return poses;
}

JointLimits Limits(double lower, double upper, double velocity = 1.0, double effort = 0.0) {
  JointLimits l;
  l.lower = lower;
  l.upper = upper;
  l.velocity = velocity;
  l.effort = effort;
  return l;
}

// ---------------------------------------------------------------------------------------------
// UR5 (examples/robots/ur5.urdf, ur5_dh.json, ur5_poe.json; keep the numbers in sync).

constexpr double kD1 = 0.089159, kA2 = -0.425, kA3 = -0.39225, kD4 = 0.10915, kD5 = 0.09465,
                 kD6 = 0.0823;
constexpr double kS = M_SQRT1_2;
const char* const kUr5JointNames[6] = {"shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
                                       "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"};

JointLimits Ur5Limits(int i) {
  return Limits(i == 2 ? -kPi : -2 * kPi, i == 2 ? kPi : 2 * kPi, 3.15, i < 3 ? 150.0 : 28.0);
}

LinkProperties Ur5BaseGeometry() {
  LinkProperties p;
  p.collision.push_back(Shape::Cylinder(0.075, 0.08, Pose(0, 0, 0.04)));
  return p;
}

/// The published UR5 DH table with `base` = Rz(π), so the frames are those of ur5.urdf;
/// collision shapes are ur5.urdf's, re-expressed in DH frame i.
DhDescription Ur5Dh() {
  DhDescription dh;
  dh.name = "ur5_dh";
  dh.convention = DhConvention::kStandard;
  const double a[6] = {0, kA2, kA3, 0, 0, 0};
  const double alpha[6] = {kPi / 2, 0, 0, kPi / 2, -kPi / 2, 0};
  const double d[6] = {kD1, 0, 0, kD4, kD5, kD6};
  std::vector<std::vector<Shape>> shapes = {
      {Shape::Cylinder(0.06, 0.14, Pose(0, 0, 0.03, 0, -1, 0, 0))},
      {Shape::Sphere(0.065, Pose(0.425, 0, 0.13585)),
       Shape::Cylinder(0.05, 0.3, Pose(0.2125, 0, 0.13585, 0.5, -0.5, -0.5, 0.5)),
       Shape::Sphere(0.06, Pose(0, 0, 0.13585))},
      {Shape::Sphere(0.055, Pose(0.39225, 0, 0.01615)),
       Shape::Cylinder(0.04, 0.27, Pose(0.20225, 0, 0.01615, 0.5, -0.5, -0.5, 0.5))},
      {Shape::Cylinder(0.045, 0.09, Pose(0, -0.02, 0, 0, -kS, kS, 0))},
      {Shape::Cylinder(0.045, 0.07, Pose(0, 0.04465, 0, 0, -kS, -kS, 0))},
      {Shape::Cylinder(0.04, 0.06, Pose(0, 0, -0.0323, 0, -1, 0, 0))},
  };
  for (int i = 0; i < 6; ++i) {
    DhJoint j;
    j.name = kUr5JointNames[i];
    j.a = a[i];
    j.alpha = alpha[i];
    j.d = d[i];
    j.limits = Ur5Limits(i);
    j.link.collision = shapes[i];
    dh.joints.push_back(j);
  }
  dh.base = Pose(0, 0, 0, 0, 0, 1, 0);  // Rz(π)
  dh.base_link = Ur5BaseGeometry();
  dh.allowed_collisions = {{"base_link", "link2"}};
  return dh;
}

/// Modern Robotics Example 4.5 with the exact DH lengths; link frames at ur5.urdf's link
/// frames (base-aligned, on the axes), so the collision shapes are ur5.urdf's verbatim.
PoeDescription Ur5Poe(bool body_frame) {
  const double W1 = kD4, W2 = kD6, L1 = -kA2, L2 = -kA3, H1 = kD1, H2 = kD5;
  PoeDescription poe;
  poe.name = "ur5_poe";
  poe.home.linear() << -1, 0, 0, 0, 0, 1, 0, 1, 0;
  poe.home.translation() = Eigen::Vector3d(L1 + L2, W1 + W2, H1 - H2);
  const Vector6d s[6] = {Screw(0, 0, 1, 0, 0, 0),           Screw(0, 1, 0, -H1, 0, 0),
                         Screw(0, 1, 0, -H1, 0, L1),        Screw(0, 1, 0, -H1, 0, L1 + L2),
                         Screw(0, 0, -1, -W1, L1 + L2, 0),  Screw(0, 1, 0, H2 - H1, 0, L1 + L2)};
  const Eigen::Isometry3d homes[6] = {Pose(0, 0, H1),           Pose(0, 0.13585, H1),
                                      Pose(L1, 0.01615, H1),    Pose(L1 + L2, W1, H1),
                                      Pose(L1 + L2, W1, H1),    Pose(L1 + L2, W1, H1 - H2)};
  std::vector<std::vector<Shape>> shapes = {
      {Shape::Cylinder(0.06, 0.14, Pose(0, 0.03, 0, kS, 0, 0, kS))},
      {Shape::Sphere(0.065), Shape::Cylinder(0.05, 0.3, Pose(0.2125, 0, 0, 0, kS, 0, kS)),
       Shape::Sphere(0.06, Pose(0.425, 0, 0))},
      {Shape::Sphere(0.055), Shape::Cylinder(0.04, 0.27, Pose(0.19, 0, 0, 0, kS, 0, kS))},
      {Shape::Cylinder(0.045, 0.09, Pose(0, -0.02, 0, kS, 0, 0, kS))},
      {Shape::Cylinder(0.045, 0.07, Pose(0, 0, -0.05))},
      {Shape::Cylinder(0.04, 0.06, Pose(0, 0.05, 0, kS, 0, 0, kS))},
  };
  poe.body_frame = body_frame;
  const Matrix6d ad_home_inv = Ad(poe.home.inverse());
  for (int i = 0; i < 6; ++i) {
    PoeJoint j;
    j.name = kUr5JointNames[i];
    j.screw = body_frame ? Vector6d(ad_home_inv * s[i]) : s[i];
    j.limits = Ur5Limits(i);
    j.link_home = homes[i];
    j.link.collision = shapes[i];
    poe.joints.push_back(j);
  }
  poe.base_link = Ur5BaseGeometry();
  poe.allowed_collisions = {{"base_link", "link2"}};
  return poe;
}

TEST(Ur5Descriptions, UrdfDhAndPoeAgreeOnToolPoseGeometryAndLimits) {
  const auto urdf = LoadExampleRobot("ur5");
  const auto dh = RobotFromDh(Ur5Dh());
  const auto poe = RobotFromPoe(Ur5Poe(false));
  ASSERT_EQ(dh->num_dofs(), 6);
  ASSERT_EQ(poe->num_dofs(), 6);
  ASSERT_EQ(dh->num_links(), urdf->num_links());
  ASSERT_EQ(poe->num_links(), urdf->num_links());
  const int urdf_tool = urdf->FindLink("tool0");
  const int dh_tool = dh->FindLink("tool");
  const int poe_tool = poe->FindLink("tool");
  ASSERT_GE(urdf_tool, 0);
  ASSERT_GE(dh_tool, 0);
  ASSERT_GE(poe_tool, 0);
  EXPECT_EQ(dh->dof_names(), urdf->dof_names());
  EXPECT_EQ(poe->dof_names(), urdf->dof_names());
  for (const auto* model : {dh.get(), poe.get()}) {
    EXPECT_EQ(model->lower_limits(), urdf->lower_limits());
    EXPECT_EQ(model->upper_limits(), urdf->upper_limits());
    EXPECT_EQ(model->velocity_limits(), urdf->velocity_limits());
    EXPECT_EQ(model->effort_limits(), urdf->effort_limits());
    for (int d = 0; d < 6; ++d) {
      EXPECT_LT((model->space_screw_axis(d) - urdf->space_screw_axis(d)).cwiseAbs().maxCoeff(), 1e-12)
          << model->name() << " dof " << d;
    }
    // base_link/link2 allowed as in ur5.srdf, adjacent links allowed, others not.
    EXPECT_TRUE(model->allowed_collisions().IsAllowed(0, 2));
    EXPECT_TRUE(model->allowed_collisions().IsAllowed(3, 4));
    EXPECT_FALSE(model->allowed_collisions().IsAllowed(1, 3));
  }

  std::mt19937_64 rng(7);
  double max_tool = 0.0, max_shape = 0.0;
  for (int trial = 0; trial < 1000; ++trial) {
    const Eigen::VectorXd q = RandomConfiguration(rng, 6, 2 * kPi);
    const auto pu = Fk(*urdf, q);
    const auto pd = Fk(*dh, q);
    const auto pp = Fk(*poe, q);
    max_tool = std::max({max_tool, PoseError(pd[dh_tool], pu[urdf_tool]),
                         PoseError(pp[poe_tool], pu[urdf_tool])});
    // Every collision shape at the same place in the world (links correspond by index).
    for (int l = 0; l < urdf->num_links(); ++l) {
      const auto& su = urdf->links()[l].collision;
      ASSERT_EQ(dh->links()[l].collision.size(), su.size()) << "link " << l;
      ASSERT_EQ(poe->links()[l].collision.size(), su.size()) << "link " << l;
      for (size_t k = 0; k < su.size(); ++k) {
        const Eigen::Isometry3d world = pu[l] * su[k].pose;
        EXPECT_EQ(dh->links()[l].collision[k].type, su[k].type);
        EXPECT_EQ(dh->links()[l].collision[k].radius, su[k].radius);
        EXPECT_EQ(dh->links()[l].collision[k].length, su[k].length);
        // A sphere's orientation is immaterial (the DH table gives none): compare its centre.
        const bool sphere = su[k].type == ShapeType::kSphere;
        for (const auto& [model, poses] : {std::pair<const RobotModel*, const std::vector<Eigen::Isometry3d>*>{dh.get(), &pd},
                                           std::pair<const RobotModel*, const std::vector<Eigen::Isometry3d>*>{poe.get(), &pp}}) {
          const Eigen::Isometry3d placed = (*poses)[l] * model->links()[l].collision[k].pose;
          const double error = sphere ? (placed.translation() - world.translation()).cwiseAbs().maxCoeff()
                                      : PoseError(placed, world);
          max_shape = std::max(max_shape, error);
          EXPECT_LT(error, 1e-9) << model->name() << " link " << l << " shape " << k;
        }
      }
    }
  }
  EXPECT_LT(max_tool, 1e-9);
  EXPECT_LT(max_shape, 1e-9);
}

TEST(Ur5Descriptions, DhFramesEqualTheDhProductAndPoeToolEqualsTheExponentialProduct) {
  const DhDescription desc = Ur5Dh();
  const auto dh = RobotFromDh(desc);
  const PoeDescription pdesc = Ur5Poe(false);
  const auto poe = RobotFromPoe(pdesc);
  std::mt19937_64 rng(11);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::VectorXd q = RandomConfiguration(rng, 6);
    const auto pd = Fk(*dh, q);
    Eigen::Isometry3d frame = desc.base;
    for (int i = 0; i < 6; ++i) {
      const DhJoint& j = desc.joints[i];
      frame = frame * DhStandard(j.a, j.alpha, j.d, q[i] + j.theta_offset);
      // Internal link i is DH frame i−1 turned by q_i; DH frame i = link i · Tx(a) Rx(α).
      const Eigen::Isometry3d dh_frame = pd[i + 1] * DhStandard(j.a, j.alpha, 0, 0);
      ASSERT_LT(PoseError(dh_frame, frame), 1e-12) << "frame " << i + 1;
    }
    ASSERT_LT(PoseError(pd[dh->FindLink("tool")], frame * desc.tool), 1e-12);
    std::vector<Eigen::Isometry3d> chained;
    dh->ForwardKinematicsByChaining(q, &chained);
    ASSERT_LT(PoseError(chained[dh->FindLink("tool")], frame), 1e-12);

    Eigen::Isometry3d product = Eigen::Isometry3d::Identity();
    for (int i = 0; i < 6; ++i) product = product * ExpScrew(pdesc.joints[i].screw, q[i]);
    ASSERT_LT(PoseError(Fk(*poe, q)[poe->FindLink("tool")], product * pdesc.home), 1e-12);
  }
}

// ---------------------------------------------------------------------------------------------
// Textbook 2R and the PUMA 560

TEST(DhDescription, Planar2RMatchesClosedFormAndTheUrdf) {
  const double L1 = 1.0, L2 = 0.8;
  DhDescription dh;
  dh.name = "planar_2r";
  for (double a : {L1, L2}) {
    DhJoint j;
    j.a = a;
    j.limits = Limits(-kPi, kPi, 2.0);
    dh.joints.push_back(j);
  }
  const auto model = RobotFromDh(dh);
  EXPECT_EQ(model->dof_names(), (std::vector<std::string>{"joint1", "joint2"}));
  EXPECT_EQ(model->links()[1].name, "link1");
  EXPECT_EQ(model->links()[2].name, "link2");
  const auto urdf = LoadExampleRobot("planar_2r");
  const int tool = model->FindLink("tool");
  std::mt19937_64 rng(3);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::VectorXd q = RandomConfiguration(rng, 2);
    const Eigen::Isometry3d t = Fk(*model, q)[tool];
    EXPECT_NEAR(t.translation().x(), L1 * std::cos(q[0]) + L2 * std::cos(q[0] + q[1]), 1e-12);
    EXPECT_NEAR(t.translation().y(), L1 * std::sin(q[0]) + L2 * std::sin(q[0] + q[1]), 1e-12);
    EXPECT_NEAR(t.translation().z(), 0.0, 1e-12);
    const Eigen::Matrix3d r = Eigen::AngleAxisd(q[0] + q[1], Eigen::Vector3d::UnitZ()).toRotationMatrix();
    EXPECT_LT((t.linear() - r).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LT(PoseError(t, Fk(*urdf, q)[urdf->FindLink("tool")]), 1e-12);
  }
}

TEST(PoeDescription, Planar2RMatchesClosedForm) {
  const double L1 = 1.0, L2 = 0.8;
  PoeDescription poe;
  poe.home.translation() = Eigen::Vector3d(L1 + L2, 0, 0);
  PoeJoint j;
  j.limits = Limits(-kPi, kPi);
  j.screw = Screw(0, 0, 1, 0, 0, 0);
  poe.joints.push_back(j);
  j.screw = Screw(0, 0, 1, 0, -L1, 0);
  poe.joints.push_back(j);
  const auto model = RobotFromPoe(poe);
  EXPECT_EQ(model->name(), "poe_robot");
  // Default link frames: base-aligned at the axis point nearest the origin.
  EXPECT_LT(PoseError(model->home_pose(2), Pose(L1, 0, 0)), 1e-15);
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::VectorXd q = RandomConfiguration(rng, 2);
    const auto p = Fk(*model, q);
    const Eigen::Vector3d tool = p[model->FindLink("tool")].translation();
    EXPECT_NEAR(tool.x(), L1 * std::cos(q[0]) + L2 * std::cos(q[0] + q[1]), 1e-12);
    EXPECT_NEAR(tool.y(), L1 * std::sin(q[0]) + L2 * std::sin(q[0] + q[1]), 1e-12);
    EXPECT_NEAR(p[2].translation().x(), L1 * std::cos(q[0]), 1e-12);  // elbow
  }
}

/// PUMA 560, standard DH (Corke, Robotics Toolbox `mdl_puma560`); as examples/robots/puma560_dh.json.
DhDescription Puma560Dh() {
  DhDescription dh;
  dh.name = "puma560";
  const double a[6] = {0, 0.4318, 0.0203, 0, 0, 0};
  const double alpha[6] = {kPi / 2, 0, -kPi / 2, kPi / 2, -kPi / 2, 0};
  const double d[6] = {0, 0, 0.15005, 0.4318, 0, 0};
  const double lower[6] = {-160, -45, -225, -110, -100, -266};
  const double upper[6] = {160, 225, 45, 170, 100, 266};
  for (int i = 0; i < 6; ++i) {
    DhJoint j;
    j.a = a[i];
    j.alpha = alpha[i];
    j.d = d[i];
    j.limits = Limits(lower[i] * kPi / 180, upper[i] * kPi / 180, 1.0);
    dh.joints.push_back(j);
  }
  return dh;
}

TEST(DhDescription, Puma560StandardMatchesTheDhProductEverywhere) {
  const DhDescription desc = Puma560Dh();
  const auto model = RobotFromDh(desc);
  std::mt19937_64 rng(13);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::VectorXd q = RandomConfiguration(rng, 6);
    const auto p = Fk(*model, q);
    Eigen::Isometry3d frame = Eigen::Isometry3d::Identity();
    for (int i = 0; i < 6; ++i) {
      const DhJoint& j = desc.joints[i];
      frame = frame * DhStandard(j.a, j.alpha, j.d, q[i]);
      ASSERT_LT(PoseError(p[i + 1] * DhStandard(j.a, j.alpha, 0, 0), frame), 1e-12) << i;
    }
    ASSERT_LT(PoseError(p[model->FindLink("tool")], frame), 1e-12);
  }
}

TEST(DhDescription, Puma560ModifiedMatchesCraigsClosedFormWristPosition) {
  // Craig, Introduction to Robotics, PUMA 560 modified-DH table (α_{i−1}, a_{i−1}, d_i) and
  // the closed-form position of frame 4's origin (the wrist centre), with the link lengths above.
  const double a2 = 0.4318, a3 = 0.0203, d3 = 0.15005, d4 = 0.4318;
  const double alpha[6] = {0, -kPi / 2, 0, -kPi / 2, kPi / 2, -kPi / 2};
  const double a[6] = {0, 0, a2, a3, 0, 0};
  const double d[6] = {0, 0, d3, d4, 0, 0};
  DhDescription dh;
  dh.convention = DhConvention::kModified;
  dh.base = Pose(0.1, -0.2, 0.6, 0.1, 0.2, 0.3, 0.9);
  dh.tool = Pose(0, 0, 0.05, 0, 0, 0.3, 1);
  for (int i = 0; i < 6; ++i) {
    DhJoint j;
    j.a = a[i];
    j.alpha = alpha[i];
    j.d = d[i];
    j.limits = Limits(-kPi, kPi);
    dh.joints.push_back(j);
  }
  const auto model = RobotFromDh(dh);
  EXPECT_EQ(model->name(), "dh_robot");
  std::mt19937_64 rng(17);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::VectorXd q = RandomConfiguration(rng, 6);
    const auto p = Fk(*model, q);
    const double c1 = std::cos(q[0]), s1 = std::sin(q[0]), c2 = std::cos(q[1]), s2 = std::sin(q[1]);
    const double c23 = std::cos(q[1] + q[2]), s23 = std::sin(q[1] + q[2]);
    const double r = a2 * c2 + a3 * c23 - d4 * s23;
    const Eigen::Vector3d wrist(c1 * r - d3 * s1, s1 * r + d3 * c1, -a3 * s23 - a2 * s2 - d4 * c23);
    EXPECT_LT((p[4].translation() - dh.base * wrist).cwiseAbs().maxCoeff(), 1e-12);
    // Modified convention: link i is DH frame i exactly.
    Eigen::Isometry3d frame = dh.base;
    for (int i = 0; i < 6; ++i) {
      frame = frame * DhModified(a[i], alpha[i], d[i], q[i]);
      ASSERT_LT(PoseError(p[i + 1], frame), 1e-12) << i;
    }
    ASSERT_LT(PoseError(p[model->FindLink("tool")], frame * dh.tool), 1e-12);
  }
}

TEST(DhDescription, PrismaticJointsThetaOffsetsAndLinkGeometryInBothConventions) {
  for (const DhConvention convention : {DhConvention::kStandard, DhConvention::kModified}) {
    DhDescription dh;
    dh.convention = convention;
    dh.base = Pose(0.3, 0.1, -0.2, 0.2, -0.1, 0.4, 0.8);
    dh.tool = Pose(0.01, 0.02, 0.1, 0.3, 0.1, 0, 1);
    const JointType types[4] = {JointType::kRevolute, JointType::kPrismatic, JointType::kContinuous,
                                JointType::kRevolute};
    const double a[4] = {0.1, -0.2, 0.3, 0.05}, alpha[4] = {0.3, -kPi / 2, 1.1, 0};
    const double d[4] = {0.4, 0.25, -0.1, 0.2}, offset[4] = {0.2, kPi / 2, -0.7, 1.5};
    for (int i = 0; i < 4; ++i) {
      DhJoint j;
      j.type = types[i];
      j.a = a[i];
      j.alpha = alpha[i];
      j.d = d[i];
      j.theta_offset = offset[i];
      j.limits = types[i] == JointType::kPrismatic ? Limits(-0.5, 0.5, 0.3, 100) : Limits(-3, 3, 2, 10);
      j.damping = 0.1 * i;
      j.friction = 0.2 * i;
      j.armature = 0.3 * i;
      j.link.collision.push_back(Shape::Box(Eigen::Vector3d(0.1, 0.2, 0.3), Pose(0.1 * i, 0.05, -0.02, 0.1, 0.7, 0, 0.7)));
      Inertial in;
      in.mass = 1.0 + i;
      in.com = Eigen::Vector3d(0.02, -0.01 * i, 0.05);
      in.inertia << 0.3, 0.01, 0.02, 0.01, 0.2, -0.03, 0.02, -0.03, 0.1;
      j.link.inertial = in;
      dh.joints.push_back(j);
    }
    const auto model = RobotFromDh(dh);
    ASSERT_EQ(model->num_dofs(), 4);
    EXPECT_EQ(model->lower_limits()[2], -kPi);  // continuous
    EXPECT_EQ(model->upper_limits()[1], 0.5);
    for (int i = 0; i < 4; ++i) {
      const Joint& joint = model->joints()[model->dof_joint(i)];
      EXPECT_EQ(joint.type, types[i]);
      EXPECT_EQ(joint.damping, 0.1 * i);
      EXPECT_EQ(joint.friction, 0.2 * i);
      EXPECT_EQ(joint.armature, 0.3 * i);
    }
    std::mt19937_64 rng(19);
    for (int trial = 0; trial < 100; ++trial) {
      Eigen::VectorXd q = RandomConfiguration(rng, 4, 3.0);
      q[1] *= 0.5 / 3.0;
      const auto p = Fk(*model, q);
      Eigen::Isometry3d frame = dh.base;
      for (int i = 0; i < 4; ++i) {
        const bool prismatic = types[i] == JointType::kPrismatic;
        const double theta = offset[i] + (prismatic ? 0.0 : q[i]);
        const double di = d[i] + (prismatic ? q[i] : 0.0);
        frame = frame * (convention == DhConvention::kStandard ? DhStandard(a[i], alpha[i], di, theta)
                                                               : DhModified(a[i], alpha[i], di, theta));
        // Geometry and inertia given in DH frame i follow DH frame i.
        const Link& link = model->links()[i + 1];
        const Shape& given = dh.joints[i].link.collision[0];
        ASSERT_LT(PoseError(p[i + 1] * link.collision[0].pose, frame * given.pose), 1e-12) << i;
        const Inertial& in = *dh.joints[i].link.inertial;
        EXPECT_LT((p[i + 1] * link.inertial->com - frame * in.com).norm(), 1e-12);
        const Eigen::Matrix3d world_inertia =
            p[i + 1].linear() * link.inertial->inertia * p[i + 1].linear().transpose();
        EXPECT_LT((world_inertia - frame.linear() * in.inertia * frame.linear().transpose()).cwiseAbs().maxCoeff(), 1e-12);
        EXPECT_EQ(link.inertial->mass, in.mass);
      }
      ASSERT_LT(PoseError(p[model->FindLink("tool")], frame * dh.tool), 1e-12);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// PoE: exact product, body = space, link frames

Eigen::Isometry3d RandomPose(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Pose(n(rng), n(rng), n(rng), n(rng), n(rng), n(rng), n(rng));
}

/// A random 6-joint arm with one prismatic joint; link_home on some joints, off the axes.
PoeDescription RandomPoe(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  PoeDescription poe;
  poe.name = "random";
  poe.home = RandomPose(rng);
  for (int i = 0; i < 6; ++i) {
    PoeJoint j;
    const Eigen::Vector3d dir = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
    if (i == 3) {
      j.type = JointType::kPrismatic;
      j.screw << 0, 0, 0, dir;
      j.limits = Limits(-1, 1);
    } else {
      const Eigen::Vector3d point(n(rng), n(rng), n(rng));
      j.screw << dir, -dir.cross(point);
      j.limits = Limits(-kPi, kPi);
    }
    if (i % 2 == 1) j.link_home = RandomPose(rng);
    j.link.collision.push_back(Shape::Capsule(0.05, 0.2, RandomPose(rng)));
    Inertial in;
    in.mass = 2.0;
    in.com = Eigen::Vector3d(n(rng), n(rng), n(rng)) * 0.1;
    in.inertia = Eigen::Vector3d(0.3, 0.2, 0.1).asDiagonal();
    j.link.inertial = in;
    poe.joints.push_back(j);
  }
  return poe;
}

TEST(PoeDescription, ToolIsTheExponentialProductAndGeometryFollowsLinkHome) {
  std::mt19937_64 rng(23);
  for (int robot = 0; robot < 10; ++robot) {
    const PoeDescription poe = RandomPoe(rng);
    const auto model = RobotFromPoe(poe);
    const int tool = model->FindLink("tool");
    ASSERT_EQ(tool, 7);
    for (int i = 0; i < 6; ++i) {
      EXPECT_LT((model->space_screw_axis(i) - poe.joints[i].screw).cwiseAbs().maxCoeff(), 1e-12);
    }
    for (int trial = 0; trial < 100; ++trial) {
      const Eigen::VectorXd q = RandomConfiguration(rng, 6, 1.0);
      const auto p = Fk(*model, q);
      Eigen::Isometry3d product = Eigen::Isometry3d::Identity();
      for (int i = 0; i < 6; ++i) {
        product = product * ExpScrew(poe.joints[i].screw, q[i]);
        const PoeJoint& j = poe.joints[i];
        // The frame the link is described in: link_home, or base-aligned at the axis point
        // nearest the origin (ω × v) for revolute joints, at the origin for prismatic ones.
        Eigen::Isometry3d given = Eigen::Isometry3d::Identity();
        if (j.link_home) {
          given = *j.link_home;
        } else if (j.type != JointType::kPrismatic) {
          given.translation() = j.screw.head<3>().cross(j.screw.tail<3>());
          EXPECT_LT(PoseError(model->home_pose(i + 1), given), 1e-12);
        }
        const Link& link = model->links()[i + 1];
        ASSERT_LT(PoseError(p[i + 1] * link.collision[0].pose, product * given * j.link.collision[0].pose), 1e-12)
            << "robot " << robot << " joint " << i << (j.link_home ? " with" : " without") << " link_home";
        EXPECT_LT((p[i + 1] * link.inertial->com - product * given * j.link.inertial->com).norm(), 1e-12);
      }
      ASSERT_LT(PoseError(p[tool], product * poe.home), 1e-12);
    }
  }
}

TEST(PoeDescription, BodyFrameScrewsGiveTheSameRobotAsSpaceFrameScrews) {
  std::mt19937_64 rng(29);
  for (int robot = 0; robot < 10; ++robot) {
    const PoeDescription space = RandomPoe(rng);
    PoeDescription body = space;
    body.body_frame = true;
    const Matrix6d ad_inv = Ad(space.home.inverse());
    for (PoeJoint& j : body.joints) j.screw = ad_inv * j.screw;
    const auto ms = RobotFromPoe(space);
    const auto mb = RobotFromPoe(body);
    for (int i = 0; i < 6; ++i) {
      EXPECT_LT((mb->space_screw_axis(i) - ms->space_screw_axis(i)).cwiseAbs().maxCoeff(), 1e-12);
    }
    for (int trial = 0; trial < 50; ++trial) {
      const Eigen::VectorXd q = RandomConfiguration(rng, 6, 1.0);
      const auto ps = Fk(*ms, q);
      const auto pb = Fk(*mb, q);
      for (int l = 0; l < ms->num_links(); ++l) ASSERT_LT(PoseError(pb[l], ps[l]), 1e-12) << l;
      // Body form: T = M e^{[B1]q1} ··· e^{[Bn]qn}.
      Eigen::Isometry3d product = body.home;
      for (int i = 0; i < 6; ++i) product = product * ExpScrew(body.joints[i].screw, q[i]);
      ASSERT_LT(PoseError(pb[7], product), 1e-12);
    }
  }
  // The UR5 in body form too.
  const auto ur5_space = RobotFromPoe(Ur5Poe(false));
  const auto ur5_body = RobotFromPoe(Ur5Poe(true));
  std::mt19937_64 rng2(31);
  for (int trial = 0; trial < 100; ++trial) {
    const Eigen::VectorXd q = RandomConfiguration(rng2, 6);
    ASSERT_LT(PoseError(Fk(*ur5_body, q)[7], Fk(*ur5_space, q)[7]), 1e-12);
  }
}

// ---------------------------------------------------------------------------------------------
// The example JSON files hold the numbers of the C++ descriptions above (the JSON → model path
// itself is tested with the proto conversion in tests/server).

/// One expected JSON value: a number, or a quaternion (x, y, z, w) compared up to sign.
struct Expected {
  std::vector<double> values;
  bool quaternion = false;
};

class Flattener {
 public:
  void Num(double x) { items.push_back({{x}, false}); }
  void Position(const Eigen::Isometry3d& t) {
    for (int i = 0; i < 3; ++i) Num(t.translation()[i]);
  }
  void Orientation(const Eigen::Isometry3d& t) {
    const Eigen::Quaterniond q(t.linear());
    items.push_back({{q.x(), q.y(), q.z(), q.w()}, true});
  }
  void FullPose(const Eigen::Isometry3d& t) {
    Position(t);
    Orientation(t);
  }
  /// A pose whose orientation the files omit when it is the identity.
  void ShapePose(const Eigen::Isometry3d& t, bool sphere) {
    Position(t);
    if (!sphere && !t.linear().isIdentity(1e-15)) Orientation(t);
  }
  void Limits(const JointLimits& l) {
    for (double x : {l.lower, l.upper, l.velocity, l.effort}) Num(x);
  }
  void Link(const LinkProperties& p) {
    for (ShapeType type : {ShapeType::kSphere, ShapeType::kBox, ShapeType::kCylinder, ShapeType::kCapsule}) {
      for (const Shape& s : p.collision) {
        if (s.type != type) continue;
        if (type == ShapeType::kBox) {
          for (int i = 0; i < 3; ++i) Num(s.size[i]);
        } else {
          Num(s.radius);
          if (type != ShapeType::kSphere) Num(s.length);
        }
        ShapePose(s.pose, type == ShapeType::kSphere);
      }
    }
  }
  std::vector<Expected> items;
};

std::vector<Expected> Flatten(const DhDescription& dh) {
  Flattener f;
  for (const DhJoint& j : dh.joints) {
    for (double x : {j.a, j.alpha, j.d, j.theta_offset}) f.Num(x);
    f.Limits(j.limits);
    f.Link(j.link);
  }
  f.FullPose(dh.base);
  f.FullPose(dh.tool);
  f.Link(dh.base_link);
  return f.items;
}

std::vector<Expected> Flatten(const PoeDescription& poe) {
  Flattener f;
  f.FullPose(poe.home);
  for (const PoeJoint& j : poe.joints) {
    for (int i = 0; i < 6; ++i) f.Num(j.screw[i]);
    f.Limits(j.limits);
    if (j.link_home) f.ShapePose(*j.link_home, false);
    f.Link(j.link);
  }
  f.Link(poe.base_link);
  return f.items;
}

/// Every number of a JSON text that is an object value (`"key": number`), in document order.
std::vector<double> JsonNumbers(const std::string& text) {
  std::vector<double> numbers;
  for (size_t i = text.find(':'); i != std::string::npos; i = text.find(':', i + 1)) {
    size_t k = i + 1;
    while (k < text.size() && std::isspace(static_cast<unsigned char>(text[k]))) ++k;
    if (k < text.size() && (text[k] == '-' || std::isdigit(static_cast<unsigned char>(text[k])))) {
      numbers.push_back(std::strtod(text.c_str() + k, nullptr));
    }
  }
  return numbers;
}

void ExpectJsonHolds(const std::string& file, const std::vector<Expected>& expected) {
  const std::vector<double> numbers = JsonNumbers(testing::ReadExample("robots/" + file));
  size_t at = 0;
  for (size_t e = 0; e < expected.size(); ++e) {
    const std::vector<double>& want = expected[e].values;
    ASSERT_LE(at + want.size(), numbers.size()) << file << ": too few numbers";
    double plus = 0.0, minus = 0.0;
    for (size_t k = 0; k < want.size(); ++k) {
      plus = std::max(plus, std::abs(numbers[at + k] - want[k]));
      minus = std::max(minus, std::abs(numbers[at + k] + want[k]));
    }
    EXPECT_LT(expected[e].quaternion ? std::min(plus, minus) : plus, 1e-12)
        << file << ": value " << e << " (number " << at << ") is " << numbers[at] << ", expected " << want[0];
    at += want.size();
  }
  EXPECT_EQ(at, numbers.size()) << file << ": more numbers than expected";
}

TEST(ExampleFiles, JsonDescriptionsHoldTheNumbersTestedHere) {
  ExpectJsonHolds("ur5_dh.json", Flatten(Ur5Dh()));
  ExpectJsonHolds("ur5_poe.json", Flatten(Ur5Poe(false)));
  ExpectJsonHolds("puma560_dh.json", Flatten(Puma560Dh()));
  const std::string dh = testing::ReadExample("robots/ur5_dh.json");
  EXPECT_NE(dh.find("\"convention\": \"STANDARD\""), std::string::npos);
  EXPECT_NE(dh.find("\"link1\": \"base_link\""), std::string::npos);
  EXPECT_NE(testing::ReadExample("robots/ur5_poe.json").find("\"body_frame\": false"), std::string::npos);
}

// ---------------------------------------------------------------------------------------------
// Validation

DhDescription TwoLinkDh() {
  DhDescription dh;
  for (int i = 0; i < 2; ++i) {
    DhJoint j;
    j.a = 0.5;
    j.limits = Limits(-1, 1);
    dh.joints.push_back(j);
  }
  return dh;
}

PoeDescription TwoLinkPoe() {
  PoeDescription poe;
  poe.home.translation() = Eigen::Vector3d(1, 0, 0);
  PoeJoint j;
  j.limits = Limits(-1, 1);
  j.screw = Screw(0, 0, 1, 0, 0, 0);
  poe.joints.push_back(j);
  j.type = JointType::kPrismatic;
  j.screw = Screw(0, 0, 0, 1, 0, 0);
  poe.joints.push_back(j);
  return poe;
}

template <typename Description, typename Edit>
void ExpectDescriptionInvalid(Edit edit, const std::string& message) {
  Description desc;
  if constexpr (std::is_same_v<Description, DhDescription>) {
    desc = TwoLinkDh();
  } else {
    desc = TwoLinkPoe();
  }
  edit(desc);
  ExpectInvalid([&] {
    if constexpr (std::is_same_v<Description, DhDescription>) {
      RobotFromDh(desc);
    } else {
      RobotFromPoe(desc);
    }
  }, message);
}

template <typename Edit>
void ExpectDh(Edit edit, const std::string& message) { ExpectDescriptionInvalid<DhDescription>(edit, message); }
template <typename Edit>
void ExpectPoe(Edit edit, const std::string& message) { ExpectDescriptionInvalid<PoeDescription>(edit, message); }

TEST(DescriptionValidation, ValidBaselinesBuild) {
  EXPECT_EQ(RobotFromDh(TwoLinkDh())->num_dofs(), 2);
  EXPECT_EQ(RobotFromPoe(TwoLinkPoe())->num_dofs(), 2);
}

TEST(DescriptionValidation, DhTableRules) {
  using D = DhDescription;
  ExpectDh([](D& d) { d.joints.clear(); }, "dh.joints is empty; a DH table needs at least one joint");
  ExpectDh([](D& d) { d.joints[1].alpha = NAN; }, "dh.joints[1].alpha = nan must be finite");
  ExpectDh([](D& d) { d.joints[0].a = INFINITY; }, "dh.joints[0].a = inf must be finite");
  ExpectDh([](D& d) { d.joints[0].d = -INFINITY; }, "dh.joints[0].d = -inf must be finite");
  ExpectDh([](D& d) { d.joints[1].theta_offset = NAN; }, "dh.joints[1].theta_offset = nan must be finite");
  ExpectDh([](D& d) { d.joints[1].type = JointType::kFixed; },
           "dh.joints[1].type = fixed must be revolute, continuous or prismatic");
  ExpectDh([](D& d) { d.joints[0].limits = Limits(2, 1); }, "dh.joints[0].limits lower = 2 > upper = 1");
  ExpectDh([](D& d) { d.joints[0].limits.lower = NAN; }, "dh.joints[0].limits lower = nan must be finite");
  ExpectDh([](D& d) { d.joints[1].limits.upper = INFINITY; }, "dh.joints[1].limits upper = inf must be finite");
  ExpectDh([](D& d) { d.joints[1].limits.velocity = 0; },
           "dh.joints[1].limits velocity = 0 must be > 0 and finite");
  ExpectDh([](D& d) { d.joints[1].limits.effort = -1; },
           "dh.joints[1].limits effort = -1 must be >= 0 and finite");
  ExpectDh([](D& d) { d.joints[0].damping = -0.5; }, "dh.joints[0].damping = -0.5 must be >= 0 and finite");
  ExpectDh([](D& d) { d.joints[0].friction = NAN; }, "dh.joints[0].friction = nan must be >= 0 and finite");
  ExpectDh([](D& d) { d.joints[1].armature = -2; }, "dh.joints[1].armature = -2 must be >= 0 and finite");
  ExpectDh([](D& d) { d.joints[1].name = "joint1"; },
           "dh.joints[1].name = 'joint1' is used by dh.joints[0] too; joint names must be unique");
  ExpectDh([](D& d) { d.joints[0].name = "tool_joint"; },
           "dh.joints[0].name = 'tool_joint' is reserved for the fixed joint of the tool link");
  ExpectDh([](D& d) { d.joints[1].link.collision.push_back(Shape::Sphere(-1)); },
           "dh.joints[1].link.collision[0] radius = -1 must be > 0 and finite");
  ExpectDh([](D& d) { d.base_link.collision.push_back(Shape::Cylinder(0.1, 0)); },
           "dh.base_link.collision[0] length = 0 must be > 0 and finite");
  ExpectDh([](D& d) { d.joints[0].link.collision.push_back(Shape::Box(Eigen::Vector3d(1, -1, 1))); },
           "dh.joints[0].link.collision[0] size[1] = -1 must be > 0 and finite");
  ExpectDh([](D& d) {
    Inertial in;
    in.mass = -1;
    d.joints[0].link.inertial = in;
  }, "dh.joints[0].link.inertial mass = -1 must be >= 0 and finite");
  ExpectDh([](D& d) { d.allowed_collisions = {{"link1", "nope"}}; },
           "dh.allowed_collisions[0].second = 'nope' is not a link (links are base_link, link1 … link2, tool)");
  // Continuous joints ignore their position limits but still need a velocity.
  DhDescription continuous = TwoLinkDh();
  continuous.joints[0].type = JointType::kContinuous;
  continuous.joints[0].limits = Limits(NAN, NAN);
  EXPECT_EQ(RobotFromDh(continuous)->upper_limits()[0], kPi);
}

TEST(DescriptionValidation, BaseToolAndHomeMustBeRigidTransforms) {
  using D = DhDescription;
  using P = PoeDescription;
  ExpectDh([](D& d) { d.base.linear() = Eigen::Vector3d(1, 1, -1).asDiagonal(); },
           "dh.base is not in SE(3): rotation part has det = -1");
  ExpectDh([](D& d) { d.tool.linear() *= 1.1; },
           "dh.tool is not in SE(3): rotation part is not orthonormal (max |RᵀR − I| = " +
               FormatNumber(1.1 * 1.1 - 1) + " > 1e-6)");
  ExpectDh([](D& d) { d.tool.translation().x() = NAN; }, "dh.tool is not in SE(3): it has non-finite entries");
  ExpectDh([](D& d) { d.base.matrix()(3, 2) = 0.5; },
           "dh.base is not in SE(3): bottom row is (0 0 0.5 1), must be (0 0 0 1)");
  ExpectPoe([](P& p) { p.home.linear() = -Eigen::Matrix3d::Identity(); },
            "poe.home is not in SE(3): rotation part has det = -1");
  ExpectPoe([](P& p) { p.joints[1].link_home = Eigen::Isometry3d(Eigen::Matrix3d::Zero()); },
            "poe.joints[1].link_home is not in SE(3): rotation part is not orthonormal (max |RᵀR − I| = 1 > 1e-6)");
  ExpectDh([](D& d) { d.joints[0].link.collision.push_back(Shape::Sphere(0.1, Eigen::Isometry3d(2.0 * Eigen::Matrix3d::Identity()))); },
           "dh.joints[0].link.collision[0].pose is not in SE(3): rotation part is not orthonormal (max |RᵀR − I| = 3 > 1e-6)");
  // Within 1e-6 is accepted and made exactly orthonormal.
  DhDescription nearly = TwoLinkDh();
  nearly.base.linear() *= 1.0 + 2e-7;
  const auto model = RobotFromDh(nearly);
  const Eigen::Matrix3d r = model->joints()[0].origin.linear();
  EXPECT_LT((r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(DescriptionValidation, PoeScrewRules) {
  using P = PoeDescription;
  ExpectPoe([](P& p) { p.joints.clear(); }, "poe.joints is empty; a PoE description needs at least one joint");
  ExpectPoe([](P& p) { p.joints[0].screw = Screw(0, 0, 0.5, 0, 0, 0); },
            "poe.joints[0].screw: |ω| = 0.5 must be 1 for a revolute joint");
  ExpectPoe([](P& p) {
    p.joints[0].type = JointType::kContinuous;
    p.joints[0].screw = Screw(0, 2, 0, 0, 0, 0);
  }, "poe.joints[0].screw: |ω| = 2 must be 1 for a continuous joint");
  ExpectPoe([](P& p) { p.joints[0].screw = Screw(0, 0, 1, 0, 0.2, 0.1); },
            "poe.joints[0].screw: ω·v = 0.1 must be 0 for a revolute joint (a pure rotation; screws "
            "with nonzero pitch are not supported)");
  ExpectPoe([](P& p) { p.joints[1].screw = Screw(0, 0, 0, 2, 0, 0); },
            "poe.joints[1].screw: ω = 0 and |v| = 2 must be 1 for a prismatic joint");
  ExpectPoe([](P& p) { p.joints[1].screw = Screw(1, 0, 0, 1, 0, 0); },
            "poe.joints[1].screw: |ω| = 1 must be 0 for a prismatic joint");
  ExpectPoe([](P& p) { p.joints[0].screw[0] = NAN; },
            "poe.joints[0].screw = (nan 0 1 0 0 0) must be finite");
  ExpectPoe([](P& p) { p.joints[1].type = JointType::kFixed; },
            "poe.joints[1].type = fixed must be revolute, continuous or prismatic");
  ExpectPoe([](P& p) { p.joints[1].limits.velocity = -1; },
            "poe.joints[1].limits velocity = -1 must be > 0 and finite");
  ExpectPoe([](P& p) { p.joints[0].limits = Limits(0.5, 0.25); },
            "poe.joints[0].limits lower = 0.5 > upper = 0.25");
  ExpectPoe([](P& p) { p.allowed_collisions = {{"base", "tool"}}; },
            "poe.allowed_collisions[0].first = 'base' is not a link (links are base_link, link1 … link2, tool)");
  // Within the tolerances: accepted.
  PoeDescription nearly = TwoLinkPoe();
  nearly.joints[0].screw = Screw(0, 0, 1 + 5e-7, 0, 0, 5e-7);
  nearly.joints[1].screw = Screw(1e-7, 0, 0, 1 - 5e-7, 0, 0);
  EXPECT_EQ(RobotFromPoe(nearly)->num_dofs(), 2);
}

}  // namespace
}  // namespace chasles
