// Unit tests of the load-path stiffness-change detector (pd/load_path_events.hpp).
#include <gtest/gtest.h>

#include <cmath>

#include "pd/load_path_events.hpp"

using namespace lamina;
using namespace lamina::pd;

namespace {

/// Sample P(Delta) at equal load steps dp up to p_end from a compliance function dDelta/dP.
void sample(Real p_end, Real dp, Real (*compliance)(Real), std::vector<Real>& load, std::vector<Real>& displacement) {
  load.assign(1, 0.0);
  displacement.assign(1, 0.0);
  for (Real p = dp; p <= p_end + 1e-12; p += dp) {
    // midpoint rule over 100 sub-steps
    Real d = displacement.back();
    for (int k = 0; k < 100; ++k) d += compliance(p - dp + (k + 0.5) * dp / 100) * dp / 100;
    load.push_back(p);
    displacement.push_back(d);
  }
}

}  // namespace

TEST(LoadPathEvents, BilinearPathGivesTheKinkAndTheStiffnessRatio) {
  // stiffness 100 up to P = 10, then 40 (ratio 0.4): the kink lies inside increment 10..11
  std::vector<Real> load, displacement;
  sample(30, 1.0, [](Real p) { return p < 10.5 ? 0.01 : 0.025; }, load, displacement);
  const auto events = detect_stiffness_changes(load, displacement);
  ASSERT_EQ(events.size(), 1u);
  EXPECT_NEAR(events[0].load, 10.5, 1e-9);
  EXPECT_NEAR(events[0].stiffness_ratio, 0.4, 1e-9);
}

TEST(LoadPathEvents, SmoothSigmoidKneeNearItsCentreAndTwoEventsSeparated) {
  // compliance rises smoothly from 0.01 to 0.025 around P = 15 (width 1.5), and again to 0.04 around P = 35
  std::vector<Real> load, displacement;
  sample(50, 0.5, [](Real p) { return 0.01 + 0.015 / (1 + std::exp(-(p - 15) / 1.5)) + 0.015 / (1 + std::exp(-(p - 35) / 1.5)); },
         load, displacement);
  const auto events = detect_stiffness_changes(load, displacement);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_NEAR(events[0].load, 15.0, 0.75);  // within 5 %
  EXPECT_NEAR(events[1].load, 35.0, 1.75);
  EXPECT_NEAR(events[0].stiffness_ratio, 0.4, 0.03);
  EXPECT_NEAR(events[1].stiffness_ratio, 0.25, 0.03);
}

TEST(LoadPathEvents, LinearOrGentlySofteningPathHasNoEvent) {
  std::vector<Real> load, displacement;
  sample(40, 1.0, [](Real) { return 0.01; }, load, displacement);
  EXPECT_TRUE(detect_stiffness_changes(load, displacement).empty());
  sample(40, 1.0, [](Real p) { return 0.01 * (1 + 0.002 * p); }, load, displacement);  // 8 % softer at the end
  EXPECT_TRUE(detect_stiffness_changes(load, displacement).empty());
}

TEST(LoadPathEvents, SnapUnderLoadControlIsOneEvent) {
  // the displacement jumps by 0.5 between P = 20 and 21 (near-zero tangent), then stiffness 60
  std::vector<Real> load{0}, displacement{0};
  for (int p = 1; p <= 30; ++p) {
    load.push_back(p);
    displacement.push_back(p <= 20 ? 0.01 * p : 0.2 + 0.5 + (p - 21) / 60.0);
  }
  const auto events = detect_stiffness_changes(load, displacement);
  ASSERT_EQ(events.size(), 1u);
  EXPECT_GE(events[0].load, 20.0);
  EXPECT_LE(events[0].load, 21.0);
  EXPECT_NEAR(events[0].stiffness_ratio, 0.6, 1e-9);
}

TEST(LoadPathEvents, ImperfectPlateKneeLiesBelowTheBifurcationLoad) {
  // One-term Marguerre plate with an imperfection in the buckling mode: deflection xi added to the initial
  // xi0, stretching energy ~ ((xi + xi0)^2 - xi0^2)^2, so (1 - P/Pcr) xi + c xi (xi + xi0)(xi + 2 xi0) =
  // (P/Pcr) xi0, and end shortening Delta = P/K0 + beta ((xi + xi0)^2 - xi0^2). The perfect plate's branches,
  // Delta = P/K0 and P = Pcr (1 + c xi^2), cross at Pcr; beta = 1.5 c Pcr / K0 makes the post-buckling
  // stiffness 0.4 K0. Imperfection xi0 = 0.1 (t / 10 with xi in thicknesses, c = 1) and 45 equal load steps
  // to 4.5 Pcr, as in seed 002's plate (validation/pd_plate_post_buckling). The imperfect path approaches
  // the perfect asymptote only as xi0 / xi, so any two-tangent reading of its knee lies below Pcr: the
  // initial tangent crossed with the tangent at 1.1 / 2.2 / 4.4 Pcr gives 0.76 / 0.89 / 0.94 Pcr. The
  // detector's local reading (the tangents where the drop rate is half its peak) gives 0.78 Pcr: an exact
  // plate with this imperfection shows its first stiffness change about 22 % below its bifurcation load.
  const Real pcr = 10.0, k0 = 100.0, c = 1.0, xi0 = 0.1, beta = 1.5 * c * pcr / k0;
  std::vector<Real> load{0}, displacement{0};
  for (int i = 1; i <= 45; ++i) {
    const Real p = i;
    // the left side minus the right rises monotonically with xi >= 0 from -P xi0 / Pcr: bisection
    Real low = 0.0, high = 100.0;
    for (int it = 0; it < 200; ++it) {
      const Real xi = 0.5 * (low + high);
      ((1.0 - p / pcr) * xi + c * xi * (xi + xi0) * (xi + 2.0 * xi0) - p / pcr * xi0 < 0.0 ? low : high) = xi;
    }
    const Real xi = 0.5 * (low + high);
    load.push_back(p);
    displacement.push_back(p / k0 + beta * xi * (xi + 2.0 * xi0));
  }
  const auto events = detect_stiffness_changes(load, displacement);
  ASSERT_EQ(events.size(), 1u);
  EXPECT_NEAR(events[0].load / pcr, 0.78, 0.02);
  EXPECT_GT(events[0].peak_load, 0.6 * pcr);  // the steepest drop, also inside the knee
  EXPECT_LT(events[0].peak_load, pcr);
  EXPECT_NEAR(events[0].stiffness_ratio, 0.45, 0.05);  // settled on the way to the asymptote's 0.4
}
