// Tests of the SO(3)/SE(3) utilities: closed forms, Exp/Log round trips (including the
// θ ≈ 0 and θ ≈ π branches), and the adjoint identities.
#include "chasles/robot/lie_group.h"
#include "test_util.h"

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <random>

#include <gtest/gtest.h>

namespace chasles {
namespace {

using testing::RandomConfiguration;
using testing::TestCases;
using testing::TestSeed;
using testing::Uniform;

constexpr double kPi = 3.14159265358979323846;


// Uniform in [0, 1) from 53 random bits.
double Uniform(std::mt19937_64& rng, double lo, double hi) { return lo + (hi - lo) * Uniform(rng); }

Eigen::Vector3d RandomUnit(std::mt19937_64& rng) {
  for (;;) {
    Eigen::Vector3d v(Uniform(rng, -1, 1), Uniform(rng, -1, 1), Uniform(rng, -1, 1));
    const double n = v.norm();
    if (n > 0.1 && n <= 1.0) return v / n;
  }
}

Vector6d RandomTwist(std::mt19937_64& rng, double angle) {
  Vector6d t;
  t.head<3>() = RandomUnit(rng) * angle;
  t.tail<3>() = Eigen::Vector3d(Uniform(rng, -2, 2), Uniform(rng, -2, 2), Uniform(rng, -2, 2));
  return t;
}

Eigen::Isometry3d RandomPose(std::mt19937_64& rng) {
  return ExpSE3(RandomTwist(rng, Uniform(rng, 0, kPi)), 1.0);
}

// A rotation built independently of ExpSO3 (Eigen's AngleAxis).
Eigen::Matrix3d AngleAxisMatrix(const Eigen::Vector3d& axis, double angle) {
  return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}

TEST(LieGroupTest, SkewIsCrossProduct) {
  const Eigen::Vector3d w(0.3, -1.2, 2.5), p(-0.7, 0.4, 1.1);
  EXPECT_LT((Skew(w) * p - w.cross(p)).norm(), 1e-15);
  EXPECT_LT((Skew(w) + Skew(w).transpose()).norm(), 1e-15);
}

TEST(LieGroupTest, ExpSO3MatchesAngleAxis) {
  std::mt19937_64 rng(TestSeed(12345u));
  for (int i = 0; i < TestCases(1000); ++i) {
    const Eigen::Vector3d axis = RandomUnit(rng);
    const double angle = Uniform(rng, -4.0, 4.0);
    EXPECT_LT((ExpSO3(axis * angle) - AngleAxisMatrix(axis, angle)).norm(), 1e-14);
  }
  EXPECT_EQ(ExpSO3(Eigen::Vector3d::Zero()), Eigen::Matrix3d::Identity());
  // Tiny angles: first order term must be exact to rounding.
  const Eigen::Vector3d tiny(1e-9, -2e-9, 3e-9);
  EXPECT_LT((ExpSO3(tiny) - (Eigen::Matrix3d::Identity() + Skew(tiny))).norm(), 1e-17);
}

TEST(LieGroupTest, LogSO3RoundTripAllAngles) {
  std::mt19937_64 rng(TestSeed(12345u) + 1);
  const double special[] = {0.0, 1e-12, 1e-8, 1e-5, 9.9e-5, 1.01e-4, 1e-3, 0.5, 2.0,
                            2.0 * kPi / 3.0 - 1e-9, 2.0 * kPi / 3.0 + 1e-9, kPi - 1e-3,
                            kPi - 1e-6, kPi - 1e-9, kPi - 1e-12, kPi};
  for (int i = 0; i < TestCases(1000); ++i) {
    const Eigen::Vector3d axis = RandomUnit(rng);
    const double angle = i < 16 * 8 ? special[i % 16] : Uniform(rng, 0.0, kPi);
    const Eigen::Matrix3d R = AngleAxisMatrix(axis, angle);
    const Eigen::Vector3d r = LogSO3(R);
    ASSERT_TRUE(r.allFinite()) << "angle " << angle;
    EXPECT_LE(r.norm(), kPi + 1e-12);
    EXPECT_NEAR(r.norm(), angle, 1e-9) << "angle " << angle;
    // The rotation is recovered (at θ = π either axis sign is the same rotation).
    EXPECT_LT((ExpSO3(r) - R).norm(), 1e-12) << "angle " << angle;
    // Away from π the vector itself is unique.
    if (angle < kPi - 1e-6) {
      EXPECT_LT((r - axis * angle).norm(), 1e-9) << "angle " << angle;
    }
  }
}

TEST(LieGroupTest, LogSO3ExactHalfTurns) {
  // R = diag(1, -1, -1) is a half turn about x; the π branch must find the axis exactly.
  const Eigen::Matrix3d R = Eigen::Vector3d(1, -1, -1).asDiagonal();
  const Eigen::Vector3d r = LogSO3(R);
  EXPECT_NEAR(r.norm(), kPi, 1e-15);
  EXPECT_NEAR(std::abs(r.x()), kPi, 1e-15);
  const Eigen::Vector3d axis = Eigen::Vector3d(1, 1, 1).normalized();
  EXPECT_LT((ExpSO3(LogSO3(AngleAxisMatrix(axis, kPi))) - AngleAxisMatrix(axis, kPi)).norm(), 1e-14);
}

TEST(LieGroupTest, ExpSE3ScrewMotion) {
  // Rotation by π/2 about the z axis through (1, 0, 0): the origin goes to (1, -1, 0).
  Vector6d s;
  // S = (ω, −ω × q) with q = (1, 0, 0): v = −(0,0,1)×(1,0,0) = (0, −1, 0).
  s << 0, 0, 1, 0, -1, 0;
  const Eigen::Isometry3d T = ExpSE3(s, kPi / 2);
  EXPECT_LT((T.translation() - Eigen::Vector3d(1, -1, 0)).norm(), 1e-15);
  EXPECT_LT((T.linear() - AngleAxisMatrix(Eigen::Vector3d::UnitZ(), kPi / 2)).norm(), 1e-15);
  // Pitch h = 0.1 adds 0.1·θ along the axis.
  s << 0, 0, 1, 0, -1, 0.1;
  EXPECT_NEAR(ExpSE3(s, kPi / 2).translation().z(), 0.1 * kPi / 2, 1e-15);
  // Pure translation.
  s << 0, 0, 0, 0.6, 0, 0.8;
  const Eigen::Isometry3d P = ExpSE3(s, 2.0);
  EXPECT_EQ(P.linear(), Eigen::Matrix3d::Identity());
  EXPECT_LT((P.translation() - Eigen::Vector3d(1.2, 0, 1.6)).norm(), 1e-15);
  // θ scales the twist: ExpSE3(S, θ) == ExpSE3(S θ, 1).
  s << 0.6, 0, 0.8, 0.3, -0.2, 0.5;
  EXPECT_LT((ExpSE3(s, 1.7).matrix() - ExpSE3(s * 1.7, 1.0).matrix()).norm(), 1e-14);
}

TEST(LieGroupTest, ExpSE3MatchesMatrixExponentialSeries) {
  // Independent check: the 4×4 matrix exponential by scaling and squaring of a Taylor series.
  std::mt19937_64 rng(TestSeed(12345u) + 2);
  for (int i = 0; i < 50; ++i) {
    const Vector6d t = RandomTwist(rng, Uniform(rng, 0, kPi));
    Eigen::Matrix4d X = Eigen::Matrix4d::Zero();
    X.topLeftCorner<3, 3>() = Skew(t.head<3>());
    X.topRightCorner<3, 1>() = t.tail<3>();
    const int squarings = 10;
    X /= std::pow(2.0, squarings);
    Eigen::Matrix4d E = Eigen::Matrix4d::Identity(), term = Eigen::Matrix4d::Identity();
    for (int k = 1; k < 20; ++k) {
      term = term * X / k;
      E += term;
    }
    for (int k = 0; k < squarings; ++k) E = E * E;
    EXPECT_LT((ExpSE3(t, 1.0).matrix() - E).norm(), 1e-11);
  }
}

TEST(LieGroupTest, LogSE3RoundTrip) {
  std::mt19937_64 rng(TestSeed(12345u) + 3);
  const double special[] = {0.0, 1e-12, 1e-7, 1e-4, 1e-3, 1.0, kPi - 1e-4, kPi - 1e-8, kPi};
  for (int i = 0; i < TestCases(1000); ++i) {
    const double angle = i < 9 * 8 ? special[i % 9] : Uniform(rng, 0.0, kPi);
    const Vector6d t = RandomTwist(rng, angle);
    const Eigen::Isometry3d T = ExpSE3(t, 1.0);
    const Vector6d back = LogSE3(T);
    ASSERT_TRUE(back.allFinite()) << "angle " << angle;
    EXPECT_LT((ExpSE3(back, 1.0).matrix() - T.matrix()).norm(), 1e-11) << "angle " << angle;
    if (angle < kPi - 1e-6) {
      EXPECT_LT((back - t).norm(), 1e-9) << "angle " << angle;
    }
  }
  // Pure translation.
  Eigen::Isometry3d P = Eigen::Isometry3d::Identity();
  P.translation() << 1, 2, 3;
  Vector6d expected;
  expected << 0, 0, 0, 1, 2, 3;
  EXPECT_LT((LogSE3(P) - expected).norm(), 1e-15);
}

TEST(LieGroupTest, AdjointIdentities) {
  std::mt19937_64 rng(TestSeed(12345u) + 4);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Isometry3d T1 = RandomPose(rng), T2 = RandomPose(rng);
    // Ad_{T1 T2} = Ad_{T1} Ad_{T2};  Ad_{T⁻¹} = Ad_T⁻¹.
    EXPECT_LT((Adjoint(T1 * T2) - Adjoint(T1) * Adjoint(T2)).norm(), 1e-12);
    EXPECT_LT((Adjoint(T1.inverse()) * Adjoint(T1) - Matrix6d::Identity()).norm(), 1e-12);
    // Twist transformation: T [V] T⁻¹ = [Ad_T V].
    const Vector6d V = RandomTwist(rng, 1.0);
    Eigen::Matrix4d hat = Eigen::Matrix4d::Zero();
    hat.topLeftCorner<3, 3>() = Skew(V.head<3>());
    hat.topRightCorner<3, 1>() = V.tail<3>();
    const Eigen::Matrix4d conj = T1.matrix() * hat * T1.inverse().matrix();
    const Vector6d AdV = Adjoint(T1) * V;
    EXPECT_LT((conj.topLeftCorner<3, 3>() - Skew(AdV.head<3>())).norm(), 1e-12);
    EXPECT_LT((conj.topRightCorner<3, 1>() - AdV.tail<3>()).norm(), 1e-12);
    // T e^{[V]} T⁻¹ = e^{[Ad_T V]}.
    EXPECT_LT(((T1 * ExpSE3(V, 1.0) * T1.inverse()).matrix() - ExpSE3(AdV, 1.0).matrix()).norm(),
              1e-11);
  }
}

TEST(LieGroupTest, LieBracketIsMatrixCommutator) {
  std::mt19937_64 rng(TestSeed(12345u) + 5);
  auto hat = [](const Vector6d& V) {
    Eigen::Matrix4d m = Eigen::Matrix4d::Zero();
    m.topLeftCorner<3, 3>() = Skew(V.head<3>());
    m.topRightCorner<3, 1>() = V.tail<3>();
    return m;
  };
  for (int i = 0; i < 100; ++i) {
    const Vector6d V1 = RandomTwist(rng, 1.3), V2 = RandomTwist(rng, 0.7);
    const Vector6d br = LieBracket(V1) * V2;
    const Eigen::Matrix4d comm = hat(V1) * hat(V2) - hat(V2) * hat(V1);
    EXPECT_LT((hat(br) - comm).norm(), 1e-12);
    // d/dt Ad_{e^{[V1] t}} at t = 0 is ad_{V1}.
    const double h = 1e-6;
    const Matrix6d d = (Adjoint(ExpSE3(V1, h)) - Adjoint(ExpSE3(V1, -h))) / (2 * h);
    EXPECT_LT((d - LieBracket(V1)).norm(), 1e-8);
  }
}

}  // namespace
}  // namespace chasles
