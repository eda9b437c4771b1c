#pragma once
// Factorisation of the m x m MLS moment matrix A (seed 004, A r = p of eqs 1-18/1-19): Jacobi-scaled dense
// Cholesky in fixed-size storage, condition estimate, and the map to a weighted-orthonormal basis.
#include <cmath>
#include <limits>

#include "core/types.hpp"

namespace lamina::mls {

/// Factors S A S = L L^T with S = diag(1/sqrt(A_aa)) and forms T = L^-1 S, so that A^-1 = T^T T and
/// the basis q = T p is orthonormal for the weighted inner product that defines A.
/// Condition estimate: ||S A S||_1 * ||L^-1||_F^2 = ||S A S||_1 * trace((S A S)^-1), an upper bound of the
/// 2-norm condition number of the Jacobi-scaled A, at most m^1.5 times too large.
template <int M>
class MomentMatrixFactor {
 public:
  using Matrix = Eigen::Matrix<Real, M, M>;
  using Vector = Eigen::Matrix<Real, M, 1>;

  /// Factors the symmetric A (only the lower triangle is read). Returns false if A is singular or
  /// ill-conditioned: a non-positive diagonal, a Cholesky pivot of the scaled matrix below
  /// 1 / max_condition (then cond_2 >= 1 / pivot > max_condition for certain), or an estimate above
  /// max_condition.
  // Plain scalar loops on purpose: for m <= 10, vectorised in-place updates mostly stall on store
  // forwarding (a vector load of values just written by scalar stores).
  [[gnu::optimize("no-tree-vectorize")]] bool factor(const Matrix& a, Real max_condition) {
    condition_ = std::numeric_limits<Real>::infinity();
    Real scale[M];
    for (int k = 0; k < M; ++k) {
      const Real diagonal = a(k, k);
      if (!(diagonal > 0.0) || !std::isfinite(diagonal)) return false;
      scale[k] = 1.0 / std::sqrt(diagonal);
    }
    // Scaled matrix (lower triangle, lower[i][j] for i >= j) and its 1-norm.
    Real lower[M][M];
    Real column_sums[M];
    for (int j = 0; j < M; ++j) column_sums[j] = 1.0;
    for (int j = 0; j < M; ++j) {
      lower[j][j] = 1.0;
      for (int i = j + 1; i < M; ++i) {
        const Real value = a(i, j) * scale[i] * scale[j];
        lower[i][j] = value;
        column_sums[j] += std::abs(value);
        column_sums[i] += std::abs(value);
      }
    }
    Real norm = 0.0;
    for (int j = 0; j < M; ++j) norm = std::max(norm, column_sums[j]);
    // Left-looking Cholesky by rows: lower[i][j] = (s_ij - sum_k<j L_ik L_jk) / L_jj.
    const Real minimum_pivot = 1.0 / max_condition;
    Real inverse_diagonal[M];
    for (int i = 0; i < M; ++i) {
      for (int j = 0; j < i; ++j) {
        Real value = lower[i][j];
        for (int k = 0; k < j; ++k) value -= lower[i][k] * lower[j][k];
        lower[i][j] = value * inverse_diagonal[j];
      }
      Real pivot = lower[i][i];
      for (int k = 0; k < i; ++k) pivot -= lower[i][k] * lower[i][k];
      if (!(pivot > minimum_pivot)) return false;
      const Real root = std::sqrt(pivot);
      lower[i][i] = root;
      inverse_diagonal[i] = 1.0 / root;
    }
    // T = L^-1 S by rows: T_ij = -(sum_{j<=k<i} L_ik T_kj) / L_ii, T_ii = 1 / L_ii.
    Real inverse[M][M];
    Real trace = 0.0;
    for (int i = 0; i < M; ++i) {
      for (int j = 0; j < i; ++j) {
        Real value = 0.0;
        for (int k = j; k < i; ++k) value -= lower[i][k] * inverse[k][j];
        inverse[i][j] = value * inverse_diagonal[i];
        trace += inverse[i][j] * inverse[i][j];
      }
      inverse[i][i] = inverse_diagonal[i];
      trace += inverse_diagonal[i] * inverse_diagonal[i];
    }
    for (int j = 0; j < M; ++j)
      for (int i = 0; i < M; ++i) transform_(i, j) = i >= j ? inverse[i][j] * scale[j] : 0.0;
    condition_ = norm * trace;
    return std::isfinite(condition_) && condition_ <= max_condition;
  }

  /// Condition estimate of the Jacobi-scaled A (infinity if factor() stopped early).
  Real condition() const { return condition_; }

  /// T = L^-1 S (lower triangular).
  const Matrix& transform() const { return transform_; }

  /// y = A^-1 b = T^T (T b).
  Vector solve(const Vector& b) const { return transform_.transpose().lazyProduct(transform_.lazyProduct(b)); }

 private:
  Matrix transform_ = Matrix::Identity();
  Real condition_ = std::numeric_limits<Real>::infinity();
};

}  // namespace lamina::mls
