#pragma once
/// \file
/// SO(3)/SE(3) utilities in Modern Robotics conventions (Lynch & Park, ch. 3): twists and
/// screw axes are 6-vectors (ω, v); wrenches are (m, f). All functions are pure.

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace chasles {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// [ω]: the skew-symmetric matrix with [ω] p = ω × p.
Eigen::Matrix3d Skew(const Eigen::Vector3d& w);

/// e^{[ω̂]θ} for a rotation vector ω̂θ (any norm; 0 gives identity). Rodrigues' formula.
Eigen::Matrix3d ExpSO3(const Eigen::Vector3d& rotation_vector);
/// The rotation vector ω̂θ with θ ∈ [0, π] of a rotation matrix (the inverse of ExpSO3).
Eigen::Vector3d LogSO3(const Eigen::Matrix3d& R);

/// e^{[S]θ} for a screw axis S = (ω, v) and distance θ (‖ω‖ = 1, or ω = 0 and ‖v‖ = 1 for a
/// pure translation); also correct for any twist S·θ given as `twist` with theta = 1.
Eigen::Isometry3d ExpSE3(const Vector6d& screw, double theta);
/// The twist 𝒱 = (ω, v) with e^{[𝒱]} = T, ‖ω‖ ∈ [0, π] (the inverse of ExpSE3(𝒱, 1)).
Vector6d LogSE3(const Eigen::Isometry3d& T);

/// [Ad_T]: maps a twist in frame {b} to frame {a} for T = T_ab. 6×6, (ω, v) ordering.
Matrix6d Adjoint(const Eigen::Isometry3d& T);
/// [ad_𝒱]: the Lie bracket matrix of a twist, [ad_𝒱] 𝒱₂ = [𝒱, 𝒱₂].
Matrix6d LieBracket(const Vector6d& twist);

}  // namespace chasles
