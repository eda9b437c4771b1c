#pragma once
// Factorisation of the m x m MLS moment matrix A (seed 004, eqs 1-12, 1-18/1-19): Jacobi-scaled
// dense Cholesky in fixed-size storage, with a 1-norm condition number estimate (Hager/Higham).
#include <cmath>
#include <limits>

#include "core/types.hpp"

namespace lamina::mls {

/// Factors A = S^-1 (L L^T) S^-1 with S = diag(1/sqrt(A_aa)), so that L L^T has a unit diagonal;
/// detects singular / ill-conditioned A; solves A y = b.
template <int M>
class MomentMatrixFactor {
 public:
  using Matrix = Eigen::Matrix<Real, M, M>;
  using Vector = Eigen::Matrix<Real, M, 1>;

  /// Factors the symmetric A (only the lower triangle is read). Returns false when A is not
  /// numerically positive definite: a non-positive diagonal, or a Cholesky pivot of the scaled matrix
  /// below 1 / max_condition (then cond_2(A_scaled) >= 1 / pivot > max_condition for certain).
  bool factor(const Matrix& a, Real max_condition) {
    condition_ = std::numeric_limits<Real>::infinity();
    for (int k = 0; k < M; ++k) {
      const Real diagonal = a(k, k);
      if (!(diagonal > 0.0) || !std::isfinite(diagonal)) return false;
      scale_[k] = 1.0 / std::sqrt(diagonal);
    }
    const Real minimum_pivot = 1.0 / max_condition;
    for (int j = 0; j < M; ++j) {
      Real pivot = 1.0;  // scaled diagonal
      for (int k = 0; k < j; ++k) pivot -= lower_(j, k) * lower_(j, k);
      if (!(pivot > minimum_pivot)) return false;
      const Real root = std::sqrt(pivot);
      lower_(j, j) = root;
      const Real inverse_root = 1.0 / root;
      for (int i = j + 1; i < M; ++i) {
        Real value = a(i, j) * scale_[i] * scale_[j];
        for (int k = 0; k < j; ++k) value -= lower_(i, k) * lower_(j, k);
        lower_(i, j) = value * inverse_root;
      }
    }
    // ||A_scaled||_1 from the scaled lower triangle of a.
    Real norm = 0.0;
    for (int j = 0; j < M; ++j) {
      Real column = 0.0;
      for (int i = 0; i < M; ++i) {
        const Real entry = i == j ? 1.0 : (i > j ? a(i, j) : a(j, i)) * scale_[i] * scale_[j];
        column += std::abs(entry);
      }
      norm = std::max(norm, column);
    }
    condition_ = norm * inverse_norm_estimate();
    return std::isfinite(condition_) && condition_ <= max_condition;
  }

  /// Estimated 1-norm condition number of the Jacobi-scaled A (infinity if factor() failed early).
  Real condition() const { return condition_; }

  /// y = A^-1 b.
  Vector solve(const Vector& b) const {
    Vector y = scale_.cwiseProduct(b);
    solve_scaled_in_place(y);
    return scale_.cwiseProduct(y);
  }

 private:
  /// y <- (L L^T)^-1 y.
  void solve_scaled_in_place(Vector& y) const {
    for (int i = 0; i < M; ++i) {
      Real value = y[i];
      for (int k = 0; k < i; ++k) value -= lower_(i, k) * y[k];
      y[i] = value / lower_(i, i);
    }
    for (int i = M - 1; i >= 0; --i) {
      Real value = y[i];
      for (int k = i + 1; k < M; ++k) value -= lower_(k, i) * y[k];
      y[i] = value / lower_(i, i);
    }
  }

  /// Hager's estimate of ||(L L^T)^-1||_1 (the matrix is symmetric, so A^-T = A^-1).
  Real inverse_norm_estimate() const {
    Vector x = Vector::Constant(1.0 / M);
    Vector y = x;
    solve_scaled_in_place(y);
    Real estimate = y.template lpNorm<1>();
    for (int iteration = 0; iteration < 5; ++iteration) {
      Vector z = y.unaryExpr([](Real v) { return v >= 0.0 ? 1.0 : -1.0; });
      solve_scaled_in_place(z);
      int j = 0;
      const Real largest = z.cwiseAbs().maxCoeff(&j);
      if (iteration > 0 && largest <= z.dot(x)) break;
      x.setZero();
      x[j] = 1.0;
      y = x;
      solve_scaled_in_place(y);
      const Real next = y.template lpNorm<1>();
      if (next <= estimate) break;
      estimate = next;
    }
    return estimate;
  }

  Eigen::Matrix<Real, M, M> lower_ = Eigen::Matrix<Real, M, M>::Zero();
  Vector scale_ = Vector::Ones();
  Real condition_ = std::numeric_limits<Real>::infinity();
};

}  // namespace lamina::mls
