#include "efg/background_quadrature.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <functional>
#include <numbers>
#include <optional>

#include <fmt/format.h>
#include <omp.h>

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

Real largest_cell_turn(const BackgroundCells& cells) {
  Real largest = 0.0;
  for (Index c = 0; c < cells.size(); ++c) {
    Vec3 lo, hi;
    cells.bounds(c, lo, hi);
    Vec3 corner[8];
    for (int k = 0; k < 8; ++k)
      corner[k] = cells.map.position(Vec3((k & 1) ? hi[0] : lo[0], (k & 2) ? hi[1] : lo[1], (k & 4) ? hi[2] : lo[2]));
    for (int d = 0; d < 3; ++d) {
      const int bit = 1 << d;
      Vec3 edge[4];
      int count = 0;
      Real longest = 0.0;
      for (int k = 0; k < 8; ++k)
        if (!(k & bit)) {
          edge[count] = corner[k | bit] - corner[k];
          longest = std::max(longest, edge[count].norm());
          ++count;
        }
      for (int a = 0; a < 4; ++a)
        for (int b = a + 1; b < 4; ++b) {
          const Real na = edge[a].norm(), nb = edge[b].norm();
          if (na <= 1e-9 * longest || nb <= 1e-9 * longest) continue;  // a collapsed edge
          const Real cosine = std::clamp(edge[a].dot(edge[b]) / (na * nb), -1.0, 1.0);
          largest = std::max(largest, std::acos(cosine));
        }
    }
  }
  return largest;
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

/// Where a selection crosses a boundary face (the selection test is evaluated at parametric points
/// (s, t) along the face's two axes a, b).
struct FaceSelection {
  /// Sample points nearest a rectangle's edges are set in by this fraction of its size (a selection of the
  /// adjacent face's plane, such as x < 1e-9, holds on the shared edge itself).
  static constexpr Real kInset = 1e-3;
  const BackgroundCells& cells;
  int d, a, b, face;
  Real u_d;
  const std::function<bool(const Vec3&, int)>& keep;
  const std::vector<Real>& xa;  // Gauss abscissae along a and b (on [-1, 1])
  const std::vector<Real>& xb;

  Vec3 parametric(Real s, Real t) const {
    Vec3 u;
    u[d] = u_d;
    u[a] = s;
    u[b] = t;
    return u;
  }
  bool holds(Real s, Real t) const { return keep(cells.map.position(parametric(s, t)), face); }

  /// Tests the rectangle [s0, s1] x [t0, t1] at its Gauss points and at a 3 x 3 grid of points set in
  /// by kInset of its size from its edges and corners (so that a region boundary between a Gauss point
  /// and an edge is seen); returns the number of points where the selection holds, out of `count`, and
  /// the sum of their coordinates.
  int sample(Real s0, Real s1, Real t0, Real t1, int& count, Real& sum_s, Real& sum_t) const {
    const Real fractions[3] = {kInset, 0.5, 1.0 - kInset};
    int in = 0;
    count = 0;
    sum_s = sum_t = 0;
    auto test = [&](Real s, Real t) {
      ++count;
      if (holds(s, t)) {
        ++in;
        sum_s += s;
        sum_t += t;
      }
    };
    for (const Real ft : fractions)
      for (const Real fs : fractions) test(s0 + fs * (s1 - s0), t0 + ft * (t1 - t0));
    for (const Real gt : xb)
      for (const Real gs : xa) test(0.5 * (s0 + s1) + 0.5 * (s1 - s0) * gs, 0.5 * (t0 + t1) + 0.5 * (t1 - t0) * gt);
    return in;
  }

  /// Whether the selection holds anywhere on a lattice over [s0, s1] x [t0, t1]: the corners of its
  /// split x split sub-faces (those on the rectangle's edges set in by kInset of a sub-face) and their
  /// centres. A face it misses is left out without testing every sub-face.
  bool touches(Real s0, Real s1, Real t0, Real t1, int split) const {
    auto at = [&](Real lo, Real hi, int k, int twice_split) {
      Real f = static_cast<Real>(k) / twice_split;
      if (k == 0) f = kInset / split;
      if (k == twice_split) f = 1.0 - kInset / split;
      return lo + f * (hi - lo);
    };
    for (int kt = 0; kt <= 2 * split; ++kt)
      for (int ks = 0; ks <= 2 * split; ++ks) {
        if ((ks % 2) != (kt % 2)) continue;  // sub-face corners (even, even) and centres (odd, odd)
        if (holds(at(s0, s1, ks, 2 * split), at(t0, t1, kt, 2 * split))) return true;
      }
    return false;
  }

  /// The parametric area of [s0, s1] x [t0, t1] where the selection holds, and its first moments, by
  /// quadtree bisection of the rectangles the region boundary crosses (`depth` more levels; a crossed
  /// rectangle of the last level counts its sampled fraction at the centroid of its selected points).
  void selected_part(Real s0, Real s1, Real t0, Real t1, int depth, Real& area, Real& moment_s, Real& moment_t) const {
    int count = 0;
    Real sum_s = 0, sum_t = 0;
    const int in = sample(s0, s1, t0, t1, count, sum_s, sum_t);
    const Real size = (s1 - s0) * (t1 - t0);
    if (in == 0) return;
    if (in == count) {
      area += size;
      moment_s += size * 0.5 * (s0 + s1);
      moment_t += size * 0.5 * (t0 + t1);
      return;
    }
    if (depth == 0) {
      area += size * in / count;
      moment_s += size * sum_s / count;
      moment_t += size * sum_t / count;
      return;
    }
    const Real sm = 0.5 * (s0 + s1), tm = 0.5 * (t0 + t1);
    selected_part(s0, sm, t0, tm, depth - 1, area, moment_s, moment_t);
    selected_part(sm, s1, t0, tm, depth - 1, area, moment_s, moment_t);
    selected_part(s0, sm, tm, t1, depth - 1, area, moment_s, moment_t);
    selected_part(sm, s1, tm, t1, depth - 1, area, moment_s, moment_t);
  }
};

/// Levels of bisection below a sub-face that a selection boundary crosses: the boundary is located to
/// 1 / (split 2^6) of the cell (about 2e-3 of it for split 8).
constexpr int kBoundaryDepth = 6;

/// Appends the Gauss points of one boundary face (axis d, side) of a cell, optionally split into
/// `split` x `split` sub-faces. With `keep`, a sub-face where the selection holds at every sample
/// point (FaceSelection::sample) keeps its Gauss points, one where it holds nowhere is left out, and
/// one that the selection's boundary crosses gets a single point at the centroid of its selected part
/// with that part's area (FaceSelection::selected_part), so a load's resultant and its moment, and a
/// constraint's extent, follow the region to about 1 / (split 2^6) of the cell.
void append_face(const BackgroundCells& cells, Index c, int d, int side, const std::array<int, 3>& gauss, int split,
                 const std::array<std::vector<Real>, 3>& xi, const std::array<std::vector<Real>, 3>& wi,
                 SurfaceQuadrature& q, std::vector<Vec3>& points, std::vector<Vec3>& normals, std::vector<Real>& weights,
                 std::vector<Real>& sizes, const std::function<bool(const Vec3&, int)>* keep = nullptr) {
  const int a = (d + 1) % 3, b = (d + 2) % 3;
  Vec3 lo, hi;
  cells.bounds(c, lo, hi);
  const Vec3 step = kStepFraction * (hi - lo);
  const Real u_d = side == 0 ? lo[d] : hi[d];
  // one point of the face: parametric u, area weight in parameter space
  auto emit = [&](const Vec3& u, const Vec3& x, Real parametric_weight) {
    const Mat3 J = map_jacobian(cells.map, u, step);
    const Vec3 cross = J.col(a).cross(J.col(b));
    const Real area = cross.norm();
    const Real scale = (J.col(a).norm() + 1e-300) * (J.col(b).norm() + 1e-300);
    if (!(area > 1e-12 * scale)) return;  // degenerate face (collapsed axis): no area
    Vec3 normal = cross / area;
    const Real orientation = normal.dot(J.col(d));
    if ((side == 1 && orientation < 0) || (side == 0 && orientation > 0)) normal = -normal;
    points.push_back(x);
    normals.push_back(normal);
    weights.push_back(parametric_weight * area);
    sizes.push_back(J.col(d).norm() * (hi[d] - lo[d]));
    q.face.push_back(2 * d + side);
    q.cell.push_back(c);
  };
  std::optional<FaceSelection> selection;
  if (keep) {
    selection.emplace(FaceSelection{cells, d, a, b, 2 * d + side, u_d, *keep, xi[a], xi[b]});
    if (!selection->touches(lo[a], hi[a], lo[b], hi[b], split)) return;
  }
  for (int sb = 0; sb < split; ++sb)
    for (int sa = 0; sa < split; ++sa) {
      const Real a0 = lo[a] + (hi[a] - lo[a]) * sa / split, a1 = lo[a] + (hi[a] - lo[a]) * (sa + 1) / split;
      const Real b0 = lo[b] + (hi[b] - lo[b]) * sb / split, b1 = lo[b] + (hi[b] - lo[b]) * (sb + 1) / split;
      const Real ma = 0.5 * (a0 + a1), ha = 0.5 * (a1 - a0), mb = 0.5 * (b0 + b1), hb = 0.5 * (b1 - b0);
      if (selection) {
        int count = 0;
        Real sum_s = 0, sum_t = 0;
        const int in = selection->sample(a0, a1, b0, b1, count, sum_s, sum_t);
        if (in == 0) continue;
        if (in < count) {  // the region's boundary crosses this sub-face
          Real area = 0, moment_s = 0, moment_t = 0;
          selection->selected_part(a0, a1, b0, b1, kBoundaryDepth, area, moment_s, moment_t);
          if (area > 0) {
            const Vec3 u = selection->parametric(moment_s / area, moment_t / area);
            emit(u, cells.map.position(u), area);
          }
          continue;
        }
      }
      for (int kb = 0; kb < gauss[b]; ++kb)
        for (int ka = 0; ka < gauss[a]; ++ka) {
          Vec3 u;
          u[d] = u_d;
          u[a] = ma + ha * xi[a][ka];
          u[b] = mb + hb * xi[b][kb];
          emit(u, cells.map.position(u), wi[a][ka] * wi[b][kb] * ha * hb);
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

CellFaceQuadrature cell_face_quadrature(const BackgroundCells& cells, const std::array<int, 3>& gauss) {
  std::array<std::vector<Real>, 3> xi, wi;
  for (int d = 0; d < 3; ++d) gauss_legendre(gauss[d], xi[d], wi[d]);
  std::vector<Vec3> points, normals;
  std::vector<Real> weights, sizes;
  CellFaceQuadrature result;
  SurfaceQuadrature& q = result.faces;
  const Index n = cells.size();
  result.cell_begin.resize(static_cast<std::size_t>(n + 1));
  for (Index c = 0; c < n; ++c) {
    result.cell_begin[static_cast<std::size_t>(c)] = static_cast<Index>(points.size());
    for (int d = 0; d < 3; ++d)
      for (int side = 0; side < 2; ++side) append_face(cells, c, d, side, gauss, 1, xi, wi, q, points, normals, weights, sizes);
  }
  result.cell_begin[static_cast<std::size_t>(n)] = static_cast<Index>(points.size());
  q = finish(std::move(q), points, normals, weights, sizes);
  return result;
}

namespace {

/// refine_selected_faces over the faces (runs of base points of one cell face) on `threads` threads, each
/// with its own selector; every face's points are kept apart and joined in face order, so the result does
/// not depend on the thread count.
SurfaceQuadrature refine_faces(const BackgroundCells& cells, const SurfaceQuadrature& base, const std::array<int, 3>& gauss,
                               int split, const SelectorFactory& make_selected, int threads) {
  std::array<std::vector<Real>, 3> xi, wi;
  for (int d = 0; d < 3; ++d) gauss_legendre(gauss[d], xi[d], wi[d]);
  std::vector<Index> face_begin;  // the points of one face are consecutive
  for (Index s = 0; s < base.size();) {
    face_begin.push_back(s);
    Index e = s;
    while (e < base.size() && base.cell[static_cast<std::size_t>(e)] == base.cell[static_cast<std::size_t>(s)] &&
           base.face[static_cast<std::size_t>(e)] == base.face[static_cast<std::size_t>(s)])
      ++e;
    s = e;
  }
  face_begin.push_back(base.size());
  const auto faces = static_cast<Index>(face_begin.size()) - 1;
  struct FacePoints {
    SurfaceQuadrature q;  // face and cell of each point
    std::vector<Vec3> points, normals;
    std::vector<Real> weights, sizes;
  };
  std::vector<FacePoints> parts(static_cast<std::size_t>(faces));
  std::exception_ptr failure;
#pragma omp parallel num_threads(threads) if (threads > 1 && faces > 1)
  {
    std::function<bool(const Vec3&, int)> selected;
    try {
      selected = make_selected();
    } catch (...) {
#pragma omp critical(lamina_refine_faces_failure)
      if (!failure) failure = std::current_exception();
    }
#pragma omp for schedule(dynamic, 4)
    for (Index f = 0; f < faces; ++f) {
      if (!selected) continue;
      try {
        const Index s = face_begin[static_cast<std::size_t>(f)], e = face_begin[static_cast<std::size_t>(f + 1)];
        int hits = 0;
        for (Index i = s; i < e; ++i) hits += selected(base.points.col(i), base.face[static_cast<std::size_t>(i)]) ? 1 : 0;
        const int face = base.face[static_cast<std::size_t>(s)];
        const Index c = base.cell[static_cast<std::size_t>(s)];
        // A face where the selection holds at every base point and at the face's own sample points (set in
        // from its edges and corners) is taken whole; every other face is split and tested sub-face by
        // sub-face (a region smaller than a cell may hold at none of the base points).
        bool all = hits == e - s;
        if (all) {
          const int d = face / 2, a = (d + 1) % 3, b = (d + 2) % 3;
          Vec3 lo, hi;
          cells.bounds(c, lo, hi);
          const FaceSelection whole{cells, d, a, b, face, face % 2 == 0 ? lo[d] : hi[d], selected, xi[a], xi[b]};
          int count = 0;
          Real sum_s = 0, sum_t = 0;
          all = whole.sample(lo[a], hi[a], lo[b], hi[b], count, sum_s, sum_t) == count;
        }
        FacePoints& part = parts[static_cast<std::size_t>(f)];
        append_face(cells, c, face / 2, face % 2, gauss, all ? 1 : split, xi, wi, part.q, part.points, part.normals,
                    part.weights, part.sizes, all ? nullptr : &selected);
      } catch (...) {
#pragma omp critical(lamina_refine_faces_failure)
        if (!failure) failure = std::current_exception();
      }
    }
  }
  if (failure) std::rethrow_exception(failure);
  SurfaceQuadrature q;
  std::vector<Vec3> points, normals;
  std::vector<Real> weights, sizes;
  for (const FacePoints& part : parts) {
    q.face.insert(q.face.end(), part.q.face.begin(), part.q.face.end());
    q.cell.insert(q.cell.end(), part.q.cell.begin(), part.q.cell.end());
    points.insert(points.end(), part.points.begin(), part.points.end());
    normals.insert(normals.end(), part.normals.begin(), part.normals.end());
    weights.insert(weights.end(), part.weights.begin(), part.weights.end());
    sizes.insert(sizes.end(), part.sizes.begin(), part.sizes.end());
  }
  return finish(std::move(q), points, normals, weights, sizes);
}

}  // namespace

SurfaceQuadrature refine_selected_faces(const BackgroundCells& cells, const SurfaceQuadrature& base,
                                        const std::array<int, 3>& gauss, int split, const SelectorFactory& make_selected) {
  return refine_faces(cells, base, gauss, split, make_selected, omp_get_max_threads());
}

SurfaceQuadrature refine_selected_faces(const BackgroundCells& cells, const SurfaceQuadrature& base,
                                        const std::array<int, 3>& gauss, int split,
                                        const std::function<bool(const Vec3&, int)>& selected) {
  return refine_faces(cells, base, gauss, split, [&selected] { return selected; }, 1);
}

}  // namespace lamina::efg
