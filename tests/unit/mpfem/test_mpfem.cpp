// Unit tests of the MPFEM family (seed 001): five-node particle elements (Kronecker delta,
// partition of unity, linear reproduction, rebuild from moved particles), quadrature weights
// and the integration constraint, the patch test, cantilever convergence rates, degenerate sets.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <random>

#include "core/error.hpp"
#include "mpfem/mpfem_analysis.hpp"
#include "mpfem/plate_with_hole.hpp"
#include "mpfem/tributary_cells.hpp"

namespace lamina::mpfem {
namespace {

/// n0 x n1 grid particles on [0, width] x [0, height], interior particles moved by up to
/// jitter x spacing per direction.
ParticleLayout grid_layout(int n0, int n1, Real width, Real height, Real jitter, unsigned seed = 1) {
  ParticleLayout layout;
  layout.grid = LogicalGrid{n0, n1, false};
  layout.positions.resize(2, static_cast<Index>(n0) * n1);
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<Real> uniform(-1.0, 1.0);
  const Real hx = width / (n0 - 1), hy = height / (n1 - 1);
  for (int j = 0; j < n1; ++j)
    for (int i = 0; i < n0; ++i) {
      Vec2 p(i * hx, j * hy);
      if (i > 0 && i + 1 < n0) p.x() += jitter * hx * uniform(random);
      if (j > 0 && j + 1 < n1) p.y() += jitter * hy * uniform(random);
      layout.positions.col(i + static_cast<Index>(n0) * j) = p;
    }
  return layout;
}

void expect_interpolating_linear_basis(const ParticleDiscretization& d, const Points2& x, Real width, Real height) {
  // Kronecker delta at every particle
  for (Index p = 0; p < x.cols(); ++p) {
    const auto values = shape_functions_at(d, x, x.col(p));
    ASSERT_FALSE(values.empty());
    for (const auto& v : values) EXPECT_NEAR(v.value, v.particle == p ? 1.0 : 0.0, 1e-12) << "particle " << p;
  }
  // partition of unity and linear reproduction at random points of the body
  std::mt19937_64 random(5);
  std::uniform_real_distribution<Real> ux(0.0, width), uy(0.0, height);
  int evaluated = 0;
  for (int k = 0; k < 200; ++k) {
    const Vec2 point(ux(random), uy(random));
    const auto values = shape_functions_at(d, x, point);
    if (values.empty()) continue;
    ++evaluated;
    Real sum = 0;
    Vec2 reproduced = Vec2::Zero(), gradient_sum = Vec2::Zero();
    Eigen::Matrix2d gradient_of_x = Eigen::Matrix2d::Zero();
    for (const auto& v : values) {
      sum += v.value;
      reproduced += v.value * x.col(v.particle);
      gradient_sum += v.gradient;
      gradient_of_x += x.col(v.particle) * v.gradient.transpose();
    }
    EXPECT_NEAR(sum, 1.0, 1e-12);
    EXPECT_NEAR((reproduced - point).norm(), 0.0, 1e-12);
    EXPECT_NEAR(gradient_sum.norm(), 0.0, 1e-10);
    EXPECT_NEAR((gradient_of_x - Eigen::Matrix2d::Identity()).norm(), 0.0, 1e-10);
  }
  EXPECT_GT(evaluated, 150);  // the body is covered by the elements
}

TEST(mpfem_elements, InterpolatingPartitionOfUnityLinearOnJitteredGrid) {
  const ParticleLayout layout = grid_layout(9, 6, 2.0, 1.0, 0.3);
  const ParticleDiscretization d = build_particle_elements(layout, ElementOptions{});
  expect_interpolating_linear_basis(d, layout.positions, 2.0, 1.0);
  // element sizes: 4 triangles inside, 2 on an edge, 1 at a corner
  EXPECT_EQ(d.elements[0].triangle_count, 1);
  EXPECT_EQ(d.elements[1].triangle_count, 2);
  EXPECT_EQ(d.elements[static_cast<std::size_t>(1 + 9)].triangle_count, 4);
}

TEST(mpfem_elements, WeightsSumToAreaAndPerimeter) {
  const ParticleLayout layout = grid_layout(11, 7, 3.0, 2.0, 0.3, 4);
  const ParticleDiscretization d = build_particle_elements(layout, ElementOptions{});
  EXPECT_NEAR(d.area_weight.sum(), 6.0, 1e-12);       // dV_I = A_I / 2 (star)
  EXPECT_NEAR(d.boundary_weight.sum(), 10.0, 1e-12);  // dS_I
  const TributaryCells cells = build_tributary_cells(layout);
  EXPECT_NEAR(cells.area.sum(), 6.0, 1e-12);
  for (const auto& m : cells.second_moment) EXPECT_GT(m.determinant(), 0.0);
}

TEST(mpfem_elements, CellStrainSatisfiesIntegrationConstraint) {
  // sum_I |Omega_I| B_I^J = boundary integral of phi_J n, for every particle J
  const ParticleLayout layout = grid_layout(8, 7, 2.0, 1.5, 0.3, 9);
  const ParticleDiscretization d = build_particle_elements(layout, ElementOptions{});
  const TributaryCells cells = build_tributary_cells(layout);
  const Index n = layout.positions.cols();
  Points2 volume_sum = Points2::Zero(2, n), boundary_sum = Points2::Zero(2, n);
  for (Index p = 0; p < n; ++p)
    for (const auto& [q, g] : cells.mean_gradient[static_cast<std::size_t>(p)]) volume_sum.col(q) += cells.area[p] * g;
  for (const auto& s : d.boundary) {
    boundary_sum.col(s.a) += 0.5 * s.length * s.normal;
    boundary_sum.col(s.b) += 0.5 * s.length * s.normal;
  }
  EXPECT_NEAR((volume_sum - boundary_sum).cwiseAbs().maxCoeff(), 0.0, 1e-13);
  // and the cell strain is exact for a linear field
  for (Index p = 0; p < n; ++p) {
    Eigen::Matrix2d g = Eigen::Matrix2d::Zero();
    for (const auto& [q, c] : cells.mean_gradient[static_cast<std::size_t>(p)]) g += layout.positions.col(q) * c.transpose();
    EXPECT_NEAR((g - Eigen::Matrix2d::Identity()).norm(), 0.0, 1e-12);
  }
}

TEST(mpfem_elements, RebuiltFromMovedParticles) {
  ParticleLayout layout = grid_layout(7, 5, 2.0, 1.0, 0.2, 2);
  // move the particles: rotation by 30 degrees, stretch, shift; rebuild
  Eigen::Matrix2d map;
  const Real c = std::cos(0.5236), s = std::sin(0.5236);
  map << 1.3 * c, -0.8 * s, 1.3 * s, 0.8 * c;
  Points2 moved = map * layout.positions;
  moved.colwise() += Vec2(3.0, -1.0);
  MpfemProblem problem;
  problem.layout = layout;
  problem.materials = {material::LinearElastic{1000.0, 0.3}};
  MpfemAnalysis analysis(problem, {});
  const Real area_before = analysis.total_volume();
  analysis.rebuild(moved);
  EXPECT_NEAR(analysis.total_volume(), area_before * std::abs(map.determinant()), 1e-12);
  for (Index p = 0; p < moved.cols(); ++p) {
    const auto values = shape_functions_at(analysis.discretization(), moved, moved.col(p));
    for (const auto& v : values) EXPECT_NEAR(v.value, v.particle == p ? 1.0 : 0.0, 1e-12);
  }
  const Vec2 inside = moved.col(2 + 7 * 2);
  const auto values = shape_functions_at(analysis.discretization(), moved, inside + Vec2(0.01, 0.02));
  Vec2 reproduced = Vec2::Zero();
  for (const auto& v : values) reproduced += v.value * moved.col(v.particle);
  EXPECT_NEAR((reproduced - inside - Vec2(0.01, 0.02)).norm(), 0.0, 1e-12);
}

/// Patch test problem: exact linear field, tractions on x = w, y = 0, y = h; x = 0 prescribed.
MpfemProblem patch_problem(const ParticleLayout& layout, Real width, Real height, PlaneKind plane) {
  MpfemProblem p;
  p.layout = layout;
  p.thickness = 0.1;
  p.materials = {material::LinearElastic{1000.0, 0.25}};
  p.options.plane = plane;
  p.options.exact_displacement = std::array<std::string, 2>{"1e-3*(1 + 2*x + 3*y)", "1e-3*(-1 + 1.5*x - y)"};
  const Eigen::Vector3d strain(2e-3, -1e-3, 4.5e-3);
  const Eigen::Vector3d stress = PlaneMaterial{p.materials[0], plane}.matrix() * strain;
  IndexList left, right, bottom, top;
  for (Index q = 0; q < layout.positions.cols(); ++q) {
    const Vec2 x = layout.positions.col(q);
    if (x.x() < 1e-12) left.push_back(q);
    if (x.x() > width - 1e-12) right.push_back(q);
    if (x.y() < 1e-12) bottom.push_back(q);
    if (x.y() > height - 1e-12) top.push_back(q);
  }
  for (Index q : left) {
    const Vec2 x = layout.positions.col(q);
    p.prescribed.push_back({q, 0, 1e-3 * (1 + 2 * x.x() + 3 * x.y())});
    p.prescribed.push_back({q, 1, 1e-3 * (-1 + 1.5 * x.x() - x.y())});
  }
  auto traction = [&](const IndexList& particles, Real tx, Real ty) {
    model::Load load;
    load.kind = model::Load::Kind::traction;
    load.select.nodes = particles;
    load.vector[0].constant = tx;
    load.vector[1].constant = ty;
    p.loads.push_back(load);
  };
  traction(right, stress[0], stress[2]);
  traction(bottom, -stress[2], -stress[1]);
  traction(top, stress[2], stress[1]);
  return p;
}

TEST(mpfem_analysis, PatchTestJitteredAllVariants) {
  const ParticleLayout layout = grid_layout(9, 7, 2.0, 1.0, 0.3, 7);
  for (ParticleStrain strain : {ParticleStrain::cell, ParticleStrain::star, ParticleStrain::voronoi})
    for (PlaneKind plane : {PlaneKind::stress, PlaneKind::strain}) {
      MpfemProblem problem = patch_problem(layout, 2.0, 1.0, plane);
      problem.options.particle_strain = strain;
      MpfemAnalysis analysis(problem, {});
      analysis.solve();
      EXPECT_LT(analysis.errors().max_displacement, 1e-10);
      EXPECT_LT(analysis.errors().max_stress, 1e-8);
      if (plane == PlaneKind::strain) {
        // sigma_zz = nu (sxx + syy) is reported through the stress probe
        Probe szz;
        szz.name = "szz";
        szz.field = "stress";
        szz.component = "zz";
        szz.at = Vec3(1.0, 0.5, 0.0);
        const Eigen::Vector3d s = analysis.particle_stress(0);
        MpfemAnalysis with_probe(problem, {szz});
        with_probe.solve();
        EXPECT_NEAR(with_probe.probe(szz), 0.25 * (s[0] + s[1]), 1e-10);
      }
    }
}

TEST(mpfem_analysis, PatchTestDetectsAWrongStiffness) {
  // the same patch with the wrong Poisson ratio in the tractions must fail: the test can fail
  const ParticleLayout layout = grid_layout(9, 7, 2.0, 1.0, 0.3, 7);
  MpfemProblem problem = patch_problem(layout, 2.0, 1.0, PlaneKind::stress);
  problem.materials[0].nu = 0.3;
  MpfemAnalysis analysis(problem, {});
  analysis.solve();
  EXPECT_GT(analysis.errors().max_displacement, 1e-4);
}

/// Timoshenko cantilever (L = 48, D = 12, E = 3e7, nu = 0.3, P = 1000), exact end displacements.
MpfemAnalysis::Errors cantilever(int n0, int n1, ElementKind element, Real& tip, Real& seconds) {
  MpfemProblem p;
  p.layout = grid_layout(n0, n1, 48.0, 12.0, 0.0);
  p.layout.positions.row(1).array() -= 6.0;
  p.materials = {material::LinearElastic{3e7, 0.3}};
  p.options.element = element;
  const std::string c = "1000/(6*3e7*144)";
  p.options.exact_displacement = std::array<std::string, 2>{
      "-" + c + "*y*((6*48-3*x)*x+(2+0.3)*(y^2-36))", c + "*(3*0.3*y^2*(48-x)+(4+5*0.3)*144*x/4+(3*48-x)*x^2)"};
  const Real k = 1000.0 / (6 * 3e7 * 144);
  model::Load load;
  load.kind = model::Load::Kind::traction;
  load.vector[1].expression = "1000/(2*144)*(36-y^2)";
  for (Index q = 0; q < p.layout.positions.cols(); ++q) {
    const Vec2 x = p.layout.positions.col(q);
    if (x.x() < 1e-9) {
      const Real y = x.y();
      p.prescribed.push_back({q, 0, -k * y * ((2 + 0.3) * (y * y - 36))});
      p.prescribed.push_back({q, 1, k * 3 * 0.3 * y * y * 48});
    }
    if (x.x() > 48 - 1e-9) load.select.nodes.push_back(q);
  }
  p.loads.push_back(load);
  MpfemAnalysis analysis(p, {});
  analysis.solve();
  tip = analysis.displacement_at(Vec2(48, 0)).y();
  seconds = analysis.timings().at("total_s");
  return analysis.errors();
}

TEST(mpfem_analysis, CantileverTipAndConvergenceRates) {
  const Real exact_tip = 0.0089;
  Real tip = 0, seconds = 0;
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);  // small systems: threads only contend
  cantilever(33, 9, ElementKind::five_node, tip, seconds);
  EXPECT_NEAR(tip / exact_tip, 1.0, 0.01);
  std::vector<MpfemAnalysis::Errors> errors;
  for (int r : {1, 2, 4, 8}) errors.push_back(cantilever(16 * r + 1, 4 * r + 1, ElementKind::five_node, tip, seconds));
  for (std::size_t k = 1; k < errors.size(); ++k) {
    const Real l2_rate = std::log2(errors[k - 1].l2 / errors[k].l2);
    const Real energy_rate = std::log2(errors[k - 1].energy / errors[k].energy);
    EXPECT_GE(l2_rate, 1.8) << "refinement " << k;
    EXPECT_GE(energy_rate, 0.9) << "refinement " << k;
  }
  omp_set_num_threads(threads);
}

TEST(mpfem_analysis, DeterministicAcrossThreadCounts) {
  const ParticleLayout layout = grid_layout(13, 9, 2.0, 1.0, 0.25, 3);
  MpfemProblem problem = patch_problem(layout, 2.0, 1.0, PlaneKind::stress);
  problem.loads[0].vector[1].constant = 5.0;  // not a patch field: a general solution
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  MpfemAnalysis one(problem, {});
  one.solve();
  omp_set_num_threads(std::max(2, threads));
  MpfemAnalysis many(problem, {});
  many.solve();
  omp_set_num_threads(threads);
  // the assembly is bitwise identical (the direct solver's BLAS may round differently)
  const solve::SparseMatrix difference = one.stiffness() - many.stiffness();
  EXPECT_EQ(one.stiffness().nonZeros(), many.stiffness().nonZeros());
  for (int c = 0; c < difference.outerSize(); ++c)
    for (solve::SparseMatrix::InnerIterator it(difference, c); it; ++it) EXPECT_EQ(it.value(), 0.0);
  for (Index p = 0; p < layout.positions.cols(); ++p)
    EXPECT_NEAR((one.displacement(p) - many.displacement(p)).norm(), 0.0, 1e-12 * one.displacement(p).norm() + 1e-15);
}

TEST(mpfem_analysis, PlateWithHoleGenerator) {
  PlateWithHoleSpec spec;
  spec.n_radial = 13;
  spec.n_angular = 17;
  spec.grading = 1.5;
  const GeneratedParticles g = generate_plate_with_hole(spec);
  EXPECT_NEAR(g.area.sum(), 25.0 - 3.14159265358979 / 4, 0.01);  // chords cut the arc: O(h^2)
  for (Index q : g.sets.at("hole")) EXPECT_NEAR(g.layout.positions.col(q).norm(), 1.0, 1e-12);
  EXPECT_EQ(g.sets.at("xmax").size() + g.sets.at("ymax").size(), 18u);  // the corner particle is in both
}

TEST(mpfem_degenerate, CoincidentAndLonelyParticlesAreInputErrors) {
  ParticleLayout layout = grid_layout(5, 4, 1.0, 1.0, 0.0);
  ElementOptions sectors;
  sectors.rule = NeighbourRule::sectors;
  ParticleLayout coincident = layout;
  coincident.grid.reset();
  coincident.positions.conservativeResize(2, layout.positions.cols() + 1);
  coincident.positions.col(layout.positions.cols()) = layout.positions.col(6);
  EXPECT_THROW(build_particle_elements(coincident, sectors), InputError);
  ParticleLayout lonely = layout;
  lonely.grid.reset();
  lonely.positions.conservativeResize(2, layout.positions.cols() + 1);
  lonely.positions.col(layout.positions.cols()) = Vec2(50, 50);
  EXPECT_THROW(build_particle_elements(lonely, sectors), InputError);
  ParticleLayout tangled = layout;
  tangled.positions.col(6) = tangled.positions.col(12) + Vec2(0.1, 0.1);  // pushed through its neighbour
  EXPECT_THROW(build_particle_elements(tangled, ElementOptions{}), InputError);
  ParticleLayout few;
  few.positions = Points2::Zero(2, 2);
  EXPECT_THROW(build_particle_elements(few, sectors), InputError);
  MpfemProblem no_grid;
  no_grid.layout = lonely;
  no_grid.layout.positions.conservativeResize(2, layout.positions.cols());
  no_grid.materials = {material::LinearElastic{1.0, 0.3}};
  no_grid.options.element = ElementKind::t3;
  EXPECT_THROW(MpfemAnalysis(no_grid, {}), InputError);
}

TEST(mpfem_degenerate, FreeRigidMotionIsAnAnalysisError) {
  const ParticleLayout layout = grid_layout(6, 4, 2.0, 1.0, 0.1);
  MpfemProblem problem = patch_problem(layout, 2.0, 1.0, PlaneKind::stress);
  std::vector<PrescribedDof> only_y;
  for (const auto& d : problem.prescribed)
    if (d.component == 1) only_y.push_back(d);
  problem.prescribed = only_y;
  MpfemAnalysis analysis(problem, {});
  EXPECT_THROW(analysis.solve(), AnalysisError);
}

}  // namespace
}  // namespace lamina::mpfem
