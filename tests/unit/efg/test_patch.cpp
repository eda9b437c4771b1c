// Linear patch test: the linear field prescribed on the boundary of the unit cube must be
// reproduced everywhere (Galerkin + Nitsche + VCI exactly; penalty to the penalty error).
#include <gtest/gtest.h>

#include "efg_test_helpers.hpp"

namespace lamina::efg {
namespace {

using namespace testing;

/// Largest relative error of u^h and sigma^h at a set of interior and boundary points.
std::pair<Real, Real> patch_errors(const EfgAnalysis& a) {
  const material::LinearElastic mat{1.0, 0.25};
  Mat3 G;
  G << 2, 3, 4, -1, 2, 1, 3, -2, 0.5;
  G *= 1e-3;
  const material::Voigt exact_stress = mat.stress(material::strain_from_gradient(G));
  Real du = 0, ds = 0;
  for (int i = 0; i <= 6; ++i)
    for (int j = 0; j <= 6; ++j)
      for (int k = 0; k <= 6; ++k) {
        const Vec3 x(0.05 + 0.15 * i, 0.02 + 0.16 * j, 0.0 + k / 6.0);
        du = std::max(du, (a.displacement_at(x) - linear_field_at(x)).norm() / linear_field_at(Vec3(1, 1, 1)).norm());
        ds = std::max(ds, (a.stress_at(x) - exact_stress).norm() / exact_stress.norm());
      }
  return {du, ds};
}

struct PatchCase {
  int nodes;
  Real jitter;
  mls::Basis basis;
  Real kappa;
};

class PatchTest : public ::testing::TestWithParam<PatchCase> {};

TEST_P(PatchTest, NitscheWithVciIsExact) {
  const auto c = GetParam();
  EfgProblem p = patch_problem(c.nodes, c.jitter);
  p.options.mls.basis = c.basis;
  p.options.mls.kappa = c.kappa;
  p.options.essential = EssentialMethod::nitsche;
  p.options.correction = IntegrationCorrection::vci;
  EfgAnalysis a(p, {});
  a.solve();
  const auto [du, ds] = patch_errors(a);
  EXPECT_LT(du, 1e-10);
  EXPECT_LT(ds, 1e-9);
}

TEST_P(PatchTest, StiffPenaltyWithVciIsAccurate) {
  const auto c = GetParam();
  EfgProblem p = patch_problem(c.nodes, c.jitter);
  p.options.mls.basis = c.basis;
  p.options.mls.kappa = c.kappa;
  p.options.essential = EssentialMethod::penalty;
  p.options.penalty_factor = 1e9;
  p.options.correction = IntegrationCorrection::vci;
  EfgAnalysis a(p, {});
  a.solve();
  const auto [du, ds] = patch_errors(a);
  EXPECT_LT(du, 1e-6);
  EXPECT_LT(ds, 1e-5);
}

INSTANTIATE_TEST_SUITE_P(Nodes, PatchTest,
                         ::testing::Values(PatchCase{5, 0.0, mls::Basis::linear, 2.0},
                                           PatchCase{6, 0.25, mls::Basis::linear, 2.0},
                                           PatchCase{5, 0.0, mls::Basis::quadratic, 2.5},
                                           PatchCase{6, 0.25, mls::Basis::quadratic, 2.5}));

TEST(PatchTestPlainGauss, FailsTheIntegrationConstraintWithoutVci) {
  // Gauss quadrature of rational MLS functions is not exact: the test must see that error
  EfgProblem p = patch_problem(5, 0.0);
  p.options.mls.basis = mls::Basis::linear;
  p.options.essential = EssentialMethod::nitsche;
  EfgAnalysis a(p, {});
  a.solve();
  const auto [du, ds] = patch_errors(a);
  EXPECT_GT(ds, 1e-6);
  EXPECT_LT(ds, 0.1);
}

TEST(PatchTestEnergy, InternalEnergyEqualsTheWorkOfTheBoundaryReactions) {
  EfgProblem p = patch_problem(5, 0.0);
  p.options.mls.basis = mls::Basis::linear;
  p.options.essential = EssentialMethod::nitsche;
  p.options.correction = IntegrationCorrection::vci;
  EfgAnalysis a(p, {});
  a.solve();
  const material::LinearElastic mat{1.0, 0.25};
  Mat3 G;
  G << 2, 3, 4, -1, 2, 1, 3, -2, 0.5;
  G *= 1e-3;
  const Real energy = mat.energy_density(material::strain_from_gradient(G));  // unit volume
  EXPECT_NEAR(a.internal_energy(), energy, 1e-9 * energy);
  EXPECT_NEAR(a.external_energy(), energy, 1e-9 * energy);
  EXPECT_LT(a.reaction({}).norm(), 1e-12);  // self-equilibrated boundary tractions
}

}  // namespace
}  // namespace lamina::efg
