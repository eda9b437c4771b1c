#pragma once
// Shared helpers for the geometry generator tests.
#include <cmath>
#include <functional>
#include <numbers>
#include <utility>
#include <vector>

#include "core/types.hpp"
#include "geometry/geometry_spec.hpp"

namespace lamina::geometry::testing {

inline constexpr Real pi = std::numbers::pi;

/// All pairs (i < j) of points closer than `tolerance`.
inline std::vector<std::pair<Index, Index>> coincident_pairs(const PointMatrix& x, Real tolerance) {
  std::vector<std::pair<Index, Index>> pairs;
  for (Index i = 0; i < x.cols(); ++i)
    for (Index j = i + 1; j < x.cols(); ++j)
      if ((x.col(i) - x.col(j)).norm() < tolerance) pairs.emplace_back(i, j);
  return pairs;
}

/// Indices of the points for which `on` holds.
inline IndexList matching(const PointMatrix& x, const std::function<bool(const Vec3&)>& on) {
  IndexList list;
  for (Index i = 0; i < x.cols(); ++i)
    if (on(x.col(i))) list.push_back(i);
  return list;
}

/// Distance from (x, y) to the half-plane through the z axis at polar angle `angle`
/// (the points s (cos, sin) with s >= 0), ignoring z.
inline Real distance_to_half_plane(Real x, Real y, Real angle) {
  const Real c = std::cos(angle), s = std::sin(angle);
  const Real along = x * c + y * s;
  if (along < 0) return std::hypot(x, y);
  return std::abs(-x * s + y * c);
}

/// Offset of (x, y) from the square tube's mid-surface section (positive outwards):
/// the Chebyshev distance for sharp corners, the rounded-square distance otherwise.
inline Real square_tube_offset(const GeometrySpec& s, Real x, Real y) {
  const Real a = 0.5 * s.width;
  if (s.corner_radius <= 0) return std::max(std::abs(x), std::abs(y)) - a;
  const Real b = a - s.corner_radius;
  const Real dx = std::abs(x) - b, dy = std::abs(y) - b;
  const Real sd = std::hypot(std::max(dx, 0.0), std::max(dy, 0.0)) + std::min(std::max(dx, dy), 0.0);
  return sd - s.corner_radius;
}

inline GeometrySpec box_spec(Vec3 lo, Vec3 hi) {
  GeometrySpec s;
  s.type = GeometryType::box;
  s.min = lo;
  s.max = hi;
  return s;
}
inline GeometrySpec plate_spec(Real x0, Real y0, Real x1, Real y1, Real t) {
  GeometrySpec s;
  s.type = GeometryType::plate;
  s.min = Vec3(x0, y0, -0.5 * t);
  s.max = Vec3(x1, y1, 0.5 * t);
  s.thickness = t;
  return s;
}
inline GeometrySpec curved_beam_spec(Real ri, Real ro, Real angle, Real z0, Real z1) {
  GeometrySpec s;
  s.type = GeometryType::curved_beam;
  s.inner_radius = ri;
  s.outer_radius = ro;
  s.angle_deg = angle;
  s.z_range = {z0, z1};
  return s;
}
inline GeometrySpec cylinder_spec(Real r, Real length, int axis, Real thickness, Real angle = 360.0) {
  GeometrySpec s;
  s.type = GeometryType::cylinder;
  s.radius = r;
  s.length = length;
  s.axis = axis;
  s.thickness = thickness;
  s.angle_deg = angle;
  return s;
}
inline GeometrySpec sphere_cap_spec(Real r, Real t, Real hole, Real sector) {
  GeometrySpec s;
  s.type = GeometryType::sphere_cap;
  s.radius = r;
  s.thickness = t;
  s.polar_hole_deg = hole;
  s.sector_deg = sector;
  return s;
}
inline GeometrySpec annulus_spec(Real ri, Real ro, Real t, bool slit) {
  GeometrySpec s;
  s.type = GeometryType::annulus;
  s.inner_radius = ri;
  s.outer_radius = ro;
  s.thickness = t;
  s.slit = slit;
  s.z_range = {0.0, t};
  return s;
}
inline GeometrySpec square_tube_spec(Real width, Real length, Real corner_radius, Real t) {
  GeometrySpec s;
  s.type = GeometryType::square_tube;
  s.width = width;
  s.length = length;
  s.corner_radius = corner_radius;
  s.thickness = t;
  return s;
}

}  // namespace lamina::geometry::testing
