// Assembly is parallel over background cells: the same problem on 1 and 2 threads must give the
// same stiffness matrix (cells split into contiguous chunks assembled in two phases, either in place
// or into per-thread copies summed in thread order: only the association of a few sums changes) and, through the direct solver, the same
// solution up to the conditioning of the system.
#include <gtest/gtest.h>
#include <array>
#include <cmath>
#include <omp.h>

#include "efg/galerkin_assembly.hpp"
#include "efg_test_helpers.hpp"
#include "geometry/body_maps.hpp"

namespace lamina::efg {
namespace {

using namespace testing;

EfgProblem plate() {
  EfgProblem p = clamped_plate_quarter({9, 9, 3}, 0.3, 9.0, false);
  model::Load weight;
  weight.kind = model::Load::Kind::body_force;
  weight.select.spec.kind = geometry::SelectionSpec::Kind::all;
  weight.vector = {constant(0.0), constant(0.0), field("-1 - 0.1*x")};
  p.loads.push_back(weight);
  p.options.mls.basis = mls::Basis::quadratic;
  p.options.mls.kappa = 2.5;
  p.options.essential = EssentialMethod::nitsche;
  return p;
}

/// A strip 40 x 4 x 1: with 2 threads the cells assembled at the same time are far apart (direct writes).
EfgProblem strip() {
  EfgProblem p = make_problem(box(Vec3::Zero(), Vec3(40, 4, 1)), {41, 5, 3}, 1e4, 0.3);
  model::Constraint clamp;
  clamp.select = where("x < 1e-9", p.cloud);
  clamp.fixed = {true, true, true};
  p.constraints.push_back(clamp);
  p.options.mls.basis = mls::Basis::quadratic;
  p.options.mls.kappa = 2.5;
  return p;
}

struct Assembled {
  std::vector<Real> values;
  Eigen::VectorXd f;
  bool direct = false;
};

/// A problem with its 2 x 2 x 2 Gauss rule, shape functions, cell neighbour lists and sparsity pattern,
/// ready for assemble_volume (one material; VCI correction xi with a zero boundary term if vci).
struct AssemblySetup {
  EfgProblem problem;
  BackgroundCells cells;
  VolumeQuadrature quadrature;
  mls::MlsShapeFunctions shapes;
  std::vector<IndexList> cell_nodes;
  solve::BlockPattern pattern;
  Eigen::Matrix3Xd xi;
  std::vector<int> material;
  std::vector<material::LinearElastic> materials;

  AssemblySetup(EfgProblem p, const std::array<int, 3>& counts, bool vci)
      : problem(std::move(p)),
        cells(make_background_cells(geometry::make_volume_map(problem.geometry), counts)),
        quadrature(volume_quadrature(cells, {2, 2, 2})),
        shapes(problem.cloud.positions, problem.options.mls, problem.cloud.spacing),
        material(static_cast<std::size_t>(quadrature.size()), 0),
        materials{problem.materials[0].elastic} {
    std::vector<IndexList> groups;
    VolumeIntegrals integrals;
    cell_nodes = cell_neighbours(shapes, quadrature, vci ? &integrals : nullptr, &groups);
    pattern = solve::BlockPattern(problem.cloud.size(), 3, groups, !vci);
    if (vci) xi = vci_correction(integrals, Eigen::Matrix3Xd::Zero(3, problem.cloud.size()));
  }

