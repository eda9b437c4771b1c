#pragma once
// Test helper: the eigenvalues of the ADR density-scaled stiffness Lambda^-1/2 K0 Lambda^-1/2 on the free
// dofs, with Lambda = 1/4 sum_j |K0_ij| (seed 002 eq (5)); central differences with dt = 1 are stable
// when they lie in (0, 4].
#include <Eigen/Dense>

#include <cmath>
#include <vector>

#include "pd/peridynamic_model.hpp"

namespace lamina::pd::test_support {

inline Eigen::VectorXd density_scaled_spectrum(const solve::SparseMatrix& k0_upper, const std::vector<Index>& free) {
  const Eigen::MatrixXd k = Eigen::MatrixXd(Eigen::MatrixXd(k0_upper).selfadjointView<Eigen::Upper>());
  const Eigen::VectorXd lambda = 0.25 * absolute_row_sums(k0_upper);
  Eigen::MatrixXd scaled(free.size(), free.size());
  for (std::size_t r = 0; r < free.size(); ++r)
    for (std::size_t c = 0; c < free.size(); ++c)
      scaled(r, c) = k(free[r], free[c]) / std::sqrt(lambda[free[r]] * lambda[free[c]]);
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(scaled).eigenvalues();
}

}  // namespace lamina::pd::test_support
