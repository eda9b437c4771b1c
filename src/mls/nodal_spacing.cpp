#include "mls/nodal_spacing.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "mls/neighbour_search.hpp"

namespace lamina::mls {

Real mean_nodal_spacing(const PointMatrix& nodes, int dimension) {
  if (nodes.cols() == 0) return 0.0;
  const Vec3 extent = nodes.rowwise().maxCoeff() - nodes.rowwise().minCoeff();
  Real largest = 0.0;  // (a loop: head(dimension) of a Vec3 draws a false -Warray-bounds from GCC 12 with AVX)
  for (int d = 0; d < dimension; ++d) largest = std::max(largest, extent[d]);
  Real volume = 1.0;
  int axes = 0;
  for (int d = 0; d < dimension; ++d) {
    if (extent[d] > 1e-12 * largest) {
      volume *= extent[d];
      ++axes;
    }
  }
  if (axes == 0) return 0.0;
  return std::pow(volume / static_cast<Real>(nodes.cols()), 1.0 / axes);
}

Eigen::Matrix3Xd estimate_nodal_spacing(const PointMatrix& nodes_in, int dimension) {
  if (dimension < 1 || dimension > 3)
    throw InputError("mls.dimension", "1, 2 or 3", std::to_string(dimension));
  const Index count = nodes_in.cols();
  PointMatrix nodes = nodes_in;
  nodes.bottomRows(3 - dimension).setZero();
  const Real spacing = count >= 2 ? mean_nodal_spacing(nodes, dimension) : 0.0;
  if (!(spacing > 0.0) || !std::isfinite(spacing))
    throw InputError("mls.nodes", "at least 2 distinct finite nodes to estimate the nodal spacing",
                     std::to_string(count) + " node(s)");
  const CellList cells(nodes, spacing);
  const int neighbour_count = dimension == 1 ? 2 : (dimension == 2 ? 8 : 26);
  const Real cosine = 1.0 / std::sqrt(static_cast<Real>(dimension));
  Eigen::Matrix3Xd result = Eigen::Matrix3Xd::Zero(3, count);
  std::vector<char> missing(count, 0);

#pragma omp parallel
  {
    std::vector<std::pair<Real, Index>> nearest;
#pragma omp for schedule(static)
    for (Index i = 0; i < count; ++i) {
      const Vec3 x = nodes.col(i);
      cells.nearest(x, neighbour_count, nearest, i);
      Real plus[3], minus[3];
      std::fill(plus, plus + 3, INFINITY);
      std::fill(minus, minus + 3, INFINITY);
      for (const auto& [distance_squared, j] : nearest) {
        if (!(distance_squared > 0.0)) continue;  // coincident node
        const Vec3 dx = nodes.col(j) - x;
        const Real distance = std::sqrt(distance_squared);
        for (int d = 0; d < dimension; ++d) {
          const Real along = std::abs(dx[d]);
          if (along < cosine * distance * (1.0 - 1e-12)) continue;
          Real& side = dx[d] > 0.0 ? plus[d] : minus[d];
          side = std::min(side, along);
        }
      }
      Real largest = 0.0;
      for (int d = 0; d < dimension; ++d) {
        Real value = 0.0;
        if (std::isfinite(plus[d]) && std::isfinite(minus[d])) value = std::max(plus[d], minus[d]);
        else if (std::isfinite(plus[d])) value = plus[d];
        else if (std::isfinite(minus[d])) value = minus[d];
        result(d, i) = value;
        largest = std::max(largest, value);
      }
      if (largest > 0.0) {
        for (int d = 0; d < dimension; ++d)
          if (result(d, i) == 0.0) result(d, i) = largest;
      } else {
        missing[i] = 1;
      }
    }
  }
  // Nodes whose nearest neighbours all coincide with them: use the cloud's mean spacing.
  for (Index i = 0; i < count; ++i)
    if (missing[i]) result.col(i).head(dimension).setConstant(spacing);
  return result;
}

}  // namespace lamina::mls
