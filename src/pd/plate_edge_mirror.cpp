#include "pd/plate_edge_mirror.hpp"

#include <fmt/format.h>

#include <cmath>
#include <map>

namespace lamina::pd {

namespace {

/// m_G = S_m o m(image) + (I - S_m) o m(edge), a_G alike, terms of one column merged.
std::vector<MirrorTerm> reflected(const std::vector<MirrorTerm>& image, const std::vector<MirrorTerm>& edge,
                                  const Vec3& sign_m, const Vec3& sign_a) {
  std::vector<MirrorTerm> out;
  auto add = [&](const MirrorTerm& term, const Vec3& scale_m, const Vec3& scale_a) {
    const Vec3 m = term.m.cwiseProduct(scale_m), a = term.a.cwiseProduct(scale_a);
    for (MirrorTerm& existing : out)
      if (existing.column == term.column) {
        existing.m += m;
        existing.a += a;
        return;
      }
    out.push_back({term.column, m, a});
  };
  for (const MirrorTerm& term : image) add(term, sign_m, sign_a);
  for (const MirrorTerm& term : edge) add(term, Vec3::Ones() - sign_m, Vec3::Ones() - sign_a);
  std::erase_if(out, [](const MirrorTerm& term) { return term.m.isZero() && term.a.isZero(); });
  return out;
}

}  // namespace

PlateEdgeMirror no_edge_mirror(Index columns) {
  PlateEdgeMirror mirror;
  mirror.energy_factor.setOnes(columns);
  mirror.strip.setZero(2, columns);
  return mirror;
}

PlateEdgeMirror mirror_supported_edges(const PlateColumns& columns, const PointMatrix& centre,
                                       const std::vector<char>& held, Real reach) {
  const Index nc = columns.columns();
  PlateEdgeMirror mirror = no_edge_mirror(nc);
  if (nc == 0 || static_cast<Index>(held.size()) < 3 * static_cast<Index>(columns.node.size())) return mirror;
  const Real h = columns.spacing;
  const Real tolerance = 1e-3 * h;
  // every column (real, then mirror): centre and motion; positions on a grid of h / 64 for the lookups
  std::vector<Eigen::Vector2d> position;
  std::vector<std::vector<MirrorTerm>> motion;
  std::map<std::pair<long, long>, Index> at;
  auto key = [&](const Eigen::Vector2d& p) {
    return std::pair<long, long>{std::lround(p[0] * 64.0 / h), std::lround(p[1] * 64.0 / h)};
  };
  for (Index c = 0; c < nc; ++c) {
    position.emplace_back(centre.col(c).head<2>());
    motion.push_back({MirrorTerm{c, Vec3::Ones(), Vec3::Ones()}});
    at[key(position.back())] = c;
  }
  auto all_held = [&](Index c, int component) {
    for (Index p = columns.first[c]; p < columns.first[c + 1]; ++p)
      if (!held[static_cast<std::size_t>(3 * columns.node[p] + component)]) return false;
    return true;
  };
  for (int axis = 0; axis < 2; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int tangent = 1 - axis;
      Real line = side == 0 ? INFINITY : -INFINITY;
      for (Index c = 0; c < nc; ++c)
        line = side == 0 ? std::min(line, centre(axis, c)) : std::max(line, centre(axis, c));
      // the edge's columns: every node must hold the normal (even w) or the z motion (odd w)
      bool normal_held = true, deflection_held = true, tangent_held = true;
      Index on_line = 0;
      for (Index c = 0; c < nc; ++c) {
        if (std::abs(centre(axis, c) - line) > tolerance) continue;
        ++on_line;
        normal_held = normal_held && all_held(c, axis);
        deflection_held = deflection_held && all_held(c, 2);
        tangent_held = tangent_held && all_held(c, tangent);
      }
      if (on_line < 2 || !(normal_held || deflection_held)) continue;
      // the continuation's signs: +1 even, -1 odd about the edge column's value
      Vec3 sign_m = Vec3::Ones(), sign_a = Vec3::Ones();
      sign_m[axis] = -1;
      if (normal_held) {  // clamp or symmetry plane: w even (zero slope)
        sign_a[axis] = -1;
        if (tangent_held) sign_m[tangent] = -1;
      } else {  // simple support: w odd (no bending moment), the membrane continued linearly
        sign_m[tangent] = -1;
        sign_m[2] = -1;
        sign_a[tangent] = -1;
      }
      // mirror every column (real or mirror of an earlier edge) within reach inside the edge
      const Index existing = static_cast<Index>(position.size());
      std::vector<std::pair<Index, Index>> images;  // (image column, edge column)
      bool regular = true;
      for (Index c = 0; c < existing && regular; ++c) {
        const Real inside = side == 0 ? position[c][axis] - line : line - position[c][axis];
        if (!(inside > tolerance && inside <= reach + tolerance)) continue;
        Eigen::Vector2d foot = position[c];
        foot[axis] = line;
        Eigen::Vector2d image = position[c];
        image[axis] = 2 * line - position[c][axis];
        const auto edge = at.find(key(foot));
        regular = edge != at.end() && !at.contains(key(image));
        if (regular) images.emplace_back(c, edge->second);
      }
      if (!regular) continue;
      for (const auto& [c, edge] : images) {
        Eigen::Vector2d image = position[c];
        image[axis] = 2 * line - position[c][axis];
        at[key(image)] = static_cast<Index>(position.size());
        position.push_back(image);
        motion.push_back(
            reflected(motion[static_cast<std::size_t>(c)], motion[static_cast<std::size_t>(edge)], sign_m, sign_a));
        mirror.image_of.push_back(c);
      }
      for (Index c = 0; c < nc; ++c)
        if (std::abs(centre(axis, c) - line) <= tolerance) {
          mirror.energy_factor[c] *= 0.5;
          if (!tangent_held) mirror.strip(tangent, c) = 1.0;
        }
      const char* kind = normal_held ? (deflection_held ? "clamped" : "symmetry") : "simply supported";
      mirror.edges.push_back(fmt::format("{} = {:.6g} ({})", axis == 0 ? "x" : "y", line, kind));
    }
  const Index ghosts = static_cast<Index>(position.size()) - nc;
  mirror.centre.setZero(3, ghosts);
  for (Index g = 0; g < ghosts; ++g) mirror.centre.col(g).head<2>() = position[static_cast<std::size_t>(nc + g)];
  mirror.motion.assign(motion.begin() + nc, motion.end());
  return mirror;
}

}  // namespace lamina::pd
