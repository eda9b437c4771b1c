#include "geometry/body_maps.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/error.hpp"

namespace lamina::geometry {

using std::numbers::pi;

bool is_full_turn(Real angle_deg) { return angle_deg >= 360.0 - 1e-9; }
Real radians(Real degrees) { return degrees * pi / 180.0; }

CylinderFrame::CylinderFrame(int axis_index) {
  const int i = ((axis_index % 3) + 3) % 3;
  e1 = Vec3::Unit((i + 1) % 3);
  e2 = Vec3::Unit((i + 2) % 3);
  axis = Vec3::Unit(i);
}

Real SquareSection::perimeter() const { return 8.0 * (a - rc) + 2.0 * pi * rc; }

Eigen::Vector2d SquareSection::map(Real t, Real s) const {
  const Real quarter = 0.25 * perimeter();
  const Real qf = std::floor(s / quarter);
  Real local = s - qf * quarter;
  const int q = ((static_cast<int>(qf) % 4) + 4) % 4;
  Eigen::Vector2d x;
  if (rc > 0.0) {
    const Real straight = a - rc, arc = 0.5 * pi * rc;
    if (local <= straight) {
      x = {a + t, local};
    } else if (local <= straight + arc) {
      const Real psi = (local - straight) / rc;
      x = Eigen::Vector2d(straight, straight) + (rc + t) * Eigen::Vector2d(std::cos(psi), std::sin(psi));
    } else {
      x = {straight - (local - straight - arc), a + t};
    }
  } else {
    const Real stretch = 1.0 + t / a;  // mitred: the side's length grows linearly with the offset
    if (local <= a)
      x = {a + t, local * stretch};
    else
      x = {(a - (local - a)) * stretch, a + t};
  }
  for (int r = 0; r < q; ++r) x = Eigen::Vector2d(-x.y(), x.x());  // rotate by 90 degrees
  return x;
}

Real SquareSection::growth_integral(Real s) const {
  if (rc <= 0.0) return s / a;
  const Real quarter = 0.25 * perimeter();
  const Real qf = std::floor(s / quarter);
  const Real local = s - qf * quarter;
  return qf * 0.5 * pi + std::clamp((local - (a - rc)) / rc, 0.0, 0.5 * pi);
}

namespace {

GridAxis axis(const char* name, Real lo, Real hi, bool periodic = false, int min_count = 1) {
  return GridAxis{name, lo, hi, periodic, min_count};
}

/// Product of three one-dimensional measures (separable Jacobians).
template <class F0, class F1, class F2>
std::function<Real(const Vec3&, const Vec3&)> separable(F0 f0, F1 f1, F2 f2) {
  return [=](const Vec3& lo, const Vec3& hi) { return f0(lo[0], hi[0]) * f1(lo[1], hi[1]) * f2(lo[2], hi[2]); };
}

const auto length = [](Real a, Real b) { return b - a; };
const auto radial = [](Real a, Real b) { return 0.5 * (b * b - a * a); };     // integral of r dr
const auto spherical = [](Real a, Real b) { return (b * b * b - a * a * a) / 3.0; };  // rho^2 drho
const auto polar = [](Real a, Real b) { return std::cos(a) - std::cos(b); };  // sin(phi) dphi

}  // namespace

VolumeMap make_volume_map(const GeometrySpec& spec) {
  VolumeMap m;
  switch (spec.type) {
    case GeometryType::box:
    case GeometryType::plate: {
      const bool plate = spec.type == GeometryType::plate;
      const Real z0 = plate ? -0.5 * spec.thickness : spec.min.z(), z1 = plate ? 0.5 * spec.thickness : spec.max.z();
      m.axes = {axis("x", spec.min.x(), spec.max.x()), axis("y", spec.min.y(), spec.max.y()), axis("z", z0, z1)};
      m.position = [](const Vec3& u) { return u; };
      m.measure = separable(length, length, length);
      m.sets = {{"xmin", 0, 0}, {"xmax", 0, 1}, {"ymin", 1, 0}, {"ymax", 1, 1},
                {plate ? "bottom" : "zmin", 2, 0}, {plate ? "top" : "zmax", 2, 1}};
      break;
    }
    case GeometryType::curved_beam: {
      m.axes = {axis("radial", spec.inner_radius, spec.outer_radius),
                axis("circumferential", 0.0, radians(spec.angle_deg)),
                axis("z", spec.z_range[0], spec.z_range[1])};
      m.position = [](const Vec3& u) { return Vec3(u[0] * std::cos(u[1]), u[0] * std::sin(u[1]), u[2]); };
      m.measure = separable(radial, length, length);
      m.sets = {{"inner", 0, 0}, {"outer", 0, 1}, {"start", 1, 0}, {"end", 1, 1}, {"zmin", 2, 0}, {"zmax", 2, 1}};
      break;
    }
    case GeometryType::cylinder: {
      const CylinderFrame f(spec.axis);
      const bool full = is_full_turn(spec.angle_deg), tube = spec.thickness > 0.0;
      const Real r0 = tube ? spec.radius - 0.5 * spec.thickness : 0.0;
      const Real r1 = tube ? spec.radius + 0.5 * spec.thickness : spec.radius;
      m.axes = {axis(tube ? "through-thickness" : "radial", r0, r1),
                axis("circumferential", 0.0, full ? 2.0 * pi : radians(spec.angle_deg), full),
                axis("axial", 0.0, spec.length)};
      if (!tube) {
        m.collapse_axis = 0;
        m.collapse_over = 1;
      }
      m.position = [f](const Vec3& u) {
        return Vec3(u[0] * (std::cos(u[1]) * f.e1 + std::sin(u[1]) * f.e2) + u[2] * f.axis);
      };
      m.measure = separable(radial, length, length);
      m.sets = {{"end0", 2, 0}, {"end1", 2, 1}, {"outer", 0, 1}};
      if (tube) m.sets.push_back({"inner", 0, 0});
      if (!full) {
        m.sets.push_back({"edge0", 1, 0});
        m.sets.push_back({"edge1", 1, 1});
      }
      break;
    }
    case GeometryType::sphere_cap: {
      const bool full = is_full_turn(spec.sector_deg);
      const Real hole = radians(spec.polar_hole_deg);
      m.axes = {axis("through-thickness", spec.radius - 0.5 * spec.thickness, spec.radius + 0.5 * spec.thickness),
                axis("meridional", hole, 0.5 * pi),
                axis("circumferential", 0.0, full ? 2.0 * pi : radians(spec.sector_deg), full)};
      if (spec.polar_hole_deg <= 0.0) {
        m.collapse_axis = 1;
        m.collapse_over = 2;
      }
      m.position = [](const Vec3& u) {
        const Real s = std::sin(u[1]);
        return Vec3(u[0] * s * std::cos(u[2]), u[0] * s * std::sin(u[2]), u[0] * std::cos(u[1]));
      };
      m.measure = separable(spherical, polar, length);
      m.sets = {{"inner", 0, 0}, {"outer", 0, 1}, {"hole", 1, 0}, {"base", 1, 1}};
      if (!full) {
        m.sets.push_back({"side0", 2, 0});
        m.sets.push_back({"side1", 2, 1});
      }
      break;
    }
    case GeometryType::annulus: {
      m.axes = {axis("radial", spec.inner_radius, spec.outer_radius),
                axis("circumferential", 0.0, 2.0 * pi, !spec.slit, 3),
                axis("through-thickness", 0.0, spec.thickness)};
      m.position = [](const Vec3& u) { return Vec3(u[0] * std::cos(u[1]), u[0] * std::sin(u[1]), u[2]); };
      m.measure = separable(radial, length, length);
      m.sets = {{"inner", 0, 0}, {"outer", 0, 1}, {"bottom", 2, 0}, {"top", 2, 1}};
      if (spec.slit) {
        m.sets.push_back({"slit_start", 1, 0});
        m.sets.push_back({"slit_end", 1, 1});
      }
      break;
    }
    case GeometryType::square_tube: {
      const SquareSection section{0.5 * spec.width, spec.corner_radius};
      m.axes = {axis("through-thickness", -0.5 * spec.thickness, 0.5 * spec.thickness),
                axis("perimeter", 0.0, section.perimeter(), true), axis("axial", 0.0, spec.length)};
      m.position = [section](const Vec3& u) {
        const Eigen::Vector2d x = section.map(u[0], u[1]);
        return Vec3(x.x(), x.y(), u[2]);
      };
      // det J = 1 + t * (growth rate); integrate over t analytically, over s piecewise.
      m.measure = [section](const Vec3& lo, const Vec3& hi) {
        const Real ds = hi[1] - lo[1], dt = hi[0] - lo[0], dz = hi[2] - lo[2];
        const Real growth = section.growth_integral(hi[1]) - section.growth_integral(lo[1]);
        return dz * (ds * dt + growth * 0.5 * (hi[0] * hi[0] - lo[0] * lo[0]));
      };
      m.sets = {{"inner", 0, 0}, {"outer", 0, 1}, {"end0", 2, 0}, {"end1", 2, 1}};
      break;
    }
    case GeometryType::mesh:
      throw InputError("geometry.type", "a generator type (a mesh file has no parametric map)", "mesh");
  }
  return m;
}

SurfaceMap make_surface_map(const GeometrySpec& spec) {
  SurfaceMap m;
  switch (spec.type) {
    case GeometryType::plate: {
      m.axes = {axis("x", spec.min.x(), spec.max.x()), axis("y", spec.min.y(), spec.max.y())};
      m.position = [](Real u, Real v) { return Vec3(u, v, 0.0); };
      m.thickness = spec.thickness;
      m.sets = {{"xmin", 0, 0}, {"xmax", 0, 1}, {"ymin", 1, 0}, {"ymax", 1, 1}, {"bottom", 0, -1}, {"top", 0, -1}};
      break;
    }
    case GeometryType::box: {
      const Vec3 extent = spec.max - spec.min;
      int d = 2;
      if (extent.y() < extent[d]) d = 1;
      if (extent.x() < extent[d]) d = 0;
      const int p = (d + 1) % 3, q = (d + 2) % 3;
      static const char* names[3][2] = {{"xmin", "xmax"}, {"ymin", "ymax"}, {"zmin", "zmax"}};
      static const char* axis_names[3] = {"x", "y", "z"};
      m.axes = {axis(axis_names[p], spec.min[p], spec.max[p]), axis(axis_names[q], spec.min[q], spec.max[q])};
      const Real middle = 0.5 * (spec.min[d] + spec.max[d]);
      m.position = [=](Real u, Real v) {
        Vec3 x;
        x[p] = u;
        x[q] = v;
        x[d] = middle;
        return x;
      };
      m.thickness = extent[d];
      m.sets = {{names[p][0], 0, 0}, {names[p][1], 0, 1}, {names[q][0], 1, 0}, {names[q][1], 1, 1},
                {names[d][0], 0, -1}, {names[d][1], 0, -1}};
      break;
    }
    case GeometryType::curved_beam: {
      const Real rm = 0.5 * (spec.inner_radius + spec.outer_radius);
      m.axes = {axis("circumferential", 0.0, radians(spec.angle_deg)), axis("z", spec.z_range[0], spec.z_range[1])};
      m.position = [rm](Real u, Real v) { return Vec3(rm * std::cos(u), rm * std::sin(u), v); };
      m.thickness = spec.outer_radius - spec.inner_radius;
      m.sets = {{"start", 0, 0}, {"end", 0, 1}, {"zmin", 1, 0}, {"zmax", 1, 1}, {"inner", 0, -1}, {"outer", 0, -1}};
      break;
    }
    case GeometryType::cylinder: {
      if (!(spec.thickness > 0.0))
        throw InputError("geometry.thickness", "a thickness > 0 (a solid cylinder has no shell mid-surface)",
                         std::to_string(spec.thickness));
      const CylinderFrame f(spec.axis);
      const bool full = is_full_turn(spec.angle_deg);
      const Real r = spec.radius;
      m.axes = {axis("circumferential", 0.0, full ? 2.0 * pi : radians(spec.angle_deg), full),
                axis("axial", 0.0, spec.length)};
      m.position = [f, r](Real u, Real v) { return Vec3(r * (std::cos(u) * f.e1 + std::sin(u) * f.e2) + v * f.axis); };
      m.thickness = spec.thickness;
      m.sets = {{"end0", 1, 0}, {"end1", 1, 1}, {"inner", 0, -1}, {"outer", 0, -1}};
      if (!full) {
        m.sets.push_back({"edge0", 0, 0});
        m.sets.push_back({"edge1", 0, 1});
      }
      break;
    }
    case GeometryType::sphere_cap: {
      const bool full = is_full_turn(spec.sector_deg);
      const Real r = spec.radius;
      m.axes = {axis("meridional", radians(spec.polar_hole_deg), 0.5 * pi),
                axis("circumferential", 0.0, full ? 2.0 * pi : radians(spec.sector_deg), full)};
      if (spec.polar_hole_deg <= 0.0) m.collapse_axis = 0;
      m.position = [r](Real u, Real v) {
        return Vec3(r * std::sin(u) * std::cos(v), r * std::sin(u) * std::sin(v), r * std::cos(u));
      };
      m.thickness = spec.thickness;
      m.sets = {{"hole", 0, 0}, {"base", 0, 1}, {"inner", 0, -1}, {"outer", 0, -1}};
      if (!full) {
        m.sets.push_back({"side0", 1, 0});
        m.sets.push_back({"side1", 1, 1});
      }
      break;
    }
    case GeometryType::annulus: {
      const Real z = 0.5 * spec.thickness;
      m.axes = {axis("radial", spec.inner_radius, spec.outer_radius),
                axis("circumferential", 0.0, 2.0 * pi, !spec.slit, 3)};
      m.position = [z](Real u, Real v) { return Vec3(u * std::cos(v), u * std::sin(v), z); };
      m.thickness = spec.thickness;
      m.sets = {{"inner", 0, 0}, {"outer", 0, 1}, {"bottom", 0, -1}, {"top", 0, -1}};
      if (spec.slit) {
        m.sets.push_back({"slit_start", 1, 0});
        m.sets.push_back({"slit_end", 1, 1});
      }
      break;
    }
    case GeometryType::square_tube: {
      const SquareSection section{0.5 * spec.width, spec.corner_radius};
      m.axes = {axis("perimeter", 0.0, section.perimeter(), true), axis("axial", 0.0, spec.length)};
      m.position = [section](Real u, Real v) {
        const Eigen::Vector2d x = section.map(0.0, u);
        return Vec3(x.x(), x.y(), v);
      };
      m.thickness = spec.thickness;
      m.sets = {{"end0", 1, 0}, {"end1", 1, 1}, {"inner", 0, -1}, {"outer", 0, -1}};
      break;
    }
    case GeometryType::mesh:
      throw InputError("geometry.type", "a generator type (a mesh file has no parametric map)", "mesh");
  }
  return m;
}

}  // namespace lamina::geometry
