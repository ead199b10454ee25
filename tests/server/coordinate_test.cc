// The Coordinate RPC and workcell reservations over loopback gRPC: the example scenarios,
// commit / plan / release / expiry, and named errors.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <thread>

#include "chasles/multi/coordinator.h"
#include "chasles/server/convert.h"
#include "chasles/server/convert_multi.h"
#include "../budget_scale.h"
#include "server_fixture.h"

namespace chasles::testing {
namespace {

using ::testing::HasSubstr;

class CoordinateTest : public SharedServerTest<> {
 protected:
  static v1::RobotModel MobileBase() {
    v1::RobotModel robot;
    const auto status = google::protobuf::util::JsonStringToMessage(ReadText(ExamplePath("robots/mobile_base.json")),
                                                                    robot.mutable_mobile());
    EXPECT_TRUE(status.ok()) << status.ToString();
    return robot;
  }
  static v1::TeamRobot Base(const std::string& name, double x0, double y0, double x1, double y1) {
    v1::TeamRobot robot;
    robot.set_name(name);
    *robot.mutable_robot() = MobileBase();
    for (double v : {x0, y0, 0.0}) robot.mutable_start()->add_positions(v);
    for (double v : {x1, y1, 0.0}) robot.mutable_goal()->add_positions(v);
    return robot;
  }
  static v1::PlanRequest BasePlan(double x0, double y0, double x1, double y1) {
    v1::PlanRequest request;
    *request.mutable_robot() = MobileBase();
    request.mutable_scene();  // empty floor
    for (double v : {x0, y0, 0.0}) request.mutable_start()->add_positions(v);
    for (double v : {x1, y1, 0.0}) request.mutable_goal()->add_positions(v);
    request.set_seed(3);
    return request;
  }
  static grpc::Status Coordinate(const v1::CoordinateRequest& request, v1::CoordinateResponse* response) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(120));
    return server_->stub().Coordinate(&context, request, response);
  }
  static grpc::Status CreateWorkcell(const std::string& name, v1::CreateWorkcellResponse* response = nullptr) {
    grpc::ClientContext context;
    v1::CreateWorkcellRequest request;
    request.set_name(name);
    v1::CreateWorkcellResponse ignored;
    return server_->stub().CreateWorkcell(&context, request, response ? response : &ignored);
  }
  static grpc::Status Commit(const v1::CommitTrajectoryRequest& request, v1::CommitTrajectoryResponse* response) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
    return server_->stub().CommitTrajectory(&context, request, response);
  }
  static grpc::Status Release(const v1::ReleaseRequest& request, v1::ReleaseResponse* response) {
    grpc::ClientContext context;
    return server_->stub().Release(&context, request, response);
  }
  static double Now() {
    return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  }
  /// The response's trajectory as the server reads a committed one.
  static CommittedMotion Motion(const std::string& name, const v1::JointTrajectory& trajectory, double begin,
                                double until) {
    CommittedMotion motion;
    motion.id = name;
    motion.placement.name = name;
    motion.placement.model = RobotFromProto(MobileBase());
    motion.trajectory = TrajectoryFromPoints(trajectory, *motion.placement.model, name);
    motion.begin = begin;
    motion.until = until;
    return motion;
  }
};

