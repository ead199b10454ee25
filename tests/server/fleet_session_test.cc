// Fleet sessions over gRPC (issue 21, item 5): the fleet example's 60 bases are opened as a
// session, their goals sent as they come (in batches, some while robots are still moving), and
// every robot's executed motion — rebuilt here from the FleetPlan knots alone, each plan from its
// start_time until the next plan of that robot starts — is checked independently at 1 ms: discs
// apart, clear of the scene's boxes, within the velocity limits, continuous where plans hand
// over. Bad input gets named errors and changes nothing.

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <google/protobuf/util/json_util.h>
#include <gtest/gtest.h>

#include "redis_fixture.h"
#include "server_fixture.h"

namespace chasles::testing {
namespace {

/// A robot's motion from TrajectoryKnots (the rule in chasles.proto), from `start` [s].
struct KnotMotion {
  double start = 0.0;
  v1::TrajectoryKnots knots;
  /// (x, y) and speed at absolute time t >= start.
  void At(double t, double* x, double* y, double* speed) const {
    const int n = knots.joint_names_size();
    const int m = knots.times_size();
    const double tau_abs = t - start;
    int i = static_cast<int>(std::upper_bound(knots.times().begin(), knots.times().end(), tau_abs) - knots.times().begin()) - 1;
    if (i < 0) i = 0;
    double q[3], v[3];
    if (i >= m - 1) {
      for (int j = 0; j < 3; ++j) {
        q[j] = knots.positions((m - 1) * n + j);
        v[j] = 0.0;
      }
    } else {
      const double T = knots.times(i + 1) - knots.times(i), tau = tau_abs - knots.times(i);
      for (int j = 0; j < 3; ++j) {
        const double vi = knots.velocities(i * n + j), vn = knots.velocities((i + 1) * n + j);
        q[j] = knots.positions(i * n + j) + vi * tau + (vn - vi) * tau * tau / (2.0 * T);
        v[j] = vi + (vn - vi) * tau / T;
      }
    }
    *x = q[0];
    *y = q[1];
    *speed = std::hypot(v[0], v[1]);
  }
};

/// Where a robot `lag` seconds behind its current plan is at `now`: true, with that position,
/// when the plan has it moving (faster than 0.05 m/s) both then and `lag` before.
bool SeenLate(const std::vector<KnotMotion>& plans, double now, double lag, double* x, double* y) {
  const KnotMotion& current = plans.back();
  double xn, yn, speed, speed_before;
  current.At(now, &xn, &yn, &speed);
  current.At(now - lag, x, y, &speed_before);
  return current.start <= now - lag && speed >= 0.05 && speed_before >= 0.05;
}

/// The independent check at 1 ms of every robot's executed motion (its start, then each plan from
/// its start_time until the robot's next plan starts), rebuilt from the knots alone: discs of
/// 0.4 m at least 0.2 m apart (1 m spacing), 0.1 m from the scene's unit boxes, at most 1 m/s;
/// a new plan starts where the robot is, at rest.
void CheckExecuted(const v1::CoordinateRequest& example, std::map<std::string, std::vector<KnotMotion>> motions,
                   double from, double horizon) {
  const int n = example.robots_size();
  std::map<std::string, std::vector<double>> starts;
  for (const v1::TeamRobot& r : example.robots()) starts[r.name()] = {r.start().positions(0), r.start().positions(1)};
  // The scene's boxes are unit cells: blocked[(cx, cy)] with the box centred at (cx + 0.5, cy + 0.5).
  std::set<std::pair<int, int>> blocked;
  for (const v1::Box& box : example.scene().boxes()) {
    ASSERT_EQ(box.size().x(), 1.0);
    ASSERT_EQ(box.size().y(), 1.0);
    blocked.insert({static_cast<int>(std::floor(box.pose().position().x())),
                    static_cast<int>(std::floor(box.pose().position().y()))});
  }
  std::vector<std::string> names;
  for (const v1::TeamRobot& r : example.robots()) names.push_back(r.name());
  const double radius = 0.4;
  double min_pair = 1e9, min_box = 1e9, max_speed = 0.0;
  std::vector<double> x(static_cast<std::size_t>(n)), y(static_cast<std::size_t>(n));
  for (double t = from; t <= horizon + 1e-9; t += 1e-3) {
    for (int i = 0; i < n; ++i) {
      const auto& list = motions[names[static_cast<std::size_t>(i)]];
      double speed = 0.0;
      x[i] = starts[names[static_cast<std::size_t>(i)]][0];
      y[i] = starts[names[static_cast<std::size_t>(i)]][1];
      for (std::size_t k = 0; k < list.size(); ++k) {
        if (list[k].start > t) break;
        list[k].At(t, &x[i], &y[i], &speed);
      }
      max_speed = std::max(max_speed, speed);
      const int cx = static_cast<int>(std::floor(x[i])), cy = static_cast<int>(std::floor(y[i]));
      for (int bx = cx - 1; bx <= cx + 1; ++bx) {
        for (int by = cy - 1; by <= cy + 1; ++by) {
          if (blocked.count({bx, by}) == 0) continue;
          const double dx = std::max(std::abs(x[i] - (bx + 0.5)) - 0.5, 0.0);
          const double dy = std::max(std::abs(y[i] - (by + 0.5)) - 0.5, 0.0);
          min_box = std::min(min_box, std::hypot(dx, dy) - radius);
        }
      }
    }
    for (int i = 0; i < n; ++i) {
      for (int j = i + 1; j < n; ++j) {
        const double dx = x[i] - x[j], dy = y[i] - y[j];
        if (std::abs(dx) < 2.0 && std::abs(dy) < 2.0) min_pair = std::min(min_pair, std::hypot(dx, dy) - 2 * radius);
      }
    }
  }
  // Hand-overs: a new plan starts where the robot is at that moment, at rest.
  for (const auto& [name, list] : motions) {
    for (std::size_t k = 1; k < list.size(); ++k) {
      double x0, y0, s0, x1, y1, s1;
      list[k - 1].At(list[k].start, &x0, &y0, &s0);
      list[k].At(list[k].start, &x1, &y1, &s1);
      EXPECT_NEAR(x0, x1, 1e-9) << name;
      EXPECT_NEAR(y0, y1, 1e-9) << name;
      EXPECT_NEAR(s0, 0.0, 1e-9) << name;
    }
  }
  EXPECT_GE(min_pair, 0.2 - 1e-9);  // spacing 1 m: discs of 0.4 m keep 0.2 m
  EXPECT_GE(min_box, 0.1 - 1e-9);   // nodes 0.5 m from a box edge
  EXPECT_LE(max_speed, 1.0 + 1e-9);  // 1 m/s, along one axis at a time
}

class FleetSessions : public SharedServerTest<> {
 protected:
  static v1::CoordinateRequest Example() {
    v1::CoordinateRequest request;
    const auto parsed = google::protobuf::util::JsonStringToMessage(
        ReadText(ExamplePath("requests/coordinate_fleet.json")), &request);
    EXPECT_TRUE(parsed.ok()) << parsed.ToString();
    return request;
  }
  static v1::OpenFleetSessionRequest OpenRequest(const v1::CoordinateRequest& example, const std::string& name) {
    v1::OpenFleetSessionRequest open;
    open.set_name(name);
    *open.mutable_scene() = example.scene();
    for (const v1::TeamRobot& robot : example.robots()) {
      v1::TeamRobot* r = open.add_robots();
      *r = robot;
      r->clear_goal();
    }
    open.set_fleet_resolution(1.0);
    open.set_start_time(1000.0);
    return open;
  }
  template <typename Request, typename Response, typename Method>
  static grpc::Status Call(const Request& request, Response* response, Method call) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
    return (server_->stub().*call)(&context, request, response);
  }
};

TEST_F(FleetSessions, GoalsThatKeepComingAreAnsweredApartAndCertifiedIndependently) {
  const v1::CoordinateRequest example = Example();
  v1::OpenFleetSessionResponse opened;
  grpc::Status status = Call(OpenRequest(example, "depot"), &opened, &v1::Planning::Stub::OpenFleetSession);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(opened.robots(), 60u);
  EXPECT_EQ(opened.start_time(), 1000.0);
  EXPECT_DOUBLE_EQ(opened.lattice().resolution(), 1.0);

  const int n = example.robots_size();
  std::map<std::string, std::vector<KnotMotion>> motions;
  // Round 1: the example's goals, in three batches 2 s apart (robots of the first batches are
  // moving when the later ones come). Round 2: every robot back to its start, once all are idle.
  double now = 1000.0, horizon = 1000.0, slowest = 0.0;
  int answered = 0, deferred_total = 0;
  for (int round = 0; round < 2; ++round) {
    std::vector<std::pair<std::string, std::vector<double>>> pending;
    for (const v1::TeamRobot& r : example.robots()) {
      const auto& to = round == 0 ? r.goal().positions() : r.start().positions();
      pending.push_back({r.name(), {to[0], to[1], to[2]}});
    }
    for (int attempt = 0; attempt < 4 && !pending.empty(); ++attempt) {
      std::vector<std::pair<std::string, std::vector<double>>> deferred;
      const std::size_t batch = (pending.size() + 2) / 3;
      for (std::size_t from = 0; from < pending.size(); from += batch) {
        v1::AssignFleetGoalsRequest goals;
        goals.set_name("depot");
        goals.set_now(now);
        for (std::size_t k = from; k < std::min(pending.size(), from + batch); ++k) {
          v1::FleetGoal* goal = goals.add_goals();
          goal->set_robot(pending[k].first);
          for (double v : pending[k].second) goal->add_positions(v);
        }
        v1::AssignFleetGoalsResponse response;
        status = Call(goals, &response, &v1::Planning::Stub::AssignFleetGoals);
        ASSERT_TRUE(status.ok()) << status.error_message();
        EXPECT_EQ(response.now(), now);
        ASSERT_EQ(response.results_size(), goals.goals_size());
        for (int k = 0; k < response.results_size(); ++k) {
          const v1::FleetGoalResult& result = response.results(k);
          slowest = std::max(slowest, result.seconds());
          if (result.outcome() == v1::SUCCESS) {
            ++answered;
          } else {
            EXPECT_NE(result.message().find("is going to park"), std::string::npos) << result.message();
            deferred.push_back(pending[from + static_cast<std::size_t>(k)]);
          }
        }
        for (const v1::FleetPlan& plan : response.plans()) {
          EXPECT_GE(plan.start_time(), now - 1e-9);
          EXPECT_GE(plan.finish_time(), plan.arrival_time());
          EXPECT_EQ(plan.knots().joint_names_size(), 3);
          motions[plan.robot()].push_back({plan.start_time(), plan.knots()});
          horizon = std::max(horizon, plan.finish_time());
        }
        for (const v1::FleetOrder& order : response.orders()) EXPECT_LE(order.leaves(), order.enters() + 1e-9);
        now += 2.0;
      }
      deferred_total += static_cast<int>(deferred.size());
      pending = deferred;
      now = std::max(now, horizon + 0.5);  // retry once every robot is idle
    }
    ASSERT_TRUE(pending.empty());
    now = std::max(now, horizon + 0.5);
  }
  EXPECT_EQ(answered, 2 * n);
  std::cout << "[ session  ] " << answered << " goals answered (" << deferred_total << " retried once all idle), slowest "
            << slowest * 1e3 << " ms; horizon " << horizon - 1000.0 << " s\n";

  CheckExecuted(example, motions, 1000.0, horizon);
}

TEST_F(FleetSessions, BadInputGetsNamedErrorsAndChangesNothing) {
  const v1::CoordinateRequest example = Example();
  v1::OpenFleetSessionResponse opened;
  ASSERT_TRUE(Call(OpenRequest(example, "yard"), &opened, &v1::Planning::Stub::OpenFleetSession).ok());
  // The same name again.
  grpc::Status status = Call(OpenRequest(example, "yard"), &opened, &v1::Planning::Stub::OpenFleetSession);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_NE(status.error_message().find("fleet session 'yard' is open already"), std::string::npos);
  // A start off the lattice, and an arm in a fleet.
  v1::OpenFleetSessionRequest bad = OpenRequest(example, "bad");
  bad.mutable_robots(3)->mutable_start()->set_positions(0, 10.7);
  status = Call(bad, &opened, &v1::Planning::Stub::OpenFleetSession);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("robots[3].start.positions = (10.7, "), std::string::npos) << status.error_message();
  bad = OpenRequest(example, "bad name");
  status = Call(bad, &opened, &v1::Planning::Stub::OpenFleetSession);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(status.error_message(), "name = 'bad name' must be 1 to 64 characters of [A-Za-z0-9_.-]");
  bad = OpenRequest(example, "bad");
  bad.mutable_robots(2)->set_name("");
  status = Call(bad, &opened, &v1::Planning::Stub::OpenFleetSession);
  EXPECT_EQ(status.error_message(), "robots[2].name = '' must be 1 to 64 characters of [A-Za-z0-9_.-]");
  bad = OpenRequest(example, "bad");
  bad.set_start_time(-1.0);
  status = Call(bad, &opened, &v1::Planning::Stub::OpenFleetSession);
  EXPECT_EQ(status.error_message(), "start_time = -1 must be finite and >= 0 s since the Unix epoch (0 = now)");
  bad = OpenRequest(example, "bad");
  bad.mutable_robots(1)->clear_robot();
  bad.mutable_robots(1)->mutable_robot()->mutable_urdf()->set_urdf(ReadText(ExamplePath("robots/panda.urdf")));
  status = Call(bad, &opened, &v1::Planning::Stub::OpenFleetSession);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("robots[1] 'r01' is not a planar mobile base"), std::string::npos)
      << status.error_message();

  v1::AssignFleetGoalsRequest goals;
  goals.set_name("nowhere");
  v1::AssignFleetGoalsResponse response;
  status = Call(goals, &response, &v1::Planning::Stub::AssignFleetGoals);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_NE(status.error_message().find("fleet session 'nowhere' is not open"), std::string::npos);
  // A good goal before a bad one: neither is planned.
  goals.set_name("yard");
  goals.set_now(1001.0);
  v1::FleetGoal* good = goals.add_goals();
  good->set_robot(example.robots(0).name());
  for (double v : example.robots(0).goal().positions()) good->add_positions(v);
  v1::FleetGoal* unknown = goals.add_goals();
  unknown->set_robot("r999");
  unknown->add_positions(1.5);
  status = Call(goals, &response, &v1::Planning::Stub::AssignFleetGoals);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(status.error_message(), "goals[1].robot = 'r999' is not a robot of this fleet session");
  unknown->set_robot(example.robots(1).name());
  status = Call(goals, &response, &v1::Planning::Stub::AssignFleetGoals);
  EXPECT_EQ(status.error_message(), "goals[1].positions has 1 values; give (x, y, θ)");
  unknown->add_positions(std::nan(""));
  unknown->add_positions(0.0);
  status = Call(goals, &response, &v1::Planning::Stub::AssignFleetGoals);
  EXPECT_EQ(status.error_message(), "goals[1].positions[1] = nan must be finite");
  unknown->set_positions(0, 2.5);  // the centre of box cell_2_0
  unknown->set_positions(1, 0.5);
  status = Call(goals, &response, &v1::Planning::Stub::AssignFleetGoals);
  EXPECT_NE(status.error_message().find("goals[1].positions = (2.5, 0.5) is on a blocked lattice node"),
            std::string::npos)
      << status.error_message();
  goals.set_now(10.0);
  goals.mutable_goals()->RemoveLast();
  status = Call(goals, &response, &v1::Planning::Stub::AssignFleetGoals);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("before the session's start 1000"), std::string::npos) << status.error_message();
  // Nothing was planned: the first good goal now succeeds and is the robot's first plan.
  goals.set_now(1001.0);
  status = Call(goals, &response, &v1::Planning::Stub::AssignFleetGoals);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(response.results_size(), 1);
  EXPECT_EQ(response.results(0).outcome(), v1::SUCCESS) << response.results(0).message();
  ASSERT_GE(response.plans_size(), 1);
  EXPECT_EQ(response.plans(0).start_time(), 1001.0);

  v1::CloseFleetSessionRequest close;
  close.set_name("yard");
  v1::CloseFleetSessionResponse closed;
  ASSERT_TRUE(Call(close, &closed, &v1::Planning::Stub::CloseFleetSession).ok());
  EXPECT_TRUE(closed.closed());
  ASSERT_TRUE(Call(close, &closed, &v1::Planning::Stub::CloseFleetSession).ok());
  EXPECT_FALSE(closed.closed());
}

