// Team composition (multi/team.h): the composite RobotModel places every robot's links exactly
// where the robot alone puts them (base pose first, frozen robots at their configuration), keeps
// each robot's own allowed collisions and checks robots against each other; trajectories side by
// side evaluate exactly as each robot's own; VerifyTeam finds robots meeting in space and time.

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "chasles/collision/collision_checker.h"
#include "chasles/multi/team.h"
#include "chasles/optimizers/time_parameterization.h"
#include "chasles/robot/error.h"
#include "chasles/robot/mobile.h"

namespace chasles {
namespace {

constexpr double kPi = 3.14159265358979323846;

/// A planar arm of revolute joints about z, link i of length lengths[i] along x, carrying spheres
/// of radius 0.08 m no more than 0.25 m apart up to its tip; limits ±π, 2 rad/s. With lengths
/// (1, 0.3, 1) the arm folded at (0, π, 0) lays link3 over link1: a self-collision (the pair
/// is not adjacent, so not allowed).
std::shared_ptr<const RobotModel> PlanarArm(const std::vector<double>& lengths, const std::string& name = "planar") {
  std::string urdf = "<?xml version=\"1.0\"?><robot name=\"" + name + "\"><link name=\"base_link\"/>";
  std::string parent = "base_link";
  double offset = 0.0;
  for (std::size_t i = 0; i < lengths.size(); ++i) {
    const std::string link = "link" + std::to_string(i + 1);
    urdf += "<joint name=\"joint" + std::to_string(i + 1) + "\" type=\"revolute\"><parent link=\"" + parent +
            "\"/><child link=\"" + link + "\"/><origin xyz=\"" + std::to_string(offset) +
            " 0 0\"/><axis xyz=\"0 0 1\"/><limit lower=\"-3.141592653589793\" upper=\"3.141592653589793\" "
            "velocity=\"2\" effort=\"10\"/></joint><link name=\"" + link + "\">";
    const int spheres = static_cast<int>(std::ceil(lengths[i] / 0.25 - 1e-9));
    for (int k = 1; k <= spheres; ++k) {
      urdf += "<collision><origin xyz=\"" + std::to_string(lengths[i] * k / spheres) +
              " 0 0\"/><geometry><sphere radius=\"0.08\"/></geometry></collision>";
    }
    urdf += "<inertial><origin xyz=\"" + std::to_string(0.5 * lengths[i]) +
            " 0 0\"/><mass value=\"1.5\"/><inertia ixx=\"0.01\" ixy=\"0\" ixz=\"0\" iyy=\"0.1\" iyz=\"0\" "
            "izz=\"0.1\"/></inertial></link>";
    parent = link;
    offset = lengths[i];
  }
  return RobotModel::FromUrdf(urdf + "</robot>");
}

std::shared_ptr<const RobotModel> ThreeLinkArm() { return PlanarArm({1.0, 0.3, 1.0}, "three_link"); }

std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << path;
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::shared_ptr<const RobotModel> Panda() {
  static const std::shared_ptr<const RobotModel> panda = [] {
    const std::string dir = std::string(CHASLES_SOURCE_DIR) + "/examples/robots/";
    return RobotModel::FromUrdf(ReadFile(dir + "panda.urdf"), ReadFile(dir + "panda.srdf"));
  }();
  return panda;
}

Eigen::Isometry3d Pose(double x, double y, double z, double angle = 0.0,
                       const Eigen::Vector3d& axis = Eigen::Vector3d::UnitZ()) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  pose.translation() = Eigen::Vector3d(x, y, z);
  return pose;
}

PlacedRobot Place(const std::string& name, std::shared_ptr<const RobotModel> model,
                  const Eigen::Isometry3d& pose = Eigen::Isometry3d::Identity(), Eigen::VectorXd frozen_at = {}) {
  PlacedRobot robot;
  robot.name = name;
  robot.model = std::move(model);
  robot.base_pose = pose;
  robot.frozen_at = std::move(frozen_at);
  return robot;
}

Eigen::VectorXd RandomConfiguration(const RobotModel& robot, std::mt19937* rng) {
  Eigen::VectorXd q(robot.num_dofs());
  for (int i = 0; i < q.size(); ++i) {
    q[i] = std::uniform_real_distribution<double>(robot.lower_limits()[i], robot.upper_limits()[i])(*rng);
  }
  return q;
}

Eigen::VectorXd Concat(const std::vector<Eigen::VectorXd>& parts) {
  Eigen::Index n = 0;
  for (const auto& p : parts) n += p.size();
  Eigen::VectorXd out(n);
  n = 0;
  for (const auto& p : parts) {
    out.segment(n, p.size()) = p;
    n += p.size();
  }
  return out;
}

bool StartsWith(const std::string& s, const std::string& prefix) { return s.rfind(prefix, 0) == 0; }

void ExpectError(const std::function<void()>& f, ErrorCode code, const std::vector<std::string>& parts) {
  try {
    f();
    ADD_FAILURE() << "no error thrown; expected one mentioning '" << parts.front() << "'";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), code) << e.what();
    for (const std::string& part : parts) EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
  }
}

// --- composition --------------------------------------------------------------------------------

