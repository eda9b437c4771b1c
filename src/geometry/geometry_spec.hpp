#pragma once
// The case file's `geometry:` block as typed data (PRODUCT.md section 4): which generator and
// its parameters. Filled by the case reader, consumed by the generators.
#include <array>
#include <string>

#include "core/types.hpp"

namespace lamina::geometry {

enum class GeometryType { box, plate, curved_beam, cylinder, sphere_cap, annulus, square_tube, mesh };

struct GeometrySpec {
  GeometryType type = GeometryType::box;
  // box: min/max corners. plate: min/max x-y corners (z ignored) + thickness.
  Vec3 min = Vec3::Zero();
  Vec3 max = Vec3::Ones();
  Real thickness = 0.0;           // plate, sphere_cap, annulus, square_tube; cylinder: > 0 means tube wall
  // curved_beam / annulus
  Real inner_radius = 0.0;
  Real outer_radius = 0.0;
  Real angle_deg = 90.0;          // curved_beam: sector angle from +x towards +y; cylinder panel angle (360 = full)
  std::array<Real, 2> z_range{0.0, 1.0};  // curved_beam z extent; annulus: z in [0, thickness] unless given
  // cylinder (axis along x, y or z through the origin, from 0 to length)
  Real radius = 0.0;
  Real length = 0.0;
  int axis = 2;                   // 0 = x, 1 = y, 2 = z
  // sphere_cap: sphere centred at the origin, pole on +z; hole of polar_hole_deg around the pole,
  // cap reaches down to the equator (z = 0); sector_deg of longitude from +x towards +y (360 = full)
  Real polar_hole_deg = 0.0;
  Real sector_deg = 360.0;
  // annulus
  bool slit = false;
  // square_tube: section width x width (outer-to-outer mid-surface width), along z from 0 to length
  Real width = 0.0;
  Real corner_radius = 0.0;
  // mesh
  std::string file;
};

const char* to_string(GeometryType type);

}  // namespace lamina::geometry
