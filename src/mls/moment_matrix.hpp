#pragma once
// Inverse of the m x m MLS moment matrix A (seed 004, A r = p of eqs 1-18/1-19): Jacobi-scaled Gauss-Jordan
// in fixed-size vector storage, condition estimate, and the map to a weighted-orthonormal basis.
#include <cmath>
#include <limits>
#include <utility>

#include "core/types.hpp"

namespace lamina::mls {

/// Inverts the Jacobi-scaled A_s = S A S (S = diag(1/sqrt(A_aa))) by Gauss-Jordan elimination without
/// pivoting (A_s is symmetric positive definite), so that A^-1 = S A_s^-1 S. On request forms
/// T = L^-1 S from A_s = L L^T, so that A^-1 = T^T T and the basis q = T p is orthonormal for the
/// weighted inner product that defines A.
/// Condition estimate: ||A_s||_1 * trace(A_s^-1) (= ||A_s||_1 ||L^-1||_F^2), an upper bound of the
/// 2-norm condition number of A_s, at most m^1.5 times too large.
template <int M>
class MomentMatrixFactor {
 public:
  using Matrix = Eigen::Matrix<Real, M, M>;
  using Vector = Eigen::Matrix<Real, M, 1>;

  /// Factors the symmetric A (both triangles are read). Returns false if A is singular or
  /// ill-conditioned: a non-positive diagonal, a pivot of the scaled matrix below 1 / max_condition
  /// (then cond_2 >= 1 / pivot > max_condition for certain), or an estimate above max_condition.
  /// The pivots are those of the Cholesky factorisation (the diagonals of the Schur complements).
  bool factor(const Matrix& a, Real max_condition) {
    return factor_entries([&a](int i, int j) { return a(i, j); }, max_condition);
  }

  /// The same for A given by its entries, entry(i, j) = A_ij (for the MLS kernel: straight from the
  /// distinct moments, without forming A). (Out of line: inlined into the MLS kernel it cost about 190
  /// more instructions per point.)
  template <class Entry>
  [[gnu::noinline]] bool factor_entries(const Entry& entry, Real max_condition) {
    condition_ = std::numeric_limits<Real>::infinity();
    has_transform_ = false;
    // S as vectors of four (vector square roots and divisions; padding lanes 1).
    Real4* scale = scale_;
    for (int b = 0; b < blocks; ++b) {
      Real4 diagonal;
      for (int l = 0; l < 4; ++l) diagonal[l] = 4 * b + l < M ? entry(4 * b + l, 4 * b + l) : 1.0;
      for (int l = 0; l < 4; ++l)
        if (!(diagonal[l] > 0.0) || !std::isfinite(diagonal[l])) return false;
      scale[b] = 1.0 / Real4{std::sqrt(diagonal[0]), std::sqrt(diagonal[1]), std::sqrt(diagonal[2]),
                             std::sqrt(diagonal[3])};
    }
    // A_s = S A S by rows (A symmetric: row i holds A_ji), padded with zeros; its 1-norm (the largest
    // row sum of |A_s|).
    Real norm = 0.0;
#pragma GCC unroll 16
    for (int i = 0; i < M; ++i) {
      const Real scale_i = scale[i / 4][i % 4];
      Real4 sums = {0.0, 0.0, 0.0, 0.0};
#pragma GCC unroll 4
      for (int b = 0; b < blocks; ++b) {
        Real4 values;
#pragma GCC unroll 4
        for (int l = 0; l < 4; ++l) values[l] = 4 * b + l < M ? entry(4 * b + l, i) : 0.0;
        const Real4 row = values * scale[b] * scale_i;
        rows_[i][b] = row;
        sums += row < 0.0 ? -row : row;
      }
      norm = std::max(norm, sums[0] + sums[1] + sums[2] + sums[3]);
    }
    for (int i = 0; i < M; ++i)
      for (int b = 0; b < blocks; ++b) scaled_[i][b] = rows_[i][b];
    // Gauss-Jordan in place: step k divides row k by the pivot and eliminates column k from the other
    // rows. The rows' updates are independent vector operations, unlike the chains of dot products of
    // a Cholesky factorisation and a triangular inverse. Unrolled over k, so every lane index is a
    // constant and the rows stay in registers.
    const Real minimum_pivot = 1.0 / max_condition;
    bool regular = true;
    [&]<int... K>(std::integer_sequence<int, K...>) {
      ((regular = regular && eliminate<K>(minimum_pivot)), ...);
    }(std::make_integer_sequence<int, M>{});
    if (!regular) return false;
    Real trace = 0.0;
    for (int k = 0; k < M; ++k) trace += rows_[k][k / 4][k % 4];
    condition_ = norm * trace;
    return std::isfinite(condition_) && condition_ <= max_condition;
  }

  /// Condition estimate of the Jacobi-scaled A (infinity if factor() stopped early).
  Real condition() const { return condition_; }

  /// T = L^-1 S (lower triangular), formed on the first call after a successful factor().
  const Matrix& transform() const {
    if (!has_transform_) form_transform();
    return transform_;
  }

