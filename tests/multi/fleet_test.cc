// Fleet lattice and schedule (multi/fleet_lattice.h, multi/fleet.h). The lattice is held to a
// brute-force check written here (exact point– and segment–box distances in the plane), and
// every schedule to an independent certificate written here too, sharing nothing with fleet.cc:
// each trajectory's pieces evaluated at 1 ms, a bound on how far a robot can move between
// samples, a spatial hash per sample for robot pairs and one for the scene's boxes, and the
// velocity and acceleration limits checked exactly on every polynomial piece.

#include <algorithm>
#include <cmath>
#include <functional>
#include <iostream>
#include <limits>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "chasles/collision/scene.h"
#include "chasles/multi/fleet.h"
#include "chasles/multi/fleet_lattice.h"
#include "chasles/multi/fleet_session.h"
#include "chasles/multi/grid_mapf.h"
#include "chasles/robot/error.h"
#include "chasles/robot/mobile.h"

namespace chasles {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = 3.14159265358979323846;

// ---------------------------------------------------------------------------------------------
// Obstacles: upright boxes (turned about z only), measured exactly in the plane.

struct UprightBox {
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  double yaw = 0.0;
  Eigen::Vector2d half = Eigen::Vector2d::Zero();  // half extents in the box frame
  double z_lo = 0.0, z_hi = 0.0;
};

Eigen::Vector2d ToBoxFrame(const UprightBox& box, const Eigen::Vector2d& p) {
  const Eigen::Vector2d d = p - box.centre;
  const double c = std::cos(box.yaw), s = std::sin(box.yaw);
  return Eigen::Vector2d(c * d.x() + s * d.y(), -s * d.x() + c * d.y());
}

double PointBoxDistance(const UprightBox& box, const Eigen::Vector2d& p) {
  const Eigen::Vector2d q = ToBoxFrame(box, p);
  return std::hypot(std::max(std::abs(q.x()) - box.half.x(), 0.0), std::max(std::abs(q.y()) - box.half.y(), 0.0));
}

double PointSegmentDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (a + t * ab - p).norm();
}

double SegmentBoxDistance(const UprightBox& box, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d p = ToBoxFrame(box, a), q = ToBoxFrame(box, b);
  // Liang–Barsky: does the segment meet the rectangle?
  double lo = 0.0, hi = 1.0;
  bool meets = true;
  for (int i = 0; i < 2 && meets; ++i) {
    const double d = q[i] - p[i];
    for (const double sign : {-1.0, 1.0}) {
      const double num = box.half[i] - sign * p[i], den = sign * d;
      if (den == 0.0) {
        if (num < 0.0) meets = false;
      } else if (den > 0.0) {
        hi = std::min(hi, num / den);
      } else {
        lo = std::max(lo, num / den);
      }
    }
  }
  if (meets && lo <= hi) return 0.0;
  double best = std::min(PointBoxDistance(box, a), PointBoxDistance(box, b));
  for (const double sx : {-1.0, 1.0}) {
    for (const double sy : {-1.0, 1.0}) {
      best = std::min(best, PointSegmentDistance(Eigen::Vector2d(sx * box.half.x(), sy * box.half.y()), p, q));
    }
  }
  return best;
}

void AddBox(Scene* scene, std::vector<UprightBox>* boxes, const UprightBox& box) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::AngleAxisd(box.yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  pose.translation() = Eigen::Vector3d(box.centre.x(), box.centre.y(), 0.5 * (box.z_lo + box.z_hi));
  scene->AddObject({"box" + std::to_string(boxes->size()),
                    Shape::Box(Eigen::Vector3d(2 * box.half.x(), 2 * box.half.y(), box.z_hi - box.z_lo), pose)});
  boxes->push_back(box);
}

UprightBox Box(double x, double y, double hx, double hy, double yaw = 0.0, double z_lo = 0.0, double z_hi = 1.0) {
  UprightBox box;
  box.centre = Eigen::Vector2d(x, y);
  box.half = Eigen::Vector2d(hx, hy);
  box.yaw = yaw;
  box.z_lo = z_lo;
  box.z_hi = z_hi;
  return box;
}

// ---------------------------------------------------------------------------------------------
// The independent certificate.

struct Body {
  double radius = 0.3;
  Eigen::Vector3d max_velocity = Eigen::Vector3d::Ones(), max_acceleration = Eigen::Vector3d::Ones();
  Eigen::Vector3d start = Eigen::Vector3d::Zero(), goal = Eigen::Vector3d::Zero();
};

struct Certificate {
  bool ok = true;
  std::string failure;
  double min_pair_gap = kInf;      // min over samples of |p_i − p_j| − (R_i + R_j + padding)
  double min_obstacle_gap = kInf;  // min over samples of distance to a box − R_i
  long samples = 0;
  void Fail(const std::string& why) {
    if (ok) failure = why;
    ok = false;
  }
};

/// Value, first and second derivative of one coordinate's polynomial at local time tau.
void EvalPoly(const Eigen::MatrixXd& c, int row, double tau, double* x, double* v, double* a) {
  const int top = static_cast<int>(c.cols()) - 1;
  *x = *v = *a = 0.0;
  for (int k = top; k >= 0; --k) *x = *x * tau + c(row, k);
  for (int k = top; k >= 1; --k) *v = *v * tau + k * c(row, k);
  for (int k = top; k >= 2; --k) *a = *a * tau + k * (k - 1) * c(row, k);
}

/// Limits on every piece exactly (pieces of degree <= 3: velocity extrema at the ends or at the
/// vertex of its parabola, acceleration linear), continuity between pieces, and the ends.
void CheckLimitsAndEnds(const TimedTrajectory& trajectory, const Body& body, int robot, Certificate* out) {
  const auto& pieces = trajectory.pieces();
  const std::string who = "robot " + std::to_string(robot);
  if (pieces.empty()) return out->Fail(who + ": empty trajectory");
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    const auto& piece = pieces[k];
    if (piece.degree() > 3) return out->Fail(who + ": piece of degree > 3");
    for (int i = 0; i < 3; ++i) {
      std::vector<double> taus = {0.0, piece.duration};
      if (piece.degree() == 3 && piece.coefficients(i, 3) != 0.0) {
        const double vertex = -piece.coefficients(i, 2) / (3.0 * piece.coefficients(i, 3));
        if (vertex > 0.0 && vertex < piece.duration) taus.push_back(vertex);
      }
      for (const double tau : taus) {
        double x, v, a;
        EvalPoly(piece.coefficients, i, tau, &x, &v, &a);
        if (std::abs(v) > body.max_velocity[i] * (1 + 1e-9) + 1e-12) {
          out->Fail(who + ": |velocity[" + std::to_string(i) + "]| = " + std::to_string(std::abs(v)) + " at t = " +
                    std::to_string(piece.t0 + tau));
        }
        if (std::abs(a) > body.max_acceleration[i] * (1 + 1e-9) + 1e-12) {
          out->Fail(who + ": |acceleration[" + std::to_string(i) + "]| = " + std::to_string(std::abs(a)) +
                    " at t = " + std::to_string(piece.t0 + tau));
        }
      }
    }
    if (k > 0) {
      const auto& prev = pieces[k - 1];
      if (std::abs(prev.t0 + prev.duration - piece.t0) > 1e-9) out->Fail(who + ": pieces not consecutive in time");
      for (int i = 0; i < 3; ++i) {
        double x0, v0, a0, x1, v1, a1;
        EvalPoly(prev.coefficients, i, prev.duration, &x0, &v0, &a0);
        EvalPoly(piece.coefficients, i, 0.0, &x1, &v1, &a1);
        if (std::abs(x0 - x1) > 1e-9 || std::abs(v0 - v1) > 1e-9) {
          out->Fail(who + ": discontinuous at t = " + std::to_string(piece.t0));
        }
      }
    }
  }
  double x, v, a;
  for (int i = 0; i < 3; ++i) {
    EvalPoly(pieces.front().coefficients, i, 0.0, &x, &v, &a);
    if (x != body.start[i] || v != 0.0) out->Fail(who + ": does not start at rest at its start");
    EvalPoly(pieces.back().coefficients, i, pieces.back().duration, &x, &v, &a);
    if (std::abs(x - body.goal[i]) > 1e-9 || std::abs(v) > 1e-9) out->Fail(who + ": does not end at rest at its goal");
  }
  if (trajectory.Evaluate(trajectory.duration()).q != body.goal) out->Fail(who + ": end position is not the goal");
}