/// Three robots: a movable three-link arm, a movable Panda and a frozen two-link arm.
std::vector<PlacedRobot> MixedTeam() {
  return {Place("left", ThreeLinkArm(), Pose(0.2, -0.5, 0.1, 0.7, Eigen::Vector3d(1, 2, 3))),
          Place("panda", Panda(), Pose(1.5, 0.3, -0.2, -2.1, Eigen::Vector3d(0.3, -0.2, 1))),
          Place("parked", PlanarArm({1.0, 1.0}), Pose(-1.0, 2.0, 0.0, 1.2), Eigen::Vector2d(0.3, -1.2))};
}

TEST(ComposeRobotsTest, EveryLinkPoseIsTheBasePoseTimesTheRobotsOwn) {
  const std::vector<PlacedRobot> team = MixedTeam();
  const auto composite = ComposeRobots(team);
  ASSERT_EQ(composite->num_dofs(), 3 + 7);
  std::mt19937 rng(7);
  std::vector<Eigen::Isometry3d> poses, chained, own;
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<Eigen::VectorXd> qs;
    for (const PlacedRobot& robot : team) {
      qs.push_back(robot.frozen_at.size() != 0 ? robot.frozen_at : RandomConfiguration(*robot.model, &rng));
    }
    composite->ForwardKinematics(Concat({qs[0], qs[1]}), &poses);
    composite->ForwardKinematicsByChaining(Concat({qs[0], qs[1]}), &chained);
    EXPECT_TRUE(poses[composite->FindLink("world")].isApprox(Eigen::Isometry3d::Identity(), 1e-15));
    for (std::size_t k = 0; k < team.size(); ++k) {
      const RobotModel& model = *team[k].model;
      model.ForwardKinematics(qs[k], &own);
      for (int l = 0; l < model.num_links(); ++l) {
        const int c = composite->FindLink(team[k].name + "/" + model.links()[l].name);
        ASSERT_GE(c, 0) << model.links()[l].name;
        const Eigen::Matrix4d expected = (team[k].base_pose * own[l]).matrix();
        EXPECT_LT((poses[c].matrix() - expected).cwiseAbs().maxCoeff(), 1e-12) << composite->links()[c].name;
        EXPECT_LT((chained[c].matrix() - expected).cwiseAbs().maxCoeff(), 1e-12) << composite->links()[c].name;
      }
    }
  }
}

TEST(ComposeRobotsTest, MimicJointsKeepFollowingTheirJointMovableOrFrozen) {
  // Two dual-arm robots (grippers whose second finger is a <mimic>) after a Panda: the movable
  // one keeps one coordinate per gripper, the frozen one is fixed at its mimic fingers' values.
  const std::string dir = std::string(CHASLES_SOURCE_DIR) + "/examples/robots/";
  const auto dual = RobotModel::FromUrdf(ReadFile(dir + "dual_arm.urdf"), ReadFile(dir + "dual_arm.srdf"));
  ASSERT_EQ(dual->num_dofs(), 13);
  std::mt19937 rng(17);
  Eigen::VectorXd parked_at = RandomConfiguration(*dual, &rng);
  parked_at[6] = 0.035;  // a wide-open gripper: finger b at -0.035
  const std::vector<PlacedRobot> team = {Place("panda", Panda(), Pose(1.5, 0.3, 0.0, 0.4)),
                                         Place("dual", dual, Pose(0.0, -0.5, 0.1, 0.7, Eigen::Vector3d(1, 2, 3))),
                                         Place("parked", dual, Pose(-1.0, 2.0, 0.0, 1.2), parked_at)};
  const auto composite = ComposeRobots(team);
  ASSERT_EQ(composite->num_dofs(), 7 + 13);
  EXPECT_EQ(composite->num_moving_joints(), 7 + 15);
  for (const Joint& joint : composite->joints()) {
    if (!joint.mimic) continue;
    EXPECT_TRUE(StartsWith(joint.name, "dual/")) << joint.name;  // the frozen robot's are fixed
    EXPECT_EQ(composite->joints()[joint.mimic->joint].name, joint.name.substr(0, joint.name.size() - 8) + "_joint")
        << joint.name;  // dual/left_finger_b_joint follows dual/left_finger_joint
  }
  std::vector<Eigen::Isometry3d> poses, chained, own;
  for (int trial = 0; trial < 100; ++trial) {
    const std::vector<Eigen::VectorXd> qs = {RandomConfiguration(*Panda(), &rng), RandomConfiguration(*dual, &rng),
                                             parked_at};
    composite->ForwardKinematics(Concat({qs[0], qs[1]}), &poses);
    composite->ForwardKinematicsByChaining(Concat({qs[0], qs[1]}), &chained);
    for (std::size_t k = 0; k < team.size(); ++k) {
      const RobotModel& model = *team[k].model;
      model.ForwardKinematics(qs[k], &own);
      for (int l = 0; l < model.num_links(); ++l) {
        const int c = composite->FindLink(team[k].name + "/" + model.links()[l].name);
        ASSERT_GE(c, 0);
        const Eigen::Matrix4d expected = (team[k].base_pose * own[l]).matrix();
        EXPECT_LT((poses[c].matrix() - expected).cwiseAbs().maxCoeff(), 1e-12) << composite->links()[c].name;
        EXPECT_LT((chained[c].matrix() - expected).cwiseAbs().maxCoeff(), 1e-12) << composite->links()[c].name;
      }
    }
  }
}

