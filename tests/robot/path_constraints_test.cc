// PathConstraints: errors against an independent computation (FK by chaining the URDF joints,
// Eigen's AngleAxis, the Euler factors multiplied back), certification against a dense re-check
// of hostile segments that graze the tolerances, the lever bounds against finite differences,
// projection, and named errors.

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "chasles/robot/error.h"
#include "chasles/robot/kinematics.h"
#include "chasles/robot/path_constraints.h"
#include "test_util.h"

namespace chasles {
namespace {

constexpr double kPi = 3.14159265358979323846;

Eigen::VectorXd RandomQ(const RobotModel& robot, std::mt19937_64* rng) {
  Eigen::VectorXd q(robot.num_dofs());
  for (int i = 0; i < q.size(); ++i) {
    q[i] = std::uniform_real_distribution<double>(robot.lower_limits()[i], robot.upper_limits()[i])(*rng);
  }
  return q;
}

Eigen::Isometry3d ChainedPose(const RobotModel& robot, const Eigen::VectorXd& q, int link) {
  std::vector<Eigen::Isometry3d> poses;
  robot.ForwardKinematicsByChaining(q, &poses);
  return poses[static_cast<std::size_t>(link)];
}

/// The Panda's hand kept near its orientation at `q0` (tolerance t per axis).
OrientationConstraintSpec HandAt(const RobotModel& robot, const Eigen::VectorXd& q0, Eigen::Vector3d t,
                                 OrientationParameterization p) {
  OrientationConstraintSpec c;
  c.link = robot.FindLink("panda_hand");
  c.orientation = Eigen::Quaterniond(ChainedPose(robot, q0, c.link).linear());
  c.tolerance = t;
  c.parameterization = p;
  return c;
}

const Eigen::VectorXd& Ready() {
  static const Eigen::VectorXd q = (Eigen::VectorXd(7) << 0, -0.785, 0, -2.356, 0, 1.571, 0.785).finished();
  return q;
}

TEST(PathConstraints, RotationVectorErrorsEqualAngleAxisOfTheChainedPose) {
  const auto robot = testing::LoadExampleRobot("panda");
  const PathConstraints c(robot, {HandAt(*robot, Ready(), Eigen::Vector3d(3, 3, 3), OrientationParameterization::kRotationVector)}, {});
  std::mt19937_64 rng(1);
  Eigen::VectorXd e;
  int checked = 0;
  for (int k = 0; k < 300; ++k) {
    const Eigen::VectorXd q = RandomQ(*robot, &rng);
    const Eigen::Matrix3d E = c.orientation()[0].orientation.toRotationMatrix().transpose() *
                              ChainedPose(*robot, q, c.orientation()[0].link).linear();
    const Eigen::AngleAxisd aa(E);
    if (aa.angle() > kPi - 1e-3) continue;  // the sign of the axis is arbitrary at π
    c.Errors(q, &e);
    EXPECT_LT((e - aa.axis() * aa.angle()).norm(), 1e-9) << "q = " << q.transpose();
    ++checked;
  }
  EXPECT_GT(checked, 250);
}

TEST(PathConstraints, EulerErrorsMultiplyBackToTheRotation) {
  const auto robot = testing::LoadExampleRobot("panda");
  const PathConstraints c(robot, {HandAt(*robot, Ready(), Eigen::Vector3d(3, 1.5, 3), OrientationParameterization::kXyzEulerAngles)}, {});
  std::mt19937_64 rng(2);
  Eigen::VectorXd e;
  for (int k = 0; k < 300; ++k) {
    const Eigen::VectorXd q = RandomQ(*robot, &rng);
    c.Errors(q, &e);
    const Eigen::Matrix3d E = c.orientation()[0].orientation.toRotationMatrix().transpose() *
                              ChainedPose(*robot, q, c.orientation()[0].link).linear();
    const Eigen::Matrix3d back = (Eigen::AngleAxisd(e[0], Eigen::Vector3d::UnitX()) *
                                  Eigen::AngleAxisd(e[1], Eigen::Vector3d::UnitY()) *
                                  Eigen::AngleAxisd(e[2], Eigen::Vector3d::UnitZ()))
                                     .toRotationMatrix();
    EXPECT_LT((back - E).norm(), 1e-9) << "q = " << q.transpose();
    EXPECT_LE(std::abs(e[1]), kPi / 2 + 1e-12);
    // x and y alone fix where the link's z axis points (a glass kept upright): angle to the target's z.
    const double tilt = std::acos(std::clamp(E(2, 2), -1.0, 1.0));
    EXPECT_NEAR(std::cos(tilt), std::cos(e[0]) * std::cos(e[1]), 1e-9);
  }
}

TEST(PathConstraints, PositionErrorsAreThePointInTheBoxFrame) {
  const auto robot = testing::LoadExampleRobot("panda");
  PositionConstraintSpec p;
  p.link = robot->FindLink("panda_hand");
  p.point = Eigen::Vector3d(0.01, -0.02, 0.1);
  p.region = Eigen::Translation3d(0.4, 0.1, 0.5) * Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized());
  p.half_extents = Eigen::Vector3d(0.1, 0.2, 0.0);
  const PathConstraints c(robot, {}, {p});
  std::mt19937_64 rng(3);
  Eigen::VectorXd e;
  for (int k = 0; k < 100; ++k) {
    const Eigen::VectorXd q = RandomQ(*robot, &rng);
    c.Errors(q, &e);
    const Eigen::Vector3d world = ChainedPose(*robot, q, p.link) * p.point;
    EXPECT_LT((p.region * Eigen::Vector3d(e.head<3>()) - world).norm(), 1e-12);
  }
}

TEST(PathConstraints, ErrorJacobianEqualsCentralDifferences) {
  const auto robot = testing::LoadExampleRobot("panda");
  PositionConstraintSpec p;
  p.link = robot->FindLink("panda_link6");
  p.point = Eigen::Vector3d(0.05, 0.02, -0.03);
  p.region = Eigen::Translation3d(0.3, -0.2, 0.4) * Eigen::AngleAxisd(1.1, Eigen::Vector3d(0.3, -1, 0.5).normalized());
  const PathConstraints c(robot,
                          {HandAt(*robot, Ready(), Eigen::Vector3d(3, 3, 3), OrientationParameterization::kRotationVector),
                           HandAt(*robot, Ready(), Eigen::Vector3d(3, 1.5, 3), OrientationParameterization::kXyzEulerAngles)},
                          {p});
  std::mt19937_64 rng(9);
  Eigen::VectorXd e, ep, em;
  Eigen::MatrixXd J;
  int checked = 0;
  for (int k = 0; k < 200; ++k) {
    const Eigen::VectorXd q = RandomQ(*robot, &rng);
    c.ErrorJacobian(q, &e, &J);
    c.Errors(q, &ep);
    ASSERT_EQ(e, ep);
    if (e.head<3>().norm() > kPi - 0.05 || std::abs(e[4]) > kPi / 2 - 0.05) continue;  // log flips, gimbal lock
    ++checked;
    constexpr double h = 1e-6;
    for (int i = 0; i < robot->num_dofs(); ++i) {
      Eigen::VectorXd qp = q, qm = q;
      qp[i] += h;
      qm[i] -= h;
      c.Errors(qp, &ep);
      c.Errors(qm, &em);
      const Eigen::VectorXd numeric = (ep - em) / (2 * h);
      EXPECT_LT((J.col(i) - numeric).cwiseAbs().maxCoeff(), 1e-5 * (1.0 + numeric.cwiseAbs().maxCoeff()))
          << "joint " << i << " at q = " << q.transpose() << "\nanalytic " << J.col(i).transpose() << "\nnumeric  "
          << numeric.transpose();
    }
  }
  EXPECT_GT(checked, 150);
}

TEST(PathConstraints, LeversBoundTheFiniteDifferenceSpeeds) {
  const auto robot = testing::LoadExampleRobot("panda");
  const int hand = robot->FindLink("panda_hand");
  const Eigen::Vector3d point(0.03, 0.0, 0.12);
  const Eigen::VectorXd levers = PointLevers(*robot, hand, point);
  const Eigen::VectorXd angular = AngularLevers(*robot, hand);
  std::mt19937_64 rng(4);
  constexpr double h = 1e-6;
  double tightest = 0.0;
  for (int k = 0; k < 200; ++k) {
    const Eigen::VectorXd q = RandomQ(*robot, &rng);
    for (int i = 0; i < robot->num_dofs(); ++i) {
      Eigen::VectorXd qp = q, qm = q;
      qp[i] += h;
      qm[i] -= h;
      const Eigen::Isometry3d Tp = ChainedPose(*robot, qp, hand), Tm = ChainedPose(*robot, qm, hand);
      const double speed = (Tp * point - Tm * point).norm() / (2 * h);
      EXPECT_LE(speed, levers[i] + 1e-6) << "joint " << i;
      tightest = std::max(tightest, speed / levers[i]);
      const double turn = Eigen::AngleAxisd(Tm.linear().transpose() * Tp.linear()).angle() / (2 * h);
      EXPECT_LE(turn, angular[i] + 1e-6) << "joint " << i;
    }
  }
  EXPECT_GT(tightest, 0.8);  // not vacuous: some configuration comes close to a lever
}

/// Hostile segments: both ends projected into the band, up to 0.3 rad apart, so many graze its
/// edges. A certified segment must keep the constraints at 4001 states along it; the ones a
/// dense check finds violating must not be certified; and certification is not vacuous.
void CheckCertificationAgainstDenseRecheck(const PathConstraints& c, std::uint64_t seed) {
  const RobotModel& robot = c.robot();
  std::mt19937_64 rng(seed);
  int certified = 0, violating = 0, rejected_free = 0;
  for (int k = 0; k < 300; ++k) {
    Eigen::VectorXd a = Ready();
    for (int i = 0; i < a.size(); ++i) a[i] += std::uniform_real_distribution<double>(-0.4, 0.4)(rng);
    a = a.cwiseMax(robot.lower_limits()).cwiseMin(robot.upper_limits());
    if (!c.Project(&a, 0.95)) continue;
    Eigen::VectorXd b = a;
    for (int i = 0; i < b.size(); ++i) b[i] += std::uniform_real_distribution<double>(-0.3, 0.3)(rng);
    b = b.cwiseMax(robot.lower_limits()).cwiseMin(robot.upper_limits());
    if (!c.Project(&b, 1.0)) continue;
    bool dense_ok = true;
    for (int j = 0; j <= 4000 && dense_ok; ++j) dense_ok = c.Satisfied(a + (b - a) * (j / 4000.0));
    const bool ok = c.IsSegmentSatisfied(a, b);
    if (ok) {
      ++certified;
      EXPECT_TRUE(dense_ok) << "certified a segment that leaves the constraints: a = " << a.transpose()
                            << ", b = " << b.transpose();
    }
    if (!dense_ok) ++violating;
    if (!ok && dense_ok) ++rejected_free;
  }
  EXPECT_GT(certified, 50);
  EXPECT_GT(violating, 10);  // the generator does produce segments that leave the band
  // Conservative, not blind: few free segments are refused (they come within rounding of a bound).
  EXPECT_LT(rejected_free, certified / 4 + 5);
}

TEST(PathConstraints, CertifiedRotationVectorSegmentsKeepTheConstraintsEverywhere) {
  const auto robot = testing::LoadExampleRobot("panda");
  CheckCertificationAgainstDenseRecheck(
      PathConstraints(robot, {HandAt(*robot, Ready(), Eigen::Vector3d(0.1, 0.05, 0.2), OrientationParameterization::kRotationVector)}, {}),
      5);
}

TEST(PathConstraints, CertifiedEulerSegmentsKeepTheConstraintsEverywhere) {
  const auto robot = testing::LoadExampleRobot("panda");
  CheckCertificationAgainstDenseRecheck(
      PathConstraints(robot, {HandAt(*robot, Ready(), Eigen::Vector3d(0.1, 0.1, kPi), OrientationParameterization::kXyzEulerAngles)}, {}),
      6);
}

TEST(PathConstraints, CertifiedPositionSegmentsKeepTheConstraintsEverywhere) {
  const auto robot = testing::LoadExampleRobot("panda");
  PositionConstraintSpec p;
  p.link = robot->FindLink("panda_hand");
  p.point = Eigen::Vector3d(0, 0, 0.1);
  std::vector<Eigen::Isometry3d> poses;
  robot->ForwardKinematics(Ready(), &poses);
  p.region = Eigen::Isometry3d::Identity();
  p.region.translation() = poses[static_cast<std::size_t>(p.link)] * p.point;
  p.half_extents = Eigen::Vector3d(0.2, 0.2, 0.01);  // a thin slab: the point stays near a table's height
  CheckCertificationAgainstDenseRecheck(PathConstraints(robot, {}, {p}), 7);
}

TEST(PathConstraints, ProjectionLandsInsideTheTightenedBand) {
  const auto robot = testing::LoadExampleRobot("panda");
  const PathConstraints c(robot, {HandAt(*robot, Ready(), Eigen::Vector3d(0.05, 0.05, kPi), OrientationParameterization::kXyzEulerAngles)}, {});
  std::mt19937_64 rng(8);
  int projected = 0;
  for (int k = 0; k < 200; ++k) {
    Eigen::VectorXd q = RandomQ(*robot, &rng);
    if (!c.Project(&q, 0.8)) continue;
    ++projected;
    Eigen::VectorXd e;
    c.Errors(q, &e);
    const Eigen::VectorXd bounds = c.TightenedBounds(0.8);
    EXPECT_EQ(bounds[2], std::numeric_limits<double>::infinity());  // z (tolerance π) is left free
    for (int a = 0; a < 3; ++a) EXPECT_LE(std::abs(e[a]), bounds[a] + 1e-9) << "axis " << a;
    EXPECT_TRUE((q.array() >= robot->lower_limits().array()).all() && (q.array() <= robot->upper_limits().array()).all());
  }
  EXPECT_GT(projected, 150);
}

TEST(PathConstraints, ViolationNamesTheConstraintTheAxisAndTheTolerance) {
  const auto robot = testing::LoadExampleRobot("panda");
  const PathConstraints c(robot, {HandAt(*robot, Ready(), Eigen::Vector3d(0.1, 0.1, 0.1), OrientationParameterization::kRotationVector)}, {});
  EXPECT_EQ(c.Violation(Ready()), "");
  Eigen::VectorXd q = Ready();
  q[6] += 0.3;  // the hand turns 0.3 rad about its own z axis
  int link = -1;
  const std::string v = c.Violation(q, &link);
  const std::string head = "path_constraints.orientation[0] (link 'panda_hand', rotation vector): z = ";
  ASSERT_EQ(v.rfind(head, 0), 0u) << v;
  EXPECT_NEAR(std::stod(v.substr(head.size())), 0.3, 1e-9) << v;
  EXPECT_NE(v.find(" rad exceeds the tolerance 0.1 rad"), std::string::npos) << v;
  EXPECT_EQ(link, robot->FindLink("panda_hand"));
}

TEST(PathConstraints, RefusesBadConstraintsNamingFieldAndRule) {
  const auto robot = testing::LoadExampleRobot("panda");
  const auto message = [&](std::vector<OrientationConstraintSpec> o, std::vector<PositionConstraintSpec> p) {
    try {
      PathConstraints(robot, std::move(o), std::move(p));
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
      return std::string(e.what());
    }
    return std::string("no error");
  };
  OrientationConstraintSpec o = HandAt(*robot, Ready(), Eigen::Vector3d(0.0, 0.1, 0.1), OrientationParameterization::kRotationVector);
  EXPECT_EQ(message({o}, {}), "path_constraints.orientation[0].tolerance.x = 0 must be within (0, π] [rad]");
  o.tolerance = Eigen::Vector3d(0.1, kPi / 2, 0.1);
  o.parameterization = OrientationParameterization::kXyzEulerAngles;
  EXPECT_NE(message({o}, {}).find("path_constraints.orientation[0].tolerance.y = 1.5707963267948966 must be within (0, π/2)"),
            std::string::npos);
  o.tolerance = Eigen::Vector3d(0.1, 0.1, 0.1);
  o.orientation.coeffs().setZero();
  EXPECT_NE(message({o}, {}).find("path_constraints.orientation[0].orientation must be a finite quaternion"), std::string::npos);
  o.orientation = Eigen::Quaterniond::Identity();
  o.link = 99;
  EXPECT_EQ(message({o}, {}).rfind("path_constraints.orientation[0].link = 99 is not a link of robot 'panda'", 0), 0u);
  PositionConstraintSpec p;
  p.link = 3;
  p.half_extents = Eigen::Vector3d(0.1, -0.1, 0.1);
  EXPECT_EQ(message({}, {p}), "path_constraints.position[0].half_extents.y = -0.1 must be finite and >= 0 [m]");
  p.half_extents = Eigen::Vector3d(0.1, 0.1, 0.1);
  p.point = Eigen::Vector3d(NAN, 0, 0);
  EXPECT_EQ(message({}, {p}), "path_constraints.position[0].point must be finite");
}

}  // namespace
}  // namespace chasles
