// VerifyTrajectory: a good trajectory passes; collisions, limits, endpoint mismatches and broken
// segments fail with a reason that names what and where.

#include "chasles/optimizers/verification.h"

#include <cmath>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "chasles/optimizers/shortcut.h"
#include "chasles/optimizers/time_parameterization.h"
#include "chasles/robot/error.h"
#include "planar_fixture.h"

namespace chasles {
namespace {

using ::testing::HasSubstr;

KinematicLimits Limits(double v, double a) {
  KinematicLimits limits;
  limits.max_velocity = Eigen::Vector2d::Constant(v);
  limits.max_acceleration = Eigen::Vector2d::Constant(a);
  return limits;
}

class VerificationTest : public ::testing::Test {
 protected:
  void SetUp() override {
    checker_ = test::PlanarCheckerWithPost();
    path_ = ShortcutPath(test::ZigZagAroundPost(), *checker_, ShortcutOptions{});
    // v = 1, a = 10: every segment of ≥ 0.1 rad reaches cruise (trapezoid).
    limits_ = Limits(1.0, 10.0);
    trajectory_ = ParameterizeRestToRest(path_, limits_);
  }
  std::shared_ptr<const CollisionChecker> checker_;
  JointPath path_;
  KinematicLimits limits_;
  TimedTrajectory trajectory_;
};

TEST_F(VerificationTest, GoodTrajectoryPasses) {
  const VerificationReport report =
      VerifyTrajectory(trajectory_, path_.front(), path_.back(), *checker_, limits_);
  EXPECT_TRUE(report.ok) << report.reason;
  EXPECT_EQ(report.reason, "");
  // Dense: at least one state per 0.005 rad of the widest joint motion of every segment.
  double steps = 0;
  for (std::size_t k = 0; k + 1 < path_.size(); ++k) {
    steps += std::ceil((path_[k + 1] - path_[k]).cwiseAbs().maxCoeff() / 0.005);
  }
  EXPECT_GE(report.states_checked, static_cast<int>(steps));
  EXPECT_LE(report.max_velocity_ratio, 1.0 + 1e-9);
  EXPECT_GT(report.max_velocity_ratio, 0.999);  // minimum time: some joint cruises at its limit
  EXPECT_LE(report.max_acceleration_ratio, 1.0 + 1e-9);
  EXPECT_GT(report.max_acceleration_ratio, 0.999);
}

TEST_F(VerificationTest, TrajectoryThroughTheObstacleFailsNamingLinkAndObstacle) {
  const TimedTrajectory straight = ParameterizeRestToRest({path_.front(), path_.back()}, limits_);
  const VerificationReport report = VerifyTrajectory(straight, path_.front(), path_.back(), *checker_, limits_);
  EXPECT_FALSE(report.ok);
  EXPECT_THAT(report.reason, HasSubstr("collision at t = "));
  EXPECT_THAT(report.reason, HasSubstr("between link 'link"));
  EXPECT_THAT(report.reason, HasSubstr("and 'post'"));
  // The reported time is inside the motion, not at its (valid) ends.
  const double t = std::stod(report.reason.substr(report.reason.find("t = ") + 4));
  EXPECT_GT(t, 0.1 * straight.duration());
  EXPECT_LT(t, 0.9 * straight.duration());
}

TEST_F(VerificationTest, TighterLimitsFailNamingTheJoint) {
  VerificationReport report =
      VerifyTrajectory(trajectory_, path_.front(), path_.back(), *checker_, Limits(0.5, 10.0));
  EXPECT_FALSE(report.ok);
  EXPECT_THAT(report.reason, HasSubstr("velocity"));
  EXPECT_THAT(report.reason, HasSubstr("exceeds limit 0.5 rad/s at t = "));
  EXPECT_THAT(report.reason, ::testing::MatchesRegex("joint [01] 'joint[12]' velocity .*"));

  report = VerifyTrajectory(trajectory_, path_.front(), path_.back(), *checker_, Limits(1.0, 9.0));
  EXPECT_FALSE(report.ok);
  EXPECT_THAT(report.reason, ::testing::MatchesRegex("joint [01] 'joint[12]' acceleration .* exceeds limit 9 .*"));

  // Slack within limit_tolerance is accepted.
  VerificationOptions options;
  options.limit_tolerance = 1e-3;
  report = VerifyTrajectory(trajectory_, path_.front(), path_.back(), *checker_, Limits(1.0 / 1.0005, 10.0),
                            options);
  EXPECT_TRUE(report.ok) << report.reason;
}

TEST_F(VerificationTest, EndpointMismatchFails) {
  Eigen::VectorXd goal = path_.back();
  goal[1] += 1e-3;
  VerificationReport report = VerifyTrajectory(trajectory_, path_.front(), goal, *checker_, limits_);
  EXPECT_FALSE(report.ok);
  EXPECT_THAT(report.reason, HasSubstr("from the goal"));
  Eigen::VectorXd start = path_.front();
  start[0] -= 1e-3;
  report = VerifyTrajectory(trajectory_, start, path_.back(), *checker_, limits_);
  EXPECT_FALSE(report.ok);
  EXPECT_THAT(report.reason, HasSubstr("from the start"));
  // Within endpoint_tolerance it passes.
  VerificationOptions options;
  options.endpoint_tolerance = 2e-3;
  EXPECT_TRUE(VerifyTrajectory(trajectory_, start, goal, *checker_, limits_, options).ok);
}

TEST_F(VerificationTest, PositionLimitViolationFailsNamingTheJoint) {
  // Folded elbow (free of the post), joint1 driven past π.
  const JointPath beyond{Eigen::Vector2d(2.8, 2.5), Eigen::Vector2d(3.3, 2.5)};
  const TimedTrajectory traj = ParameterizeRestToRest(beyond, limits_);
  const VerificationReport report = VerifyTrajectory(traj, beyond.front(), beyond.back(), *checker_, limits_);
  EXPECT_FALSE(report.ok);
  EXPECT_THAT(report.reason, HasSubstr("joint 0 'joint1' position"));
  EXPECT_THAT(report.reason, HasSubstr("outside its limits"));
}

TEST_F(VerificationTest, BrokenPiecesFail) {
  auto pieces = trajectory_.pieces();
  ASSERT_GE(pieces.size(), 2u);
  pieces[1].coefficients(0, 0) += 0.01;  // a jump between pieces 0 and 1
  VerificationReport report =
      VerifyTrajectory(TimedTrajectory(pieces), path_.front(), path_.back(), *checker_, limits_);
  EXPECT_FALSE(report.ok);
  EXPECT_THAT(report.reason, HasSubstr("piece 1 does not start where piece 0 ends: joint 0 jumps 0.01 rad"));

  pieces = trajectory_.pieces();
  pieces[0].duration *= 1.01;  // piece 1 no longer starts when piece 0 ends
  report = VerifyTrajectory(TimedTrajectory(pieces), path_.front(), path_.back(), *checker_, limits_);
  EXPECT_FALSE(report.ok);
  EXPECT_THAT(report.reason, HasSubstr("piece 1 starts at t = "));

  pieces = trajectory_.pieces();
  pieces[1].coefficients(1, 1) += 0.1;  // a velocity step
  report = VerifyTrajectory(TimedTrajectory(pieces), path_.front(), path_.back(), *checker_, limits_);
  EXPECT_FALSE(report.ok);
  EXPECT_THAT(report.reason, HasSubstr("piece 1 velocity of joint 1 jumps 0.1"));

  pieces = trajectory_.pieces();
  pieces[2].coefficients(0, 1) = std::nan("");
  report = VerifyTrajectory(TimedTrajectory(pieces), path_.front(), path_.back(), *checker_, limits_);
  EXPECT_FALSE(report.ok);
  EXPECT_THAT(report.reason, HasSubstr("piece 2 has a non-finite coefficient"));

  report = VerifyTrajectory(TimedTrajectory(), path_.front(), path_.back(), *checker_, limits_);
  EXPECT_FALSE(report.ok);
  EXPECT_EQ(report.reason, "trajectory is empty");
}

TEST_F(VerificationTest, InvalidOptionsThrow) {
  VerificationOptions options;
  options.max_joint_step = 0.0;
  try {
    VerifyTrajectory(trajectory_, path_.front(), path_.back(), *checker_, limits_, options);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "verification max_joint_step = 0 must be finite and > 0");
  }
  EXPECT_THROW(VerifyTrajectory(trajectory_, Eigen::Vector3d::Zero(), path_.back(), *checker_, limits_), Error);
  EXPECT_THROW(VerifyTrajectory(trajectory_, path_.front(), path_.back(), *checker_, Limits(-1.0, 1.0)), Error);
}

}  // namespace
}  // namespace chasles