TEST_F(CoordinateTest, ExampleScenariosSucceedOrReportTheirConflict) {
  for (const std::string name : {"coordinate_swap_bases", "coordinate_crossing_arms", "coordinate_corridor"}) {
    SCOPED_TRACE(name);
    v1::CoordinateRequest request;
    const auto parsed = google::protobuf::util::JsonStringToMessage(ReadText(ExamplePath("requests/" + name + ".json")), &request);
    ASSERT_TRUE(parsed.ok()) << parsed.ToString();
    // The example's budget (0 = 30 s), scaled under the sanitizers (budget_scale.h).
    request.set_time_budget(test::Budget(request.time_budget() > 0 ? request.time_budget() : 30.0));
    v1::CoordinateResponse response;
    const grpc::Status status = Coordinate(request, &response);
    ASSERT_TRUE(status.ok()) << status.error_message();
    EXPECT_EQ(response.outcome(), v1::SUCCESS) << response.message();
    ASSERT_EQ(response.robots_size(), request.robots_size());
    EXPECT_GT(response.makespan(), 0.0);
    EXPECT_FALSE(response.method().empty());
    // Sphere robots among primitives, no workcell: certified along the continuous motion.
    EXPECT_EQ(response.verification().collision_guarantee(), "certified");
    EXPECT_EQ(response.verification().collision_guarantee_reason(), "");
    EXPECT_GT(response.verification().states_checked(), 0u);
    EXPECT_LE(response.verification().max_velocity_ratio(), 1.0 + 1e-9);
    for (int k = 0; k < response.robots_size(); ++k) {
      const v1::RobotTrajectory& robot = response.robots(k);
      EXPECT_EQ(robot.name(), request.robots(k).name());
      ASSERT_GT(robot.trajectory().points_size(), 1);
      EXPECT_NEAR(robot.trajectory().points(robot.trajectory().points_size() - 1).time_from_start(), robot.duration(), 1e-9);
      EXPECT_EQ(robot.trajectory().points(0).positions_size(), request.robots(k).start().positions_size());
    }
  }
  v1::CoordinateRequest overlap;
  ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(
                  ReadText(ExamplePath("requests/coordinate_goals_overlap.json")), &overlap)
                  .ok());
  v1::CoordinateResponse response;
  ASSERT_TRUE(Coordinate(overlap, &response).ok());
  EXPECT_EQ(response.outcome(), v1::GOALS_IN_CONFLICT) << response.message();
  EXPECT_EQ(response.robots_size(), 0);
}

/// Commit one robot's crossing, plan a second through it: never meets it; after release it
/// goes straight; commits that clash are refused.
TEST_F(CoordinateTest, CommitPlanRelease) {
  ASSERT_TRUE(CreateWorkcell("floor").ok());
  v1::CreateWorkcellResponse again;
  ASSERT_TRUE(CreateWorkcell("floor", &again).ok());
  EXPECT_FALSE(again.created());

  // Robot a crosses the floor along y = 4; it passes x = 6 about when b (below) passes y = 4.
  v1::PlanResponse a;
  ASSERT_TRUE(server_->Plan(BasePlan(3, 4, 11, 4), &a).ok());
  ASSERT_EQ(a.outcome(), v1::SUCCESS) << a.message();
  const double t0 = Now() + 60.0;  // on the workcell clock, in a minute
  v1::CommitTrajectoryRequest commit;
  commit.set_workcell("floor");
  commit.set_robot_name("a");
  *commit.mutable_robot() = MobileBase();
  *commit.mutable_trajectory() = a.trajectory();
  commit.set_start_time(t0);
  v1::CommitTrajectoryResponse committed;
  grpc::Status status = Commit(commit, &committed);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_THAT(committed.reservation_id(), HasSubstr("floor/"));
  EXPECT_NEAR(committed.end_time() - committed.start_time(), a.duration(), 1e-6);

  // Robot b crosses along x = 6, through a's route, starting at the same time.
  v1::PlanResponse alone;
  ASSERT_TRUE(server_->Plan(BasePlan(6, 1, 6, 7), &alone).ok());
  ASSERT_EQ(alone.outcome(), v1::SUCCESS);
  v1::PlanRequest b_request = BasePlan(6, 1, 6, 7);
  b_request.mutable_workcell()->set_name("floor");
  b_request.mutable_workcell()->set_start_time(t0);
  b_request.mutable_workcell()->set_robot_name("b");
  v1::PlanResponse b;
  status = server_->Plan(b_request, &b);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(b.outcome(), v1::SUCCESS) << b.message();
  // Certified against the scene, but against a's committed trajectory only at discrete times.
  EXPECT_EQ(alone.verification().collision_guarantee(), "certified");
  EXPECT_EQ(b.verification().collision_guarantee(), "discrete");
  EXPECT_THAT(b.verification().collision_guarantee_reason(), HasSubstr("committed trajectories"));
  const CommittedMotion a_motion = Motion("a", a.trajectory(), 0.0, a.duration());
  EXPECT_EQ(FindMotionConflict(Motion("b", b.trajectory(), 0.0, std::numeric_limits<double>::infinity()), a_motion, 0.0), "");
  // Without the workcell it would have met a.
  EXPECT_THAT(FindMotionConflict(Motion("b", alone.trajectory(), 0.0, std::numeric_limits<double>::infinity()), a_motion, 0.0),
              HasSubstr("collide"));

  // Committing b's straight run instead is refused, naming the reservation.
  v1::CommitTrajectoryRequest clash = commit;
  clash.set_robot_name("b");
  *clash.mutable_trajectory() = alone.trajectory();
  status = Commit(clash, &committed);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_THAT(status.error_message(), HasSubstr("floor/1"));
  // b's planned trajectory commits.
  *clash.mutable_trajectory() = b.trajectory();
  status = Commit(clash, &committed);
  EXPECT_TRUE(status.ok()) << status.error_message();

  // After releasing a (and b), b's straight plan is free again.
  v1::ReleaseRequest release;
  release.set_workcell("floor");
  release.set_robot_name("a");
  v1::ReleaseResponse released;
  ASSERT_TRUE(Release(release, &released).ok());
  EXPECT_EQ(released.released(), 1u);
  EXPECT_EQ(released.active_reservations(), 1u);
  release.set_robot_name("b");
  ASSERT_TRUE(Release(release, &released).ok());
  v1::PlanResponse free;
  ASSERT_TRUE(server_->Plan(b_request, &free).ok());
  ASSERT_EQ(free.outcome(), v1::SUCCESS) << free.message();
  EXPECT_NEAR(free.duration(), alone.duration(), 1e-6);
}

