// Shortcut → rest-to-rest parameterisation → verification on the 7-DOF example Panda
// (sphere geometry, self-collision under its SRDF) with a box in front of it: every stage's
// output passes the next stage's checks, seeded random paths.

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "chasles/collision/collision_checker.h"
#include "chasles/optimizers/shortcut.h"
#include "chasles/optimizers/time_parameterization.h"
#include "chasles/optimizers/verification.h"
#include "test_util.h"

namespace chasles {
namespace {

using test::ReadFile;

std::shared_ptr<const CollisionChecker> PandaWithBox() {
  const std::string dir = std::string(CHASLES_SOURCE_DIR) + "/examples/robots/";
  auto robot = RobotModel::FromUrdf(ReadFile(dir + "panda.urdf"), ReadFile(dir + "panda.srdf"));
  auto scene = std::make_shared<Scene>();
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(0.55, 0.0, 0.3);
  scene->AddObject(SceneObject{"box", Shape::Box(Eigen::Vector3d(0.2, 0.6, 0.6), pose)});
  return std::make_shared<CollisionChecker>(robot, scene);
}

/// A random valid configuration within `radius` (max-norm) of `near`, reachable from it by a
/// valid straight motion; falls back to `near` itself when none is found.
Eigen::VectorXd RandomNeighbour(test::Random& rng, const CollisionChecker& checker, const Eigen::VectorXd& near,
                                double radius) {
  const RobotModel& robot = checker.robot();
  for (int tries = 0; tries < 50; ++tries) {
    Eigen::VectorXd q = near + rng.Vector(robot.num_dofs(), -radius, radius);
    q = q.cwiseMax(robot.lower_limits()).cwiseMin(robot.upper_limits());
    if (checker.IsValid(q) && checker.IsMotionValid(near, q, 0.005)) return q;
  }
  return near;
}

TEST(PandaPipeline, ShortcutParameterizeVerifyAgreeOnRandomPaths) {
  const auto checker = PandaWithBox();
  const RobotModel& robot = checker->robot();
  ASSERT_EQ(robot.num_dofs(), 7);
  test::Random rng(test::TestSeed() + 3);
  KinematicLimits limits;
  limits.max_velocity = robot.velocity_limits();
  limits.max_acceleration = 2.0 * robot.velocity_limits();

  Eigen::VectorXd home(7);
  home << 0.0, -0.6, 0.0, -2.2, 0.0, 1.6, 0.8;
  ASSERT_TRUE(checker->IsValid(home)) << checker->Check(home).link_a << " / " << checker->Check(home).other;

  const int cases = std::max(1, test::TestCases(1000) / 50);
  for (int c = 0; c < cases; ++c) {
    SCOPED_TRACE("case " + std::to_string(c));
    // A wandering valid path with a repeated waypoint and a reversal.
    JointPath path{home};
    for (int k = 0; k < 6; ++k) path.push_back(RandomNeighbour(rng, *checker, path.back(), 0.5));
    path.push_back(path.back());
    path.push_back(path[path.size() - 3]);
    for (int k = 0; k < 3; ++k) path.push_back(RandomNeighbour(rng, *checker, path.back(), 0.5));

    ASSERT_GT(PathLength(path), 1.0) << "the random path hardly moves";

    ShortcutOptions options;
    options.seed = static_cast<std::uint64_t>(c) + 1;
    const JointPath shortened = ShortcutPath(path, *checker, options);
    EXPECT_TRUE(test::BitEqual(shortened.front(), path.front()));
    EXPECT_TRUE(test::BitEqual(shortened.back(), path.back()));
    EXPECT_LE(PathLength(shortened), PathLength(path));

    for (const JointPath* p : std::vector<const JointPath*>{&path, &shortened}) {
      const TimedTrajectory traj = ParameterizeRestToRest(*p, limits);
      const VerificationReport report = VerifyTrajectory(traj, p->front(), p->back(), *checker, limits);
      EXPECT_TRUE(report.ok) << report.reason;
      EXPECT_LE(report.max_velocity_ratio, 1.0 + 1e-9);
      EXPECT_LE(report.max_acceleration_ratio, 1.0 + 1e-9);
      const auto samples = traj.Sample(0.01);
      EXPECT_TRUE(test::BitEqual(samples.front().q, p->front()));
      EXPECT_TRUE(test::BitEqual(samples.back().q, p->back()));
    }
    // Slower limits than the trajectory was timed for: verification must notice.
    const TimedTrajectory traj = ParameterizeRestToRest(shortened, limits);
    if (traj.duration() > 0.0) {
      KinematicLimits slower = limits;
      slower.max_velocity *= 0.9;
      slower.max_acceleration *= 0.9;
      const VerificationReport report = VerifyTrajectory(traj, path.front(), path.back(), *checker, slower);
      EXPECT_FALSE(report.ok);
      EXPECT_NE(report.reason.find("exceeds limit"), std::string::npos) << report.reason;
    }
  }
}

}  // namespace
}  // namespace chasles
