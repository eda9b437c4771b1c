#pragma once
// Dense Cholesky (Eigen's blocked LLT) for the small, nearly full systems of the static methods: on an
// EFG body a few supports wide, K couples most node pairs and a sparse factorisation spends its time on
// ordering and bookkeeping. Measured on R1a (one thread): 432 dofs, 100 % full: CHOLMOD 5-8 ms, dense
// 1.6 ms; 972 dofs, 73 %: 29 ms / 12 ms; 1452 dofs, 57 %: 46 ms / 33 ms. It also spares a small run the
// loading of CHOLMOD and BLAS (solve/sparse_cholesky.hpp).
#include <Eigen/Dense>

#include "solve/sparse_cholesky.hpp"

namespace lamina::solve {

/// True when K (upper triangle, n x n) is better factored dense: n at most `dense_cholesky_max_rows`
/// and at least half of the upper triangle stored.
bool dense_cholesky_pays(const SparseMatrix& upper);
inline constexpr Index dense_cholesky_max_rows = 2000;  // 32 MB of dense storage

/// K = L L^T of the symmetric matrix given by its (sparse) upper triangle, the factor stored dense: the
/// SparseCholesky interface, so that solve_symmetric treats both factorisations alike.
class DenseCholesky final : public SparseCholesky {
 public:
  /// Factors; false if K is not positive definite (a pivot <= 0).
  bool compute(const SparseMatrix& upper) override;
  /// (min diag L / max diag L)^2, the estimate CHOLMOD reports (cholmod_rcond).
  Real rcond() const override;
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const override;

 private:
  Eigen::LLT<Eigen::MatrixXd, Eigen::Lower> llt_;
};

}  // namespace lamina::solve