/// Samples every trajectory at `dt`. Between samples a robot with planar speed |v_k| at sample k
/// and acceleration at most A (the planar norm of its per-coordinate limits, which
/// CheckLimitsAndEnds proves it respects) is within δ = |v_k|·dt/2 + A·dt²/8 of where it is at
/// the nearest sample, so a pair is certified apart over the half-intervals about sample k when
/// |p_i − p_j| − δ_i − δ_j >= R_i + R_j + padding, and a robot clear of a box when its distance
/// to it minus δ_i >= R_i. Robots that have ended hold their end position.
Certificate CertifyFleet(const std::vector<TimedTrajectory>& trajectories, const std::vector<Body>& bodies,
                         double padding, const std::vector<UprightBox>& boxes, double z_lo, double z_hi,
                         const Eigen::Vector2d& lower, const Eigen::Vector2d& upper, double dt = 1e-3) {
  Certificate out;
  const int n = static_cast<int>(trajectories.size());
  double horizon = 0.0, reach = 0.0;
  for (int i = 0; i < n; ++i) {
    CheckLimitsAndEnds(trajectories[i], bodies[i], i, &out);
    horizon = std::max(horizon, trajectories[i].duration());
    reach = std::max(reach, bodies[i].radius + bodies[i].max_velocity.head<2>().norm() * dt);
  }
  // Spatial hash: cells of side h >= the largest distance that can matter, so pairs and boxes
  // that matter are in the 3 x 3 cells about a robot's.
  const double h = 2.0 * reach + padding + 0.01;
  const Eigen::Vector2d base = lower - Eigen::Vector2d::Constant(2 * h);
  const int gx = static_cast<int>((upper.x() - lower.x()) / h) + 5, gy = static_cast<int>((upper.y() - lower.y()) / h) + 5;
  const auto cell_of = [&](const Eigen::Vector2d& p) {
    const int cx = std::clamp(static_cast<int>(std::floor((p.x() - base.x()) / h)), 0, gx - 1);
    const int cy = std::clamp(static_cast<int>(std::floor((p.y() - base.y()) / h)), 0, gy - 1);
    return cy * gx + cx;
  };
  std::vector<std::vector<int>> box_cells(gx * gy);
  for (std::size_t b = 0; b < boxes.size(); ++b) {
    if (boxes[b].z_hi < z_lo || boxes[b].z_lo > z_hi) continue;  // above or below every body
    const double r = boxes[b].half.norm() + reach;
    const int x0 = cell_of(boxes[b].centre - Eigen::Vector2d::Constant(r)) % gx;
    const int y0 = cell_of(boxes[b].centre - Eigen::Vector2d::Constant(r)) / gx;
    const int x1 = cell_of(boxes[b].centre + Eigen::Vector2d::Constant(r)) % gx;
    const int y1 = cell_of(boxes[b].centre + Eigen::Vector2d::Constant(r)) / gx;
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) box_cells[y * gx + x].push_back(static_cast<int>(b));
    }
  }
  std::vector<std::size_t> cursor(n, 0);
  std::vector<Eigen::Vector2d> p(n);
  std::vector<double> delta(n);
  std::vector<int> head(gx * gy, -1), next(n, -1), stamp(gx * gy, -1);
  const long count = static_cast<long>(std::ceil(horizon / dt)) + 1;
  for (long k = 0; k < count && out.ok; ++k) {
    const double t = std::min(k * dt, horizon);
    for (int i = 0; i < n; ++i) {
      const auto& pieces = trajectories[i].pieces();
      while (cursor[i] + 1 < pieces.size() && pieces[cursor[i]].t0 + pieces[cursor[i]].duration <= t) ++cursor[i];
      const auto& piece = pieces[cursor[i]];
      const double tau = std::clamp(t - piece.t0, 0.0, piece.duration);
      Eigen::Vector3d q, v, a;
      for (int c = 0; c < 3; ++c) EvalPoly(piece.coefficients, c, tau, &q[c], &v[c], &a[c]);
      if (t > piece.t0 + piece.duration) v.setZero();  // ended: holding
      p[i] = q.head<2>();
      delta[i] = v.head<2>().norm() * dt / 2 + bodies[i].max_acceleration.head<2>().norm() * dt * dt / 8;
      if ((p[i].array() < lower.array() - 1e-9).any() || (p[i].array() > upper.array() + 1e-9).any()) {
        out.Fail("robot " + std::to_string(i) + " leaves the bounds at t = " + std::to_string(t));
      }
      if (std::abs(q.z()) > kPi + 1e-9) out.Fail("robot " + std::to_string(i) + " heading beyond ±π");
    }
    for (int i = 0; i < n; ++i) {
      const int c = cell_of(p[i]);
      const int cx = c % gx, cy = c / gx;
      for (int y = std::max(0, cy - 1); y <= std::min(gy - 1, cy + 1); ++y) {
        for (int x = std::max(0, cx - 1); x <= std::min(gx - 1, cx + 1); ++x) {
          const int cell = y * gx + x;
          if (stamp[cell] == k) {
            for (int j = head[cell]; j >= 0; j = next[j]) {
              const double gap = (p[i] - p[j]).norm() - bodies[i].radius - bodies[j].radius - padding;
              out.min_pair_gap = std::min(out.min_pair_gap, gap);
              if (gap < delta[i] + delta[j]) {
                std::ostringstream why;
                why << "robots " << j << " and " << i << " at t = " << t << " are " << (p[i] - p[j]).norm()
                    << " m apart, need " << bodies[i].radius + bodies[j].radius + padding << " + " << delta[i] + delta[j];
                out.Fail(why.str());
              }
            }
          }
        }
      }
      // Boxes were entered in every cell within their reach: the robot's own cell lists them.
      for (const int b : box_cells[c]) {
        const double gap = PointBoxDistance(boxes[b], p[i]) - bodies[i].radius;
        out.min_obstacle_gap = std::min(out.min_obstacle_gap, gap);
        if (gap < delta[i]) {
          std::ostringstream why;
          why << "robot " << i << " at t = " << t << " is " << gap + bodies[i].radius << " m from box " << b;
          out.Fail(why.str());
        }
      }
      if (stamp[c] != k) {
        stamp[c] = static_cast<int>(k);
        head[c] = -1;
      }
      next[i] = head[c];
      head[c] = i;
    }
    ++out.samples;
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// Helpers to set problems up.

std::vector<TimedTrajectory> Trajectories(const FleetSchedule& schedule) {
  std::vector<TimedTrajectory> out;
  for (const auto& robot : schedule.robots) out.push_back(robot.trajectory);
  return out;
}

LatticeGeometry OpenLattice(int width, int height, double spacing) {
  LatticeGeometry lattice;
  lattice.width = width;
  lattice.height = height;
  lattice.spacing = spacing;
  return lattice;
}

/// Robots at the nodes of paths[i].front() / .back(), headings as given, the same limits.
FleetScheduleRequest PlanRequest(const LatticeGeometry& lattice, const std::vector<std::vector<GridCell>>& paths,
                                 const std::vector<double>& start_heading = {},
                                 const std::vector<double>& goal_heading = {}) {
  FleetScheduleRequest request;
  request.lattice = lattice;
  request.paths = paths;
  for (std::size_t i = 0; i < paths.size(); ++i) {
    FleetRobot robot;
    robot.start.head<2>() = lattice.origin + lattice.spacing * Eigen::Vector2d(paths[i].front() % lattice.width,
                                                                               paths[i].front() / lattice.width);
    robot.goal.head<2>() = lattice.origin + lattice.spacing * Eigen::Vector2d(paths[i].back() % lattice.width,
                                                                             paths[i].back() / lattice.width);
    robot.start.z() = i < start_heading.size() ? start_heading[i] : 0.0;
    robot.goal.z() = i < goal_heading.size() ? goal_heading[i] : robot.start.z();
    request.robots.push_back(robot);
  }
  return request;
}

std::vector<Body> Bodies(const FleetScheduleRequest& request, double radius) {
  std::vector<Body> bodies;
  for (const FleetRobot& robot : request.robots) {
    Body body;
    body.radius = radius;
    body.max_velocity = robot.max_velocity;
    body.max_acceleration = robot.max_acceleration;
    body.start = robot.start;
    body.goal = robot.goal;
    bodies.push_back(body);
  }
  return bodies;
}

Certificate CertifyOpen(const FleetScheduleRequest& request, const FleetSchedule& schedule, double radius,
                        double padding) {
  const LatticeGeometry& l = request.lattice;
  const Eigen::Vector2d upper = l.origin + l.spacing * Eigen::Vector2d(l.width - 1, l.height - 1);
  return CertifyFleet(Trajectories(schedule), Bodies(request, radius), padding, {}, 0.0, 1.0, l.origin, upper);
}

bool HasDependency(const FleetSchedule& schedule, int robot, int step, int waits_for_robot, int waits_for_step) {
  for (const auto& d : schedule.dependencies) {
    if (d.robot == robot && d.step == step && d.waits_for_robot == waits_for_robot && d.waits_for_step == waits_for_step) {
      return true;
    }
  }
  return false;
}

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument) << e.what();
    return e.what();
  }
  return "";
}

// ---------------------------------------------------------------------------------------------
// Footprint and resolution.

TEST(FleetFootprint, BoundsEveryShapeAtEveryHeading) {
  MobileDescription mobile;
  mobile.workspace_min = Eigen::Vector3d(-5, -5, 0);
  mobile.workspace_max = Eigen::Vector3d(5, 5, 0);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(0.1, 0.0, 0.15);
  mobile.body.collision.push_back(Shape::Box(Eigen::Vector3d(0.6, 0.4, 0.3), pose));
  Footprint f = PlanarFootprint(*RobotFromMobile(mobile));
  EXPECT_NEAR(f.radius, std::hypot(0.4, 0.2), 1e-12);  // the far corners
  EXPECT_NEAR(f.z_min, 0.0, 1e-12);
  EXPECT_NEAR(f.z_max, 0.3, 1e-12);

  // A mast (upright cylinder) at the back, a lidar ball on top, a lying capsule bumper.
  Eigen::Isometry3d mast = Eigen::Isometry3d::Identity();
  mast.translation() = Eigen::Vector3d(-0.25, 0.0, 0.6);
  mobile.body.collision.push_back(Shape::Cylinder(0.05, 0.6, mast));
  Eigen::Isometry3d lidar = Eigen::Isometry3d::Identity();
  lidar.translation() = Eigen::Vector3d(-0.25, 0.0, 0.95);
  mobile.body.collision.push_back(Shape::Sphere(0.08, lidar));
  Eigen::Isometry3d bumper = Eigen::Isometry3d::Identity();
  bumper.linear() = Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();  // axis along y
  bumper.translation() = Eigen::Vector3d(0.45, 0.0, 0.1);
  mobile.body.collision.push_back(Shape::Capsule(0.05, 0.5, bumper));
  f = PlanarFootprint(*RobotFromMobile(mobile));
  EXPECT_NEAR(f.radius, std::hypot(0.45, 0.25) + 0.05, 1e-12);  // the bumper's ends
  EXPECT_NEAR(f.z_max, 1.03, 1e-12);                             // the lidar's top
  EXPECT_NEAR(f.z_min, 0.0, 1e-12);

  // Brute force: sampled surface points of the box at 64 headings stay inside.
  for (int k = 0; k < 64; ++k) {
    const Eigen::Rotation2Dd turn(2 * kPi * k / 64);
    for (int corner = 0; corner < 8; ++corner) {
      const Eigen::Vector2d p(0.1 + ((corner & 1) ? 0.3 : -0.3), (corner & 2) ? 0.2 : -0.2);
      EXPECT_LE((turn * p).norm(), f.radius + 1e-12);
    }
  }
  const Footprint cover = CoverFootprints({{0.3, 0.0, 0.5}, {0.4, 0.1, 0.3}, {0.2, -0.1, 0.2}});
  EXPECT_EQ(cover.radius, 0.4);
  EXPECT_EQ(cover.z_min, -0.1);
  EXPECT_EQ(cover.z_max, 0.5);
}

