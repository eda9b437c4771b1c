#include "solve/dense_cholesky.hpp"

namespace lamina::solve {

bool dense_cholesky_pays(const SparseMatrix& upper) {
  const Index n = upper.rows();
  if (n == 0 || n > dense_cholesky_max_rows) return false;
  const Real triangle = 0.5 * static_cast<Real>(n) * static_cast<Real>(n + 1);
  return static_cast<Real>(upper.nonZeros()) >= 0.5 * triangle;
}

bool DenseCholesky::compute(const SparseMatrix& upper) {
  const Index n = upper.rows();
  Eigen::MatrixXd lower = Eigen::MatrixXd::Zero(n, n);
  // entry (row <= col) of the upper triangle to (col, row) of the lower one, the triangle LLT reads
  for (Index col = 0; col < upper.outerSize(); ++col)
    for (SparseMatrix::InnerIterator it(upper, col); it; ++it)
      if (it.row() <= col) lower(col, it.row()) = it.value();
  llt_.compute(lower);
  return llt_.info() == Eigen::Success;
}

Real DenseCholesky::rcond() const {
  if (llt_.info() != Eigen::Success || llt_.matrixLLT().size() == 0) return 0.0;
  const Eigen::VectorXd d = llt_.matrixLLT().diagonal().cwiseAbs();
  const Real ratio = d.minCoeff() / d.maxCoeff();
  return ratio * ratio;
}

Eigen::VectorXd DenseCholesky::solve(const Eigen::VectorXd& b) const { return llt_.solve(b); }

}  // namespace lamina::solve
