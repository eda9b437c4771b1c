#include "efg/background_quadrature.hpp"

#include <cmath>
#include <functional>
#include <numbers>

#include <fmt/format.h>

#include "core/error.hpp"
#include "core/gauss_legendre.hpp"

namespace lamina::efg {

void BackgroundCells::bounds(Index cell, Vec3& lo, Vec3& hi) const {
  const Index i = cell % counts[0];
  const Index j = (cell / counts[0]) % counts[1];
  const Index k = cell / (static_cast<Index>(counts[0]) * counts[1]);
  const Index ijk[3] = {i, j, k};
  for (int d = 0; d < 3; ++d) {
    lo[d] = breaks[d][static_cast<std::size_t>(ijk[d])];
    hi[d] = breaks[d][static_cast<std::size_t>(ijk[d] + 1)];
  }
}

std::array<int, 3> default_cell_counts(const geometry::VolumeMap& map, const std::array<Index, 3>& node_counts) {
  std::array<int, 3> c{};
  for (int d = 0; d < 3; ++d) {
    const Index n = node_counts[d];
    if (n <= 0)
      throw InputError("efg.integration.cells",
                       "background cell counts [cx, cy, cz] (the nodes are not a structured grid, so cells cannot be derived)",
                       "nothing");
    c[d] = map.axes[d].periodic ? static_cast<int>(n) : static_cast<int>(std::max<Index>(n - 1, 1));
  }
  return c;
}

BackgroundCells make_background_cells(geometry::VolumeMap map, const std::array<int, 3>& counts) {
  BackgroundCells cells;
  cells.map = std::move(map);
  cells.counts = counts;
  for (int d = 0; d < 3; ++d) {
    if (counts[d] < 1)
      throw InputError(fmt::format("efg.integration.cells.{}", d), "at least one cell per direction", fmt::format("{}", counts[d]));
    const auto& axis = cells.map.axes[d];
    cells.breaks[d].resize(static_cast<std::size_t>(counts[d] + 1));
    for (int i = 0; i <= counts[d]; ++i)
      cells.breaks[d][static_cast<std::size_t>(i)] = i == counts[d] ? axis.hi : axis.lo + (axis.hi - axis.lo) * i / counts[d];
  }
  return cells;
}

Mat3 map_jacobian(const geometry::VolumeMap& map, const Vec3& u, const Vec3& h) {
  Mat3 J;
  for (int d = 0; d < 3; ++d) {
    Vec3 a = u, b = u, c = u, e = u;
    a[d] -= 2 * h[d];
    b[d] -= h[d];
    c[d] += h[d];
    e[d] += 2 * h[d];
    J.col(d) = (map.position(a) - 8.0 * map.position(b) + 8.0 * map.position(c) - map.position(e)) / (12.0 * h[d]);
  }
  return J;
}

namespace {
constexpr Real kStepFraction = 1e-3;
}

VolumeQuadrature volume_quadrature(const BackgroundCells& cells, const std::array<int, 3>& gauss) {
  std::array<std::vector<Real>, 3> xi, wi;
  for (int d = 0; d < 3; ++d) gauss_legendre(gauss[d], xi[d], wi[d]);
  const Index per_cell = static_cast<Index>(gauss[0]) * gauss[1] * gauss[2];
  const Index n = cells.size();
  VolumeQuadrature q;
  q.points.resize(3, n * per_cell);
  q.weights.resize(n * per_cell);
  q.cell_begin.resize(static_cast<std::size_t>(n + 1));
#pragma omp parallel for schedule(static)
  for (Index c = 0; c < n; ++c) {
    Vec3 lo, hi;
    cells.bounds(c, lo, hi);
    const Vec3 mid = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
    const Vec3 step = kStepFraction * (hi - lo);
    Index p = c * per_cell;
    for (int k = 0; k < gauss[2]; ++k)
      for (int j = 0; j < gauss[1]; ++j)
        for (int i = 0; i < gauss[0]; ++i, ++p) {
          const Vec3 u(mid[0] + half[0] * xi[0][i], mid[1] + half[1] * xi[1][j], mid[2] + half[2] * xi[2][k]);
          const Mat3 J = map_jacobian(cells.map, u, step);
          q.points.col(p) = cells.map.position(u);
          q.weights[p] = wi[0][i] * wi[1][j] * wi[2][k] * half.prod() * std::abs(J.determinant());
        }
  }
  for (Index c = 0; c <= n; ++c) q.cell_begin[static_cast<std::size_t>(c)] = c * per_cell;
  return q;
}

namespace {

/// Appends the Gauss points of one boundary face (axis d, side) of a cell, optionally split into
/// `split` x `split` sub-faces; with `keep`, only the points where keep(x, face) holds (tested before the
/// point's Jacobian is computed).
void append_face(const BackgroundCells& cells, Index c, int d, int side, const std::array<int, 3>& gauss, int split,
                 const std::array<std::vector<Real>, 3>& xi, const std::array<std::vector<Real>, 3>& wi,
                 SurfaceQuadrature& q, std::vector<Vec3>& points, std::vector<Vec3>& normals, std::vector<Real>& weights,
                 std::vector<Real>& sizes, const std::function<bool(const Vec3&, int)>* keep = nullptr) {
  const int a = (d + 1) % 3, b = (d + 2) % 3;
  Vec3 lo, hi;
  cells.bounds(c, lo, hi);
  const Vec3 step = kStepFraction * (hi - lo);
  for (int sb = 0; sb < split; ++sb)
    for (int sa = 0; sa < split; ++sa) {
      const Real a0 = lo[a] + (hi[a] - lo[a]) * sa / split, a1 = lo[a] + (hi[a] - lo[a]) * (sa + 1) / split;
      const Real b0 = lo[b] + (hi[b] - lo[b]) * sb / split, b1 = lo[b] + (hi[b] - lo[b]) * (sb + 1) / split;
      const Real ma = 0.5 * (a0 + a1), ha = 0.5 * (a1 - a0), mb = 0.5 * (b0 + b1), hb = 0.5 * (b1 - b0);
      for (int kb = 0; kb < gauss[b]; ++kb)
        for (int ka = 0; ka < gauss[a]; ++ka) {
          Vec3 u;
          u[d] = side == 0 ? lo[d] : hi[d];
          u[a] = ma + ha * xi[a][ka];
          u[b] = mb + hb * xi[b][kb];
          const Vec3 x = cells.map.position(u);
          if (keep && !(*keep)(x, 2 * d + side)) continue;
          const Mat3 J = map_jacobian(cells.map, u, step);
          const Vec3 cross = J.col(a).cross(J.col(b));
          const Real area = cross.norm();
          const Real scale = (J.col(a).norm() + 1e-300) * (J.col(b).norm() + 1e-300);
          if (!(area > 1e-12 * scale)) continue;  // degenerate face (collapsed axis): no area
          Vec3 normal = cross / area;
          const Real orientation = normal.dot(J.col(d));
          if ((side == 1 && orientation < 0) || (side == 0 && orientation > 0)) normal = -normal;
          points.push_back(x);
          normals.push_back(normal);
          weights.push_back(wi[a][ka] * wi[b][kb] * ha * hb * area);
          sizes.push_back(J.col(d).norm() * (hi[d] - lo[d]));
          q.face.push_back(2 * d + side);
          q.cell.push_back(c);
        }
    }
}

SurfaceQuadrature finish(SurfaceQuadrature q, const std::vector<Vec3>& points, const std::vector<Vec3>& normals,
                         const std::vector<Real>& weights, const std::vector<Real>& sizes) {
  const Index n = static_cast<Index>(points.size());
  q.points.resize(3, n);
  q.normals.resize(3, n);
  q.weights.resize(n);
  q.cell_size.resize(n);
  for (Index i = 0; i < n; ++i) {
    q.points.col(i) = points[static_cast<std::size_t>(i)];
    q.normals.col(i) = normals[static_cast<std::size_t>(i)];
    q.weights[i] = weights[static_cast<std::size_t>(i)];
    q.cell_size[i] = sizes[static_cast<std::size_t>(i)];
  }
  return q;
}

}  // namespace

SurfaceQuadrature boundary_quadrature(const BackgroundCells& cells, const std::array<int, 3>& gauss) {
  std::array<std::vector<Real>, 3> xi, wi;
  for (int d = 0; d < 3; ++d) gauss_legendre(gauss[d], xi[d], wi[d]);
  std::vector<Vec3> points, normals;
  std::vector<Real> weights, sizes;
  SurfaceQuadrature q;
  for (int d = 0; d < 3; ++d) {
    if (cells.map.axes[d].periodic) continue;
    const int a = (d + 1) % 3, b = (d + 2) % 3;
    for (int side = 0; side < 2; ++side) {
      const int layer = side == 0 ? 0 : cells.counts[d] - 1;
      for (int jb = 0; jb < cells.counts[b]; ++jb)
        for (int ja = 0; ja < cells.counts[a]; ++ja) {
          int ijk[3];
          ijk[d] = layer;
          ijk[a] = ja;
          ijk[b] = jb;
          append_face(cells, cells.index(ijk[0], ijk[1], ijk[2]), d, side, gauss, 1, xi, wi, q, points, normals, weights, sizes);
        }
    }
  }
  return finish(std::move(q), points, normals, weights, sizes);
}

SurfaceQuadrature refine_selected_faces(const BackgroundCells& cells, const SurfaceQuadrature& base,
                                        const std::array<int, 3>& gauss, int split,
                                        const std::function<bool(const Vec3&, int)>& selected) {
  std::array<std::vector<Real>, 3> xi, wi;
  for (int d = 0; d < 3; ++d) gauss_legendre(gauss[d], xi[d], wi[d]);
  std::vector<Vec3> points, normals;
  std::vector<Real> weights, sizes;
  SurfaceQuadrature q;
  Index s = 0;
  while (s < base.size()) {
    // the points of one face are consecutive
    Index e = s;
    while (e < base.size() && base.cell[static_cast<std::size_t>(e)] == base.cell[static_cast<std::size_t>(s)] &&
           base.face[static_cast<std::size_t>(e)] == base.face[static_cast<std::size_t>(s)])
      ++e;
    int hits = 0;
    for (Index i = s; i < e; ++i) hits += selected(base.points.col(i), base.face[static_cast<std::size_t>(i)]) ? 1 : 0;
    const int face = base.face[static_cast<std::size_t>(s)];
    const Index c = base.cell[static_cast<std::size_t>(s)];
    // candidates for a partial selection: faces with some hits, or whose neighbours on the
    // refined grid might hit (test the refined points of every face that is not fully selected)
    const bool all = hits == e - s;
    append_face(cells, c, face / 2, face % 2, gauss, all ? 1 : split, xi, wi, q, points, normals, weights, sizes, &selected);
    s = e;
  }
  return finish(std::move(q), points, normals, weights, sizes);
}

}  // namespace lamina::efg
