#include "geometry/generators.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/error.hpp"
#include "geometry/body_maps.hpp"
#include "geometry/gmsh_import.hpp"

namespace lamina::geometry {

using std::numbers::pi;

namespace {

void require(bool ok, const char* key, const std::string& expected, const std::string& found) {
  if (!ok) throw InputError(std::string("geometry.") + key, expected, found);
}
void require(bool ok, const char* key, const std::string& expected, Real found) {
  require(ok, key, expected, fmt::format("{}", found));
}
std::string vec_text(const Vec3& v) { return fmt::format("[{}, {}, {}]", v.x(), v.y(), v.z()); }

/// Distance from the 2D point p to the ray {s d : s >= 0} (d a unit vector).
Real distance_to_ray(const Eigen::Vector2d& p, const Eigen::Vector2d& d) {
  const Real s = p.dot(d);
  if (s <= 0.0) return p.norm();
  return std::abs(p.x() * d.y() - p.y() * d.x());
}

/// Whether the 2D point p lies in the sector 0 <= angle <= sector (radians, < 2 pi), or within
/// `tolerance` of one of its bounding rays.
bool in_sector(const Eigen::Vector2d& p, Real sector, Real tolerance) {
  Real theta = std::atan2(p.y(), p.x());
  if (theta < 0.0) theta += 2.0 * pi;
  if (theta <= sector) return true;
  return distance_to_ray(p, {1.0, 0.0}) <= tolerance ||
         distance_to_ray(p, {std::cos(sector), std::sin(sector)}) <= tolerance;
}

bool in_range(Real v, Real lo, Real hi, Real tolerance) { return v >= lo - tolerance && v <= hi + tolerance; }

/// The thinnest axis of a box (ties: z, then y, then x).
int thinnest_axis(const Vec3& extent) {
  int d = 2;
  if (extent.y() < extent[d]) d = 1;
  if (extent.x() < extent[d]) d = 0;
  return d;
}

Real sector_angle(Real degrees) { return is_full_turn(degrees) ? 2.0 * pi : radians(degrees); }

}  // namespace

void validate_geometry(const GeometrySpec& s) {
  auto finite = [](Real v) { return std::isfinite(v); };
  switch (s.type) {
    case GeometryType::box:
      require(s.min.allFinite(), "min", "finite coordinates", vec_text(s.min));
      require(s.max.allFinite(), "max", "finite coordinates", vec_text(s.max));
      require((s.max.array() > s.min.array()).all(), "max", "max > min in every component", vec_text(s.max));
      break;
    case GeometryType::plate:
      require(s.min.head<2>().allFinite(), "min", "finite coordinates", vec_text(s.min));
      require(s.max.head<2>().allFinite(), "max", "finite coordinates", vec_text(s.max));
      require(s.max.x() > s.min.x() && s.max.y() > s.min.y(), "max", "max > min in x and y", vec_text(s.max));
      require(s.thickness > 0.0 && finite(s.thickness), "thickness", "a thickness > 0", s.thickness);
      break;
    case GeometryType::curved_beam:
      require(s.inner_radius > 0.0 && finite(s.inner_radius), "inner_radius", "an inner radius > 0", s.inner_radius);
      require(s.outer_radius > s.inner_radius && finite(s.outer_radius), "outer_radius", "outer_radius > inner_radius",
              s.outer_radius);
      require(s.angle_deg > 0.0 && s.angle_deg < 360.0, "angle",
              "an angle in (0, 360) degrees (a full ring is an annulus with slit)", s.angle_deg);
      require(finite(s.z_range[0]) && finite(s.z_range[1]) && s.z_range[1] > s.z_range[0], "z", "[z0, z1] with z1 > z0",
              fmt::format("[{}, {}]", s.z_range[0], s.z_range[1]));
      break;
    case GeometryType::cylinder:
      require(s.radius > 0.0 && finite(s.radius), "radius", "a radius > 0", s.radius);
      require(s.length > 0.0 && finite(s.length), "length", "a length > 0", s.length);
      require(s.axis >= 0 && s.axis <= 2, "axis", "x, y or z", fmt::format("{}", s.axis));
      require(s.angle_deg > 0.0 && s.angle_deg <= 360.0, "angle", "an angle in (0, 360] degrees", s.angle_deg);
      require(s.thickness >= 0.0 && s.thickness < 2.0 * s.radius, "thickness",
              "0 (solid) or a wall thickness < 2 * radius", s.thickness);
      break;
    case GeometryType::sphere_cap:
      require(s.radius > 0.0 && finite(s.radius), "radius", "a radius > 0", s.radius);
      require(s.thickness > 0.0 && s.thickness < 2.0 * s.radius, "thickness", "a thickness in (0, 2 * radius)", s.thickness);
      require(s.polar_hole_deg >= 0.0 && s.polar_hole_deg < 90.0, "polar_hole", "a polar hole in [0, 90) degrees",
              s.polar_hole_deg);
      require(s.sector_deg > 0.0 && s.sector_deg <= 360.0, "sector", "a sector in (0, 360] degrees", s.sector_deg);
      break;
    case GeometryType::annulus:
      require(s.inner_radius > 0.0 && finite(s.inner_radius), "inner_radius", "an inner radius > 0", s.inner_radius);
      require(s.outer_radius > s.inner_radius && finite(s.outer_radius), "outer_radius", "outer_radius > inner_radius",
              s.outer_radius);
      require(s.thickness > 0.0 && finite(s.thickness), "thickness", "a thickness > 0", s.thickness);
      break;
    case GeometryType::square_tube:
      require(s.width > 0.0 && finite(s.width), "width", "a width > 0", s.width);
      require(s.length > 0.0 && finite(s.length), "length", "a length > 0", s.length);
      require(s.thickness > 0.0 && s.thickness < s.width, "thickness", "a thickness in (0, width)", s.thickness);
      require(s.corner_radius >= 0.0 && s.corner_radius < 0.5 * s.width, "corner_radius",
              "a corner radius in [0, width / 2)", s.corner_radius);
      require(s.corner_radius == 0.0 || s.corner_radius >= 0.5 * s.thickness, "corner_radius",
              "0 (sharp corners) or a mid-surface corner radius >= thickness / 2", s.corner_radius);
      break;
    case GeometryType::mesh:
      require(!s.file.empty(), "file", "a Gmsh .msh file name", "nothing");
      break;
  }
}

PointCloud generate_volume_nodes(const GeometrySpec& spec, const std::array<int, 3>& counts) {
  validate_geometry(spec);
  if (spec.type == GeometryType::mesh) return import_gmsh(spec.file).cloud;
  return build_volume_grid(make_volume_map(spec), counts, "discretization.nodes");
}

ShellMesh generate_shell_mesh(const GeometrySpec& spec, const std::array<int, 2>& elements) {
  validate_geometry(spec);
  if (spec.type == GeometryType::mesh) {
    ImportedMesh imported = import_gmsh(spec.file);
    if (!imported.has_quads)
      throw InputError("geometry.file", "a mesh with quadrilateral (shell) elements", "'" + spec.file + "' has none");
    if (!(spec.thickness > 0))
      throw InputError("geometry.thickness", "the shell's thickness (a positive number) with a quadrilateral shell mesh",
                       "none");
    imported.shell.thickness = spec.thickness;
    return std::move(imported.shell);
  }
  return build_surface_grid(make_surface_map(spec), elements, "discretization.elements");
}

Real body_volume(const GeometrySpec& s) {
  validate_geometry(s);
  switch (s.type) {
    case GeometryType::box:
      return (s.max - s.min).prod();
    case GeometryType::plate:
      return (s.max.x() - s.min.x()) * (s.max.y() - s.min.y()) * s.thickness;
    case GeometryType::curved_beam:
      return 0.5 * radians(s.angle_deg) * (s.outer_radius * s.outer_radius - s.inner_radius * s.inner_radius) *
             (s.z_range[1] - s.z_range[0]);
    case GeometryType::cylinder: {
      const Real angle = sector_angle(s.angle_deg);
      if (s.thickness > 0.0) return angle * s.radius * s.thickness * s.length;  // (r1^2 - r0^2) / 2 = R t
      return 0.5 * angle * s.radius * s.radius * s.length;
    }
    case GeometryType::sphere_cap: {
      const Real r0 = s.radius - 0.5 * s.thickness, r1 = s.radius + 0.5 * s.thickness;
      return (r1 * r1 * r1 - r0 * r0 * r0) / 3.0 * std::cos(radians(s.polar_hole_deg)) * sector_angle(s.sector_deg);
    }
    case GeometryType::annulus:
      return pi * (s.outer_radius * s.outer_radius - s.inner_radius * s.inner_radius) * s.thickness;
    case GeometryType::square_tube:
      return SquareSection{0.5 * s.width, s.corner_radius}.perimeter() * s.thickness * s.length;
    case GeometryType::mesh:
      return import_gmsh(s.file).cloud.volumes.sum();
  }
  return 0.0;
}

Real mid_surface_area(const GeometrySpec& s) {
  validate_geometry(s);
  switch (s.type) {
    case GeometryType::box: {
      const Vec3 extent = s.max - s.min;
      return extent.prod() / extent[thinnest_axis(extent)];
    }
    case GeometryType::plate:
      return (s.max.x() - s.min.x()) * (s.max.y() - s.min.y());
    case GeometryType::curved_beam:
      return 0.5 * (s.inner_radius + s.outer_radius) * radians(s.angle_deg) * (s.z_range[1] - s.z_range[0]);
    case GeometryType::cylinder:
      if (!(s.thickness > 0.0))
        throw InputError("geometry.thickness", "a thickness > 0 (a solid cylinder has no shell mid-surface)",
                         fmt::format("{}", s.thickness));
      return sector_angle(s.angle_deg) * s.radius * s.length;
    case GeometryType::sphere_cap:
      return s.radius * s.radius * std::cos(radians(s.polar_hole_deg)) * sector_angle(s.sector_deg);
    case GeometryType::annulus:
      return pi * (s.outer_radius * s.outer_radius - s.inner_radius * s.inner_radius);
    case GeometryType::square_tube:
      return SquareSection{0.5 * s.width, s.corner_radius}.perimeter() * s.length;
    case GeometryType::mesh:
      return import_gmsh(s.file).shell.area();
  }
  return 0.0;
}

bool body_contains(const GeometrySpec& s, const Vec3& x, Real tol) {
  switch (s.type) {
    case GeometryType::box:
      return (x.array() >= s.min.array() - tol).all() && (x.array() <= s.max.array() + tol).all();
    case GeometryType::plate:
      return in_range(x.x(), s.min.x(), s.max.x(), tol) && in_range(x.y(), s.min.y(), s.max.y(), tol) &&
             in_range(x.z(), -0.5 * s.thickness, 0.5 * s.thickness, tol);
    case GeometryType::curved_beam: {
      const Eigen::Vector2d p(x.x(), x.y());
      return in_range(p.norm(), s.inner_radius, s.outer_radius, tol) && in_range(x.z(), s.z_range[0], s.z_range[1], tol) &&
             in_sector(p, radians(s.angle_deg), tol);
    }
    case GeometryType::cylinder: {
      const CylinderFrame f(s.axis);
      const Eigen::Vector2d p(x.dot(f.e1), x.dot(f.e2));
      const Real r0 = s.thickness > 0.0 ? s.radius - 0.5 * s.thickness : 0.0;
      const Real r1 = s.thickness > 0.0 ? s.radius + 0.5 * s.thickness : s.radius;
      return in_range(x.dot(f.axis), 0.0, s.length, tol) && in_range(p.norm(), r0, r1, tol) &&
             (is_full_turn(s.angle_deg) || in_sector(p, radians(s.angle_deg), tol));
    }
    case GeometryType::sphere_cap: {
      const Real rho = x.norm();
      if (!in_range(rho, s.radius - 0.5 * s.thickness, s.radius + 0.5 * s.thickness, tol) || x.z() < -tol) return false;
      const Eigen::Vector2d meridian(std::hypot(x.x(), x.y()), x.z());  // (distance from the axis, z)
      const Real hole = radians(s.polar_hole_deg);
      if (hole > 0.0 && std::atan2(meridian.x(), meridian.y()) < hole &&
          distance_to_ray(meridian, {std::sin(hole), std::cos(hole)}) > tol)
        return false;
      return is_full_turn(s.sector_deg) || in_sector({x.x(), x.y()}, radians(s.sector_deg), tol);
    }
    case GeometryType::annulus:
      return in_range(std::hypot(x.x(), x.y()), s.inner_radius, s.outer_radius, tol) && in_range(x.z(), 0.0, s.thickness, tol);
    case GeometryType::square_tube: {
      if (!in_range(x.z(), 0.0, s.length, tol)) return false;
      const Real a = 0.5 * s.width, half = 0.5 * s.thickness;
      if (s.corner_radius <= 0.0) return std::abs(std::max(std::abs(x.x()), std::abs(x.y())) - a) <= half + tol;
      // Signed distance to the square of half width a - rc; the mid-surface is its rc-offset.
      const Real b = a - s.corner_radius;
      const Real dx = std::abs(x.x()) - b, dy = std::abs(x.y()) - b;
      const Real signed_distance = std::hypot(std::max(dx, 0.0), std::max(dy, 0.0)) + std::min(std::max(dx, dy), 0.0);
      return std::abs(signed_distance - s.corner_radius) <= half + tol;
    }
    case GeometryType::mesh:
      return true;
  }
  return false;
}

}  // namespace lamina::geometry
