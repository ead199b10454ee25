// PlanRequest/OptimizeRequest `padding` over gRPC: every robot shape grown by it for the start
// check, planning and verification (a start closer to the table than the padding is
// START_IN_COLLISION, every returned sample keeps the padding), named INVALID_ARGUMENT errors for
// values outside [0, 0.5] m and with a workcell, and the server's checker cache keyed by padding
// (a checker built for one padding is never returned for another).

#include <cmath>
#include <limits>
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "chasles/collision/collision_checker.h"
#include "chasles/robot/robot_model.h"
#include "chasles/server/convert.h"
#include "chasles/server/default_assets.h"
#include "chasles/server/model_store.h"
#include "server_fixture.h"

namespace chasles::testing {
namespace {

/// The default Panda at the default table (what panda_table.json plans with), built here.
struct PandaAtTable {
  std::shared_ptr<const RobotModel> robot = RobotModel::FromUrdf(ReadText(ExamplePath("robots/panda.urdf")),
                                                                 ReadText(ExamplePath("robots/panda.srdf")));
  std::shared_ptr<const Scene> scene = SceneFromProto(LoadScene("table"));
};

Eigen::VectorXd Positions(const google::protobuf::RepeatedField<double>& values) {
  Eigen::VectorXd q(values.size());
  for (int i = 0; i < values.size(); ++i) q[i] = values[i];
  return q;
}

class PaddingTest : public SharedServerTest<> {};

TEST_F(PaddingTest, AStartCloserToTheTableThanThePaddingIsInCollisionAndTheCacheKeepsPaddingsApart) {
  const PandaAtTable world;
  const CollisionChecker bare(world.robot, world.scene);
  v1::PlanRequest request = LoadRequest("panda_table");
  // The start: the ready pose leaned forward (shoulder, joint 1) until the arm is 1-4 mm from
  // the table's objects. (Paddings stay below 5 mm: the padding applies to self pairs too, and
  // the sphere model's wrist links 5 and 7 are 11.2 mm apart in the ready pose's wrist posture.)
  Eigen::VectorXd start = Positions(request.start().positions());
  while (start[1] < 1.5 && !(bare.IsValid(start) && bare.Clearance(start) < 0.004)) start[1] += 0.0005;
  ASSERT_TRUE(bare.IsValid(start));
  request.mutable_start()->set_positions(1, start[1]);
  const double clearance = bare.Clearance(start);
  ASSERT_GT(clearance, 0.001);
  ASSERT_LT(clearance, 0.004);

  // Alternate paddings on the same robot and scene: a checker cached for one padding must not
  // answer for the other (the padded start collides, the bare one does not).
  for (int round = 0; round < 2; ++round) {
    SCOPED_TRACE("round " + std::to_string(round));
    v1::PlanResponse response;
    request.set_padding(0.0);
    ASSERT_TRUE(server_->Plan(request, &response).ok());
    EXPECT_EQ(response.outcome(), v1::SUCCESS) << response.message();

    request.set_padding(clearance + 0.001);
    ASSERT_TRUE(server_->Plan(request, &response).ok());
    EXPECT_EQ(response.outcome(), v1::START_IN_COLLISION) << response.message();
    EXPECT_NE(response.message().find("start is in collision"), std::string::npos) << response.message();
    EXPECT_NE(response.message().find("table"), std::string::npos) << response.message();
  }

  // A padding the start keeps: the plan succeeds, certified, and every returned sample keeps it
  // (checked here on the bare robot), with min_clearance measured to the padded robot.
  const double padding = 0.5 * clearance;
  request.set_padding(padding);
  v1::PlanResponse padded;
  ASSERT_TRUE(server_->Plan(request, &padded).ok());
  ASSERT_EQ(padded.outcome(), v1::SUCCESS) << padded.message();
  EXPECT_EQ(padded.verification().collision_guarantee(), "certified");
  EXPECT_EQ(padded.verification().collision_guarantee_reason(), "");
  double smallest = std::numeric_limits<double>::infinity();
  for (const v1::TrajectoryPoint& point : padded.trajectory().points()) {
    smallest = std::min(smallest, bare.Clearance(Positions(point.positions())));
  }
  EXPECT_GE(smallest, padding);
  EXPECT_GE(padded.quality().min_clearance(), 0.0);
  EXPECT_LE(padded.quality().min_clearance(), smallest - padding + 1e-9);
}

TEST_F(PaddingTest, ValuesOutsideTheRangeAreInvalidArgumentsNamingFieldAndRule) {
  const auto expect_invalid = [](const grpc::Status& status, const std::string& message) {
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();
    EXPECT_NE(status.error_message().find(message), std::string::npos)
        << "'" << message << "' not in: " << status.error_message();
  };
  v1::PlanRequest request = LoadRequest("panda_table");
  v1::PlanResponse response;
  request.set_padding(-1.0);
  expect_invalid(server_->Plan(request, &response), "padding = -1 must be in [0, 0.5] m");
  request.set_padding(0.6);
  expect_invalid(server_->Plan(request, &response), "padding = 0.6 must be in [0, 0.5] m");
  request.set_padding(std::nan(""));
  expect_invalid(server_->Plan(request, &response), "padding = nan must be in [0, 0.5] m");

  // Optimize: the same rule.
  v1::OptimizeRequest optimize;
  *optimize.add_path() = request.start();
  *optimize.add_path()->mutable_positions() = request.goal().positions();
  optimize.set_padding(-0.01);
  v1::OptimizeResponse optimized;
  grpc::ClientContext context;
  expect_invalid(server_->stub().Optimize(&context, optimize, &optimized), "padding = -0.01 must be in [0, 0.5] m");

  // A workcell plan is coordinated without robot padding: a padding there is refused, not ignored.
  request.set_padding(0.01);
  request.mutable_workcell()->set_name("cell");
  expect_invalid(server_->Plan(request, &response), "padding = 0.01 is not supported with workcell");
}

TEST(PaddingCache, ModelStoreBuildsOneCheckerPerPadding) {
  v1::RobotModel robot;
  robot.mutable_urdf()->set_urdf(std::string(kDefaultRobotUrdf));
  robot.mutable_urdf()->set_srdf(std::string(kDefaultRobotSrdf));
  ModelStore store(robot, LoadScene("table"));
  const StoredRobot r = store.default_robot();
  const StoredScene s = store.default_scene();
  const auto bare = store.Checker(r, s);
  const auto padded = store.Checker(r, s, 0.05);
  const auto finer = store.Checker(r, s, 0.05 + 1e-12);
  EXPECT_EQ(bare->options().padding, 0.0);
  EXPECT_EQ(padded->options().padding, 0.05);
  EXPECT_EQ(finer->options().padding, 0.05 + 1e-12);
  EXPECT_NE(bare, padded);
  EXPECT_NE(padded, finer);
  EXPECT_EQ(store.Checker(r, s, 0.05), padded);  // cached per padding
  EXPECT_EQ(store.Checker(r, s, 0.0), bare);
}

}  // namespace
}  // namespace chasles::testing
