#include "efg/volumetric_projection.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "core/error.hpp"

namespace lamina::efg {

Eigen::VectorXd ProjectedVolumetric::nodal_divergence(const Eigen::VectorXd& u) const {
  Eigen::VectorXd theta(pressure_nodes());
  for (Index i = 0; i < pressure_nodes(); ++i) {
    const auto& list = nodes[static_cast<std::size_t>(i)];
    const auto& g = divergence[static_cast<std::size_t>(i)];
    Real sum = 0.0;
    for (std::size_t k = 0; k < list.size(); ++k) sum += g.col(static_cast<Index>(k)).dot(u.segment<3>(3 * list[k]));
    theta[i] = sum / lumped[i];
  }
  return theta;
}

void ProjectedVolumetric::add_stiffness(const solve::BlockPattern& pattern, Real* values) const {
  const Index n = pattern.nodes();
  // transpose: for every displacement node J the pressure nodes I with J in nodes[I], and J's position
  std::vector<Index> start(static_cast<std::size_t>(n + 1), 0);
  for (const auto& list : nodes)
    for (Index j : list) ++start[static_cast<std::size_t>(j + 1)];
  for (Index j = 0; j < n; ++j) start[static_cast<std::size_t>(j + 1)] += start[static_cast<std::size_t>(j)];
  std::vector<std::pair<Index, Index>> entries(static_cast<std::size_t>(start.back()));
  {
    std::vector<Index> fill(start.begin(), start.end() - 1);
    for (Index i = 0; i < pressure_nodes(); ++i) {
      const auto& list = nodes[static_cast<std::size_t>(i)];
      for (std::size_t k = 0; k < list.size(); ++k)
        entries[static_cast<std::size_t>(fill[static_cast<std::size_t>(list[k])]++)] = {i, static_cast<Index>(k)};
    }
  }
  const Eigen::VectorXd scale = lambda.cwiseQuotient(lumped);
#pragma omp parallel
  {
    // column block J of the upper triangle: sum over I of scale_I g_Ik g_IJ^T for nodes k <= J
    std::vector<Mat3> accumulator(static_cast<std::size_t>(n), Mat3::Zero());
#pragma omp for schedule(dynamic, 16)
    for (Index J = 0; J < n; ++J) {
      for (Index e = start[static_cast<std::size_t>(J)]; e < start[static_cast<std::size_t>(J + 1)]; ++e) {
        const auto [i, position] = entries[static_cast<std::size_t>(e)];
        const auto& list = nodes[static_cast<std::size_t>(i)];
        const auto& g = divergence[static_cast<std::size_t>(i)];
        const Vec3 gJ = scale[i] * g.col(position);
        for (Index k = 0; k <= position; ++k)  // list sorted: entries 0..position are the nodes <= J
          accumulator[static_cast<std::size_t>(list[static_cast<std::size_t>(k)])].noalias() += g.col(k) * gJ.transpose();
      }
      Index rank = 0;
      for (const Index* it = pattern.neighbours_begin(J); it != pattern.neighbours_end(J); ++it, ++rank) {
        Mat3& block = accumulator[static_cast<std::size_t>(*it)];
        for (int b = 0; b < 3; ++b) {
          const Index column = pattern.column_start(3 * J + b) + 3 * rank;
          const int rows = *it == J ? b + 1 : 3;
          for (int a = 0; a < rows; ++a) values[column + a] += block(a, b);
        }
        block.setZero();
      }
    }
  }
}

bool ShepardPressure::evaluate(const Vec3& x, mls::ShapeFunctionValues& out) const {
  nodes_.neighbours(x, out.neighbours);
  const auto count = static_cast<Index>(out.neighbours.size());
  out.phi.resize(count);
  const auto& radii = nodes_.support_radii();
  const bool box = nodes_.options().shape == mls::SupportShape::box;
  const int dimension = nodes_.options().dimension;
  Real sum = 0.0;
  for (Index k = 0; k < count; ++k) {
    const Index i = out.neighbours[static_cast<std::size_t>(k)];
    const Vec3 d = x - nodes_.nodes().col(i);
    Real w = 1.0;
    if (box) {
      for (int a = 0; a < dimension; ++a) w *= weight_.evaluate(std::abs(d[a]) / radii(a, i)).value;
    } else {
      Real r2 = 0.0;  // (a loop, not d.head(dimension): GCC 12 warns on the vectorised dynamic-size block of a Vec3)
      for (int a = 0; a < dimension; ++a) r2 += d[a] * d[a];
      w = weight_.evaluate(std::sqrt(r2) / radii(0, i)).value;
    }
    out.phi[k] = w;
    sum += w;
  }
  if (!(sum > 0.0)) return false;
  out.phi /= sum;
  return true;
}

ProjectedVolumetric project_volumetric(const mls::MlsShapeFunctions& shapes, const ShepardPressure& pressure,
                                       const VolumeQuadrature& volume, const Eigen::VectorXd& lambda_at_point) {
  const Index n = shapes.node_count(), pressure_nodes = pressure.nodes().node_count(), points = volume.size();
  const auto displacement_values = shapes.evaluate_all(volume.points, 1);
  std::vector<mls::ShapeFunctionValues> pressure_values(static_cast<std::size_t>(points));
  Index uncovered = -1;
#pragma omp parallel for schedule(static)
  for (Index q = 0; q < points; ++q)
    if (!pressure.evaluate(volume.points.col(q), pressure_values[static_cast<std::size_t>(q)])) {
#pragma omp critical(lamina_pressure_uncovered)
      if (uncovered < 0 || q < uncovered) uncovered = q;
    }
  if (uncovered >= 0)
    throw InputError("efg.integration.pressure_kappa",
                     "pressure node supports that cover every quadrature point (a larger pressure_kappa or more pressure_nodes)",
                     fmt::format("no pressure node in reach of the quadrature point ({:.6g}, {:.6g}, {:.6g})",
                                 volume.points(0, uncovered), volume.points(1, uncovered), volume.points(2, uncovered)));

  // transpose of psi: for every pressure node the quadrature points in its support, with w_q psi_I(x_q)
  std::vector<Index> start(static_cast<std::size_t>(pressure_nodes + 1), 0);
  for (const auto& pv : pressure_values)
    for (Index i : pv.neighbours) ++start[static_cast<std::size_t>(i + 1)];
  for (Index i = 0; i < pressure_nodes; ++i) start[static_cast<std::size_t>(i + 1)] += start[static_cast<std::size_t>(i)];
  std::vector<std::pair<Index, Real>> entries(static_cast<std::size_t>(start.back()));
  {
    std::vector<Index> fill(start.begin(), start.end() - 1);
    for (Index q = 0; q < points; ++q) {
      const auto& pv = pressure_values[static_cast<std::size_t>(q)];
      for (std::size_t k = 0; k < pv.neighbours.size(); ++k)
        entries[static_cast<std::size_t>(fill[static_cast<std::size_t>(pv.neighbours[k])]++)] = {
            q, volume.weights[q] * pv.phi[static_cast<Index>(k)]};
    }
  }

  ProjectedVolumetric out;
  out.nodes.resize(static_cast<std::size_t>(pressure_nodes));
  out.divergence.resize(static_cast<std::size_t>(pressure_nodes));
  out.lumped = Eigen::VectorXd::Zero(pressure_nodes);
  out.lambda = Eigen::VectorXd::Zero(pressure_nodes);
#pragma omp parallel
  {
    std::vector<Vec3> accumulator(static_cast<std::size_t>(n), Vec3::Zero());
    std::vector<char> touched(static_cast<std::size_t>(n), 0);
#pragma omp for schedule(dynamic, 8)
    for (Index i = 0; i < pressure_nodes; ++i) {
      IndexList& list = out.nodes[static_cast<std::size_t>(i)];
      Real mass = 0.0, lambda = 0.0;
      for (Index e = start[static_cast<std::size_t>(i)]; e < start[static_cast<std::size_t>(i + 1)]; ++e) {
        const auto [q, weight] = entries[static_cast<std::size_t>(e)];
        mass += weight;
        lambda += weight * lambda_at_point[q];
        const auto& sv = displacement_values[static_cast<std::size_t>(q)];
        for (std::size_t k = 0; k < sv.neighbours.size(); ++k) {
          const Index j = sv.neighbours[k];
          if (!touched[static_cast<std::size_t>(j)]) {
            touched[static_cast<std::size_t>(j)] = 1;
            list.push_back(j);
          }
          accumulator[static_cast<std::size_t>(j)] += weight * sv.dphi.col(static_cast<Index>(k));
        }
      }
      std::sort(list.begin(), list.end());
      Eigen::Matrix3Xd g(3, static_cast<Index>(list.size()));
      for (std::size_t k = 0; k < list.size(); ++k) {
        g.col(static_cast<Index>(k)) = accumulator[static_cast<std::size_t>(list[k])];
        accumulator[static_cast<std::size_t>(list[k])].setZero();
        touched[static_cast<std::size_t>(list[k])] = 0;
      }
      out.divergence[static_cast<std::size_t>(i)] = std::move(g);
      out.lumped[i] = mass;
      out.lambda[i] = mass > 0 ? lambda / mass : 0.0;
    }
  }
  for (Index i = 0; i < pressure_nodes; ++i)
    if (!(out.lumped[i] > 0))
      throw InputError("efg.integration.pressure_kappa",
                       "pressure functions that each have a positive integral over the body (a larger pressure_kappa, "
                       "fewer pressure_nodes or more Gauss points)",
                       fmt::format("pressure node {} at ({:.6g}, {:.6g}, {:.6g}) with integral {:.3g}", i,
                                   pressure.nodes().nodes()(0, i), pressure.nodes().nodes()(1, i), pressure.nodes().nodes()(2, i),
                                   out.lumped[i]));
  return out;
}

}  // namespace lamina::efg
