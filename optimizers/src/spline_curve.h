#pragma once
// Private to chasles_optimizers: the clamped B-spline in time behind SmoothWithBSpline — knots,
// basis functions, derivative control points (hodographs) and the exact power-basis polynomial
// of every knot span, each with its gradient with respect to the control points and the span
// durations.
//
// A clamped B-spline of degree p with K control points P₀…P_{K−1} has m = K − p knot spans of
// durations Δ₀…Δ_{m−1} > 0 and the knot vector
//   u₀ = … = u_p = 0,  u_{p+j} = Δ₀ + … + Δ_{j−1},  u_K = … = u_{K+p} = T = ΣΔ.
// Its r-th derivative is a clamped B-spline of degree p − r whose control points are
//   C⁽ʳ⁾ᵢ = (p − r + 1)·(C⁽ʳ⁻¹⁾ᵢ₊₁ − C⁽ʳ⁻¹⁾ᵢ) / (u_{i+p+1} − u_{i+r}),  i = 0 … K−1−r,
// and lies in their convex hull, so |C⁽ʳ⁾ᵢ| <= limit for every i bounds the derivative
// everywhere. C⁽ᵖ⁾ⱼ is the (constant) p-th derivative on span j.

#include <Eigen/Core>

namespace chasles {
namespace spline {

/// Spans [first, last) whose durations add up to the knot gap u_b − u_a (a <= b).
struct SpanRange {
  int first = 0;
  int last = 0;
};
SpanRange KnotGapSpans(int degree, int num_spans, int a, int b);

/// The clamped knot vector (size m + 2p + 1) of span durations `delta`.
Eigen::VectorXd ClampedKnots(int degree, const Eigen::VectorXd& delta);

/// Values N_{i,p}(t) of the K = knots.size() − p − 1 basis functions at t ∈ [0, T] (t = T
/// belongs to the last span), written to out[0 … K−1].
void BasisFunctions(int degree, const Eigen::VectorXd& knots, double t, double* out);

using RowMajorMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// One joint's spline: hodographs and span polynomials, with gradients with respect to
/// `slots` variables (0 = values only). The caller seeds the control points' gradients; the
/// span durations Δⱼ are the slots delta_slot + j.
class JointSpline {
 public:
  JointSpline(int degree, int num_control_points, int slots);

  /// control: K values; seeds: K × slots gradients of the control points (unused when
  /// slots = 0); delta: the m span durations; delta_slot: slot of Δ₀ (unused when slots = 0).
  void Compute(const double* control, const RowMajorMatrix& seeds, const Eigen::VectorXd& delta, int delta_slot);

  int degree() const { return p_; }
  int num_spans() const { return m_; }
  int slots() const { return slots_; }
  /// Control points of the r-th derivative (0 <= r <= p): K − r values, gradients (K − r) × slots.
  const Eigen::VectorXd& hodograph(int r) const { return level_[r]; }
  const RowMajorMatrix& hodograph_gradient(int r) const { return level_grad_[r]; }
  /// Span j's polynomial q(u_{p+j} + τ) = Σₖ coefficient(j, k)·τᵏ, k = 0 … p, exact up to
  /// rounding (Taylor expansion from the clamped start, span by span).
  double coefficient(int j, int k) const { return coeff_(j, k); }
  /// Span j's polynomial (p + 1 values) from the hodographs' values at the span's start alone,
  /// each by its own basis functions on `knots` (ClampedKnots of the durations given to
  /// Compute): no rounding carried over from earlier spans, so the output uses this. Values only.
  void SpanCoefficients(const Eigen::VectorXd& knots, int j, double* out) const;
  /// Gradient of coefficient(j, k): a row of `slots` values.
  Eigen::Map<const Eigen::RowVectorXd> coefficient_gradient(int j, int k) const {
    return Eigen::Map<const Eigen::RowVectorXd>(coeff_grad_.row(j * (p_ + 1) + k).data(), slots_);
  }

 private:
  int p_, k_, m_, slots_;
  Eigen::VectorXd level_[6];
  RowMajorMatrix level_grad_[6];
  RowMajorMatrix coeff_;       // m × (p + 1)
  RowMajorMatrix coeff_grad_;  // m·(p + 1) × slots
  Eigen::VectorXd d_, next_d_;             // derivative values at the current span start
  RowMajorMatrix d_grad_, next_d_grad_;    // their gradients
};

}  // namespace spline
}  // namespace chasles
