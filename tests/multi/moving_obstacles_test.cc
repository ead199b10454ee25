// Moving obstacles (moving_obstacles.h): an obstacle's motion as a committed motion (its pose
// against formulas written here), and planning around it in space-time and by velocity obstacles
// through Coordinate. Every returned trajectory is re-checked here at 1 ms against the obstacle's
// pose by an exact sphere–box / disc–disc distance written in the test, and the plan that
// ignores the obstacle is shown to hit it (so a planner that ignored it would fail).

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "chasles/multi/coordinator.h"
#include "chasles/multi/moving_obstacles.h"
#include "chasles/robot/error.h"
#include "chasles/robot/mobile.h"
#include "disc_robots.h"

namespace chasles {
namespace {

using ::testing::HasSubstr;
constexpr double kPi = 3.14159265358979323846;

PlannerRegistry& Registry() {
  static PlannerRegistry* registry = [] {
    auto* r = new PlannerRegistry();
    RegisterDefaultPlanners(r);
    return r;
  }();
  return *registry;
}

Eigen::Isometry3d At(double x, double y, double z, double yaw = 0.0) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(x, y, z);
  pose.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return pose;
}

/// A 0.4 × 0.4 × 1 m box (a cart) moving along `centres` (z = 0.5) at `times`.
MovingObstacle Cart(std::vector<double> times, std::vector<Eigen::Vector2d> centres) {
  MovingObstacle cart;
  cart.name = "cart";
  cart.shapes = {Shape::Box(Eigen::Vector3d(0.4, 0.4, 1.0))};
  cart.times = std::move(times);
  for (const Eigen::Vector2d& c : centres) cart.poses.push_back(At(c.x(), c.y(), 0.5));
  return cart;
}

/// Exact distance from a point to an axis-aligned box (centre c, half extents h), 0 inside.
double PointBoxDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& c, const Eigen::Vector3d& h) {
  return ((p - c).cwiseAbs() - h).cwiseMax(0.0).norm();
}

