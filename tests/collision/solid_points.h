#pragma once
// Dense points on and in primitive solids (cylinder, capsule, box, each in its own frame: centred,
// axis z) and the exact distance from a point to each solid: the sphere-fit tests' own geometry.

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Core>

namespace chasles::test {

/// Exact distances from p to the solids, in their frames: a cylinder (radius r, length L, axis z,
/// centred; the nearest point is on the side, a cap or a rim), a capsule (cylindrical part of
/// length L) and a box of `size`.
inline double CylinderDistance(const Eigen::Vector3d& p, double r, double length) {
  const double dr = std::hypot(p.x(), p.y()) - r, dz = std::abs(p.z()) - 0.5 * length;
  return std::hypot(std::max(dr, 0.0), std::max(dz, 0.0));
}
inline double CapsuleDistance(const Eigen::Vector3d& p, double r, double length) {
  const Eigen::Vector3d on_axis(0.0, 0.0, std::clamp(p.z(), -0.5 * length, 0.5 * length));
  return std::max((p - on_axis).norm() - r, 0.0);
}
inline double BoxDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& size) {
  return (p.cwiseAbs() - 0.5 * size).cwiseMax(0.0).norm();
}

/// Points of the solid cylinder: `count` in its volume, as many on its side and caps (by area),
/// and its two rims, its axis and the caps' diameters densely.
inline std::vector<Eigen::Vector3d> CylinderPoints(double r, double length, int count, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Eigen::Vector3d> points;
  const auto at = [&](double radial, double angle, double z) {
    points.emplace_back(radial * std::cos(angle), radial * std::sin(angle), z);
  };
  for (int i = 0; i < count; ++i) at(r * std::sqrt(unit(rng)), 2.0 * M_PI * unit(rng), length * (unit(rng) - 0.5));
  const double side = 2.0 * M_PI * r * length, cap = M_PI * r * r;
  for (int i = 0; i < count; ++i) {
    if (unit(rng) * (side + 2.0 * cap) < side) {
      at(r, 2.0 * M_PI * unit(rng), length * (unit(rng) - 0.5));
    } else {
      at(r * std::sqrt(unit(rng)), 2.0 * M_PI * unit(rng), unit(rng) < 0.5 ? -0.5 * length : 0.5 * length);
    }
  }
  for (int i = 0; i < 4096; ++i) {
    const double angle = 2.0 * M_PI * i / 4096;
    at(r, angle, -0.5 * length);
    at(r, angle, 0.5 * length);
    at(r * (i % 64) / 63.0, angle, (i % 2 == 0 ? -0.5 : 0.5) * length);
  }
  for (int i = 0; i <= 256; ++i) at(0.0, 0.0, length * (i / 256.0 - 0.5));
  return points;
}

/// Points of the solid capsule: in its volume and on its surface, `count` each, and its rims.
inline std::vector<Eigen::Vector3d> CapsulePoints(double r, double length, int count, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> normal;
  std::vector<Eigen::Vector3d> points;
  const auto direction = [&] { return Eigen::Vector3d(normal(rng), normal(rng), normal(rng)).normalized(); };
  const double side = 2.0 * M_PI * r * length, ends = 4.0 * M_PI * r * r;
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3d d = direction();
    if (unit(rng) * (side + ends) < side) {
      points.emplace_back(r * d.x() / std::hypot(d.x(), d.y()), r * d.y() / std::hypot(d.x(), d.y()),
                          length * (unit(rng) - 0.5));
    } else {
      points.push_back(Eigen::Vector3d(0.0, 0.0, (d.z() < 0.0 ? -0.5 : 0.5) * length) + r * d);
    }
    // Inside: a point of the segment plus a point of the ball of radius r.
    points.push_back(Eigen::Vector3d(0.0, 0.0, length * (unit(rng) - 0.5)) + r * std::cbrt(unit(rng)) * direction());
  }
  for (int i = 0; i < 4096; ++i) {
    const double angle = 2.0 * M_PI * i / 4096;
    for (double z : {-0.5 * length, 0.5 * length}) points.emplace_back(r * std::cos(angle), r * std::sin(angle), z);
  }
  return points;
}

/// Points of the solid box: in its volume and on its faces, `count` each, and its 12 edges.
inline std::vector<Eigen::Vector3d> BoxPoints(const Eigen::Vector3d& size, int count, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(-0.5, 0.5);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3d p(unit(rng) * size.x(), unit(rng) * size.y(), unit(rng) * size.z());
    points.push_back(p);
    Eigen::Vector3d face = p;
    const int axis = i % 3;
    face[axis] = (i % 2 == 0 ? -0.5 : 0.5) * size[axis];
    points.push_back(face);
  }
  for (int i = 0; i <= 1024; ++i) {
    for (int axis = 0; axis < 3; ++axis) {
      for (int corner = 0; corner < 4; ++corner) {
        Eigen::Vector3d p = 0.5 * size;
        p[(axis + 1) % 3] *= corner & 1 ? 1.0 : -1.0;
        p[(axis + 2) % 3] *= corner & 2 ? 1.0 : -1.0;
        p[axis] = size[axis] * (i / 1024.0 - 0.5);
        points.push_back(p);
      }
    }
  }
  return points;
}

}  // namespace chasles::test
