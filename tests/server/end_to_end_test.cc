// End to end over loopback gRPC: every example request with rrt_connect, and every registered
// planner on every example request. Each returned trajectory must be verified,
// start and end exactly at the request's start and goal, and respect the limits.
#include <cmath>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "../budget_scale.h"
#include "server_fixture.h"

namespace chasles::testing {
namespace {

const std::vector<std::string> kRequests = {
    "panda_table",     "panda_shelf",      "panda_cage",         "panda_shelf_octomap",
    "ur5_table",       "ur5_shelf",        "ur5_cage",           "planar_2r_table",
    "planar_2r_shelf", "planar_2r_cage",   "planar_2r_posts",    "maze_astar",
    "maze_wavefront",  "maze_rrt_connect", "office_astar",       "office_wavefront",
    "office_rrt_connect", "office_car",    "drone_astar",        "drone_potential_field",
    "drone_wavefront", "drone_rrt_connect"};

constexpr double kPi = 3.14159265358979323846;

bool IsCarRequest(const v1::PlanRequest& request) {
  return request.robot().has_mobile() && (request.robot().mobile().kind() == v1::MobileRobot::DUBINS_CAR ||
                                          request.robot().mobile().kind() == v1::MobileRobot::REEDS_SHEPP_CAR);
}

/// A car's heading is unwrapped along its path: it ends at the goal heading modulo 2π.
void ExpectAtGoal(const v1::PlanRequest& request, int joint, double value) {
  const double goal = request.goal().positions(joint);
  if (IsCarRequest(request) && joint == 2) {
    EXPECT_NEAR(std::remainder(value - goal, 2 * kPi), 0.0, 1e-6) << "heading";
  } else {
    EXPECT_NEAR(value, goal, 1e-6) << "joint " << joint;
  }
}

/// "arm", or the mobile kind as ListPlanners spells it.
std::string RequestKind(const v1::PlanRequest& request) {
  if (!request.robot().has_mobile()) return "arm";
  switch (request.robot().mobile().kind()) {
    case v1::MobileRobot::DUBINS_CAR: return "dubins_car";
    case v1::MobileRobot::REEDS_SHEPP_CAR: return "reeds_shepp_car";
    case v1::MobileRobot::FREE_FLYER: return "free_flyer";
    default: return "planar";
  }
}

void ExpectVerifiedTrajectory(const v1::PlanRequest& request, const v1::PlanResponse& response) {
  ASSERT_EQ(response.outcome(), v1::SUCCESS) << v1::PlanOutcome_Name(response.outcome()) << ": " << response.message();
  const int dofs = request.start().positions_size();
  const v1::JointTrajectory& trajectory = response.trajectory();
  ASSERT_GT(trajectory.points_size(), 1);
  ASSERT_EQ(trajectory.joint_names_size(), dofs);
  const v1::TrajectoryPoint& first = trajectory.points(0);
  const v1::TrajectoryPoint& last = trajectory.points(trajectory.points_size() - 1);
  EXPECT_EQ(first.time_from_start(), 0.0);
  EXPECT_NEAR(last.time_from_start(), response.duration(), 1e-9);
  EXPECT_GT(response.duration(), 0.0);
  for (int j = 0; j < dofs; ++j) {
    ASSERT_EQ(first.positions_size(), dofs);
    ASSERT_EQ(last.positions_size(), dofs);
    EXPECT_NEAR(first.positions(j), request.start().positions(j), 1e-6) << "joint " << j;
    ExpectAtGoal(request, j, last.positions(j));
  }
  // The limits the response reports are the ones every sample keeps.
  const v1::TrajectoryLimits& limits = response.limits();
  ASSERT_EQ(limits.max_velocity_size(), dofs);
  ASSERT_EQ(limits.max_acceleration_size(), dofs);
  double previous = -1.0;
  for (const v1::TrajectoryPoint& point : trajectory.points()) {
    ASSERT_GT(point.time_from_start(), previous);
    previous = point.time_from_start();
    ASSERT_EQ(point.velocities_size(), dofs);
    ASSERT_EQ(point.accelerations_size(), dofs);
    for (int j = 0; j < dofs; ++j) {
      ASSERT_TRUE(std::isfinite(point.positions(j)));
      ASSERT_GT(limits.max_velocity(j), 0.0);
      EXPECT_LE(std::abs(point.velocities(j)), limits.max_velocity(j) * (1 + 1e-9) + 1e-12) << "joint " << j;
      EXPECT_LE(std::abs(point.accelerations(j)), limits.max_acceleration(j) * (1 + 1e-9) + 1e-12) << "joint " << j;
    }
  }
  ASSERT_GE(response.path_size(), 2);
  for (int j = 0; j < dofs; ++j) {
    EXPECT_NEAR(response.path(0).positions(j), request.start().positions(j), 1e-6);
    ExpectAtGoal(request, j, response.path(response.path_size() - 1).positions(j));
  }
  EXPECT_GT(response.verification().states_checked(), 0u);
  EXPECT_LE(response.verification().max_velocity_ratio(), 1.0 + 1e-9);
  EXPECT_LE(response.verification().max_acceleration_ratio(), 1.0 + 1e-9);
  EXPECT_GT(response.verification().max_velocity_ratio(), 0.0);
  EXPECT_EQ(response.robot_id().size(), 32u);
  EXPECT_EQ(response.scene_id().size(), 32u);
  EXPECT_GT(response.statistics().collision_checks(), 0u);
  EXPECT_GE(response.timings().total(), response.timings().plan());
  // Every stage of a successful plan is timed, the quality figures and the samples included,
  // and the named stages add up to no more than the total.
  const v1::StageTimings& t = response.timings();
  EXPECT_GT(t.quality(), 0.0);
  EXPECT_GT(t.sample(), 0.0);
  EXPECT_LE(t.validate() + t.plan() + t.shortcut() + t.parameterize() + t.optimize() + t.verify() + t.quality() +
                t.sample(),
            t.total());
}

class ExampleRequest : public SharedServerTest<::testing::TestWithParam<std::string>> {};

TEST_P(ExampleRequest, RrtConnectReturnsAVerifiedTrajectory) {
  v1::PlanRequest request = LoadRequest(GetParam());
  request.mutable_planner()->set_planner_id("rrt_connect");
  v1::PlanResponse response;
  const grpc::Status status = server_->Plan(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.request_id(), GetParam());
  ExpectVerifiedTrajectory(request, response);
}

INSTANTIATE_TEST_SUITE_P(Examples, ExampleRequest, ::testing::ValuesIn(kRequests),
                         [](const ::testing::TestParamInfo<std::string>& info) { return info.param; });

// Every registered planner; EveryPlannerIsInTheMatrix keeps this list equal to ListPlanners.
const std::vector<std::string> kPlanners = {"astar", "bit_star", "informed_rrt_star", "lazy_prm_star",
                                            "potential_field", "prm", "prm_star", "rrt",
                                            "rrt_connect", "rrt_star", "wavefront"};

TEST(EveryPlanner, EveryPlannerIsInTheMatrix) {
  LoopbackServer server;
  v1::ListPlannersResponse planners;
  ASSERT_TRUE(server.ListPlanners(&planners).ok());
  std::vector<std::string> ids;
  for (const v1::PlannerDescription& planner : planners.planners()) ids.push_back(planner.id());
  EXPECT_EQ(ids, kPlanners);
}

class EveryPlannerOnEveryRequest : public SharedServerTest<::testing::TestWithParam<std::tuple<std::string, std::string>>> {};

// Every planner on every request returns a verified trajectory, except where it says why not:
// a planner refuses a robot kind it does not plan for (FAILED_PRECONDITION, as ListPlanners
// tells), the wavefront refuses more than 3 moving coordinates, and the potential field may stop
// in a local minimum — an outcome with no trajectory, never a wrong one.
TEST_P(EveryPlannerOnEveryRequest, ReturnsAVerifiedTrajectory) {
  const auto& [problem, planner] = GetParam();
  v1::PlanRequest request = LoadRequest(problem);
  request.mutable_planner()->set_planner_id(planner);
  request.mutable_planner()->clear_parameters();
  v1::ListPlannersResponse planners;
  ASSERT_TRUE(server_->ListPlanners(&planners).ok());
  bool optimizing = false, kind_supported = false;
  for (const v1::PlannerDescription& p : planners.planners()) {
    if (p.id() != planner) continue;
    optimizing = p.optimizing();
    for (const std::string& kind : p.robot_kinds()) kind_supported |= kind == RequestKind(request);
  }
  // Anytime planners refine until the budget ends: keep it small (a car's curves cost more).
  // Scaled under the sanitizers (budget_scale.h).
  request.set_time_budget(test::Budget(optimizing ? (IsCarRequest(request) ? 2.0 : 0.5) : 5.0));
  v1::PlanResponse response;
  const grpc::Status status = server_->Plan(request, &response);
  if (!kind_supported) {
    EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION) << status.error_message();
    EXPECT_NE(status.error_message().find("does not plan for " + RequestKind(request) + " robots"), std::string::npos)
        << status.error_message();
    return;
  }
  if (planner == "wavefront" && status.error_code() == grpc::StatusCode::FAILED_PRECONDITION) {
    EXPECT_NE(status.error_message().find("at most 3 moving coordinates"), std::string::npos) << status.error_message();
    EXPECT_GT(request.start().positions_size(), 3);
    return;
  }
  ASSERT_TRUE(status.ok()) << status.error_message();
  if (planner == "potential_field" && response.outcome() == v1::LOCAL_MINIMUM) {
    EXPECT_EQ(response.trajectory().points_size(), 0);
    EXPECT_EQ(response.path_size(), 0);
    EXPECT_NE(response.message().find("local minimum"), std::string::npos) << response.message();
    return;
  }
  ExpectVerifiedTrajectory(request, response);
}

INSTANTIATE_TEST_SUITE_P(Matrix, EveryPlannerOnEveryRequest,
                         ::testing::Combine(::testing::ValuesIn(kRequests), ::testing::ValuesIn(kPlanners)),
                         [](const auto& info) { return std::get<0>(info.param) + "_" + std::get<1>(info.param); });

}  // namespace
}  // namespace chasles::testing
