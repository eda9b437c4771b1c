// Sparse building blocks: block pattern positions and scatter, CHOLMOD / dense Cholesky / LDLT / LU
// solves and their singularity detection.
#include <gtest/gtest.h>

#include "core/error.hpp"
#include "solve/block_pattern.hpp"
#include "solve/sparse_cholesky.hpp"
#include "solve/sparse_linear_solver.hpp"

namespace lamina::solve {
namespace {

TEST(BlockPattern, SymmetricPatternHoldsTheUpperTriangleOfEveryGroup) {
  BlockPattern p(5, 3, {{0, 1, 2}, {2, 4}}, true);
  EXPECT_EQ(p.dofs(), 15);
  EXPECT_GE(p.position(0, 3), 0);     // (node 0, node 1)
  EXPECT_EQ(p.position(3, 0), -1);    // lower triangle
  EXPECT_EQ(p.position(0, 12), -1);   // nodes 0 and 4 share no group
  EXPECT_GE(p.position(6, 14), 0);    // nodes 2 and 4
  EXPECT_GE(p.position(9, 9), 0);     // node 3 alone still has its diagonal block
  // entries: diagonal blocks 6 each (5 nodes), off-diagonal pairs (0,1) (0,2) (1,2) (2,4): 9 each
  EXPECT_EQ(p.nonzeros(), 5 * 6 + 4 * 9);
}

TEST(BlockPattern, ScatterAddsALocalMatrix) {
  BlockPattern p(3, 3, {{0, 2}}, false);
  std::vector<Real> values(static_cast<std::size_t>(p.nonzeros()), 0.0);
  Eigen::MatrixXd k = Eigen::MatrixXd::Zero(6, 6);
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) k(i, j) = 10 * i + j;
  p.scatter({0, 2}, k, values.data());
  p.scatter({0, 2}, k, values.data());
  const SparseMatrix m = p.matrix(values);
  EXPECT_EQ(m.coeff(1, 8), 2 * k(1, 5));  // row node 0 comp 1, column node 2 comp 2
  EXPECT_EQ(m.coeff(7, 2), 2 * k(4, 2));  // row node 2 comp 1, column node 0 comp 2
  EXPECT_EQ(m.coeff(3, 3), 0.0);          // node 1 untouched
  // a non-zero block outside the pattern is a programming error
  Eigen::MatrixXd bad = Eigen::MatrixXd::Ones(6, 6);
  EXPECT_THROW(p.scatter({0, 1}, bad, values.data()), std::logic_error);
}

SparseMatrix laplacian_upper(int n, Real shift) {
  std::vector<Eigen::Triplet<Real>> t;
  for (int i = 0; i < n; ++i) {
    t.emplace_back(i, i, 2.0 + shift);
    if (i + 1 < n) t.emplace_back(i, i + 1, -1.0);
  }
  SparseMatrix m(n, n);
  m.setFromTriplets(t.begin(), t.end());
  return m;
}

TEST(SparseSolver, CholmodSolvesAnSpdSystem) {
  const int n = 50;
  const SparseMatrix k = laplacian_upper(n, 0.01);
  const Eigen::VectorXd x0 = Eigen::VectorXd::LinSpaced(n, -1, 2);
  const Eigen::VectorXd b = multiply_symmetric_upper(k, x0);
  SolverReport r;
  const Eigen::VectorXd x = solve_symmetric(k, b, r);
  EXPECT_EQ(r.method, "cholmod_supernodal_llt");
  EXPECT_LT((x - x0).norm(), 1e-10 * x0.norm());
  SolverOptions o;
  o.force_fallback = true;
  const Eigen::VectorXd y = solve_symmetric(k, b, r, o);
  EXPECT_EQ(r.method, "simplicial_ldlt");
  EXPECT_LT((y - x0).norm(), 1e-10 * x0.norm());
}

/// Upper triangle of B B^T + shift I for a deterministic n x r matrix B (full, symmetric positive
/// semi-definite; definite for shift > 0 or r >= n).
SparseMatrix full_gram_upper(int n, int r, Real shift) {
  Eigen::MatrixXd b(n, r);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < r; ++j) b(i, j) = std::sin(0.37 * (i + 1) * (j + 2)) + (i == j ? 2.0 : 0.0);
  const Eigen::MatrixXd k = b * b.transpose() + shift * Eigen::MatrixXd::Identity(n, n);
  const Eigen::MatrixXd upper = k.triangularView<Eigen::Upper>();
  return upper.sparseView();
}

