// TrajectoryKnots: a trajectory as knots joined by constant accelerations, the compact form of
// Plan, Optimize and Coordinate answers. Each test evaluates the proto's documented rule here,
// independently of the server's trajectory code, and holds it to the samples the server returns
// for the same request (which it evaluates from its own polynomials).

#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "server_fixture.h"

namespace chasles::testing {
namespace {

/// The documented rule: q(t) = q_i + v_i·τ + (v_{i+1} − v_i)·τ²/(2T) on [t_i, t_{i+1}]; the last
/// knot's positions after it. Writes positions and velocities.
void EvaluateKnots(const v1::TrajectoryKnots& knots, double t, std::vector<double>* q, std::vector<double>* v) {
  const int n = knots.joint_names_size();
  const int count = knots.times_size();
  q->assign(n, 0.0);
  v->assign(n, 0.0);
  int i = 0;
  while (i + 1 < count && knots.times(i + 1) <= t) ++i;
  if (i + 1 >= count) {
    for (int j = 0; j < n; ++j) (*q)[j] = knots.positions(i * n + j);
    return;
  }
  const double T = knots.times(i + 1) - knots.times(i);
  const double tau = t - knots.times(i);
  for (int j = 0; j < n; ++j) {
    const double q0 = knots.positions(i * n + j), v0 = knots.velocities(i * n + j);
    const double v1 = knots.velocities((i + 1) * n + j);
    const double a = (v1 - v0) / T;
    (*q)[j] = q0 + v0 * tau + 0.5 * a * tau * tau;
    (*v)[j] = v0 + a * tau;
  }
}

/// Knots agree with samples of the same trajectory, and are consistent between them: each
/// interval's constant acceleration carries the positions to the next knot.
void ExpectKnotsMatchSamples(const v1::TrajectoryKnots& knots, const v1::JointTrajectory& samples) {
  const int n = knots.joint_names_size();
  ASSERT_GT(n, 0);
  ASSERT_GE(knots.times_size(), 2);
  ASSERT_EQ(knots.positions_size(), n * knots.times_size());
  ASSERT_EQ(knots.velocities_size(), n * knots.times_size());
  EXPECT_EQ(knots.times(0), 0.0);
  for (int j = 0; j < n; ++j) EXPECT_EQ(knots.joint_names(j), samples.joint_names(j));
  for (int i = 0; i + 1 < knots.times_size(); ++i) {
    const double T = knots.times(i + 1) - knots.times(i);
    ASSERT_GT(T, 0.0) << "knot " << i;
    for (int j = 0; j < n; ++j) {
      const double q0 = knots.positions(i * n + j), q1 = knots.positions((i + 1) * n + j);
      const double v0 = knots.velocities(i * n + j), v1 = knots.velocities((i + 1) * n + j);
      EXPECT_NEAR(q0 + 0.5 * (v0 + v1) * T, q1, 1e-9) << "knot " << i << " joint " << j;
    }
  }
  ASSERT_GT(samples.points_size(), 2);
  std::vector<double> q, v;
  for (const v1::TrajectoryPoint& point : samples.points()) {
    EvaluateKnots(knots, point.time_from_start(), &q, &v);
    for (int j = 0; j < n; ++j) {
      EXPECT_NEAR(q[j], point.positions(j), 1e-9) << "t = " << point.time_from_start() << " joint " << j;
      EXPECT_NEAR(v[j], point.velocities(j), 1e-9) << "t = " << point.time_from_start() << " joint " << j;
    }
  }
}

class Knots : public SharedServerTest<> {};

TEST_F(Knots, APlanAnswersWithKnotsThatReproduceItsSamplesAndNoSamplesUnlessAsked) {
  v1::PlanRequest request = LoadRequest("panda_table");
  request.set_seed(5);
  request.mutable_trajectory()->set_knots_only(true);
  v1::PlanResponse compact;
  grpc::Status status = server_->Plan(request, &compact);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(compact.outcome(), v1::SUCCESS) << compact.message();
  EXPECT_EQ(compact.trajectory().points_size(), 0);
  ASSERT_GE(compact.knots().times_size(), 2);
  EXPECT_NEAR(compact.knots().times(compact.knots().times_size() - 1), compact.duration(), 1e-12);

  // The same request with a sample period: the same trajectory, sampled too.
  request.mutable_trajectory()->set_sample_period(0.005);
  v1::PlanResponse both;
  status = server_->Plan(request, &both);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(both.outcome(), v1::SUCCESS) << both.message();
  EXPECT_EQ(both.knots().SerializeAsString(), compact.knots().SerializeAsString());
  ExpectKnotsMatchSamples(both.knots(), both.trajectory());
  // Compact: far fewer bytes than the samples.
  EXPECT_LT(both.knots().ByteSizeLong() * 10, both.trajectory().ByteSizeLong());
}

TEST_F(Knots, ATrajectoryOfHigherDegreeHasNoKnotsAndKeepsItsSamples) {
  v1::PlanRequest request = LoadRequest("panda_table");
  request.mutable_trajectory()->set_knots_only(true);
  for (int i = 0; i < 7; ++i) request.mutable_trajectory()->add_max_jerk(50.0);
  v1::PlanResponse response;
  const grpc::Status status = server_->Plan(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  EXPECT_EQ(response.knots().times_size(), 0);
  EXPECT_GT(response.trajectory().points_size(), 2);
}

TEST_F(Knots, CoordinateAnswersWithKnotsPerRobot) {
  v1::CoordinateRequest request;
  const auto parsed = google::protobuf::util::JsonStringToMessage(
      ReadText(ExamplePath("requests/coordinate_swap_bases.json")), &request);
  ASSERT_TRUE(parsed.ok()) << parsed.ToString();
  request.set_knots_only(true);
  request.set_sample_period(0.01);
  v1::CoordinateResponse response;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(120));
  const grpc::Status status = server_->stub().Coordinate(&context, request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  for (const v1::RobotTrajectory& robot : response.robots()) {
    SCOPED_TRACE(robot.name());
    ExpectKnotsMatchSamples(robot.knots(), robot.trajectory());
  }
}

}  // namespace
}  // namespace chasles::testing
