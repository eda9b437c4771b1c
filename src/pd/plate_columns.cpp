#include "pd/plate_columns.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <utility>

namespace lamina::pd {

std::optional<PlateColumns> find_plate_columns(const PointMatrix& positions, const Eigen::VectorXd& volumes,
                                               std::string* reason) {
  auto refuse = [&](std::string why) -> std::optional<PlateColumns> {
    if (reason) *reason = std::move(why);
    return std::nullopt;
  };
  const Index n = positions.cols();
  if (n < 8) return refuse("fewer than 8 nodes");
  const Vec3 lower = positions.rowwise().minCoeff(), upper = positions.rowwise().maxCoeff();
  const Real extent = (upper - lower).norm();
  const Real tolerance = 1e-7 * extent;
  // Group by the in-plane position (rounded to the tolerance).
  std::map<std::pair<long long, long long>, std::vector<Index>> groups;
  for (Index i = 0; i < n; ++i)
    groups[{std::llround(positions(0, i) / tolerance / 16), std::llround(positions(1, i) / tolerance / 16)}].push_back(i);
  PlateColumns c;
  c.first.push_back(0);
  std::vector<Real> heights;
  for (auto& [key, list] : groups) {
    std::sort(list.begin(), list.end(), [&](Index a, Index b) { return positions(2, a) < positions(2, b); });
    if (heights.empty()) {
      for (Index i : list) heights.push_back(positions(2, i));
      c.layers = static_cast<int>(list.size());
    }
    if (static_cast<int>(list.size()) != c.layers)
      return refuse(fmt::format("columns of {} and {} nodes", c.layers, list.size()));
    for (std::size_t k = 0; k < list.size(); ++k)
      if (std::abs(positions(2, list[k]) - heights[k]) > 1e3 * tolerance) return refuse("layers at different heights");
    for (Index i : list) c.node.push_back(i);
    c.first.push_back(static_cast<Index>(c.node.size()));
  }
  if (c.layers < 1 || c.layers > 4) return refuse(fmt::format("{} node layers (the plate models take 1-4)", c.layers));
  if (c.layers == 1) {
    // one layer: the thickness is the cells' height, volume / in-plane cell area (the smallest steps
    // between distinct column coordinates in x and in y)
    std::vector<Real> xs, ys;
    for (const auto& [key, list] : groups) {
      xs.push_back(positions(0, list.front()));
      ys.push_back(positions(1, list.front()));
    }
    auto step = [&](std::vector<Real>& values) {
      std::sort(values.begin(), values.end());
      Real smallest = INFINITY;
      for (std::size_t k = 1; k < values.size(); ++k)
        if (values[k] - values[k - 1] > 1e3 * tolerance) smallest = std::min(smallest, values[k] - values[k - 1]);
      return smallest;
    };
    const Real area = step(xs) * step(ys);
    if (!std::isfinite(area)) return refuse("a single row of nodes (not a plate)");
    c.thickness = volumes.mean() / area;
  } else {
    const Real dz = (heights.back() - heights.front()) / (c.layers - 1);
    for (int k = 1; k < c.layers; ++k)
      if (std::abs(heights[static_cast<std::size_t>(k)] - heights[static_cast<std::size_t>(k - 1)] - dz) > 1e-6 * dz)
        return refuse("unevenly spaced layers");
    c.thickness = c.layers * dz;
  }
  if (upper.x() - lower.x() < 3 * c.thickness || upper.y() - lower.y() < 3 * c.thickness)
    return refuse("in-plane extent below 4 thicknesses (a solid, not a plate)");
  const Index columns = c.columns();
  c.column_of.assign(static_cast<std::size_t>(n), -1);
  c.phi.resize(n);
  c.psi.resize(n);
  c.zeta.resize(n);
  Real spacing = INFINITY;
  Vec3 previous = Vec3::Constant(NAN);
  for (Index col = 0; col < columns; ++col) {
    Real volume = 0, moment = 0, mid = 0;
    for (Index p = c.first[col]; p < c.first[col + 1]; ++p) {
      const Index i = c.node[p];
      c.column_of[i] = col;
      volume += volumes[i];
      mid += volumes[i] * positions(2, i);
    }
    mid /= volume;
    for (Index p = c.first[col]; p < c.first[col + 1]; ++p) {
      const Index i = c.node[p];
      c.zeta[i] = positions(2, i) - mid;
      moment += volumes[i] * c.zeta[i] * c.zeta[i];
    }
    for (Index p = c.first[col]; p < c.first[col + 1]; ++p) {
      const Index i = c.node[p];
      c.phi[i] = volumes[i] / volume;
      c.psi[i] = moment > 0 ? volumes[i] * c.zeta[i] / moment : 0.0;
    }
    const Vec3 x = positions.col(c.node[c.first[col]]);
    if (col > 0) spacing = std::min(spacing, (x - previous).head<2>().norm());
    previous = x;
  }
  c.spacing = spacing;
  return c;
}

}  // namespace lamina::pd