TEST(ComposeRobotsTest, DofsAreTheMovableRobotsInOrderWithTheirLimits) {
  const std::vector<PlacedRobot> team = MixedTeam();
  const auto composite = ComposeRobots(team);
  EXPECT_EQ(composite->name(), "team");
  EXPECT_EQ(composite->kind(), RobotKind::kArm);
  EXPECT_EQ(composite->links()[composite->root_link()].name, "world");
  EXPECT_TRUE(composite->links()[composite->root_link()].collision.empty());
  EXPECT_EQ(composite->num_links(), 1 + 4 + Panda()->num_links() + 3);

  std::vector<std::string> names;
  Eigen::VectorXd lower(10), upper(10), velocity(10), effort(10);
  lower << team[0].model->lower_limits(), Panda()->lower_limits();
  upper << team[0].model->upper_limits(), Panda()->upper_limits();
  velocity << team[0].model->velocity_limits(), Panda()->velocity_limits();
  effort << team[0].model->effort_limits(), Panda()->effort_limits();
  for (const std::string& n : team[0].model->dof_names()) names.push_back("left/" + n);
  for (const std::string& n : Panda()->dof_names()) names.push_back("panda/" + n);
  EXPECT_EQ(composite->dof_names(), names);
  EXPECT_EQ(composite->dof_names().front(), "left/joint1");
  EXPECT_EQ(composite->dof_names()[3], "panda/panda_joint1");
  EXPECT_EQ(composite->lower_limits(), lower);
  EXPECT_EQ(composite->upper_limits(), upper);
  EXPECT_EQ(composite->velocity_limits(), velocity);
  EXPECT_EQ(composite->effort_limits(), effort);

  // The frozen robot's joints are fixed; every robot hangs from "world" by "<name>/base".
  for (const char* name : {"parked/joint1", "parked/joint2", "left/base", "panda/base", "parked/base"}) {
    const auto& joints = composite->joints();
    const auto it = std::find_if(joints.begin(), joints.end(), [&](const Joint& j) { return j.name == name; });
    ASSERT_NE(it, joints.end()) << name;
    EXPECT_EQ(it->type, JointType::kFixed) << name;
  }

  // Geometry and inertia come along.
  for (const PlacedRobot& robot : team) {
    for (const Link& link : robot.model->links()) {
      const Link& copy = composite->links()[composite->FindLink(robot.name + "/" + link.name)];
      EXPECT_EQ(copy.collision.size(), link.collision.size()) << copy.name;
      ASSERT_EQ(copy.inertial.has_value(), link.inertial.has_value()) << copy.name;
      if (link.inertial) {
        EXPECT_EQ(copy.inertial->mass, link.inertial->mass);
        EXPECT_EQ(copy.inertial->com, link.inertial->com);
        EXPECT_EQ(copy.inertial->inertia, link.inertial->inertia);
      }
    }
  }

  EXPECT_EQ(CompositeOffsets(team), (std::vector<int>{0, 3, 10, 10}));
  std::vector<PlacedRobot> reordered{team[2], team[1], team[0]};
  EXPECT_EQ(CompositeOffsets(reordered), (std::vector<int>{0, 0, 7, 10}));
  EXPECT_EQ(ComposeRobots(reordered)->dof_names()[0], "panda/panda_joint1");
}

TEST(ComposeRobotsTest, RobotsAreCheckedAgainstEachOther) {
  // Two three-link arms (reach 2.3 m) 1.5 m apart, facing each other: q1 = 0 points at the other.
  const auto composite = ComposeRobots({Place("left", ThreeLinkArm()), Place("right", ThreeLinkArm(), Pose(1.5, 0, 0, kPi))});
  const CollisionChecker checker(composite, std::make_shared<Scene>());
  EXPECT_TRUE(checker.uses_fast_path());

  const CollisionResult overlap = checker.Check(Eigen::VectorXd::Zero(6));
  ASSERT_TRUE(overlap.in_collision);
  EXPECT_TRUE(overlap.self_collision);
  const bool left_first = StartsWith(overlap.link_a, "left/");
  EXPECT_TRUE(StartsWith(left_first ? overlap.other : overlap.link_a, "right/")) << overlap.link_a << " " << overlap.other;
  EXPECT_TRUE(StartsWith(left_first ? overlap.link_a : overlap.other, "left/")) << overlap.link_a << " " << overlap.other;

  // Both pointing away from the other (left towards +y, right towards −y in the world).
  Eigen::VectorXd apart(6);
  apart << kPi / 2, 0, 0, kPi / 2, 0, 0;
  EXPECT_TRUE(checker.IsValid(apart));
  EXPECT_FALSE(checker.Check(apart).in_collision);
  // Only the left arm reaching across: its tip passes the right arm's base at 1.5 m, clear of
  // the right arm's first sphere (0.25 m along −y) by 0.09 m.
  apart[0] = 0.0;
  EXPECT_TRUE(checker.IsValid(apart));
  // Right arm turned towards the left one's link: contact again.
  apart[3] = 0.6;
  EXPECT_FALSE(checker.IsValid(apart));
}

