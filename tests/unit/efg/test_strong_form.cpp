// Collocation and weighted least squares EFG (seed 004 section 1.2.2 (2), (5); section 3.3):
// the Navier operator on a quadratic field, the linear patch test (1e-6, issue 3 acceptance 1),
// a quadratic field with body force, uniaxial tension with symmetry and traction conditions,
// the seed's observation that both degrade with a fully clamped end, and input errors.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <functional>

#include "core/error.hpp"
#include "efg/strong_form_residuals.hpp"
#include "efg/weighted_least_squares_system.hpp"
#include "efg_test_helpers.hpp"

namespace lamina::efg {
namespace {

using namespace testing;

/// Largest relative errors of u^h and sigma^h against an exact field at a grid of points in [lo, hi].
std::pair<Real, Real> field_errors(const EfgAnalysis& a, const Vec3& lo, const Vec3& hi,
                                   const std::function<Vec3(const Vec3&)>& u_exact,
                                   const std::function<material::Voigt(const Vec3&)>& s_exact) {
  Real du = 0, ds = 0, umax = 0, smax = 0;
  for (int i = 0; i <= 6; ++i)
    for (int j = 0; j <= 6; ++j)
      for (int k = 0; k <= 6; ++k) {
        const Vec3 t(0.03 + 0.94 * i / 6.0, 0.02 + 0.96 * j / 6.0, k / 6.0);
        const Vec3 x = lo + t.cwiseProduct(hi - lo);
        du = std::max(du, (a.displacement_at(x) - u_exact(x)).norm());
        ds = std::max(ds, (a.stress_at(x) - s_exact(x)).norm());
        umax = std::max(umax, u_exact(x).norm());
        smax = std::max(smax, s_exact(x).norm());
      }
  return {du / umax, ds / smax};
}

material::Voigt patch_strain() {
  Mat3 G;
  G << 2, 3, 4, -1, 2, 1, 3, -2, 0.5;
  return material::strain_from_gradient(1e-3 * G);
}

material::Voigt patch_stress() { return material::LinearElastic{1.0, 0.25}.stress(patch_strain()); }

std::string formulation_name(const ::testing::TestParamInfo<Formulation>& info) { return to_string(info.param); }

struct StrongCase {
  Formulation formulation;
  Real jitter;
};

class StrongFormPatchTest : public ::testing::TestWithParam<StrongCase> {};

TEST_P(StrongFormPatchTest, ReproducesTheLinearField) {
  const auto c = GetParam();
  EfgProblem p = patch_problem(6, c.jitter);
  p.options.formulation = c.formulation;
  p.options.mls.basis = mls::Basis::quadratic;
  p.options.mls.kappa = 2.5;
  EfgAnalysis a(p, {});
  a.solve();
  const auto [du, ds] = field_errors(a, Vec3::Zero(), Vec3::Ones(), linear_field_at, [](const Vec3&) { return patch_stress(); });
  EXPECT_LT(du, 1e-6);  // issue 3 acceptance 1: collocation and WLSM to 1e-6
  EXPECT_LT(ds, 1e-6);
  const Real energy = material::LinearElastic{1.0, 0.25}.energy_density(patch_strain());  // unit cube
  EXPECT_NEAR(a.internal_energy(), energy, 1e-6 * energy);
}

INSTANTIATE_TEST_SUITE_P(Formulations, StrongFormPatchTest,
                         ::testing::Values(StrongCase{Formulation::collocation, 0.0},
                                           StrongCase{Formulation::collocation, 0.25},
                                           StrongCase{Formulation::weighted_least_squares, 0.0},
                                           StrongCase{Formulation::weighted_least_squares, 0.25}),
                         [](const ::testing::TestParamInfo<StrongCase>& info) {
                           return to_string(info.param.formulation) + (info.param.jitter > 0 ? "_jittered" : "_regular");
                         });

TEST(StrongFormPatchTestAuxiliaryPoints, WeightedLeastSquaresWithCellCentresReproducesTheLinearField) {
  EfgProblem p = patch_problem(6, 0.25);
  p.options.formulation = Formulation::weighted_least_squares;
  p.options.least_squares.cell_centre_points = true;  // + 125 equilibrium points
  p.options.mls.kappa = 2.5;
  EfgAnalysis a(p, {});
  a.solve();
  EXPECT_EQ(a.timings().at("equations"), 3.0 * (216 + 125) + 3.0 * (216 - 64));  // equilibrium everywhere + boundary
  const auto [du, ds] = field_errors(a, Vec3::Zero(), Vec3::Ones(), linear_field_at, [](const Vec3&) { return patch_stress(); });
  EXPECT_LT(du, 1e-6);
  EXPECT_LT(ds, 1e-6);
}

TEST(NavierOperator, GivesDivSigmaOfAQuadraticField) {
  // u = (x^2 + y z, x y, z^2) reproduced exactly by a quadratic MLS basis:
  // div sigma = mu lap u + (lambda + mu) grad div u = (2 mu + 3 (lambda + mu), 0, 2 mu + 2 (lambda + mu))
  const PointCloud cloud = geometry::generate_volume_nodes(box(Vec3::Zero(), Vec3::Ones()), {6, 6, 6});
  mls::MlsOptions o;
  o.dimension = 3;
  o.basis = mls::Basis::quadratic;
  o.kappa = 2.5;
  const mls::MlsShapeFunctions shapes(cloud.positions, o, cloud.spacing);
  Eigen::VectorXd u(3 * cloud.size());
  for (Index i = 0; i < cloud.size(); ++i) {
    const Vec3 x = cloud.positions.col(i);
    u.segment<3>(3 * i) = Vec3(x[0] * x[0] + x[1] * x[2], x[0] * x[1], x[2] * x[2]);
  }
  const material::LinearElastic m{3.0, 0.3};
  const Vec3 expected(2 * m.mu() + 3 * (m.lambda() + m.mu()), 0.0, 2 * m.mu() + 2 * (m.lambda() + m.mu()));
  for (const Vec3& x : {Vec3(0.5, 0.5, 0.5), Vec3(0.13, 0.71, 0.4), Vec3(0.0, 1.0, 0.3)}) {
    const auto sv = shapes.evaluate(x, 2);
    const auto N = navier_operator(sv, m);
    Eigen::VectorXd local(3 * static_cast<Index>(sv.neighbours.size()));
    for (std::size_t k = 0; k < sv.neighbours.size(); ++k) local.segment<3>(3 * static_cast<Index>(k)) = u.segment<3>(3 * sv.neighbours[k]);
    const Vec3 div_sigma = N * local;
    EXPECT_LT((div_sigma - expected).norm(), 1e-8 * expected.norm()) << x.transpose();
  }
}

class StrongFormQuadraticTest : public ::testing::TestWithParam<Formulation> {};

TEST_P(StrongFormQuadraticTest, QuadraticFieldWithBodyForceIsExact) {
  // the strong forms are exact for fields in the basis: u = 1e-3 (x^2 + y z, x y, z^2) on the
  // boundary, body force b = -div sigma (E = 1, nu = 0.25: lambda = mu = 0.4)
  EfgProblem p = make_problem(box(Vec3::Zero(), Vec3::Ones()), {6, 6, 6}, 1.0, 0.25);
  p.options.formulation = GetParam();
  p.options.mls.basis = mls::Basis::quadratic;
  p.options.mls.kappa = 2.5;
  model::Constraint c;
  c.select = where("x < 1e-9 or x > 1 - 1e-9 or y < 1e-9 or y > 1 - 1e-9 or z < 1e-9 or z > 1 - 1e-9", p.cloud);
  c.fixed = {true, true, true};
  c.displacement = {field("1e-3*(x^2 + y*z)"), field("1e-3*x*y"), field("1e-3*z^2")};
  p.constraints.push_back(c);
  model::Load b;
  b.kind = model::Load::Kind::body_force;
  b.select.spec.kind = geometry::SelectionSpec::Kind::all;
  b.select.label = "all";
  for (Index i = 0; i < p.cloud.size(); ++i) b.select.nodes.push_back(i);
  b.vector = {constant(-3.2e-3), constant(0.0), constant(-2.4e-3)};
  p.loads.push_back(b);
  EfgAnalysis a(p, {});
  a.solve();
  const material::LinearElastic m{1.0, 0.25};
  auto u_exact = [](const Vec3& x) { return Vec3(1e-3 * (x[0] * x[0] + x[1] * x[2]), 1e-3 * x[0] * x[1], 1e-3 * x[2] * x[2]); };
  auto s_exact = [&](const Vec3& x) {
    Mat3 G;
    G << 2 * x[0], x[2], x[1], x[1], x[0], 0, 0, 0, 2 * x[2];
    return m.stress(material::strain_from_gradient(1e-3 * G));
  };
  const auto [du, ds] = field_errors(a, Vec3::Zero(), Vec3::Ones(), u_exact, s_exact);
  EXPECT_LT(du, 1e-6);
  EXPECT_LT(ds, 1e-6);
}

INSTANTIATE_TEST_SUITE_P(Formulations, StrongFormQuadraticTest,
                         ::testing::Values(Formulation::collocation, Formulation::weighted_least_squares), formulation_name);

/// Bar [0,4] x [0,2] x [0,2], E = 1e4, nu = 1/3, traction 1 in +x on x = 4, 13 x 5 x 5 nodes.
EfgProblem bar_problem(Formulation formulation, bool clamped) {
  EfgProblem p = make_problem(box(Vec3::Zero(), Vec3(4, 2, 2)), {13, 5, 5}, 1e4, 1.0 / 3.0);
  p.options.formulation = formulation;
  p.options.mls.basis = mls::Basis::quadratic;
  p.options.mls.kappa = 2.5;
  p.options.essential = EssentialMethod::nitsche;
  p.options.correction = IntegrationCorrection::vci;
  auto condition = [&](const std::string& set_name, std::array<bool, 3> constrained) {
    model::Constraint c;
    c.select = set(set_name, p.cloud);
    for (std::size_t a = 0; a < 3; ++a) c.fixed[a] = constrained[a];
    p.constraints.push_back(c);
  };
  if (clamped) {
    condition("xmin", {true, true, true});
  } else {
    condition("xmin", {true, false, false});
    condition("ymin", {false, true, false});
    condition("zmin", {false, false, true});
  }
  model::Load t;
  t.kind = model::Load::Kind::traction;
  t.select = set("xmax", p.cloud);
  t.vector = {constant(1.0), constant(0.0), constant(0.0)};
  p.loads.push_back(t);
  return p;
}

class StrongFormBarTest : public ::testing::TestWithParam<Formulation> {};

TEST_P(StrongFormBarTest, UniaxialTensionWithSymmetryConditionsIsExact) {
  // mixed rows (one constrained component + traction rows) on the symmetry faces, edge normals
  EfgAnalysis a(bar_problem(GetParam(), false), {});
  a.solve();
  auto u_exact = [](const Vec3& x) { return Vec3(1e-4 * x[0], -1e-4 / 3 * x[1], -1e-4 / 3 * x[2]); };
  auto s_exact = [](const Vec3&) {
    material::Voigt s = material::Voigt::Zero();
    s[0] = 1.0;
    return s;
  };
  const auto [du, ds] = field_errors(a, Vec3::Zero(), Vec3(4, 2, 2), u_exact, s_exact);
  EXPECT_LT(du, 1e-6);
  EXPECT_LT(ds, 1e-6);
  // reaction on x = 0 from the traction sigma(u^h) n there: -4
  EXPECT_NEAR(a.reaction(a.problem().constraints[0].select.nodes).x(), -4.0, 1e-5);
  EXPECT_NEAR(a.internal_energy(), 8e-4, 1e-9);
}

INSTANTIATE_TEST_SUITE_P(Formulations, StrongFormBarTest,
                         ::testing::Values(Formulation::collocation, Formulation::weighted_least_squares), formulation_name);

TEST(StrongFormBarLoads, PressureOnAWhereSelectionLoadsOnlyItsFace) {
  // the load as a negative pressure on `where: x > 4 - 1e-9`: the selection also holds at the edge
  // nodes of the side faces, which must stay traction-free (see strong_form_nodes)
  for (Formulation f : {Formulation::collocation, Formulation::weighted_least_squares}) {
    EfgProblem p = bar_problem(f, false);
    p.loads.clear();
    model::Load load;
    load.kind = model::Load::Kind::pressure;
    load.select = where("x > 4 - 1e-9", p.cloud);
    load.scalar = constant(-1.0);
    p.loads.push_back(load);
    EfgAnalysis a(p, {});
    a.solve();
    EXPECT_NEAR(a.displacement_at(Vec3(4, 2, 2)).x(), 4e-4, 1e-6 * 4e-4) << to_string(f);
    EXPECT_NEAR(a.displacement_at(Vec3(4, 2, 2)).y(), -2e-4 / 3, 1e-6 * 4e-4) << to_string(f);
    EXPECT_NEAR(a.stress_at(Vec3(3.9, 1.9, 0.1))[0], 1.0, 1e-6) << to_string(f);
  }
}

TEST(StrongFormCurvedFaces, RoundBarInTensionIsExact) {
  // solid cylinder (radius 1, length 4, axis x): the exact uniaxial field prescribed on end0, unit
  // traction on end1 (its centre node sits on the collapsed axis), the curved outer face free
  const geometry::GeometrySpec g = cylinder_spec(1.0, 4.0, 0);
  for (Formulation f : {Formulation::collocation, Formulation::weighted_least_squares}) {
    EfgProblem p = make_problem(g, {4, 12, 9}, 1e4, 0.25);
    p.options.formulation = f;
    p.options.mls.kappa = 2.5;
    model::Constraint c;
    c.select = set("end0", p.cloud);
    c.fixed = {true, true, true};
    c.displacement = {field("1e-4*x"), field("-0.25e-4*y"), field("-0.25e-4*z")};
    p.constraints.push_back(c);
    model::Load t;
    t.kind = model::Load::Kind::traction;
    t.select = set("end1", p.cloud);
    t.vector = {constant(1.0), constant(0.0), constant(0.0)};
    p.loads.push_back(t);
    EfgAnalysis a(p, {});
    a.solve();
    for (const Vec3& x : {Vec3(4, 0, 0), Vec3(2, 0.7, 0.7), Vec3(3.3, -0.2, 0.95)}) {
      EXPECT_LT((a.displacement_at(x) - Vec3(1e-4 * x[0], -0.25e-4 * x[1], -0.25e-4 * x[2])).norm(), 1e-6 * 4e-4)
          << to_string(f) << " at " << x.transpose();
      material::Voigt s = material::Voigt::Zero();
      s[0] = 1.0;
      EXPECT_LT((a.stress_at(x) - s).norm(), 1e-6) << to_string(f) << " at " << x.transpose();
    }
  }
}

/// Largest |sxx - 1| on the axis (y = z = 1) and on an edge (y = z = 2) at the node planes
/// x = 2 .. 4, one section width and more from the clamped end.
Real far_stress_error(const EfgAnalysis& a) {
  Real e = 0;
  for (int i = 6; i <= 12; ++i)
    for (const Vec3& x : {Vec3(i / 3.0, 1, 1), Vec3(i / 3.0, 2, 2)}) e = std::max(e, std::abs(a.stress_at(x)[0] - 1.0));
  return e;
}

TEST(StrongFormClampedBar, DegradesWhereGalerkinStaysAccurate) {
  // seed 004 section 3.3.2 / fig 3-11: with a fully clamped end only EFG (Galerkin) stays accurate
  EfgAnalysis galerkin(bar_problem(Formulation::galerkin, true), {});
  galerkin.solve();
  EfgAnalysis collocation(bar_problem(Formulation::collocation, true), {});
  collocation.solve();
  EfgAnalysis wlsm(bar_problem(Formulation::weighted_least_squares, true), {});
  wlsm.solve();
  const Real eg = far_stress_error(galerkin), ec = far_stress_error(collocation), ew = far_stress_error(wlsm);
  EXPECT_LT(eg, 0.02);       // issue 3 acceptance 2: within 2 % of P/A away from the clamped end
  EXPECT_GT(ec, 2.0 * eg);   // the strong forms are clearly worse (measured: 1.9 %, 6.7 %, 48 %)
  EXPECT_GT(ew, 2.0 * eg);
  // the reaction on the clamped face balances P = 4 in Galerkin, not in the strong forms
  const IndexList& clamped = galerkin.problem().constraints[0].select.nodes;
  EXPECT_NEAR(galerkin.reaction(clamped).x(), -4.0, 0.01 * 4.0);
  EXPECT_GT(std::abs(collocation.reaction(clamped).x() + 4.0), 0.1 * 4.0);
  EXPECT_GT(std::abs(wlsm.reaction(clamped).x() + 4.0), 0.1 * 4.0);
}

TEST(StrongFormDeterminism, SameSolutionOnOneAndTwoThreadsAndOnRepeat) {
  // the clamped plate quarter with a patch pressure (an unsymmetric-looking, non-trivial case)
  auto solve_with = [](Formulation f, int threads) {
    const int saved = omp_get_max_threads();
    omp_set_num_threads(threads);
    EfgProblem p = clamped_plate_quarter({9, 9, 3}, 0.3, 8.7, false);
    p.options.formulation = f;
    p.options.mls.kappa = 2.5;
    EfgAnalysis a(p, {});
    a.solve();
    omp_set_num_threads(saved);
    return Eigen::VectorXd(a.nodal_parameters());
  };
  for (Formulation f : {Formulation::collocation, Formulation::weighted_least_squares}) {
    const Eigen::VectorXd one = solve_with(f, 1), two = solve_with(f, 2), again = solve_with(f, 2);
    EXPECT_EQ((two - again).cwiseAbs().maxCoeff(), 0.0) << to_string(f);  // bitwise repeatable
    // summation order only, amplified by the condition number: collocation (no thread-dependent
    // sums) 1e-10; WLSM normal equations (condition ~ square of the rows') measured 8e-8 -> 1e-6
    EXPECT_LT((one - two).norm(), (f == Formulation::collocation ? 1e-10 : 1e-6) * one.norm()) << to_string(f);
    EXPECT_GT(one.norm(), 0.0);
  }
}

TEST(StrongFormErrors, LinearBasisPointForceAndSeveralMaterialsAreInputErrors) {
  EfgProblem p = patch_problem(5, 0.0);
  p.options.formulation = Formulation::collocation;
  p.options.mls.basis = mls::Basis::linear;
  EXPECT_THROW(EfgAnalysis(p, {}), InputError);

  p.options.mls.basis = mls::Basis::quadratic;
  p.options.mls.kappa = 2.5;
  model::Load f;
  f.kind = model::Load::Kind::force;
  f.select = set("xmax", p.cloud);
  f.vector = {constant(1.0), constant(0.0), constant(0.0)};
  p.loads.push_back(f);
  EfgAnalysis with_force(p, {});
  EXPECT_THROW(with_force.solve(), InputError);

  p.loads.clear();
  p.materials.push_back(p.materials.front());
  EXPECT_THROW(EfgAnalysis(p, {}), InputError);
}

TEST(StrongFormErrors, FreeRigidBodyMotionIsAnAnalysisError) {
  // a cube pulled on x = 1 with u_x = 0 on x = 0 only: translations y, z and rotation about x stay free
  for (Formulation f : {Formulation::collocation, Formulation::weighted_least_squares}) {
    EfgProblem p = make_problem(box(Vec3::Zero(), Vec3::Ones()), {5, 5, 5}, 1.0, 0.25);
    p.options.formulation = f;
    p.options.mls.kappa = 2.5;
    fix_set(p, "xmin", {true, false, false});
    traction_on_set(p, "xmax", Vec3(1, 0, 0));
    EfgAnalysis a(p, {});
    EXPECT_THROW(a.solve(), AnalysisError) << to_string(f);
  }
}

TEST(StrongFormRigidBodyCheck, AcceptsThreeSymmetryPlanesAndRejectsOneFixedPoint) {
  std::vector<StrongFormPoint> points;
  auto point = [&](const Vec3& x, std::array<bool, 3> constrained) {
    StrongFormPoint p;
    p.x = x;
    p.constrained = constrained;
    points.push_back(p);
  };
  point(Vec3(0, 0, 0), {true, true, true});
  EXPECT_THROW(require_no_free_rigid_body_motion(points), AnalysisError);  // rotations about the point
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) {
      point(Vec3(0, i, j), {true, false, false});
      point(Vec3(i, 0, j), {false, true, false});
      point(Vec3(i, j, 0), {false, false, true});
    }
  EXPECT_NO_THROW(require_no_free_rigid_body_motion(points));
}

TEST(WeightedLeastSquares, SeedPenaltyWeights) {
  // alpha = beta [E / (1 - nu^2)]^2 (seed 004 section 1.2.2 (5))
  EXPECT_DOUBLE_EQ(seed_displacement_weight(1e5, material::LinearElastic{1e4, 0.3}), 1e5 * std::pow(1e4 / (1 - 0.09), 2));
}

}  // namespace
}  // namespace lamina::efg
