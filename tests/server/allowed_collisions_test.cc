// Scene.allowed_collisions over gRPC: a Plan whose start rests the hand on objects succeeds when
// the scene allows exactly those contacts and is START_IN_COLLISION otherwise; names that do not
// resolve are INVALID_ARGUMENT naming the pair.
#include <string>

#include <gtest/gtest.h>

#include "server_fixture.h"

namespace chasles::testing {
namespace {

// Panda folded down onto the table: panda_hand touches table_top and rolling_pin (no other link
// touches anything).
const double kPandaOnTable[] = {0.0, 1.2, 0.0, -0.5, 0.0, 1.5, 0.785};

class AllowedCollisionsTest : public SharedServerTest<> {
 protected:
  /// The examples' Panda-at-the-table request with the table scene inline and the start on it.
  static v1::PlanRequest OnTheTable() {
    v1::PlanRequest request = LoadRequest("panda_table");
    *request.mutable_scene() = LoadScene("table");
    request.mutable_start()->clear_positions();
    for (double q : kPandaOnTable) request.mutable_start()->add_positions(q);
    return request;
  }
  static void Allow(v1::PlanRequest* request, const std::string& link1, const std::string& link2) {
    v1::LinkPair* pair = request->mutable_scene()->add_allowed_collisions();
    pair->set_link1(link1);
    pair->set_link2(link2);
  }
};

TEST_F(AllowedCollisionsTest, StartTouchingAllowedObjectsPlans) {
  v1::PlanRequest request = OnTheTable();
  v1::PlanResponse response;
  ASSERT_TRUE(server_->Plan(request, &response).ok());
  EXPECT_EQ(response.outcome(), v1::START_IN_COLLISION) << response.message();
  const std::string plain_scene_id = response.scene_id();

  // One of the two contacts allowed: the other one is still a collision.
  Allow(&request, "panda_hand", "table_top");
  ASSERT_TRUE(server_->Plan(request, &response).ok());
  EXPECT_EQ(response.outcome(), v1::START_IN_COLLISION) << response.message();
  EXPECT_NE(response.message().find("rolling_pin"), std::string::npos) << response.message();
  EXPECT_NE(response.scene_id(), plain_scene_id);  // the pairs are part of the scene's content id

  Allow(&request, "panda_hand", "rolling_pin");
  ASSERT_TRUE(server_->Plan(request, &response).ok());
  ASSERT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  ASSERT_GT(response.trajectory().points_size(), 1);
  const auto& first = response.trajectory().points(0).positions();
  ASSERT_EQ(first.size(), 7);
  for (int i = 0; i < 7; ++i) EXPECT_NEAR(first[i], kPandaOnTable[i], 1e-9) << "joint " << i;
}

TEST_F(AllowedCollisionsTest, NamesThatDoNotResolveAreInvalidArguments) {
  const auto expect_error = [](const v1::PlanRequest& request, const std::string& fragment) {
    v1::PlanResponse response;
    const grpc::Status status = server_->Plan(request, &response);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();
    EXPECT_NE(status.error_message().find(fragment), std::string::npos)
        << "'" << fragment << "' not in: " << status.error_message();
  };
  v1::PlanRequest request = OnTheTable();
  Allow(&request, "panda_hand", "table_top");
  Allow(&request, "hand", "rolling_pin");
  expect_error(request, "scene.allowed_collisions[1].link1 = 'hand' is not a link of robot 'panda'");

  request = OnTheTable();
  Allow(&request, "panda_hand", "nope");
  expect_error(request, "scene.allowed_collisions[0].link2 = 'nope' is neither a link of robot 'panda' nor an "
                        "object or OctoMap of the scene");

  request = OnTheTable();
  Allow(&request, "panda_hand", "");
  expect_error(request, "scene.allowed_collisions[0].link2 is empty");
}

}  // namespace
}  // namespace chasles::testing
