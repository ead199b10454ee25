// VerifyTrajectory: a good trajectory passes; collisions, limits, endpoint mismatches and broken
// segments fail with a reason that names what and where.

#include "chasles/optimizers/verification.h"

#include <algorithm>
#include <cmath>
#include <limits>
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
  // The sphere path certifies every piece: at least one advancement state per piece.
  ASSERT_TRUE(checker_->certifies_motion());
  EXPECT_EQ(report.collision_guarantee, "certified");
  EXPECT_EQ(report.collision_guarantee_reason, "");
  EXPECT_GE(report.states_checked, static_cast<int>(trajectory_.pieces().size()));
  EXPECT_LE(report.max_velocity_ratio, 1.0 + 1e-9);
  EXPECT_GT(report.max_velocity_ratio, 0.999);  // minimum time: some joint cruises at its limit
  EXPECT_LE(report.max_acceleration_ratio, 1.0 + 1e-9);
  EXPECT_GT(report.max_acceleration_ratio, 0.999);

  // On the FCL path the check is discrete: at least one state per 0.005 rad of the widest joint
  // motion of every segment, and the report says so and why.
  CollisionOptions fcl;
  fcl.force_fcl = true;
  const CollisionChecker discrete(checker_->robot_ptr(), std::make_shared<Scene>(checker_->scene()), fcl);
  const VerificationReport sampled = VerifyTrajectory(trajectory_, path_.front(), path_.back(), discrete, limits_);
  EXPECT_TRUE(sampled.ok) << sampled.reason;
  double steps = 0;
  for (std::size_t k = 0; k + 1 < path_.size(); ++k) {
    steps += std::ceil((path_[k + 1] - path_[k]).cwiseAbs().maxCoeff() / 0.005);
  }
  EXPECT_GE(sampled.states_checked, static_cast<int>(steps));
  EXPECT_EQ(sampled.collision_guarantee, "discrete");
  EXPECT_THAT(sampled.collision_guarantee_reason, HasSubstr("at most 0.005 rad apart"));
  EXPECT_THAT(sampled.collision_guarantee_reason, HasSubstr("force_fcl"));
}

/// The stretched planar arm swinging q1 up to `apex` and back along q1(τ) = apex − (τ − τ*)²
/// over [0, 2] s (q2 = 0), and a wall above it whose face the tip sphere (centre 2 m out,
/// radius 0.08 m) crosses by `depth` [m] at the apex only.
struct DippingSwing {
  static constexpr double kApex = 0.3;
  double apex_time = 0.0;
  TimedTrajectory trajectory;
  std::shared_ptr<const Scene> scene;
  /// The trajectory moves at both ends.
  VerificationOptions Options() const {
    VerificationOptions options;
    options.start_velocity = trajectory.Evaluate(0.0).qd;
    options.end_velocity = trajectory.Evaluate(trajectory.duration()).qd;
    return options;
  }
};

DippingSwing MakeDippingSwing(double depth) {
  DippingSwing out;
  // max|q̇| = 2·(2 − τ*) = 2.8 rad/s nearly: 1120 states at 0.005 rad, 1/560 s apart; τ* lies
  // half-way between two of them, where q1 is 8e-7 rad (the tip 1.5 µm) below the apex.
  out.apex_time = 0.6 + 0.5 / 560.0;
  TimedTrajectory::Piece piece;
  piece.duration = 2.0;
  piece.coefficients = Eigen::MatrixXd::Zero(2, 3);
  const double ts = out.apex_time;
  piece.coefficients.row(0) << DippingSwing::kApex - ts * ts, 2.0 * ts, -1.0;
  out.trajectory = TimedTrajectory({piece});
  auto scene = std::make_shared<Scene>();
  const double face = 2.0 * std::sin(DippingSwing::kApex) + 0.08 - depth;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(2.0, face + 0.2, 0.0);
  scene->AddObject({"wall", Shape::Box(Eigen::Vector3d(0.6, 0.4, 0.4), pose)});
  out.scene = scene;
  return out;
}

