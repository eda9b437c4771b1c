#include "mpfem/tributary_cells.hpp"

#include <fmt/format.h>

#include <array>

#include "mpfem/gradient_list.hpp"
#include "core/error.hpp"

namespace lamina::mpfem {

namespace {

/// A point of a quarter polygon: its position and phi there as weights of the cell's 4 corners.
struct PolygonPoint {
  Vec2 x;
  Eigen::Vector4d phi;
};

}  // namespace

TributaryCells build_tributary_cells(const ParticleLayout& layout) {
  if (!layout.grid) throw InputError("mpfem.particle_strain", "particle_strain: voronoi or star for particle sets without a grid", "cell");
  const auto& g = *layout.grid;
  const Points2& x = layout.positions;
  const Index n = x.cols();
  TributaryCells cells;
  cells.mean_gradient.resize(static_cast<std::size_t>(n));
  cells.area = Eigen::VectorXd::Zero(n);
  cells.centroid = Points2::Zero(2, n);
  cells.second_moment.assign(static_cast<std::size_t>(n), Eigen::Matrix2d::Zero());
  std::vector<Vec2> first_moment(static_cast<std::size_t>(n), Vec2::Zero());  // about the particle

  const int cells1 = g.periodic1 ? g.n1 : g.n1 - 1;
  for (int j = 0; j < cells1; ++j)
    for (int i = 0; i + 1 < g.n0; ++i) {
      auto id = [&](int a, int b) { return static_cast<Index>(a) + static_cast<Index>(g.n0) * (b % g.n1); };
      const std::array<Index, 4> corner{id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)};
      std::array<Vec2, 4> p;
      for (int k = 0; k < 4; ++k) p[static_cast<std::size_t>(k)] = x.col(corner[static_cast<std::size_t>(k)]);
      // diagonals a-c and b-d: a + t (c - a) = b + s (d - b)
      Eigen::Matrix2d m;
      m.col(0) = p[2] - p[0];
      m.col(1) = p[1] - p[3];
      const Real det = m.determinant();
      const Vec2 ts = std::abs(det) > 0 ? Vec2(m.inverse() * (p[1] - p[0])) : Vec2(-1, -1);
      const Real t = ts[0], s = ts[1];
      if (!(t > 0 && t < 1 && s > 0 && s < 1))
        throw InputError("discretization.particles", "grid cells whose diagonals cross inside them (convex cells)",
                         fmt::format("a tangled or non-convex cell at particles {}, {}, {}, {} near ({:.6g}, {:.6g}); "
                                     "reduce the jitter",
                                     corner[0], corner[1], corner[2], corner[3], p[0].x(), p[0].y()));
      PolygonPoint centre;
      centre.x = p[0] + t * (p[2] - p[0]);
      centre.phi << 0.5 * (1 - t), 0.5 * (1 - s), 0.5 * t, 0.5 * s;  // mean of the two diagonal interpolants
      for (int k = 0; k < 4; ++k) {
        const int next = (k + 1) % 4, previous = (k + 3) % 4;
        std::array<PolygonPoint, 4> polygon;
        polygon[0].x = p[static_cast<std::size_t>(k)];
        polygon[0].phi = Eigen::Vector4d::Unit(k);
        polygon[1].x = 0.5 * (p[static_cast<std::size_t>(k)] + p[static_cast<std::size_t>(next)]);
        polygon[1].phi = 0.5 * (Eigen::Vector4d::Unit(k) + Eigen::Vector4d::Unit(next));
        polygon[2] = centre;
        polygon[3].x = 0.5 * (p[static_cast<std::size_t>(k)] + p[static_cast<std::size_t>(previous)]);
        polygon[3].phi = 0.5 * (Eigen::Vector4d::Unit(k) + Eigen::Vector4d::Unit(previous));
        const Index owner = corner[static_cast<std::size_t>(k)];
        const Vec2 origin = x.col(owner);
        Real area = 0;
        Vec2 first = Vec2::Zero();
        Eigen::Matrix2d second = Eigen::Matrix2d::Zero();
        Eigen::Matrix<Real, 2, 4> flux = Eigen::Matrix<Real, 2, 4>::Zero();  // integral phi n ds per corner
        for (int e = 0; e < 4; ++e) {
          const PolygonPoint& a = polygon[static_cast<std::size_t>(e)];
          const PolygonPoint& b = polygon[static_cast<std::size_t>((e + 1) % 4)];
          const Vec2 u = a.x - origin, v = b.x - origin;
          const Real cross = u.x() * v.y() - v.x() * u.y();
          area += 0.5 * cross;
          first += cross / 6.0 * (u + v);
          second(0, 0) += cross / 12.0 * (u.x() * u.x() + u.x() * v.x() + v.x() * v.x());
          second(1, 1) += cross / 12.0 * (u.y() * u.y() + u.y() * v.y() + v.y() * v.y());
          second(0, 1) += cross / 24.0 * (u.x() * v.y() + 2 * u.x() * u.y() + 2 * v.x() * v.y() + v.x() * u.y());
          const Vec2 normal_length(b.x.y() - a.x.y(), a.x.x() - b.x.x());  // outward for a counter-clockwise polygon
          flux += normal_length * (0.5 * (a.phi + b.phi)).transpose();
        }
        second(1, 0) = second(0, 1);
        if (!(area > 0))
          throw InputError("discretization.particles", "counter-clockwise, non-degenerate grid cells",
                           fmt::format("a cell quarter of particle {} with area {:.3g}", owner, area));
        cells.area[owner] += area;
        first_moment[static_cast<std::size_t>(owner)] += first;
        cells.second_moment[static_cast<std::size_t>(owner)] += second;
        for (int c = 0; c < 4; ++c)
          add_gradient(cells.mean_gradient[static_cast<std::size_t>(owner)], corner[static_cast<std::size_t>(c)], flux.col(c));
      }
    }
  for (Index q = 0; q < n; ++q) {
    const auto sq = static_cast<std::size_t>(q);
    if (!(cells.area[q] > 0))
      throw InputError("discretization.particles", "every particle in at least one grid cell", fmt::format("particle {}", q));
    const Vec2 offset = first_moment[sq] / cells.area[q];
    cells.centroid.col(q) = x.col(q) + offset;
    cells.second_moment[sq] -= cells.area[q] * offset * offset.transpose();  // about the centroid
    for (auto& [p, v] : cells.mean_gradient[sq]) v /= cells.area[q];
  }
  return cells;
}

}  // namespace lamina::mpfem