  VolumeAssembly input() const {
    VolumeAssembly in;
    in.shapes = &shapes;
    in.quadrature = &quadrature;
    in.cell_nodes = &cell_nodes;
    in.material_of_point = &material;
    in.materials = &materials;
    in.vci = xi.cols() > 0 ? &xi : nullptr;
    return in;
  }
};

Assembled assemble_with_threads(int threads, bool vci, bool long_strip = false) {
  const int saved = omp_get_max_threads();
  omp_set_num_threads(threads);
  const AssemblySetup setup(long_strip ? strip() : plate(),
                            long_strip ? std::array<int, 3>{40, 4, 2} : std::array<int, 3>{8, 8, 2}, vci);
  const VolumeQuadrature& q = setup.quadrature;
  Eigen::Matrix3Xd body = Eigen::Matrix3Xd::Zero(3, q.size());
  for (Index i = 0; i < q.size(); ++i) body(2, i) = -1 - 0.1 * q.points(0, i);
  VolumeAssembly in = setup.input();
  in.body_force = &body;
  Assembled out;
  out.values.assign(static_cast<std::size_t>(setup.pattern.nonzeros()), 0.0);
  out.direct = assemble_volume(in, setup.pattern, out.values.data(), out.f).direct;
  omp_set_num_threads(saved);
  return out;
}

void expect_close(const Assembled& a, const Assembled& b) {
  ASSERT_EQ(a.values.size(), b.values.size());
  Real scale = 0, difference = 0;
  for (std::size_t i = 0; i < a.values.size(); ++i) {
    scale = std::max(scale, std::abs(a.values[i]));
    difference = std::max(difference, std::abs(a.values[i] - b.values[i]));
  }
  EXPECT_GT(scale, 0.0);
  EXPECT_LE(difference, 1e-14 * scale);
  EXPECT_LE((a.f - b.f).lpNorm<Eigen::Infinity>(), 1e-14 * a.f.lpNorm<Eigen::Infinity>());
}

TEST(Determinism, AssemblyOnOneAndTwoThreadsAgrees) {
  // 8 x 8 x 2 cells: on 2 threads the halves assembled at the same time share nodes (per-thread copies)
  const Assembled one = assemble_with_threads(1, false), two = assemble_with_threads(2, false);
  EXPECT_TRUE(one.direct);
  EXPECT_FALSE(two.direct);
  expect_close(one, two);
}

TEST(Determinism, DirectWritesOnTwoThreadsAgreeWithOneThread) {
  // a long strip: the cells assembled at the same time are far apart, the threads add in place
  const Assembled one = assemble_with_threads(1, false, true), two = assemble_with_threads(2, false, true);
  EXPECT_TRUE(one.direct);
  EXPECT_TRUE(two.direct);
  expect_close(one, two);
  const Assembled again = assemble_with_threads(2, false, true);
  EXPECT_TRUE(again.values == two.values);
}

TEST(Determinism, VciAssemblyOnOneAndTwoThreadsAgrees) {
  expect_close(assemble_with_threads(1, true), assemble_with_threads(2, true));
}

TEST(Determinism, AReducedRuleWithAnEmptyCellAddsNothingThere) {
  // selective reduced integration where one cell has no reduced point: the cell's lambda part is zero
  // (Eigen's triangular product divides by the inner dimension: this used to raise SIGFPE)
  const AssemblySetup setup(plate(), {8, 8, 2}, false);
  const solve::BlockPattern& pattern = setup.pattern;
  const VolumeQuadrature one_point = volume_quadrature(setup.cells, {1, 1, 1});
  VolumeQuadrature reduced = one_point;  // drop the point of cell 0
  reduced.points = one_point.points.rightCols(one_point.size() - 1);
  reduced.weights = one_point.weights.tail(one_point.size() - 1);
  for (std::size_t c = 1; c < reduced.cell_begin.size(); ++c) reduced.cell_begin[c] = one_point.cell_begin[c] - 1;
  reduced.cell_begin[0] = 0;
  const std::vector<int> reduced_material(static_cast<std::size_t>(reduced.size()), 0);
  VolumeAssembly in = setup.input();
  in.reduced = &reduced;
  in.material_of_reduced_point = &reduced_material;
  std::vector<Real> values(static_cast<std::size_t>(pattern.nonzeros()), 0.0);
  Eigen::VectorXd f;
  EXPECT_NO_THROW(assemble_volume(in, pattern, values.data(), f));
  for (const Real v : values) ASSERT_TRUE(std::isfinite(v));
  // the full one-point rule adds a positive lambda part to the diagonal of a node of cell 0
  std::vector<Real> full(values.size(), 0.0);
  in.reduced = &one_point;
  const std::vector<int> one_point_material(static_cast<std::size_t>(one_point.size()), 0);
  in.material_of_reduced_point = &one_point_material;
  assemble_volume(in, pattern, full.data(), f);
  const Index corner = setup.cell_nodes[0].front();
  const Index diagonal = pattern.position(3 * corner, 3 * corner);
  EXPECT_GT(full[static_cast<std::size_t>(diagonal)], values[static_cast<std::size_t>(diagonal)]);
}

TEST(Determinism, RepeatedAssemblyIsBitwiseIdentical) {
  const Assembled a = assemble_with_threads(2, false), b = assemble_with_threads(2, false);
  EXPECT_TRUE(a.values == b.values);
  EXPECT_EQ((a.f - b.f).lpNorm<Eigen::Infinity>(), 0.0);
}

Eigen::VectorXd solve_with_threads(int threads) {
  const int saved = omp_get_max_threads();
  omp_set_num_threads(threads);
  EfgAnalysis a(plate(), {});
  a.solve();
  omp_set_num_threads(saved);
  return a.nodal_parameters();
}

TEST(Determinism, SolutionOnOneAndTwoThreadsAgrees) {
  const Eigen::VectorXd one = solve_with_threads(1), two = solve_with_threads(2);
  ASSERT_EQ(one.size(), two.size());
  EXPECT_GT(one.lpNorm<Eigen::Infinity>(), 1e-3);
  // rounding differences of the assembly (1e-16) amplified by the condition number of K
  EXPECT_LE((one - two).lpNorm<Eigen::Infinity>(), 1e-10 * one.lpNorm<Eigen::Infinity>());
}

}  // namespace
}  // namespace lamina::efg
