// Weight functions (seed 004, eqs 1-6, 1-7, 1-8): values against the formulas and derivatives against
// finite differences.
#include <gtest/gtest.h>

#include <cmath>

#include "mls/weight_function.hpp"

namespace lamina::mls {
namespace {

TEST(WeightFunction, ValuesMatchSeedFormulas) {
  const WeightFunction quartic(Weight::quartic_spline);
  const WeightFunction cubic(Weight::cubic_spline);
  const Real beta = 2.5;
  const WeightFunction gauss(Weight::gauss, beta);
  for (Real s : {0.0, 0.1, 0.25, 0.5, 0.6, 0.75, 0.9, 0.999}) {
    EXPECT_NEAR(quartic.value(s), 1 - 6 * s * s + 8 * s * s * s - 3 * s * s * s * s, 1e-14) << s;
    const Real expected_cubic = s <= 0.5 ? 2.0 / 3 - 4 * s * s + 4 * s * s * s
                                         : 4.0 / 3 - 4 * s + 4 * s * s - 4.0 / 3 * s * s * s;
    EXPECT_NEAR(cubic.value(s), expected_cubic, 1e-14) << s;
    const Real expected_gauss = (std::exp(-s * s * beta * beta) - std::exp(-beta * beta)) / (1 - std::exp(-beta * beta));
    EXPECT_NEAR(gauss.value(s), expected_gauss, 1e-14) << s;
  }
  for (const WeightFunction& w : {quartic, cubic, gauss}) {
    EXPECT_EQ(w.value(1.0), 0.0);
    EXPECT_EQ(w.value(1.5), 0.0);
    EXPECT_EQ(w.evaluate(2.0).first, 0.0);
    EXPECT_NEAR(w.value(1.0 - 1e-12), 0.0, 1e-10);
  }
  EXPECT_DOUBLE_EQ(quartic.value(0.0), 1.0);
  EXPECT_DOUBLE_EQ(cubic.value(0.0), 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(gauss.value(0.0), 1.0);
  EXPECT_EQ(default_gauss_beta, 2.5);
}

// Central differences with step 1e-6: error ~ 1e-12 (truncation) + 1e-10 (rounding); tolerance 1e-7.
TEST(WeightFunction, DerivativesMatchFiniteDifferences) {
  const Real step = 1e-6;
  for (Weight kind : {Weight::gauss, Weight::cubic_spline, Weight::quartic_spline})
    for (Real beta : {1.0, 2.5, 4.0}) {
      const WeightFunction w(kind, beta);
      for (Real s : {0.05, 0.2, 0.35, 0.49, 0.51, 0.7, 0.95}) {
        const WeightValue centre = w.evaluate(s);
        const Real first = (w.value(s + step) - w.value(s - step)) / (2 * step);
        const Real second = (w.evaluate(s + step).first - w.evaluate(s - step).first) / (2 * step);
        EXPECT_NEAR(centre.first, first, 1e-7) << to_string(kind) << " s = " << s;
        EXPECT_NEAR(centre.second, second, 1e-7) << to_string(kind) << " s = " << s;
        EXPECT_NEAR(centre.first_over_s, centre.first / s, 1e-12 * std::max(1.0, std::abs(centre.first / s)));
      }
      // (dw/ds)/s is finite at s = 0 and equals w''(0).
      EXPECT_NEAR(w.evaluate(0.0).first_over_s, w.evaluate(0.0).second, 1e-12);
      EXPECT_EQ(w.evaluate(0.0).first, 0.0);
    }
}

TEST(WeightFunction, SplinesAreSmoothAtTheirJoints) {
  const WeightFunction cubic(Weight::cubic_spline);
  const WeightValue left = cubic.evaluate(0.5 - 1e-13);
  const WeightValue right = cubic.evaluate(0.5 + 1e-13);
  EXPECT_NEAR(left.value, right.value, 1e-12);
  EXPECT_NEAR(left.first, right.first, 1e-11);
  EXPECT_NEAR(left.second, right.second, 1e-10);
  for (Weight kind : {Weight::cubic_spline, Weight::quartic_spline}) {
    const WeightValue edge = WeightFunction(kind).evaluate(1.0 - 1e-9);
    EXPECT_NEAR(edge.first, 0.0, 1e-8) << to_string(kind);
    EXPECT_NEAR(edge.second, 0.0, 1e-7) << to_string(kind);
  }
}

}  // namespace
}  // namespace lamina::mls