TEST(FleetFootprint, BoundsAreTheCommonWorkspace) {
  MobileDescription a;
  a.workspace_min = Eigen::Vector3d(-5, -2, 0);
  a.workspace_max = Eigen::Vector3d(5, 8, 0);
  a.body.collision.push_back(Shape::Sphere(0.2));
  MobileDescription b = a;
  b.workspace_min = Eigen::Vector3d(-1, -4, 0);
  b.workspace_max = Eigen::Vector3d(9, 6, 0);
  const auto [lower, upper] = FleetBounds({RobotFromMobile(a), RobotFromMobile(b)});
  EXPECT_EQ(lower, Eigen::Vector2d(-1, -2));
  EXPECT_EQ(upper, Eigen::Vector2d(5, 6));
  b.workspace_min.x() = 6;
  EXPECT_NE(ErrorOf([&] { FleetBounds({RobotFromMobile(a), RobotFromMobile(b)}); }).find("do not overlap"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { FleetBounds({RobotFromMobile(a), nullptr}); }).find("robots[1] is null"), std::string::npos);
}

TEST(FleetFootprint, RefusesRobotsThatAreNotPlanar) {
  MobileDescription car;
  car.kind = RobotKind::kDubinsCar;
  car.workspace_min = Eigen::Vector3d(-5, -5, 0);
  car.workspace_max = Eigen::Vector3d(5, 5, 0);
  car.body.collision.push_back(Shape::Sphere(0.2));
  const std::string message = ErrorOf([&] { PlanarFootprint(*RobotFromMobile(car)); });
  EXPECT_NE(message.find("planar robot (x, y, theta)"), std::string::npos) << message;
}

TEST(FleetResolution, IsTheLargestPairPlusPadding) {
  EXPECT_DOUBLE_EQ(FleetResolution({0.3, 0.5, 0.4}, 0.1), 1.0);
  EXPECT_DOUBLE_EQ(FleetResolution({0.3, 0.3}, 0.0), 0.6);
  EXPECT_DOUBLE_EQ(FleetResolution({0.5, 0.2, 0.5}, 0.05), 1.05);
  EXPECT_DOUBLE_EQ(FleetResolution({0.25}, 0.1), 0.6);
  EXPECT_NE(ErrorOf([] { FleetResolution({0.3, -1.0}, 0.0); }).find("radii[1] = -1"), std::string::npos);
  EXPECT_NE(ErrorOf([] { FleetResolution({0.3}, -0.1); }).find("padding = -0.1"), std::string::npos);
  EXPECT_NE(ErrorOf([] { FleetResolution({}, 0.0); }).find("radii is empty"), std::string::npos);
}

// ---------------------------------------------------------------------------------------------
// The lattice against brute force.

TEST(FleetLattice, MatchesBruteForceOnRandomBoxes) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Scene scene;
  std::vector<UprightBox> boxes;
  for (int k = 0; k < 250; ++k) {
    UprightBox box = Box(unit(rng) * 20.0, unit(rng) * 12.0, 0.05 + 0.4 * unit(rng), 0.05 + 0.4 * unit(rng),
                         unit(rng) * kPi);
    if (k % 10 == 0) {  // some overhead (above the bodies) and some low ones (under them)
      box.z_lo = k % 20 == 0 ? 1.2 : -0.5;
      box.z_hi = k % 20 == 0 ? 2.0 : -0.05;
    }
    AddBox(&scene, &boxes, box);
  }
  FleetLatticeRequest request;
  request.anchor = Eigen::Vector2d(0.25, 0.25);
  request.spacing = 0.5;
  request.lower = Eigen::Vector2d(0.0, 0.0);
  request.upper = Eigen::Vector2d(20.0, 12.0);
  request.footprint = {0.3, 0.0, 1.0};
  FleetLatticeStats stats;
  const FleetLattice lattice = BuildFleetLattice(scene, request, &stats);
  const LatticeGeometry& g = lattice.geometry();
  ASSERT_EQ(g.width, 40);
  ASSERT_EQ(g.height, 24);
  EXPECT_EQ(g.origin, Eigen::Vector2d(0.25, 0.25));
  EXPECT_EQ(stats.node_checks, 40u * 24u);

  const auto relevant = [&](const UprightBox& b) { return !(b.z_hi < 0.0 || b.z_lo > 1.0); };
  const double band = 1e-6;  // contact within this is left to FCL's tolerance
  int free_nodes = 0, blocked_nodes = 0, free_edges = 0, blocked_edges = 0;
  for (GridCell c = 0; c < g.num_cells(); ++c) {
    const Eigen::Vector2d p = g.Position(c);
    double nearest = kInf;
    for (const UprightBox& b : boxes) {
      if (relevant(b)) nearest = std::min(nearest, PointBoxDistance(b, p));
    }
    if (std::abs(nearest - 0.3) > band) {
      EXPECT_EQ(lattice.node_free(c), nearest > 0.3) << "node " << c << " at " << p.transpose() << ", " << nearest;
    }
    (lattice.node_free(c) ? free_nodes : blocked_nodes)++;
    EXPECT_EQ(lattice.map().blocked[c] != 0, !lattice.node_free(c));
    for (const LatticeDirection d : {LatticeDirection::kEast, LatticeDirection::kNorth}) {
      const GridCell other = g.Neighbour(c, d);
      if (other < 0 || !lattice.node_free(c) || !lattice.node_free(other)) {
        EXPECT_FALSE(lattice.edge_free(c, d));
        continue;
      }
      double swept = kInf;
      for (const UprightBox& b : boxes) {
        if (relevant(b)) swept = std::min(swept, SegmentBoxDistance(b, p, g.Position(other)));
      }
      if (std::abs(swept - 0.3) > band) {
        EXPECT_EQ(lattice.edge_free(c, d), swept > 0.3) << "edge " << c << " -> " << other << ", " << swept;
      }
      EXPECT_EQ(lattice.edge_free(c, d), lattice.edge_free(other, static_cast<LatticeDirection>((static_cast<int>(d) + 2) % 4)));
      (lattice.edge_free(c, d) ? free_edges : blocked_edges)++;
    }
  }
  // The scene is dense enough that every case occurs.
  EXPECT_GT(free_nodes, 100);
  EXPECT_GT(blocked_nodes, 100);
  EXPECT_GT(free_edges, 100);
  EXPECT_GT(blocked_edges, 0);
  EXPECT_EQ(static_cast<int>(lattice.blocked_edges().size()), blocked_edges);
}

TEST(FleetLattice, ReportsEdgesBlockedBetweenFreeNodes) {
  // A thin post midway between two nodes 1 m apart: both discs (r = 0.3) clear it by 0.4 m,
  // the disc swept between them does not.
  Scene scene;
  std::vector<UprightBox> boxes;
  AddBox(&scene, &boxes, Box(1.5, 1.0, 0.05, 0.05));
  FleetLatticeRequest request;
  request.spacing = 1.0;
  request.lower = Eigen::Vector2d(0, 0);
  request.upper = Eigen::Vector2d(3, 2);
  request.footprint = {0.3, 0.0, 0.5};
  const FleetLattice lattice = BuildFleetLattice(scene, request);
  const LatticeGeometry& g = lattice.geometry();
  const GridCell a = g.NodeAt(Eigen::Vector2d(1, 1), "a"), b = g.NodeAt(Eigen::Vector2d(2, 1), "b");
  EXPECT_TRUE(lattice.node_free(a));
  EXPECT_TRUE(lattice.node_free(b));
  EXPECT_FALSE(lattice.edge_free(a, LatticeDirection::kEast));
  EXPECT_FALSE(lattice.edge_free(b, LatticeDirection::kWest));
  EXPECT_TRUE(lattice.edge_free(a, LatticeDirection::kNorth));
  ASSERT_EQ(lattice.blocked_edges().size(), 1u);
  EXPECT_EQ(lattice.blocked_edges()[0].cell, a);
  EXPECT_EQ(lattice.blocked_edges()[0].direction, LatticeDirection::kEast);
  EXPECT_EQ(std::count(lattice.map().blocked.begin(), lattice.map().blocked.end(), 1), 0);
  const GridMap safe = lattice.NodeBlockingMap();
  EXPECT_EQ(std::count(safe.blocked.begin(), safe.blocked.end(), 1), 1);
  EXPECT_TRUE(safe.blocked[a] != 0 || safe.blocked[b] != 0);

  // A plan through the blocked edge is refused when the schedule knows the free space.
  FleetScheduleRequest plan = PlanRequest(g, {{a, b}});
  plan.free_space = &lattice;
  const std::string message = ErrorOf([&] { ScheduleFleet(plan); });
  EXPECT_NE(message.find("paths[0][1] moves along the blocked edge"), std::string::npos) << message;
  plan.free_space = nullptr;
  EXPECT_NO_THROW(ScheduleFleet(plan));
}

