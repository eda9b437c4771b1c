#include "geometry/mapped_grid.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <set>

#include "core/error.hpp"

namespace lamina::geometry {

std::vector<Real> axis_nodes(const GridAxis& axis, int n) {
  std::vector<Real> u(static_cast<std::size_t>(n));
  const Real span = axis.hi - axis.lo;
  for (int i = 0; i < n; ++i) {
    if (axis.periodic)
      u[i] = axis.lo + span * i / n;
    else if (n == 1)
      u[i] = 0.5 * (axis.lo + axis.hi);
    else
      u[i] = (i == n - 1) ? axis.hi : axis.lo + span * i / (n - 1);
  }
  return u;
}

std::array<Real, 2> axis_tributary(const GridAxis& axis, int n, int i) {
  const Real span = axis.hi - axis.lo;
  if (axis.periodic) {
    const Real h = span / n, c = axis.lo + span * i / n;
    return {c - 0.5 * h, c + 0.5 * h};
  }
  if (n == 1) return {axis.lo, axis.hi};
  const Real h = span / (n - 1);
  const Real a = (i == 0) ? axis.lo : axis.lo + h * (i - 0.5);
  const Real b = (i == n - 1) ? axis.hi : axis.lo + h * (i + 0.5);
  return {a, b};
}

namespace {

int minimum_count(const GridAxis& axis) { return axis.periodic ? std::max(3, axis.min_count) : std::max(1, axis.min_count); }

void check_count(const GridAxis& axis, int count, int d, const std::string& key_path, const char* what) {
  const int minimum = minimum_count(axis);
  if (count < minimum)
    throw InputError(fmt::format("{}.{}", key_path, d),
                     fmt::format("at least {} {} along the {} direction{}", minimum, what, axis.name,
                                 axis.periodic ? " (closed, periodic)" : ""),
                     fmt::format("{}", count));
}

void sort_unique(IndexList& list) {
  std::sort(list.begin(), list.end());
  list.erase(std::unique(list.begin(), list.end()), list.end());
}

}  // namespace

PointCloud build_volume_grid(const VolumeMap& map, const std::array<int, 3>& counts, const std::string& key_path) {
  for (int d = 0; d < 3; ++d) check_count(map.axes[d], counts[d], d, key_path, "nodes");
  if (map.collapse_axis >= 0 && counts[map.collapse_axis] < 2)
    throw InputError(fmt::format("{}.{}", key_path, map.collapse_axis),
                     fmt::format("at least 2 nodes along the {} direction", map.axes[map.collapse_axis].name),
                     fmt::format("{}", counts[map.collapse_axis]));
  const std::array<int, 3> n = counts;
  std::array<std::vector<Real>, 3> u;
  std::array<std::vector<std::array<Real, 2>>, 3> trib;
  for (int d = 0; d < 3; ++d) {
    u[d] = axis_nodes(map.axes[d], n[d]);
    for (int i = 0; i < n[d]; ++i) trib[d].push_back(axis_tributary(map.axes[d], n[d], i));
  }
  const Index total = static_cast<Index>(n[0]) * n[1] * n[2];
  auto flat = [&](const std::array<int, 3>& s) { return s[0] + static_cast<Index>(n[0]) * (s[1] + static_cast<Index>(n[1]) * s[2]); };
  auto duplicate = [&](const std::array<int, 3>& s) {
    return map.collapse_axis >= 0 && s[map.collapse_axis] == 0 && s[map.collapse_over] != 0;
  };
  auto representative = [&](std::array<int, 3> s) {
    if (duplicate(s)) s[map.collapse_over] = 0;
    return s;
  };

  // Number the kept nodes in structured order, then point duplicates at their representative.
  std::vector<Index> node_of(static_cast<std::size_t>(total), -1);
  Index count = 0;
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        const std::array<int, 3> s{i, j, k};
        if (!duplicate(s)) node_of[flat(s)] = count++;
      }
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        const std::array<int, 3> s{i, j, k};
        if (duplicate(s)) node_of[flat(s)] = node_of[flat(representative(s))];
      }

  PointCloud cloud;
  cloud.positions.resize(3, count);
  cloud.parametric.resize(3, count);
  cloud.volumes = Eigen::VectorXd::Zero(count);
  cloud.spacing = Eigen::Matrix3Xd::Zero(3, count);
  cloud.counts = {n[0], n[1], n[2]};
  auto param = [&](const std::array<int, 3>& s) { return Vec3(u[0][s[0]], u[1][s[1]], u[2][s[2]]); };

  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        const std::array<int, 3> s{i, j, k};
        const Index node = node_of[flat(s)];
        if (!duplicate(s)) {
          cloud.parametric.col(node) = param(s);
          cloud.positions.col(node) = map.position(param(s));
        }
        const Vec3 lo(trib[0][i][0], trib[1][j][0], trib[2][k][0]);
        const Vec3 hi(trib[0][i][1], trib[1][j][1], trib[2][k][1]);
        cloud.volumes[node] += map.measure(lo, hi);
      }

  // Local spacing: largest coordinate differences to the grid neighbours.
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        const std::array<int, 3> s{i, j, k};
        const Index node = node_of[flat(s)];
        const Vec3 x = cloud.positions.col(node);
        Vec3 h = cloud.spacing.col(node);
        for (int d = 0; d < 3; ++d) {
          if (n[d] == 1) {
            Vec3 a = param(s), b = param(s);
            a[d] = map.axes[d].lo;
            b[d] = map.axes[d].hi;
            h = h.cwiseMax((map.position(b) - map.position(a)).cwiseAbs());
            continue;
          }
          for (int step : {-1, 1}) {
            std::array<int, 3> t = s;
            t[d] += step;
            if (map.axes[d].periodic)
              t[d] = (t[d] + n[d]) % n[d];
            else if (t[d] < 0 || t[d] >= n[d])
              continue;
            h = h.cwiseMax((cloud.positions.col(node_of[flat(t)]) - x).cwiseAbs());
          }
        }
        cloud.spacing.col(node) = h;
      }

  for (const GridSet& set : map.sets) {
    IndexList& list = cloud.sets[set.name];
    for (int k = 0; k < n[2]; ++k)
      for (int j = 0; j < n[1]; ++j)
        for (int i = 0; i < n[0]; ++i) {
          const std::array<int, 3> s{i, j, k};
          if (set.side < 0 || s[set.axis] == (set.side == 0 ? 0 : n[set.axis] - 1)) list.push_back(node_of[flat(s)]);
        }
    sort_unique(list);
  }
  return cloud;
}

