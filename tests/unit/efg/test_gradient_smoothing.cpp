// Gradient smoothing over the background cells (efg.integration.correction: smoothed): the faces of
// every cell close, the linear and quadratic patch tests hold on jittered nodes and the smoothed system
// stays symmetric, and on a curved body (mapped cells) the patch test and the reaction balance hold
// where plain Gauss points miss them (galerkin_assembly.hpp, docs/efg.md section 6).
#include <gtest/gtest.h>

#include <cmath>

#include "efg/background_quadrature.hpp"
#include "geometry/body_maps.hpp"

#include "efg_test_helpers.hpp"

namespace lamina::efg {
namespace {

using namespace testing;

BackgroundCells cells_of(const geometry::GeometrySpec& g, const std::array<int, 3>& counts) {
  return make_background_cells(geometry::make_volume_map(g), counts);
}

// Box cells: the divergence theorem for q = 1, x, y, z holds on each cell's faces to round-off
// (sum_f w n = 0, sum_f w n_a x_b = V delta_ab), and over all cells the interior faces cancel.
TEST(CellFaces, EveryBoxCellIsClosedAndInteriorFacesCancel) {
  const BackgroundCells cells = cells_of(box(Vec3::Zero(), Vec3(4, 2, 1)), {4, 2, 3});
  const CellFaceQuadrature q = cell_face_quadrature(cells, {2, 2, 2});
  const VolumeQuadrature volume = volume_quadrature(cells, {2, 2, 2});
  ASSERT_EQ(q.cell_begin.size(), static_cast<std::size_t>(cells.size() + 1));
  Mat3 total = Mat3::Zero();
  for (Index c = 0; c < cells.size(); ++c) {
    Vec3 closure = Vec3::Zero();
    Mat3 first = Mat3::Zero();  // sum_f w n_a x_b
    for (Index f = q.cell_begin[static_cast<std::size_t>(c)]; f < q.cell_begin[static_cast<std::size_t>(c + 1)]; ++f) {
      const Vec3 wn = q.faces.weights[f] * q.faces.normals.col(f);
      closure += wn;
      first += wn * q.faces.points.col(f).transpose();
    }
    const Real v = volume.weights.segment(volume.cell_begin[static_cast<std::size_t>(c)], 8).sum();
    EXPECT_LT(closure.norm(), 1e-13);
    EXPECT_LT((first - v * Mat3::Identity()).norm(), 1e-12);
    total += first;
  }
  // sum over the cells = the boundary integral of n x^T = body volume x I
  EXPECT_LT((total - 8.0 * Mat3::Identity()).norm(), 1e-11);
}

/// Largest relative error of u^h and sigma^h against a field at points inside the unit cube.
template <class Field, class Stress>
std::pair<Real, Real> field_errors(const EfgAnalysis& a, Field exact, Stress exact_stress) {
  Real du = 0, ds = 0, umax = 0, smax = 0;
  for (int i = 0; i <= 5; ++i)
    for (int j = 0; j <= 5; ++j)
      for (int k = 0; k <= 5; ++k) {
        const Vec3 x(0.05 + 0.18 * i, 0.03 + 0.19 * j, 0.01 + 0.196 * k);
        du = std::max(du, (a.displacement_at(x) - exact(x)).norm());
        ds = std::max(ds, (a.stress_at(x) - exact_stress(x)).norm());
        umax = std::max(umax, exact(x).norm());
        smax = std::max(smax, exact_stress(x).norm());
      }
  return {du / umax, ds / smax};
}

// Linear patch test on jittered nodes, linear and quadratic bases, Nitsche: exact with smoothing (and a
// symmetric system, solved by Cholesky), 1e-3-ish off with plain Gauss points.
TEST(SmoothedPatchTest, LinearFieldOnJitteredNodesIsExactAndSymmetric) {
  const material::LinearElastic mat{1.0, 0.25};
  Mat3 G;
  G << 2, 3, 4, -1, 2, 1, 3, -2, 0.5;
  G *= 1e-3;
  const material::Voigt stress = mat.stress(material::strain_from_gradient(G));
  for (const mls::Basis basis : {mls::Basis::linear, mls::Basis::quadratic}) {
    for (const bool smoothed : {false, true}) {
      EfgProblem p = patch_problem(6, 0.25);
      p.options.mls.basis = basis;
      p.options.mls.kappa = basis == mls::Basis::linear ? 2.0 : 2.5;
      p.options.essential = EssentialMethod::nitsche;
      p.options.correction = smoothed ? IntegrationCorrection::smoothed : IntegrationCorrection::none;
      EfgAnalysis a(p, {});
      a.solve();
      const auto [du, ds] = field_errors(a, linear_field_at, [&](const Vec3&) { return stress; });
      if (smoothed) {
        EXPECT_LT(du, 1e-10);
        EXPECT_LT(ds, 1e-9);
        // symmetric: a Cholesky factorisation (dense for this small, nearly full K), not the LDLT fallback
        EXPECT_EQ(a.timings().at("solver_cholmod") + a.timings().at("solver_dense"), 1.0);
      } else {
        EXPECT_GT(ds, 1e-5);  // the quadrature error the smoothing removes
      }
    }
  }
}

// Quadratic patch test: u = 1e-3 (x^2, y z, 0) with its body force b = -div sigma (constant) on jittered
// nodes, quadratic basis: exact with smoothing (the smoothed gradients are linear in each cell and the
// divergence identity holds for linear stresses), not with plain Gauss points.
TEST(SmoothedPatchTest, QuadraticFieldWithBodyForceIsExact) {
  const Real E = 1.0, nu = 0.25;
  const material::LinearElastic mat{E, nu};
  const Real lambda = mat.lambda(), mu = mat.mu();
  auto exact = [](const Vec3& x) { return Vec3(1e-3 * x[0] * x[0], 1e-3 * x[1] * x[2], 0.0); };
  auto gradient = [](const Vec3& x) {
    Mat3 G = Mat3::Zero();
    G(0, 0) = 2e-3 * x[0];
    G(1, 1) = 1e-3 * x[2];
    G(1, 2) = 1e-3 * x[1];
    return G;
  };
  auto stress = [&](const Vec3& x) { return mat.stress(material::strain_from_gradient(gradient(x))); };
  // div sigma with sigma = lambda tr(eps) I + 2 mu eps, tr(eps) = 2e-3 x + 1e-3 z, 2 eps_yz = 1e-3 y:
  // x: 2e-3 (lambda + 2 mu), y: 0, z: 1e-3 (lambda + mu)
  const Vec3 body = -Vec3(2e-3 * (lambda + 2.0 * mu), 0.0, 1e-3 * lambda + 1e-3 * mu);
  for (const bool smoothed : {false, true}) {
    EfgProblem p = patch_problem(6, 0.25);  // jittered unit cube, E = 1, nu = 0.25, the whole boundary held
    p.constraints.front().displacement = {field("1e-3*x*x"), field("1e-3*y*z"), field("0")};
    model::Load b;
    b.kind = model::Load::Kind::body_force;
    b.select = where("x > -1", p.cloud);
    b.vector = {constant(body[0]), constant(body[1]), constant(body[2])};
    p.loads.push_back(b);
    p.options.mls.basis = mls::Basis::quadratic;
    p.options.mls.kappa = 2.5;
    p.options.essential = EssentialMethod::nitsche;
    p.options.correction = smoothed ? IntegrationCorrection::smoothed : IntegrationCorrection::none;
    EfgAnalysis a(p, {});
    a.solve();
    const auto [du, ds] = field_errors(a, exact, stress);
    if (smoothed) {
      EXPECT_LT(du, 1e-9);
      EXPECT_LT(ds, 1e-8);
    } else {
      EXPECT_GT(du, 1e-5);
    }
  }
}

// Thick ring r = 3..5 (quarter, plane strain through fixed z faces) with the same pressure inside and
// out: uniform stress -p, u_r = eps r. Mapped (curved) cells: plain Gauss points are 1e-2 off on the
// 5 x 9 x 3 nodes, the smoothed gradients 1e-4 (the remaining error is the mapped cells' quadrature of
// linear fields, 5e-6 on 9 x 17 x 3). The reaction on each symmetry face balances the load exactly.
TEST(SmoothedCurvedBody, HydrostaticRingPassesThePatchTestAndBalances) {
  geometry::GeometrySpec g = curved_beam_spec();
  g.z_range = {0.0, 1.0};
  const Real E = 1e4, nu = 0.3, pressure = 1.0;
  const Real eps = -(1 + nu) * (1 - 2 * nu) / E * pressure;  // plane strain, sigma_rr = sigma_tt = -p
  Vec3 reactions[2];
  for (const bool smoothed : {false, true}) {
    EfgProblem p = make_problem(g, {5, 9, 3}, E, nu);
    fix_set(p, "start", {false, true, false});
    fix_set(p, "end", {true, false, false});
    model::Constraint z;
    z.select = where("z < 1e-9 or z > 1 - 1e-9", p.cloud);
    z.fixed = {false, false, true};
    p.constraints.push_back(z);
    for (const char* face : {"inner", "outer"}) {
      model::Load load;
      load.kind = model::Load::Kind::pressure;
      load.select = set(face, p.cloud);
      load.scalar = constant(pressure);
      p.loads.push_back(load);
    }
    p.options.essential = EssentialMethod::nitsche;
    p.options.correction = smoothed ? IntegrationCorrection::smoothed : IntegrationCorrection::none;
    EfgAnalysis a(p, {});
    a.solve();
    Real error = 0.0;
    for (const Real r : {3.0, 3.5, 4.0, 4.5, 5.0})
      for (const Real angle : {0.0, 0.3, 0.785398, 1.2, 1.570796}) {
        const Vec3 x(r * std::cos(angle), r * std::sin(angle), 0.5);
        error = std::max(error, (a.displacement_at(x) - eps * Vec3(x[0], x[1], 0.0)).norm() / std::abs(eps * 5.0));
      }
    reactions[smoothed ? 1 : 0] = a.reaction({});
    if (smoothed) EXPECT_LT(error, 3e-4);
    else EXPECT_GT(error, 3e-3);
  }
  // All reactions balance the (discrete) pressure loads, p (b - a) = 2 per unit length along -x and -y,
  // with and without smoothing: a rigid translation strains no cell.
  EXPECT_LT((reactions[1] - reactions[0]).norm(), 1e-10);
  EXPECT_NEAR(reactions[1][1], 2.0, 1e-6);
}

// The default (automatic) smooths where the nodes are not the cells' grid (jittered nodes) and where the
// cells are curved but turn by at most 35 degrees; it keeps Gauss points on the generators' regular grids
// of flat bodies, on coarse polar cells (8 sectors of 45 degrees) and with a single Gauss point.
TEST(SmoothedOptions, TheDefaultSmoothsIrregularNodesAndCurvedCells) {
  auto resolved = [](EfgProblem p) -> Real {
    EXPECT_EQ(p.options.correction, IntegrationCorrection::automatic);
    EfgAnalysis a(p, {});
    a.solve();
    return a.timings().at("integration_smoothed");
  };
  EXPECT_EQ(resolved(patch_problem(5, 0.0)), 0.0);
  EXPECT_EQ(resolved(patch_problem(6, 0.25)), 1.0);
  EfgProblem single = patch_problem(6, 0.25);
  single.options.gauss = {1, 1, 1};
  single.options.mls.basis = mls::Basis::linear;
  EXPECT_EQ(resolved(single), 0.0);
  EfgProblem ring = make_problem(curved_beam_spec(), {5, 9, 3}, 1e4, 0.3);  // quarter ring, cells of 11.25 deg
  fix_set(ring, "start");
  traction_on_set(ring, "end", Vec3(0.0, -1.0, 0.0));
  EXPECT_EQ(resolved(ring), 1.0);
  EfgProblem tube = make_problem(cylinder_spec(1.0, 10.0, 0, 0.4), {3, 8, 11}, 1e4, 0.3);  // 8 sectors of 45 deg
  fix_set(tube, "end0");
  traction_on_set(tube, "end1", Vec3(0.0, -1.0, 0.0));
  EXPECT_EQ(resolved(tube), 0.0);
}

// The turn of the cells: zero on a box, the sector's angle on polar cells; a solid cylinder's cells at the
// axis (collapsed edges) count their other edges.
TEST(CellTurn, IsZeroOnABoxAndTheSectorAngleOnPolarCells) {
  const Real degree = M_PI / 180.0;
  EXPECT_NEAR(largest_cell_turn(cells_of(box(Vec3::Zero(), Vec3(4, 2, 1)), {4, 2, 2})), 0.0, 1e-12);
  EXPECT_NEAR(largest_cell_turn(cells_of(curved_beam_spec(), {2, 8, 1})), 11.25 * degree, 1e-9);
  EXPECT_NEAR(largest_cell_turn(cells_of(cylinder_spec(1.0, 10.0, 0, 0.4), {2, 8, 4})), 45.0 * degree, 1e-9);
  EXPECT_NEAR(largest_cell_turn(cells_of(cylinder_spec(1.0, 10.0, 0), {2, 12, 4})), 30.0 * degree, 1e-9);
}

// Points on the body's edges and corners (here the free edge at the diaphragm of the Scordelis-Lo roof on
// 3 x 9 x 9 nodes, a polar layout with box kappa 2) leave A singular with the user's support: the boundary
// points grow their support (SINCHECK) and the run goes through (it stopped with exit 2 before 2026-12-05).
TEST(SmoothedOptions, BoundaryPointsOfAPolarLayoutGrowTheirSupport) {
  geometry::GeometrySpec g = cylinder_spec(25.0, 25.0, 1, 0.25);
  g.angle_deg = 40.0;
  EfgProblem p = make_problem(g, {3, 9, 9}, 4.32e8, 0.0);
  fix_set(p, "end0", {true, false, true});
  fix_set(p, "end1", {false, true, false});
  fix_set(p, "edge0", {true, false, false});
  model::Load gravity;
  gravity.kind = model::Load::Kind::body_force;
  gravity.select = where("1", p.cloud);
  gravity.vector = {constant(0.0), constant(0.0), constant(-360.0)};
  p.loads.push_back(gravity);
  ASSERT_FALSE(p.options.mls.singular_remedy);
  EfgAnalysis a(p, {});
  ASSERT_NO_THROW(a.solve());
  // coarse (9 nodes along 40 deg): within 10 % of MacNeal-Harder's 0.3024 (measured 0.940)
  const Vec3 free_edge(25.0 * std::sin(40.0 * M_PI / 180.0), 25.0, 25.0 * std::cos(40.0 * M_PI / 180.0));
  EXPECT_NEAR(a.displacement_at(free_edge)[2] / -0.3024, 1.0, 0.10);
}

TEST(SmoothedOptions, ProjectedVolumetricIsRefused) {
  EfgProblem p = clamped_plate_quarter({5, 5, 3}, 0.3, 9.5, true);
  p.options.projected_volumetric = true;
  p.options.correction = IntegrationCorrection::smoothed;
  EXPECT_THROW(EfgAnalysis(p, {}), InputError);
}

}  // namespace
}  // namespace lamina::efg
