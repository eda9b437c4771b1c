// Unit tests of the Voronoi-cell particle strain of MPFEM (issue 21, criterion 1): the cells tile
// the body, the integration constraint holds, and the linear patch test is exact (1e-10
// displacements, 1e-8 stresses) on unstructured particle sets: uniform random, jittered 0.3 and
// 0.45 with sector neighbours, a Gmsh triangle mesh's nodes, and issue 21's 287-particle cloud.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "core/error.hpp"
#include "geometry/gmsh_import.hpp"
#include "mpfem/mpfem_analysis.hpp"
#include "mpfem/voronoi_cells.hpp"

namespace lamina::mpfem {
namespace {

constexpr Real kWidth = 3.0, kHeight = 1.5;

/// Regular boundary particles on [0, 3] x [0, 1.5] at spacing h (corners included).
std::vector<Vec2> regular_boundary(int nx, int ny) {
  std::vector<Vec2> points;
  const Real hx = kWidth / (nx - 1), hy = kHeight / (ny - 1);
  for (int i = 0; i < nx; ++i) points.emplace_back(i * hx, 0.0), points.emplace_back(i * hx, kHeight);
  for (int j = 1; j + 1 < ny; ++j) points.emplace_back(0.0, j * hy), points.emplace_back(kWidth, j * hy);
  return points;
}

ParticleLayout layout_of(const std::vector<Vec2>& points) {
  ParticleLayout layout;
  layout.positions.resize(2, static_cast<Index>(points.size()));
  for (std::size_t i = 0; i < points.size(); ++i) layout.positions.col(static_cast<Index>(i)) = points[i];
  return layout;
}

/// Regular boundary (25 x 13, h = 0.125) and `count` random interior points, each at least
/// min_distance x h from all others (0: uniform random).
ParticleLayout random_cloud(int count, Real min_distance, unsigned seed) {
  std::vector<Vec2> points = regular_boundary(25, 13);
  const Real h = 0.125;
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<Real> ux(0.0, kWidth), uy(0.0, kHeight);
  while (static_cast<int>(points.size()) < 72 + count) {
    const Vec2 p(ux(random), uy(random));
    if (std::min({p.x(), kWidth - p.x(), p.y(), kHeight - p.y()}) < 0.05 * h) continue;
    bool far = true;
    for (const Vec2& q : points) far = far && (q - p).norm() >= std::max(min_distance * h, 1e-6 * h);
    if (far) points.push_back(p);
  }
  return layout_of(points);
}

/// n0 x n1 grid on the plate, interior particles moved by up to jitter x spacing; no logical grid
/// (the sector neighbour rule).
ParticleLayout jittered_cloud(int n0, int n1, Real jitter, unsigned seed) {
  std::vector<Vec2> points;
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<Real> uniform(-1.0, 1.0);
  const Real hx = kWidth / (n0 - 1), hy = kHeight / (n1 - 1);
  for (int j = 0; j < n1; ++j)
    for (int i = 0; i < n0; ++i) {
      Vec2 p(i * hx, j * hy);
      if (i > 0 && i + 1 < n0) p.x() += jitter * hx * uniform(random);
      if (j > 0 && j + 1 < n1) p.y() += jitter * hy * uniform(random);
      points.push_back(p);
    }
  return layout_of(points);
}

/// The nodes of validation/mpfem_patch_unstructured/plate_gmsh.msh: a Frontal-Delaunay triangle
/// mesh of the plate (Gmsh 4.8, size 0.15; make_plate_gmsh.cpp beside it).
ParticleLayout gmsh_cloud() {
  const auto mesh = geometry::import_gmsh(std::string(LAMINA_SOURCE_DIR) + "/validation/mpfem_patch_unstructured/plate_gmsh.msh");
  ParticleLayout layout;
  layout.positions = mesh.cloud.positions.topRows(2);
  return layout;
}

Real exact_u(const Vec2& x) { return 1e-3 * (1 + 2 * x.x() + 3 * x.y()); }
Real exact_v(const Vec2& x) { return 1e-3 * (-1 + 1.5 * x.x() - x.y()); }

/// Patch problem: exact linear displacement on x = 0 and either on the rest of the boundary too
/// (all_dirichlet) or the exact tractions sigma n there.
MpfemProblem patch(const ParticleLayout& layout, bool all_dirichlet, ParticleStrain strain) {
  MpfemProblem p;
  p.layout = layout;
  p.thickness = 0.1;
  p.materials = {material::LinearElastic{1000.0, 0.25}};
  p.options.elements.rule = NeighbourRule::sectors;
  p.options.particle_strain = strain;
  p.options.exact_displacement = std::array<std::string, 2>{"1e-3*(1 + 2*x + 3*y)", "1e-3*(-1 + 1.5*x - y)"};
  const Real sxx = 28.0 / 15.0, syy = -8.0 / 15.0, sxy = 1.8;  // plane stress, E = 1000, nu = 0.25
  IndexList right, bottom, top;
  const Real tol = 1e-12;
  for (Index q = 0; q < layout.positions.cols(); ++q) {
    const Vec2 x = layout.positions.col(q);
    const bool left = x.x() < tol;
    const bool boundary = left || x.x() > kWidth - tol || x.y() < tol || x.y() > kHeight - tol;
    if (left || (all_dirichlet && boundary)) {
      p.prescribed.push_back({q, 0, exact_u(x)});
      p.prescribed.push_back({q, 1, exact_v(x)});
    }
    if (x.x() > kWidth - tol) right.push_back(q);
    if (x.y() < tol) bottom.push_back(q);
    if (x.y() > kHeight - tol) top.push_back(q);
  }
  if (!all_dirichlet) {
    auto traction = [&](const IndexList& particles, Real tx, Real ty) {
      model::Load load;
      load.kind = model::Load::Kind::traction;
      load.select.nodes = particles;
      load.vector[0].constant = tx;
      load.vector[1].constant = ty;
      p.loads.push_back(load);
    };
    traction(right, sxx, sxy);
    traction(bottom, -sxy, -syy);
    traction(top, sxy, syy);
  }
  return p;
}

MpfemAnalysis::Errors solve_patch(const ParticleLayout& layout, bool all_dirichlet, ParticleStrain strain) {
  MpfemAnalysis analysis(patch(layout, all_dirichlet, strain), {});
  analysis.solve();
  return analysis.errors();
}

void expect_exact_patch(const char* name, const ParticleLayout& layout) {
  for (bool all_dirichlet : {true, false}) {
    const auto voronoi = solve_patch(layout, all_dirichlet, ParticleStrain::voronoi);
    const auto star = solve_patch(layout, all_dirichlet, ParticleStrain::star);
    std::printf("%-26s %-9s N = %4ld  voronoi: err_displacement %.2e err_stress %.2e | star (before): %.2e / %.2e\n",
                name, all_dirichlet ? "dirichlet" : "traction", static_cast<long>(layout.positions.cols()),
                voronoi.max_displacement, voronoi.max_stress, star.max_displacement, star.max_stress);
    EXPECT_LT(voronoi.max_displacement, 1e-10) << name;
    EXPECT_LT(voronoi.max_stress, 1e-8) << name;
  }
}

TEST(mpfem_voronoi, CellsTileTheHullAndSatisfyTheIntegrationConstraint) {
  const ParticleLayout layout = random_cloud(215, 0.0, 3);
  ElementOptions options;
  options.rule = NeighbourRule::sectors;
  const ParticleDiscretization d = build_particle_elements(layout, options);
  const VoronoiCells v = build_voronoi_cells(layout, d, 3.0 * d.typical_spacing);
  const Index n = layout.positions.cols();
  EXPECT_NEAR(v.cells.area.sum(), kWidth * kHeight, 1e-12);
  EXPECT_NEAR(v.boundary_weight.sum(), 2 * (kWidth + kHeight), 1e-12);
  EXPECT_EQ(v.boundary.size(), 72u);
  // sum_I |Omega_I| b_IJ = boundary integral of psi_J n; psi_J = 0 on the boundary for interior J
  Points2 volume_sum = Points2::Zero(2, n), boundary_sum = Points2::Zero(2, n);
  for (Index p = 0; p < n; ++p)
    for (const auto& [q, g] : v.cells.mean_gradient[static_cast<std::size_t>(p)]) volume_sum.col(q) += v.cells.area[p] * g;
  for (const auto& s : v.boundary) {
    boundary_sum.col(s.a) += 0.5 * s.length * s.normal;
    boundary_sum.col(s.b) += 0.5 * s.length * s.normal;
  }
  EXPECT_NEAR((volume_sum - boundary_sum).cwiseAbs().maxCoeff(), 0.0, 1e-13);
  // the smoothed gradient of x is the identity (linear exactness)
  for (Index p = 0; p < n; ++p) {
    Eigen::Matrix2d g = Eigen::Matrix2d::Zero();
    for (const auto& [q, c] : v.cells.mean_gradient[static_cast<std::size_t>(p)]) g += layout.positions.col(q) * c.transpose();
    EXPECT_NEAR((g - Eigen::Matrix2d::Identity()).norm(), 0.0, 1e-12) << "particle " << p;
  }
}

TEST(mpfem_voronoi, PatchTestExactOnUniformRandomCloud) { expect_exact_patch("uniform random", random_cloud(215, 0.0, 5)); }

TEST(mpfem_voronoi, PatchTestExactOnJitteredClouds) {
  expect_exact_patch("jitter 0.3 (25 x 13)", jittered_cloud(25, 13, 0.3, 3));
  expect_exact_patch("jitter 0.45 (25 x 13)", jittered_cloud(25, 13, 0.45, 7));
}

TEST(mpfem_voronoi, PatchTestExactOnGmshMeshNodes) { expect_exact_patch("gmsh triangle mesh nodes", gmsh_cloud()); }

TEST(mpfem_voronoi, PatchTestExactOnIssue21Cloud) {
  // 287 particles: regular boundary, random interior points at least 0.6 spacings apart
  const ParticleLayout layout = random_cloud(215, 0.6, 21);
  ASSERT_EQ(layout.positions.cols(), 287);
  expect_exact_patch("issue 21 (min 0.6 h)", layout);
}

TEST(mpfem_voronoi, PatchTestDetectsAWrongStiffness) {
  // the tractions of nu = 0.25 on a nu = 0.3 body must fail the patch test: the test can fail
  MpfemProblem p = patch(random_cloud(215, 0.6, 21), false, ParticleStrain::voronoi);
  p.materials[0].nu = 0.3;
  MpfemAnalysis analysis(p, {});
  analysis.solve();
  EXPECT_GT(analysis.errors().max_displacement, 1e-4);
}

TEST(mpfem_voronoi, DeterministicAcrossThreadCountsAndRebuilt) {
  MpfemProblem problem = patch(random_cloud(215, 0.6, 21), false, ParticleStrain::voronoi);
  problem.loads[0].vector[1].constant = 5.0;  // not a patch field: a general solution
  problem.options.body_area = kWidth * kHeight;
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  MpfemAnalysis one(problem, {});
  one.solve();
  omp_set_num_threads(std::max(2, threads));
  MpfemAnalysis many(problem, {});
  many.solve();
  omp_set_num_threads(threads);
  const solve::SparseMatrix difference = one.stiffness() - many.stiffness();
  EXPECT_EQ(one.stiffness().nonZeros(), many.stiffness().nonZeros());
  for (int c = 0; c < difference.outerSize(); ++c)
    for (solve::SparseMatrix::InnerIterator it(difference, c); it; ++it) EXPECT_EQ(it.value(), 0.0);
  // moved particles (a rotation and a stretch of the plate): cells rebuilt, the volume follows
  Eigen::Matrix2d map;
  map << 1.2 * std::cos(0.4), -0.9 * std::sin(0.4), 1.2 * std::sin(0.4), 0.9 * std::cos(0.4);
  one.rebuild(map * problem.layout.positions);
  EXPECT_NEAR(one.total_volume(), 0.1 * kWidth * kHeight * map.determinant(), 1e-12);
}

TEST(mpfem_voronoi, SparseCloudNamesTheParticle) {
  // a dense patch in one corner and one far particle: its cell reaches across the empty hull
  std::vector<Vec2> points;
  for (int j = 0; j < 6; ++j)
    for (int i = 0; i < 6; ++i) points.emplace_back(0.1 * i, 0.1 * j);
  points.emplace_back(3.0, 3.0);
  const ParticleLayout layout = layout_of(points);
  ElementOptions options;
  options.rule = NeighbourRule::sectors;
  options.max_neighbour_distance = 100.0;
  const ParticleDiscretization d = build_particle_elements(layout, options);
  try {
    build_voronoi_cells(layout, d, 3.0 * d.typical_spacing);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("particle 36 at (3, 3) reaches"), std::string::npos) << e.what();
  }
}

TEST(mpfem_voronoi, ConvexHullSkipsCollinearParticles) {
  const ParticleLayout layout = random_cloud(20, 0.6, 1);
  const std::vector<Index> hull = convex_hull(layout.positions);
  ASSERT_EQ(hull.size(), 4u);  // the four corners only
  Real area = 0;
  for (std::size_t k = 0; k < hull.size(); ++k) {
    const Vec2 a = layout.positions.col(hull[k]), b = layout.positions.col(hull[(k + 1) % hull.size()]);
    area += 0.5 * (a.x() * b.y() - a.y() * b.x());
  }
  EXPECT_NEAR(area, kWidth * kHeight, 1e-14);
}

}  // namespace
}  // namespace lamina::mpfem
