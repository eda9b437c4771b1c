#include "mpm/cpdi2_domains.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

#include "shell/belytschko_tsay_shell.hpp"

namespace lamina::mpm {

Cpdi2CornerWeights cpdi2_corner_weights(const Eigen::Matrix<Real, 2, 4>& p) {
  auto cross = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); };
  const Eigen::Vector2d x21 = p.col(1) - p.col(0), x41 = p.col(3) - p.col(0), x32 = p.col(2) - p.col(1),
                        x34 = p.col(2) - p.col(3);
  const Real c1 = cross(x21, x41), c2 = cross(x21, x32), c3 = cross(x34, x41), c4 = cross(x34, x32);
  Cpdi2CornerWeights w;
  Real area = 0.0;  // shoelace
  for (int a = 0; a < 4; ++a) area += 0.5 * cross(p.col(a), p.col((a + 1) % 4));
  w.area = area;
  w.value << 4 * c1 + 2 * c2 + 2 * c3 + c4, 2 * c1 + 4 * c2 + c3 + 2 * c4, c1 + 2 * c2 + 2 * c3 + 4 * c4,
      2 * c1 + c2 + 4 * c3 + 2 * c4;
  w.value /= 36.0 * area;
  w.gradient.col(0) << p(1, 1) - p(1, 3), p(0, 3) - p(0, 1);
  w.gradient.col(1) << p(1, 2) - p(1, 0), p(0, 0) - p(0, 2);
  w.gradient.col(2) = -w.gradient.col(0);
  w.gradient.col(3) = -w.gradient.col(1);
  w.gradient /= 2.0 * area;
  return w;
}

Eigen::Matrix<Real, 2, 4> planar_corners(const Eigen::Matrix<Real, 3, 4>& corners) {
  Mat3 R;
  Eigen::Matrix<Real, 2, 4> p = Eigen::Matrix<Real, 2, 4>::Zero();
  if (!shell::BelytschkoTsayShell::corotational_frame(corners, R)) return p;
  const Vec3 centre = corners.rowwise().mean();
  const Eigen::Matrix<Real, 3, 4> local = R * (corners.colwise() - centre);
  return local.topRows<2>();
}

Cpdi2Domains::Cpdi2Domains(const ShellMesh& mesh, Real density) {
  const Index n = mesh.node_count(), e_count = mesh.element_count();
  node_mass_ = Eigen::VectorXd::Zero(n);
  node_inertia_ = Eigen::VectorXd::Zero(n);
  element_area_ = Eigen::VectorXd::Zero(e_count);
  std::vector<Real> edges;
  std::map<std::pair<Index, Index>, Index> directed;  // directed edge -> element
  const Real h = mesh.thickness;
  for (Index e = 0; e < e_count; ++e) {
    Eigen::Matrix<Real, 3, 4> x;
    bool repeated = false;
    for (int a = 0; a < 4; ++a) {
      const Index node = mesh.quads(a, e);
      if (node < 0 || node >= n) {
        defects_.push_back({e, fmt::format("node index {} outside 0..{}", node, n - 1)});
        repeated = true;
        break;
      }
      x.col(a) = mesh.nodes.col(node);
      for (int b = 0; b < a; ++b)
        if (mesh.quads(b, e) == node) repeated = true;
    }
    if (repeated) {
      defects_.push_back({e, "a repeated node (degenerate quadrilateral, zero area at a corner)"});
      continue;
    }
    Real longest = 0.0;
    for (int a = 0; a < 4; ++a) {
      const Real len = (x.col((a + 1) % 4) - x.col(a)).norm();
      edges.push_back(len);
      longest = std::max(longest, len);
      const std::pair<Index, Index> edge{mesh.quads(a, e), mesh.quads((a + 1) % 4, e)};
      auto [it, inserted] = directed.emplace(edge, e);
      if (!inserted)
        defects_.push_back({e, fmt::format("orientation opposite to element {} (edge {}-{} runs the same way in both: "
                                           "inverted element)",
                                           it->second, edge.first, edge.second)});
    }
    Mat3 R;
    if (!shell::BelytschkoTsayShell::corotational_frame(x, R)) {
      defects_.push_back({e, "zero area (collinear or coincident corners)"});
      continue;
    }
    const Eigen::Matrix<Real, 2, 4> p = planar_corners(x);
    // every corner must turn left (convex, not self-intersecting)
    for (int a = 0; a < 4; ++a) {
      const Eigen::Vector2d in = p.col(a) - p.col((a + 3) % 4), out = p.col((a + 1) % 4) - p.col(a);
      const Real turn = in.x() * out.y() - in.y() * out.x();
      if (!(turn > 1e-10 * longest * longest)) {
        defects_.push_back({e, fmt::format("corner {} is not convex (inverted, self-intersecting or zero-area quadrilateral)", a + 1)});
        break;
      }
    }
    const Cpdi2CornerWeights w = cpdi2_corner_weights(p);
    if (!(w.area > 0.0) || !std::isfinite(w.area)) {
      defects_.push_back({e, "zero or negative area"});
      continue;
    }
    element_area_[e] = w.area;
    const Real mass = density * h * w.area;
    const Real radius2 = std::max(h * h / 12.0, w.area / 8.0);
    for (int a = 0; a < 4; ++a) {
      node_mass_[mesh.quads(a, e)] += mass * w.value[a];
      node_inertia_[mesh.quads(a, e)] += mass * w.value[a] * radius2;
    }
  }
  if (!edges.empty()) {
    std::sort(edges.begin(), edges.end());
    shortest_edge_ = edges.front();
    median_edge_ = edges[edges.size() / 2];
  }
}

}  // namespace lamina::mpm