TEST(CertifiedVerification, APieceThatDipsIntoAnObstacleBetweenDiscreteStatesIsRejected) {
  const DippingSwing swing = MakeDippingSwing(0.5e-6);  // 0.5 µm deep, for about 1 ms
  const TimedTrajectory& trajectory = swing.trajectory;
  const Eigen::VectorXd start = trajectory.Evaluate(0.0).q, goal = trajectory.Evaluate(2.0).q;
  const KinematicLimits limits = Limits(3.0, 10.0);
  const CollisionChecker checker(test::PlanarArm(), swing.scene);
  ASSERT_TRUE(checker.certifies_motion());
  // The apex state itself collides; the discrete states around it do not.
  ASSERT_FALSE(checker.IsValid(trajectory.Evaluate(swing.apex_time).q));
  ASSERT_EQ(std::ceil(trajectory.pieces()[0].MaxJointTravel() / 0.005), 1120.0);
  for (int i : {336, 337}) ASSERT_TRUE(checker.IsValid(trajectory.Evaluate(i / 560.0).q)) << i;

  const VerificationReport report = VerifyTrajectory(trajectory, start, goal, checker, limits, swing.Options());
  EXPECT_FALSE(report.ok);
  EXPECT_EQ(report.collision_guarantee, "certified");
  EXPECT_THAT(report.reason, HasSubstr("between link 'link2' and 'wall'"));
  const double t = std::stod(report.reason.substr(report.reason.find("t = ") + 4));
  EXPECT_NEAR(t, swing.apex_time, 2e-3) << report.reason;

  // The same trajectory checked at discrete states (FCL path) passes: the dip falls between them.
  CollisionOptions fcl;
  fcl.force_fcl = true;
  const CollisionChecker discrete(test::PlanarArm(), swing.scene, fcl);
  const VerificationReport sampled = VerifyTrajectory(trajectory, start, goal, discrete, limits, swing.Options());
  EXPECT_TRUE(sampled.ok) << sampled.reason;
  EXPECT_EQ(sampled.collision_guarantee, "discrete");

  // With the wall 0.1 mm higher the swing is certified free.
  const DippingSwing clear = MakeDippingSwing(-1e-4);
  const CollisionChecker clear_checker(test::PlanarArm(), clear.scene);
  const VerificationReport free = VerifyTrajectory(clear.trajectory, start, goal, clear_checker, limits, clear.Options());
  EXPECT_TRUE(free.ok) << free.reason;
  // ... and its min_clearance is a lower bound on the true minimum, 0.1 mm at the apex.
  const TrajectoryQuality quality = MeasureTrajectory(clear.trajectory, limits, {}, &clear_checker);
  EXPECT_LE(quality.min_clearance, 1e-4 + 1e-12);
  EXPECT_GE(quality.min_clearance, 0.0);
  // With the wall 1 mm higher: a lower bound on the 1 mm minimum, within the documented 1e-4 m.
  const DippingSwing far = MakeDippingSwing(-1e-3);
  const CollisionChecker far_checker(test::PlanarArm(), far.scene);
  const TrajectoryQuality far_quality = MeasureTrajectory(far.trajectory, limits, {}, &far_checker);
  EXPECT_LE(far_quality.min_clearance, 1e-3 + 1e-12);
  EXPECT_GE(far_quality.min_clearance, 1e-3 - 1e-4 - 1e-12);
}