ShellMesh build_surface_grid(const SurfaceMap& map, const std::array<int, 2>& elements, const std::string& key_path) {
  for (int d = 0; d < 2; ++d) check_count(map.axes[d], elements[d], d, key_path, "elements");
  std::array<int, 2> n{};
  std::array<std::vector<Real>, 2> u;
  for (int d = 0; d < 2; ++d) {
    n[d] = map.axes[d].periodic ? elements[d] : elements[d] + 1;
    u[d] = axis_nodes(map.axes[d], n[d]);
  }
  const int over = 1 - map.collapse_axis;
  auto duplicate = [&](int i, int j) {
    const std::array<int, 2> s{i, j};
    return map.collapse_axis >= 0 && s[map.collapse_axis] == 0 && s[over] != 0;
  };
  std::vector<Index> node_of(static_cast<std::size_t>(n[0]) * n[1], -1);
  auto flat = [&](int i, int j) { return static_cast<std::size_t>(i) + static_cast<std::size_t>(n[0]) * j; };
  Index count = 0;
  for (int j = 0; j < n[1]; ++j)
    for (int i = 0; i < n[0]; ++i)
      if (!duplicate(i, j)) node_of[flat(i, j)] = count++;
  for (int j = 0; j < n[1]; ++j)
    for (int i = 0; i < n[0]; ++i)
      if (duplicate(i, j)) node_of[flat(i, j)] = node_of[flat(0, 0)];  // the collapsed line's representative

  ShellMesh mesh;
  mesh.thickness = map.thickness;
  mesh.nodes.resize(3, count);
  for (int j = 0; j < n[1]; ++j)
    for (int i = 0; i < n[0]; ++i)
      if (!duplicate(i, j)) mesh.nodes.col(node_of[flat(i, j)]) = map.position(u[0][i], u[1][j]);

  std::vector<std::array<Index, 4>> quads;
  for (int j = 0; j < elements[1]; ++j)
    for (int i = 0; i < elements[0]; ++i) {
      const int i1 = (i + 1) % n[0], j1 = (j + 1) % n[1];
      const std::array<Index, 4> q{node_of[flat(i, j)], node_of[flat(i1, j)], node_of[flat(i1, j1)], node_of[flat(i, j1)]};
      if (std::set<Index>(q.begin(), q.end()).size() < 3) continue;  // fully collapsed
      quads.push_back(q);
    }
  mesh.quads.resize(4, static_cast<Index>(quads.size()));
  for (std::size_t e = 0; e < quads.size(); ++e)
    for (int a = 0; a < 4; ++a) mesh.quads(a, static_cast<Index>(e)) = quads[e][a];

  for (const GridSet& set : map.sets) {
    IndexList& list = mesh.sets[set.name];
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        const std::array<int, 2> s{i, j};
        if (set.side < 0 || s[set.axis] == (set.side == 0 ? 0 : n[set.axis] - 1)) list.push_back(node_of[flat(i, j)]);
      }
    sort_unique(list);
  }
  return mesh;
}

}  // namespace lamina::geometry