TEST(FleetLattice, MeshesOctoMapsAndHeightsCount) {
  // A mesh cube (through FCL's BVH) blocks a node; a box above the bodies' height blocks nothing.
  auto cube = std::make_shared<TriangleMesh>();
  for (int k = 0; k < 8; ++k) cube->vertices.emplace_back((k & 1) ? 0.1 : -0.1, (k & 2) ? 0.1 : -0.1, (k & 4) ? 0.1 : -0.1);
  const int faces[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                            {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  for (const auto& f : faces) cube->triangles.emplace_back(f[0], f[1], f[2]);
  Shape mesh;
  mesh.type = ShapeType::kMesh;
  mesh.mesh = cube;
  mesh.pose.translation() = Eigen::Vector3d(2.0, 1.0, 0.2);
  Scene scene;
  scene.AddObject({"crate", mesh});
  std::vector<UprightBox> boxes;
  AddBox(&scene, &boxes, Box(0.5, 1.0, 1.0, 2.0, 0.0, 0.6, 1.0));  // a shelf above 0.5 m bodies
  FleetLatticeRequest request;
  request.spacing = 1.0;
  request.lower = Eigen::Vector2d(0, 0);
  request.upper = Eigen::Vector2d(3, 2);
  request.footprint = {0.3, 0.0, 0.5};
  const FleetLattice lattice = BuildFleetLattice(scene, request);
  const LatticeGeometry& g = lattice.geometry();
  EXPECT_FALSE(lattice.node_free(g.NodeAt(Eigen::Vector2d(2, 1), "crate")));
  EXPECT_EQ(std::count(lattice.map().blocked.begin(), lattice.map().blocked.end(), 1), 1);
  request.footprint.z_max = 0.7;  // taller bodies reach the shelf
  const FleetLattice tall = BuildFleetLattice(scene, request);
  EXPECT_FALSE(tall.node_free(g.NodeAt(Eigen::Vector2d(0, 0), "under the shelf")));
  EXPECT_TRUE(tall.node_free(g.NodeAt(Eigen::Vector2d(3, 0), "beyond the shelf")));

  // An OctoMap: a few points seen from above near node (3, 2) and between nodes (2, 0) and (3, 0).
  PointCloudInsertion cloud;
  cloud.points = {3.05, 2.0, 0.2, 3.0, 1.95, 0.25, 2.5, 0.0, 0.3};
  cloud.sensor_origin = Eigen::Vector3d(2.5, 1.0, 2.0);
  cloud.resolution = 0.05;
  const FleetLattice mapped = BuildFleetLattice(scene.InsertPointCloud(cloud), request);
  EXPECT_FALSE(mapped.node_free(g.NodeAt(Eigen::Vector2d(3, 2), "seen")));
  EXPECT_TRUE(mapped.node_free(g.NodeAt(Eigen::Vector2d(3, 1), "unseen")));
  const GridCell west = g.NodeAt(Eigen::Vector2d(2, 0), "west");
  EXPECT_TRUE(mapped.node_free(west));
  EXPECT_FALSE(mapped.edge_free(west, LatticeDirection::kEast));
  EXPECT_TRUE(tall.edge_free(west, LatticeDirection::kEast));
}

TEST(FleetLattice, CacheKeysOnSceneIdAndEveryField) {
  Scene scene;
  std::vector<UprightBox> boxes;
  AddBox(&scene, &boxes, Box(1.0, 1.0, 0.2, 0.2));
  FleetLatticeRequest request;
  request.spacing = 1.0;
  request.lower = Eigen::Vector2d(0, 0);
  request.upper = Eigen::Vector2d(3, 2);
  request.footprint = {0.3, 0.0, 0.5};
  FleetLatticeCache cache(2);
  const auto first = cache.GetOrBuild("scene-a", scene, request);
  EXPECT_EQ(cache.GetOrBuild("scene-a", scene, request), first);
  FleetLatticeRequest other = request;
  other.footprint.radius = 0.31;
  EXPECT_NE(FleetLatticeKey("scene-a", request), FleetLatticeKey("scene-a", other));
  EXPECT_NE(FleetLatticeKey("scene-a", request), FleetLatticeKey("scene-b", request));
  const auto second = cache.GetOrBuild("scene-a", scene, other);
  EXPECT_NE(second, first);
  cache.GetOrBuild("scene-b", scene, request);
  EXPECT_EQ(cache.size(), 2u);
  EXPECT_NE(cache.GetOrBuild("scene-a", scene, request), first);  // evicted, rebuilt
}

TEST(FleetLattice, NamesOffLatticePoints) {
  const LatticeGeometry g = OpenLattice(4, 3, 1.0);
  EXPECT_EQ(g.NodeAt(Eigen::Vector2d(2.0 + 5e-7, 1.0), "p"), 6);
  const std::string message = ErrorOf([&] { g.NodeAt(Eigen::Vector2d(1.2, 0.4), "robots[3].start"); });
  EXPECT_NE(message.find("robots[3].start = (1.2, 0.4) is not on a lattice node: the nearest node is cell 1 at (1, 0)"),
            std::string::npos)
      << message;
  EXPECT_NE(ErrorOf([&] { g.NodeAt(Eigen::Vector2d(9, 1), "q"); }).find("nearest node is cell 7 at (3, 1)"),
            std::string::npos);
}

// ---------------------------------------------------------------------------------------------
// Schedules of hand-made plans.

TEST(FleetSchedule, StraightRunAndCornersHaveExactDurations) {
  // v = a = 1, s = 1: three cells in a row are one trapezoid of 3/1 + 1/1 = 4 s; with a corner
  // after two cells, 2 + 1 = 3 s then (1 cell: the triangle and trapezoid agree) 2 s.
  const LatticeGeometry g = OpenLattice(5, 5, 1.0);
  FleetSchedule straight = ScheduleFleet(PlanRequest(g, {{0, 1, 2, 3}}));
  EXPECT_NEAR(straight.robots[0].arrival_time, 4.0, 1e-12);
  EXPECT_EQ(straight.robots[0].runs.size(), 1u);
  FleetScheduleRequest corner = PlanRequest(g, {{0, 1, 1, 2, 7, 7}}, {0.0}, {kPi / 2});
  const FleetSchedule turned = ScheduleFleet(corner);
  const FleetRobotSchedule& robot = turned.robots[0];
  ASSERT_EQ(robot.runs.size(), 2u);
  EXPECT_NEAR(robot.runs[0].end_time, 3.0, 1e-12);  // the plan's wait at cell 1 costs nothing
  EXPECT_NEAR(robot.arrival_time, 5.0, 1e-12);
  // Then a turn of π/2 in place: trapezoid 1.5708 + 1 (ω = α = 1).
  EXPECT_NEAR(robot.finish_time, 5.0 + kPi / 2 + 1.0, 1e-12);
  EXPECT_EQ(robot.wait_time, 0.0);
  // At rest at the corner, θ held during translation.
  const TrajectorySample at_corner = robot.trajectory.Evaluate(3.0);
  EXPECT_NEAR(at_corner.q.x(), 2.0, 1e-12);
  EXPECT_NEAR(at_corner.qd.norm(), 0.0, 1e-12);
  EXPECT_EQ(robot.trajectory.Evaluate(4.2).q.z(), 0.0);
  EXPECT_EQ(robot.trajectory.Evaluate(robot.finish_time).q, corner.robots[0].goal);
  const Certificate certificate = CertifyOpen(corner, turned, 0.3, 0.0);
  EXPECT_TRUE(certificate.ok) << certificate.failure;
}

TEST(FleetSchedule, FollowingChainWaitsForEachArrival) {
  // Three robots in a row move east together (each follows the one ahead): the middle and last
  // robots wait at every step for the one ahead to arrive, so their runs are single moves.
  const LatticeGeometry g = OpenLattice(8, 3, 0.7);
  const FleetScheduleRequest request = PlanRequest(g, {{0, 1, 2, 3}, {1, 2, 3, 4}, {2, 3, 4, 5}});
  const FleetSchedule schedule = ScheduleFleet(request);
  ASSERT_EQ(schedule.dependencies.size(), 6u);
  for (int step = 0; step < 3; ++step) {
    EXPECT_TRUE(HasDependency(schedule, 1, step, 2, step)) << step;
    EXPECT_TRUE(HasDependency(schedule, 0, step, 1, step)) << step;
  }
  const FleetDependency& d = schedule.dependencies.front();
  EXPECT_EQ(d.robot, 0);
  EXPECT_EQ(d.cell, 1);
  EXPECT_DOUBLE_EQ(d.x, 0.7);
  EXPECT_EQ(schedule.robots[2].runs.size(), 1u);
  EXPECT_EQ(schedule.robots[1].runs.size(), 3u);
  EXPECT_EQ(schedule.robots[0].runs.size(), 3u);
  // Robot 1's first move starts when robot 2 reaches cell 3.
  EXPECT_GT(schedule.robots[1].runs[0].start_time, 0.0);
  EXPECT_NEAR(schedule.robots[2].trajectory.Evaluate(schedule.robots[1].runs[0].start_time).q.x(), 2.1, 1e-9);
  EXPECT_GT(schedule.robots[0].wait_time, schedule.robots[1].wait_time);
  EXPECT_EQ(schedule.discrete_makespan, 3);
  // Exactly the spacing apart, 0.7 >= 0.3 + 0.3 + 0.1 − rounding; not more: a 0.1 m padding
  // certified, 0.11 m not.
  EXPECT_TRUE(CertifyOpen(request, schedule, 0.3, 0.098).ok);
  EXPECT_FALSE(CertifyOpen(request, schedule, 0.3, 0.11).ok);
}

TEST(FleetSchedule, CrossingRobotWaitsForTheJunction) {
  // A plus-shaped junction: robot 0 crosses west → east, robot 1 south → north and waits a
  // step in the plan for robot 0 to leave the centre.
  const LatticeGeometry g = OpenLattice(5, 5, 1.0);
  //   cell = 5·y + x; centre 12.
  const std::vector<std::vector<GridCell>> paths = {{10, 11, 12, 13, 14, 14}, {2, 7, 7, 12, 17, 22}};
  const FleetScheduleRequest request = PlanRequest(g, paths);
  const FleetSchedule schedule = ScheduleFleet(request);
  ASSERT_EQ(schedule.dependencies.size(), 1u);
  const FleetDependency& d = schedule.dependencies[0];
  EXPECT_EQ(d.robot, 1);
  EXPECT_EQ(d.step, 2);
  EXPECT_EQ(d.waits_for_robot, 0);
  EXPECT_EQ(d.waits_for_step, 2);
  EXPECT_EQ(d.cell, 12);
  EXPECT_EQ(Eigen::Vector2d(d.x, d.y), Eigen::Vector2d(2, 2));
  // Robot 0 passes the centre in its run; robot 1 starts into it when robot 0 is past (at 13).
  const double go = schedule.robots[1].runs[1].start_time;
  EXPECT_NEAR(schedule.robots[0].trajectory.Evaluate(go).q.x(), 3.0, 1e-9);
  EXPECT_GT(schedule.robots[1].wait_time, 0.0);
  const Certificate certificate = CertifyOpen(request, schedule, 0.3, 0.35);
  EXPECT_TRUE(certificate.ok) << certificate.failure;
}

TEST(FleetSchedule, CorridorWithABayAndLateRobots) {
  // A corridor one node wide between walls, with a bay: robot 0 goes east, robot 1 west; robot
  // 1 steps into the bay (north of cell 3) to let robot 0 pass.
  Scene scene;
  std::vector<UprightBox> boxes;
  const double s = FleetResolution({0.3, 0.3}, 0.1 + 0.002);  // 2 mm for the sampled certificate
  AddBox(&scene, &boxes, Box(3.5 * s, -0.75 * s, 4.5 * s, 0.2 * s));           // south wall
  AddBox(&scene, &boxes, Box(1.0 * s, 0.75 * s, 1.5 * s, 0.2 * s));           // north wall, west part
  AddBox(&scene, &boxes, Box(5.5 * s, 0.75 * s, 2.0 * s, 0.2 * s));           // north wall, east part
  AddBox(&scene, &boxes, Box(2.25 * s, 1.5 * s, 0.2 * s, 0.8 * s));            // bay, west side
  AddBox(&scene, &boxes, Box(3.75 * s, 1.5 * s, 0.2 * s, 0.8 * s));            // bay, east side
  FleetLatticeRequest lattice_request;
  lattice_request.spacing = s;
  lattice_request.lower = Eigen::Vector2d(0, 0);
  lattice_request.upper = Eigen::Vector2d(7 * s, 1 * s);
  lattice_request.footprint = {0.3 + 0.002, 0.0, 0.5};
  const FleetLattice lattice = BuildFleetLattice(scene, lattice_request);
  const LatticeGeometry& g = lattice.geometry();
  ASSERT_EQ(g.width, 8);
  ASSERT_EQ(g.height, 2);
  // Free: the corridor row (0..7) and the bay (11, above cell 3). Nothing else.
  for (GridCell c = 0; c < g.num_cells(); ++c) {
    EXPECT_EQ(lattice.node_free(c), c < 8 || c == 11) << c;
  }
  EXPECT_TRUE(lattice.blocked_edges().empty());
  // Robot 1 ducks into 11 at step 2 and comes back out after robot 0 passed 3.
  const std::vector<std::vector<GridCell>> paths = {{0, 1, 2, 2, 3, 4, 5, 6, 7, 7, 7},
                                                    {6, 5, 4, 3, 11, 11, 11, 3, 2, 1, 0}};
  FleetScheduleRequest request = PlanRequest(g, paths, {0.0, kPi}, {kPi / 2, -kPi / 2});
  request.free_space = &lattice;
  request.robots[1].max_velocity = Eigen::Vector3d(0.5, 0.5, 2.0);
  request.robots[1].max_acceleration = Eigen::Vector3d(0.3, 0.3, 2.0);
  const Eigen::Vector2d upper = g.Position(g.num_cells() - 1);
  for (const double late : {0.0, 4.0, 30.0}) {
    for (int robot = 0; robot < 2; ++robot) {
      FleetScheduleRequest delayed = request;
      delayed.robots[robot].release_time = late;
      const FleetSchedule schedule = ScheduleFleet(delayed);
      // Robot 0 enters cell 3 only after robot 1 has left it for the bay, and robot 1 comes back
      // into 3 only after robot 0 has moved on to 4.
      EXPECT_TRUE(HasDependency(schedule, 0, 3, 1, 3));
      EXPECT_TRUE(HasDependency(schedule, 1, 6, 0, 4));
      EXPECT_GE(schedule.robots[robot].runs.front().start_time, late);
      std::vector<Body> bodies = Bodies(delayed, 0.3);
      const Certificate certificate =
          CertifyFleet(Trajectories(schedule), bodies, 0.1, boxes, 0.0, 0.5, g.origin, upper);
      EXPECT_TRUE(certificate.ok) << "late " << late << " robot " << robot << ": " << certificate.failure;
      EXPECT_GE(certificate.min_obstacle_gap, 0.0);
      if (late == 30.0) {
        // The other robot waits for the late one wherever the plan makes it.
        EXPECT_GT(schedule.robots[1 - robot].wait_time, 20.0) << robot;
      }
    }
  }
}

TEST(FleetSchedule, RefusesBrokenPlansByName) {
  const LatticeGeometry g = OpenLattice(4, 4, 1.0);
  const auto error = [&](const std::vector<std::vector<GridCell>>& paths) {
    return ErrorOf([&] { ScheduleFleet(PlanRequest(g, paths)); });
  };
  EXPECT_NE(error({{0, 1}, {2, 1}}).find("paths[1][1] = 1: robots 0 and 1 are both in that cell at step 1"),
            std::string::npos);
  EXPECT_NE(error({{0, 1}, {1, 0}}).find("robots 0 and 1 swap cells 0 and 1"), std::string::npos);
  EXPECT_NE(error({{0, 2}}).find("paths[0][1] = 2 is not a neighbour of paths[0][0] = 0"), std::string::npos);
  EXPECT_NE(error({{3, 4}}).find("paths[0][1] = 4 is not a neighbour"), std::string::npos);  // no wrap
  EXPECT_NE(error({{0, 1}, {5}}).find("paths[1] has 1 steps"), std::string::npos);
  // Four robots round the square 0-1-5-4 in one step: a rotation cycle.
  const std::string cycle = error({{0, 1}, {1, 5}, {5, 4}, {4, 0}});
  EXPECT_NE(cycle.find("rotation cycle"), std::string::npos) << cycle;
  // Off-lattice start, named with its nearest node.
  FleetScheduleRequest request = PlanRequest(g, {{0, 1}});
  request.robots[0].start.x() = 0.3;
  const std::string start = ErrorOf([&] { ScheduleFleet(request); });
  EXPECT_NE(start.find("robots[0].start = (0.3, 0) is not on a lattice node: the nearest node is cell 0 at (0, 0)"),
            std::string::npos)
      << start;
  request = PlanRequest(g, {{0, 1}});
  request.robots[0].max_acceleration[1] = 0.0;
  EXPECT_NE(ErrorOf([&] { ScheduleFleet(request); }).find("robots[0].max_acceleration[1] = 0 must be > 0"),
            std::string::npos);
  request = PlanRequest(g, {{0, 1}});
  request.robots[0].goal.x() = 2.0;
  EXPECT_NE(ErrorOf([&] { ScheduleFleet(request); }).find("is not robots[0].goal's cell 2"), std::string::npos);
}

// ---------------------------------------------------------------------------------------------
// A fleet: over 100 robots on a 32 x 32 lattice of a cluttered scene, planned by a prioritized
// space-time BFS written here.

/// Prioritized planning on the grid: robots in order, each a BFS over (cell, step) that avoids
/// the earlier robots' cells and swaps, may follow an earlier robot into the cell it leaves
/// but never stands where an earlier robot arrives next step (so only later robots follow
/// earlier ones: no rotation cycles), never enters a later robot's start, and ends at its goal
/// once no earlier robot passes there any more. Robots are planned in `order`; returns -1, or
/// the first robot that finds no path.
int PlanPrioritized(const GridMap& map, const std::vector<GridCell>& starts, const std::vector<GridCell>& goals,
                    const std::vector<int>& order, int horizon, std::vector<std::vector<GridCell>>* paths) {
  const int cells = map.width * map.height, n = static_cast<int>(starts.size());
  std::vector<int> occupant(static_cast<std::size_t>(horizon + 2) * cells, -1);
  std::vector<int> last_busy(cells, -1);
  std::vector<char> start_of_later(cells, 0);
  for (const GridCell s : starts) start_of_later[s] = 1;
  paths->assign(n, {});
  const auto at = [&](int t, GridCell c) -> int& { return occupant[static_cast<std::size_t>(t) * cells + c]; };
  std::vector<int> parent(static_cast<std::size_t>(horizon + 1) * cells);
  for (const int k : order) {
    start_of_later[starts[k]] = 0;
    std::fill(parent.begin(), parent.end(), -2);
    std::vector<GridCell> layer = {starts[k]};
    parent[starts[k]] = -1;
    int found = -1;
    for (int t = 0; t < horizon && found < 0; ++t) {
      std::vector<GridCell> next;
      for (const GridCell c : layer) {
        if (c == goals[k] && last_busy[c] < t) {
          found = t;
          break;
        }
        const int x = c % map.width, y = c / map.width;
        const GridCell options[5] = {c, x + 1 < map.width ? c + 1 : -1, x > 0 ? c - 1 : -1,
                                     y + 1 < map.height ? c + map.width : -1, y > 0 ? c - map.width : -1};
        for (const GridCell d : options) {
          if (d < 0 || map.blocked[d] != 0 || start_of_later[d] != 0) continue;
          if (at(t + 1, d) >= 0 || at(t + 2, d) >= 0) continue;  // taken, or an earlier robot arrives next
          const int other = at(t, d);
          if (d != c && other >= 0 && at(t + 1, c) == other) continue;  // swap
          std::size_t slot = static_cast<std::size_t>(t + 1) * cells + d;
          if (parent[slot] != -2) continue;
          parent[slot] = c;
          next.push_back(d);
        }
      }
      if (found < 0) layer = std::move(next);
    }
    if (found < 0) return k;
    std::vector<GridCell> path(found + 1);
    GridCell c = goals[k];
    for (int t = found; t >= 0; --t) {
      path[t] = c;
      c = parent[static_cast<std::size_t>(t) * cells + c];
    }
    for (int t = 0; t <= horizon + 1; ++t) at(t, t <= found ? path[t] : goals[k]) = k;
    for (int t = 0; t <= found; ++t) last_busy[path[t]] = std::max(last_busy[path[t]], t);
    last_busy[goals[k]] = horizon + 1;
    (*paths)[k] = std::move(path);
  }
  std::size_t length = 0;
  for (const auto& path : *paths) length = std::max(length, path.size());
  for (int k = 0; k < n; ++k) (*paths)[k].resize(length, goals[k]);
  return -1;
}

TEST(FleetSchedule, HundredRobotsOnAClutteredLattice) {
  std::mt19937_64 rng(2024);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int robots = 110;
  // Two kinds of bodies: a box base (R = hypot(0.2, 0.15) = 0.25) and a round one (R = 0.3).
  MobileDescription small;
  small.workspace_min = Eigen::Vector3d(0, 0, 0);
  small.workspace_max = Eigen::Vector3d(100, 100, 0);
  small.body.collision.push_back(Shape::Box(Eigen::Vector3d(0.4, 0.3, 0.4), Eigen::Isometry3d(Eigen::Translation3d(0, 0, 0.2))));
  MobileDescription round = small;
  round.body.collision = {Shape::Cylinder(0.3, 0.5, Eigen::Isometry3d(Eigen::Translation3d(0, 0, 0.25)))};
  const Footprint small_print = PlanarFootprint(*RobotFromMobile(small));
  const Footprint round_print = PlanarFootprint(*RobotFromMobile(round));
  ASSERT_NEAR(small_print.radius, 0.25, 1e-12);
  ASSERT_NEAR(round_print.radius, 0.3, 1e-12);
  std::vector<double> radii;
  for (int i = 0; i < robots; ++i) radii.push_back(i % 3 == 0 ? 0.3 : 0.25);
  const double padding = 0.05, margin = 0.002;  // the sampled certificate needs a little room
  const double s = FleetResolution(radii, padding + margin);
  EXPECT_NEAR(s, 0.652, 1e-12);

  // 32 x 32 nodes; small rotated crates on ~12% of the nodes, a long wall with gaps, and a
  // mezzanine above the bodies that must block nothing.
  Scene scene;
  std::vector<UprightBox> boxes;
  for (int k = 0; k < 120; ++k) {
    const int ix = static_cast<int>(unit(rng) * 32), iy = static_cast<int>(unit(rng) * 32);
    AddBox(&scene, &boxes, Box(ix * s, iy * s, 0.15, 0.1, unit(rng) * kPi));
  }
  for (int ix = 0; ix < 32; ++ix) {
    if (ix % 8 != 3) AddBox(&scene, &boxes, Box(ix * s, 16 * s, 0.5 * s, 0.05));
  }
  AddBox(&scene, &boxes, Box(10 * s, 10 * s, 6 * s, 6 * s, 0.0, 0.7, 0.8));
  FleetLatticeRequest lattice_request;
  lattice_request.spacing = s;
  lattice_request.lower = Eigen::Vector2d(0, 0);
  lattice_request.upper = Eigen::Vector2d(31 * s, 31 * s) + Eigen::Vector2d::Constant(1e-12);
  lattice_request.footprint = CoverFootprints({small_print, round_print});
  lattice_request.footprint.radius += margin;
  const FleetLattice lattice = BuildFleetLattice(scene, lattice_request);
  const LatticeGeometry& g = lattice.geometry();
  ASSERT_EQ(g.width, 32);
  ASSERT_EQ(g.height, 32);
  const GridMap map = lattice.NodeBlockingMap();

  // Distinct random starts and goals on free nodes; prioritized planning, a failing robot moved
  // to the front.
  // Starts and goals are distinct cells (prioritized planning cannot park on a later robot's
  // start) away from the wall's rows (a parked robot would close a gap).
  std::vector<GridCell> free_cells;
  for (GridCell c = 0; c < g.num_cells(); ++c) {
    if (map.blocked[c] == 0 && std::abs(c / g.width - 16) > 1) free_cells.push_back(c);
  }
  ASSERT_GT(free_cells.size(), 3u * robots);
  std::shuffle(free_cells.begin(), free_cells.end(), rng);
  const std::vector<GridCell> starts(free_cells.begin(), free_cells.begin() + robots);
  const std::vector<GridCell> goals(free_cells.begin() + robots, free_cells.begin() + 2 * robots);
  std::vector<std::vector<GridCell>> paths;
  std::vector<int> order(robots);
  for (int i = 0; i < robots; ++i) order[i] = i;
  int attempts = 0;
  for (int failed = 0; attempts < 30; ++attempts) {
    failed = PlanPrioritized(map, starts, goals, order, 400, &paths);
    if (failed < 0) break;
    order.erase(std::find(order.begin(), order.end(), failed));  // plan the stuck robot first
    order.insert(order.begin(), failed);
  }
  ASSERT_LT(attempts, 30) << "the test's prioritized planner found no plan";

  FleetScheduleRequest request;
  request.lattice = g;
  request.paths = paths;
  request.free_space = &lattice;
  std::vector<Body> bodies;
  for (int i = 0; i < robots; ++i) {
    FleetRobot robot;
    robot.start << g.Position(starts[i]), (unit(rng) - 0.5) * 2 * kPi;
    robot.goal << g.Position(goals[i]), (unit(rng) - 0.5) * 2 * kPi;
    robot.max_velocity = Eigen::Vector3d(0.6 + 0.6 * unit(rng), 0.6 + 0.6 * unit(rng), 1.5);
    robot.max_acceleration = Eigen::Vector3d(0.4 + 0.8 * unit(rng), 0.4 + 0.8 * unit(rng), 2.0);
    request.robots.push_back(robot);
    Body body;
    body.radius = radii[i];
    body.max_velocity = robot.max_velocity;
    body.max_acceleration = robot.max_acceleration;
    body.start = robot.start;
    body.goal = robot.goal;
    bodies.push_back(body);
  }
  const FleetSchedule schedule = ScheduleFleet(request);
  EXPECT_GT(schedule.dependencies.size(), 50u);
  const auto following = std::count_if(schedule.dependencies.begin(), schedule.dependencies.end(),
                                       [](const FleetDependency& d) { return d.step == d.waits_for_step; });
  EXPECT_GT(following, 0);  // the plan has robots following others within a step
  const Certificate certificate = CertifyFleet(Trajectories(schedule), bodies, padding, boxes, 0.0, 0.5, g.origin,
                                               g.Position(g.num_cells() - 1));
  EXPECT_TRUE(certificate.ok) << certificate.failure;
  EXPECT_GE(certificate.min_pair_gap, margin - 1e-9);
  EXPECT_GE(certificate.min_obstacle_gap, margin - 1e-6);  // FCL's contact tolerance
  // The continuous makespan against the discrete one times the slowest robot's one-cell move.
  double step_time = 0.0;
  for (const FleetRobot& robot : request.robots) {
    for (int i = 0; i < 2; ++i) {
      const double v = robot.max_velocity[i], a = robot.max_acceleration[i];
      step_time = std::max(step_time, s * a >= v * v ? s / v + v / a : 2 * std::sqrt(s / a));
    }
  }
  std::cout << "[ fleet    ] " << robots << " robots (planned after " << attempts << " reorderings), "
            << paths[0].size() << " steps, " << following << " followings, discrete makespan "
            << schedule.discrete_makespan << " x " << step_time << " s = " << schedule.discrete_makespan * step_time
            << " s; continuous makespan " << schedule.makespan << " s, " << schedule.dependencies.size()
            << " dependencies, " << certificate.samples << " samples; min gaps " << certificate.min_pair_gap
            << " m (pairs), " << certificate.min_obstacle_gap << " m (boxes)\n";
  RecordProperty("continuous_makespan", std::to_string(schedule.makespan));
  RecordProperty("discrete_makespan_times_step", std::to_string(schedule.discrete_makespan * step_time));

  // The same plan with one robot released late still certifies.
  FleetScheduleRequest late = request;
  late.robots[robots / 2].release_time = 12.5;
  const FleetSchedule delayed = ScheduleFleet(late);
  const Certificate late_certificate = CertifyFleet(Trajectories(delayed), bodies, padding, boxes, 0.0, 0.5, g.origin,
                                                    g.Position(g.num_cells() - 1));
  EXPECT_TRUE(late_certificate.ok) << late_certificate.failure;
}

// ---------------------------------------------------------------------------------------------
// Lifelong operation (multi/fleet_session.h): goals keep coming, one robot at a time.

/// What each robot actually executes: its plan from each plan's start until the next plan of it
/// starts, as one trajectory from t = 0.
class Executed {
 public:
  explicit Executed(const FleetSession& session) {
    for (int i = 0; i < session.num_robots(); ++i) Record(session, i);
  }
  void Record(const FleetSession& session, int robot) {
    const FleetSessionPlan& plan = session.plan(robot);
    segments_.resize(static_cast<std::size_t>(session.num_robots()));
    segments_[static_cast<std::size_t>(robot)].push_back({plan.start_time, plan.trajectory});
  }
  /// Robot's executed trajectory; *handover_gap the largest jump in position or velocity where
  /// one plan hands over to the next.
  TimedTrajectory Of(int robot, double* handover_gap) const {
    const auto& segments = segments_[static_cast<std::size_t>(robot)];
    std::vector<TimedTrajectory::Piece> pieces;
    for (std::size_t k = 0; k < segments.size(); ++k) {
      const double from = segments[k].first;
      const double until = k + 1 < segments.size() ? segments[k + 1].first : kInf;
      if (k + 1 < segments.size()) {
        const TrajectorySample old_end = segments[k].second.Evaluate(until - from);
        const TrajectorySample next = segments[k + 1].second.Evaluate(0.0);
        *handover_gap = std::max({*handover_gap, (old_end.q - next.q).norm(), old_end.qd.norm(), next.qd.norm()});
      }
      for (TimedTrajectory::Piece piece : segments[k].second.pieces()) {
        piece.t0 += from;
        if (piece.t0 >= until) break;
        piece.duration = std::min(piece.duration, until - piece.t0);
        if (piece.duration <= 0.0 && !pieces.empty()) continue;
        if (!pieces.empty()) {
          // A hold before the plan starts (the robot stood until `from`).
          const auto& last = pieces.back();
          if (piece.t0 > last.t0 + last.duration + 1e-12) {
            Eigen::VectorXd at = Eigen::VectorXd::Zero(3);
            for (int i = 0; i < 3; ++i) {
              double x, v, a;
              EvalPoly(last.coefficients, i, last.duration, &x, &v, &a);
              at[i] = x;
            }
            pieces.push_back(LinePiece(last.t0 + last.duration, piece.t0 - last.t0 - last.duration, at,
                                       Eigen::VectorXd::Zero(3), 0.0, 0.0, 0.0));
          }
        }
        pieces.push_back(piece);
      }
    }
    return TimedTrajectory(std::move(pieces), segments.back().second.Evaluate(kInf).q);
  }

 private:
  std::vector<std::vector<std::pair<double, TimedTrajectory>>> segments_;
};

/// The free cells of `map` as upright boxes (one per blocked cell) in a scene, and the lattice
/// built from it with footprint `radius`.
std::shared_ptr<const FleetLattice> SceneLattice(const GridMap& map, double s, double radius, Scene* scene,
                                                 std::vector<UprightBox>* boxes) {
  for (int y = 0; y < map.height; ++y) {
    for (int x = 0; x < map.width; ++x) {
      if (map.blocked[static_cast<std::size_t>(y * map.width + x)]) AddBox(scene, boxes, Box(x * s, y * s, 0.5 * s, 0.5 * s));
    }
  }
  FleetLatticeRequest request;
  request.spacing = s;
  request.lower = Eigen::Vector2d(0, 0);
  request.upper = Eigen::Vector2d((map.width - 1) * s, (map.height - 1) * s) + Eigen::Vector2d::Constant(1e-12);
  request.footprint = {radius, 0.0, 0.5};
  return std::make_shared<const FleetLattice>(BuildFleetLattice(*scene, request));
}

/// 100 robots in a warehouse of shelf rows; 400 goals, each to the robot that is idle first (and
/// every fourth to a robot still on its way, which finishes its run and turns to the new goal);
/// with `report_late`, after every third goal a robot on its way reports being late. Every
/// executed trajectory is then certified independently at 1 ms: pairs, shelves, limits.
void RunWarehouseSession(bool report_late) {
  const GridMap map = WarehouseGridMap(60, 30, 8, 2, 8);
  const double s = 1.0, radius = 0.3, padding = 0.3;
  Scene scene;
  std::vector<UprightBox> boxes;
  const std::shared_ptr<const FleetLattice> lattice = SceneLattice(map, s, radius, &scene, &boxes);
  std::vector<GridCell> starts, goals;
  const int n = 100;
  RandomScenario(map, n, 11, &starts, &goals);
  std::vector<FleetSessionRobot> robots(n);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int i = 0; i < n; ++i) {
    robots[i].pose << lattice->geometry().Position(starts[i]).x(), lattice->geometry().Position(starts[i]).y(),
        unit(rng) * kPi;
    if (i % 4 == 0) robots[i].max_velocity = Eigen::Vector3d(0.6, 0.6, 1.0);
  }
  FleetSession session(lattice, robots, 0.0);
  Executed executed(session);
  std::vector<GridCell> free_cells;
  for (GridCell c = 0; c < lattice->geometry().num_cells(); ++c) {
    if (lattice->node_free(c)) free_cells.push_back(c);
  }
  std::mt19937_64 late_rng(7);
  int solved = 0, moved_aside = 0, orders = 0, deferred = 0, reported_late = 0, delayed = 0;
  double now = 0.0, slowest = 0.0;
  const int goals_total = 400;
  for (int k = 0; k < goals_total; ++k) {
    int robot = 0;
    if (k % 4 == 3) {
      robot = static_cast<int>(unit(rng) * n);
    } else {
      for (int i = 1; i < n; ++i) {
        if (session.plan(i).finish_time < session.plan(robot).finish_time) robot = i;
      }
      now = std::max(now, session.plan(robot).finish_time);
    }
    now += 0.05;
    // A free node no other robot is bound for (as a dispatcher assigns; a goal where another
    // robot is going to park is a named failure, tested below).
    GridCell cell = -1;
    while (cell < 0) {
      cell = free_cells[static_cast<std::size_t>(unit(rng) * free_cells.size())];
      for (int i = 0; i < n && cell >= 0; ++i) {
        const Eigen::Vector2d end = session.plan(i).trajectory.Evaluate(kInf).q.head<2>();
        if (i != robot && end == lattice->geometry().Position(cell)) cell = -1;
      }
    }
    const Eigen::Vector2d xy = lattice->geometry().Position(cell);
    const FleetGoalOutcome outcome = session.Assign(robot, Eigen::Vector3d(xy.x(), xy.y(), unit(rng) * kPi), now);
    slowest = std::max(slowest, outcome.seconds);
    if (outcome.code != FleetGoalCode::kSuccess) {
      // A robot bound for a node on every way there: as a dispatcher would, retry once every
      // robot is idle (then any robot in the way steps aside).
      ASSERT_NE(outcome.message.find("is going to park at"), std::string::npos) << outcome.message;
      EXPECT_TRUE(outcome.robots.empty());
      ++deferred;
      for (int i = 0; i < n; ++i) now = std::max(now, session.plan(i).finish_time);
      const FleetGoalOutcome again = session.Assign(robot, Eigen::Vector3d(xy.x(), xy.y(), 0.0), now);
      ASSERT_EQ(again.code, FleetGoalCode::kSuccess) << "goal " << k << ": " << again.message;
      for (int r : again.robots) executed.Record(session, r);
      moved_aside += static_cast<int>(again.robots.size()) - 1;
      ++solved;
      continue;
    }
    ++solved;
    ASSERT_EQ(outcome.robots.front(), robot);
    moved_aside += static_cast<int>(outcome.robots.size()) - 1;
    orders += static_cast<int>(outcome.orders.size());
    for (const FleetSessionOrder& order : outcome.orders) EXPECT_LE(order.leaves, order.enters + 1e-9);
    for (int r : outcome.robots) {
      EXPECT_GE(session.plan(r).start_time, now - 1e-12);
      executed.Record(session, r);
    }
    const Eigen::Vector3d end = session.plan(robot).trajectory.Evaluate(kInf).q;
    EXPECT_EQ(end.head<2>(), xy);
    if (report_late && k % 3 == 1) {
      // A robot on its way reports being where its plan had it 0.7 s ago: late. Its plan and
      // those ordered after it are delayed; the certificate below checks them all.
      const int r = static_cast<int>(unit(late_rng) * n);
      const FleetSessionPlan& plan = session.plan(r);
      if (plan.runs.empty() || now - 0.7 <= plan.runs.front().start_time || now >= plan.arrival_time) continue;
      const Eigen::Vector2d seen = session.PoseAt(r, now - 0.7).head<2>();
      const FleetStateOutcome late = session.Report(r, seen, now, 1e-3);
      if (late.status != FleetStateStatus::kLate) {
        EXPECT_EQ(late.status, FleetStateStatus::kOnPlan) << late.message;  // it stood still then
        continue;
      }
      ++reported_late;
      delayed += static_cast<int>(late.robots.size()) - 1;
      // (Within the report's tolerance: a point that close to a node may be taken as the start
      // of the run from it.)
      EXPECT_LE((session.PoseAt(r, now).head<2>() - seen).norm(), 1e-3);
      for (int d : late.robots) executed.Record(session, d);
    }
  }
  EXPECT_EQ(solved, goals_total);
  if (report_late) {
    EXPECT_GT(reported_late, 20);
    EXPECT_GT(delayed, 0);
  } else {
    EXPECT_GT(moved_aside, 0);
  }
  EXPECT_GT(orders, 0);
  std::vector<TimedTrajectory> trajectories;
  std::vector<Body> bodies;
  double handover_gap = 0.0;
  for (int i = 0; i < n; ++i) {
    trajectories.push_back(executed.Of(i, &handover_gap));
    Body body;
    body.radius = radius;
    body.max_velocity = robots[i].max_velocity;
    body.max_acceleration = robots[i].max_acceleration;
    body.start = robots[i].pose;
    body.start.head<2>() = lattice->geometry().Position(starts[i]);
    body.goal = trajectories.back().Evaluate(kInf).q;
    bodies.push_back(body);
  }
  EXPECT_LE(handover_gap, 1e-9);
  const Certificate certificate = CertifyFleet(trajectories, bodies, padding - 0.01, boxes, 0.0, 0.5,
                                               lattice->geometry().origin,
                                               lattice->geometry().Position(lattice->geometry().num_cells() - 1));
  EXPECT_TRUE(certificate.ok) << certificate.failure;
  EXPECT_GE(certificate.min_pair_gap, 0.0);
  EXPECT_GE(certificate.min_obstacle_gap, 0.0);
  std::cout << "[ session  ] " << solved << "/" << goals_total << " goals (" << deferred << " deferred), " << moved_aside
            << " idle robots moved aside, " << reported_late << " robots reported late (" << delayed
            << " others delayed after them), slowest goal " << slowest * 1e3 << " ms, horizon " << now << " s, "
            << certificate.samples << " samples, min pair gap " << certificate.min_pair_gap << " m\n";
}

TEST(FleetSession, GoalsKeepComingAndEveryRobotStaysApart) { RunWarehouseSession(false); }

TEST(FleetSession, RobotsReportedLateAreDelayedWithThoseOrderedAfterThemAndStayApart) { RunWarehouseSession(true); }

TEST(FleetSession, AnIdleRobotInTheWayStepsAsideAndFailuresChangeNothing) {
  // A corridor one node wide with a bay (cells 0..7, bay 11 above 3): robot 1 idles in the
  // corridor at 5; robot 0 at 0 is sent to 7. Robot 1 must duck into the bay first.
  GridMap map;
  map.width = 8;
  map.height = 2;
  map.blocked.assign(16, 1);
  for (int c = 0; c < 8; ++c) map.blocked[c] = 0;
  map.blocked[11] = 0;
  Scene scene;
  std::vector<UprightBox> boxes;
  const auto lattice = SceneLattice(map, 1.0, 0.3, &scene, &boxes);
  std::vector<FleetSessionRobot> robots(2);
  robots[0].pose = Eigen::Vector3d(0, 0, 0);
  robots[1].pose = Eigen::Vector3d(5, 0, 0);
  FleetSession session(lattice, robots, 10.0);
  Executed executed(session);
  const FleetGoalOutcome outcome = session.Assign(0, Eigen::Vector3d(7, 0, kPi / 2), 10.0);
  ASSERT_EQ(outcome.code, FleetGoalCode::kSuccess) << outcome.message;
  ASSERT_EQ(outcome.robots, (std::vector<int>{0, 1}));
  EXPECT_EQ(session.PoseAt(1, 1e6).head<2>(), Eigen::Vector2d(3, 1));  // in the bay
  EXPECT_EQ(session.PoseAt(0, 1e6), Eigen::Vector3d(7, 0, kPi / 2));
  for (int r : outcome.robots) executed.Record(session, r);
  // Robot 0 passes 3 and 4 only after robot 1 has left them.
  bool ordered = false;
  for (const FleetSessionOrder& order : outcome.orders) ordered |= order.before_robot == 1 && order.after_robot == 0;
  EXPECT_TRUE(ordered);
  double gap = 0.0;
  std::vector<TimedTrajectory> trajectories = {executed.Of(0, &gap), executed.Of(1, &gap)};
  std::vector<Body> bodies(2);
  for (int i = 0; i < 2; ++i) {
    bodies[i].radius = 0.3;
    bodies[i].start = robots[i].pose;
    bodies[i].goal = trajectories[i].Evaluate(kInf).q;
  }
  const Certificate certificate =
      CertifyFleet(trajectories, bodies, 0.3, boxes, 0.0, 0.5, Eigen::Vector2d(0, 0), Eigen::Vector2d(7, 1));
  EXPECT_TRUE(certificate.ok) << certificate.failure;

  // An idle robot on the goal steps aside too: robot 1 sent to 7, where robot 0 stands idle.
  const FleetGoalOutcome swap = session.Assign(1, Eigen::Vector3d(7, 0, 0), 100.0);
  ASSERT_EQ(swap.code, FleetGoalCode::kSuccess) << swap.message;
  EXPECT_EQ(swap.robots, (std::vector<int>{1, 0}));
  // A goal where a moving robot is going to park is a named failure that changes nothing.
  ASSERT_EQ(session.Assign(0, Eigen::Vector3d(0, 0, 0), 200.0).code, FleetGoalCode::kSuccess);
  const FleetSessionPlan before = session.plan(1);
  const FleetGoalOutcome blocked = session.Assign(1, Eigen::Vector3d(0, 0, 0), 200.5);
  EXPECT_EQ(blocked.message, "the goal node (0, 0) (cell 0) is where robot 0 is going to park");
  EXPECT_NE(blocked.code, FleetGoalCode::kSuccess);
  EXPECT_FALSE(blocked.message.empty());
  EXPECT_TRUE(blocked.robots.empty());
  EXPECT_EQ(session.plan(1).start_time, before.start_time);
  EXPECT_EQ(session.PoseAt(1, 1e6), before.trajectory.Evaluate(kInf).q.head<3>());
  // Named errors.
  EXPECT_NE(ErrorOf([&] { session.Assign(0, Eigen::Vector3d(2, 1, 0), 200.0); }).find("blocked lattice node"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { session.Assign(0, Eigen::Vector3d(2.5, 0, 0), 200.0); }).find("is not on a lattice node"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { session.Assign(0, Eigen::Vector3d(2, 0, 0), 5.0); }).find("before the session's start"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { session.Assign(2, Eigen::Vector3d(2, 0, 0), 200.0); }).find("robot = 2 must be in [0, 2)"),
            std::string::npos);
  robots[1].pose = Eigen::Vector3d(0, 0, 0);
  EXPECT_NE(ErrorOf([&] { FleetSession(lattice, robots, 0.0); }).find("robots[1].pose = (0, 0) is on the node of robots[0]"),
            std::string::npos);
}

TEST(FleetSession, ALateRobotDelaysItsPlanAndTheRobotsOrderedAfterIt) {
  // A corridor (y = 1, x = 0..10) crossed by a passage at x = 4. Robot 0 runs the corridor in one
  // straight run (8 m at 1 m/s, 1 m/s²: x = 0.5 at t = 1, then 1 m/s, 9 s in all); robot 1,
  // sent across at t = 3, waits below the crossing until robot 0's run has ended.
  GridMap map;
  map.width = 11;
  map.height = 3;
  map.blocked.assign(33, 1);
  for (int x = 0; x < 11; ++x) map.blocked[11 + x] = 0;
  map.blocked[4] = map.blocked[26] = 0;
  Scene scene;
  std::vector<UprightBox> boxes;
  const auto lattice = SceneLattice(map, 1.0, 0.3, &scene, &boxes);
  std::vector<FleetSessionRobot> robots(3);
  robots[0].pose = Eigen::Vector3d(0, 1, 0);
  robots[1].pose = Eigen::Vector3d(4, 0, 0);
  robots[2].pose = Eigen::Vector3d(10, 1, 0);  // idle beyond robot 0's goal
  FleetSession session(lattice, robots, 0.0);
  Executed executed(session);
  ASSERT_EQ(session.Assign(0, Eigen::Vector3d(8, 1, 0), 0.0).code, FleetGoalCode::kSuccess);
  executed.Record(session, 0);
  const FleetGoalOutcome crossing = session.Assign(1, Eigen::Vector3d(4, 2, 0), 3.0);
  ASSERT_EQ(crossing.code, FleetGoalCode::kSuccess) << crossing.message;
  for (int r : crossing.robots) executed.Record(session, r);
  bool after_robot_0 = false;
  for (const FleetSessionOrder& order : crossing.orders) after_robot_0 |= order.before_robot == 0 && order.after_robot == 1;
  ASSERT_TRUE(after_robot_0);
  ASSERT_NEAR(session.PoseAt(0, 5.0).x(), 4.5, 1e-9);
  const double robot_1_departs = session.plan(1).runs.front().start_time;
  EXPECT_GE(robot_1_departs, 9.0);

  // On plan, ahead, off plan: nothing changes.
  const FleetStateOutcome on = session.Report(0, Eigen::Vector2d(4.52, 1.0), 5.0, 0.05);
  EXPECT_EQ(on.status, FleetStateStatus::kOnPlan);
  EXPECT_NEAR(on.deviation, 0.02, 1e-9);
  const FleetStateOutcome ahead = session.Report(0, Eigen::Vector2d(6.0, 1.0), 5.0, 0.05);
  EXPECT_EQ(ahead.status, FleetStateStatus::kAhead) << ahead.message;
  EXPECT_NEAR(ahead.delay, -1.5, 1e-6);
  const FleetStateOutcome off = session.Report(0, Eigen::Vector2d(4.0, 1.5), 5.0, 0.05);
  EXPECT_EQ(off.status, FleetStateStatus::kOffPlan) << off.message;
  EXPECT_NE(off.message.find("off every run of its plan"), std::string::npos) << off.message;
  EXPECT_NEAR(session.PoseAt(0, 5.0).x(), 4.5, 1e-9);

  // Late: at x = 2 at t = 5, where the plan was at t = 2.5. Robot 0 waits 2.5 s at its start,
  // robot 1 until robot 0 has left the crossing again; robot 2 (nothing after robot 0) keeps
  // its plan.
  const FleetStateOutcome late = session.Report(0, Eigen::Vector2d(2.0, 1.0), 5.0, 0.05);
  ASSERT_EQ(late.status, FleetStateStatus::kLate) << late.message;
  EXPECT_NEAR(late.delay, 2.5, 1e-6);
  EXPECT_EQ(late.robots, (std::vector<int>{0, 1}));
  EXPECT_NEAR(session.PoseAt(0, 5.0).x(), 2.0, 1e-6);
  EXPECT_NEAR(session.plan(0).arrival_time, 9.0 + 2.5, 1e-6);
  EXPECT_NEAR(session.plan(1).runs.front().start_time, robot_1_departs + 2.5, 1e-5);
  EXPECT_FALSE(late.orders.empty());
  for (const FleetSessionOrder& order : late.orders) EXPECT_LE(order.leaves, order.enters + 1e-9);
  for (int r : late.robots) executed.Record(session, r);
  double gap = 0.0;
  std::vector<TimedTrajectory> trajectories;
  std::vector<Body> bodies(3);
  for (int i = 0; i < 3; ++i) {
    trajectories.push_back(executed.Of(i, &gap));
    bodies[i].radius = 0.3;
    bodies[i].start = robots[i].pose;
    bodies[i].goal = trajectories[i].Evaluate(kInf).q;
  }
  EXPECT_LE(gap, 1e-9);
  const Certificate certificate =
      CertifyFleet(trajectories, bodies, 0.3, boxes, 0.0, 0.5, Eigen::Vector2d(0, 0), Eigen::Vector2d(10, 2));
  EXPECT_TRUE(certificate.ok) << certificate.failure;

  // Named errors.
  EXPECT_NE(ErrorOf([&] { session.Report(3, Eigen::Vector2d(0, 0), 6.0, 0.05); }).find("robot = 3 must be in [0, 3)"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { session.Report(0, Eigen::Vector2d(std::numeric_limits<double>::quiet_NaN(), 0), 6.0, 0.05); }).find("must be finite"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { session.Report(0, Eigen::Vector2d(0, 0), 6.0, 0.0); }).find("tolerance = 0 must be finite and > 0"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { session.Report(0, Eigen::Vector2d(0, 0), -1.0, 0.05); }).find("before the session's start"),
            std::string::npos);
}

}  // namespace
}  // namespace chasles
