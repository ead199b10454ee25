// Path constraints over loopback gRPC: carrying a glass upright between two compartments of the
// shelf (examples/requests/panda_shelf_glass.json). Without the constraint the plan tips the
// hand; with it — in OMPL's projected state space and with projected samples — every state
// between every pair of samples keeps it, re-checked here at 0.002 rad steps with the hand's
// orientation from the URDF joints chained and Eigen's AngleAxis (not the server's code).
// Starts and goals that break a constraint are outcomes; malformed constraints are named errors.

#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "chasles/robot/robot_model.h"
#include "server_fixture.h"

namespace chasles::testing {
namespace {

constexpr double kPi = 3.14159265358979323846;

Eigen::VectorXd ToVector(const google::protobuf::RepeatedField<double>& values) {
  Eigen::VectorXd q(values.size());
  for (int i = 0; i < values.size(); ++i) q[i] = values[i];
  return q;
}

/// The largest |rotation-vector component| / tolerance of the hand over the trajectory: every
/// pair of consecutive samples joined by states at most 0.002 rad apart.
double WorstHandRatio(const v1::PlanRequest& request, const v1::JointTrajectory& trajectory) {
  static const auto panda =
      RobotModel::FromUrdf(ReadText(ExamplePath("robots/panda.urdf")), ReadText(ExamplePath("robots/panda.srdf")));
  const v1::OrientationConstraint& c = request.path_constraints().orientation(0);
  const int hand = panda->FindLink(c.link());
  const Eigen::Matrix3d target =
      Eigen::Quaterniond(c.orientation().w(), c.orientation().x(), c.orientation().y(), c.orientation().z())
          .normalized()
          .toRotationMatrix();
  const Eigen::Vector3d tolerance(c.tolerance().x(), c.tolerance().y(), c.tolerance().z());
  std::vector<Eigen::Isometry3d> poses;
  double worst = 0.0;
  const auto measure = [&](const Eigen::VectorXd& q) {
    panda->ForwardKinematicsByChaining(q, &poses);
    const Eigen::AngleAxisd error(target.transpose() * poses[static_cast<std::size_t>(hand)].linear());
    const Eigen::Vector3d v = error.axis() * error.angle();
    worst = std::max(worst, (v.cwiseAbs().array() / tolerance.array()).maxCoeff());
  };
  for (int s = 0; s + 1 < trajectory.points_size(); ++s) {
    const Eigen::VectorXd a = ToVector(trajectory.points(s).positions());
    const Eigen::VectorXd b = ToVector(trajectory.points(s + 1).positions());
    const int n = std::max(1, static_cast<int>(std::ceil((b - a).cwiseAbs().maxCoeff() / 0.002)));
    for (int i = 0; i <= n; ++i) measure(a + (b - a) * (static_cast<double>(i) / n));
  }
  return worst;
}

class PathConstraintsTest : public SharedServerTest<> {
 protected:
  void TearDown() override {
    v1::ListPlannersResponse planners;  // the server survives every request
    EXPECT_TRUE(server_->ListPlanners(&planners).ok());
  }
  /// The glass example with the whole orientation held within 0.1 rad per axis.
  static v1::PlanRequest Glass() {
    v1::PlanRequest request = LoadRequest("panda_shelf_glass");
    v1::Vector3* t = request.mutable_path_constraints()->mutable_orientation(0)->mutable_tolerance();
    t->set_x(0.1);
    return request;
  }
};

TEST_F(PathConstraintsTest, TheGlassStaysUprightOnlyWithTheConstraint) {
  v1::PlanRequest free = Glass();
  free.clear_path_constraints();
  v1::PlanResponse tipped;
  ASSERT_TRUE(server_->Plan(free, &tipped).ok());
  ASSERT_EQ(tipped.outcome(), v1::SUCCESS) << tipped.message();
  EXPECT_GT(WorstHandRatio(Glass(), tipped.trajectory()), 2.0) << "the scenario should need the constraint";
  for (const bool projected_space : {true, false}) {
    v1::PlanRequest request = Glass();
    (*request.mutable_planner()->mutable_parameters())["constrained_space"].set_bool_value(projected_space);
    v1::PlanResponse kept;
    const grpc::Status status = server_->Plan(request, &kept);
    ASSERT_TRUE(status.ok()) << status.error_message();
    ASSERT_EQ(kept.outcome(), v1::SUCCESS) << kept.message();
    EXPECT_EQ(kept.verification().collision_guarantee(), "certified");
    const double worst = WorstHandRatio(request, kept.trajectory());
    EXPECT_LE(worst, 1.0 + 1e-9) << "projected_space " << projected_space;
    EXPECT_GT(kept.quality().max_constraint_ratio(), 0.05);
    EXPECT_LE(kept.quality().max_constraint_ratio(), 1.0);
  }
}

TEST_F(PathConstraintsTest, ATightToleranceIsKeptAndEveryRangeEnds) {
  // 0.01 rad about the horizontal axes. With short ranges the projected steps once turned back
  // forever inside RRT-Connect's connect loop (the request ran past its deadline).
  for (const double range : {0.0, 0.2, 0.5}) {
    v1::PlanRequest request = Glass();
    v1::Vector3* t = request.mutable_path_constraints()->mutable_orientation(0)->mutable_tolerance();
    t->set_y(0.01);
    t->set_z(0.01);
    (*request.mutable_planner()->mutable_parameters())["range"].set_double_value(range);
    v1::PlanResponse response;
    const grpc::Status status = server_->Plan(request, &response);
    ASSERT_TRUE(status.ok()) << "range " << range << ": " << status.error_message();
    ASSERT_EQ(response.outcome(), v1::SUCCESS) << "range " << range << ": " << response.message();
    EXPECT_LE(WorstHandRatio(request, response.trajectory()), 1.0 + 1e-9) << "range " << range;
  }
}

TEST_F(PathConstraintsTest, OptimizeKeepsThemOnAUsersPath) {
  // The straight joint-space line from start to goal tips the glass: refused, naming the constraint.
  const v1::PlanRequest glass = Glass();
  v1::OptimizeRequest optimize;
  *optimize.mutable_scene() = glass.scene();
  *optimize.mutable_path_constraints() = glass.path_constraints();
  *optimize.add_path() = glass.start();
  *optimize.add_path()->mutable_positions() = glass.goal().positions();
  v1::OptimizeResponse refused;
  grpc::ClientContext a;
  ASSERT_TRUE(server_->stub().Optimize(&a, optimize, &refused).ok());
  EXPECT_EQ(refused.outcome(), v1::VERIFICATION_FAILED) << refused.message();
  EXPECT_EQ(refused.message().rfind("the input path leaves its path constraints: segment path[0] → path[1] at s = ", 0), 0u)
      << refused.message();
  EXPECT_NE(refused.message().find("breaks path_constraints.orientation[0]"), std::string::npos) << refused.message();
  // A constrained plan's waypoints, optimised again: kept along the whole new trajectory.
  v1::PlanResponse planned;
  ASSERT_TRUE(server_->Plan(glass, &planned).ok());
  ASSERT_EQ(planned.outcome(), v1::SUCCESS) << planned.message();
  optimize.clear_path();
  for (const v1::JointState& waypoint : planned.path()) *optimize.add_path() = waypoint;
  v1::OptimizeResponse kept;
  grpc::ClientContext b;
  ASSERT_TRUE(server_->stub().Optimize(&b, optimize, &kept).ok());
  ASSERT_EQ(kept.outcome(), v1::SUCCESS) << kept.message();
  EXPECT_LE(WorstHandRatio(glass, kept.trajectory()), 1.0 + 1e-9);
}

TEST_F(PathConstraintsTest, AStartOrGoalThatBreaksItIsAnOutcome) {
  v1::PlanRequest request = Glass();
  request.mutable_start()->set_positions(6, request.start().positions(6) + 0.3);  // the hand turned 0.3 rad
  v1::PlanResponse response;
  ASSERT_TRUE(server_->Plan(request, &response).ok());
  EXPECT_EQ(response.outcome(), v1::START_VIOLATES_CONSTRAINTS) << response.message();
  EXPECT_EQ(response.message().rfind("start breaks path_constraints.orientation[0] (link 'panda_hand', rotation vector): ", 0), 0u)
      << response.message();
  EXPECT_NE(response.message().find("exceeds the tolerance 0.1 rad"), std::string::npos) << response.message();

  request = Glass();
  request.mutable_goal()->set_positions(6, request.goal().positions(6) - 0.3);
  ASSERT_TRUE(server_->Plan(request, &response).ok());
  EXPECT_EQ(response.outcome(), v1::GOAL_VIOLATES_CONSTRAINTS) << response.message();
  EXPECT_EQ(response.message().rfind("goal breaks path_constraints.orientation[0]", 0), 0u) << response.message();
}

TEST_F(PathConstraintsTest, MalformedConstraintsAreNamedErrors) {
  const auto refused = [this](const v1::PlanRequest& request, const std::string& expected) {
    v1::PlanResponse response;
    const grpc::Status status = server_->Plan(request, &response);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();
    EXPECT_NE(status.error_message().find(expected), std::string::npos) << status.error_message();
  };
  v1::PlanRequest request = Glass();
  request.mutable_path_constraints()->mutable_orientation(0)->mutable_tolerance()->set_y(0.0);
  refused(request, "path_constraints.orientation[0].tolerance.y = 0 must be within (0, π] [rad]");
  request = Glass();
  request.mutable_path_constraints()->mutable_orientation(0)->set_link("glass");
  refused(request, "path_constraints.orientation[0].link = 'glass' is not a link of robot 'panda'");
  request = Glass();
  request.mutable_path_constraints()->mutable_orientation(0)->mutable_orientation()->set_w(NAN);
  refused(request, "path_constraints.orientation[0].orientation.w = nan must be finite");
  request = Glass();
  request.mutable_path_constraints()->mutable_orientation(0)->set_parameterization(v1::OrientationConstraint::XYZ_EULER_ANGLES);
  request.mutable_path_constraints()->mutable_orientation(0)->mutable_tolerance()->set_y(kPi / 2);
  refused(request, "with XYZ_EULER_ANGLES: at |y| = π/2 the x and z angles are undefined");
  request = Glass();
  v1::PositionConstraint* box = request.mutable_path_constraints()->add_position();
  box->mutable_half_extents()->set_x(-0.1);
  refused(request, "path_constraints.position[0].half_extents.x = -0.1 must be finite and >= 0 [m]");
  request = Glass();
  request.mutable_workcell()->set_name("cell");
  refused(request, "path_constraints are not supported with workcell");
}

TEST_F(PathConstraintsTest, APositionConstraintKeepsTheToolInItsBox) {
  // The tool kept within 5 mm of the plane z = its start height while the arm turns 1.5 rad at
  // its base and reaches out: re-checked at 0.002 rad steps on the URDF joints chained.
  v1::PlanRequest request;
  const std::vector<double> start = {0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785};
  for (double v : start) request.mutable_start()->add_positions(v);
  const auto panda =
      RobotModel::FromUrdf(ReadText(ExamplePath("robots/panda.urdf")), ReadText(ExamplePath("robots/panda.srdf")));
  const int tcp = panda->FindLink("panda_tcp");
  std::vector<Eigen::Isometry3d> poses;
  panda->ForwardKinematicsByChaining(ToVector(request.start().positions()), &poses);
  const double height = poses[static_cast<std::size_t>(tcp)].translation().z();
  v1::PoseGoal* goal = request.mutable_pose_goal();
  goal->set_link("panda_tcp");
  goal->mutable_pose()->mutable_position()->set_x(0.55 * std::cos(1.5));
  goal->mutable_pose()->mutable_position()->set_y(0.55 * std::sin(1.5));
  goal->mutable_pose()->mutable_position()->set_z(height);
  const Eigen::Quaterniond down(poses[static_cast<std::size_t>(tcp)].linear());
  goal->mutable_pose()->mutable_orientation()->set_x(down.x());
  goal->mutable_pose()->mutable_orientation()->set_y(down.y());
  goal->mutable_pose()->mutable_orientation()->set_z(down.z());
  goal->mutable_pose()->mutable_orientation()->set_w(down.w());
  v1::PositionConstraint* slab = request.mutable_path_constraints()->add_position();
  slab->set_link("panda_tcp");
  slab->mutable_region()->mutable_position()->set_z(height);
  slab->mutable_half_extents()->set_x(2.0);
  slab->mutable_half_extents()->set_y(2.0);
  slab->mutable_half_extents()->set_z(0.005);
  request.set_seed(3);
  request.set_time_budget(10.0);
  const auto worst_height = [&](const v1::JointTrajectory& t) {
    double worst = 0.0;
    for (int s = 0; s + 1 < t.points_size(); ++s) {
      const Eigen::VectorXd a = ToVector(t.points(s).positions()), b = ToVector(t.points(s + 1).positions());
      const int n = std::max(1, static_cast<int>(std::ceil((b - a).cwiseAbs().maxCoeff() / 0.002)));
      for (int i = 0; i <= n; ++i) {
        panda->ForwardKinematicsByChaining(a + (b - a) * (static_cast<double>(i) / n), &poses);
        worst = std::max(worst, std::abs(poses[static_cast<std::size_t>(tcp)].translation().z() - height));
      }
    }
    return worst;
  };
  v1::PlanRequest free = request;
  free.clear_path_constraints();
  v1::PlanResponse bare;
  ASSERT_TRUE(server_->Plan(free, &bare).ok());
  ASSERT_EQ(bare.outcome(), v1::SUCCESS) << bare.message();
  EXPECT_GT(worst_height(bare.trajectory()), 0.01) << "the scenario should need the constraint";
  v1::PlanResponse response;
  const grpc::Status status = server_->Plan(request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  EXPECT_LE(worst_height(response.trajectory()), 0.005 + 1e-9);
}

}  // namespace
}  // namespace chasles::testing