  /// y = A^-1 b = S A_s^-1 S b (A_s^-1 symmetric: a sum of its rows).
  Vector solve(const Vector& b) const {
    Real4 sum[blocks] = {};
    for (int j = 0; j < M; ++j) {
      const Real coefficient = scale_[j / 4][j % 4] * b[j];
      for (int k = 0; k < blocks; ++k) sum[k] += coefficient * rows_[j][k];
    }
    Vector y;
    for (int k = 0; k < blocks; ++k) {
      const Real4 scaled = sum[k] * scale_[k];
      for (int l = 0; l < 4; ++l)
        if (4 * k + l < M) y[4 * k + l] = scaled[l];
    }
    return y;
  }

 private:
  using Real4 = Real __attribute__((vector_size(32)));  // four doubles (one AVX2 register)
  static constexpr int blocks = (M + 3) / 4;

  template <int K>
  bool eliminate(Real minimum_pivot) {
    constexpr int kb = K / 4, kl = K % 4;
    const Real pivot = rows_[K][kb][kl];
    if (!(pivot > minimum_pivot)) return false;
    const Real inverse_pivot = 1.0 / pivot;
    // In place: column K of the identity shares column K of A. Row K becomes row K / pivot with 1 / pivot
    // in column K; every other row i becomes row i - A_iK row K / pivot with -A_iK / pivot in column K.
    // The factor A_iK is broadcast from its lane and column K is written by a blend (both register
    // operations: a scalar store into a row read back as a vector would stall the store forwarding).
    using Mask4 = long long __attribute__((vector_size(32)));
    constexpr Mask4 broadcast = {kl, kl, kl, kl};
    constexpr Mask4 lane_k = {kl == 0 ? -1 : 0, kl == 1 ? -1 : 0, kl == 2 ? -1 : 0, kl == 3 ? -1 : 0};
    const Real4 inverse = {inverse_pivot, inverse_pivot, inverse_pivot, inverse_pivot};
    Real4 row[blocks];
    for (int b = 0; b < blocks; ++b) row[b] = rows_[K][b] * inverse;
    row[kb] = lane_k ? inverse : row[kb];
    for (int i = 0; i < M; ++i) {
      if (i == K) continue;
      const Real4 factor = __builtin_shuffle(rows_[i][kb], broadcast);
      const Real4 column = -factor * inverse;  // the new entry (i, K)
      for (int b = 0; b < blocks; ++b) rows_[i][b] = fused_subtract(factor, row[b], rows_[i][b]);
      rows_[i][kb] = lane_k ? column : rows_[i][kb];
    }
    for (int b = 0; b < blocks; ++b) rows_[K][b] = row[b];
    return true;
  }

  /// c - a * b, fused where the CPU has FMA (the build turns off the compiler's own contraction).
  static Real4 fused_subtract(const Real4& a, const Real4& b, const Real4& c) {
#ifdef __FMA__
    return __builtin_ia32_vfnmaddpd256(a, b, c);
#else
    return c - a * b;
#endif
  }

  /// Left-looking Cholesky of A_s by rows, then T = L^-1 S by rows. (Out of line: only the orthonormal
  /// path calls it, and inlined GCC 12 could not see that it writes every entry of transform_.)
  [[gnu::noinline]] void form_transform() const {
    auto scaled = [&](int i, int j) { return scaled_[i][j / 4][j % 4]; };
    Real lower[M][M];
    Real inverse_diagonal[M];
    for (int i = 0; i < M; ++i) {
      for (int j = 0; j < i; ++j) {
        Real value = scaled(i, j);
        for (int k = 0; k < j; ++k) value -= lower[i][k] * lower[j][k];
        lower[i][j] = value * inverse_diagonal[j];
      }
      Real pivot = scaled(i, i);
      for (int k = 0; k < i; ++k) pivot -= lower[i][k] * lower[i][k];
      const Real root = std::sqrt(std::max(pivot, std::numeric_limits<Real>::min()));
      lower[i][i] = root;
      inverse_diagonal[i] = 1.0 / root;
    }
    Real inverse[M][M];
    for (int i = 0; i < M; ++i) {
      for (int j = 0; j < i; ++j) {
        Real value = 0.0;
        for (int k = j; k < i; ++k) value -= lower[i][k] * inverse[k][j];
        inverse[i][j] = value * inverse_diagonal[i];
      }
      inverse[i][i] = inverse_diagonal[i];
    }
    for (int j = 0; j < M; ++j)
      for (int i = 0; i < M; ++i) transform_(i, j) = i >= j ? inverse[i][j] * scale_[j / 4][j % 4] : 0.0;
    has_transform_ = true;
  }

  // Set by factor() (not initialised here: a factor object is made for every evaluation point).
  Real4 scale_[blocks];
  Real4 scaled_[M][blocks];  // A_s
  Real4 rows_[M][blocks];    // A_s^-1
  mutable Matrix transform_;
  mutable bool has_transform_ = false;
  Real condition_ = std::numeric_limits<Real>::infinity();
};

}  // namespace lamina::mls
