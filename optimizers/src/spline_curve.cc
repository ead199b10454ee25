#include "spline_curve.h"

#include <algorithm>

namespace chasles {
namespace spline {

SpanRange KnotGapSpans(int degree, int num_spans, int a, int b) {
  SpanRange out;
  out.first = std::min(std::max(a - degree, 0), num_spans);
  out.last = std::min(std::max(b - degree, 0), num_spans);
  return out;
}

Eigen::VectorXd ClampedKnots(int degree, const Eigen::VectorXd& delta) {
  const int m = static_cast<int>(delta.size());
  Eigen::VectorXd prefix(m + 1);  // prefix[j] = Δ₀ + … + Δ_{j−1}
  prefix[0] = 0.0;
  for (int j = 0; j < m; ++j) prefix[j + 1] = prefix[j] + delta[j];
  Eigen::VectorXd knots(m + 2 * degree + 1);
  for (int k = 0; k < knots.size(); ++k) knots[k] = prefix[std::min(std::max(k - degree, 0), m)];
  return knots;
}

void BasisFunctions(int degree, const Eigen::VectorXd& knots, double t, double* out) {
  const int p = degree;
  const int num = static_cast<int>(knots.size()) - p - 1;
  std::fill(out, out + num, 0.0);
  // The span s with u_s <= t < u_{s+1}, p <= s <= num − 1 (t at or past T: the last span).
  int s = num - 1;
  if (t < knots[num]) {
    s = static_cast<int>(std::upper_bound(knots.data() + p, knots.data() + num, t) - knots.data()) - 1;
    s = std::max(p, std::min(s, num - 1));
  }
  // Cox–de Boor, degree by degree: N holds the j + 1 non-zero functions of degree j on span s.
  double n_values[6] = {1.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  double left[6] = {0.0}, right[6] = {0.0};
  for (int j = 1; j <= p; ++j) {
    left[j] = t - knots[s + 1 - j];
    right[j] = knots[s + j] - t;
    double carry = 0.0;
    for (int r = 0; r < j; ++r) {
      const double gap = right[r + 1] + left[j - r];
      const double share = gap > 0.0 ? n_values[r] / gap : 0.0;
      n_values[r] = carry + right[r + 1] * share;
      carry = left[j - r] * share;
    }
    n_values[j] = carry;
  }
  for (int r = 0; r <= p; ++r) out[s - p + r] = n_values[r];
}

JointSpline::JointSpline(int degree, int num_control_points, int slots)
    : p_(degree), k_(num_control_points), m_(num_control_points - degree), slots_(slots) {
  for (int r = 0; r <= p_; ++r) {
    level_[r].resize(k_ - r);
    level_grad_[r].setZero(k_ - r, slots_);
  }
  coeff_.setZero(m_, p_ + 1);
  coeff_grad_.setZero(m_ * (p_ + 1), slots_);
  d_.resize(p_ + 1);
  next_d_.resize(p_ + 1);
  d_grad_.setZero(p_ + 1, slots_);
  next_d_grad_.setZero(p_ + 1, slots_);
}

void JointSpline::Compute(const double* control, const RowMajorMatrix& seeds, const Eigen::VectorXd& delta,
                          int delta_slot) {
  const bool gradients = slots_ > 0;
  for (int i = 0; i < k_; ++i) level_[0][i] = control[i];
  if (gradients) level_grad_[0] = seeds;

  // Hodographs: C⁽ʳ⁾ᵢ = c·(C⁽ʳ⁻¹⁾ᵢ₊₁ − C⁽ʳ⁻¹⁾ᵢ)/g with c = p − r + 1 and the knot gap
  // g = u_{i+p+1} − u_{i+r}; ∂C⁽ʳ⁾ᵢ/∂Δₗ = −C⁽ʳ⁾ᵢ/g for the spans l inside the gap.
  for (int r = 1; r <= p_; ++r) {
    const double c = static_cast<double>(p_ - r + 1);
    const Eigen::VectorXd& prev = level_[r - 1];
    for (int i = 0; i < k_ - r; ++i) {
      const SpanRange spans = KnotGapSpans(p_, m_, i + r, i + p_ + 1);
      double gap = 0.0;
      for (int l = spans.first; l < spans.last; ++l) gap += delta[l];
      const double value = c * (prev[i + 1] - prev[i]) / gap;
      level_[r][i] = value;
      if (!gradients) continue;
      level_grad_[r].row(i) = (c / gap) * (level_grad_[r - 1].row(i + 1) - level_grad_[r - 1].row(i));
      for (int l = spans.first; l < spans.last; ++l) level_grad_[r](i, delta_slot + l) -= value / gap;
    }
  }

  // Span polynomials. At t = 0 every derivative equals the first control point of its
  // hodograph (clamped); on span j the p-th derivative is C⁽ᵖ⁾ⱼ; the derivatives at the next
  // span's start follow from the Taylor expansion over Δⱼ.
  double factorial[6] = {1.0, 1.0, 2.0, 6.0, 24.0, 120.0};
  for (int k = 0; k < p_; ++k) {
    d_[k] = level_[k][0];
    if (gradients) d_grad_.row(k) = level_grad_[k].row(0);
  }
  for (int j = 0; j < m_; ++j) {
    d_[p_] = level_[p_][j];
    if (gradients) d_grad_.row(p_) = level_grad_[p_].row(j);
    for (int k = 0; k <= p_; ++k) {
      coeff_(j, k) = d_[k] / factorial[k];
      if (gradients) coeff_grad_.row(j * (p_ + 1) + k) = d_grad_.row(k) / factorial[k];
    }
    if (j + 1 == m_) break;
    const double h = delta[j];
    for (int k = 0; k < p_; ++k) {
      // D⁽ᵏ⁾(h) = Σ_{l>=k} a_l·l!/(l−k)!·h^{l−k}, a_l = coeff_(j, l).
      double value = 0.0, slope = 0.0, power = 1.0;
      if (gradients) next_d_grad_.row(k).setZero();
      for (int l = k; l <= p_; ++l) {
        const double falling = factorial[l] / factorial[l - k];
        value += coeff_(j, l) * falling * power;
        if (gradients) {
          next_d_grad_.row(k) += (falling * power) * coeff_grad_.row(j * (p_ + 1) + l);
          if (l > k) slope += coeff_(j, l) * falling * (l - k) * power / h;
        }
        power *= h;
      }
      next_d_[k] = value;
      if (gradients) next_d_grad_(k, delta_slot + j) += slope;
    }
    for (int k = 0; k < p_; ++k) {
      d_[k] = next_d_[k];
      if (gradients) d_grad_.row(k) = next_d_grad_.row(k);
    }
  }
}

void JointSpline::SpanCoefficients(const Eigen::VectorXd& knots, int j, double* out) const {
  const double factorial[6] = {1.0, 1.0, 2.0, 6.0, 24.0, 120.0};
  if (j == 0) {  // clamped: each derivative at t = 0 is its hodograph's first control point
    for (int r = 0; r <= p_; ++r) out[r] = level_[r][0] / factorial[r];
    return;
  }
  const double t = knots[p_ + j];
  Eigen::VectorXd basis(k_);
  for (int r = 0; r <= p_; ++r) {
    // The r-th derivative is the degree p − r spline of C⁽ʳ⁾ on the knots without r at each end.
    const Eigen::VectorXd trimmed = knots.segment(r, knots.size() - 2 * r);
    BasisFunctions(p_ - r, trimmed, t, basis.data());
    out[r] = basis.head(k_ - r).dot(level_[r]) / factorial[r];
  }
}

}  // namespace spline
}  // namespace chasles
