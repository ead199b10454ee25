#pragma once
/// \file
/// A geometric path in configuration space.

#include <vector>

#include <Eigen/Core>

namespace chasles {

/// Waypoints in configuration space [rad] / [m], joined by straight joint-space segments.
using JointPath = std::vector<Eigen::VectorXd>;

}  // namespace chasles