// The executor's stream: goals and robot states on one StreamFleetSession call, answered in
// order. Robots on their way report where they are every second — one of them 0.4 s behind its
// plan each time: LATE by 0.4 s, its plan and those ordered after it delayed (their new plans in
// the answer) — and every executed motion, delays included, is checked at 1 ms as above.
TEST_F(FleetSessions, AStreamCarriesStatesAndGoalsAndALateRobotIsDelayedWithThoseOrderedAfterIt) {
  const v1::CoordinateRequest example = Example();
  v1::OpenFleetSessionResponse opened;
  grpc::Status status = Call(OpenRequest(example, "stream_depot"), &opened, &v1::Planning::Stub::OpenFleetSession);
  ASSERT_TRUE(status.ok()) << status.error_message();
  std::map<std::string, std::vector<KnotMotion>> motions;
  double horizon = 1000.0;
  const auto keep = [&](const v1::AssignFleetGoalsResponse& response) {
    for (const v1::FleetPlan& plan : response.plans()) {
      motions[plan.robot()].push_back({plan.start_time(), plan.knots()});
      horizon = std::max(horizon, plan.finish_time());
    }
  };
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  auto stream = server_->stub().StreamFleetSession(&context);
  const int n = example.robots_size();
  int late = 0, on_plan = 0, delayed_others = 0;
  for (int second = 0; second < 12; ++second) {
    const double now = 1000.0 + second;
    v1::AssignFleetGoalsRequest message;
    if (second == 0) message.set_name("stream_depot");  // later messages: the stream's session
    message.set_now(now);
    if (second == 0 || second == 6) {
      for (int k = second == 0 ? 0 : n / 2; k < (second == 0 ? n / 2 : n); ++k) {
        v1::FleetGoal* goal = message.add_goals();
        goal->set_robot(example.robots(k).name());
        *goal->mutable_positions() = example.robots(k).goal().positions();
      }
    }
    // States: every robot on its way; the first one moving for at least 0.4 s is seen 0.4 s
    // behind its plan.
    std::string late_robot;
    for (const auto& [name, list] : motions) {
      double x0, y0, x, y, speed;
      if (!SeenLate(list, now, 0.4, &x0, &y0)) continue;
      v1::FleetRobotState* state = message.add_states();
      state->set_robot(name);
      if (late_robot.empty()) {
        late_robot = name;
        state->set_x(x0);
        state->set_y(y0);
      } else {
        list.back().At(now, &x, &y, &speed);  // on plan
        state->set_x(x);
        state->set_y(y);
      }
    }
    ASSERT_TRUE(stream->Write(message));
    v1::AssignFleetGoalsResponse answer;
    ASSERT_TRUE(stream->Read(&answer)) << "second " << second;
    EXPECT_EQ(answer.now(), now);
    ASSERT_EQ(answer.states_size(), message.states_size());
    for (const v1::FleetStateResult& result : answer.states()) {
      if (result.robot() == late_robot) {
        EXPECT_EQ(result.status(), v1::LATE) << result.message();
        EXPECT_NEAR(result.delay(), 0.4, 1e-6) << result.message();
        late += result.status() == v1::LATE;
        delayed_others += result.delayed_size();
      } else {
        EXPECT_EQ(result.status(), v1::ON_PLAN) << result.robot() << ": " << result.message();
        on_plan += result.status() == v1::ON_PLAN;
      }
    }
    for (const v1::FleetGoalResult& result : answer.results()) {
      EXPECT_TRUE(result.outcome() == v1::SUCCESS || result.message().find("is going to park") != std::string::npos)
          << result.message();
    }
    keep(answer);
  }
  ASSERT_TRUE(stream->WritesDone());
  status = stream->Finish();
  EXPECT_TRUE(status.ok()) << status.error_message();
  EXPECT_GE(late, 8);
  EXPECT_GT(on_plan, 50);
  std::cout << "[ stream   ] " << late << " robots reported late (" << delayed_others << " others delayed after them), "
            << on_plan << " on plan\n";
  CheckExecuted(example, motions, 1000.0, horizon);

  // A bad message ends the stream with its status, naming the message; what came before stays.
  grpc::ClientContext bad_context;
  bad_context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  auto bad = server_->stub().StreamFleetSession(&bad_context);
  v1::AssignFleetGoalsRequest first;
  first.set_name("stream_depot");
  ASSERT_TRUE(bad->Write(first));
  v1::AssignFleetGoalsResponse answer;
  ASSERT_TRUE(bad->Read(&answer));
  v1::AssignFleetGoalsRequest second = first;
  second.set_name("");
  v1::FleetRobotState* state = second.add_states();
  state->set_robot("nobody");
  bad->Write(second);
  EXPECT_FALSE(bad->Read(&answer));
  status = bad->Finish();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("message 1: states[0].robot = 'nobody' is not a robot of this fleet session"),
            std::string::npos)
      << status.error_message();
  // Another session's name on the stream, a NaN position, a negative tolerance: named too.
  const auto refused = [&](const v1::AssignFleetGoalsRequest& message) {
    grpc::ClientContext c;
    c.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
    auto s = server_->stub().StreamFleetSession(&c);
    s->Write(message);
    v1::AssignFleetGoalsResponse ignored;
    while (s->Read(&ignored)) {
    }
    return s->Finish();
  };
  v1::AssignFleetGoalsRequest nan = first;
  v1::FleetRobotState* nan_state = nan.add_states();
  nan_state->set_robot(example.robots(0).name());
  nan_state->set_x(std::nan(""));
  status = refused(nan);
  EXPECT_NE(status.error_message().find("message 0: states[0] (x, y) = (nan, 0) must be finite"), std::string::npos)
      << status.error_message();
  v1::AssignFleetGoalsRequest tolerance = first;
  tolerance.set_state_tolerance(-1.0);
  status = refused(tolerance);
  EXPECT_NE(status.error_message().find("state_tolerance = -1 must be finite and > 0 m"), std::string::npos)
      << status.error_message();
  v1::AssignFleetGoalsRequest unknown = first;
  unknown.set_name("no_such_session");
  status = refused(unknown);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::NOT_FOUND) << status.error_message();
}