TEST(ComposeRobotsTest, SelfCollisionsFollowEachRobotsOwnMatrix) {
  const auto arm = ThreeLinkArm();
  const CollisionChecker alone(arm, std::make_shared<Scene>());
  const Eigen::Vector3d folded(0.0, kPi, 0.0);  // link3 over link1
  const CollisionResult own = alone.Check(folded);
  ASSERT_TRUE(own.self_collision);
  EXPECT_EQ(own.link_a == "link1" ? own.other : own.link_a, "link3");

  const std::vector<PlacedRobot> team{Place("left", arm), Place("right", arm, Pose(1.5, 0, 0, kPi))};
  CompositionOptions pairs_only;
  pairs_only.self_collisions = false;
  const CollisionChecker with_self(ComposeRobots(team), std::make_shared<Scene>());
  const CollisionChecker without_self(ComposeRobots(team, pairs_only), std::make_shared<Scene>());
  EXPECT_TRUE(without_self.uses_fast_path());
  Eigen::VectorXd q(6);
  q << folded, kPi / 2, 0, 0;
  const CollisionResult contact = with_self.Check(q);
  ASSERT_TRUE(contact.in_collision);
  EXPECT_TRUE((contact.link_a == "left/link1" && contact.other == "left/link3") ||
              (contact.link_a == "left/link3" && contact.other == "left/link1"))
      << contact.link_a << " " << contact.other;
  EXPECT_TRUE(without_self.IsValid(q));
  // Every pair within one robot is allowed without self checks; no pair across robots ever is.
  const RobotModel& composite = without_self.robot();
  EXPECT_TRUE(composite.allowed_collisions().IsAllowed(composite.FindLink("left/link1"), composite.FindLink("left/link3")));
  EXPECT_FALSE(with_self.robot().allowed_collisions().IsAllowed(with_self.robot().FindLink("left/link1"),
                                                                with_self.robot().FindLink("left/link3")));
  for (const auto* model : {&composite, &with_self.robot()}) {
    for (int a = 0; a < model->num_links(); ++a) {
      for (int b = 0; b < model->num_links(); ++b) {
        if (a == b) continue;
        const std::string& na = model->links()[a].name;
        const std::string& nb = model->links()[b].name;
        if (na == "world" || nb == "world") {
          EXPECT_TRUE(model->allowed_collisions().IsAllowed(a, b));
        } else if (StartsWith(na, "left/") != StartsWith(nb, "left/")) {
          EXPECT_FALSE(model->allowed_collisions().IsAllowed(a, b)) << na << " " << nb;
        }
      }
    }
  }

  // Far apart (10 m, out of reach), the composite is valid exactly when both robots are.
  std::mt19937 rng(11);
  for (const auto& model : {arm, Panda()}) {
    const CollisionChecker single(model, std::make_shared<Scene>());
    const CollisionChecker pair(ComposeRobots({Place("a", model), Place("b", model, Pose(10, 0, 0, 0.3))}),
                                std::make_shared<Scene>());
    int valid = 0, invalid = 0;
    for (int trial = 0; trial < 300; ++trial) {
      const Eigen::VectorXd a = RandomConfiguration(*model, &rng);
      const Eigen::VectorXd b = RandomConfiguration(*model, &rng);
      const bool expected = single.IsValid(a) && single.IsValid(b);
      ASSERT_EQ(pair.IsValid(Concat({a, b})), expected) << model->name() << " trial " << trial;
      (expected ? valid : invalid) += 1;
    }
    EXPECT_GT(valid, 0) << model->name();
    EXPECT_GT(invalid, 0) << model->name();
  }
}

TEST(ComposeRobotsTest, FrozenRobotIsAStaticObstacleAtItsConfiguration) {
  const auto arm = ThreeLinkArm();
  const Eigen::Isometry3d facing = Pose(1.5, 0, 0, kPi);
  // Frozen pointing at the left arm's base: the left arm stretched towards it collides.
  const auto towards = ComposeRobots({Place("left", arm), Place("right", arm, facing, Eigen::Vector3d::Zero())});
  ASSERT_EQ(towards->num_dofs(), 3);
  EXPECT_EQ(towards->dof_names(), (std::vector<std::string>{"left/joint1", "left/joint2", "left/joint3"}));
  const CollisionChecker blocked(towards, std::make_shared<Scene>());
  const CollisionResult contact = blocked.Check(Eigen::Vector3d::Zero());
  ASSERT_TRUE(contact.in_collision);
  EXPECT_TRUE(StartsWith(contact.link_a, "right/") || StartsWith(contact.other, "right/"));
  EXPECT_TRUE(blocked.IsValid(Eigen::Vector3d(kPi / 2, 0, 0)));
  // Frozen pointing away (world −y): the same reach is clear.
  const auto away = ComposeRobots({Place("left", arm), Place("right", arm, facing, Eigen::Vector3d(kPi / 2, 0, 0))});
  EXPECT_TRUE(CollisionChecker(away, std::make_shared<Scene>()).IsValid(Eigen::Vector3d::Zero()));
}

