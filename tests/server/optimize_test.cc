// Trajectory post-processing over gRPC: Plan with each post_processing choice, the Optimize RPC
// on a user's path and on a timed trajectory, expected failures as outcomes (a colliding input
// path, torque limits below gravity), and named INVALID_ARGUMENT errors for bad options.

#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "server_fixture.h"

namespace chasles::testing {
namespace {

class OptimizeTest : public SharedServerTest<> {
 protected:
  static grpc::Status Optimize(const v1::OptimizeRequest& request, v1::OptimizeResponse* response) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
    return server_->stub().Optimize(&context, request, response);
  }

  /// The planar 2R request among posts, planned once: its robot, scene and verified path.
  static const v1::PlanResponse& Planned() {
    static const v1::PlanResponse* planned = [] {
      auto* response = new v1::PlanResponse();
      const grpc::Status status = server_->Plan(LoadRequest("planar_2r_posts"), response);
      EXPECT_TRUE(status.ok()) << status.error_message();
      return response;
    }();
    return *planned;
  }

  /// An Optimize request for the planned path, with the request's robot and scene inline.
  static v1::OptimizeRequest PathRequest(v1::TrajectoryOptions::PostProcessing method) {
    const v1::PlanRequest plan = LoadRequest("planar_2r_posts");
    v1::OptimizeRequest request;
    *request.mutable_robot() = plan.robot();
    *request.mutable_scene() = plan.scene();
    for (const v1::JointState& q : Planned().path()) *request.add_path() = q;
    request.mutable_options()->set_post_processing(method);
    return request;
  }

  static void ExpectError(const v1::OptimizeRequest& request, const std::string& fragment) {
    v1::OptimizeResponse response;
    const grpc::Status status = Optimize(request, &response);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();
    EXPECT_NE(status.error_message().find(fragment), std::string::npos)
        << "'" << fragment << "' not in: " << status.error_message();
  }

