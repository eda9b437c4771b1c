#include "mpfem/mesh_boundary.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <map>

#include "core/error.hpp"

namespace lamina::mpfem {

Real polygon_area(const Points2& x, const std::vector<Index>& loop) {
  Real twice = 0;
  for (std::size_t k = 0; k < loop.size(); ++k) {
    const Vec2 a = x.col(loop[k]), b = x.col(loop[(k + 1) % loop.size()]);
    twice += a.x() * b.y() - a.y() * b.x();
  }
  return 0.5 * twice;
}

std::vector<Index> mesh_boundary_loop(const Points2& x, const std::vector<std::array<Index, 3>>& triangles) {
  const char* key = "discretization.particles";
  const char* expected = "a triangle mesh of one body without holes (its boundary one closed loop)";
  // directed edges of counter-clockwise triangles; an edge used once is a boundary edge
  std::map<std::pair<Index, Index>, int> uses;  // (min, max) -> count
  std::vector<std::pair<Index, Index>> directed;
  for (const auto& t : triangles) {
    std::array<Index, 3> v = t;
    const Vec2 a = x.col(v[0]), b = x.col(v[1]), c = x.col(v[2]);
    const Real twice = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
    if (twice == 0.0) continue;  // a degenerate triangle adds no boundary
    if (twice < 0) std::swap(v[1], v[2]);
    for (int k = 0; k < 3; ++k) {
      const Index p = v[static_cast<std::size_t>(k)], q = v[static_cast<std::size_t>((k + 1) % 3)];
      ++uses[{std::min(p, q), std::max(p, q)}];
      directed.emplace_back(p, q);
    }
  }
  if (directed.empty()) throw InputError(key, expected, "no triangle with an area");
  std::map<Index, Index> next;  // boundary edge p -> q
  for (const auto& [p, q] : directed) {
    const int n = uses[{std::min(p, q), std::max(p, q)}];
    if (n > 2) throw InputError(key, expected, fmt::format("the edge of nodes {} and {} in {} triangles", p, q, n));
    if (n == 1 && !next.emplace(p, q).second)
      throw InputError(key, expected, fmt::format("the boundary touches itself at node {}", p));
  }
  std::vector<Index> loop;
  Index at = next.begin()->first;
  do {
    loop.push_back(at);
    const auto it = next.find(at);
    if (it == next.end()) throw InputError(key, expected, fmt::format("the boundary is open at node {}", at));
    at = it->second;
  } while (at != loop.front() && loop.size() <= next.size());
  if (loop.size() != next.size())
    throw InputError(key, expected,
                     fmt::format("several boundary loops (a hole or separate parts; {} of {} boundary nodes on the first)",
                                 loop.size(), next.size()));
  return loop;
}

}  // namespace lamina::mpfem