std::shared_ptr<const RobotModel> Car(RobotKind kind, double turning_radius = 2.0) {
  MobileDescription d;
  d.name = "car";
  d.kind = kind;
  d.workspace_min = Eigen::Vector3d(-10, -10, 0);
  d.workspace_max = Eigen::Vector3d(10, 10, 1);
  d.turning_radius = turning_radius;
  d.body.collision = {Shape::Sphere(0.5)};
  return RobotFromMobile(d);
}

TEST(ComposeRobotsTest, MotionModelIsTheMovableRobotsOrAnArm) {
  const auto car = Car(RobotKind::kDubinsCar, 2.5);
  const auto arm = ThreeLinkArm();
  const Eigen::Vector3d parked(3, 3, 0);
  // One movable car among frozen robots keeps its kind and turning radius.
  const auto one = ComposeRobots({Place("arm", arm, Eigen::Isometry3d::Identity(), Eigen::Vector3d(0.1, 0, 0)),
                                  Place("car1", car), Place("car2", car, Eigen::Isometry3d::Identity(), parked)});
  EXPECT_EQ(one->kind(), RobotKind::kDubinsCar);
  EXPECT_EQ(one->motion().turning_radius, 2.5);
  EXPECT_EQ(one->num_dofs(), 3);
  EXPECT_EQ(ComposeRobots({Place("planar", Car(RobotKind::kPlanar)), Place("arm", arm, Pose(5, 0, 0), Eigen::Vector3d::Zero())})->kind(),
            RobotKind::kPlanar);
  // Several movable: an arm, unless one is a car.
  EXPECT_EQ(ComposeRobots({Place("a", arm), Place("b", Car(RobotKind::kPlanar), Pose(5, 0, 0))})->kind(), RobotKind::kArm);
  ExpectError([&] { ComposeRobots({Place("car1", car), Place("car2", car, Pose(5, 0, 0))}); },
              ErrorCode::kFailedPrecondition, {"car1", "dubins_car"});
  ExpectError([&] { ComposeRobots({Place("arm", arm), Place("rs", Car(RobotKind::kReedsSheppCar), Pose(5, 0, 0))}); },
              ErrorCode::kFailedPrecondition, {"robots[1] 'rs'", "reeds_shepp_car"});
  // All frozen: no configuration at all.
  const auto none = ComposeRobots({Place("car1", car, Eigen::Isometry3d::Identity(), parked)});
  EXPECT_EQ(none->num_dofs(), 0);
  EXPECT_EQ(none->kind(), RobotKind::kArm);
}

TEST(ComposeRobotsTest, NamedErrors) {
  const auto arm = ThreeLinkArm();
  ExpectError([] { ComposeRobots({}); }, ErrorCode::kInvalidArgument, {"robots is empty"});
  ExpectError([&] { ComposeRobots({Place("a", arm), Place("", arm)}); }, ErrorCode::kInvalidArgument, {"robots[1].name is empty"});
  ExpectError([&] { ComposeRobots({Place("a", arm), Place("b", arm), Place("a", arm)}); }, ErrorCode::kInvalidArgument,
              {"robots[2].name = 'a'", "robots[0]", "unique"});
  ExpectError([&] { ComposeRobots({Place("a", arm), Place("b", nullptr)}); }, ErrorCode::kInvalidArgument,
              {"robots[1] 'b'", "model is null"});
  ExpectError([&] { ComposeRobots({Place("a", arm, Eigen::Isometry3d::Identity(), Eigen::Vector2d(0, 0))}); },
              ErrorCode::kInvalidArgument, {"robots[0] 'a' frozen_at has 2 values", "3 joints"});
  ExpectError([&] { ComposeRobots({Place("a", arm, Eigen::Isometry3d::Identity(), Eigen::Vector3d(0, 4, 0))}); },
              ErrorCode::kInvalidArgument, {"robots[0] 'a' frozen_at[1] = 4", "joint2"});
  ExpectError([&] { ComposeRobots({Place("a", arm), Place("b", arm, Pose(std::nan(""), 0, 0))}); },
              ErrorCode::kInvalidArgument, {"robots[1] 'b'", "base_pose must be finite"});
  Eigen::Isometry3d skewed = Eigen::Isometry3d::Identity();
  skewed.linear()(0, 1) = 0.5;
  ExpectError([&] { ComposeRobots({Place("a", arm, skewed)}); }, ErrorCode::kInvalidArgument,
              {"robots[0] 'a'", "base_pose rotation"});
  ExpectError([&] { CompositeOffsets({Place("a", nullptr)}); }, ErrorCode::kInvalidArgument, {"model is null"});
}

// --- trajectories side by side ----------------------------------------------------------------

