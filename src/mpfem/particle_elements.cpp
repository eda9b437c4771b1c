#include "mpfem/particle_elements.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "core/error.hpp"
#include "mpfem/particle_bins.hpp"

namespace lamina::mpfem {

namespace {

constexpr Real kPi = 3.14159265358979323846;

std::string point_text(const Vec2& p) { return fmt::format("({:.6g}, {:.6g})", p.x(), p.y()); }

Real bounding_area(const Points2& x) {
  const Vec2 extent = x.rowwise().maxCoeff() - x.rowwise().minCoeff();
  const Real a = extent.x() * extent.y();
  const Real l = std::max(extent.x(), extent.y());
  return a > 0 ? a : l * l;
}

/// Neighbours E N W S of every particle from the logical grid.
std::vector<std::array<Index, 4>> grid_neighbours(const LogicalGrid& g, Index count) {
  if (static_cast<Index>(g.n0) * g.n1 != count)
    throw InputError("discretization.particles", fmt::format("{} x {} grid particles", g.n0, g.n1),
                     fmt::format("{} particles", count));
  std::vector<std::array<Index, 4>> n(static_cast<std::size_t>(count));
  for (int j = 0; j < g.n1; ++j)
    for (int i = 0; i < g.n0; ++i) {
      auto id = [&](int a, int b) -> Index {
        if (a < 0 || a >= g.n0) return -1;
        if (g.periodic1) b = (b + g.n1) % g.n1;
        else if (b < 0 || b >= g.n1) return -1;
        return a + static_cast<Index>(g.n0) * b;
      };
      n[static_cast<std::size_t>(id(i, j))] = {id(i + 1, j), id(i, j + 1), id(i - 1, j), id(i, j - 1)};
    }
  return n;
}

Real median_nearest_distance(const Points2& x, const ParticleBins& bins, Real cell) {
  const Index n = x.cols();
  std::vector<Real> nearest(static_cast<std::size_t>(n), INFINITY);
#pragma omp parallel for schedule(static)
  for (Index p = 0; p < n; ++p) {
    Real best = INFINITY;
    for (Real radius = cell; !std::isfinite(best) && radius < 1e3 * cell; radius *= 2)
      bins.for_each_near(x.col(p), radius, [&](Index q) {
        if (q != p) best = std::min(best, (x.col(q) - x.col(p)).norm());
      });
    nearest[static_cast<std::size_t>(p)] = best;
  }
  std::nth_element(nearest.begin(), nearest.begin() + n / 2, nearest.end());
  return nearest[static_cast<std::size_t>(n / 2)];
}

/// Nearest particle to p in each 90-degree sector centred on +x, +y, -x, -y, within `reach`.
std::array<Index, 4> nearest_per_sector(const Points2& x, const ParticleBins& bins, Index p, Real reach) {
  std::array<Index, 4> best{-1, -1, -1, -1};
  std::array<Real, 4> distance{INFINITY, INFINITY, INFINITY, INFINITY};
  bins.for_each_near(x.col(p), reach, [&](Index q) {
    if (q == p) return;
    const Vec2 d = x.col(q) - x.col(p);
    const Real r = d.norm();
    if (r > reach) return;
    Real angle = std::atan2(d.y(), d.x()) + kPi / 4;  // sector k: [k pi/2 - pi/4, k pi/2 + pi/4)
    if (angle < 0) angle += 2 * kPi;
    const int k = std::min(3, static_cast<int>(angle / (kPi / 2)));
    if (r < distance[static_cast<std::size_t>(k)] ||
        (r == distance[static_cast<std::size_t>(k)] && q < best[static_cast<std::size_t>(k)])) {
      distance[static_cast<std::size_t>(k)] = r;
      best[static_cast<std::size_t>(k)] = q;
    }
  });
  return best;
}

/// Neighbours E N W S of every particle: nearest particle per 90-degree sector. A particle without
/// neighbours in two consecutive sectors (no element) looks again up to 2 and 4 x the reach.
std::vector<std::array<Index, 4>> sector_neighbours(const Points2& x, const ParticleBins& bins, Real reach) {
  const Index n = x.cols();
  std::vector<std::array<Index, 4>> result(static_cast<std::size_t>(n));
#pragma omp parallel for schedule(static)
  for (Index p = 0; p < n; ++p) {
    std::array<Index, 4> best{};
    for (Real factor : {1.0, 2.0, 4.0}) {
      best = nearest_per_sector(x, bins, p, factor * reach);
      bool consecutive = false;
      for (int k = 0; k < 4; ++k)
        consecutive = consecutive || (best[static_cast<std::size_t>(k)] >= 0 && best[static_cast<std::size_t>((k + 1) % 4)] >= 0);
      if (consecutive) break;
    }
    result[static_cast<std::size_t>(p)] = best;
  }
  return result;
}

}  // namespace

Eigen::Matrix<Real, 2, 3> triangle_gradient(const Vec2& p0, const Vec2& p1, const Vec2& p2, Real& signed_area) {
  const Real twice = (p1.x() - p0.x()) * (p2.y() - p0.y()) - (p2.x() - p0.x()) * (p1.y() - p0.y());
  signed_area = 0.5 * twice;
  Eigen::Matrix<Real, 2, 3> g;
  g << p1.y() - p2.y(), p2.y() - p0.y(), p0.y() - p1.y(),  //
      p2.x() - p1.x(), p0.x() - p2.x(), p1.x() - p0.x();
  return g / twice;
}

std::vector<std::array<Index, 4>> choose_neighbours(const ParticleLayout& layout, const ElementOptions& options) {
  const Points2& x = layout.positions;
  const Index n = x.cols();
  if (options.rule == NeighbourRule::logical_grid) {
    if (!layout.grid)
      throw InputError("mpfem.neighbours", "neighbours: sectors for particle sets without a generator grid",
                       "neighbours: grid");
    return grid_neighbours(*layout.grid, n);
  }
  const Real h = std::sqrt(bounding_area(x) / static_cast<Real>(n));
  ParticleBins bins(x, h);
  const Real reach = options.max_neighbour_distance * median_nearest_distance(x, bins, h);
  ParticleBins search(x, std::max(reach / 2, 1e-3 * h));
  return sector_neighbours(x, search, reach);
}

ParticleDiscretization build_particle_elements(const ParticleLayout& layout, const ElementOptions& options,
                                               const std::vector<std::array<Index, 4>>* given) {
  const Points2& x = layout.positions;
  const Index n = x.cols();
  if (n < 3) throw InputError("discretization.particles", "at least 3 particles", fmt::format("{}", n));
  if (!x.allFinite()) throw InputError("discretization.particles", "finite particle coordinates", "NaN or infinity");
  ParticleDiscretization d;
  d.rule = options.rule;
  d.typical_spacing = std::sqrt(bounding_area(x) / static_cast<Real>(n));
  const Real h = d.typical_spacing;
  if (!(h > 0)) throw InputError("discretization.particles", "particles spread over an area", "all particles coincide");
  ParticleBins bins(x, h);

  // coincident particles
  const Real coincident = options.coincidence_tolerance * h;
  {
    Index first = -1, second = -1;
    for (Index p = 0; p < n && first < 0; ++p)
      bins.for_each_near(x.col(p), coincident, [&](Index q) {
        if (first < 0 && q > p && (x.col(q) - x.col(p)).norm() <= coincident) first = p, second = q;
      });
    if (first >= 0)
      throw InputError("discretization.particles", "distinct particle positions (each particle carries its own dofs)",
                       fmt::format("particles {} and {} coincide at {}; remove one of them (or give the slit/seam "
                                   "particles separate sets)", first, second, point_text(x.col(first))));
  }

  const std::vector<std::array<Index, 4>> neighbours = given ? *given : choose_neighbours(layout, options);
  const bool skip_flat = options.rule == NeighbourRule::sectors || given != nullptr;

  d.elements.resize(static_cast<std::size_t>(n));
  std::vector<std::string> problems(static_cast<std::size_t>(n));
#pragma omp parallel for schedule(static)
  for (Index p = 0; p < n; ++p) {
    ParticleElement& e = d.elements[static_cast<std::size_t>(p)];
    e.nodes[0] = p;
    int present = 0;
    for (int k = 0; k < 4; ++k) {
      e.nodes[static_cast<std::size_t>(k + 1)] = neighbours[static_cast<std::size_t>(p)][static_cast<std::size_t>(k)];
      present += e.nodes[static_cast<std::size_t>(k + 1)] >= 0;
    }
    for (int k = 0; k < 4; ++k) {
      const int a = 1 + k, b = 1 + (k + 1) % 4;
      const Index ja = e.nodes[static_cast<std::size_t>(a)], jb = e.nodes[static_cast<std::size_t>(b)];
      if (ja < 0 || jb < 0) continue;
      Real signed_area = 0;
      const Eigen::Matrix<Real, 2, 3> g = triangle_gradient(x.col(p), x.col(ja), x.col(jb), signed_area);
      if (skip_flat) {
        // skip reflex or flat gaps (a concave boundary, or neighbours on a straight line)
        if (signed_area <= 1e-10 * h * h) continue;
      } else if (signed_area <= 1e-10 * h * h) {
        problems[static_cast<std::size_t>(p)] = fmt::format(
            "the five-node element of particle {} at {} is inverted or flat (triangle with particles {} and {}, "
            "area {:.3g}); the particle grid is tangled: reduce the jitter or use neighbours: sectors",
            p, point_text(x.col(p)), ja, jb, signed_area);
        continue;
      }
      ElementTriangle& t = e.triangles[static_cast<std::size_t>(e.triangle_count++)];
      t.local = {0, a, b};
      t.area = signed_area;
      t.gradient.setZero();
      t.gradient.col(0) = g.col(0);
      t.gradient.col(a) = g.col(1);
      t.gradient.col(b) = g.col(2);
      e.area += t.area;
      e.mean_gradient += t.area * t.gradient;
    }
    if (e.triangle_count == 0 && problems[static_cast<std::size_t>(p)].empty())
      problems[static_cast<std::size_t>(p)] = fmt::format(
          "particle {} at {} has {} neighbour(s) in consecutive sectors and no element area: every particle needs "
          "at least two neighbours at less than 180 degrees (add particles around it or remove it)",
          p, point_text(x.col(p)), present);
    if (e.area > 0) e.mean_gradient /= e.area;
  }
  for (const auto& problem : problems)
    if (!problem.empty()) throw InputError("discretization.particles", "particles that form five-node elements", problem);

  d.area_weight.resize(n);
  for (Index p = 0; p < n; ++p) d.area_weight[p] = d.elements[static_cast<std::size_t>(p)].area / d.covering;

  // boundary segments: triangle edges whose triangles all lie on one side
  struct EdgeSides {
    int left = 0, right = 0;  // triangles on the left / right of min -> max
  };
  std::map<std::pair<Index, Index>, EdgeSides> edges;
  for (const auto& e : d.elements)
    for (int t = 0; t < e.triangle_count; ++t) {
      const auto& tri = e.triangles[static_cast<std::size_t>(t)];
      for (int k = 0; k < 3; ++k) {
        const Index a = e.nodes[static_cast<std::size_t>(tri.local[static_cast<std::size_t>(k)])];
        const Index b = e.nodes[static_cast<std::size_t>(tri.local[static_cast<std::size_t>((k + 1) % 3)])];
        // counter-clockwise triangle: its interior is on the left of a -> b
        if (a < b) ++edges[{a, b}].left;
        else ++edges[{b, a}].right;
      }
    }
  d.boundary_weight = Eigen::VectorXd::Zero(n);
  for (const auto& [key, sides] : edges) {
    if (sides.left > 0 && sides.right > 0) continue;
    BoundarySegment s;
    s.a = sides.left > 0 ? key.first : key.second;
    s.b = sides.left > 0 ? key.second : key.first;
    const Vec2 t = x.col(s.b) - x.col(s.a);
    s.length = t.norm();
    s.normal = Vec2(t.y(), -t.x()) / s.length;  // body on the left => outward normal on the right
    d.boundary.push_back(s);
    d.boundary_weight[s.a] += 0.5 * s.length;
    d.boundary_weight[s.b] += 0.5 * s.length;
  }
  return d;
}

std::vector<ShapeValue> shape_functions_at(const ParticleDiscretization& d, const Points2& positions, const Vec2& x) {
  std::map<Index, ShapeValue> sum;
  int covering = 0;
  const Real tolerance = 1e-12;
  for (const auto& e : d.elements)
    for (int t = 0; t < e.triangle_count; ++t) {
      const auto& tri = e.triangles[static_cast<std::size_t>(t)];
      std::array<Real, 3> bary{};
      const Vec2 p0 = positions.col(e.nodes[static_cast<std::size_t>(tri.local[0])]);
      for (int k = 0; k < 3; ++k) {
        const int a = tri.local[static_cast<std::size_t>(k)];
        bary[static_cast<std::size_t>(k)] = (k == 0 ? 1.0 : 0.0) + tri.gradient.col(a).dot(x - p0);
      }
      // barycentric of vertex 0 = 1 + grad N0 . (x - p0); others = grad Nk . (x - p0)
      if (*std::min_element(bary.begin(), bary.end()) < -tolerance) continue;
      ++covering;
      for (int k = 0; k < 3; ++k) {
        const int a = tri.local[static_cast<std::size_t>(k)];
        ShapeValue& v = sum[e.nodes[static_cast<std::size_t>(a)]];
        v.particle = e.nodes[static_cast<std::size_t>(a)];
        v.value += bary[static_cast<std::size_t>(k)];
        v.gradient += tri.gradient.col(a);
      }
      break;  // one triangle per element (a point on a shared edge of the star counts once)
    }
  std::vector<ShapeValue> result;
  if (covering == 0) return result;
  for (auto& [particle, v] : sum) {
    v.value /= covering;
    v.gradient /= covering;
    result.push_back(v);
  }
  return result;
}

}  // namespace lamina::mpfem