TEST(SparseSolver, SmallFullSystemIsFactoredDenseWithCholmodsConditionEstimate) {
  const int n = 40;
  const SparseMatrix k = full_gram_upper(n, n, 0.1);
  const Eigen::VectorXd x0 = Eigen::VectorXd::LinSpaced(n, -1, 2);
  const Eigen::VectorXd b = multiply_symmetric_upper(k, x0);
  SolverReport r;
  const Eigen::VectorXd x = solve_symmetric(k, b, r);
  EXPECT_EQ(r.method, "dense_llt");
  EXPECT_LT((x - x0).norm(), 1e-10 * x0.norm());
  // the estimate is CHOLMOD's formula, (min diag L / max diag L)^2; CHOLMOD factors a permuted K, so
  // its value on the same matrix differs, but by less than a factor n here (both far from singular)
  const auto cholmod = make_sparse_cholesky();
  ASSERT_TRUE(cholmod->compute(k));
  EXPECT_GT(r.rcond, 0.0);
  EXPECT_LT(r.rcond, 1.0);
  EXPECT_LT(std::abs(std::log10(r.rcond / cholmod->rcond())), std::log10(static_cast<Real>(n)));
  EXPECT_LT((cholmod->solve(b) - x0).norm(), 1e-10 * x0.norm());
  // a sparse (banded) system of the same size stays with CHOLMOD
  solve_symmetric(laplacian_upper(n, 0.01), b, r);
  EXPECT_EQ(r.method, "cholmod_supernodal_llt");
}

TEST(SparseSolver, SingularFullSystemIsReported) {
  // rank n - 1: a zero-energy mode in a full matrix (the dense path)
  const int n = 20;
  const SparseMatrix k = full_gram_upper(n, n - 1, 0.0);
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(n);
  SolverReport r;
  EXPECT_THROW(solve_symmetric(k, b, r), AnalysisError);
}

TEST(SparseSolver, SingularSystemIsReported) {
  // free-free chain: the constant vector is a zero-energy mode
  const int n = 20;
  std::vector<Eigen::Triplet<Real>> t;
  for (int i = 0; i + 1 < n; ++i) {
    t.emplace_back(i, i, 1.0);
    t.emplace_back(i + 1, i + 1, 1.0);
    t.emplace_back(i, i + 1, -1.0);
  }
  SparseMatrix k(n, n);
  k.setFromTriplets(t.begin(), t.end());
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
  b[n - 1] = 1.0;
  SolverReport r;
  EXPECT_THROW(solve_symmetric(k, b, r), AnalysisError);
}

TEST(SparseSolver, LuSolvesAnUnsymmetricSystem) {
  const int n = 30;
  std::vector<Eigen::Triplet<Real>> t;
  for (int i = 0; i < n; ++i) {
    t.emplace_back(i, i, 4.0);
    if (i + 1 < n) t.emplace_back(i, i + 1, -1.0);
    if (i > 1) t.emplace_back(i, i - 2, 0.5);
  }
  SparseMatrix a(n, n);
  a.setFromTriplets(t.begin(), t.end());
  const Eigen::VectorXd x0 = Eigen::VectorXd::LinSpaced(n, 1, 3);
  SolverReport r;
  const Eigen::VectorXd x = solve_general(a, a * x0, r);
  EXPECT_LT((x - x0).norm(), 1e-12 * x0.norm());
  EXPECT_EQ(r.method, "sparse_lu");
}

}  // namespace
}  // namespace lamina::solve
