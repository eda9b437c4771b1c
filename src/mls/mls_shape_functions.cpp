#include "mls/mls_shape_functions.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <exception>
#include <limits>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include "core/error.hpp"
#include "mls/basis.hpp"
#include "mls/moment_matrix.hpp"
#include "mls/mls_workspace.hpp"
#include "mls/nodal_spacing.hpp"
#include "mls/real4.hpp"
#include "mls/weight_evaluation.hpp"
#include "mls/weight_function.hpp"

namespace lamina::mls {

namespace {
using namespace simd;  // Real4 and its helpers (mls/real4.hpp)
using namespace detail;  // the workspace and the weights (mls_workspace.hpp, weight_evaluation.hpp)

/// Above this condition estimate the shape functions are computed in a weighted-orthonormal basis,
/// orthonormalised twice (Cholesky-QR2). With A^-1 applied directly, rounding in A leaves the
/// consistency (reproduction) conditions of the derivatives satisfied only to O(eps cond A) times the
/// size of the intermediate terms; for cond <= 100 that is below 1e-12 on the test layouts, for the
/// second derivatives too.
constexpr Real orthonormalise_condition = 1e2;
/// The same for evaluations up to first derivatives (the Galerkin EFG's): their error stays below 1e-12
/// up to cond 1e4 (test FirstDerivativesOnThinPlateLattices: 7.8e-13 at 1.6e3; second derivatives formed
/// directly up to 1e6 failed the reproduction tests by up to 9e-9). The plates' moment matrices sit at 1e2-1e4, and the orthonormal path cost about 10 %
/// of a small EFG run (R1a 6 x 6 x 4).
constexpr Real orthonormalise_condition_first = 1e4;

detail::MlsWorkspace& thread_workspace() {
  thread_local detail::MlsWorkspace workspace;
  return workspace;
}

/// Gives `m` (a vector of `previous` values, or a matrix of fixed rows and `previous` columns) the size
/// n without freeing and allocating where it can: the neighbour count changes from point to point, so
/// a reused output swaps its storage with the one of that size kept in `by_size` (after a few points
/// every size seen has its storage). Sizes from 1024 on are resized in place.
template <class Matrix>
void fit_size(std::vector<Matrix>& by_size, Matrix& m, Index previous, Index n) {
  if (previous == n) return;
  constexpr Index pooled = 1024;
  if (n < pooled && previous < pooled) {
    const auto slots = static_cast<std::size_t>(std::max(n, previous)) + 1;
    if (by_size.size() < slots) by_size.resize(slots);
    Matrix taken = std::move(by_size[static_cast<std::size_t>(n)]);
    by_size[static_cast<std::size_t>(previous)] = std::move(m);
    m = std::move(taken);
  }
  if constexpr (Matrix::ColsAtCompileTime == 1) {
    if (m.size() != n) m.resize(n);
  } else {
    if (m.cols() != n) m.resize(Eigen::NoChange, n);
  }
}

/// sum_j w_j b_j b_j^T (both triangles) for the n x M matrix of basis values (rows b_j^T);
/// `weighted_storage` is n scratch values.
template <int M, class BasisMatrix>
void weighted_gram(const BasisMatrix& basis, const Eigen::Map<const Eigen::VectorXd>& weights, Real* weighted_storage,
                   Eigen::Matrix<Real, M, M>& a) {
  Eigen::Map<Eigen::VectorXd> weighted(weighted_storage, basis.rows());
  for (int col = 0; col < M; ++col) {
    weighted = weights.cwiseProduct(basis.col(col));
    for (int row = col; row < M; ++row) a(row, col) = a(col, row) = weighted.dot(basis.col(row));
  }
}

/// The distinct moments sum_j w_j p_a p_b of polynomial basis values p_j (MomentPlan; moment c is A_ab
/// for every a, b with plan.moment_of[a][b] = c), four neighbours at a time with one accumulator per
/// moment, in passes of at most 12 moments (all 35 of the 3D quadratic basis in one pass kept most
/// accumulators in memory, not in the 16 vector registers).
template <int Dim, Basis B>
void distinct_moments(const Real* basis, const Real* weights, Index n, Real* moments) {
  static constexpr MomentPlan<Dim, B> plan = MomentPlan<Dim, B>::make();
  constexpr int M = PolynomialBasis<Dim, B>::size;
  constexpr int C = plan.count;
  constexpr int per_pass = 12;
  const Real* columns[M + 1];
  for (int k = 0; k < M; ++k) columns[k] = basis + k * n;
  columns[M] = weights;
  const auto pass = [&]<int First>(std::integral_constant<int, First>) {
    constexpr int Count = std::min(per_pass, C - First);
    Real4 sums[Count];
    for (int m = 0; m < Count; ++m) sums[m] = Real4{0.0, 0.0, 0.0, 0.0};
    for_each_block_of_four<M + 1>(columns, n, [&](const Real4* lanes) {
#pragma GCC unroll 16
      for (int m = 0; m < Count; ++m) {
        const Real4 weighted = lanes[M] * lanes[plan.column[First + m]];  // w_j p_b (shared ones computed once)
        sums[m] = multiply_add(weighted, lanes[plan.row[First + m]], sums[m]);
      }
    });
    sum_lanes<Count>(sums, moments + First);
  };
  [&]<int... K>(std::integer_sequence<int, K...>) {
    (pass(std::integral_constant<int, K * per_pass>{}), ...);
  }(std::make_integer_sequence<int, (C + per_pass - 1) / per_pass>{});
}

/// out_j = b_j . v for the rows b_j of the n x M basis matrix (one fused pass, vectorised over j).
template <int M, class BasisMatrix, class Vector, class Out>
void basis_times(const BasisMatrix& basis, const Vector& v, Out& out) {
  const Index n = basis.rows();
  const Real* data = basis.data();
  Real* result = out.data();
  for (Index j = 0; j < n; ++j) {
    Real value = data[j] * v[0];
    for (int k = 1; k < M; ++k) value += data[k * n + j] * v[k];
    result[j] = value;
  }
}

/// sum_j c_j b_j (M dot products over the columns, in one pass four neighbours at a time).
template <int M, class BasisMatrix, class Vector>
Eigen::Matrix<Real, M, 1> basis_transpose_times(const BasisMatrix& basis, const Vector& c) {
  const Index n = basis.rows();
  const Real* columns[M + 1];
  for (int k = 0; k < M; ++k) columns[k] = basis.data() + k * n;
  columns[M] = c.data();
  Real4 sums[M];
  for (int k = 0; k < M; ++k) sums[k] = Real4{0.0, 0.0, 0.0, 0.0};
  for_each_block_of_four<M + 1>(columns, n, [&](const Real4* lanes) {
#pragma GCC unroll 16
    for (int k = 0; k < M; ++k) sums[k] = multiply_add(lanes[k], lanes[M], sums[k]);
  });
  Eigen::Matrix<Real, M, 1> result;
  for (int k = 0; k < M; ++k) result[k] = sum_lanes(sums[k]);
  return result;
}

std::string format_point(const Vec3& x) { return fmt::format("({:.6g}, {:.6g}, {:.6g})", x[0], x[1], x[2]); }

}  // namespace

FieldValue approximate_field(const ShapeFunctionValues& shape, const Eigen::Ref<const Eigen::VectorXd>& nodal_values) {
  FieldValue result;
  const Index n = static_cast<Index>(shape.neighbours.size());
  Eigen::VectorXd local(n);
  for (Index j = 0; j < n; ++j) local[j] = nodal_values[shape.neighbours[j]];
  result.value = shape.phi.dot(local);
  if (shape.dphi.cols() == n && n > 0) result.gradient = shape.dphi * local;
  if (shape.ddphi.cols() == n && n > 0) {
    const Eigen::Matrix<Real, 6, 1> second = shape.ddphi * local;
    result.hessian << second[0], second[3], second[5],  //
        second[3], second[1], second[4],                 //
        second[5], second[4], second[2];
  }
  return result;
}

template <int Dim, Basis B, bool Enriched>
bool MlsShapeFunctions::evaluate_kernel(const Vec3& x_in, int derivative_order, bool remedy, ShapeFunctionValues& out) const {
  using Polynomial = PolynomialBasis<Dim, B>;
  constexpr int P = Polynomial::size;           // polynomial terms
  constexpr int M = P + (Enriched ? 1 : 0);     // + the interface term |d(y)| / rho_n
  using VectorM = Eigen::Matrix<Real, M, 1>;
  using MatrixM = Eigen::Matrix<Real, M, M>;
  using BasisMap = Eigen::Map<Eigen::Matrix<Real, Eigen::Dynamic, M>>;
  using VectorMap = Eigen::Map<Eigen::VectorXd>;
  using ConstVectorMap = Eigen::Map<const Eigen::VectorXd>;
  detail::MlsWorkspace& workspace = thread_workspace();

  Vec3 x = x_in;
  for (int d = Dim; d < 3; ++d) x[d] = 0.0;
  const WeightFunction& function = weight_function_;
  const bool box = options_.shape == SupportShape::box;
  const bool node_centred_mode = node_centred();
  Real radius_factor = 1.0;
  Index nearest_count = options_.nearest;
  int step = 0;
  MomentMatrixFactor<M> factor;
  MatrixM a;
  Vec3 rho;
  Index n = 0;

  // Interface enrichment: signed distance d(y) = n . (y - point), scaled by rho_n = |n| . rho.
  const Vec3& normal = options_.interface_normal;
  auto signed_distance = [&](const Vec3& y) { return normal.dot(y - options_.interface_point); };
  Real rho_n = 1.0;

  // Neighbours, weights, basis values and A = sum_I w_I p_I p_I^T; the SINCHECK remedy if enabled.
  for (;;) {
    n = gather<Dim>(x, radius_factor, nearest_count, workspace, rho);
    if constexpr (Enriched) {
      // only where the support holds nodes strictly on both sides (elsewhere |d| is affine there: A singular)
      bool below = false, above = false;
      const Real tolerance = 1e-9 * rho.head(Dim).maxCoeff();
      for (Index j = 0; j < n; ++j) {
        const Real d = signed_distance(projected_.col(workspace.indices[static_cast<std::size_t>(j)]));
        below |= d < -tolerance;
        above |= d > tolerance;
      }
      if (!(below && above)) return false;
      rho_n = normal.cwiseAbs().dot(rho);
    }
    bool regular = false;
    Real condition = std::numeric_limits<Real>::infinity();
    if (n >= M) {
      const auto count = static_cast<std::size_t>(n);
      grow(workspace.weights, 10 * count);
      grow(workspace.basis, M * count);
      grow(workspace.scratch, std::max(9, M) * count);
      compute_weights<Dim>(function, box, derivative_order >= 2, count, workspace.stride, workspace.offsets.data(),
                           workspace.inverse_radii.data(), workspace.scratch.data(), workspace.weights.data());
      BasisMap basis(workspace.basis.data(), n, M);
      Real inverse_rho[3];
      for (int d = 0; d < Dim; ++d) inverse_rho[d] = -1.0 / rho[d];
      const Real* offsets = workspace.offsets.data();
      Real* columns = workspace.basis.data();  // column k at k * n: vectorised over the neighbours j
      const std::size_t stride = workspace.stride;
      for_each_group_of_four(n, [&](Index j, Index lanes) {
        Real4 z[3], p[P];
        for (int d = 0; d < Dim; ++d) z[d] = load4(offsets + d * stride + j, lanes) * inverse_rho[d];
        Polynomial::values(z, p);
#pragma GCC unroll 16
        for (int k = 0; k < P; ++k) store4(columns + k * n + j, p[k], lanes);
      });
      if constexpr (Enriched)
        for (Index j = 0; j < n; ++j)
          basis(j, P) = std::abs(signed_distance(projected_.col(workspace.indices[static_cast<std::size_t>(j)]))) / rho_n;
      if constexpr (Enriched) {
        weighted_gram<M>(basis, ConstVectorMap(workspace.weights.data(), n), workspace.scratch.data(), a);
        regular = factor.factor(a, options_.max_condition);
      } else {  // A straight from its distinct moments
        static constexpr MomentPlan<Dim, B> plan = MomentPlan<Dim, B>::make();
        Real moments[plan.count];
        distinct_moments<Dim, B>(workspace.basis.data(), workspace.weights.data(), n, moments);
        regular = factor.factor_entries([&moments](int i, int j) { return moments[plan.moment_of[i][j]]; },
                                        options_.max_condition);
      }
      condition = factor.condition();
    }
    if (regular) {
      out.condition = condition;
      break;
    }
    if constexpr (Enriched) return false;  // the caller falls back to the polynomial basis
    // Nothing more to gain once every node is a neighbour (radius modes) or N = all nodes.
    // (SELECT: one more node while the N nearest are a choice among more covering nodes, else wider supports)
    const bool capped = workspace.capped;
    const bool can_grow = node_centred_mode ? n < node_count() : nearest_count < node_count();
    if (!remedy || step >= options_.remedy_max_steps || !can_grow) throw_singular(x_in, n, condition, remedy);
    ++step;
    if (capped) ++nearest_count;
    else if (node_centred_mode) radius_factor *= 1.25;
    else ++nearest_count;
  }
  out.remedy_steps = step;

  BasisMap basis(workspace.basis.data(), n, M);
  const Real* weights = workspace.weights.data();
  auto weight = [&](int q) { return ConstVectorMap(weights + q * n, n); };
  Real* scratch = workspace.scratch.data();
  VectorMap projection(scratch, n);  // p_I . r
  VectorMap combined(scratch + 4 * n, n);
  auto first_projection = [&](int i) { return VectorMap(scratch + (1 + i) * n, n); };  // p_I . r_,i

  // Two equivalent ways to apply A^-1 (= S A_s^-1 S = T^T T, T = L^-1 S with A_s = L L^T):
  //  direct:       basis rows p_I, right-hand sides g as they are, solve(h) = S A_s^-1 S h;
  //  orthonormal:  basis rows q_I = T p_I (orthonormalised once more, T <- T2 T), right-hand sides
  //                T g, solve(h) = h -- used above orthonormalise_condition(_first) for accuracy.
  const bool orthonormal =
      out.condition > (derivative_order >= 2 ? orthonormalise_condition : orthonormalise_condition_first);
  MatrixM transform;  // set (and used) only when orthonormal: no identity matrix is filled per point
  if (orthonormal) {
    transform = factor.transform();
    // rows b_I <- T b_I, through the scratch buffer (no allocation)
    auto transform_rows = [&](const MatrixM& by) {
      BasisMap transformed(scratch, n, M);
      for (int c = 0; c < M; ++c) {
        auto column = transformed.col(c);
        basis_times<M>(basis, by.row(c), column);
      }
      basis = transformed;
    };
    transform_rows(transform);
    MomentMatrixFactor<M> second;
    weighted_gram<M>(basis, weight(0), scratch, a);
    if (!second.factor(a, options_.max_condition)) throw_singular(x_in, n, out.condition, remedy);
    transform_rows(second.transform());
    transform = (second.transform().lazyProduct(transform)).eval();
  }
  auto prepare = [&](const VectorM& g) -> VectorM { return orthonormal ? VectorM(transform.lazyProduct(g)) : g; };
  auto solve = [&](const VectorM& h) -> VectorM { return orthonormal ? h : factor.solve(h); };

  // phi_I = w_I p_I . A^-1 p(x) with p(x) = e_0 in the shifted basis (eqs 1-18, 1-19).
  VectorM unit = VectorM::Zero();
  unit[0] = 1.0;
  Real distance_x = 0.0;
  if constexpr (Enriched) {
    distance_x = signed_distance(x);
    unit[P] = std::abs(distance_x) / rho_n;
  }
  // the basis vector's derivatives at x: polynomial part at the origin, interface term sign(d) n_i / rho_n
  auto first_derivative = [&](int i) -> VectorM {
    VectorM g = VectorM::Zero();
    g.template head<P>() = Polynomial::first_derivative_at_origin(i, rho);
    if constexpr (Enriched) g[P] = (distance_x > 0.0 ? 1.0 : distance_x < 0.0 ? -1.0 : 0.0) * normal[i] / rho_n;
    return g;
  };
  auto second_derivative = [&](int k) -> VectorM {
    VectorM g = VectorM::Zero();
    g.template head<P>() = Polynomial::second_derivative_at_origin(k, rho);
    return g;
  };
  const VectorM r = solve(prepare(unit));
  out.neighbours.swap(workspace.indices);  // the next gather rewrites the workspace's list
  const Real* columns = basis.data();  // column k at k * n
  // p_J . r for the neighbours j .. j + lanes - 1 (the same sums for every derivative order)
  Real4 r4[M];  // r's coefficients broadcast once (not once per group)
  for (int k = 0; k < M; ++k) r4[k] = Real4{r[k], r[k], r[k], r[k]};
  const auto project = [&](Index j, Index lanes, Real4* b) {
    for (int k = 0; k < M; ++k) b[k] = load4(columns + k * n + j, lanes);
    Real4 projected = b[0] * r4[0];
    for (int k = 1; k < M; ++k) projected = multiply_add(b[k], r4[k], projected);
    return projected;
  };
  fit_size(workspace.phi_by_size, out.phi, out.phi.size(), n);
  if (derivative_order < 1) {
    for_each_group_of_four(n, [&](Index j, Index lanes) {
      Real4 b[M];
      store4(out.phi.data() + j, load4(weights + j, lanes) * project(j, lanes, b), lanes);
    });
    out.dphi.resize(3, 0);
    out.ddphi.resize(6, 0);
    return true;
  }

  // First derivatives (eq 1-20): phi_I,i = w_I,i p_I.r + w_I p_I.r_,i with
  // r_,i = A^-1 (p_,i - A_,i r) and A_,i r = sum_J w_J,i (p_J . r) p_J.
  // Sweeps over the neighbours, four at a time: p_J.r and phi; then per direction the sums A_,i r;
  // then p_J.r_,i and phi_,i of every direction in one sweep.
  if constexpr (Dim == 3) fit_size(workspace.dphi_by_size, out.dphi, out.dphi.cols(), n);  // every row written below
  else out.dphi.setZero(3, n);
  {
    Real* q = projection.data();
    Real* phi = out.phi.data();
    for_each_group_of_four(n, [&](Index j, Index lanes) {  // p_J . r and phi_J
      Real4 b[M];
      const Real4 projected = project(j, lanes, b);
      store4(q + j, projected, lanes);
      store4(phi + j, load4(weights + j, lanes) * projected, lanes);
    });
    // One direction per sweep, so that its M sums (and its M coefficients below) stay in registers.
    VectorM r_first[Dim];
    for (int i = 0; i < Dim; ++i) {
      const Real* weight_i = weights + (1 + i) * n;
      Real4 sums[M];
      for (int k = 0; k < M; ++k) sums[k] = Real4{0.0, 0.0, 0.0, 0.0};
      for_each_group_of_four(n, [&](Index j, Index lanes) {
        const Real4 c = load4(weight_i + j, lanes) * load4(q + j, lanes);
        for (int k = 0; k < M; ++k) sums[k] = multiply_add(c, load4(columns + k * n + j, lanes), sums[k]);
      });
      VectorM products;
      sum_lanes<M>(sums, products.data());
      r_first[i] = solve(VectorM(prepare(first_derivative(i)) - products));
    }
    // Then every direction in one sweep: the basis values loaded once, the coefficients of r_,i
    // broadcast once.
    Real* dphi = out.dphi.data();  // (i, J) at 3 J + i
    const bool keep = derivative_order >= 2;
    Real4 coefficients[Dim][M];
    for (int i = 0; i < Dim; ++i)
      for (int k = 0; k < M; ++k) coefficients[i][k] = Real4{r_first[i][k], r_first[i][k], r_first[i][k], r_first[i][k]};
    for_each_group_of_four(n, [&](Index j, Index lanes) {
      Real4 b[M];
      for (int k = 0; k < M; ++k) b[k] = load4(columns + k * n + j, lanes);
      const Real4 projected = load4(q + j, lanes), weight = load4(weights + j, lanes);
      Real4 d[Dim];
      for (int i = 0; i < Dim; ++i) {
        Real4 t = b[0] * coefficients[i][0];
        for (int k = 1; k < M; ++k) t = multiply_add(b[k], coefficients[i][k], t);
        if (keep) store4(scratch + (1 + i) * n + j, t, lanes);  // p_J . r_,i for the second derivatives
        d[i] = load4(weights + (1 + i) * n + j, lanes) * projected + weight * t;
      }
      if constexpr (Dim == 3) {
        if (lanes == 4) {
          store_interleaved3(dphi + 3 * j, d[0], d[1], d[2]);
          return;
        }
      }
      for (Index l = 0; l < lanes; ++l)
        for (int i = 0; i < Dim; ++i) dphi[3 * (j + l) + i] = d[i][l];
    });
    // Constant consistency made exact: sum_J phi_J,i = 0 holds only to about eps cond(A) |phi_,i| after the
    // solves, so a rigid translation would strain every quadrature point a little, and in a stiff,
    // ill-conditioned body (a thin cantilever: cond(K) ~ 1e13) the support reaction then misses the
    // applied load by 1e-3. phi_J,i -= phi_J sum_K phi_K,i (sum_J phi_J = 1) removes that part; the change
    // is of the size of the rounding.
    Real total[3] = {0.0, 0.0, 0.0};
    Index j = 0;
    if constexpr (Dim == 3) {  // four nodes (12 interleaved values) at a time
      using Lanes = std::int64_t __attribute__((vector_size(32)));
      Real4 s0 = {0.0, 0.0, 0.0, 0.0}, s1 = s0, s2 = s0;  // lanes: x y z x | y z x y | z x y z
      for (; j + 4 <= n; j += 4) {
        const Real* d = dphi + 3 * j;
        s0 += load4(d);
        s1 += load4(d + 4);
        s2 += load4(d + 8);
      }
      for (Index k = j; k < n; ++k)
        for (int i = 0; i < 3; ++i) total[i] += dphi[3 * k + i];
      total[0] += (s0[0] + s0[3]) + (s1[2] + s2[1]);
      total[1] += (s0[1] + s1[0]) + (s1[3] + s2[2]);
      total[2] += (s0[2] + s1[1]) + (s2[0] + s2[3]);
      const Real4 t0 = {total[0], total[1], total[2], total[0]}, t1 = {total[1], total[2], total[0], total[1]},
                  t2 = {total[2], total[0], total[1], total[2]};
      for (j = 0; j + 4 <= n; j += 4) {
        const Real4 p = load4(phi + j);
        Real* d = dphi + 3 * j;
        store4(d, multiply_add(-__builtin_shuffle(p, Lanes{0, 0, 0, 1}), t0, load4(d)));
        store4(d + 4, multiply_add(-__builtin_shuffle(p, Lanes{1, 1, 2, 2}), t1, load4(d + 4)));
        store4(d + 8, multiply_add(-__builtin_shuffle(p, Lanes{2, 3, 3, 3}), t2, load4(d + 8)));
      }
    } else {
      for (Index k = 0; k < n; ++k)
        for (int i = 0; i < Dim; ++i) total[i] += dphi[3 * k + i];
    }
    for (; j < n; ++j)
      for (int i = 0; i < Dim; ++i) dphi[3 * j + i] -= phi[j] * total[i];
  }
  if (derivative_order < 2) {
    out.ddphi.resize(6, 0);
    return true;
  }

  // Second derivatives (eq 1-21): r_,ij = A^-1 (p_,ij - A_,i r_,j - A_,j r_,i - A_,ij r);
  // phi_I,ij = c_I + w_I p_I . r_,ij with c_I = w_I,ij p_I.r + w_I,i p_I.r_,j + w_I,j p_I.r_,i, and
  // the right-hand side is p_,ij - sum_J c_J p_J.
  out.ddphi.setZero(6, n);
  VectorMap u(scratch + 5 * n, n);
  for (int k = 0; k < 6; ++k) {
    const int i = Polynomial::pair_first[k];
    const int l = Polynomial::pair_second[k];
    if (i >= Dim || l >= Dim) continue;
    combined = weight(4 + k).cwiseProduct(projection) + weight(1 + i).cwiseProduct(first_projection(l)) +
               weight(1 + l).cwiseProduct(first_projection(i));
    const VectorM right = prepare(second_derivative(k)) - basis_transpose_times<M>(basis, combined);
    const VectorM r_second = solve(right);
    basis_times<M>(basis, r_second, u);
    out.ddphi.row(k) = (combined + weight(0).cwiseProduct(u)).transpose();
  }
  return true;
}

void MlsShapeFunctions::throw_singular(const Vec3& x, Index neighbours, Real condition, bool remedy) const {
  const int dimension = options_.dimension;
  std::string cause;
  if (neighbours < basis_size_) {
    cause = fmt::format("fewer neighbours than basis terms");
  } else if (!std::isfinite(condition)) {
    cause = "A is not numerically positive definite";
  } else {
    cause = fmt::format("estimated condition number {:.3g} > max_condition {:.3g}", condition, options_.max_condition);
  }
  std::string advice;
  switch (options_.mode) {
    case SupportMode::kappa:
      advice = options_.kappa_axes != Vec3::Zero()
                   ? fmt::format("increase the support size kappa (now [{}, {}, {}])", options_.kappa_axes[0],
                                 options_.kappa_axes[1], options_.kappa_axes[2])
                   : fmt::format("increase the support size kappa (now {})", options_.kappa);
      break;
    case SupportMode::fixed_radius:
      advice = fmt::format("increase the support radius (now [{}, {}, {}])", options_.radius[0], options_.radius[1],
                           options_.radius[2]);
      break;
    case SupportMode::nearest:
    case SupportMode::all:
    case SupportMode::variable:
      advice = fmt::format("increase the number of nearest nodes (now {}) or the radius scale (now {})", options_.nearest,
                           options_.scale);
      break;
  }
  if (options_.basis == Basis::quadratic) advice += ", use a linear basis";
  advice += remedy
                ? fmt::format(" (the singular remedy gave up after {} steps)", options_.remedy_max_steps)
                : ", or enable the singular remedy";
  const std::string message = fmt::format(
      "MLS moment matrix singular or ill-conditioned at x = {}: {} neighbour(s) found for the {} basis with m = {} "
      "terms in {}D, {} support ({}; {}). Fix: {}.",
      format_point(x), neighbours, to_string(options_.basis), basis_size_, dimension, to_string(options_.shape),
      to_string(options_.mode), cause, advice);
  throw SingularMomentMatrix(message, x, neighbours, basis_size_, condition);
}

template <int Dim>
void MlsShapeFunctions::evaluate_dimension(const Vec3& x, int derivative_order, bool enrich, bool remedy,
                                           ShapeFunctionValues& out) const {
  if (options_.basis == Basis::linear) {
    if (!enrich || !evaluate_kernel<Dim, Basis::linear, true>(x, derivative_order, remedy, out))
      evaluate_kernel<Dim, Basis::linear, false>(x, derivative_order, remedy, out);
  } else {
    if (!enrich || !evaluate_kernel<Dim, Basis::quadratic, true>(x, derivative_order, remedy, out))
      evaluate_kernel<Dim, Basis::quadratic, false>(x, derivative_order, remedy, out);
  }
}

void MlsShapeFunctions::evaluate(const Vec3& x, int derivative_order, ShapeFunctionValues& out, bool grow_if_singular) const {
  if (derivative_order < 0 || derivative_order > 2)
    throw std::invalid_argument(fmt::format("MLS derivative order must be 0, 1 or 2, got {}", derivative_order));
  // interface enrichment where the support may cross the interface plane
  bool enrich = false;
  if (options_.interface_enrichment) {
    const Real reach = node_centred() ? options_.interface_normal.cwiseAbs().dot(max_radius_) : std::numeric_limits<Real>::infinity();
    enrich = std::abs(options_.interface_normal.dot(x - options_.interface_point)) < reach;
  }
  const bool remedy = options_.singular_remedy || grow_if_singular;
  switch (options_.dimension) {
    case 1: return evaluate_dimension<1>(x, derivative_order, enrich, remedy, out);
    case 2: return evaluate_dimension<2>(x, derivative_order, enrich, remedy, out);
    default: return evaluate_dimension<3>(x, derivative_order, enrich, remedy, out);
  }
}

void MlsShapeFunctions::neighbours(const Vec3& x_in, IndexList& out, bool grow_if_singular) const {
  if (options_.singular_remedy || grow_if_singular) {
    ShapeFunctionValues values;
    evaluate(x_in, 0, values, grow_if_singular);
    out.swap(values.neighbours);
    return;
  }
  detail::MlsWorkspace& workspace = thread_workspace();
  Vec3 x = x_in, rho;
  for (int d = options_.dimension; d < 3; ++d) x[d] = 0.0;
  switch (options_.dimension) {
    case 1: gather<1>(x, 1.0, options_.nearest, workspace, rho); break;
    case 2: gather<2>(x, 1.0, options_.nearest, workspace, rho); break;
    default: gather<3>(x, 1.0, options_.nearest, workspace, rho); break;
  }
  out.assign(workspace.indices.begin(), workspace.indices.end());
}

ShapeFunctionValues MlsShapeFunctions::evaluate(const Vec3& x, int derivative_order) const {
  ShapeFunctionValues out;
  evaluate(x, derivative_order, out);
  return out;
}

std::vector<ShapeFunctionValues> MlsShapeFunctions::evaluate_all(const PointMatrix& points, int derivative_order,
                                                                 bool grow_if_singular) const {
  if (derivative_order < 0 || derivative_order > 2)
    throw std::invalid_argument(fmt::format("MLS derivative order must be 0, 1 or 2, got {}", derivative_order));
  const Index count = points.cols();
  std::vector<ShapeFunctionValues> results(static_cast<std::size_t>(count));
  Index failed = -1;
  std::exception_ptr error;
#pragma omp parallel for schedule(dynamic, 64)
  for (Index i = 0; i < count; ++i) {
    try {
      evaluate(points.col(i), derivative_order, results[static_cast<std::size_t>(i)], grow_if_singular);
    } catch (...) {
#pragma omp critical(lamina_mls_evaluate_all)
      {
        if (failed < 0 || i < failed) {
          failed = i;
          error = std::current_exception();
        }
      }
    }
  }
  if (error) std::rethrow_exception(error);
  return results;
}

FieldValue MlsShapeFunctions::approximate(const Vec3& x, const Eigen::Ref<const Eigen::VectorXd>& nodal_values,
                                          int derivative_order) const {
  if (nodal_values.size() != node_count())
    throw std::invalid_argument(
        fmt::format("MLS approximate: {} nodal values for {} nodes", nodal_values.size(), node_count()));
  ShapeFunctionValues shape;
  evaluate(x, derivative_order, shape);
  return approximate_field(shape, nodal_values);
}

}  // namespace lamina::mls
