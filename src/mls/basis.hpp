#pragma once
// Complete polynomial bases p of the MLS approximation u^h = p^T A^-1 B u (seed 004), linear or quadratic in
// 1, 2 or 3 dimensions, in scaled local coordinates z = (x - centre) / rho, with derivatives at z = 0.
#include <array>

#include "core/types.hpp"
#include "mls/mls_options.hpp"

namespace lamina::mls {

/// Term order: 1, z_1..z_d, then (quadratic) z_1^2..z_d^2, then the cross terms in the order
/// z_1 z_2, z_2 z_3, z_3 z_1 (3D) or z_1 z_2 (2D) -- the same order as second-derivative rows
/// (xx yy zz xy yz zx).
template <int Dim, Basis B>
struct PolynomialBasis {
  static_assert(Dim >= 1 && Dim <= 3);
  static constexpr int dimension = Dim;
  static constexpr int size = B == Basis::linear ? Dim + 1 : (Dim + 1) * (Dim + 2) / 2;
  /// Number of independent second derivatives in Dim dimensions (1, 3, 6).
  static constexpr int second_count = Dim * (Dim + 1) / 2;
  using Vector = Eigen::Matrix<Real, size, 1>;

  /// Second-derivative pair (i, j) of component k in the 6-row layout xx yy zz xy yz zx.
  static constexpr std::array<int, 6> pair_first{0, 1, 2, 0, 1, 2};
  static constexpr std::array<int, 6> pair_second{0, 1, 2, 1, 2, 0};
  /// Row k (0..5) of the 6-row layout used in Dim dimensions, listed first to last.
  static constexpr std::array<int, 3> used_second_rows() {
    if constexpr (Dim == 1) return {0, -1, -1};
    else if constexpr (Dim == 2) return {0, 1, 3};
    else return {0, 1, 2};
  }

  /// Exponents (of z_1, z_2, z_3) of term k.
  static constexpr std::array<std::array<int, 3>, size> exponents() {
    std::array<std::array<int, 3>, size> result{};
    for (int d = 0; d < Dim; ++d) result[1 + d][d] = 1;
    if constexpr (B == Basis::quadratic) {
      for (int d = 0; d < Dim; ++d) result[1 + Dim + d][d] = 2;
      if constexpr (Dim == 2) result[5] = {1, 1, 0};
      if constexpr (Dim == 3) {
        result[7] = {1, 1, 0};
        result[8] = {0, 1, 1};
        result[9] = {1, 0, 1};
      }
    }
    return result;
  }

  /// Writes p(z) to out[0..size). T: Real, or a vector of Reals (GCC vector extension) for several
  /// points at once.
  template <class T>
  static void values(const T* z, T* out) {
    out[0] = T{} + 1.0;
    for (int d = 0; d < Dim; ++d) out[1 + d] = z[d];
    if constexpr (B == Basis::quadratic) {
      for (int d = 0; d < Dim; ++d) out[1 + Dim + d] = z[d] * z[d];
      if constexpr (Dim == 2) out[5] = z[0] * z[1];
      if constexpr (Dim == 3) {
        out[7] = z[0] * z[1];
        out[8] = z[1] * z[2];
        out[9] = z[2] * z[0];
      }
    }
  }

  /// dp/dx_i at z = 0 for z = (x - centre) / rho: only the term z_i is hit, with 1 / rho_i.
  static Vector first_derivative_at_origin(int i, const Vec3& rho) {
    Vector p = Vector::Zero();
    p[1 + i] = 1.0 / rho[i];
    return p;
  }

  /// d2p/dx_i dx_j at z = 0 (row k of the layout xx yy zz xy yz zx, i.e. i = pair_first[k], j = pair_second[k]).
  static Vector second_derivative_at_origin(int k, const Vec3& rho) {
    Vector p = Vector::Zero();
    if constexpr (B == Basis::quadratic) {
      const int i = pair_first[k];
      const int j = pair_second[k];
      if (i == j) {
        p[1 + Dim + i] = 2.0 / (rho[i] * rho[i]);
      } else if constexpr (Dim == 2) {
        p[5] = 1.0 / (rho[0] * rho[1]);
      } else if constexpr (Dim == 3) {
        p[7 + (k - 3)] = 1.0 / (rho[i] * rho[j]);
      }
    }
    return p;
  }
};

/// The moment matrix A = sum_I w_I p_I p_I^T has only as many distinct entries as there are monomials
/// of degree <= 2 * degree (35 instead of 55 for the 3D quadratic basis): entry (a, b) is the moment
/// sum_I w_I z_I^(e_a + e_b). The plan lists, per distinct moment, one (row, column) pair computing it
/// (smallest column first) and, per lower entry, which moment it is.
template <int Dim, Basis B>
struct MomentPlan {
  using Polynomial = PolynomialBasis<Dim, B>;
  static constexpr int size = Polynomial::size;
  int count = 0;
  std::array<int, size*(size + 1) / 2> row{};     // per moment: a
  std::array<int, size*(size + 1) / 2> column{};  // per moment: b <= a
  std::array<std::array<int, size>, size> moment_of{};  // [a][b], both triangles

  static constexpr MomentPlan make() {
    MomentPlan plan;
    constexpr auto exponent = Polynomial::exponents();
    std::array<int, 125> seen{};
    for (auto& value : seen) value = -1;
    for (int b = 0; b < size; ++b) {
      for (int a = b; a < size; ++a) {
        const int key = (exponent[a][0] + exponent[b][0]) + 5 * (exponent[a][1] + exponent[b][1]) +
                        25 * (exponent[a][2] + exponent[b][2]);
        if (seen[key] < 0) {
          seen[key] = plan.count;
          plan.row[plan.count] = a;
          plan.column[plan.count] = b;
          ++plan.count;
        }
        plan.moment_of[a][b] = plan.moment_of[b][a] = seen[key];
      }
    }
    return plan;
  }
};

}  // namespace lamina::mls