/// Random polynomial pieces (coefficients in [−1, 1]) over `duration`, split at random times;
/// `zero_piece` inserts a piece of zero duration in the middle. The end position is off the
/// last polynomial by 1e-3, so holding it after the end is told apart from extrapolating.
TimedTrajectory RandomTrajectory(int dofs, int degree, double duration, int pieces, bool zero_piece, std::mt19937* rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<double> cuts{0.0, duration};
  for (int k = 1; k < pieces; ++k) cuts.push_back(std::uniform_real_distribution<double>(0.0, duration)(*rng));
  std::sort(cuts.begin(), cuts.end());
  if (zero_piece) {
    const double middle = cuts[cuts.size() / 2];
    cuts.insert(cuts.begin() + static_cast<long>(cuts.size() / 2), middle);
  }
  std::vector<TimedTrajectory::Piece> out;
  for (std::size_t k = 0; k + 1 < cuts.size(); ++k) {
    TimedTrajectory::Piece piece;
    piece.t0 = cuts[k];
    piece.duration = cuts[k + 1] - cuts[k];
    piece.coefficients = Eigen::MatrixXd::NullaryExpr(dofs, degree + 1, [&] { return unit(*rng); });
    out.push_back(piece);
  }
  Eigen::VectorXd end = out.back().State(out.back().duration).q + Eigen::VectorXd::Constant(dofs, 1e-3);
  return TimedTrajectory(std::move(out), end);
}

TEST(ComposeTrajectoriesTest, EachRobotsRowsEvaluateAsItsOwnTrajectory) {
  std::mt19937 rng(3);
  const std::vector<TimedTrajectory> parts{
      RandomTrajectory(2, 2, 2.0, 5, true, &rng), RandomTrajectory(3, 3, 3.7, 4, false, &rng),
      RandomTrajectory(1, 5, 1.1, 3, false, &rng), HoldTrajectory(Eigen::Vector2d(0.5, -0.25), 0.0)};
  const TimedTrajectory team = ComposeTrajectories(parts);
  ASSERT_EQ(team.num_dofs(), 8);
  EXPECT_EQ(team.degree(), 5);
  EXPECT_EQ(team.duration(), parts[1].duration());
  // Boundaries: the union of every part's piece starts and ends (the zero-duration piece and
  // the parts' common start add none).
  std::vector<double> expected;
  for (const TimedTrajectory& part : parts) {
    for (const auto& piece : part.pieces()) expected.push_back(piece.t0);
    expected.push_back(part.duration());
  }
  std::sort(expected.begin(), expected.end());
  expected.erase(std::unique(expected.begin(), expected.end(), [](double a, double b) { return b - a < 1e-12; }),
                 expected.end());
  ASSERT_EQ(expected.size(), 1u + (4 + 3 + 2) + 3);  // 0, the interior cuts, the ends 1.1, 2 and 3.7
  ASSERT_EQ(team.pieces().size() + 1, expected.size());
  for (std::size_t j = 0; j < team.pieces().size(); ++j) {
    EXPECT_NEAR(team.pieces()[j].t0, expected[j], 1e-12);
    EXPECT_GT(team.pieces()[j].duration, 0.0);
  }

  std::uniform_real_distribution<double> when(0.0, 4.5);
  std::vector<double> times{0.0, 1.1, 2.0, 3.7, 10.0};
  for (int k = 0; k < 1000; ++k) times.push_back(when(rng));
  for (double t : times) {
    const TrajectorySample all = team.Evaluate(t);
    int row = 0;
    for (std::size_t k = 0; k < parts.size(); ++k) {
      const TrajectorySample own = parts[k].Evaluate(t);
      const int n = parts[k].num_dofs();
      EXPECT_LT((all.q.segment(row, n) - own.q).cwiseAbs().maxCoeff(), 1e-12) << "robot " << k << " t = " << t;
      if (t < parts[k].duration()) {
        EXPECT_LT((all.qd.segment(row, n) - own.qd).cwiseAbs().maxCoeff(), 1e-12) << "robot " << k << " t = " << t;
        EXPECT_LT((all.qdd.segment(row, n) - own.qdd).cwiseAbs().maxCoeff(), 1e-12) << "robot " << k << " t = " << t;
      } else if (t > parts[k].duration() && t < team.duration()) {  // holding: at rest
        EXPECT_EQ(all.qd.segment(row, n), Eigen::VectorXd::Zero(n)) << "robot " << k << " t = " << t;
      }
      row += n;
    }
  }
  // The end: every robot's end position, exactly.
  EXPECT_EQ(team.Evaluate(team.duration()).q,
            Concat({parts[0].Evaluate(9).q, parts[1].Evaluate(9).q, parts[2].Evaluate(9).q, parts[3].Evaluate(9).q}));
}

TEST(ComposeTrajectoriesTest, NearlyEqualBoundariesMerge) {
  TimedTrajectory a = ConcatenateTrajectories({HoldTrajectory(Eigen::VectorXd::Constant(1, 1.0), 1.0),
                                               HoldTrajectory(Eigen::VectorXd::Constant(1, 1.0), 1.0)});
  TimedTrajectory b = ConcatenateTrajectories({HoldTrajectory(Eigen::VectorXd::Constant(1, 2.0), 1.0 + 1e-14),
                                               HoldTrajectory(Eigen::VectorXd::Constant(1, 2.0), 1.0 - 1e-14)});
  const TimedTrajectory team = ComposeTrajectories({a, b});
  ASSERT_EQ(team.pieces().size(), 2u);
  EXPECT_EQ(team.pieces()[1].t0, 1.0);
  EXPECT_EQ(team.Evaluate(1.5).q, Eigen::Vector2d(1.0, 2.0));
  // A single robot's trajectory comes back as it was.
  const TimedTrajectory alone = ComposeTrajectories({a});
  ASSERT_EQ(alone.pieces().size(), a.pieces().size());
  ExpectError([] { ComposeTrajectories({}); }, ErrorCode::kInvalidArgument, {"trajectories is empty"});
  ExpectError([&] { ComposeTrajectories({a, TimedTrajectory()}); }, ErrorCode::kInvalidArgument, {"trajectories[1] is empty"});
}

