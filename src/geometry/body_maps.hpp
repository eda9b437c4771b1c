#pragma once
// The parametric maps of the generator bodies (used by generators.cpp; see generators.hpp for
// the conventions they implement).
#include "geometry/geometry_spec.hpp"
#include "geometry/mapped_grid.hpp"

namespace lamina::geometry {

/// Right-handed frame of a cylinder: e1, e2 span the section, axis along spec.axis.
struct CylinderFrame {
  Vec3 e1, e2, axis;
  explicit CylinderFrame(int axis_index);
};

/// Mid-surface section of a square tube: half width a, corner radius rc (0 = sharp corners).
/// Arc length s starts at (a, 0) and runs counter-clockwise.
struct SquareSection {
  Real a = 0.5, rc = 0.0;
  Real perimeter() const;
  /// Point at offset t (along the outward normal; mitred at sharp corners) from arc length s.
  Eigen::Vector2d map(Real t, Real s) const;
  /// Integral over [0, s] of the wall's area growth rate d(det J)/dt: 1/rc on the arcs, 0 on
  /// straight sides; 1/a everywhere for sharp (mitred) corners. Valid for any real s.
  Real growth_integral(Real s) const;
};

bool is_full_turn(Real angle_deg);
Real radians(Real degrees);

VolumeMap make_volume_map(const GeometrySpec& spec);
SurfaceMap make_surface_map(const GeometrySpec& spec);

}  // namespace lamina::geometry
