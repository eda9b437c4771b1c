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
