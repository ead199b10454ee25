#include "chasles/robot/lie_group.h"

#include <algorithm>
#include <cmath>

namespace chasles {

namespace {

// Below this angle the trigonometric coefficients are replaced by their Taylor series
// (truncation error O(θ⁴) relative, far below double precision at this threshold).
constexpr double kSmallAngle = 1e-4;

inline Eigen::Vector3d Vee(const Eigen::Matrix3d& m) {
  return Eigen::Vector3d(m(2, 1) - m(1, 2), m(0, 2) - m(2, 0), m(1, 0) - m(0, 1));
}

}  // namespace

Eigen::Matrix3d Skew(const Eigen::Vector3d& w) {
  Eigen::Matrix3d s;
  s << 0.0, -w.z(), w.y(),
       w.z(), 0.0, -w.x(),
       -w.y(), w.x(), 0.0;
  return s;
}

Eigen::Matrix3d ExpSO3(const Eigen::Vector3d& rotation_vector) {
  const double theta2 = rotation_vector.squaredNorm();
  const double theta = std::sqrt(theta2);
  // R = I + a [r] + b [r]², a = sin θ / θ, b = (1 − cos θ) / θ² for r = ω̂θ.
  double a, b;
  if (theta < kSmallAngle) {
    a = 1.0 - theta2 / 6.0;
    b = 0.5 - theta2 / 24.0;
  } else {
    a = std::sin(theta) / theta;
    b = (1.0 - std::cos(theta)) / theta2;
  }
  const double x = rotation_vector.x(), y = rotation_vector.y(), z = rotation_vector.z();
  Eigen::Matrix3d R;
  R(0, 0) = 1.0 - b * (y * y + z * z);
  R(1, 1) = 1.0 - b * (x * x + z * z);
  R(2, 2) = 1.0 - b * (x * x + y * y);
  R(0, 1) = b * x * y - a * z;
  R(1, 0) = b * x * y + a * z;
  R(0, 2) = b * x * z + a * y;
  R(2, 0) = b * x * z - a * y;
  R(1, 2) = b * y * z - a * x;
  R(2, 1) = b * y * z + a * x;
  return R;
}

Eigen::Vector3d LogSO3(const Eigen::Matrix3d& R) {
  // vee(R − Rᵀ) = 2 sin θ ω̂ and tr R = 1 + 2 cos θ; atan2 gives θ accurately on all of [0, π].
  const Eigen::Vector3d axis_sin = Vee(R);  // 2 sin θ ω̂
  const double sin2 = axis_sin.norm();      // 2 sin θ
  const double cos2 = R.trace() - 1.0;      // 2 cos θ
  const double theta = std::atan2(sin2, cos2);
  if (theta < kSmallAngle) {
    // θ / (2 sin θ) = ½ (1 + θ²/6 + …)
    return axis_sin * (0.5 + theta * theta / 12.0);
  }
  if (cos2 > -1.0) {  // θ < 2π/3: the antisymmetric part is well conditioned
    return axis_sin * (theta / sin2);
  }
  // Near π: (R + Rᵀ)/2 = cos θ I + (1 − cos θ) ω̂ω̂ᵀ. Take the best-conditioned column of ω̂ω̂ᵀ
  // and the sign from the antisymmetric part (either sign is exact at θ = π).
  const double c = 0.5 * cos2;
  Eigen::Matrix3d B = 0.5 * (R + R.transpose());
  B.diagonal().array() -= c;
  B /= (1.0 - c);
  int k = 0;
  B.diagonal().maxCoeff(&k);
  Eigen::Vector3d w = B.col(k) / std::sqrt(std::max(B(k, k), 1e-300));
  w.normalize();
  if (w.dot(axis_sin) < 0.0) w = -w;
  return w * theta;
}

Eigen::Isometry3d ExpSE3(const Vector6d& screw, double theta) {
  const Eigen::Vector3d w = screw.head<3>() * theta;
  const Eigen::Vector3d v = screw.tail<3>() * theta;
  const double phi2 = w.squaredNorm();
  const double phi = std::sqrt(phi2);
  // p = (I + b [w] + c [w]²) v, b = (1 − cos φ)/φ², c = (φ − sin φ)/φ³.
  double b, c;
  if (phi < kSmallAngle) {
    b = 0.5 - phi2 / 24.0;
    c = 1.0 / 6.0 - phi2 / 120.0;
  } else {
    b = (1.0 - std::cos(phi)) / phi2;
    c = (phi - std::sin(phi)) / (phi2 * phi);
  }
  const Eigen::Vector3d wv = w.cross(v);
  Eigen::Isometry3d T;
  T.linear() = ExpSO3(w);
  T.translation() = v + b * wv + c * w.cross(wv);
  T.makeAffine();
  return T;
}

Vector6d LogSE3(const Eigen::Isometry3d& T) {
  const Eigen::Vector3d w = LogSO3(T.linear());
  const Eigen::Vector3d& p = T.translation();
  const double phi2 = w.squaredNorm();
  const double phi = std::sqrt(phi2);
  // v = G⁻¹ p, G⁻¹ = I − ½[w] + c [w]², c = (1 − (φ/2) cot(φ/2)) / φ² (finite on [0, π]).
  double c;
  if (phi < 1e-3) {
    c = 1.0 / 12.0 + phi2 / 720.0;
  } else {
    const double half = 0.5 * phi;
    c = (1.0 - half * std::cos(half) / std::sin(half)) / phi2;
  }
  const Eigen::Vector3d wp = w.cross(p);
  Vector6d out;
  out.head<3>() = w;
  out.tail<3>() = p - 0.5 * wp + c * w.cross(wp);
  return out;
}

Matrix6d Adjoint(const Eigen::Isometry3d& T) {
  const Eigen::Matrix3d R = T.linear();
  Matrix6d ad;
  ad.topLeftCorner<3, 3>() = R;
  ad.topRightCorner<3, 3>().setZero();
  ad.bottomLeftCorner<3, 3>().noalias() = Skew(T.translation()) * R;
  ad.bottomRightCorner<3, 3>() = R;
  return ad;
}

Matrix6d LieBracket(const Vector6d& twist) {
  const Eigen::Matrix3d w = Skew(twist.head<3>());
  Matrix6d ad;
  ad.topLeftCorner<3, 3>() = w;
  ad.topRightCorner<3, 3>().setZero();
  ad.bottomLeftCorner<3, 3>() = Skew(twist.tail<3>());
  ad.bottomRightCorner<3, 3>() = w;
  return ad;
}

}  // namespace chasles
