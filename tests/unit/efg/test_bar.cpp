// One-dimensional bars against analytic solutions: end traction with symmetry planes (exact),
// and a bar hanging under its own weight (quadratic displacement, nu = 0).
#include <gtest/gtest.h>

#include "efg_test_helpers.hpp"

namespace lamina::efg {
namespace {

using namespace testing;

EfgProblem bar(const std::array<int, 3>& nodes, Real nu) {
  EfgProblem p = make_problem(box(Vec3::Zero(), Vec3(4, 2, 2)), nodes, 1e4, nu);
  const char* names[3] = {"xmin", "ymin", "zmin"};
  for (int a = 0; a < 3; ++a) {
    model::Constraint c;
    c.select = set(names[a], p.cloud);
    c.fixed[static_cast<std::size_t>(a)] = true;
    p.constraints.push_back(c);
  }
  return p;
}

TEST(Bar, TensionWithSymmetryPlanesIsExact) {
  EfgProblem p = bar({13, 5, 5}, 1.0 / 3.0);
  model::Load load;
  load.kind = model::Load::Kind::traction;
  load.select = set("xmax", p.cloud);
  load.vector = {constant(1.0), constant(0.0), constant(0.0)};
  p.loads.push_back(load);
  p.options.mls.basis = mls::Basis::linear;
  p.options.mls.kappa = 2.0;
  p.options.essential = EssentialMethod::nitsche;
  p.options.correction = IntegrationCorrection::vci;
  EfgAnalysis a(p, {});
  a.solve();
  for (const Vec3& x : {Vec3(4, 2, 2), Vec3(1.3, 0.4, 1.7), Vec3(0, 0, 0), Vec3(2, 1, 1)}) {
    const Vec3 u = a.displacement_at(x);
    EXPECT_NEAR(u[0], 1e-4 * x[0], 1e-12);
    EXPECT_NEAR(u[1], -1e-4 / 3 * x[1], 1e-12);
    EXPECT_NEAR(u[2], -1e-4 / 3 * x[2], 1e-12);
    const material::Voigt s = a.stress_at(x);
    EXPECT_NEAR(s[0], 1.0, 1e-9);
    for (int k = 1; k < 6; ++k) EXPECT_NEAR(s[k], 0.0, 1e-9);
  }
  const Vec3 r = a.reaction(p.constraints[0].select.nodes);
  EXPECT_NEAR(r[0], -4.0, 1e-9);
  EXPECT_NEAR(a.internal_energy(), 0.5 * 16 / 1e4, 1e-12);
}

TEST(Bar, HangingUnderBodyForceMatchesTheQuadraticSolution) {
  // body force b along -x on a bar fixed (symmetry) at x = 0: with nu = 0 the solution is 1D,
  // sigma_xx = -b (L - x), u_x = -(b / E) (L x - x^2 / 2).
  EfgProblem p = bar({17, 3, 3}, 0.0);
  model::Load load;
  load.kind = model::Load::Kind::body_force;
  load.select.spec.kind = geometry::SelectionSpec::Kind::all;
  load.vector = {constant(-10.0), constant(0.0), constant(0.0)};
  p.loads.push_back(load);
  p.options.mls.basis = mls::Basis::quadratic;
  p.options.mls.kappa = 2.5;
  p.options.essential = EssentialMethod::nitsche;
  p.options.gauss = {3, 3, 3};
  EfgAnalysis a(p, {});
  a.solve();
  const Real L = 4, b = 10, E = 1e4;
  for (Real x = 0.25; x <= 4.0; x += 0.5) {
    const Real exact = -(b / E) * (L * x - 0.5 * x * x);
    EXPECT_NEAR(a.displacement_at(Vec3(x, 1, 1))[0], exact, 1e-3 * std::abs(-(b / E) * 0.5 * L * L));
    EXPECT_NEAR(a.stress_at(Vec3(x, 1, 1))[0], -b * (L - x), 2e-2 * b * L);
  }
  EXPECT_NEAR(a.reaction(p.constraints[0].select.nodes)[0], b * 4 * 2 * 2, 1e-6 * b * 16);
}

TEST(Bar, PenaltyConvergesToTheConstrainedSolution) {
  Real previous = INFINITY;
  for (Real factor : {1e3, 1e5, 1e7}) {
    EfgProblem p = bar({9, 3, 3}, 0.25);
    model::Load load;
    load.kind = model::Load::Kind::traction;
    load.select = set("xmax", p.cloud);
    load.vector = {constant(1.0), constant(0.0), constant(0.0)};
    p.loads.push_back(load);
    p.options.mls.basis = mls::Basis::linear;
    p.options.essential = EssentialMethod::penalty;
    p.options.penalty_factor = factor;
    p.options.correction = IntegrationCorrection::vci;
    EfgAnalysis a(p, {});
    a.solve();
    const Real error = std::abs(a.displacement_at(Vec3(4, 1, 1))[0] - 4e-4) / 4e-4;
    EXPECT_LT(error, previous);
    previous = error;
  }
  EXPECT_LT(previous, 1e-5);
}

}  // namespace
}  // namespace lamina::efg

namespace lamina::efg {
namespace {

using namespace testing;

TEST(Bar, LagrangeMultipliersEnforceTheValuesExactlyAtTheConstrainedNodes) {
  EfgProblem p = make_problem(box(Vec3::Zero(), Vec3(4, 1, 1)), {9, 3, 3}, 1e4, 0.3);
  model::Constraint clamp;
  clamp.select = set("xmin", p.cloud);
  clamp.fixed = {true, true, true};
  clamp.displacement = {constant(1e-3), constant(0.0), field("2e-3*y")};
  p.constraints.push_back(clamp);
  model::Load load;
  load.kind = model::Load::Kind::force;
  load.select = set("xmax", p.cloud);
  load.vector = {constant(0.0), constant(-1.0), constant(0.0)};
  p.loads.push_back(load);
  p.options.mls.basis = mls::Basis::quadratic;
  p.options.mls.kappa = 2.5;
  p.options.essential = EssentialMethod::lagrange;
  EfgAnalysis a(p, {});
  a.solve();
  for (Index node : clamp.select.nodes) {
    const Vec3 x = p.cloud.positions.col(node);
    const Vec3 u = a.displacement_at(x);
    EXPECT_NEAR(u[0], 1e-3, 1e-12);
    EXPECT_NEAR(u[1], 0.0, 1e-12);
    EXPECT_NEAR(u[2], 2e-3 * x[1], 1e-12);
  }
  // the multipliers balance the applied force
  EXPECT_NEAR(a.reaction({})[1], 1.0, 1e-8);
  EXPECT_EQ(a.counts().dofs, 3 * p.cloud.size() + 3 * static_cast<Index>(clamp.select.nodes.size()));
}

}  // namespace
}  // namespace lamina::efg