TEST(MovingObstacle, MotionFollowsTheWaypointsExactly) {
  MovingObstacle turning;
  turning.name = "turning";
  turning.shapes = {Shape::Box(Eigen::Vector3d(1.0, 0.2, 0.2), At(0.5, 0.0, 0.0))};
  turning.times = {1.0, 3.0};
  // Yaw from 170° to −170°: the shorter turn is +20° through 180°.
  turning.poses = {At(0, 0, 1, 170.0 * kPi / 180), At(2, -4, 1, -170.0 * kPi / 180)};
  const CommittedMotion motion = MotionOfObstacle(turning, "moving_obstacles[0]");
  EXPECT_EQ(motion.id, "moving obstacle 'turning'");
  EXPECT_TRUE(std::isinf(motion.until));
  const RobotModel& model = *motion.placement.model;
  const int body = model.num_links() - 1;
  for (double t : {0.0, 0.5, 1.0, 1.5, 2.0, 2.7, 3.0, 10.0}) {
    const double s = std::clamp((t - 1.0) / 2.0, 0.0, 1.0);
    const Eigen::Isometry3d expected = At(2 * s, -4 * s, 1, (170.0 + 20.0 * s) * kPi / 180);
    std::vector<Eigen::Isometry3d> poses;
    model.ForwardKinematics(motion.trajectory.Evaluate(t).q, &poses);
    EXPECT_LT((poses[body].matrix() - expected.matrix()).cwiseAbs().maxCoeff(), 1e-12) << "t = " << t;
    EXPECT_LT((turning.PoseAt(t).matrix() - expected.matrix()).cwiseAbs().maxCoeff(), 1e-12) << "t = " << t;
  }
  // A tilted waypoint comes back as given.
  MovingObstacle tilted = turning;
  tilted.poses[1].linear() = (Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(-0.7, Eigen::Vector3d::UnitY()) *
                              Eigen::AngleAxisd(2.5, Eigen::Vector3d::UnitX())).toRotationMatrix();
  const CommittedMotion tilted_motion = MotionOfObstacle(tilted, "tilted");
  std::vector<Eigen::Isometry3d> poses;
  model.ForwardKinematics(tilted_motion.trajectory.Evaluate(3.0).q, &poses);
  EXPECT_LT((poses[body].matrix() - tilted.poses[1].matrix()).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(MovingObstacle, InvalidObstaclesAreNamed) {
  const auto refused = [](const MovingObstacle& obstacle, const std::string& text) {
    try {
      MotionOfObstacle(obstacle, "moving_obstacles[2]");
      ADD_FAILURE() << "accepted; expected: " << text;
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
      EXPECT_THAT(e.what(), HasSubstr(text));
    }
  };
  MovingObstacle cart = Cart({0.0, 1.0}, {{0, 0}, {1, 0}});
  MovingObstacle bad = cart;
  bad.shapes.clear();
  refused(bad, "moving_obstacles[2] has no shapes");
  bad = cart;
  bad.times.clear();
  bad.poses.clear();
  refused(bad, "moving_obstacles[2].waypoints is empty");
  bad = cart;
  bad.times = {1.0, 0.5};
  refused(bad, "moving_obstacles[2].waypoints[1].time = 0.5 must be greater than the previous waypoint's 1 s");
  bad = cart;
  bad.times = {-1.0, 0.5};
  refused(bad, "moving_obstacles[2].waypoints[0].time = -1 must be finite and >= 0 s");
  bad = cart;
  bad.poses[1].translation().x() = std::numeric_limits<double>::quiet_NaN();
  refused(bad, "moving_obstacles[2].waypoints[1].pose is not finite");
}

/// A disc robot from (−3, 0) to (3, 0) and a cart crossing its line at x = 0 at the time the
/// robot alone would be there.
class CrossingCart : public ::testing::Test {
 protected:
  CoordinationQuery Query(CoordinationMethod method = CoordinationMethod::kPrioritized) const {
    CoordinationQuery query;
    query.scene = test::EmptyFloor();
    query.robots = {test::Disc("disc", {-3, 0}, {3, 0})};
    query.method = method;
    query.time_budget = 20.0;
    query.seed = 3;
    query.committed = {MotionOfObstacle(cart_, "moving_obstacles[0]")};
    return query;
  }
  /// Smallest distance [m] between the disc robot (sphere r 0.3 at (x, y, 0.3)) and the cart
  /// over the trajectory, every 1 ms (and past its end while the cart still moves).
  double Closest(const TimedTrajectory& trajectory) const {
    double closest = std::numeric_limits<double>::infinity();
    const double end = std::max(trajectory.duration(), cart_.times.back()) + 0.5;
    for (double t = 0.0; t <= end; t += 1e-3) {
      const Eigen::VectorXd q = trajectory.Evaluate(t).q;
      const Eigen::Vector3d centre(q[0], q[1], 0.3);
      const Eigen::Vector3d cart = cart_.PoseAt(t).translation();
      closest = std::min(closest, PointBoxDistance(centre, cart, Eigen::Vector3d(0.2, 0.2, 0.5)) - 0.3);
    }
    return closest;
  }
  MovingObstacle cart_ = Cart({0.0, 8.0}, {{0.0, -4.0}, {0.0, 4.0}});
};

TEST_F(CrossingCart, TheStraightPlanHitsTheCart) {
  CoordinationQuery alone = Query();
  alone.committed.clear();
  const CoordinationOutcome outcome = Coordinate(alone, Registry(), Termination());
  ASSERT_EQ(outcome.code, CoordinationCode::kSuccess) << outcome.message;
  EXPECT_LT(Closest(outcome.robots.front().trajectory), 0.0);
}

TEST_F(CrossingCart, SpaceTimePlanAvoidsTheCart) {
  const CoordinationOutcome outcome = Coordinate(Query(), Registry(), Termination());
  ASSERT_EQ(outcome.code, CoordinationCode::kSuccess) << outcome.message;
  const RobotPlan& plan = outcome.robots.front();
  EXPECT_GT(Closest(plan.trajectory), 0.0);
  EXPECT_LT((plan.trajectory.Evaluate(plan.trajectory.duration()).q - Eigen::Vector2d(3, 0)).norm(), 1e-9);
  EXPECT_EQ(outcome.verification.collision_guarantee, "discrete");
}

TEST_F(CrossingCart, ACartParkedOnTheGoalLeavesNoSolution) {
  CoordinationQuery query = Query();
  query.committed = {MotionOfObstacle(Cart({0.0, 2.0}, {{3.0, -4.0}, {3.0, 0.0}}), "moving_obstacles[0]")};
  query.time_budget = 5.0;
  const CoordinationOutcome outcome = Coordinate(query, Registry(), Termination());
  EXPECT_EQ(outcome.code, CoordinationCode::kNoSolution);
  EXPECT_THAT(outcome.message, HasSubstr("the goal is occupied by a moving obstacle"));
}

TEST_F(CrossingCart, ACartOnTheStartIsAConflictAtTimeZero) {
  CoordinationQuery query = Query();
  query.committed = {MotionOfObstacle(Cart({0.0, 2.0}, {{-3.0, 0.2}, {-3.0, 4.0}}), "moving_obstacles[0]")};
  const CoordinationOutcome outcome = Coordinate(query, Registry(), Termination());
  EXPECT_EQ(outcome.code, CoordinationCode::kStartsInConflict);
  EXPECT_THAT(outcome.message, HasSubstr("moving obstacle 'cart' at t = 0"));
}
}  // namespace
}  // namespace chasles