// A piece along a line that goes out and comes back (it starts and ends at rest at q = 0): its
// certification and its min_clearance cover every configuration it sweeps, out to q1 = 1 rad,
// not only its ends. min_clearance is checked against the FCL path's clearance at 20001 states
// of the sweep (a second implementation).
TEST(CertifiedVerification, ALinePieceThatTurnsBackIsCertifiedAndMeasuredOverItsWholeSweep) {
  TimedTrajectory::Piece piece;  // q1(τ) = 16 τ²(1 − τ)², q2 = 0: out to 1 rad at τ = 0.5, back
  piece.duration = 1.0;
  piece.coefficients = Eigen::MatrixXd::Zero(2, 5);
  piece.coefficients.row(0) << 0.0, 0.0, 16.0, -32.0, 16.0;
  const TimedTrajectory trajectory({piece});
  const Eigen::VectorXd rest = Eigen::Vector2d::Zero();
  const KinematicLimits limits = Limits(4.0, 40.0);  // peaks 3.08 rad/s, 32 rad/s²
  // A ball of 5 cm radially outside the tip sphere's path (centre 2 m out, radius 0.08 m) at
  // q1 = 0.9, `gap` from it.
  const auto ball_at = [](double gap) {
    auto scene = std::make_shared<Scene>();
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = (2.0 + 0.08 + 0.05 + gap) * Eigen::Vector3d(std::cos(0.9), std::sin(0.9), 0.0);
    scene->AddObject({"ball", Shape::Sphere(0.05, pose)});
    return scene;
  };
  const CollisionChecker hit(test::PlanarArm(), ball_at(-0.01));
  ASSERT_TRUE(hit.certifies_motion());
  ASSERT_TRUE(hit.IsValid(rest));
  const VerificationReport rejected = VerifyTrajectory(trajectory, rest, rest, hit, limits);
  EXPECT_FALSE(rejected.ok);
  EXPECT_THAT(rejected.reason, HasSubstr("between link 'link2' and 'ball'"));

  const auto scene = ball_at(0.003);
  const CollisionChecker checker(test::PlanarArm(), scene);
  const VerificationReport report = VerifyTrajectory(trajectory, rest, rest, checker, limits);
  EXPECT_TRUE(report.ok) << report.reason;
  CollisionOptions fcl;
  fcl.force_fcl = true;
  const CollisionChecker dense(test::PlanarArm(), scene, fcl);
  double truth = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= 20000; ++i) truth = std::min(truth, dense.Clearance(Eigen::Vector2d(i / 20000.0, 0.0)));
  ASSERT_NEAR(truth, 0.003, 1e-6);
  const TrajectoryQuality quality = MeasureTrajectory(trajectory, limits, {}, &checker);
  EXPECT_LE(quality.min_clearance, truth + 1e-9);
  EXPECT_GE(quality.min_clearance, truth - 1e-4 - 1e-9);  // within the documented tolerance
}

TEST(CertifiedVerification, AMotionGrazingAnObstacleWithinRoundingIsNotCertified) {
  // The stretched arm sweeps q1 through π/2 at 1 rad/s; a ceiling 1e-12 m above the tip
  // sphere's top at π/2. The sphere moves sideways there, so the advancement's steps
  // (clearance / sweep bound) fall below 1e-7: not certified, though no state collides.
  TimedTrajectory::Piece piece;
  piece.duration = 1.0;
  piece.coefficients = Eigen::MatrixXd::Zero(2, 2);
  piece.coefficients.row(0) << M_PI / 2 - 0.5, 1.0;
  const TimedTrajectory trajectory({piece});
  VerificationOptions options;
  options.start_velocity = options.end_velocity = Eigen::Vector2d(1.0, 0.0);
  const auto ceiling = [](double gap) {
    auto scene = std::make_shared<Scene>();
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = Eigen::Vector3d(0.0, 2.08 + gap + 0.1, 0.0);
    scene->AddObject({"ceiling", Shape::Box(Eigen::Vector3d(0.6, 0.2, 0.4), pose)});
    return scene;
  };
  const Eigen::VectorXd start = trajectory.Evaluate(0.0).q, goal = trajectory.Evaluate(1.0).q;
  const CollisionChecker checker(test::PlanarArm(), ceiling(1e-12));
  ASSERT_TRUE(checker.IsValid(Eigen::Vector2d(M_PI / 2, 0.0)));
  const VerificationReport report = VerifyTrajectory(trajectory, start, goal, checker, Limits(3.0, 10.0), options);
  EXPECT_FALSE(report.ok);
  EXPECT_THAT(report.reason, HasSubstr("not certified at t = "));
  EXPECT_THAT(report.reason, HasSubstr("link 'link2' passes within rounding of 'ceiling'"));
  const double t = std::stod(report.reason.substr(report.reason.find("t = ") + 4));
  EXPECT_NEAR(t, 0.5, 1e-3) << report.reason;
  // 10 µm of room is proven.
  const CollisionChecker roomy(test::PlanarArm(), ceiling(1e-5));
  EXPECT_TRUE(VerifyTrajectory(trajectory, start, goal, roomy, Limits(3.0, 10.0), options).ok);
}