TEST(ComposeLimitsTest, ConcatenatesVelocityAndAccelerationOnly) {
  KinematicLimits a, b;
  a.max_velocity = Eigen::Vector2d(1, 2);
  a.max_acceleration = Eigen::Vector2d(3, 4);
  b.max_velocity = Eigen::Vector3d(5, 6, 7);
  b.max_acceleration = Eigen::Vector3d(8, 9, 10);
  const KinematicLimits both = ComposeLimits({a, b});
  EXPECT_EQ(both.max_velocity, Concat({a.max_velocity, b.max_velocity}));
  EXPECT_EQ(both.max_acceleration, Concat({a.max_acceleration, b.max_acceleration}));
  EXPECT_EQ(both.max_jerk.size(), 0);
  EXPECT_EQ(both.max_effort.size(), 0);
  ExpectError([] { ComposeLimits({}); }, ErrorCode::kInvalidArgument, {"limits is empty"});
  KinematicLimits jerk = b;
  jerk.max_jerk = Eigen::Vector3d(1, 1, 1);
  ExpectError([&] { ComposeLimits({a, jerk}); }, ErrorCode::kInvalidArgument, {"limits[1].max_jerk"});
  KinematicLimits effort = a;
  effort.max_effort = Eigen::Vector2d(1, 1);
  ExpectError([&] { ComposeLimits({effort, b}); }, ErrorCode::kInvalidArgument, {"limits[0].max_effort"});
  KinematicLimits uneven = a;
  uneven.max_acceleration = Eigen::Vector3d(1, 1, 1);
  ExpectError([&] { ComposeLimits({uneven}); }, ErrorCode::kInvalidArgument, {"limits[0].max_acceleration has 3 values"});
}

// --- joint verification -----------------------------------------------------------------------

/// Two three-link arms 1.5 m apart facing each other, each at rest pointing away (q1 = π/2:
/// left towards +y, right towards −y), reaching stretched towards the other (q1 = 0) and back.
struct Crossing {
  std::shared_ptr<const RobotModel> arm = ThreeLinkArm();
  CollisionChecker team{ComposeRobots({Place("left", arm), Place("right", arm, Pose(1.5, 0, 0, kPi))}),
                        std::make_shared<Scene>()};
  Eigen::VectorXd rest = Eigen::Vector3d(kPi / 2, 0, 0);
  KinematicLimits limits = [] {
    KinematicLimits l;
    l.max_velocity = Eigen::Vector3d::Constant(2.0);
    l.max_acceleration = Eigen::Vector3d::Constant(4.0);
    return l;
  }();
  TimedTrajectory reach = ParameterizeRestToRest({rest, Eigen::VectorXd::Zero(3), rest}, limits);
};

TEST(VerifyTeamTest, RobotsSweepingTheSameRegionTogetherFailAndOneDelayedPasses) {
  const Crossing c;
  TeamVerificationOptions options;
  const TeamVerificationReport together =
      VerifyTeam(c.team, {c.reach, c.reach}, {c.rest, c.rest}, {c.rest, c.rest}, {c.limits, c.limits}, options);
  EXPECT_FALSE(together.ok);
  EXPECT_NE(together.reason.find("left/link"), std::string::npos) << together.reason;
  EXPECT_NE(together.reason.find("right/link"), std::string::npos) << together.reason;
  EXPECT_GT(together.states_checked, 0u);

  const TimedTrajectory later = DelayedTrajectory(c.reach, c.reach.duration());
  const TeamVerificationReport apart =
      VerifyTeam(c.team, {c.reach, later}, {c.rest, c.rest}, {c.rest, c.rest}, {c.limits, c.limits}, options);
  EXPECT_TRUE(apart.ok) << apart.reason;
  EXPECT_EQ(apart.reason, "");
  // Sphere robots: the team's motion is certified along its continuous motion.
  ASSERT_TRUE(c.team.certifies_motion());
  EXPECT_GT(apart.states_checked, 0u);
  // On the FCL path: every 1 ms over the whole team duration at least.
  CollisionOptions fcl;
  fcl.force_fcl = true;
  const CollisionChecker sampled_team(c.team.robot_ptr(), std::make_shared<Scene>(), fcl);
  const TeamVerificationReport sampled =
      VerifyTeam(sampled_team, {c.reach, later}, {c.rest, c.rest}, {c.rest, c.rest}, {c.limits, c.limits}, options);
  EXPECT_TRUE(sampled.ok) << sampled.reason;
  EXPECT_GE(sampled.states_checked, static_cast<std::uint64_t>(later.duration() / options.time_step));
  EXPECT_FALSE(VerifyTeam(sampled_team, {c.reach, c.reach}, {c.rest, c.rest}, {c.rest, c.rest}, {c.limits, c.limits},
                          options).ok);
  EXPECT_NEAR(apart.max_velocity_ratio, 1.0, 1e-9);
  EXPECT_NEAR(apart.max_acceleration_ratio, 1.0, 1e-9);

  // A wrong goal for one robot is reported.
  const TeamVerificationReport wrong_goal = VerifyTeam(c.team, {c.reach, later}, {c.rest, c.rest},
                                                       {c.rest, Eigen::Vector3d(0, 0, 0)}, {c.limits, c.limits}, options);
  EXPECT_FALSE(wrong_goal.ok);
  EXPECT_NE(wrong_goal.reason.find("goal"), std::string::npos) << wrong_goal.reason;
}

