#pragma once
// Weight functions w(s) of the MLS approximation, s = distance / support radius, with w', w'':
// gauss (eq 1-6), cubic spline (eq 1-7), quartic spline (eq 1-8); w = 0 for s >= 1.
#include <cmath>

#include "core/types.hpp"
#include "mls/mls_options.hpp"

namespace lamina::mls {

/// w(s), dw/ds, d2w/ds2 and (dw/ds)/s (finite at s = 0, used by spherical supports).
struct WeightValue {
  Real value = 0.0;
  Real first = 0.0;
  Real second = 0.0;
  Real first_over_s = 0.0;
};

/// The splines are C2 at s = 1 (w = w' = w'' = 0); the truncated Gaussian is only C0 there
/// (w'(1) = -2 beta^2 exp(-beta^2) / (1 - exp(-beta^2)) = -0.024 for beta = 2.5), so shape function
/// derivatives jump slightly where x crosses a support boundary.
class WeightFunction {
 public:
  explicit WeightFunction(Weight kind = Weight::quartic_spline, Real gauss_beta = default_gauss_beta)
      : kind_(kind), beta_squared_(gauss_beta * gauss_beta) {
    const Real tail = std::exp(-beta_squared_);
    gauss_tail_ = tail;
    gauss_normalisation_ = 1.0 / (1.0 - tail);
  }

  Weight kind() const { return kind_; }

  /// Value and derivatives at s >= 0 (all zero for s >= 1).
  WeightValue evaluate(Real s) const {
    switch (kind_) {
      case Weight::gauss: return evaluate_as<Weight::gauss>(s);
      case Weight::cubic_spline: return evaluate_as<Weight::cubic_spline>(s);
      case Weight::quartic_spline: return evaluate_as<Weight::quartic_spline>(s);
    }
    return {};
  }

  /// evaluate() for a kind known at compile time (must equal kind(); used in inner loops).
  template <Weight Kind>
  [[gnu::always_inline]] inline WeightValue evaluate_as(Real s) const {
    if (s >= 1.0) return WeightValue{};
    return evaluate_inside<Kind>(s);
  }

  /// evaluate_as() for 0 <= s < 1 (not checked; for neighbours already known to be inside).
  template <Weight Kind>
  [[gnu::always_inline]] inline WeightValue evaluate_inside(Real s) const {
    WeightValue result;
    if constexpr (Kind == Weight::gauss) {
      // eq 1-6: w = (exp(-s^2 b^2) - exp(-b^2)) / (1 - exp(-b^2))
      const Real e = std::exp(-s * s * beta_squared_) * gauss_normalisation_;
      result.value = e - gauss_tail_ * gauss_normalisation_;
      result.first_over_s = -2.0 * beta_squared_ * e;
      result.first = result.first_over_s * s;
      result.second = (4.0 * s * s * beta_squared_ * beta_squared_ - 2.0 * beta_squared_) * e;
    } else if constexpr (Kind == Weight::cubic_spline) {
      // eq 1-7
      if (s <= 0.5) {
        result.value = 2.0 / 3.0 - 4.0 * s * s + 4.0 * s * s * s;
        result.first_over_s = -8.0 + 12.0 * s;
        result.first = result.first_over_s * s;
        result.second = -8.0 + 24.0 * s;
      } else {
        result.value = 4.0 / 3.0 - 4.0 * s + 4.0 * s * s - 4.0 / 3.0 * s * s * s;
        result.first = -4.0 + 8.0 * s - 4.0 * s * s;
        result.first_over_s = result.first / s;
        result.second = 8.0 - 8.0 * s;
      }
    } else {
      // eq 1-8: w = 1 - 6 s^2 + 8 s^3 - 3 s^4
      const Real s2 = s * s;
      result.value = 1.0 - 6.0 * s2 + 8.0 * s2 * s - 3.0 * s2 * s2;
      result.first_over_s = -12.0 + 24.0 * s - 12.0 * s2;
      result.first = result.first_over_s * s;
      result.second = -12.0 + 48.0 * s - 36.0 * s2;
    }
    return result;
  }

  Real value(Real s) const { return evaluate(s).value; }

 private:
  Weight kind_;
  Real beta_squared_;
  Real gauss_tail_ = 0.0;
  Real gauss_normalisation_ = 1.0;
};

}  // namespace lamina::mls
