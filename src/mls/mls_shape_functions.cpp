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
#include "mls/nodal_spacing.hpp"
#include "mls/real4.hpp"
#include "mls/weight_function.hpp"

namespace lamina::mls {

namespace detail {

/// Per-thread scratch memory; vectors keep their capacity between evaluations.
struct MlsWorkspace {
  std::vector<std::pair<Index, Index>> candidates;  // SELECT: (rank key index, cell-order position); grow-only
  std::vector<std::pair<Real, Index>> nearest;
  std::vector<Index> positions;     // node-centred gather: cell-order positions of the neighbours
  std::vector<Index> kept_nodes;    // node-centred gather (AVX2): their node indices; grow-only
  std::vector<std::uint64_t> node_bits;  // node-centred gather: the neighbours as bits over their index range
  bool capped = false;              // SELECT: the last gather() kept only the N nearest covering nodes
  IndexList indices;                // neighbours, ascending
  // structure of arrays, n per row (row d at d * stride): x_d - x_I,d and 1 / R_I,d of the n neighbours
  std::vector<Real> offsets;
  std::vector<Real> inverse_radii;
  std::size_t stride = 0;
  std::vector<Real> weights;        // 10 arrays of n: w, w_x, w_y, w_z, w_xx, w_yy, w_zz, w_xy, w_yz, w_zx
  std::vector<Real> basis;          // n x m, column k = basis term k at the neighbours
  std::vector<Real> scratch;        // n x max(9, m): weight factors; p_I.r, p_I.r_,i, combined terms, weighted column / n x m
  // Output storage by neighbour count (slot k: empty, or k values / columns), see fit_size.
  std::vector<Eigen::VectorXd> phi_by_size;
  std::vector<Eigen::Matrix3Xd> dphi_by_size;
};

}  // namespace detail

namespace {
using namespace simd;  // Real4 and its helpers (mls/real4.hpp)

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

/// Point-centred supports measure distances in units of the mean nodal spacing per axis when the
/// largest of those spacings exceeds the smallest by this factor (a plate or shell lattice).
constexpr Real anisotropic_lattice_ratio = 1.5;

/// 1 / (mean nodal spacing) per axis of a clearly anisotropic lattice (mean spacings of two axes more
/// than anisotropic_lattice_ratio apart), else 1 on every axis: an isotropic cloud keeps plain
/// distances, not the noise of its per-axis estimates. Zero on unused axes.
Vec3 spacing_metric(const Eigen::Matrix3Xd& spacing, int dimension) {
  Vec3 metric = Vec3::Ones();
  if (spacing.cols() > 0) {
    const Vec3 mean = spacing.rowwise().mean();
    Real largest = mean[0], smallest = mean[0];
    for (int d = 1; d < dimension; ++d) {
      largest = std::max(largest, mean[d]);
      smallest = std::min(smallest, mean[d]);
    }
    if (smallest > 0.0 && std::isfinite(largest) && largest > anisotropic_lattice_ratio * smallest)
      for (int d = 0; d < dimension; ++d) metric[d] = 1.0 / mean[d];
  }
  for (int d = dimension; d < 3; ++d) metric[d] = 0.0;
  return metric;
}

detail::MlsWorkspace& thread_workspace() {
  thread_local detail::MlsWorkspace workspace;
  return workspace;
}

template <class Vector>
void grow(Vector& vector, std::size_t size) {
  if (vector.size() < size) vector.resize(size);
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

/// Box supports: per direction d the factors w(s_d), w'(s_d) sign(dx_d) / R_d, w''(s_d) / R_d^2 into
/// `factors` (9 rows of n), then their products (in 3D without second derivatives four at a time:
/// GCC does not vectorise that loop itself).
template <int Dim, Weight Kind, bool Second>
void compute_box_weights(const WeightFunction& function, std::size_t n, std::size_t stride, const Real* offsets, const Real* inverse_radii,
                         Real* factors, Real* weights) {
  for (int d = 0; d < Dim; ++d) {
    const Real* offset = offsets + d * stride;
    const Real* inverse = inverse_radii + d * stride;
    Real* value = factors + (3 * d) * n;
    Real* first = factors + (3 * d + 1) * n;
    Real* second = factors + (3 * d + 2) * n;
    for (std::size_t j = 0; j < n; ++j) {
      const WeightValue w = function.template evaluate_inside<Kind>(std::abs(offset[j]) * inverse[j]);
      value[j] = w.value;
      first[j] = std::copysign(w.first, -offset[j]) * inverse[j];  // sign(dx_d) w' / R_d, w' <= 0
      if constexpr (Second) second[j] = w.second * inverse[j] * inverse[j];
    }
  }
  auto row = [&](int d, int q) { return factors + (3 * d + q) * n; };  // q: 0 value, 1 first, 2 second
  if constexpr (Dim == 1) {
    for (std::size_t j = 0; j < n; ++j) {
      weights[j] = row(0, 0)[j];
      weights[n + j] = row(0, 1)[j];
      if constexpr (Second) weights[4 * n + j] = row(0, 2)[j];
    }
  } else if constexpr (Dim == 2) {
    const Real *v0 = row(0, 0), *v1 = row(1, 0), *f0 = row(0, 1), *f1 = row(1, 1), *s0 = row(0, 2), *s1 = row(1, 2);
    for (std::size_t j = 0; j < n; ++j) {
      weights[j] = v0[j] * v1[j];
      weights[n + j] = f0[j] * v1[j];
      weights[2 * n + j] = v0[j] * f1[j];
      if constexpr (Second) {
        weights[4 * n + j] = s0[j] * v1[j];
        weights[5 * n + j] = v0[j] * s1[j];
        weights[7 * n + j] = f0[j] * f1[j];
      }
    }
  } else {
    const Real *v0 = row(0, 0), *v1 = row(1, 0), *v2 = row(2, 0);
    const Real *f0 = row(0, 1), *f1 = row(1, 1), *f2 = row(2, 1);
    const Real *s0 = row(0, 2), *s1 = row(1, 2), *s2 = row(2, 2);
    std::size_t j = 0;
    if constexpr (!Second)
      for (; j + 4 <= n; j += 4) {  // four at a time (the factor rows and the weights do not overlap)
        const Real4 a = load4(v0 + j), b = load4(v1 + j), c = load4(v2 + j);
        const Real4 ab = a * b;  // the same products, in the same order, as the loop below
        store4(weights + j, ab * c, 4);
        store4(weights + n + j, load4(f0 + j) * b * c, 4);
        store4(weights + 2 * n + j, a * load4(f1 + j) * c, 4);
        store4(weights + 3 * n + j, ab * load4(f2 + j), 4);
      }
    for (; j < n; ++j) {
      weights[j] = v0[j] * v1[j] * v2[j];
      weights[n + j] = f0[j] * v1[j] * v2[j];
      weights[2 * n + j] = v0[j] * f1[j] * v2[j];
      weights[3 * n + j] = v0[j] * v1[j] * f2[j];
      if constexpr (Second) {
        weights[4 * n + j] = s0[j] * v1[j] * v2[j];
        weights[5 * n + j] = v0[j] * s1[j] * v2[j];
        weights[6 * n + j] = v0[j] * v1[j] * s2[j];
        weights[7 * n + j] = f0[j] * f1[j] * v2[j];
        weights[8 * n + j] = v0[j] * f1[j] * f2[j];
        weights[9 * n + j] = f0[j] * v1[j] * f2[j];
      }
    }
  }
}

/// Spherical supports (see compute_weights).
template <int Dim, Weight Kind, bool Second>
void compute_sphere_weights(const WeightFunction& function, std::size_t n, std::size_t stride, const Real* offsets,
                            const Real* inverse_radii, Real* weights) {
  for (std::size_t j = 0; j < n; ++j) {
    // u_d = dx_d / R_d (R_d equal on every axis for a sphere, unequal for an ellipsoid), s = |u|
    Real scaled[3], inverse[3];
    for (int d = 0; d < Dim; ++d) {
      inverse[d] = inverse_radii[d * stride + j];
      scaled[d] = offsets[d * stride + j] * inverse[d];
    }
    Real squared = 0.0;
    for (int d = 0; d < Dim; ++d) squared += scaled[d] * scaled[d];
    const Real s = std::sqrt(squared);
    const WeightValue w = function.template evaluate_inside<Kind>(s);
    weights[j] = w.value;
    // ds/dx_d = u_d / (s R_d): w_,d = (w'/s) u_d / R_d
    Real gradient[3];
    for (int d = 0; d < Dim; ++d) {
      gradient[d] = scaled[d] * inverse[d];
      weights[(1 + d) * n + j] = w.first_over_s * gradient[d];
    }
    if constexpr (Second) {
      // w_,ab = (w'' - w'/s) (u_a / R_a)(u_b / R_b) / s^2 + (w'/s) delta_ab / R_a^2
      const Real radial = s > 0.0 ? (w.second - w.first_over_s) / squared : 0.0;
      constexpr int first_index[6] = {0, 1, 2, 0, 1, 2};
      constexpr int second_index[6] = {0, 1, 2, 1, 2, 0};
      for (int k = 0; k < 6; ++k) {
        const int a = first_index[k], b = second_index[k];
        if (a >= Dim || b >= Dim) continue;
        weights[(4 + k) * n + j] =
            radial * gradient[a] * gradient[b] + (a == b ? w.first_over_s * inverse[a] * inverse[a] : 0.0);
      }
    }
  }
}

/// Weights of all n neighbours and their derivatives with respect to the evaluation point x, written to
/// weights[q * n + j] for q = 0 (w), 1..3 (w_,i), 4..9 (w_,ij in xx yy zz xy yz zx; only if Second).
/// Box: w = prod_d w(s_d), s_d = |dx_d| / R_d. Sphere: s = |dx| / R, w_,i = (w'/s) dx_i / R^2,
/// w_,ij = (w'/s) delta_ij / R^2 + (w'' - w'/s) (dx_i / r)(dx_j / r) / R^2.
/// offsets, inverse_radii: 3 rows of n at `stride` (structure of arrays); factors: 9 n scratch values.
template <int Dim, bool Box, Weight Kind, bool Second>
void compute_weights(const WeightFunction& function, std::size_t n, std::size_t stride, const Real* offsets, const Real* inverse_radii,
                     Real* factors, Real* weights) {
  if constexpr (Box) compute_box_weights<Dim, Kind, Second>(function, n, stride, offsets, inverse_radii, factors, weights);
  else compute_sphere_weights<Dim, Kind, Second>(function, n, stride, offsets, inverse_radii, weights);
}

template <int Dim, bool Box, bool Second>
void compute_weights(const WeightFunction& function, std::size_t n, std::size_t stride, const Real* offsets, const Real* inverse_radii,
                     Real* factors, Real* weights) {
  switch (function.kind()) {
    case Weight::gauss:
      return compute_weights<Dim, Box, Weight::gauss, Second>(function, n, stride, offsets, inverse_radii, factors, weights);
    case Weight::cubic_spline:
      return compute_weights<Dim, Box, Weight::cubic_spline, Second>(function, n, stride, offsets, inverse_radii, factors, weights);
    case Weight::quartic_spline:
      return compute_weights<Dim, Box, Weight::quartic_spline, Second>(function, n, stride, offsets, inverse_radii, factors, weights);
  }
}

template <int Dim>
void compute_weights(const WeightFunction& function, bool box, bool second, std::size_t n, std::size_t stride, const Real* offsets,
                     const Real* inverse_radii, Real* factors, Real* weights) {
  if (box) {
    if (second) compute_weights<Dim, true, true>(function, n, stride, offsets, inverse_radii, factors, weights);
    else compute_weights<Dim, true, false>(function, n, stride, offsets, inverse_radii, factors, weights);
  } else {
    if (second) compute_weights<Dim, false, true>(function, n, stride, offsets, inverse_radii, factors, weights);
    else compute_weights<Dim, false, false>(function, n, stride, offsets, inverse_radii, factors, weights);
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

/// Whether values[0..n) is strictly ascending (std::adjacent_find with >=, but four comparisons at a
/// time with AVX2: it runs once per evaluation point).
bool is_ascending(const Index* values, std::size_t n) {
  std::size_t j = 1;
  bool ascending = true;
#ifdef __AVX2__
  __m256i in_order = _mm256_set1_epi64x(-1);
  for (; j + 4 <= n; j += 4) {
    const __m256i previous = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(values + j - 1));
    const __m256i current = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(values + j));
    in_order = _mm256_and_si256(in_order, _mm256_cmpgt_epi64(current, previous));
  }
  ascending = _mm256_movemask_pd(_mm256_castsi256_pd(in_order)) == 0b1111;
#endif
  for (; j < n; ++j) ascending &= values[j - 1] < values[j];
  return ascending;
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

MlsShapeFunctions::MlsShapeFunctions(PointMatrix nodes, MlsOptions options, Eigen::Matrix3Xd spacing)
    : nodes_(std::move(nodes)), options_(std::move(options)) {
  options_.validate();
  weight_function_ = WeightFunction(options_.weight, options_.gauss_beta);
  const int dimension = options_.dimension;
  basis_size_ = mls::basis_size(dimension, options_.basis);
  const Index count = nodes_.cols();
  if (count == 0) throw InputError("mls.nodes", "at least one node", "none");
  if (!nodes_.allFinite()) throw InputError("mls.nodes", "finite coordinates", "NaN or infinity");
  projected_ = nodes_;
  projected_.bottomRows(3 - dimension).setZero();
  const Real widen = 1.0 + support_epsilon;
  Eigen::Matrix3Xd estimate;  // nodal spacing, estimated once
  bool spacing_units = false;  // metric_ is not 1: an anisotropic lattice
  if (options_.mode == SupportMode::nearest || options_.mode == SupportMode::all ||
      options_.mode == SupportMode::variable) {
    try {
      if (count >= 2) estimate = estimate_nodal_spacing(projected_, dimension);
    } catch (const InputError&) {
      // all nodes coincide: no spacing, plain distances
    }
    metric_ = spacing_metric(estimate, dimension);
    spacing_units = (metric_.head(dimension).array() != 1.0).any();
  }

  switch (options_.mode) {
    case SupportMode::kappa:
    case SupportMode::nearest: {
      if (spacing.cols() == 0) {
        spacing_ = estimate.cols() == count ? std::move(estimate) : estimate_nodal_spacing(nodes_, dimension);
      } else {
        if (spacing.cols() != count)
          throw InputError("mls.spacing", fmt::format("3 x {} nodal spacings (one column per node)", count),
                           fmt::format("3 x {}", spacing.cols()));
        if (!(spacing.topRows(dimension).array() > 0.0).all() || !spacing.allFinite())
          throw InputError("mls.spacing", "positive finite nodal spacings", "a zero, negative or non-finite value");
        spacing_ = std::move(spacing);
        spacing_.bottomRows(3 - dimension).setZero();
      }
      radii_ = Eigen::Matrix3Xd::Zero(3, count);
      for (Index i = 0; i < count; ++i) {
        if (options_.shape == SupportShape::box && options_.kappa_axes != Vec3::Zero()) {
          radii_.col(i).head(dimension) = widen * (options_.kappa_axes.head(dimension).array() + options_.delta).matrix().cwiseProduct(spacing_.col(i).head(dimension));
        } else if (options_.shape == SupportShape::box) {
          radii_.col(i).head(dimension) = (options_.kappa + options_.delta) * widen * spacing_.col(i).head(dimension);
        } else if (options_.mode == SupportMode::nearest && spacing_units) {
          // SELECT on an anisotropic lattice: a sphere in units of the node's spacing per axis, as the
          // nearest are counted (an ellipsoid of radii kappa h_I,d)
          radii_.col(i).head(dimension) = options_.kappa * widen * spacing_.col(i).head(dimension);
        } else {
          radii_.col(i).head(dimension).setConstant(options_.kappa * widen * spacing_.col(i).head(dimension).maxCoeff());
        }
      }
      break;
    }
    case SupportMode::fixed_radius: {
      radii_ = Eigen::Matrix3Xd::Zero(3, count);
      Vec3 radius = options_.radius * widen;
      if (options_.shape == SupportShape::sphere) radius.setConstant(options_.radius[0] * widen);
      for (int d = dimension; d < 3; ++d) radius[d] = 0.0;
      radii_.colwise() = radius;
      break;
    }
    case SupportMode::all: {
      // the N-th nearest in spacing units (metric_): R_I,d = scale x that distance / metric_d
      const PointMatrix scaled = metric_.asDiagonal() * projected_;
      const Real mean = mean_nodal_spacing(scaled, dimension);
      const Index wanted = options_.nearest;
      radii_ = Eigen::Matrix3Xd::Zero(3, count);
      if (count >= 2 && mean > 0.0) {
        const CellList search(scaled, mean * std::max(1.0, 0.6 * std::pow(static_cast<Real>(wanted), 1.0 / dimension)));
#pragma omp parallel
        {
          std::vector<std::pair<Real, Index>> nearest;
#pragma omp for schedule(static)
          for (Index i = 0; i < count; ++i) {
            search.nearest(scaled.col(i), wanted, nearest, i);
            const Real distance = nearest.empty() ? 0.0 : std::sqrt(nearest.back().first);
            for (int d = 0; d < dimension; ++d) radii_(d, i) = options_.scale * widen * distance / metric_[d];
          }
        }
      }
      if (!(radii_.topRows(dimension).array() > 0.0).all())
        throw InputError("mls.nearest", "distinct nodes so that every node has a nearest node at a positive distance",
                         "coincident nodes");
      break;
    }
    case SupportMode::variable:
      break;
  }
  Real cell_size = 1.0;
  if (node_centred()) {
    max_radius_ = radii_.rowwise().maxCoeff();
    // Half the largest radius: a query box of +-R then spans about 5 cells per axis, fewer candidates
    // than 3 cells of size R, and the cells of one x-row are contiguous anyway.
    cell_size = 0.5 * max_radius_.maxCoeff();
  } else {
    metric_points_ = metric_.asDiagonal() * projected_;
    const Real mean = mean_nodal_spacing(metric_points_, dimension);
    const Real wanted = static_cast<Real>(options_.nearest);
    cell_size = mean * std::max(1.0, 0.6 * std::pow(wanted, 1.0 / dimension));
  }
  if (!(cell_size > 0.0) || !std::isfinite(cell_size)) cell_size = 1.0;  // single node / coincident nodes
  cells_ = CellList(node_centred() ? projected_ : metric_points_, cell_size);
  if (node_centred()) {
    sorted_inverse_radii_ = Eigen::Matrix3Xd::Zero(3, count);
    for (Index k = 0; k < count; ++k)
      for (int d = 0; d < dimension; ++d) sorted_inverse_radii_(d, k) = 1.0 / radii_(d, cells_.order()[k]);
    sorted_order_.assign(cells_.order().begin(), cells_.order().end());
    sorted_order_.resize(static_cast<std::size_t>(count) + 4, 0);
    position_of_node_.resize(static_cast<std::size_t>(count));
    for (Index k = 0; k < count; ++k) position_of_node_[static_cast<std::size_t>(cells_.order()[k])] = k;
    row_stride_ = static_cast<std::size_t>(count) + 4;
    sorted_rows_.assign(6 * row_stride_, 0.0);
    for (Index k = 0; k < count; ++k)
      for (int d = 0; d < 3; ++d) {
        sorted_rows_[d * row_stride_ + static_cast<std::size_t>(k)] = cells_.sorted_points()(d, k);
        sorted_rows_[(3 + d) * row_stride_ + static_cast<std::size_t>(k)] = sorted_inverse_radii_(d, k);
      }
  }
}

bool MlsShapeFunctions::node_centred() const {
  return options_.mode != SupportMode::variable;
}

template <int Dim>
Index MlsShapeFunctions::gather(const Vec3& x, Real radius_factor, Index nearest_count,
                                detail::MlsWorkspace& workspace, Vec3& rho) const {
  const bool box = options_.shape == SupportShape::box;
  const PointMatrix& sorted = cells_.sorted_points();
  const Index* order = cells_.order().data();
  const Real inverse_factor = 1.0 / radius_factor;
  std::size_t count = 0;

  if (node_centred()) {
    // Pass 1 tests the candidates four at a time along each row of cells (lanes past the row's end are
    // masked off) and keeps the cell-order positions of the nodes whose supports cover x (about half of
    // the candidates). With AVX2 it also keeps their node indices, offsets x - x_I and inverse radii,
    // packed by a lane permutation (rows of `stride`); otherwise pass 2 writes them from the positions.
    const Vec3 reach = max_radius_ * radius_factor;
    const Vec3 low = x - reach, high = x + reach;
    const auto stride = static_cast<std::size_t>(cells_.candidate_bound(low, high) + 4);
    grow(workspace.positions, stride);
    grow(workspace.kept_nodes, stride);
    grow(workspace.offsets, 3 * stride);
    grow(workspace.inverse_radii, 3 * stride);
    Index* positions = workspace.positions.data();
    Index* kept_nodes = workspace.kept_nodes.data();
    const Index* node_of_position = sorted_order_.data();  // order() padded with 4 entries
    Real* offset_rows = workspace.offsets.data();
    Real* inverse_rows = workspace.inverse_radii.data();
    const Real* points = sorted.data();
    const Real* node_inverse_radii = sorted_inverse_radii_.data();
    const Real* rows[6];
    for (int r = 0; r < 6; ++r) rows[r] = sorted_rows_.data() + static_cast<std::size_t>(r) * row_stride_;
    const Real4 lane_index = {0.0, 1.0, 2.0, 3.0};
    cells_.for_each_candidate_range(low, high, [&](Index begin, Index end) {
      for (Index k = begin; k < end; k += 4) {
        Mask4 inside = lane_index < static_cast<Real>(end - k);
        Real4 offset[3], inverse[3];
        for (int d = 0; d < 3; ++d) {
          offset[d] = x[d] - load4(rows[d] + k);
          inverse[d] = load4(rows[3 + d] + k) * inverse_factor;
        }
        if (box) {
          for (int d = 0; d < Dim; ++d) inside &= (offset[d] < 0.0 ? -offset[d] : offset[d]) * inverse[d] < 1.0;
        } else {
          // a sphere, or an ellipsoid of per-axis radii (mode all on an anisotropic lattice)
          Real4 squared = {0.0, 0.0, 0.0, 0.0};
          for (int d = 0; d < Dim; ++d) {
            const Real4 scaled = offset[d] * inverse[d];
            squared += scaled * scaled;
          }
          inside &= squared < 1.0;
        }
#ifdef __AVX2__
        const int kept = _mm256_movemask_pd(reinterpret_cast<__m256d>(inside));
        const __m256i permutation = _mm256_load_si256(&compress_lanes[kept]);
        for (int d = 0; d < 3; ++d) {
          _mm256_storeu_pd(offset_rows + d * stride + count, compress(offset[d], permutation));
          _mm256_storeu_pd(inverse_rows + d * stride + count, compress(inverse[d], permutation));
        }
        const __m256i position = _mm256_add_epi64(_mm256_set1_epi64x(k), _mm256_setr_epi64x(0, 1, 2, 3));
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(positions + count),
                            _mm256_permutevar8x32_epi32(position, permutation));
        const __m256i node = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(node_of_position + k));
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(kept_nodes + count), _mm256_permutevar8x32_epi32(node, permutation));
        count += static_cast<std::size_t>(__builtin_popcount(static_cast<unsigned>(kept)));
#else
        for (int l = 0; l < 4; ++l) {
          positions[count] = k + l;  // branch-free: kept only if inside
          count += static_cast<std::size_t>(inside[l] & 1);
        }
#endif
      }
    });
#ifdef __AVX2__
    bool packed = true;  // the neighbours' offsets and inverse radii are in rows of `stride`
#else
    bool packed = false;
#endif
    // SELECT: of the nodes whose supports cover x, the N nearest (spacing units, ties by node index).
    workspace.capped = options_.mode == SupportMode::nearest && count > static_cast<std::size_t>(nearest_count);
    if (workspace.capped) {
      auto& ranked = workspace.nearest;  // (squared distance in spacing units, node index) per position
      ranked.resize(count);
      for (std::size_t c = 0; c < count; ++c) {
        const Real* p = points + 3 * positions[c];
        Real squared = 0.0;
        for (int d = 0; d < Dim; ++d) {
          const Real scaled = (x[d] - p[d]) * metric_[d];
          squared += scaled * scaled;
        }
        // rounded to float: nodes at equal distances on a lattice tie whatever the last bits of their
        // computed distances (rounding differs between builds), and ties go to the lower node index
        ranked[c] = {static_cast<Real>(static_cast<float>(squared)), order[positions[c]]};
      }
      grow(workspace.candidates, count);
      std::pair<Index, Index>* slots = workspace.candidates.data();  // (rank key index, position)
      for (std::size_t c = 0; c < count; ++c) slots[c] = {static_cast<Index>(c), positions[c]};
      std::nth_element(slots, slots + (nearest_count - 1), slots + count,
                       [&](const auto& a, const auto& b) { return ranked[a.first] < ranked[b.first]; });
      count = static_cast<std::size_t>(nearest_count);
      for (std::size_t c = 0; c < count; ++c) positions[c] = slots[c].second;
      packed = false;
    }
    // Pass 2: neighbour data in rows of n, ascending node index (the cells deliver structured grids
    // already sorted; otherwise the positions are sorted by node index and the data written from them).
    const auto n = count;
    workspace.indices.resize(n);
    Index* indices = workspace.indices.data();
    bool ascending = true;
    if (packed) {  // pass 1 kept the node indices as well
      std::copy(kept_nodes, kept_nodes + n, indices);
      ascending = is_ascending(indices, n);
    } else {
      for (std::size_t j = 0; j < n; ++j) {
        indices[j] = order[positions[j]];
        ascending &= j == 0 || indices[j - 1] < indices[j];
      }
    }
    const auto write = [&] {
      for (std::size_t j = 0; j < n; ++j) {
        const Index k = positions[j];
        indices[j] = order[k];
        for (int d = 0; d < 3; ++d) {
          offset_rows[d * n + j] = x[d] - points[3 * k + d];
          inverse_rows[d * n + j] = node_inverse_radii[3 * k + d] * inverse_factor;
        }
      }
    };
    Index lowest = std::numeric_limits<Index>::max(), highest = 0;
    if (!ascending)
      for (std::size_t j = 0; j < n; ++j) {
        lowest = std::min(lowest, indices[j]);
        highest = std::max(highest, indices[j]);
      }
    if (!ascending && n > 0 && highest - lowest < 64 * static_cast<Index>(n)) {
      // Ascending by a bit per node over the neighbours' index range, read back word by word: on a
      // lattice the range is a few node layers (a thin plate's cells hold every layer through the
      // thickness, so the candidates never come in node order there), and the scan of range / 64 words
      // costs less than sorting n keys.
      const auto words = static_cast<std::size_t>((highest - lowest) / 64 + 1);
      workspace.node_bits.assign(words, 0);
      std::uint64_t* bits = workspace.node_bits.data();
      for (std::size_t j = 0; j < n; ++j) {
        const auto bit = static_cast<std::uint64_t>(indices[j] - lowest);
        bits[bit / 64] |= std::uint64_t{1} << (bit % 64);
      }
      std::size_t j = 0;
      for (std::size_t w = 0; w < words; ++w)
        for (std::uint64_t word = bits[w]; word != 0; word &= word - 1)
          indices[j++] = lowest + static_cast<Index>(64 * w) + __builtin_ctzll(word);
      for (j = 0; j < n; ++j) positions[j] = position_of_node_[static_cast<std::size_t>(indices[j])];
      write();
    } else if (!ascending) {
      // sorted as (node index, candidate) keys: plain integer comparisons, where a comparator through
      // order[] loaded two node indices per comparison
      int shift = 1;
      while ((std::size_t{1} << shift) < n) ++shift;
      Index* keys = kept_nodes;  // free: the node indices are in `indices`
      for (std::size_t j = 0; j < n; ++j) keys[j] = (indices[j] << shift) | static_cast<Index>(j);
      std::sort(keys, keys + n);
      const Index mask = (Index{1} << shift) - 1;
      for (std::size_t j = 0; j < n; ++j) keys[j] = positions[keys[j] & mask];
      std::copy(keys, keys + n, positions);
      write();
    } else if (!packed) {
      write();
    }
    workspace.stride = ascending && packed ? stride : n;
    // Basis scaling rho_d: the largest support radius among the neighbours.
    // (four independent minima per direction: one serial chain of min would cost its latency per neighbour)
    constexpr Real infinity = std::numeric_limits<Real>::infinity();
    for (int d = 0; d < 3; ++d) {
      Real4 smallest = {infinity, infinity, infinity, infinity};
      const Real* inverse = inverse_rows + d * workspace.stride;
      std::size_t j = 0;
      for (; j + 4 <= n; j += 4) {
        const Real4 value = load4(inverse + j);
        smallest = value < smallest ? value : smallest;
      }
      for (; j < n; ++j) smallest[0] = std::min(smallest[0], inverse[j]);
      rho[d] = 1.0 / std::min(std::min(smallest[0], smallest[1]), std::min(smallest[2], smallest[3]));
      if (!(rho[d] > 0.0) || !std::isfinite(rho[d])) rho[d] = 1.0;
    }
    return static_cast<Index>(n);
  } else {
    // VARIABLE: the N nearest nodes of x in spacing units (metric_), weighted from x with the radius
    // scale x (distance to the N-th): a sphere or box there, an ellipsoid or box of radii
    // R_d = radius / metric_d in space.
    workspace.capped = false;
    const Vec3 scaled_x = metric_.cwiseProduct(x);
    cells_.nearest(scaled_x, nearest_count, workspace.nearest);
    const Real point_radius = workspace.nearest.empty()
                                  ? 0.0
                                  : options_.scale * (1.0 + support_epsilon) * std::sqrt(workspace.nearest.back().first);
    if (!(point_radius > 0.0)) return 0;
    const Real inverse = 1.0 / point_radius;
    Real inverses[3] = {0.0, 0.0, 0.0};
    for (int d = 0; d < Dim; ++d) inverses[d] = metric_[d] * inverse;
    // the N nearest inside that support (all of them for scale >= 1), in ascending node index
    IndexList& indices = workspace.indices;
    indices.clear();
    for (const auto& [distance_squared, index] : workspace.nearest) {
      bool inside = true;
      Real squared = 0.0;
      for (int d = 0; d < Dim; ++d) {
        const Real scaled = (x[d] - projected_(d, index)) * inverses[d];
        inside &= std::abs(scaled) < 1.0;
        squared += scaled * scaled;
      }
      if (box ? inside : squared < 1.0) indices.push_back(index);
    }
    std::sort(indices.begin(), indices.end());
    const std::size_t n = indices.size();
    grow(workspace.offsets, 3 * n);
    grow(workspace.inverse_radii, 3 * n);
    workspace.stride = n;
    for (std::size_t j = 0; j < n; ++j)
      for (int d = 0; d < 3; ++d) {
        workspace.offsets[d * n + j] = x[d] - projected_(d, indices[j]);
        workspace.inverse_radii[d * n + j] = inverses[d];
      }
    for (int d = 0; d < 3; ++d) rho[d] = d < Dim ? point_radius / metric_[d] : 1.0;
    return static_cast<Index>(n);
  }
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
