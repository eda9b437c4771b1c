#include "mls/mls_shape_functions.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include "core/error.hpp"
#include "mls/basis.hpp"
#include "mls/moment_matrix.hpp"
#include "mls/nodal_spacing.hpp"
#include "mls/weight_function.hpp"

namespace lamina::mls {

namespace detail {

/// Per-thread scratch memory; vectors keep their capacity between evaluations.
struct MlsWorkspace {
  std::vector<std::pair<Index, Index>> candidates;  // (node index, cell-order position or -1)
  std::vector<std::pair<Real, Index>> nearest;
  IndexList indices;
  std::vector<Real> offsets;  // 3 per neighbour: x - x_I
  std::vector<Real> radii;    // 3 per neighbour
  std::vector<Real> weights;  // 10 arrays of n: w, w_x, w_y, w_z, w_xx, w_yy, w_zz, w_xy, w_yz, w_zx
  std::vector<Real> basis;    // m per neighbour: p((x_I - x) / rho)
  std::vector<Real> projections;  // 1 + 3 arrays of n: p_I.r, p_I.r_,i
  std::vector<Real> combined;     // n
};

}  // namespace detail

namespace {

detail::MlsWorkspace& thread_workspace() {
  thread_local detail::MlsWorkspace workspace;
  return workspace;
}

template <class Vector>
void grow(Vector& vector, std::size_t size) {
  if (vector.size() < size) vector.resize(size);
}

/// Weight of one neighbour and its derivatives with respect to the evaluation point x, written to
/// weights[q * stride + j] for q = 0 (w), 1..3 (w_,i), 4..9 (w_,ij in xx yy zz xy yz zx).
template <int Dim>
void box_weight(const WeightFunction& function, const Real* offset, const Real* radius, Real* weights,
                std::size_t stride, std::size_t j) {
  Real value[3], first[3], second[3];
  for (int d = 0; d < Dim; ++d) {
    const Real inverse = 1.0 / radius[d];
    const Real distance = std::abs(offset[d]);
    const WeightValue w = function.evaluate(distance * inverse);
    value[d] = w.value;
    first[d] = (offset[d] >= 0.0 ? w.first : -w.first) * inverse;
    second[d] = w.second * inverse * inverse;
  }
  if constexpr (Dim == 1) {
    weights[j] = value[0];
    weights[stride + j] = first[0];
    weights[4 * stride + j] = second[0];
  } else if constexpr (Dim == 2) {
    weights[j] = value[0] * value[1];
    weights[stride + j] = first[0] * value[1];
    weights[2 * stride + j] = value[0] * first[1];
    weights[4 * stride + j] = second[0] * value[1];
    weights[5 * stride + j] = value[0] * second[1];
    weights[7 * stride + j] = first[0] * first[1];
  } else {
    weights[j] = value[0] * value[1] * value[2];
    weights[stride + j] = first[0] * value[1] * value[2];
    weights[2 * stride + j] = value[0] * first[1] * value[2];
    weights[3 * stride + j] = value[0] * value[1] * first[2];
    weights[4 * stride + j] = second[0] * value[1] * value[2];
    weights[5 * stride + j] = value[0] * second[1] * value[2];
    weights[6 * stride + j] = value[0] * value[1] * second[2];
    weights[7 * stride + j] = first[0] * first[1] * value[2];
    weights[8 * stride + j] = value[0] * first[1] * first[2];
    weights[9 * stride + j] = first[0] * value[1] * first[2];
  }
}

/// Spherical support: s = |x - x_I| / R; w_,i = (w'/s) dx_i / R^2,
/// w_,ij = (w'/s) delta_ij / R^2 + (w'' - w'/s) (dx_i / r)(dx_j / r) / R^2.
template <int Dim>
void sphere_weight(const WeightFunction& function, const Real* offset, Real radius, Real* weights,
                   std::size_t stride, std::size_t j) {
  Real squared = 0.0;
  for (int d = 0; d < Dim; ++d) squared += offset[d] * offset[d];
  const Real distance = std::sqrt(squared);
  const Real inverse_squared = 1.0 / (radius * radius);
  const WeightValue w = function.evaluate(distance / radius);
  weights[j] = w.value;
  Real unit[3] = {0.0, 0.0, 0.0};
  if (distance > 0.0)
    for (int d = 0; d < Dim; ++d) unit[d] = offset[d] / distance;
  const Real radial = (w.second - w.first_over_s) * inverse_squared;
  const Real isotropic = w.first_over_s * inverse_squared;
  for (int d = 0; d < Dim; ++d) weights[(1 + d) * stride + j] = isotropic * offset[d];
  constexpr int first_index[6] = {0, 1, 2, 0, 1, 2};
  constexpr int second_index[6] = {0, 1, 2, 1, 2, 0};
  for (int k = 0; k < 6; ++k) {
    const int a = first_index[k], b = second_index[k];
    if (a >= Dim || b >= Dim) continue;
    weights[(4 + k) * stride + j] = radial * unit[a] * unit[b] + (a == b ? isotropic : 0.0);
  }
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
  const int dimension = options_.dimension;
  basis_size_ = mls::basis_size(dimension, options_.basis);
  const Index count = nodes_.cols();
  if (count == 0) throw InputError("mls.nodes", "at least one node", "none");
  if (!nodes_.allFinite()) throw InputError("mls.nodes", "finite coordinates", "NaN or infinity");
  projected_ = nodes_;
  projected_.bottomRows(3 - dimension).setZero();
  const Real widen = 1.0 + support_epsilon;

  switch (options_.mode) {
    case SupportMode::kappa: {
      if (spacing.cols() == 0) {
        spacing_ = estimate_nodal_spacing(nodes_, dimension);
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
        if (options_.shape == SupportShape::box) {
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
      radius.tail(3 - dimension).setZero();
      radii_.colwise() = radius;
      break;
    }
    case SupportMode::all: {
      const Real mean = mean_nodal_spacing(projected_, dimension);
      const Index wanted = options_.nearest;
      radii_ = Eigen::Matrix3Xd::Zero(3, count);
      if (count >= 2 && mean > 0.0) {
        const CellList search(projected_, mean * std::max(1.0, 0.6 * std::pow(static_cast<Real>(wanted), 1.0 / dimension)));
#pragma omp parallel
        {
          std::vector<std::pair<Real, Index>> nearest;
#pragma omp for schedule(static)
          for (Index i = 0; i < count; ++i) {
            search.nearest(projected_.col(i), wanted, nearest, i);
            const Real distance = nearest.empty() ? 0.0 : std::sqrt(nearest.back().first);
            radii_.col(i).head(dimension).setConstant(options_.scale * widen * distance);
          }
        }
      }
      if (!(radii_.topRows(dimension).array() > 0.0).all())
        throw InputError("mls.nearest", "distinct nodes so that every node has a nearest node at a positive distance",
                         "coincident nodes");
      break;
    }
    case SupportMode::nearest:
    case SupportMode::variable:
      break;
  }

  Real cell_size = 1.0;
  if (node_centred()) {
    max_radius_ = radii_.rowwise().maxCoeff();
    cell_size = max_radius_.maxCoeff();
  } else {
    const Real mean = mean_nodal_spacing(projected_, dimension);
    const Real wanted = static_cast<Real>(options_.nearest);
    cell_size = mean * std::max(1.0, 0.6 * std::pow(wanted, 1.0 / dimension));
  }
  if (!(cell_size > 0.0) || !std::isfinite(cell_size)) cell_size = 1.0;  // single node / coincident nodes
  cells_ = CellList(projected_, cell_size);
  if (node_centred()) {
    sorted_radii_.resize(3, count);
    for (Index k = 0; k < count; ++k) sorted_radii_.col(k) = radii_.col(cells_.order()[k]);
  }
}

bool MlsShapeFunctions::node_centred() const {
  return options_.mode == SupportMode::kappa || options_.mode == SupportMode::fixed_radius ||
         options_.mode == SupportMode::all;
}

Index MlsShapeFunctions::gather(const Vec3& x, Real radius_factor, Index nearest_count,
                                detail::MlsWorkspace& workspace, Vec3& rho) const {
  const int dimension = options_.dimension;
  const bool box = options_.shape == SupportShape::box;
  auto& candidates = workspace.candidates;
  candidates.clear();
  rho.setZero();
  const PointMatrix& sorted = cells_.sorted_points();
  const std::vector<Index>& order = cells_.order();

  auto inside = [&](const Real* offset, const Real* radius) {
    if (box) {
      for (int d = 0; d < dimension; ++d)
        if (!(std::abs(offset[d]) < radius[d])) return false;
      return true;
    }
    Real squared = 0.0;
    for (int d = 0; d < dimension; ++d) squared += offset[d] * offset[d];
    return squared < radius[0] * radius[0];
  };

  Real point_radius = 0.0;
  if (node_centred()) {
    const Vec3 reach = max_radius_ * radius_factor;
    cells_.for_each_candidate(x - reach, x + reach, [&](Index k) {
      const Real offset[3] = {x[0] - sorted(0, k), x[1] - sorted(1, k), x[2] - sorted(2, k)};
      const Real radius[3] = {sorted_radii_(0, k) * radius_factor, sorted_radii_(1, k) * radius_factor,
                              sorted_radii_(2, k) * radius_factor};
      if (inside(offset, radius)) candidates.emplace_back(order[k], k);
    });
  } else {
    cells_.nearest(x, nearest_count, workspace.nearest);
    if (workspace.nearest.empty()) return 0;
    point_radius = options_.scale * (1.0 + support_epsilon) * std::sqrt(workspace.nearest.back().first);
    if (!(point_radius > 0.0)) return 0;
    const Real radius[3] = {point_radius, point_radius, point_radius};
    if (options_.mode == SupportMode::nearest) {
      for (const auto& [distance_squared, index] : workspace.nearest) {
        const Real offset[3] = {x[0] - projected_(0, index), x[1] - projected_(1, index), x[2] - projected_(2, index)};
        if (inside(offset, radius)) candidates.emplace_back(index, -1);
      }
    } else {
      const Vec3 reach = Vec3::Constant(point_radius);
      cells_.for_each_candidate(x - reach, x + reach, [&](Index k) {
        const Real offset[3] = {x[0] - sorted(0, k), x[1] - sorted(1, k), x[2] - sorted(2, k)};
        if (inside(offset, radius)) candidates.emplace_back(order[k], k);
      });
    }
  }
  std::sort(candidates.begin(), candidates.end());

  const std::size_t n = candidates.size();
  workspace.indices.resize(n);
  grow(workspace.offsets, 3 * n);
  grow(workspace.radii, 3 * n);
  for (std::size_t j = 0; j < n; ++j) {
    const auto [index, position] = candidates[j];
    workspace.indices[j] = index;
    Real* offset = workspace.offsets.data() + 3 * j;
    Real* radius = workspace.radii.data() + 3 * j;
    for (int d = 0; d < 3; ++d) offset[d] = x[d] - projected_(d, index);
    if (node_centred()) {
      for (int d = 0; d < 3; ++d) {
        radius[d] = sorted_radii_(d, position) * radius_factor;
        rho[d] = std::max(rho[d], radius[d]);
      }
    } else {
      for (int d = 0; d < 3; ++d) radius[d] = point_radius;
    }
  }
  if (!node_centred()) rho.setConstant(point_radius);
  for (int d = 0; d < 3; ++d)
    if (!(rho[d] > 0.0)) rho[d] = 1.0;
  return static_cast<Index>(n);
}

template <int Dim, Basis B>
void MlsShapeFunctions::evaluate_kernel(const Vec3& x_in, int derivative_order, ShapeFunctionValues& out) const {
  using Polynomial = PolynomialBasis<Dim, B>;
  constexpr int M = Polynomial::size;
  using VectorM = Eigen::Matrix<Real, M, 1>;
  using MatrixM = Eigen::Matrix<Real, M, M>;
  detail::MlsWorkspace& workspace = thread_workspace();

  Vec3 x = x_in;
  x.tail(3 - Dim).setZero();
  const WeightFunction function(options_.weight, options_.gauss_beta);
  const bool box = options_.shape == SupportShape::box;
  const bool node_centred_mode = node_centred();
  Real radius_factor = 1.0;
  Index nearest_count = options_.nearest;
  int step = 0;
  MomentMatrixFactor<M> factor;
  Vec3 rho;
  std::size_t n = 0;

  for (;;) {
    n = static_cast<std::size_t>(gather(x, radius_factor, nearest_count, workspace, rho));
    bool regular = false;
    Real condition = std::numeric_limits<Real>::infinity();
    if (n >= static_cast<std::size_t>(M)) {
      grow(workspace.weights, 10 * n);
      grow(workspace.basis, M * n);
      Real* weights = workspace.weights.data();
      Real* basis = workspace.basis.data();
      const Real* offsets = workspace.offsets.data();
      const Real* radii = workspace.radii.data();
      MatrixM a = MatrixM::Zero();
      for (std::size_t j = 0; j < n; ++j) {
        if (box) box_weight<Dim>(function, offsets + 3 * j, radii + 3 * j, weights, n, j);
        else sphere_weight<Dim>(function, offsets + 3 * j, radii[3 * j], weights, n, j);
        Real z[3];
        for (int d = 0; d < Dim; ++d) z[d] = -offsets[3 * j + d] / rho[d];
        Polynomial::values(z, basis + M * j);
        const Eigen::Map<const VectorM> p(basis + M * j);
        a.noalias() += (weights[j] * p) * p.transpose();
      }
      regular = factor.factor(a, options_.max_condition);
      condition = factor.condition();
    }
    if (regular) {
      out.condition = condition;
      break;
    }
    // Nothing more to gain once every node is a neighbour (radius modes) or N = all nodes.
    const bool can_grow = node_centred_mode ? static_cast<Index>(n) < node_count() : nearest_count < node_count();
    if (!options_.singular_remedy || step >= options_.remedy_max_steps || !can_grow)
      throw_singular(x_in, static_cast<Index>(n), condition);
    ++step;
    if (node_centred_mode) radius_factor *= 1.25;
    else ++nearest_count;
  }
  out.remedy_steps = step;

  const Real* weights = workspace.weights.data();
  const Real* basis = workspace.basis.data();
  auto p_of = [&](std::size_t j) { return Eigen::Map<const VectorM>(basis + M * j); };
  grow(workspace.projections, 4 * n);
  Real* projections = workspace.projections.data();

  // r = A^-1 p(x), p(x) = e_0 in the shifted basis; phi_I = w_I p_I.r (eqs 1-18, 1-19).
  VectorM unit = VectorM::Zero();
  unit[0] = 1.0;
  const VectorM r = factor.solve(unit);
  out.neighbours.assign(workspace.indices.begin(), workspace.indices.end());
  out.phi.resize(static_cast<Index>(n));
  for (std::size_t j = 0; j < n; ++j) {
    projections[j] = p_of(j).dot(r);
    out.phi[j] = weights[j] * projections[j];
  }
  if (derivative_order < 1) {
    out.dphi.resize(3, 0);
    out.ddphi.resize(6, 0);
    return;
  }

  // First derivatives (eq 1-20): r_,i = A^-1 (p_,i - A_,i r), A_,i r = sum_I w_I,i (p_I.r) p_I.
  VectorM r_first[3];
  {
    VectorM right[Dim];
    for (int i = 0; i < Dim; ++i) right[i] = Polynomial::first_derivative_at_origin(i, rho);
    for (std::size_t j = 0; j < n; ++j) {
      const auto p = p_of(j);
      for (int i = 0; i < Dim; ++i) right[i].noalias() -= (weights[(1 + i) * n + j] * projections[j]) * p;
    }
    for (int i = 0; i < Dim; ++i) r_first[i] = factor.solve(right[i]);
  }
  out.dphi.setZero(3, static_cast<Index>(n));
  for (std::size_t j = 0; j < n; ++j) {
    const auto p = p_of(j);
    for (int i = 0; i < Dim; ++i) {
      const Real t = p.dot(r_first[i]);
      projections[(1 + i) * n + j] = t;
      out.dphi(i, j) = weights[(1 + i) * n + j] * projections[j] + weights[j] * t;
    }
  }
  if (derivative_order < 2) {
    out.ddphi.resize(6, 0);
    return;
  }

  // Second derivatives (eq 1-21): r_,ij = A^-1 (p_,ij - A_,i r_,j - A_,j r_,i - A_,ij r);
  // phi_I,ij = q_I + w_I p_I.r_,ij with q_I = w_I,ij p_I.r + w_I,i p_I.r_,j + w_I,j p_I.r_,i.
  out.ddphi.setZero(6, static_cast<Index>(n));
  grow(workspace.combined, n);
  Real* combined = workspace.combined.data();
  for (int k = 0; k < 6; ++k) {
    const int i = Polynomial::pair_first[k];
    const int l = Polynomial::pair_second[k];
    if (i >= Dim || l >= Dim) continue;
    VectorM right = Polynomial::second_derivative_at_origin(k, rho);
    for (std::size_t j = 0; j < n; ++j) {
      const Real q = weights[(4 + k) * n + j] * projections[j] + weights[(1 + i) * n + j] * projections[(1 + l) * n + j] +
                     weights[(1 + l) * n + j] * projections[(1 + i) * n + j];
      combined[j] = q;
      right.noalias() -= q * p_of(j);
    }
    const VectorM r_second = factor.solve(right);
    for (std::size_t j = 0; j < n; ++j) out.ddphi(k, j) = combined[j] + weights[j] * p_of(j).dot(r_second);
  }
}

void MlsShapeFunctions::throw_singular(const Vec3& x, Index neighbours, Real condition) const {
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
      advice = fmt::format("increase the support size kappa (now {})", options_.kappa);
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
  advice += options_.singular_remedy
                ? fmt::format(" (the singular remedy gave up after {} steps)", options_.remedy_max_steps)
                : ", or enable the singular remedy";
  const std::string message = fmt::format(
      "MLS moment matrix singular or ill-conditioned at x = {}: {} neighbour(s) found for the {} basis with m = {} "
      "terms in {}D, {} support ({}; {}). Fix: {}.",
      format_point(x), neighbours, to_string(options_.basis), basis_size_, dimension, to_string(options_.shape),
      to_string(options_.mode), cause, advice);
  throw SingularMomentMatrix(message, x, neighbours, basis_size_, condition);
}

void MlsShapeFunctions::evaluate(const Vec3& x, int derivative_order, ShapeFunctionValues& out) const {
  if (derivative_order < 0 || derivative_order > 2)
    throw std::invalid_argument(fmt::format("MLS derivative order must be 0, 1 or 2, got {}", derivative_order));
  const bool linear = options_.basis == Basis::linear;
  switch (options_.dimension) {
    case 1:
      linear ? evaluate_kernel<1, Basis::linear>(x, derivative_order, out)
             : evaluate_kernel<1, Basis::quadratic>(x, derivative_order, out);
      break;
    case 2:
      linear ? evaluate_kernel<2, Basis::linear>(x, derivative_order, out)
             : evaluate_kernel<2, Basis::quadratic>(x, derivative_order, out);
      break;
    default:
      linear ? evaluate_kernel<3, Basis::linear>(x, derivative_order, out)
             : evaluate_kernel<3, Basis::quadratic>(x, derivative_order, out);
      break;
  }
}

ShapeFunctionValues MlsShapeFunctions::evaluate(const Vec3& x, int derivative_order) const {
  ShapeFunctionValues out;
  evaluate(x, derivative_order, out);
  return out;
}

std::vector<ShapeFunctionValues> MlsShapeFunctions::evaluate_all(const PointMatrix& points, int derivative_order) const {
  if (derivative_order < 0 || derivative_order > 2)
    throw std::invalid_argument(fmt::format("MLS derivative order must be 0, 1 or 2, got {}", derivative_order));
  const Index count = points.cols();
  std::vector<ShapeFunctionValues> results(static_cast<std::size_t>(count));
  Index failed = -1;
  std::exception_ptr error;
#pragma omp parallel for schedule(dynamic, 64)
  for (Index i = 0; i < count; ++i) {
    try {
      evaluate(points.col(i), derivative_order, results[static_cast<std::size_t>(i)]);
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