/// A reservation that expires: a robot standing in the way for 0.6 s blocks a plan until then.
TEST_F(CoordinateTest, ReservationsExpire) {
  ASSERT_TRUE(CreateWorkcell("expiry").ok());
  v1::CommitTrajectoryRequest commit;
  commit.set_workcell("expiry");
  commit.set_robot_name("blocker");
  *commit.mutable_robot() = MobileBase();
  v1::TrajectoryPoint* point = commit.mutable_trajectory()->add_points();
  for (double v : {6.0, 4.0, 0.0}) point->add_positions(v);
  commit.set_hold(0.6);
  v1::CommitTrajectoryResponse committed;
  ASSERT_TRUE(Commit(commit, &committed).ok());
  EXPECT_NEAR(committed.expires_at() - committed.start_time(), 0.6, 1e-6);  // epoch seconds: ~1e-7 resolution

  // Right now the straight route through (6, 4) is blocked at the start: a robot starting there
  // conflicts with the reservation.
  v1::PlanRequest through = BasePlan(6, 4, 6, 7);
  through.mutable_workcell()->set_name("expiry");
  v1::PlanResponse blocked;
  ASSERT_TRUE(server_->Plan(through, &blocked).ok());
  EXPECT_EQ(blocked.outcome(), v1::STARTS_IN_CONFLICT) << blocked.message();
  EXPECT_THAT(blocked.message(), HasSubstr("expiry/1"));

  std::this_thread::sleep_for(std::chrono::milliseconds(800));
  v1::PlanResponse free;
  ASSERT_TRUE(server_->Plan(through, &free).ok());
  EXPECT_EQ(free.outcome(), v1::SUCCESS) << free.message();
  v1::ReleaseRequest release;
  release.set_workcell("expiry");
  release.set_reservation_id(committed.reservation_id());
  v1::ReleaseResponse released;
  const grpc::Status gone = Release(release, &released);
  EXPECT_EQ(gone.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_THAT(gone.error_message(), HasSubstr("expired"));
}

// Issue 25, item 2 on the Coordinate RPC: a start a hair outside a limit is clamped onto it
// within bounds_tolerance (default 1e-6), reported in the response's warnings naming the robot's
// field; farther out it is INVALID_ARGUMENT naming the field, the value and the limit.
TEST_F(CoordinateTest, StartsJustOutsideALimitAreClampedWithinTheBoundsTolerance) {
  v1::CoordinateRequest request;
  request.mutable_scene();
  *request.add_robots() = Base("a", 1, 1, 5, 5);
  *request.add_robots() = Base("b", -4e-7, 3, 5, 1);  // x = -4e-7 below the lower limit 0
  request.set_seed(1);
  v1::CoordinateResponse response;
  grpc::Status status = Coordinate(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  ASSERT_EQ(response.warnings_size(), 1);
  EXPECT_THAT(response.warnings(0), HasSubstr("robots[1].start.positions[0] = -4e-07 is 4e-07 below its lower limit 0"));
  EXPECT_THAT(response.warnings(0), HasSubstr("within bounds_tolerance 1e-06: clamped onto the limit"));
  ASSERT_EQ(response.robots_size(), 2);
  ASSERT_GT(response.robots(1).trajectory().points_size(), 0);
  EXPECT_EQ(response.robots(1).trajectory().points(0).positions(0), 0.0);  // the clamped start

  request.mutable_robots(1)->mutable_start()->set_positions(0, -0.001);
  status = Coordinate(request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();
  EXPECT_THAT(status.error_message(), HasSubstr("robots[1].start.positions[0] = -0.001 must be within [0, 12]"));

  request.set_bounds_tolerance(0.002);
  status = Coordinate(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  ASSERT_EQ(response.warnings_size(), 1);
  EXPECT_THAT(response.warnings(0), HasSubstr("within bounds_tolerance 0.002"));

  request.set_bounds_tolerance(0.5);
  status = Coordinate(request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(status.error_message(), HasSubstr("bounds_tolerance = 0.5"));
}

TEST_F(CoordinateTest, BadInputGetsNamedErrors) {
  const auto expect = [](const grpc::Status& status, grpc::StatusCode code, const std::string& text) {
    EXPECT_EQ(status.error_code(), code) << status.error_message();
    EXPECT_THAT(status.error_message(), HasSubstr(text));
  };
  v1::CoordinateRequest request;
  request.mutable_scene();
  *request.add_robots() = Base("a", 1, 1, 5, 5);
  *request.add_robots() = Base("a", 5, 1, 1, 5);
  v1::CoordinateResponse response;
  expect(Coordinate(request, &response), grpc::StatusCode::INVALID_ARGUMENT,
         "robots[1].name = 'a' is already the name of robots[0]");
  request.mutable_robots(1)->set_name("b");
  request.mutable_robots(1)->mutable_start()->add_positions(0.0);
  expect(Coordinate(request, &response), grpc::StatusCode::INVALID_ARGUMENT,
         "robots[1].start.positions has 4 values, robot 'mobile_base' has 3 joints");
  request.mutable_robots(1)->mutable_start()->mutable_positions()->RemoveLast();
  request.mutable_robots(0)->clear_robot();
  expect(Coordinate(request, &response), grpc::StatusCode::INVALID_ARGUMENT, "robots[0] has no robot");
  *request.mutable_robots(0) = Base("a", 1, 1, 5, 5);
  request.mutable_workcell()->set_name("no-such-cell");
  expect(Coordinate(request, &response), grpc::StatusCode::NOT_FOUND, "workcell 'no-such-cell' is unknown");
  request.clear_workcell();
  request.set_method(static_cast<v1::CoordinateRequest::Method>(42));
  expect(Coordinate(request, &response), grpc::StatusCode::INVALID_ARGUMENT, "method = 42");

  v1::PlanRequest plan = BasePlan(1, 1, 5, 5);
  plan.mutable_workcell()->set_name("no-such-cell");
  v1::PlanResponse plan_response;
  expect(server_->Plan(plan, &plan_response), grpc::StatusCode::NOT_FOUND, "workcell 'no-such-cell' is unknown");
  ASSERT_TRUE(CreateWorkcell("errors").ok());
  plan.mutable_workcell()->set_name("errors");
  plan.mutable_trajectory()->set_post_processing(v1::TrajectoryOptions::COLLOCATION);
  expect(server_->Plan(plan, &plan_response), grpc::StatusCode::INVALID_ARGUMENT,
         "trajectory.post_processing = COLLOCATION is not supported with workcell");

  v1::CommitTrajectoryRequest commit;
  commit.set_workcell("no-such-cell");
  commit.set_robot_name("a");
  *commit.mutable_robot() = MobileBase();
  for (int k = 0; k < 2; ++k) {  // two points at t = 0
    v1::TrajectoryPoint* point = commit.mutable_trajectory()->add_points();
    for (double v : {1.0, 1.0, 0.0}) point->add_positions(v);
  }
  v1::CommitTrajectoryResponse committed;
  expect(Commit(commit, &committed), grpc::StatusCode::INVALID_ARGUMENT,
         "trajectory.points[1].time_from_start = 0 must be greater than the previous point's 0");
  commit.mutable_trajectory()->mutable_points()->RemoveLast();
  expect(Commit(commit, &committed), grpc::StatusCode::NOT_FOUND, "workcell 'no-such-cell' is unknown");
  commit.set_workcell("errors");
  commit.mutable_trajectory()->mutable_points(0)->add_positions(2.0);
  expect(Commit(commit, &committed), grpc::StatusCode::INVALID_ARGUMENT,
         "trajectory.points[0].positions has 4 values, robot 'mobile_base' has 3 joints");
  commit.mutable_trajectory()->mutable_points(0)->mutable_positions()->RemoveLast();
  commit.set_hold(-1.0);
  expect(Commit(commit, &committed), grpc::StatusCode::INVALID_ARGUMENT, "hold = -1 must be within [0, 86400]");

  v1::ReleaseRequest release;
  release.set_workcell("errors");
  v1::ReleaseResponse released;
  expect(Release(release, &released), grpc::StatusCode::INVALID_ARGUMENT, "reservation_id and robot_name are both empty");
  release.set_workcell("nowhere");
  release.set_robot_name("a");
  expect(Release(release, &released), grpc::StatusCode::NOT_FOUND, "workcell 'nowhere' is unknown");
  expect(CreateWorkcell("bad name!"), grpc::StatusCode::INVALID_ARGUMENT, "name = 'bad name!' must be");

  // The server keeps serving.
  v1::PlanResponse fine;
  ASSERT_TRUE(server_->Plan(BasePlan(1, 1, 5, 5), &fine).ok());
  EXPECT_EQ(fine.outcome(), v1::SUCCESS);
}

// The fleet example: 60 disc bases on a random 32 x 32 floor. AUTO picks FLEET; the answer is
// knots (no samples asked for), the dependencies, the lattice's figures, and well under 1 MB.
// Every robot's knots are evaluated here by the documented rule at 10 ms and the discs re-checked
// pairwise (the 1 ms, between-knots check of many more robots is tests/multi/fleet_coordinate_test.cc).
TEST_F(CoordinateTest, TheFleetExampleIsPlannedByFleetAndAnsweredWithKnots) {
  v1::CoordinateRequest request;
  const auto parsed = google::protobuf::util::JsonStringToMessage(
      ReadText(ExamplePath("requests/coordinate_fleet.json")), &request);
  ASSERT_TRUE(parsed.ok()) << parsed.ToString();
  v1::CoordinateResponse response;
  const grpc::Status status = Coordinate(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  EXPECT_EQ(response.method(), "fleet");
  ASSERT_EQ(response.robots_size(), request.robots_size());
  EXPECT_LT(response.ByteSizeLong(), 1u << 20);
  EXPECT_EQ(response.fleet().width(), 32u);
  EXPECT_DOUBLE_EQ(response.fleet().resolution(), 1.0);
  EXPECT_GE(response.fleet().sum_of_costs(), response.fleet().sum_of_lower_bounds());
  EXPECT_GT(response.dependencies_size(), 0);
  EXPECT_EQ(response.verification().collision_guarantee(), "certified");
  std::vector<std::vector<Eigen::Vector2d>> at(static_cast<std::size_t>(response.robots_size()));
  const double period = 0.01;
  const int steps = static_cast<int>(std::ceil(response.makespan() / period));
  for (int k = 0; k < response.robots_size(); ++k) {
    const v1::RobotTrajectory& robot = response.robots(k);
    EXPECT_EQ(robot.trajectory().points_size(), 0);
    const v1::TrajectoryKnots& knots = robot.knots();
    ASSERT_EQ(knots.joint_names_size(), 3);
    ASSERT_GE(knots.times_size(), 1);
    const int last = knots.times_size() - 1;
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(knots.positions(3 * last + j), request.robots(k).goal().positions(j), 1e-9);
    int i = 0;
    for (int s = 0; s <= steps; ++s) {
      const double t = s * period;
      while (i + 1 < knots.times_size() && knots.times(i + 1) <= t) ++i;
      Eigen::Vector2d p(knots.positions(3 * i), knots.positions(3 * i + 1));
      if (i + 1 < knots.times_size()) {
        const double T = knots.times(i + 1) - knots.times(i), tau = t - knots.times(i);
        for (int j = 0; j < 2; ++j) {
          const double v0 = knots.velocities(3 * i + j), v1 = knots.velocities(3 * (i + 1) + j);
          p[j] += v0 * tau + (v1 - v0) * tau * tau / (2.0 * T);
        }
      }
      at[static_cast<std::size_t>(k)].push_back(p);
    }
  }
  double nearest = std::numeric_limits<double>::infinity();
  for (int s = 0; s <= steps; ++s) {
    for (std::size_t a = 0; a < at.size(); ++a) {
      for (std::size_t b = a + 1; b < at.size(); ++b) nearest = std::min(nearest, (at[a][s] - at[b][s]).norm() - 0.8);
    }
  }
  EXPECT_GE(nearest, -1e-9);
  EXPECT_GE(response.verification().min_robot_distance(), -1e-9);
}

}  // namespace
}  // namespace chasles::testing
