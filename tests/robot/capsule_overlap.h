#pragma once
// Test helper: a conservative self-collision check without the collision module. Every shape is
// replaced by a capsule that contains it (sphere: zero-length capsule; cylinder: capsule of the
// same radius and length; box: its circumscribed sphere), so "no capsule overlap" implies "no
// shape overlap". For sphere-only robots the check is exact.

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "chasles/robot/robot_model.h"

namespace chasles {
namespace testing {

struct Capsule {
  Eigen::Vector3d a, b;  // segment end points (world)
  double radius;
};

inline Capsule ToCapsule(const Shape& shape, const Eigen::Isometry3d& link_pose) {
  const Eigen::Isometry3d pose = link_pose * shape.pose;
  double half = 0.0, radius = shape.radius;
  switch (shape.type) {
    case ShapeType::kCylinder:
    case ShapeType::kCapsule: half = 0.5 * shape.length; break;
    case ShapeType::kBox: radius = 0.5 * shape.size.norm(); break;
    case ShapeType::kMesh: {
      radius = 0.0;
      for (const auto& v : shape.mesh->vertices) radius = std::max(radius, v.norm());
      break;
    }
    case ShapeType::kSphere: break;
  }
  return {pose * Eigen::Vector3d(0, 0, -half), pose * Eigen::Vector3d(0, 0, half), radius};
}

/// Distance between segments p0p1 and q0q1 (clamped closest points, degenerate cases handled).
inline double SegmentDistance(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                              const Eigen::Vector3d& q0, const Eigen::Vector3d& q1) {
  const Eigen::Vector3d d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  double s = 0.0, t = 0.0;
  if (a < 1e-18 && e < 1e-18) return r.norm();
  if (a < 1e-18) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e < 1e-18) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), denom = a * e - b * b;
      s = denom > 1e-18 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0.0) {
        t = 0.0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1.0) {
        t = 1.0;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  return ((p0 + s * d1) - (q0 + t * d2)).norm();
}

/// Largest capsule penetration between links a and b at `poses` (<= 0: apart).
inline double LinkPenetration(const RobotModel& model, const std::vector<Eigen::Isometry3d>& poses,
                              int a, int b) {
  double worst = -1e300;
  for (const Shape& sa : model.links()[a].collision) {
    const Capsule ca = ToCapsule(sa, poses[a]);
    for (const Shape& sb : model.links()[b].collision) {
      const Capsule cb = ToCapsule(sb, poses[b]);
      worst = std::max(worst, ca.radius + cb.radius - SegmentDistance(ca.a, ca.b, cb.a, cb.b));
    }
  }
  return worst;
}

/// Link pairs (names) that overlap at q and are not allowed by the ACM.
inline std::vector<std::pair<std::string, std::string>> SelfCollisions(const RobotModel& model,
                                                                       const Eigen::VectorXd& q) {
  std::vector<Eigen::Isometry3d> poses;
  model.ForwardKinematics(q, &poses);
  std::vector<std::pair<std::string, std::string>> pairs;
  for (int a = 0; a < model.num_links(); ++a) {
    for (int b = a + 1; b < model.num_links(); ++b) {
      if (model.allowed_collisions().IsAllowed(a, b)) continue;
      if (LinkPenetration(model, poses, a, b) > 0.0) {
        pairs.emplace_back(model.links()[a].name, model.links()[b].name);
      }
    }
  }
  return pairs;
}

}  // namespace testing
}  // namespace chasles
