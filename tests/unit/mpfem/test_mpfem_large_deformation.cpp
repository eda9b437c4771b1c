// Unit tests of the MPFEM large-deformation analysis (docs/mpfem.md section 9) and of the shared
// hyperelastic kernel: consistent tangents by finite differences, the uniform-deformation patch test
// (exact for neo-Hookean), objectivity under a finite rotation, the small-load limit equal to the
// linear analysis, and neighbourhood rebuilds counted on a sheared sector-neighbour set.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/error.hpp"
#include "material/hyperelastic.hpp"
#include "mpfem/mpfem_analysis.hpp"

namespace lamina::mpfem {
namespace {

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

TEST(material_hyperelastic, TangentIsDerivativeOfStress) {
  const material::LinearElastic elastic{200.0, 0.35};
  Eigen::Matrix2d F;
  F << 1.2, 0.3, -0.15, 0.85;
  for (auto kind : {material::HyperelasticKind::neo_hookean, material::HyperelasticKind::saint_venant_kirchhoff})
    for (bool plane_stress : {false, true}) {
      const auto m = material::Hyperelastic::from(kind, elastic);
      const auto r = material::hyperelastic_response_2d(m, F, plane_stress);
      const Real h = 1e-6;
      for (int b = 0; b < 4; ++b) {
        Eigen::Matrix2d Fp = F, Fm = F;
        Fp(b / 2, b % 2) += h;
        Fm(b / 2, b % 2) -= h;
        const auto rp = material::hyperelastic_response_2d(m, Fp, plane_stress);
        const auto rm = material::hyperelastic_response_2d(m, Fm, plane_stress);
        EXPECT_NEAR((rp.energy - rm.energy) / (2 * h), r.stress(b / 2, b % 2), 1e-6 * 200);
        for (int a = 0; a < 4; ++a)
          EXPECT_NEAR((rp.stress(a / 2, a % 2) - rm.stress(a / 2, a % 2)) / (2 * h), r.tangent(a, b), 1e-5 * 200)
              << "kind " << static_cast<int>(kind) << " plane stress " << plane_stress << " entry " << a << b;
      }
      if (plane_stress) {
        Mat3 F3 = Mat3::Identity();
        F3.topLeftCorner<2, 2>() = F;
        F3(2, 2) = r.stretch33;
        EXPECT_NEAR(material::hyperelastic_response(m, F3).stress(2, 2), 0.0, 1e-9);
      }
      // small strains: the linear elasticity matrix
      const auto r0 = material::hyperelastic_response_2d(m, Eigen::Matrix2d::Identity(), plane_stress);
      const Real lambda = plane_stress ? 2 * m.mu * m.lambda / (m.lambda + 2 * m.mu) : m.lambda;
      EXPECT_NEAR(r0.tangent(0, 0), lambda + 2 * m.mu, 1e-9);
      EXPECT_NEAR(r0.tangent(0, 3), lambda, 1e-9);
      EXPECT_NEAR(r0.tangent(1, 1), m.mu, 1e-9);
      EXPECT_NEAR(r0.tangent(1, 2), m.mu, 1e-9);
    }
}

MpfemProblem base_problem(const ParticleLayout& layout, ParticleStrain strain, NeighbourRule rule, bool neo) {
  MpfemProblem p;
  p.layout = layout;
  p.thickness = 0.5;
  p.materials = {material::LinearElastic{200.0, 0.3}};
  p.material_models = {neo ? material::MaterialModel::neo_hookean : material::MaterialModel::linear_elastic};
  p.options.analysis = MpfemAnalysisKind::large_deformation;
  p.options.particle_strain = strain;
  p.options.elements.rule = rule;
  return p;
}

struct Variant {
  ParticleStrain strain;
  NeighbourRule rule;
  Real jitter;
};
const Variant kVariants[] = {{ParticleStrain::cell, NeighbourRule::logical_grid, 0.0},
                             {ParticleStrain::cell, NeighbourRule::logical_grid, 0.3},
                             {ParticleStrain::voronoi, NeighbourRule::sectors, 0.3},
                             {ParticleStrain::star, NeighbourRule::logical_grid, 0.2}};

TEST(mpfem_large_deformation, TangentMatchesFiniteDifferencesOfForces) {
  for (const auto& v : kVariants)
    for (PlaneKind plane : {PlaneKind::strain, PlaneKind::stress}) {
      MpfemProblem p = base_problem(grid_layout(6, 5, 2.0, 1.5, v.jitter, 3), v.strain, v.rule, true);
      p.options.plane = plane;
      MpfemAnalysis a(p, {});
      a.build_energy_points();
      const Index n = a.positions().cols();
      std::mt19937_64 random(11);
      std::uniform_real_distribution<Real> uniform(-0.08, 0.08);
      Eigen::VectorXd u(2 * n);
      for (Index i = 0; i < 2 * n; ++i) u[i] = uniform(random);
      for (Index q = 0; q < n; ++q) u[2 * q] += 0.2 * a.positions()(1, q);  // a finite shear
      Eigen::VectorXd f, fp, fm;
      solve::SparseMatrix k;
      Real e0 = 0, ep = 0, em = 0;
      ASSERT_TRUE(a.internal_forces(u, f, &k, &e0));
      const Eigen::MatrixXd dense(k);
      EXPECT_LT((dense - dense.transpose()).norm(), 1e-10 * dense.norm());
      const Real h = 1e-6;
      Real worst = 0;
      for (Index c = 0; c < 2 * n; ++c) {
        Eigen::VectorXd up = u, um = u;
        up[c] += h;
        um[c] -= h;
        ASSERT_TRUE(a.internal_forces(up, fp, nullptr, &ep));
        ASSERT_TRUE(a.internal_forces(um, fm, nullptr, &em));
        worst = std::max(worst, ((fp - fm) / (2 * h) - dense.col(c)).lpNorm<Eigen::Infinity>());
        EXPECT_NEAR((ep - em) / (2 * h), f[c], 1e-6 * f.lpNorm<Eigen::Infinity>() + 1e-8);
      }
      EXPECT_LT(worst, 1e-6 * dense.lpNorm<Eigen::Infinity>()) << "variant " << static_cast<int>(v.strain);
    }
}

/// Every boundary particle moved by (F - I) X: the particles inside must follow exactly.
void expect_uniform_deformation_exact(const Variant& v, PlaneKind plane, const Eigen::Matrix2d& F, Index* rebuilds) {
  const Real width = 2.0, height = 1.0;
  MpfemProblem p = base_problem(grid_layout(9, 6, width, height, v.jitter, 5), v.strain, v.rule, true);
  p.options.plane = plane;
  p.options.large_deformation.increments = 4;
  p.options.large_deformation.tolerance = 1e-12;
  const Points2& x = p.layout.positions;
  for (Index q = 0; q < x.cols(); ++q) {
    const Vec2 X = x.col(q);
    const bool boundary = X.x() < 1e-12 || X.y() < 1e-12 || X.x() > width - 1e-12 || X.y() > height - 1e-12;
    if (!boundary) continue;
    const Vec2 u = (F - Eigen::Matrix2d::Identity()) * X;
    p.prescribed.push_back({q, 0, u.x()});
    p.prescribed.push_back({q, 1, u.y()});
  }
  MpfemAnalysis a(p, {});
  a.solve();
  Real worst = 0;
  for (Index q = 0; q < x.cols(); ++q)
    worst = std::max(worst, (a.displacement(q) - (F - Eigen::Matrix2d::Identity()) * x.col(q)).norm());
  EXPECT_LT(worst, 1e-10) << "variant " << static_cast<int>(v.strain) << " jitter " << v.jitter;
  // Cauchy stress of the homogeneous state at every particle
  const auto m = material::Hyperelastic::from(material::HyperelasticKind::neo_hookean, p.materials[0]);
  const auto r = material::hyperelastic_response_2d(m, F, plane == PlaneKind::stress);
  Mat3 F3 = Mat3::Identity(), P3 = Mat3::Zero();
  F3.topLeftCorner<2, 2>() = F;
  F3(2, 2) = r.stretch33;
  P3.topLeftCorner<2, 2>() = r.stress;
  P3(2, 2) = r.stress33;
  const Mat3 sigma = material::cauchy_stress(P3, F3);
  for (Index q = 0; q < x.cols(); ++q) {
    EXPECT_NEAR(a.particle_stress(q)[0], sigma(0, 0), 1e-8 * sigma.norm());
    EXPECT_NEAR(a.particle_stress(q)[2], sigma(0, 1), 1e-8 * sigma.norm());
  }
  if (rebuilds) *rebuilds = a.large_deformation_stats().rebuilds;
}

TEST(mpfem_large_deformation, UniformDeformationPatchTestExact) {
  Eigen::Matrix2d F;
  F << 1.3, 0.25, -0.1, 0.85;
  for (const auto& v : kVariants)
    for (PlaneKind plane : {PlaneKind::strain, PlaneKind::stress}) expect_uniform_deformation_exact(v, plane, F, nullptr);
}

TEST(mpfem_large_deformation, LargeShearRebuildsSectorNeighbourhoods) {
  // simple shear of 0.8 on a jittered sector-neighbour set: the current nearest particles per sector
  // change, the elements are rebuilt (counted), and the homogeneous solution stays exact
  Eigen::Matrix2d F;
  F << 1.0, 0.8, 0.0, 1.0;
  Index rebuilds = 0;
  expect_uniform_deformation_exact({ParticleStrain::voronoi, NeighbourRule::sectors, 0.3}, PlaneKind::strain, F, &rebuilds);
  EXPECT_GE(rebuilds, 1);
}

TEST(mpfem_large_deformation, RigidRotationIsStressFree) {
  for (const auto& v : kVariants) {
    MpfemProblem p = base_problem(grid_layout(7, 5, 2.0, 1.0, v.jitter, 2), v.strain, v.rule, true);
    MpfemAnalysis a(p, {});
    a.build_energy_points();
    const Index n = a.positions().cols();
    const Real angle = 1.3;  // 74 degrees
    Eigen::Matrix2d R;
    R << std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle);
    Eigen::VectorXd u(2 * n);
    for (Index q = 0; q < n; ++q) u.segment<2>(2 * q) = (R - Eigen::Matrix2d::Identity()) * a.positions().col(q);
    Eigen::VectorXd f;
    Real energy = 1;
    ASSERT_TRUE(a.internal_forces(u, f, nullptr, &energy));
    EXPECT_NEAR(energy, 0.0, 1e-11);
    EXPECT_LT(f.lpNorm<Eigen::Infinity>(), 1e-10);
  }
}

TEST(mpfem_large_deformation, SmallLoadEqualsLinearAnalysis) {
  for (const auto& v : kVariants)
    for (bool neo : {true, false}) {
      MpfemProblem p = base_problem(grid_layout(17, 5, 8.0, 1.0, v.jitter, 4), v.strain, v.rule, neo);
      IndexList tip;
      for (Index q = 0; q < p.layout.positions.cols(); ++q) {
        const Vec2 X = p.layout.positions.col(q);
        if (X.x() < 1e-12) p.prescribed.push_back({q, 0, 0.0}), p.prescribed.push_back({q, 1, 0.0});
        if (X.x() > 8.0 - 1e-12) tip.push_back(q);
      }
      model::Load load;
      load.kind = model::Load::Kind::traction;
      load.select.nodes = tip;
      load.vector[1].constant = -1e-7;
      p.loads.push_back(load);
      p.options.large_deformation.increments = 1;
      MpfemProblem linear = p;
      linear.options.analysis = MpfemAnalysisKind::linear_static;
      linear.material_models.clear();
      MpfemAnalysis large_run(p, {}), linear_run(linear, {});
      large_run.solve();
      linear_run.solve();
      const Index n = p.layout.positions.cols();
      Real worst = 0, scale = 0;
      for (Index q = 0; q < n; ++q) {
        worst = std::max(worst, (large_run.displacement(q) - linear_run.displacement(q)).norm());
        scale = std::max(scale, linear_run.displacement(q).norm());
      }
      EXPECT_LT(worst, 1e-5 * scale) << "variant " << static_cast<int>(v.strain) << " neo " << neo;
    }
}

TEST(mpfem_large_deformation, NeoHookeanNeedsLargeDeformation) {
  MpfemProblem p = base_problem(grid_layout(5, 4, 2.0, 1.0, 0.0), ParticleStrain::cell, NeighbourRule::logical_grid, true);
  p.options.analysis = MpfemAnalysisKind::linear_static;
  EXPECT_THROW(MpfemAnalysis(p, {}), InputError);
}

TEST(mpfem_large_deformation, DivergenceStopsWithAnalysisError) {
  // a compressive prescribed stretch that turns the particles inside out cannot converge
  MpfemProblem p = base_problem(grid_layout(5, 4, 2.0, 1.0, 0.0), ParticleStrain::cell, NeighbourRule::logical_grid, true);
  for (Index q = 0; q < p.layout.positions.cols(); ++q) {
    const Vec2 X = p.layout.positions.col(q);
    if (X.x() > 2.0 - 1e-12) p.prescribed.push_back({q, 0, -2.5});
    if (X.x() < 1e-12) p.prescribed.push_back({q, 0, 0.0}), p.prescribed.push_back({q, 1, 0.0});
  }
  p.options.large_deformation.increments = 1;
  p.options.large_deformation.bisections = 2;
  MpfemAnalysis a(p, {});
  EXPECT_THROW(a.solve(), AnalysisError);
}

}  // namespace
}  // namespace lamina::mpfem