TEST(VerifyTeamTest, OneRobotsLimitsAreCheckedExactly) {
  const Crossing c;
  KinematicLimits slow = c.limits;
  slow.max_velocity = Eigen::Vector3d::Constant(1.0);
  const TimedTrajectory later = DelayedTrajectory(c.reach, c.reach.duration());
  const TeamVerificationReport report =
      VerifyTeam(c.team, {c.reach, later}, {c.rest, c.rest}, {c.rest, c.rest}, {c.limits, slow});
  EXPECT_FALSE(report.ok);
  EXPECT_NE(report.reason.find("'right/joint1' velocity"), std::string::npos) << report.reason;
  EXPECT_NEAR(report.max_velocity_ratio, 2.0, 1e-9);
}

TEST(VerifyTeamTest, WaitsAreCheckedAtTheTimeStep) {
  const Crossing c;
  TeamVerificationOptions options;
  options.time_step = 0.01;
  // At discrete states (FCL path): every time step of the 10 s.
  CollisionOptions fcl;
  fcl.force_fcl = true;
  const CollisionChecker sampled_team(c.team.robot_ptr(), std::make_shared<Scene>(), fcl);
  const TeamVerificationReport wait =
      VerifyTeam(sampled_team, {HoldTrajectory(c.rest, 10.0), HoldTrajectory(c.rest, 4.0)}, {c.rest, c.rest},
                 {c.rest, c.rest}, {c.limits, c.limits}, options);
  EXPECT_TRUE(wait.ok) << wait.reason;
  EXPECT_GE(wait.states_checked, 1000u);
  EXPECT_LE(wait.states_checked, 1010u);
  // Certified (sphere path): standing still is one state per piece.
  const TeamVerificationReport certified = VerifyTeam(c.team, {HoldTrajectory(c.rest, 10.0), HoldTrajectory(c.rest, 4.0)},
                                                      {c.rest, c.rest}, {c.rest, c.rest}, {c.limits, c.limits}, options);
  EXPECT_TRUE(certified.ok) << certified.reason;
  EXPECT_LT(certified.states_checked, 10u);

  // A robot standing in the way is hit by the other moving through it while it waits.
  const TimedTrajectory blocking = HoldTrajectory(Eigen::Vector3d(0.6, 0, 0), 10.0);
  const TeamVerificationReport hit = VerifyTeam(c.team, {DelayedTrajectory(c.reach, 5.0), blocking}, {c.rest, blocking.Evaluate(0).q},
                                                {c.rest, blocking.Evaluate(0).q}, {c.limits, c.limits}, options);
  EXPECT_FALSE(hit.ok);
  EXPECT_NE(hit.reason.find("right/link"), std::string::npos) << hit.reason;
}

TEST(VerifyTeamTest, NamedErrors) {
  const Crossing c;
  const std::vector<TimedTrajectory> two{c.reach, c.reach};
  const std::vector<Eigen::VectorXd> rests{c.rest, c.rest};
  const std::vector<KinematicLimits> limits{c.limits, c.limits};
  TeamVerificationOptions zero;
  zero.time_step = 0.0;
  ExpectError([&] { VerifyTeam(c.team, two, rests, rests, limits, zero); }, ErrorCode::kInvalidArgument,
              {"options.time_step = 0"});
  TeamVerificationOptions nan;
  nan.max_joint_step = std::nan("");
  ExpectError([&] { VerifyTeam(c.team, two, rests, rests, limits, nan); }, ErrorCode::kInvalidArgument,
              {"options.max_joint_step"});
  ExpectError([&] { VerifyTeam(c.team, {}, {}, {}, {}); }, ErrorCode::kInvalidArgument, {"trajectories is empty"});
  ExpectError([&] { VerifyTeam(c.team, two, {c.rest}, rests, limits); }, ErrorCode::kInvalidArgument,
              {"starts has 1 entries"});
  ExpectError([&] { VerifyTeam(c.team, two, rests, {c.rest, Eigen::Vector2d(0, 0)}, limits); },
              ErrorCode::kInvalidArgument, {"goals[1] has 2 values"});
  ExpectError([&] { VerifyTeam(c.team, {c.reach}, {c.rest}, {c.rest}, {c.limits}); }, ErrorCode::kInvalidArgument,
              {"3 joints in all", "has 6"});
  const TeamVerificationReport empty = VerifyTeam(c.team, {c.reach, TimedTrajectory()}, rests, rests, limits);
  EXPECT_FALSE(empty.ok);
  EXPECT_NE(empty.reason.find("trajectories[1] is empty"), std::string::npos) << empty.reason;
}

}  // namespace
}  // namespace chasles