// With --store redis://… a session opened on one replica is served by every replica: batches sent
// alternately to two replicas each plan against the other's plans (the shared log replayed, late
// robots reported through the other replica included), two
// robots sent to one node at the same moment through two replicas: exactly one gets it, every
// time; every executed motion is certified as above; closed on one, gone on the other.
TEST(FleetSessionsShared, TwoReplicasServeOneSession) {
  RedisServer redis;
  ServerOptions options = LoopbackServer::QuietOptions(2);
  options.store = redis.url();
  LoopbackServer a(options), b(options);
  LoopbackServer* replicas[2] = {&a, &b};
  const auto call = [](LoopbackServer& server, const auto& request, auto* response, auto method) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
    return (server.stub().*method)(&context, request, response);
  };
  v1::CoordinateRequest example;
  ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(ReadText(ExamplePath("requests/coordinate_fleet.json")),
                                                           &example)
                  .ok());
  v1::OpenFleetSessionRequest open;
  open.set_name("shared_depot");
  *open.mutable_scene() = example.scene();
  for (const v1::TeamRobot& robot : example.robots()) {
    *open.add_robots() = robot;
    open.mutable_robots(open.robots_size() - 1)->clear_goal();
  }
  open.set_fleet_resolution(1.0);
  open.set_start_time(1000.0);
  v1::OpenFleetSessionResponse opened;
  grpc::Status status = call(a, open, &opened, &v1::Planning::Stub::OpenFleetSession);
  ASSERT_TRUE(status.ok()) << status.error_message();
  status = call(b, open, &opened, &v1::Planning::Stub::OpenFleetSession);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION) << status.error_message();

  std::map<std::string, std::vector<KnotMotion>> motions;
  double horizon = 1000.0, now = 1000.0;
  int reported_late = 0;
  const auto keep = [&](const v1::AssignFleetGoalsResponse& response) {
    for (const v1::FleetPlan& plan : response.plans()) {
      motions[plan.robot()].push_back({plan.start_time(), plan.knots()});
      horizon = std::max(horizon, plan.finish_time());
    }
  };
  // Batches of 6 goals, alternately to a and b; deferred goals again once every robot is idle.
  std::vector<int> pending;
  for (int k = 0; k < example.robots_size(); ++k) pending.push_back(k);
  for (int round = 0; round < 4 && !pending.empty(); ++round) {
    std::vector<int> deferred;
    for (std::size_t from = 0, batch = 0; from < pending.size(); from += 6, ++batch) {
      v1::AssignFleetGoalsRequest goals;
      goals.set_name("shared_depot");
      goals.set_now(now);
      for (std::size_t i = from; i < std::min(pending.size(), from + 6); ++i) {
        const v1::TeamRobot& robot = example.robots(pending[i]);
        v1::FleetGoal* goal = goals.add_goals();
        goal->set_robot(robot.name());
        *goal->mutable_positions() = robot.goal().positions();
      }
      v1::AssignFleetGoalsResponse response;
      status = call(*replicas[batch % 2], goals, &response, &v1::Planning::Stub::AssignFleetGoals);
      ASSERT_TRUE(status.ok()) << status.error_message();
      for (int k = 0; k < response.results_size(); ++k) {
        if (response.results(k).outcome() != v1::SUCCESS) deferred.push_back(pending[from + static_cast<std::size_t>(k)]);
      }
      keep(response);
      now += 1.0;
      // A robot on its way reported 0.4 s late through the other replica: the next batch (on
      // that replica or this one) plans around its delayed plan, so the log carries states too.
      for (const auto& [name, list] : motions) {
        double x0, y0;
        if (!SeenLate(list, now, 0.4, &x0, &y0)) continue;
        v1::AssignFleetGoalsRequest states;
        states.set_name("shared_depot");
        states.set_now(now);
        v1::FleetRobotState* state = states.add_states();
        state->set_robot(name);
        state->set_x(x0);
        state->set_y(y0);
        v1::AssignFleetGoalsResponse reported;
        status = call(*replicas[(batch + 1) % 2], states, &reported, &v1::Planning::Stub::AssignFleetGoals);
        ASSERT_TRUE(status.ok()) << status.error_message();
        ASSERT_EQ(reported.states_size(), 1);
        EXPECT_EQ(reported.states(0).status(), v1::LATE) << reported.states(0).message();
        reported_late += reported.states(0).status() == v1::LATE;
        keep(reported);
        break;
      }
    }
    pending = deferred;
    now = std::max(now, horizon + 0.5);
  }
  EXPECT_TRUE(pending.empty());
  EXPECT_GE(reported_late, 3);

  // The race: robot i through a, robot j through b, one node, the same moment.
  int a_won = 0, b_won = 0;
  for (int round = 0; round < 10; ++round) {
    const v1::TeamRobot& first = example.robots(2 * round);
    const v1::TeamRobot& second = example.robots(2 * round + 1);
    v1::AssignFleetGoalsRequest left, right;
    for (auto* request : {&left, &right}) {
      request->set_name("shared_depot");
      request->set_now(now);
    }
    v1::FleetGoal* goal = left.add_goals();
    goal->set_robot(first.name());
    *goal->mutable_positions() = first.start().positions();  // back where it started
    *right.add_goals() = *goal;
    right.mutable_goals(0)->set_robot(second.name());
    v1::AssignFleetGoalsResponse answer_a, answer_b;
    grpc::Status status_a, status_b;
    std::thread ta([&] { status_a = call(a, left, &answer_a, &v1::Planning::Stub::AssignFleetGoals); });
    std::thread tb([&] { status_b = call(b, right, &answer_b, &v1::Planning::Stub::AssignFleetGoals); });
    ta.join();
    tb.join();
    ASSERT_TRUE(status_a.ok()) << status_a.error_message();
    ASSERT_TRUE(status_b.ok()) << status_b.error_message();
    const bool won_a = answer_a.results(0).outcome() == v1::SUCCESS;
    const bool won_b = answer_b.results(0).outcome() == v1::SUCCESS;
    ASSERT_NE(won_a, won_b) << "round " << round << ": " << answer_a.results(0).message() << " / "
                            << answer_b.results(0).message();
    (won_a ? a_won : b_won) += 1;
    keep(answer_a);
    keep(answer_b);
    now = std::max(now, horizon + 0.5);
  }
  std::cout << "[ shared   ] 10 races for one node: replica a won " << a_won << ", b " << b_won << "\n";
  CheckExecuted(example, motions, 1000.0, horizon);

  v1::CloseFleetSessionRequest close;
  close.set_name("shared_depot");
  v1::CloseFleetSessionResponse closed;
  ASSERT_TRUE(call(b, close, &closed, &v1::Planning::Stub::CloseFleetSession).ok());
  EXPECT_TRUE(closed.closed());
  v1::AssignFleetGoalsRequest late;
  late.set_name("shared_depot");
  v1::AssignFleetGoalsResponse response;
  status = call(a, late, &response, &v1::Planning::Stub::AssignFleetGoals);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::NOT_FOUND) << status.error_message();
}

}  // namespace
}  // namespace chasles::testing