  static void ExpectSound(const v1::OptimizeResponse& response, const v1::OptimizeRequest& request) {
    ASSERT_EQ(response.outcome(), v1::SUCCESS) << response.message();
    ASSERT_GT(response.trajectory().points_size(), 1);
    const auto& points = response.trajectory().points();
    EXPECT_NEAR(points.rbegin()->time_from_start(), response.duration(), 1e-9);
    const auto& first = request.path(0).positions();
    const auto& last = request.path(request.path_size() - 1).positions();
    for (int j = 0; j < first.size(); ++j) {
      EXPECT_NEAR(points.begin()->positions(j), first[j], 1e-6);
      EXPECT_NEAR(points.rbegin()->positions(j), last[j], 1e-6);
    }
    const v1::TrajectoryQuality& q = response.quality();
    EXPECT_EQ(q.duration(), response.duration());
    EXPECT_LE(q.max_velocity_ratio(), 1.0 + 1e-9);
    EXPECT_LE(q.max_acceleration_ratio(), 1.0 + 1e-9);
    EXPECT_GT(q.max_velocity_ratio(), 0.0);
    EXPECT_GT(q.min_clearance(), 0.0);
    EXPECT_GE(q.max_deviation(), 0.0);
    EXPECT_LE(response.verification().max_velocity_ratio(), 1.0 + 1e-9);
    EXPECT_GT(response.verification().states_checked(), 0u);
  }
};

TEST_F(OptimizeTest, EveryPostProcessingReturnsAVerifiedTrajectoryOfTheUsersPath) {
  ASSERT_EQ(Planned().outcome(), v1::SUCCESS) << Planned().message();
  ASSERT_GE(Planned().path_size(), 2);
  double topp = 0.0, none = 0.0;
  for (auto method : {v1::TrajectoryOptions::TOPP, v1::TrajectoryOptions::NONE, v1::TrajectoryOptions::COLLOCATION,
                      v1::TrajectoryOptions::SPLINE}) {
    SCOPED_TRACE(v1::TrajectoryOptions::PostProcessing_Name(method));
    const v1::OptimizeRequest request = PathRequest(method);
    v1::OptimizeResponse response;
    const grpc::Status status = Optimize(request, &response);
    ASSERT_TRUE(status.ok()) << status.error_message();
    ExpectSound(response, request);
    const v1::OptimizerStatistics& o = response.optimizer();
    switch (method) {
      case v1::TrajectoryOptions::TOPP:
        topp = response.duration();
        EXPECT_EQ(o.used(), "topp");
        EXPECT_EQ(o.path_deviation(), -1.0);  // collocation's bound only
        EXPECT_LE(response.quality().max_deviation(), 0.05 + 1e-3);
        break;
      case v1::TrajectoryOptions::NONE:
        none = response.duration();
        EXPECT_EQ(o.used(), "none");
        EXPECT_LE(response.quality().max_deviation(), 1e-9);  // stops exactly at every waypoint
        break;
      default:
        // The optimisers either deliver or say why they fell back to the exact parameterisation.
        if (o.fell_back()) {
          EXPECT_EQ(o.used(), "topp");
          EXPECT_FALSE(o.message().empty());
        } else {
          EXPECT_EQ(o.used(), method == v1::TrajectoryOptions::COLLOCATION ? "collocation" : "spline");
          EXPECT_GT(o.iterations(), 0);
          EXPECT_GE(o.time_scale(), 1.0);
          EXPECT_GT(response.timings().optimize(), 0.0);
        }
        // Never slower than TOPP without saying so (no jerk weight: the objective is the duration).
        EXPECT_NEAR(o.topp_duration(), topp, 1e-9);
        EXPECT_NEAR(o.duration_ratio_to_topp(), response.duration() / topp, 1e-12);
        EXPECT_LE(o.duration_ratio_to_topp(), 1.0 + 1e-12);
        if (method == v1::TrajectoryOptions::COLLOCATION && !o.fell_back()) {
          // Along the path (the default): within max_deviation of it, by an exact bound.
          EXPECT_GE(o.path_deviation(), 0.0);
          EXPECT_LE(o.path_deviation(), 0.05);
        }
        break;
    }
  }
  EXPECT_LE(topp, none * (1 + 1e-9));  // blending never takes longer than stopping
}

TEST_F(OptimizeTest, CollocationFollowsAClosedPathAndItsFreeModeSaysWhyItCannot) {
  // A path out and back to its start: along the path (the default) it moves through both
  // waypoints; FREE keeps only the ends, which are equal, so it is refused by name.
  const v1::PlanRequest plan = LoadRequest("planar_2r_posts");
  ASSERT_EQ(Planned().outcome(), v1::SUCCESS);
  v1::OptimizeRequest request;
  *request.mutable_robot() = plan.robot();
  *request.mutable_scene() = plan.scene();
  const v1::JointState start = Planned().path(0);
  v1::JointState out = start, further = start;
  out.set_positions(0, start.positions(0) + 0.05);
  further.set_positions(0, start.positions(0) + 0.05);
  further.set_positions(1, start.positions(1) + 0.05);
  for (const v1::JointState& q : {start, out, further, start}) *request.add_path() = q;
  request.mutable_options()->set_post_processing(v1::TrajectoryOptions::COLLOCATION);
  request.mutable_options()->set_max_deviation(0.01);
  v1::OptimizeResponse response;
  const grpc::Status status = Optimize(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  EXPECT_EQ(response.optimizer().used(), "collocation") << response.optimizer().message();
  EXPECT_GT(response.duration(), 0.5 * response.optimizer().topp_duration());
  EXPECT_LE(response.optimizer().path_deviation(), 0.01);
  EXPECT_LE(response.quality().max_deviation(), 0.01);
  request.mutable_options()->mutable_collocation()->set_path_mode(v1::CollocationOptions::FREE);
  ExpectError(request, "path_mode = FREE keeps only the path's ends, and path[0] = path[3]");
  request.mutable_options()->mutable_collocation()->set_path_mode(static_cast<v1::CollocationOptions::PathMode>(7));
  ExpectError(request, "options.collocation.path_mode = 7 is not one of ALONG_PATH, FREE");
  request.mutable_options()->mutable_collocation()->set_path_mode(v1::CollocationOptions::ALONG_PATH);
  request.mutable_options()->mutable_collocation()->set_corridor(0.0);
  ExpectError(request, "options.collocation.corridor = 0 must be in (0, 1] rad");
  request.mutable_options()->mutable_collocation()->clear_corridor();
  request.mutable_options()->set_max_deviation(0.0);
  ExpectError(request, "max_deviation = 0 leaves COLLOCATION along the path no corridor");
}

TEST_F(OptimizeTest, ATimedTrajectoryIsReoptimisedAndItsDurationReported) {
  ASSERT_EQ(Planned().outcome(), v1::SUCCESS);
  const v1::PlanRequest plan = LoadRequest("planar_2r_posts");
  v1::OptimizeRequest request;
  *request.mutable_robot() = plan.robot();
  *request.mutable_scene() = plan.scene();
  *request.mutable_trajectory() = Planned().trajectory();
  request.mutable_options()->set_max_deviation(0.0);  // the samples as waypoints, at rest at each
  v1::OptimizeResponse response;
  const grpc::Status status = Optimize(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  EXPECT_NEAR(response.input_duration(), Planned().duration(), 1e-9);
  EXPECT_GT(response.duration(), 0.0);
}

TEST_F(OptimizeTest, PlanRequestsChooseThePostProcessing) {
  v1::PlanRequest request = LoadRequest("planar_2r_posts");
  request.mutable_trajectory()->set_post_processing(v1::TrajectoryOptions::NONE);
  v1::PlanResponse stops;
  ASSERT_TRUE(server_->Plan(request, &stops).ok());
  ASSERT_EQ(stops.outcome(), v1::SUCCESS) << stops.message();
  EXPECT_EQ(stops.optimizer().used(), "none");
  request.mutable_trajectory()->set_post_processing(v1::TrajectoryOptions::TOPP);
  v1::PlanResponse blended;
  ASSERT_TRUE(server_->Plan(request, &blended).ok());
  ASSERT_EQ(blended.outcome(), v1::SUCCESS) << blended.message();
  EXPECT_EQ(blended.optimizer().used(), "topp");
  EXPECT_EQ(blended.optimizer().requested(), "topp");
  EXPECT_LE(blended.duration(), stops.duration() * (1 + 1e-9));
  EXPECT_EQ(blended.quality().duration(), blended.duration());
  // Jerk limits by default choose collocation; the trajectory then starts and ends without an
  // acceleration step, and its jerk stays within the limits.
  request.mutable_trajectory()->clear_post_processing();
  for (int i = 0; i < 2; ++i) request.mutable_trajectory()->add_max_jerk(40.0);
  v1::PlanResponse smooth;
  ASSERT_TRUE(server_->Plan(request, &smooth).ok());
  ASSERT_EQ(smooth.outcome(), v1::SUCCESS) << smooth.message();
  EXPECT_EQ(smooth.optimizer().requested(), "auto");
  EXPECT_LE(smooth.quality().max_jerk_ratio(), 1.0 + 1e-9);
  EXPECT_LE(smooth.verification().max_jerk_ratio(), 1.0 + 1e-9);
  for (double a : smooth.trajectory().points(0).accelerations()) EXPECT_LE(std::abs(a), 1e-6);
}

TEST_F(OptimizeTest, ACollidingInputPathIsAnOutcomeNamingTheSegment) {
  v1::OptimizeRequest request = PathRequest(v1::TrajectoryOptions::TOPP);
  // Straight from start to goal: through the posts (the planner had to go round).
  const v1::JointState start = request.path(0), goal = request.path(request.path_size() - 1);
  request.clear_path();
  *request.add_path() = start;
  *request.add_path() = goal;
  v1::OptimizeResponse response;
  ASSERT_TRUE(Optimize(request, &response).ok());
  EXPECT_EQ(response.outcome(), v1::VERIFICATION_FAILED);
  EXPECT_NE(response.message().find("the input path is not collision-free: segment path[0] → path[1]"),
            std::string::npos)
      << response.message();
  EXPECT_EQ(response.trajectory().points_size(), 0);
}

TEST_F(OptimizeTest, TorqueLimitsBelowGravityAreInfeasible) {
  v1::OptimizeRequest request = PathRequest(v1::TrajectoryOptions::TOPP);
  // The planar arm moves in the horizontal plane: with gravity along x its joints must hold it.
  request.mutable_gravity()->set_x(-9.81);
  for (int i = 0; i < 2; ++i) request.mutable_options()->add_max_effort(0.01);
  v1::OptimizeResponse response;
  ASSERT_TRUE(Optimize(request, &response).ok());
  EXPECT_EQ(response.outcome(), v1::INFEASIBLE_LIMITS) << response.message();
  EXPECT_NE(response.message().find("to hold the robot still"), std::string::npos) << response.message();
  // Generous limits are met, and the torques are reported against them.
  request.mutable_options()->clear_max_effort();
  for (int i = 0; i < 2; ++i) request.mutable_options()->add_max_effort(500.0);
  ASSERT_TRUE(Optimize(request, &response).ok());
  ASSERT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  EXPECT_GT(response.quality().max_effort_ratio(), 0.0);
  EXPECT_LE(response.verification().max_effort_ratio(), 1.0 + 1e-9);
}

TEST_F(OptimizeTest, BadOptionsGetNamedInvalidArgumentErrors) {
  v1::OptimizeRequest request = PathRequest(v1::TrajectoryOptions::COLLOCATION);
  request.mutable_options()->mutable_collocation()->set_knots(1);
  ExpectError(request, "options.collocation.knots = 1 must be >= 2");
  request = PathRequest(v1::TrajectoryOptions::COLLOCATION);
  request.mutable_options()->mutable_collocation()->set_jerk_weight(-1.0);
  ExpectError(request, "options.collocation.jerk_weight = -1 must be finite and >= 0");
  request = PathRequest(v1::TrajectoryOptions::SPLINE);
  request.mutable_options()->mutable_spline()->set_jerk_weight(-0.5);
  ExpectError(request, "options.spline.jerk_weight = -0.5 must be finite and >= 0");
  request = PathRequest(v1::TrajectoryOptions::SPLINE);
  request.mutable_options()->mutable_spline()->set_control_points(3);
  ExpectError(request, "options.spline.control_points = 3 must be >= degree + 1 = 4");
  request = PathRequest(v1::TrajectoryOptions::SPLINE);
  request.mutable_options()->mutable_spline()->set_degree(4);
  ExpectError(request, "options.spline.degree = 4 must be 3 or 5");
  request = PathRequest(v1::TrajectoryOptions::SPLINE);
  request.mutable_options()->mutable_spline()->set_algorithm("bfgs");
  ExpectError(request, "options.spline.algorithm = 'bfgs' must be 'slsqp' or 'mma'");
  request = PathRequest(v1::TrajectoryOptions::TOPP);
  request.mutable_options()->add_max_velocity(1.0);
  request.mutable_options()->add_max_velocity(0.0);
  ExpectError(request, "options.max_velocity[1] = 0");
  request = PathRequest(v1::TrajectoryOptions::TOPP);
  request.mutable_options()->add_max_acceleration(-2.0);
  request.mutable_options()->add_max_acceleration(1.0);
  ExpectError(request, "options.max_acceleration[0] = -2");
  request = PathRequest(v1::TrajectoryOptions::TOPP);
  request.mutable_options()->add_max_jerk(10.0);
  request.mutable_options()->add_max_jerk(10.0);
  ExpectError(request, "max_jerk is set, but post_processing TOPP has acceleration steps");
  request = PathRequest(v1::TrajectoryOptions::TOPP);
  request.mutable_options()->set_max_deviation(2.0);
  ExpectError(request, "options.max_deviation = 2 must be within [0, 1]");
  request = PathRequest(static_cast<v1::TrajectoryOptions::PostProcessing>(17));
  ExpectError(request, "options.post_processing = 17 is not one of TOPP, COLLOCATION, SPLINE, NONE");
  request = PathRequest(v1::TrajectoryOptions::TOPP);
  request.mutable_path(1)->set_positions(0, std::nan(""));
  ExpectError(request, "path[1].positions[0] = nan");
  request = PathRequest(v1::TrajectoryOptions::TOPP);
  request.mutable_path(1)->add_positions(0.0);
  ExpectError(request, "path[1].positions");
  request = PathRequest(v1::TrajectoryOptions::TOPP);
  request.clear_path();
  ExpectError(request, "path and trajectory are both empty");
  request = PathRequest(v1::TrajectoryOptions::TOPP);
  request.add_start_velocity(0.3);
  request.add_start_velocity(0.3);
  ExpectError(request, "start_velocity must point along the path's first segment");
  // Plan requests name the field under `trajectory.`.
  v1::PlanRequest plan = LoadRequest("planar_2r_posts");
  plan.mutable_trajectory()->mutable_collocation()->set_knots(1);
  v1::PlanResponse response;
  const grpc::Status status = server_->Plan(plan, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("trajectory.collocation.knots = 1 must be >= 2"), std::string::npos)
      << status.error_message();
}

}  // namespace
}  // namespace chasles::testing
