#pragma once
// Helpers for the EFG unit tests: small problems built directly as efg::EfgProblem.
#include <string>

#include <fmt/format.h>

#include "efg/efg_analysis.hpp"
#include "geometry/generators.hpp"
#include "geometry/selection.hpp"

namespace lamina::efg::testing {

inline geometry::GeometrySpec box(const Vec3& lo, const Vec3& hi) {
  geometry::GeometrySpec g;
  g.type = geometry::GeometryType::box;
  g.min = lo;
  g.max = hi;
  return g;
}

inline model::Selection where(const std::string& expression, const PointCloud& cloud) {
  model::Selection r;
  r.spec.kind = geometry::SelectionSpec::Kind::where;
  r.spec.expression = expression;
  r.nodes = geometry::resolve_selection(r.spec, cloud.positions, cloud.sets);
  r.label = expression;
  return r;
}

inline model::Selection set(const std::string& name, const PointCloud& cloud) {
  model::Selection r;
  r.spec.kind = geometry::SelectionSpec::Kind::set;
  r.spec.set_name = name;
  r.nodes = geometry::resolve_selection(r.spec, cloud.positions, cloud.sets);
  r.label = name;
  return r;
}

inline geometry::ScalarField field(const std::string& expression) {
  geometry::ScalarField f;
  f.expression = expression;
  return f;
}

inline geometry::ScalarField constant(Real value) {
  geometry::ScalarField f;
  f.constant = value;
  return f;
}

/// The thick curved beam of reference R2: quarter ring r = 3..5, z in [-1, 1].
inline geometry::GeometrySpec curved_beam_spec() {
  geometry::GeometrySpec g;
  g.type = geometry::GeometryType::curved_beam;
  g.inner_radius = 3;
  g.outer_radius = 5;
  g.angle_deg = 90;
  g.z_range = {-1, 1};
  return g;
}

/// A full (360-degree) cylinder along `axis` (0 = x, 1 = y, 2 = z) from 0 to length; a tube wall of
/// mid-surface radius `radius` if thickness > 0, else solid.
inline geometry::GeometrySpec cylinder_spec(Real radius, Real length, int axis, Real thickness = 0.0) {
  geometry::GeometrySpec g;
  g.type = geometry::GeometryType::cylinder;
  g.radius = radius;
  g.length = length;
  g.axis = axis;
  g.thickness = thickness;
  g.angle_deg = 360.0;
  return g;
}

/// A body with nodes and one material, no conditions yet.
inline EfgProblem make_problem(const geometry::GeometrySpec& g, const std::array<int, 3>& nodes, Real E, Real nu) {
  EfgProblem p;
  p.geometry = g;
  p.cloud = geometry::generate_volume_nodes(g, nodes);
  EfgMaterial m;
  m.name = "solid";
  m.elastic = material::LinearElastic{E, nu};
  p.materials.push_back(m);
  p.options.mls.dimension = 3;
  return p;
}

/// Quarter of the clamped square plate of ../shared/references R1a/R1b: [0, 10]^2 x [0, 1], faces
/// x = 0 and y = 0 clamped, pressure 400 on the top face where x > patch and y > patch, with the
/// symmetry planes x = 10 and y = 10 if `symmetry`. E = 1e4.
inline EfgProblem clamped_plate_quarter(const std::array<int, 3>& nodes, Real nu, Real patch, bool symmetry) {
  EfgProblem p = make_problem(box(Vec3::Zero(), Vec3(10, 10, 1)), nodes, 1e4, nu);
  model::Constraint clamp;
  clamp.select = where("x < 1e-9 or y < 1e-9", p.cloud);
  clamp.fixed = {true, true, true};
  p.constraints.push_back(clamp);
  if (symmetry) {
    for (int a = 0; a < 2; ++a) {
      model::Constraint plane;
      plane.select = where(a == 0 ? "x > 10 - 1e-9" : "y > 10 - 1e-9", p.cloud);
      plane.fixed = {a == 0, a == 1, false};
      p.constraints.push_back(plane);
    }
  }
  model::Load load;
  load.kind = model::Load::Kind::pressure;
  load.select = where(fmt::format("x > {0:.17g} and y > {0:.17g} and z > 1 - 1e-9", patch), p.cloud);
  load.scalar = constant(400.0);
  p.loads.push_back(load);
  return p;
}

/// Linear patch-test field used by several tests.
inline const std::array<std::string, 3>& linear_field() {
  static const std::array<std::string, 3> f{"1e-3*(1 + 2*x + 3*y + 4*z)", "1e-3*(2 - x + 2*y + z)",
                                            "1e-3*(-1 + 3*x - 2*y + 0.5*z)"};
  return f;
}

inline Vec3 linear_field_at(const Vec3& x) {
  return 1e-3 * Vec3(1 + 2 * x[0] + 3 * x[1] + 4 * x[2], 2 - x[0] + 2 * x[1] + x[2], -1 + 3 * x[0] - 2 * x[1] + 0.5 * x[2]);
}

/// Unit cube with the linear field prescribed on the whole boundary.
inline EfgProblem patch_problem(int n, Real jitter) {
  EfgProblem p = make_problem(box(Vec3::Zero(), Vec3::Ones()), {n, n, n}, 1.0, 0.25);
  if (jitter > 0) {
    // deterministic perturbation of the interior nodes
    for (Index i = 0; i < p.cloud.size(); ++i) {
      Vec3 x = p.cloud.positions.col(i);
      bool interior = true;
      for (int d = 0; d < 3; ++d)
        if (x[d] < 1e-9 || x[d] > 1 - 1e-9) interior = false;
      if (!interior) continue;
      const Real h = 1.0 / (n - 1);
      x += jitter * h * Vec3(std::sin(12.9898 * i), std::sin(78.233 * i + 1), std::sin(37.719 * i + 2));
      p.cloud.positions.col(i) = x;
    }
  }
  model::Constraint c;
  c.select = where("x < 1e-9 or x > 1 - 1e-9 or y < 1e-9 or y > 1 - 1e-9 or z < 1e-9 or z > 1 - 1e-9", p.cloud);
  c.fixed = {true, true, true};
  for (int a = 0; a < 3; ++a) c.displacement[static_cast<std::size_t>(a)] = field(linear_field()[static_cast<std::size_t>(a)]);
  p.constraints.push_back(c);
  return p;
}

/// Zero values of the given components on the named node set.
inline void fix_set(EfgProblem& p, const std::string& name, const std::array<bool, 3>& components = {true, true, true}) {
  model::Constraint c;
  c.select = set(name, p.cloud);
  for (std::size_t a = 0; a < 3; ++a) c.fixed[a] = components[a];
  p.constraints.push_back(c);
}

/// A constant traction on the boundary faces of the named node set.
inline void traction_on_set(EfgProblem& p, const std::string& name, const Vec3& t) {
  model::Load load;
  load.kind = model::Load::Kind::traction;
  load.select = set(name, p.cloud);
  load.vector = {constant(t.x()), constant(t.y()), constant(t.z())};
  p.loads.push_back(load);
}

}  // namespace lamina::efg::testing
