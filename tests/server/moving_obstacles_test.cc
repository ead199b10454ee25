// Moving obstacles and the replanning stream over loopback gRPC.
//
// examples/requests/base_crossing_people.json: a planar base crosses a yard while two people walk
// across its route; its straight plan meets the first one. Every returned trajectory is re-checked
// here with the base's two body spheres and each walker's upright cylinder placed by formulas
// written in this test (linear walks, horizontal distances), at 1 ms samples: planned in
// space-time and by velocity obstacles, the base never touches a walker; planned without them
// it does (so a server that ignored them fails).
//
// Replan: a stream keeps its trajectory while nothing changes, replans (braking first from its
// velocity) when a box lands on its way or a walker appears, and plans afresh for a new goal;
// invalid messages end the stream naming the message and the field.

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "server_fixture.h"

namespace chasles::testing {
namespace {

using ::testing::HasSubstr;

/// A walker: an upright cylinder of radius 0.3 m moving linearly between timed (x, y) points.
struct Walker {
  std::vector<double> times;
  std::vector<Eigen::Vector2d> points;
  Eigen::Vector2d At(double t) const {
    if (t <= times.front()) return points.front();
    if (t >= times.back()) return points.back();
    std::size_t k = 0;
    while (times[k + 1] < t) ++k;
    const double s = (t - times[k]) / (times[k + 1] - times[k]);
    return points[k] + s * (points[k + 1] - points[k]);
  }
};

std::vector<Walker> WalkersOf(const google::protobuf::RepeatedPtrField<v1::MovingObstacle>& obstacles) {
  std::vector<Walker> walkers;
  for (const v1::MovingObstacle& o : obstacles) {
    Walker w;
    for (const v1::TimedPose& p : o.waypoints()) {
      w.times.push_back(p.time());
      w.points.emplace_back(p.pose().position().x(), p.pose().position().y());
    }
    walkers.push_back(w);
  }
  return walkers;
}

/// Smallest clearance [m] between the base's body spheres (radius 0.2 at ±0.15 m along its
/// heading) and the walkers (radius 0.3) over the samples; sample time t is stream time t + offset.
double WalkerClearance(const v1::JointTrajectory& trajectory, const std::vector<Walker>& walkers, double offset = 0.0) {
  double closest = std::numeric_limits<double>::infinity();
  for (const v1::TrajectoryPoint& p : trajectory.points()) {
    const double x = p.positions(0), y = p.positions(1), theta = p.positions(2);
    for (const double along : {0.15, -0.15}) {
      const Eigen::Vector2d sphere(x + along * std::cos(theta), y + along * std::sin(theta));
      for (const Walker& w : walkers) {
        closest = std::min(closest, (sphere - w.At(p.time_from_start() + offset)).norm() - 0.2 - 0.3);
      }
    }
  }
  return closest;
}

/// Smallest clearance [m] between the body spheres and an axis-aligned box (centre, half extents;
/// the spheres' centres are at z = 0.25, inside the box's height), exact point–box distance.
double BoxClearance(const v1::JointTrajectory& trajectory, const Eigen::Vector2d& centre, const Eigen::Vector2d& half) {
  double closest = std::numeric_limits<double>::infinity();
  for (const v1::TrajectoryPoint& p : trajectory.points()) {
    for (const double along : {0.15, -0.15}) {
      const Eigen::Vector2d sphere(p.positions(0) + along * std::cos(p.positions(2)),
                                   p.positions(1) + along * std::sin(p.positions(2)));
      closest = std::min(closest, ((sphere - centre).cwiseAbs() - half).cwiseMax(0.0).norm() - 0.2);
    }
  }
  return closest;
}

class MovingObstacles : public SharedServerTest<> {
 protected:
  static v1::PlanRequest Example(const std::string& name) {
    v1::PlanRequest request = LoadRequest(name);
    request.mutable_trajectory()->set_sample_period(0.001);
    return request;
  }
};

TEST_F(MovingObstacles, WithoutThemTheBaseWalksIntoAPerson) {
  v1::PlanRequest request = Example("base_crossing_people");
  const std::vector<Walker> walkers = WalkersOf(request.moving_obstacles());
  request.clear_moving_obstacles();
  v1::PlanResponse response;
  ASSERT_TRUE(server_->Plan(request, &response).ok());
  ASSERT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  EXPECT_LT(WalkerClearance(response.trajectory(), walkers), 0.0);
}

TEST_F(MovingObstacles, SpaceTimePlanKeepsClearOfBothWalkers) {
  const v1::PlanRequest request = Example("base_crossing_people");
  v1::PlanResponse response;
  const grpc::Status status = server_->Plan(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  EXPECT_GT(WalkerClearance(response.trajectory(), WalkersOf(request.moving_obstacles())), 0.0);
  const v1::TrajectoryPoint& last = response.trajectory().points(response.trajectory().points_size() - 1);
  EXPECT_NEAR(last.positions(0), 11.0, 1e-9);
  EXPECT_NEAR(last.positions(1), 4.0, 1e-9);
  EXPECT_LE(response.verification().max_velocity_ratio(), 1.0 + 1e-9);
  EXPECT_EQ(response.verification().collision_guarantee(), "discrete");
}

TEST_F(MovingObstacles, VelocityObstaclesSteerClearOfBothWalkers) {
  const v1::PlanRequest request = Example("base_crossing_people_vo");
  v1::PlanResponse response;
  const grpc::Status status = server_->Plan(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  EXPECT_THAT(response.message(), HasSubstr("velocity_obstacles"));
  EXPECT_GT(WalkerClearance(response.trajectory(), WalkersOf(request.moving_obstacles())), 0.0);
  const v1::TrajectoryPoint& last = response.trajectory().points(response.trajectory().points_size() - 1);
  EXPECT_NEAR(last.positions(0), 11.0, 1e-9);
  EXPECT_NEAR(last.positions(1), 4.0, 1e-9);
  EXPECT_LE(response.verification().max_velocity_ratio(), 1.0 + 1e-9);
  EXPECT_LE(response.verification().max_acceleration_ratio(), 1.0 + 1e-9);
}

TEST_F(MovingObstacles, AWalkerStandingOnTheGoalOrStartIsAnOutcome) {
  v1::PlanRequest request = Example("base_crossing_people");
  request.set_time_budget(3.0);
  v1::TimedPose* stop = request.mutable_moving_obstacles(1)->add_waypoints();
  stop->set_time(12.0);
  stop->mutable_pose()->mutable_position()->set_x(11.0);
  stop->mutable_pose()->mutable_position()->set_y(4.0);
  v1::PlanResponse response;
  ASSERT_TRUE(server_->Plan(request, &response).ok());
  EXPECT_EQ(response.outcome(), v1::NO_PATH_WITHIN_BUDGET) << response.message();
  EXPECT_THAT(response.message(), HasSubstr("the goal is occupied by a moving obstacle"));
  EXPECT_THAT(response.message(), HasSubstr("most conflicts with moving obstacle 'walker_b'"));

  request = Example("base_crossing_people");
  request.mutable_moving_obstacles(0)->mutable_waypoints(0)->mutable_pose()->mutable_position()->set_x(1.2);
  request.mutable_moving_obstacles(0)->mutable_waypoints(0)->mutable_pose()->mutable_position()->set_y(4.0);
  ASSERT_TRUE(server_->Plan(request, &response).ok());
  EXPECT_EQ(response.outcome(), v1::STARTS_IN_CONFLICT) << response.message();
  EXPECT_THAT(response.message(), HasSubstr("moving obstacle 'walker_a' at t = 0"));
}

TEST_F(MovingObstacles, InvalidObstaclesAreNamed) {
  const auto refused = [&](const v1::PlanRequest& request, const std::string& text) {
    v1::PlanResponse response;
    const grpc::Status status = server_->Plan(request, &response);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << text;
    EXPECT_THAT(status.error_message(), HasSubstr(text));
  };
  v1::PlanRequest request = Example("base_crossing_people");
  request.mutable_moving_obstacles(1)->clear_cylinders();
  refused(request, "moving_obstacles[1] has no shapes");
  request = Example("base_crossing_people");
  request.mutable_moving_obstacles(0)->mutable_waypoints(1)->set_time(-2.0);
  refused(request, "moving_obstacles[0].waypoints[1].time = -2 must be finite and >= 0 s");
  request = Example("base_crossing_people");
  request.mutable_moving_obstacles(0)->mutable_waypoints(1)->set_time(0.0);
  refused(request, "moving_obstacles[0].waypoints[1].time = 0 must be greater than the previous waypoint's 0 s");
  request = Example("base_crossing_people");
  request.mutable_moving_obstacles(0)->clear_waypoints();
  refused(request, "moving_obstacles[0].waypoints is empty");
  request = Example("base_crossing_people");
  request.mutable_moving_obstacles(0)->mutable_cylinders(0)->set_radius(0.0);
  refused(request, "moving_obstacles[0].cylinders[0].radius");
  request = Example("base_crossing_people");
  request.set_moving_obstacle_method(static_cast<v1::PlanRequest::MovingObstacleMethod>(7));
  refused(request, "moving_obstacle_method = 7 is not a method (SPACE_TIME, VELOCITY_OBSTACLES)");
  request = Example("base_crossing_people");
  request.set_padding(0.05);
  refused(request, "padding = 0.05 is not supported with moving_obstacles");
  // Velocity obstacles steer planar bases only.
  v1::PlanRequest arm = LoadRequest("panda_table");
  *arm.mutable_moving_obstacles() = Example("base_crossing_people").moving_obstacles();
  arm.set_moving_obstacle_method(v1::PlanRequest::VELOCITY_OBSTACLES);
  refused(arm, "method velocity_obstacles steers one planar base");
}

// ---- Replan -------------------------------------------------------------------------------------

class Replan : public SharedServerTest<> {
 protected:
  /// The yard without walkers: (1, 4) → (11, 4), samples every 1 ms.
  static v1::PlanRequest Problem() {
    v1::PlanRequest request = LoadRequest("base_crossing_people");
    request.clear_moving_obstacles();
    request.mutable_trajectory()->set_sample_period(0.001);
    return request;
  }
  /// One stream: each message written, its answer read; the final status in *status.
  std::vector<v1::ReplanResponse> Run(const std::vector<v1::ReplanRequest>& messages, grpc::Status* status) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
    auto stream = server_->stub().Replan(&context);
    std::vector<v1::ReplanResponse> answers;
    for (const v1::ReplanRequest& message : messages) {
      if (!stream->Write(message)) break;
      v1::ReplanResponse answer;
      if (!stream->Read(&answer)) break;
      answers.push_back(answer);
    }
    stream->WritesDone();
    *status = stream->Finish();
    return answers;
  }
  static v1::ReplanRequest At(double time) {
    v1::ReplanRequest message;
    message.set_time(time);
    return message;
  }
  /// The sample of `trajectory` at time t (1 ms samples).
  static const v1::TrajectoryPoint& SampleAt(const v1::JointTrajectory& trajectory, double t) {
    const int i = static_cast<int>(std::lround(t / 0.001));
    EXPECT_NEAR(trajectory.points(i).time_from_start(), t, 1e-9);
    return trajectory.points(i);
  }
};

TEST_F(Replan, KeepsItsTrajectoryWhileNothingChanges) {
  v1::ReplanRequest first;
  *first.mutable_plan() = Problem();
  grpc::Status status;
  const auto answers = Run({first, At(2.0), At(2.5)}, &status);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(answers.size(), 3u);
  ASSERT_EQ(answers[0].action(), v1::ReplanResponse::PLANNED);
  ASSERT_EQ(answers[0].plan().outcome(), v1::SUCCESS) << answers[0].plan().message();
  for (int k = 1; k < 3; ++k) {
    EXPECT_EQ(answers[k].sequence(), static_cast<std::uint64_t>(k));
    EXPECT_EQ(answers[k].action(), v1::ReplanResponse::KEPT) << answers[k].reason();
    ASSERT_EQ(answers[k].plan().outcome(), v1::SUCCESS);
  }
  // The kept trajectory is the first one's rest: its samples are the first's, 2 s later.
  const v1::JointTrajectory& whole = answers[0].plan().trajectory();
  const v1::JointTrajectory& rest = answers[1].plan().trajectory();
  EXPECT_NEAR(answers[1].plan().duration(), answers[0].plan().duration() - 2.0, 1e-9);
  for (double t : {0.0, 0.5, 1.234, 3.0}) {
    const v1::TrajectoryPoint& a = SampleAt(whole, 2.0 + t);
    const v1::TrajectoryPoint& b = SampleAt(rest, t);
    for (int j = 0; j < 3; ++j) {
      EXPECT_NEAR(a.positions(j), b.positions(j), 1e-9) << "t = " << t;
      EXPECT_NEAR(a.velocities(j), b.velocities(j), 1e-9) << "t = " << t;
    }
  }
}

TEST_F(Replan, ReplansWhenABoxLandsOnItsWayBrakingFirst) {
  v1::ReplanRequest first;
  *first.mutable_plan() = Problem();
  v1::ReplanRequest moved = At(2.0);
  *moved.mutable_scene() = first.plan().scene();
  v1::Box* box = moved.mutable_scene()->add_boxes();
  box->set_name("dropped_pallet");
  box->mutable_size()->set_x(1.0);
  box->mutable_size()->set_y(1.0);
  box->mutable_size()->set_z(0.6);
  box->mutable_pose()->mutable_position()->set_x(8.0);
  box->mutable_pose()->mutable_position()->set_y(4.0);
  box->mutable_pose()->mutable_position()->set_z(0.3);
  grpc::Status status;
  const auto answers = Run({first, moved}, &status);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(answers.size(), 2u);
  ASSERT_EQ(answers[0].plan().outcome(), v1::SUCCESS);
  // The first trajectory drives through where the pallet now is.
  EXPECT_LT(BoxClearance(answers[0].plan().trajectory(), {8.0, 4.0}, {0.5, 0.5}), 0.0);
  EXPECT_EQ(answers[1].action(), v1::ReplanResponse::REPLANNED);
  EXPECT_THAT(answers[1].reason(), HasSubstr("the scene changed: the current trajectory collides at t = "));
  EXPECT_THAT(answers[1].reason(), HasSubstr("dropped_pallet"));
  ASSERT_EQ(answers[1].plan().outcome(), v1::SUCCESS) << answers[1].plan().message();
  const v1::JointTrajectory& replanned = answers[1].plan().trajectory();
  EXPECT_GT(BoxClearance(replanned, {8.0, 4.0}, {0.5, 0.5}), 0.0);
  // It starts where and as fast as the robot was at t = 2 (it brakes, it does not jump).
  const v1::TrajectoryPoint& then = SampleAt(answers[0].plan().trajectory(), 2.0);
  EXPECT_GT(std::abs(then.velocities(0)), 0.5);
  for (int j = 0; j < 3; ++j) {
    EXPECT_NEAR(replanned.points(0).positions(j), then.positions(j), 1e-9);
    EXPECT_NEAR(replanned.points(0).velocities(j), then.velocities(j), 1e-9);
  }
  // Its accelerations stay within the default limits (2 × the velocity limits) at every sample.
  for (const v1::TrajectoryPoint& p : replanned.points()) {
    EXPECT_LE(std::abs(p.accelerations(0)), 2.0 + 1e-6);
    EXPECT_LE(std::abs(p.accelerations(1)), 2.0 + 1e-6);
  }
  const v1::TrajectoryPoint& last = replanned.points(replanned.points_size() - 1);
  EXPECT_NEAR(last.positions(0), 11.0, 1e-9);
  EXPECT_NEAR(last.positions(1), 4.0, 1e-9);
}

TEST_F(Replan, ReplansAroundPointsASensorSees) {
  v1::ReplanRequest first;
  *first.mutable_plan() = Problem();
  // A sensor at (6, 4, 0.3) sees a 1 m wide wall of points across the route at x = 8, each at the
  // centre of a 5 cm voxel (OctoMap's voxels span [k·res, (k+1)·res)).
  v1::ReplanRequest seen = At(1.5);
  std::vector<Eigen::Vector3d> points;
  for (int j = 0; j < 20; ++j) {
    for (int k = 0; k < 12; ++k) points.emplace_back(8.025, 3.525 + 0.05 * j, 0.025 + 0.05 * k);
  }
  for (const Eigen::Vector3d& p : points) {
    for (int i = 0; i < 3; ++i) seen.mutable_points()->add_points(p[i]);
  }
  seen.mutable_points()->mutable_sensor_origin()->set_x(6.0);
  seen.mutable_points()->mutable_sensor_origin()->set_y(4.0);
  seen.mutable_points()->mutable_sensor_origin()->set_z(0.3);
  seen.mutable_points()->set_resolution(0.05);
  grpc::Status status;
  const auto answers = Run({first, seen}, &status);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(answers.size(), 2u);
  EXPECT_EQ(answers[1].action(), v1::ReplanResponse::REPLANNED);
  EXPECT_THAT(answers[1].reason(), HasSubstr("points were added to the scene: the current trajectory collides at t = "));
  ASSERT_EQ(answers[1].plan().outcome(), v1::SUCCESS) << answers[1].plan().message();
  // Every sample keeps the body spheres off every point's voxel (exact sphere–cube distance).
  double closest = std::numeric_limits<double>::infinity();
  for (const v1::TrajectoryPoint& p : answers[1].plan().trajectory().points()) {
    for (const double along : {0.15, -0.15}) {
      const Eigen::Vector3d sphere(p.positions(0) + along * std::cos(p.positions(2)),
                                   p.positions(1) + along * std::sin(p.positions(2)), 0.25);
      for (const Eigen::Vector3d& point : points) {
        const double gap = ((sphere - point).cwiseAbs() - Eigen::Vector3d::Constant(0.025)).cwiseMax(0.0).norm();
        closest = std::min(closest, gap - 0.2);
      }
    }
  }
  EXPECT_GT(closest, 0.0);
  // The first trajectory went through the wall.
  double through = std::numeric_limits<double>::infinity();
  for (const v1::TrajectoryPoint& p : answers[0].plan().trajectory().points()) {
    for (const Eigen::Vector3d& point : points) {
      through = std::min(through, (Eigen::Vector3d(p.positions(0), p.positions(1), 0.25) - point).norm());
    }
  }
  EXPECT_LT(through, 0.2);
}

TEST_F(Replan, ReplansAroundAWalkerThatAppears) {
  v1::ReplanRequest first;
  *first.mutable_plan() = Problem();
  v1::ReplanRequest seen = At(1.0);
  seen.set_moving_obstacles_changed(true);
  *seen.mutable_moving_obstacles() = LoadRequest("base_crossing_people").moving_obstacles();
  seen.mutable_moving_obstacles()->RemoveLast();  // walker_a only: crosses y = 4 at x = 4 at t = 3.5
  grpc::Status status;
  const auto answers = Run({first, seen}, &status);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(answers.size(), 2u);
  const std::vector<Walker> walkers = WalkersOf(seen.moving_obstacles());
  EXPECT_LT(WalkerClearance(answers[0].plan().trajectory(), walkers), 0.0);
  EXPECT_EQ(answers[1].action(), v1::ReplanResponse::REPLANNED);
  EXPECT_THAT(answers[1].reason(), HasSubstr("moving obstacle 'walker_a'"));
  ASSERT_EQ(answers[1].plan().outcome(), v1::SUCCESS) << answers[1].plan().message();
  EXPECT_DOUBLE_EQ(answers[1].time(), 1.0);
  EXPECT_GT(WalkerClearance(answers[1].plan().trajectory(), walkers, 1.0), 0.0);
}

TEST_F(Replan, AStateOffItsTrajectoryOrANewGoalIsPlannedAgain) {
  v1::ReplanRequest first;
  *first.mutable_plan() = Problem();
  v1::ReplanRequest pushed = At(1.0);
  for (double q : {2.0, 4.5, 0.0}) pushed.mutable_state()->add_positions(q);
  v1::ReplanRequest goal = At(1.5);
  *goal.mutable_plan() = Problem();
  goal.mutable_plan()->mutable_goal()->set_positions(1, 6.0);
  grpc::Status status;
  const auto answers = Run({first, pushed, goal}, &status);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(answers.size(), 3u);
  EXPECT_EQ(answers[1].action(), v1::ReplanResponse::REPLANNED);
  EXPECT_THAT(answers[1].reason(), HasSubstr("off the current trajectory at t = 1 s"));
  ASSERT_EQ(answers[1].plan().outcome(), v1::SUCCESS);
  EXPECT_NEAR(answers[1].plan().trajectory().points(0).positions(1), 4.5, 1e-9);
  EXPECT_EQ(answers[2].action(), v1::ReplanResponse::PLANNED);
  ASSERT_EQ(answers[2].plan().outcome(), v1::SUCCESS);
  const v1::JointTrajectory& last = answers[2].plan().trajectory();
  EXPECT_NEAR(last.points(last.points_size() - 1).positions(1), 6.0, 1e-9);
}

TEST_F(Replan, InvalidMessagesEndTheStreamNamingThem) {
  grpc::Status status;
  auto answers = Run({At(0.0)}, &status);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(status.error_message(), HasSubstr("message 0: plan is required in the first message"));

  v1::ReplanRequest first;
  *first.mutable_plan() = Problem();
  answers = Run({first, At(2.0), At(1.0)}, &status);
  EXPECT_EQ(answers.size(), 2u);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(status.error_message(), HasSubstr("message 2: time = 1 must be finite and >= the previous message's 2 s"));

  v1::ReplanRequest bad_state = At(1.0);
  for (double q : {2.0, 4.0}) bad_state.mutable_state()->add_positions(q);
  answers = Run({first, bad_state}, &status);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(status.error_message(), HasSubstr("message 1: state.positions has 2 values"));

  v1::ReplanRequest bad_velocities = At(1.0);
  for (double v : {0.5, 0.0}) bad_velocities.add_velocities(v);
  answers = Run({first, bad_velocities}, &status);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(status.error_message(), HasSubstr("message 1: velocities has 2 values, robot 'mobile_base' has 3 joints"));

  v1::ReplanRequest bad_budget = At(1.0);
  bad_budget.set_time_budget(-1.0);
  answers = Run({first, bad_budget}, &status);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(status.error_message(), HasSubstr("message 1: time_budget = -1 must be within (0, 600] s (0 = the plan's)"));

  v1::ReplanRequest grouped = first;
  grouped.mutable_plan()->set_group("arm");
  answers = Run({grouped}, &status);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(status.error_message(), HasSubstr("message 0: plan.group is not supported in Replan"));

  v1::ReplanRequest workcell = first;
  workcell.mutable_plan()->mutable_workcell()->set_name("cell");
  answers = Run({workcell}, &status);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(status.error_message(), HasSubstr("plan.workcell is not supported in Replan"));
}

}  // namespace
}  // namespace chasles::testing
