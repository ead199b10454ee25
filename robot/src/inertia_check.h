#pragma once
// Internal: the physical-validity rule for a link's rotational inertia, shared by the URDF
// loader and the DH/PoE front ends.

#include <algorithm>
#include <string>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include "chasles/robot/error.h"

namespace chasles {
namespace robot_internal {

/// Throws Error(kInvalidArgument) `<where> = <given> has principal moment <m>; principal moments
/// must be >= 0 (a rotational inertia is positive semidefinite)` unless every eigenvalue of the
/// symmetric, finite `inertia` is >= -1e-9 · (largest |eigenvalue|). `given` spells the values
/// as the input gave them, e.g. `(ixx 1, iyy -2, izz 1, ixy 0, ixz 0, iyz 0)`.
/// The triangle inequality (each moment <= the sum of the others) is not required: CAD exports
/// and existing descriptions break it slightly, and nothing downstream fails on it.
inline void CheckInertiaPositiveSemidefinite(const Eigen::Matrix3d& inertia, const std::string& where,
                                             const std::string& given) {
  const Eigen::Vector3d moments = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(inertia, Eigen::EigenvaluesOnly).eigenvalues();
  const double scale = moments.cwiseAbs().maxCoeff();
  if (moments.minCoeff() < -1e-9 * scale) {
    ThrowInvalid(where + " = " + given + " has principal moment " + chasles::FormatNumber(moments.minCoeff()) +
                 "; principal moments must be >= 0 (a rotational inertia is positive semidefinite)");
  }
}

}  // namespace robot_internal
}  // namespace chasles
