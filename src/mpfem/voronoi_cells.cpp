#include "mpfem/voronoi_cells.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <string>

#include "mpfem/gradient_list.hpp"
#include "core/error.hpp"
#include "mpfem/particle_bins.hpp"

namespace lamina::mpfem {

namespace {

Real cross(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

std::string point_text(const Vec2& p) { return fmt::format("({:.6g}, {:.6g})", p.x(), p.y()); }

/// A convex polygon, counter-clockwise; label[k] names the edge vertex[k] -> vertex[k+1]:
/// a particle J >= 0 (the bisector with J) or -(k+1) for hull edge k.
struct LabelledPolygon {
  std::vector<Vec2> vertex;
  std::vector<Index> label;
};

/// Keeps the part of the polygon with normal . x <= offset; the new edge gets `label`.
void clip(LabelledPolygon& polygon, const Vec2& normal, Real offset, Index label) {
  const std::size_t m = polygon.vertex.size();
  std::vector<Real> side(m);
  bool any_outside = false;
  for (std::size_t k = 0; k < m; ++k) {
    side[k] = normal.dot(polygon.vertex[k]) - offset;
    any_outside = any_outside || side[k] > 0;
  }
  if (!any_outside) return;
  LabelledPolygon out;
  for (std::size_t k = 0; k < m; ++k) {
    const std::size_t next = (k + 1) % m;
    const bool in_p = side[k] <= 0, in_q = side[next] <= 0;
    const Vec2& p = polygon.vertex[k];
    const Vec2& q = polygon.vertex[next];
    if (in_p) out.vertex.push_back(p), out.label.push_back(polygon.label[k]);
    if (in_p != in_q) {
      const Vec2 x = p + side[k] / (side[k] - side[next]) * (q - p);
      out.vertex.push_back(x);
      out.label.push_back(in_p ? label : polygon.label[k]);  // leaving: the bisector edge follows
    }
  }
  polygon = std::move(out);
}

/// Values of particle K's five-node element interpolant at x, extended linearly from the star
/// triangle with the largest smallest barycentric coordinate (the triangle containing x if any).
std::array<Real, kElementNodes> star_values(const ParticleElement& e, const Points2& x, const Vec2& at) {
  const Vec2 d = at - x.col(e.nodes[0]);
  int best = 0;
  Real best_min = -INFINITY;
  for (int t = 0; t < e.triangle_count; ++t) {
    const auto& tri = e.triangles[static_cast<std::size_t>(t)];
    Real smallest = INFINITY;
    for (int k = 0; k < 3; ++k) {
      const int a = tri.local[static_cast<std::size_t>(k)];
      smallest = std::min(smallest, (a == 0 ? 1.0 : 0.0) + tri.gradient.col(a).dot(d));
    }
    if (smallest > best_min) best_min = smallest, best = t;
  }
  std::array<Real, kElementNodes> values{};
  const auto& tri = e.triangles[static_cast<std::size_t>(best)];
  for (int k = 0; k < 3; ++k) {
    const int a = tri.local[static_cast<std::size_t>(k)];
    values[static_cast<std::size_t>(a)] = (a == 0 ? 1.0 : 0.0) + tri.gradient.col(a).dot(d);
  }
  return values;
}

/// The boundary particles along one hull edge, by arc length from its first vertex.
struct HullEdge {
  Vec2 origin, tangent;  // unit tangent
  Real length = 0;
  std::vector<std::pair<Real, Index>> particles;  // (s, particle), sorted, first and last = the hull corners
};

}  // namespace

std::vector<Index> convex_hull(const Points2& x) {
  const Index n = x.cols();
  std::vector<Index> order(static_cast<std::size_t>(n));
  std::iota(order.begin(), order.end(), Index{0});
  std::sort(order.begin(), order.end(), [&](Index a, Index b) {
    if (x(0, a) != x(0, b)) return x(0, a) < x(0, b);
    if (x(1, a) != x(1, b)) return x(1, a) < x(1, b);
    return a < b;
  });
  const Vec2 extent = x.rowwise().maxCoeff() - x.rowwise().minCoeff();
  const Real tolerance = 1e-12 * extent.squaredNorm();  // collinear points are not hull corners
  std::vector<Index> hull(static_cast<std::size_t>(2 * n));
  std::size_t k = 0;
  auto turn = [&](Index o, Index a, Index b) { return cross(x.col(a) - x.col(o), x.col(b) - x.col(o)); };
  for (Index p : order) {
    while (k >= 2 && turn(hull[k - 2], hull[k - 1], p) <= tolerance) --k;
    hull[k++] = p;
  }
  const std::size_t lower = k + 1;
  for (auto it = order.rbegin() + 1; it != order.rend(); ++it) {
    while (k >= lower && turn(hull[k - 2], hull[k - 1], *it) <= tolerance) --k;
    hull[k++] = *it;
  }
  hull.resize(k > 1 ? k - 1 : k);
  return hull;
}

VoronoiCells build_voronoi_cells(const ParticleLayout& layout, const ParticleDiscretization& d, Real max_reach,
                                 const std::vector<Index>& body) {
  const Points2& x = layout.positions;
  const Index n = x.cols();
  const Real h = d.typical_spacing;
  const std::vector<Index> corners = body.empty() ? convex_hull(x) : body;
  if (corners.size() < 3)
    throw InputError("discretization.particles", "particles spread over an area (not on one line)",
                     fmt::format("{} particles whose convex hull has no area", n));

  // hull edges and the boundary particles on them (within 1e-9 spacings of the edge)
  std::vector<HullEdge> edges(corners.size());
  const Real on_edge = 1e-9 * h;
  for (std::size_t k = 0; k < corners.size(); ++k) {
    HullEdge& e = edges[k];
    e.origin = x.col(corners[k]);
    const Vec2 chord = x.col(corners[(k + 1) % corners.size()]) - e.origin;
    e.length = chord.norm();
    e.tangent = chord / e.length;
    for (Index p = 0; p < n; ++p) {
      const Vec2 r = x.col(p) - e.origin;
      const Real s = r.dot(e.tangent);
      if (std::abs(cross(e.tangent, r)) <= on_edge && s >= -on_edge && s <= e.length + on_edge)
        e.particles.emplace_back(std::clamp(s, 0.0, e.length), p);
    }
    std::sort(e.particles.begin(), e.particles.end());
  }

  VoronoiCells result;
  result.boundary_weight = Eigen::VectorXd::Zero(n);
  for (const HullEdge& e : edges)
    for (std::size_t i = 0; i + 1 < e.particles.size(); ++i) {
      BoundarySegment s;
      s.a = e.particles[i].second;
      s.b = e.particles[i + 1].second;
      s.length = e.particles[i + 1].first - e.particles[i].first;
      s.normal = Vec2(e.tangent.y(), -e.tangent.x());  // body on the left of the counter-clockwise hull
      result.boundary.push_back(s);
      result.boundary_weight[s.a] += 0.5 * s.length;
      result.boundary_weight[s.b] += 0.5 * s.length;
    }

  LabelledPolygon hull;
  for (std::size_t k = 0; k < corners.size(); ++k) {
    hull.vertex.push_back(x.col(corners[k]));
    hull.label.push_back(-static_cast<Index>(k) - 1);
  }

  TributaryCells& cells = result.cells;
  cells.mean_gradient.assign(static_cast<std::size_t>(n), {});
  cells.area = Eigen::VectorXd::Zero(n);
  cells.centroid = Points2::Zero(2, n);
  cells.second_moment.assign(static_cast<std::size_t>(n), Eigen::Matrix2d::Zero());
  std::vector<std::pair<Real, std::string>> problems(static_cast<std::size_t>(n));  // (reach, message)
  const ParticleBins bins(x, h);
  const Real g1 = 0.5 - 0.5 / std::sqrt(3.0), g2 = 0.5 + 0.5 / std::sqrt(3.0);

#pragma omp parallel for schedule(dynamic, 64)
  for (Index p = 0; p < n; ++p) {
    const auto sp = static_cast<std::size_t>(p);
    const Vec2 xp = x.col(p);
    LabelledPolygon cell;
    Real reach = 0;
    for (Real radius = 3 * h;; radius *= 2) {
      std::vector<std::pair<Real, Index>> near;
      bins.for_each_near(xp, radius, [&](Index q) {
        if (q != p) near.emplace_back((x.col(q) - xp).norm(), q);
      });
      std::sort(near.begin(), near.end());
      cell = hull;
      reach = INFINITY;
      for (const auto& [distance, q] : near) {
        if (distance >= 2 * reach) break;  // farther particles cannot cut the cell
        const Vec2 normal = x.col(q) - xp;
        clip(cell, normal, normal.dot(0.5 * (x.col(q) + xp)), q);
        reach = 0;
        for (const Vec2& v : cell.vertex) reach = std::max(reach, (v - xp).norm());
      }
      if (!std::isfinite(reach)) {
        reach = 0;
        for (const Vec2& v : cell.vertex) reach = std::max(reach, (v - xp).norm());
      }
      if (2 * reach <= radius || radius > 1e6 * h) break;
    }
    if (reach > max_reach) {
      problems[sp].first = reach;
      problems[sp].second = fmt::format(
          "the Voronoi cell of particle {} at {} reaches {:.3g} from it (more than {:.3g}): the particle cloud is too "
          "sparse there{}; add particles there or use mpfem.particle_strain: star",
          p, point_text(xp), reach, max_reach,
          body.empty() ? ", or the body is not convex (cells are clipped to the particles' convex hull)" : "");
      continue;
    }
    // area, moments and the smoothed gradients
    Real area = 0;
    Vec2 first = Vec2::Zero();
    Eigen::Matrix2d second = Eigen::Matrix2d::Zero();
    auto& gradient = cells.mean_gradient[sp];
    const ParticleElement& own = d.elements[sp];
    const std::size_t m = cell.vertex.size();
    for (std::size_t k = 0; k < m; ++k) {
      const Vec2& a = cell.vertex[k];
      const Vec2& b = cell.vertex[(k + 1) % m];
      const Vec2 u = a - xp, v = b - xp;
      const Real c = cross(u, v);
      area += 0.5 * c;
      first += c / 6.0 * (u + v);
      second(0, 0) += c / 12.0 * (u.x() * u.x() + u.x() * v.x() + v.x() * v.x());
      second(1, 1) += c / 12.0 * (u.y() * u.y() + u.y() * v.y() + v.y() * v.y());
      second(0, 1) += c / 24.0 * (u.x() * v.y() + 2 * u.x() * u.y() + 2 * v.x() * v.y() + v.x() * u.y());
      const Vec2 normal_length(b.y() - a.y(), a.x() - b.x());  // outward for a counter-clockwise polygon
      if (normal_length.squaredNorm() == 0.0) continue;
      const Index label = cell.label[k];
      if (label >= 0) {
        // interior edge shared with particle `label`: psi = (N^p + N^label) / 2, 2-point Gauss
        const ParticleElement& other = d.elements[static_cast<std::size_t>(label)];
        for (Real g : {g1, g2}) {
          const Vec2 at = (1 - g) * a + g * b;
          for (const ParticleElement* e : {&own, &other}) {
            const auto values = star_values(*e, x, at);
            for (int node = 0; node < kElementNodes; ++node) {
              const Index j = e->nodes[static_cast<std::size_t>(node)];
              if (j >= 0 && values[static_cast<std::size_t>(node)] != 0.0)
                add_gradient(gradient, j, 0.25 * values[static_cast<std::size_t>(node)] * normal_length);
            }
          }
        }
      } else {
        // hull edge: the linear interpolant between consecutive boundary particles, piece by piece
        const HullEdge& e = edges[static_cast<std::size_t>(-label - 1)];
        const Vec2 unit_normal(e.tangent.y(), -e.tangent.x());
        const Real sa = (a - e.origin).dot(e.tangent), sb = (b - e.origin).dot(e.tangent);
        for (std::size_t i = 0; i + 1 < e.particles.size(); ++i) {
          const Real s0 = e.particles[i].first, s1 = e.particles[i + 1].first;
          const Real lo = std::max(sa, s0), hi = std::min(sb, s1);
          if (!(hi > lo)) continue;
          const Real w1 = (0.5 * (lo + hi) - s0) / (s1 - s0);
          add_gradient(gradient, e.particles[i].second, (hi - lo) * (1 - w1) * unit_normal);
          add_gradient(gradient, e.particles[i + 1].second, (hi - lo) * w1 * unit_normal);
        }
      }
    }
    second(1, 0) = second(0, 1);
    if (!(area > 0)) {
      problems[sp] = {INFINITY, fmt::format("the Voronoi cell of particle {} at {} has no area", p, point_text(xp))};
      continue;
    }
    const Vec2 offset = first / area;
    cells.area[p] = area;
    cells.centroid.col(p) = xp + offset;
    cells.second_moment[sp] = second - area * offset * offset.transpose();  // about the centroid
    for (auto& [q, value] : gradient) value /= area;
  }
  // the worst three particles (farthest reach first), one line each
  std::vector<std::size_t> bad;
  for (std::size_t q = 0; q < problems.size(); ++q)
    if (!problems[q].second.empty()) bad.push_back(q);
  if (!bad.empty()) {
    std::stable_sort(bad.begin(), bad.end(), [&](std::size_t a, std::size_t b) { return problems[a].first > problems[b].first; });
    std::vector<Diagnostic> lines;
    for (std::size_t k = 0; k < std::min<std::size_t>(3, bad.size()); ++k)
      lines.push_back(Diagnostic{"", 0, 0, "discretization.particles", "particles whose Voronoi cells are compact",
                                 problems[bad[k]].second +
                                     (k == 0 && bad.size() > 3 ? fmt::format(" ({} particles in all)", bad.size()) : "")});
    throw InputError(lines);
  }
  result.hull_area = cells.area.sum();
  return result;
}

}  // namespace lamina::mpfem