TEST(CertifiedVerification, MeshScenesAndBoxRobotsAreCheckedDiscretelyAndSaySo) {
  const DippingSwing swing = MakeDippingSwing(-1e-3);
  const Eigen::VectorXd start = swing.trajectory.Evaluate(0.0).q, goal = swing.trajectory.Evaluate(2.0).q;
  // The wall as a triangle mesh (a tetrahedron well above the swing).
  auto mesh = std::make_shared<TriangleMesh>();
  mesh->vertices = {{0, 0, 0}, {0.1, 0, 0}, {0, 0.1, 0}, {0, 0, 0.1}};
  mesh->triangles = {{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}};
  Shape shape;
  shape.type = ShapeType::kMesh;
  shape.mesh = mesh;
  shape.pose.translation() = Eigen::Vector3d(2.0, 1.5, 0.0);
  auto scene = std::make_shared<Scene>(*swing.scene);
  scene->AddObject({"tetra", shape});
  const CollisionChecker checker(test::PlanarArm(), scene);
  ASSERT_TRUE(checker.uses_fast_path());
  ASSERT_FALSE(checker.certifies_motion());
  const VerificationReport report =
      VerifyTrajectory(swing.trajectory, start, goal, checker, Limits(3.0, 10.0), swing.Options());
  EXPECT_TRUE(report.ok) << report.reason;
  EXPECT_EQ(report.collision_guarantee, "discrete");
  EXPECT_THAT(report.collision_guarantee_reason, HasSubstr("scene meshes 'tetra'"));
  EXPECT_EQ(DiscreteCheckCause(checker), "scene meshes 'tetra'");
  EXPECT_GE(report.states_checked, 1120);

  // A robot with a box shape takes the FCL path: the cause names the link and the shape.
  Link base, mover;
  base.name = "base";
  mover.name = "block";
  mover.parent_joint = 0;
  mover.collision.push_back(Shape::Box(Eigen::Vector3d(0.1, 0.1, 0.1)));
  Joint slide;
  slide.name = "slide_x";
  slide.type = JointType::kPrismatic;
  slide.parent_link = 0;
  slide.child_link = 1;
  slide.axis = Eigen::Vector3d::UnitX();
  slide.limits = {-1.0, 1.0, 1.0, 0.0};
  slide.dof = 0;
  const CollisionChecker boxes(RobotModel::FromTree("slider", {base, mover}, {slide}), swing.scene);
  ASSERT_FALSE(boxes.certifies_motion());
  EXPECT_EQ(DiscreteCheckCause(boxes), "robot links with shapes other than spheres: 'block' (box)");
}

// quality.max_deviation is the largest distance of a trajectory state from the path's polyline
// and of a waypoint from the trajectory's: here with blended corners (0.05 rad allowed), states
// 0.001 rad apart, against the same figure computed here by brute force on states 0.0002 rad
// apart (every point against every segment).
TEST_F(VerificationTest, MaxDeviationMatchesABruteForceOverDenseStates) {
  TimeOptimalOptions options;
  options.max_deviation = 0.05;
  const TimedTrajectory blended = ParameterizeTimeOptimal(path_, limits_, options);
  const TrajectoryQuality quality = MeasureTrajectory(blended, limits_, path_, nullptr, 0.001);
  std::vector<Eigen::VectorXd> dense;
  for (const TimedTrajectory::Piece& piece : blended.pieces()) {
    const int m = std::max(1, static_cast<int>(std::ceil(piece.MaxJointTravel() / 0.0002)));
    for (int i = 0; i <= m; ++i) dense.push_back(piece.State(piece.duration * i / m).q);
  }
  const auto to_segment = [](const Eigen::VectorXd& x, const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
    const Eigen::VectorXd ab = b - a;
    const double s = ab.squaredNorm() > 0.0 ? std::clamp((x - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0) : 0.0;
    return (x - (a + s * ab)).norm();
  };
  double expected = 0.0;
  for (const Eigen::VectorXd& x : dense) {
    double nearest = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k + 1 < path_.size(); ++k) nearest = std::min(nearest, to_segment(x, path_[k], path_[k + 1]));
    expected = std::max(expected, nearest);
  }
  for (const Eigen::VectorXd& w : path_) {
    double nearest = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k + 1 < dense.size(); ++k) nearest = std::min(nearest, to_segment(w, dense[k], dense[k + 1]));
    expected = std::max(expected, nearest);
  }
  ASSERT_GT(expected, 0.01);  // the blends cut the corners
  EXPECT_NEAR(quality.max_deviation, expected, 1e-5);
}

