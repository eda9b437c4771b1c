// The supports of MlsShapeFunctions: each node's radii (kappa, fixed radius, the N-th nearest), the
// metric of an anisotropic lattice, and the cell list with the nodes' coordinates and inverse radii as
// rows in its order (what the neighbour gather reads).
#include <algorithm>
#include <cmath>
#include <utility>

#include <fmt/format.h>

#include "core/error.hpp"
#include "mls/mls_shape_functions.hpp"
#include "mls/nodal_spacing.hpp"
#include "mls/weight_function.hpp"

namespace lamina::mls {

namespace {

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

}  // namespace

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

}  // namespace lamina::mls
