// Car-like robots through OMPL's Dubins / Reeds–Shepp spaces: the returned chords follow curves
// of the car (heading along the chord, curvature within 1 / turning radius, forwards only for a
// Dubins car), every chord is collision-free, the path ends at the goal, and planners whose
// assumptions a Dubins car breaks refuse it.

#include <cmath>

#include <gtest/gtest.h>

#include "chasles/collision/collision_checker.h"
#include "chasles/planners/registry.h"
#include "chasles/robot/error.h"
#include "chasles/robot/mobile.h"

namespace chasles {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kRadius = 0.8;

double Wrap(double x) { return std::remainder(x, 2 * kPi); }

std::shared_ptr<const CollisionChecker> CarInYard(RobotKind kind) {
  MobileDescription car;
  car.name = "car";
  car.kind = kind;
  car.workspace_min = Eigen::Vector3d(0, 0, 0);
  car.workspace_max = Eigen::Vector3d(10, 10, 0);
  car.turning_radius = kRadius;
  for (double x : {-0.1, 0.25, 0.6}) {
    Eigen::Isometry3d at = Eigen::Isometry3d::Identity();
    at.translation() = Eigen::Vector3d(x, 0, 0.25);
    car.body.collision.push_back(Shape::Sphere(0.22, at));
  }
  auto scene = std::make_shared<Scene>();
  Eigen::Isometry3d wall = Eigen::Isometry3d::Identity();
  wall.translation() = Eigen::Vector3d(5, 4, 0.5);
  scene->AddObject({"wall", Shape::Box(Eigen::Vector3d(0.4, 8, 1), wall)});
  return std::make_shared<const CollisionChecker>(RobotFromMobile(car), scene);
}

PlanningProblem Problem(const std::shared_ptr<const CollisionChecker>& checker) {
  PlanningProblem p;
  p.checker = checker;
  p.start = Eigen::Vector3d(2, 2, kPi / 2);
  p.goal = Eigen::Vector3d(8, 2, -kPi / 2);  // behind the wall, facing back down
  p.goal_tolerance = 1e-3;
  p.seed = 3;
  return p;
}

class CarPlannerTest : public ::testing::TestWithParam<std::tuple<RobotKind, std::string>> {
 protected:
  static void SetUpTestSuite() {
    registry_ = new PlannerRegistry();
    RegisterDefaultPlanners(registry_);
  }
  static void TearDownTestSuite() { delete registry_; }
  static PlannerRegistry* registry_;
};
PlannerRegistry* CarPlannerTest::registry_ = nullptr;

TEST_P(CarPlannerTest, ChordsFollowTheCarsCurvesAndAvoidTheWall) {
  const auto& [kind, id] = GetParam();
  const auto checker = CarInYard(kind);
  PlanningProblem problem = Problem(checker);
  if (registry_->Spec(id).optimizing) problem.parameters["max_iterations"] = 400;
  auto planner = registry_->Create(id);
  planner->Setup(problem);
  const PlannerResult r = planner->Solve(Termination::After(std::chrono::seconds(20)));
  ASSERT_EQ(r.status, PlanStatus::kExactSolution) << r.message;
  EXPECT_TRUE(r.keep_path_shape);
  ASSERT_GE(r.path.size(), 3u);
  EXPECT_EQ(r.path.front(), problem.start);
  const Eigen::VectorXd& end = r.path.back();
  EXPECT_EQ(end[0], problem.goal[0]);
  EXPECT_EQ(end[1], problem.goal[1]);
  EXPECT_NEAR(Wrap(end[2] - problem.goal[2]), 0.0, 1e-9);
  bool reversed = false;
  for (size_t i = 0; i + 1 < r.path.size(); ++i) {
    const Eigen::VectorXd& a = r.path[i];
    const Eigen::VectorXd& b = r.path[i + 1];
    ASSERT_TRUE(checker->IsMotionValid(a, b, 0.001)) << "chord " << i;
    const Eigen::Vector2d d = (b - a).head<2>();
    const double chord = d.norm();
    const double turn = std::abs(b[2] - a[2]);
    // A chord of an arc of radius >= kRadius turning by `turn`: length >= 2 ρ sin(turn / 2).
    ASSERT_GE(chord, 2 * kRadius * std::sin(turn / 2) * (1 - 1e-9)) << "chord " << i << " turns too sharply";
    ASSERT_LT(turn, kPi / 2) << "chord " << i;
    // The chord of an arc points along the mean heading (forwards) or against it (backwards).
    const double mid = 0.5 * (a[2] + b[2]);
    const Eigen::Vector2d heading(std::cos(mid), std::sin(mid));
    const double along = d.dot(heading);
    const double across = heading.x() * d.y() - heading.y() * d.x();
    ASSERT_LE(std::abs(across), 1e-6 * std::max(1.0, chord)) << "chord " << i << " slides sideways";
    reversed |= along < -1e-9;
  }
  if (kind == RobotKind::kDubinsCar) {
    EXPECT_FALSE(reversed) << "a Dubins car drove backwards";
  }
}

INSTANTIATE_TEST_SUITE_P(
    Cars, CarPlannerTest,
    ::testing::Values(std::make_tuple(RobotKind::kDubinsCar, "rrt_connect"), std::make_tuple(RobotKind::kDubinsCar, "rrt"),
                      std::make_tuple(RobotKind::kDubinsCar, "rrt_star"),
                      std::make_tuple(RobotKind::kDubinsCar, "informed_rrt_star"),
                      std::make_tuple(RobotKind::kReedsSheppCar, "rrt_connect"),
                      std::make_tuple(RobotKind::kReedsSheppCar, "prm"),
                      std::make_tuple(RobotKind::kReedsSheppCar, "lazy_prm_star"),
                      std::make_tuple(RobotKind::kReedsSheppCar, "bit_star")),
    [](const auto& info) {
      return std::string(ToString(std::get<0>(info.param))) + "_" + std::get<1>(info.param);
    });

TEST(CarPlannerRefusalTest, RoadmapPlannersRefuseADubinsCar) {
  PlannerRegistry registry;
  RegisterDefaultPlanners(&registry);
  const auto checker = CarInYard(RobotKind::kDubinsCar);
  for (const std::string id : {"prm", "prm_star", "lazy_prm_star", "bit_star"}) {
    auto planner = registry.Create(id);
    try {
      planner->Setup(Problem(checker));
      ADD_FAILURE() << id << " accepted a Dubins car";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kFailedPrecondition);
      EXPECT_EQ(std::string(e.what()),
                "planner '" + id + "' does not plan for dubins_car robots (robot 'car'): its roadmap joins states "
                "in both directions, but a Dubins car's curve from a to b is not the reverse of its curve from b to a");
    }
  }
}

TEST(CarPlannerRefusalTest, SeededCarRunsRepeat) {
  PlannerRegistry registry;
  RegisterDefaultPlanners(&registry);
  const auto checker = CarInYard(RobotKind::kReedsSheppCar);
  JointPath first;
  for (int run = 0; run < 2; ++run) {
    auto planner = registry.Create("rrt_connect");
    planner->Setup(Problem(checker));
    const PlannerResult r = planner->Solve(Termination::After(std::chrono::seconds(20)));
    ASSERT_EQ(r.status, PlanStatus::kExactSolution) << r.message;
    if (run == 0) {
      first = r.path;
    } else {
      ASSERT_EQ(r.path.size(), first.size());
      for (size_t i = 0; i < first.size(); ++i) EXPECT_EQ(r.path[i], first[i]) << "waypoint " << i;
    }
  }
}

}  // namespace
}  // namespace chasles