TEST_F(VerificationTest, ABlendIsReportedWithinTheDeviationItWasBuiltFor) {
  // A right-angle corner, blended at 0.05 rad: the blend passes the corner at 0.05 rad exactly
  // (TOPP's bound, tight at the corner). The figure measured from each waypoint used to be the
  // distance to chords between sampled states, which lie outside the blend's curve: 0.0510.
  KinematicLimits limits;
  limits.max_velocity = Eigen::Vector2d(1.0, 1.0);
  limits.max_acceleration = Eigen::Vector2d(1.0, 1.0);
  const JointPath corner = {Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(1.0, 0.0), Eigen::Vector2d(1.0, 1.0)};
  TimeOptimalOptions options;
  options.max_deviation = 0.05;
  const TimedTrajectory blended = ParameterizeTimeOptimal(corner, limits, options);
  // Independently: the corner's distance to states 1e-6 s apart over the whole trajectory.
  double nearest = std::numeric_limits<double>::infinity();
  for (double t = 0.0; t <= blended.duration(); t += 1e-6) nearest = std::min(nearest, (blended.Evaluate(t).q - corner[1]).norm());
  for (double step : {0.01, 0.05, 0.2}) {
    const TrajectoryQuality quality = MeasureTrajectory(blended, limits, corner, nullptr, step);
    EXPECT_LE(quality.max_deviation, options.max_deviation * (1 + 1e-9)) << "step " << step;
    EXPECT_NEAR(quality.max_deviation, nearest, 1e-6) << "step " << step;
  }
}

TEST_F(VerificationTest, ADeviationBetweenSampledStatesIsFoundExactly) {
  // One cubic piece along the x axis that bulges off it: y(τ) = 0.3·τ²(1 − τ) peaks at τ = 2/3
  // with 0.3·4/27 = 0.0444…, between the states a coarse step samples (at 0.2: 0.0432).
  TimedTrajectory::Piece piece;
  piece.duration = 1.0;
  piece.coefficients = Eigen::MatrixXd::Zero(2, 4);
  piece.coefficients(0, 1) = 1.0;
  piece.coefficients(1, 2) = 0.3;
  piece.coefficients(1, 3) = -0.3;
  const TimedTrajectory bulge({piece}, Eigen::Vector2d(1.0, 0.0));
  const JointPath line = {Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(1.0, 0.0)};
  const double exact = 0.3 * 4.0 / 27.0;
  KinematicLimits limits;
  limits.max_velocity = Eigen::Vector2d(10.0, 10.0);
  limits.max_acceleration = Eigen::Vector2d(10.0, 10.0);
  for (double step : {0.01, 0.05, 0.2}) {
    const TrajectoryQuality quality = MeasureTrajectory(bulge, limits, line, nullptr, step);
    EXPECT_LE(quality.max_deviation, exact + 1e-12) << "step " << step;
    EXPECT_NEAR(quality.max_deviation, exact, 1e-9) << "step " << step;
  }
  // Around a corner (the largest distance where the nearest segment changes): the blend's middle.
  const JointPath corner = {Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(1.0, 0.0), Eigen::Vector2d(1.0, 1.0)};
  TimeOptimalOptions options;
  options.max_deviation = 0.05;
  const TimedTrajectory blended = ParameterizeTimeOptimal(corner, limits, options);
  double farthest = 0.0;  // independently: states 1e-6 s apart, distance to the polyline
  for (double t = 0.0; t <= blended.duration(); t += 1e-6) {
    const Eigen::VectorXd q = blended.Evaluate(t).q;
    double d = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k + 1 < corner.size(); ++k) {
      const Eigen::VectorXd ab = corner[k + 1] - corner[k];
      const double s = std::clamp((q - corner[k]).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
      d = std::min(d, (q - corner[k] - s * ab).norm());
    }
    farthest = std::max(farthest, d);
  }
  double to_corner = std::numeric_limits<double>::infinity();  // and the other way, from the corner
  for (double t = 0.0; t <= blended.duration(); t += 1e-6) to_corner = std::min(to_corner, (blended.Evaluate(t).q - corner[1]).norm());
  for (double step : {0.01, 0.2}) {
    const TrajectoryQuality quality = MeasureTrajectory(blended, limits, corner, nullptr, step);
    EXPECT_GE(quality.max_deviation, farthest - 1e-12) << "step " << step;
    EXPECT_NEAR(quality.max_deviation, std::max(farthest, to_corner), 1e-5) << "step " << step;  // the dense spacing
  }
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
  // The jump is 0.01 up to the rounding of the previous piece's end value.
  EXPECT_THAT(report.reason, HasSubstr("piece 1 does not start where piece 0 ends: joint 0 jumps 0.01"));
  const std::size_t jumps = report.reason.find("jumps ");
  ASSERT_NE(jumps, std::string::npos);
  EXPECT_NEAR(std::stod(report.reason.substr(jumps + 6)), 0.01, 1e-12) << report.reason;

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
