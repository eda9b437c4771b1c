#include "app/mpfem_method.hpp"

#include <fmt/format.h>

#include <cmath>

#include "core/error.hpp"
#include "geometry/expression.hpp"
#include "geometry/generators.hpp"
#include "mpfem/mesh_boundary.hpp"
#include "mpfem/particle_conditions.hpp"
#include "mpfem/mpfem_analysis.hpp"
#include "mpfem/plate_with_hole.hpp"

namespace lamina::app {

namespace {

struct HoleOptions {
  Real radius = 1.0;
  Real grading = 1.0;
};

struct MpfemMethodOptions : MethodOptions {
  mpfem::MpfemOptions options;
  std::string neighbours = "auto";
  std::string particle_strain = "auto";
  int refine = 1;
  std::optional<HoleOptions> hole;
};

std::unique_ptr<MethodOptions> read_mpfem(const io::Case&, const io::NodeReader& section) {
  auto result = std::make_unique<MpfemMethodOptions>();
  auto& o = result->options;
  if (!section.defined()) return result;
  if (!section.expect_map()) return result;
  o.plane = section.word("plane", {"stress", "strain"}, "stress") == "strain" ? mpfem::PlaneKind::strain
                                                                             : mpfem::PlaneKind::stress;
  o.element = section.word("element", {"five_node", "t3"}, "five_node") == "t3" ? mpfem::ElementKind::t3
                                                                                : mpfem::ElementKind::five_node;
  o.stabilization = section.real("stabilization", 0.1, 0.0, 1.0, true, false);
  result->particle_strain = section.word("particle_strain", {"auto", "cell", "star", "voronoi"}, "auto");
  result->neighbours = section.word("neighbours", {"auto", "grid", "sectors"}, "auto");
  o.elements.max_neighbour_distance = section.real("max_neighbour_distance", 3.0, 1.0, 100.0);
  o.traction_quadrature = section.word("traction_quadrature", {"gauss", "particle"}, "gauss") == "particle"
                              ? mpfem::TractionQuadrature::particle
                              : mpfem::TractionQuadrature::gauss;
  result->refine = static_cast<int>(section.integer("refine", 1, 1, 64));
  if (section.word("analysis", {"linear_static", "large_deformation"}, "linear_static") == "large_deformation")
    o.analysis = mpfem::MpfemAnalysisKind::large_deformation;
  io::NodeReader large = section.child("large_deformation");
  if (large.defined() && large.expect_map()) {
    if (o.analysis != mpfem::MpfemAnalysisKind::large_deformation)
      large.error("no large_deformation: settings without analysis: large_deformation", "large_deformation settings");
    auto& l = o.large_deformation;
    l.increments = static_cast<int>(large.integer("increments", 10, 1, 100000));
    l.tolerance = large.real("tolerance", 1e-8, 0.0, 1e-2, true);
    l.max_iterations = static_cast<int>(large.integer("max_iterations", 25, 1, 1000));
    l.bisections = static_cast<int>(large.integer("bisections", 6, 0, 30));
    l.rebuild = large.boolean("rebuild", true);
    large.reject_unknown_keys();
  }
  io::NodeReader hole = section.child("hole");
  if (hole.defined() && hole.expect_map()) {
    HoleOptions h;
    h.radius = hole.real("radius", std::nullopt, 0.0, INFINITY, true);
    h.grading = hole.real("grading", 1.0, 1.0, 4.0);
    hole.reject_unknown_keys();
    result->hole = h;
  }
  io::NodeReader exact = section.child("exact_displacement");
  if (exact.defined()) {
    if (exact.is_sequence() && (exact.node().size() == 2 || exact.node().size() == 3)) {
      std::array<std::string, 2> e;
      const auto items = exact.elements();
      for (std::size_t i = 0; i < 2; ++i) {
        geometry::ScalarField f = io::read_scalar_field(items[i]);
        e[i] = f.is_constant() ? fmt::format("{:.17g}", f.constant) : f.expression;
        try {
          geometry::Expression check(e[i]);
        } catch (const geometry::ExpressionError& error) {
          items[i].error("an expression of x, y", error.what());
        }
      }
      o.exact_displacement = e;
    } else {
      exact.error("two expressions [ux, uy] of x, y");
    }
  }
  section.reject_unknown_keys();
  return result;
}

/// Resolves the case's selections on a regenerated particle cloud (the rules of build_point_model).
Model resolve_on(const io::Case& c, PointCloud cloud) {
  Model model;
  model.cloud = std::move(cloud);
  resolve_selections(c, model);
  return model;
}

Diagnostic at(const io::SourceLocation& where, const std::string& key, const std::string& expected, const std::string& found) {
  return model::diagnostic_at(where, key, expected, found);
}

std::unique_ptr<Analysis> create_mpfem(const io::Case& c, const Model& given, const MethodOptions& options) {
  const auto& o = static_cast<const MpfemMethodOptions&>(options);
  const io::SourceLocation& disc = c.discretization_location;
  mpfem::MpfemProblem p;
  p.options = o.options;
  p.options.solver = c.solver;
  const auto& g = c.geometry;
  switch (g.type) {
    case geometry::GeometryType::box:
      p.thickness = g.max.z() - g.min.z();
      p.z_mid = 0.5 * (g.max.z() + g.min.z());
      break;
    case geometry::GeometryType::plate: p.thickness = g.thickness, p.z_mid = 0; break;
    case geometry::GeometryType::curved_beam:
      p.thickness = g.z_range[1] - g.z_range[0];
      p.z_mid = 0.5 * (g.z_range[0] + g.z_range[1]);
      break;
    case geometry::GeometryType::annulus: p.thickness = g.thickness, p.z_mid = 0.5 * g.thickness; break;
    case geometry::GeometryType::mesh: p.thickness = g.thickness > 0 ? g.thickness : 1.0, p.z_mid = 0; break;
    default:
      throw InputError(at(c.geometry_location, ".type", "box, plate, curved_beam, annulus or mesh (mpfem is 2D in x-y)",
                          geometry::to_string(g.type)));
  }
  const bool generated = c.discretization.particles.has_value() && g.type != geometry::GeometryType::mesh;
  const bool jitter = c.discretization.jitter && c.discretization.jitter->amount > 0;

  // the particle cloud: the model's, or regenerated (refine, hole)
  Model regenerated;
  const Model* model = &given;
  std::array<int, 2> counts{0, 0};
  if (generated) counts = *c.discretization.particles;
  if (o.hole || o.refine != 1) {
    if (!generated)
      throw InputError(at(disc, ".particles", "particle counts [n0, n1] (mpfem.refine and mpfem.hole regenerate them)",
                          "a particle file or mesh"));
    if (jitter)
      throw InputError(at(disc, ".jitter", "no jitter together with mpfem.refine or mpfem.hole", "a jitter"));
    for (auto& n : counts) n = o.refine * (n - 1) + 1;
    if (static_cast<double>(counts[0]) * counts[1] > 1e7)
      throw InputError(Diagnostic{c.file, 0, 0, "mpfem.refine", "at most 10000000 particles after refinement",
                                  fmt::format("{} x {}", counts[0], counts[1])});
    PointCloud cloud;
    if (o.hole) {
      if (g.type != geometry::GeometryType::box)
        throw InputError(at(c.geometry_location, ".type", "box (mpfem.hole cuts a quarter hole at its min corner)",
                            geometry::to_string(g.type)));
      mpfem::PlateWithHoleSpec spec;
      spec.origin = mpfem::Vec2(g.min.x(), g.min.y());
      spec.width = g.max.x() - g.min.x();
      spec.height = g.max.y() - g.min.y();
      spec.radius = o.hole->radius;
      spec.grading = o.hole->grading;
      spec.n_radial = counts[0];
      spec.n_angular = counts[1];
      mpfem::GeneratedParticles particles = mpfem::generate_plate_with_hole(spec);
      const Index n = particles.layout.positions.cols();
      cloud.positions.resize(3, n);
      cloud.positions.topRows(2) = particles.layout.positions;
      cloud.positions.row(2).setConstant(p.z_mid);
      cloud.volumes = particles.area * p.thickness;
      cloud.counts = {counts[0], counts[1], 1};
      cloud.sets = particles.sets;
    } else {
      cloud = geometry::generate_volume_nodes(g, {counts[0], counts[1], 1});
    }
    regenerated = resolve_on(c, std::move(cloud));
    model = &regenerated;
  }
  const Index n = model->cloud.size();
  p.layout.positions = model->cloud.positions.topRows(2);
  if (c.discretization.particles_file && g.type != geometry::GeometryType::mesh) {
    // a particle file over an analytic body: every particle must lie in it (in x-y)
    const Vec3 extent = model->cloud.positions.rowwise().maxCoeff() - model->cloud.positions.rowwise().minCoeff();
    const Real tolerance = 1e-9 * std::max<Real>(extent.norm(), 1e-300);
    Index outside = 0, first = -1;
    for (Index q = 0; q < n; ++q)
      if (!geometry::body_contains(g, Vec3(p.layout.positions(0, q), p.layout.positions(1, q), p.z_mid), tolerance))
        first = first < 0 ? q : first, ++outside;
    if (outside > 0)
      throw InputError("discretization.particles.file", fmt::format("particles inside the {} geometry", geometry::to_string(g.type)),
                          fmt::format("particle {} at ({:.6g}, {:.6g}) outside the body ({} particle(s) outside in "
                                      "'{}'); move it inside or remove it",
                                      first, p.layout.positions(0, first), p.layout.positions(1, first), outside,
                                      *c.discretization.particles_file));
  }
  if (generated) {
    const bool periodic = g.type == geometry::GeometryType::annulus && !g.slit;
    p.layout.grid = mpfem::LogicalGrid{counts[0], counts[1], periodic};
    if (static_cast<Index>(counts[0]) * counts[1] != n) p.layout.grid.reset();
  }
  if (o.neighbours == "grid") {
    if (!p.layout.grid)
      throw InputError(Diagnostic{c.file, 0, 0, "mpfem.neighbours",
                                  "neighbours: sectors (or auto) for particles without a generator grid", "grid"});
    p.options.elements.rule = mpfem::NeighbourRule::logical_grid;
  } else if (o.neighbours == "sectors") {
    p.options.elements.rule = mpfem::NeighbourRule::sectors;
  } else {
    p.options.elements.rule = p.layout.grid ? mpfem::NeighbourRule::logical_grid : mpfem::NeighbourRule::sectors;
  }

  const bool grid_rule = p.options.elements.rule == mpfem::NeighbourRule::logical_grid;
  if (o.particle_strain == "cell" && !grid_rule)
    throw InputError("mpfem.particle_strain",
                     "particle_strain: voronoi, star or auto for particles without a generator grid / neighbours: sectors",
                     "cell");
  // voronoi needs a convex body (cells clipped to the particles' convex hull: box and plate without a
  // hole) or a triangle mesh (cells clipped to the mesh's boundary polygon, any shape without holes)
  const bool convex = (g.type == geometry::GeometryType::box && !o.hole) || g.type == geometry::GeometryType::plate ||
                      g.type == geometry::GeometryType::mesh;
  if (o.particle_strain == "voronoi" && !convex)
    throw InputError("mpfem.particle_strain",
                     "particle_strain: star, cell or auto for a body that is not convex (voronoi clips the cells to the "
                     "particles' convex hull: box, plate or a mesh of a convex body)",
                     "voronoi");
  if (o.particle_strain == "star") p.options.particle_strain = mpfem::ParticleStrain::star;
  else if (o.particle_strain == "cell") p.options.particle_strain = mpfem::ParticleStrain::cell;
  else if (o.particle_strain == "voronoi" || !grid_rule) {
    p.options.particle_strain = convex ? mpfem::ParticleStrain::voronoi : mpfem::ParticleStrain::star;
  } else {
    p.options.particle_strain = mpfem::ParticleStrain::cell;
  }
  if (p.options.particle_strain == mpfem::ParticleStrain::voronoi && g.type != geometry::GeometryType::mesh)
    p.options.body_area = geometry::body_volume(g) / p.thickness;
  if (p.options.particle_strain == mpfem::ParticleStrain::voronoi && !model->triangles.empty()) {
    try {
      p.body_boundary = mpfem::mesh_boundary_loop(p.layout.positions, model->triangles);
    } catch (const InputError& e) {
      std::vector<Diagnostic> located = e.diagnostics();
      for (auto& d : located) d.key_path = "geometry.file", d.found = "'" + g.file + "': " + d.found;
      throw InputError(located);
    }
  }
  std::vector<Diagnostic> problems;
  // materials: each particle takes the first material whose selection holds there
  p.material_of_particle.assign(static_cast<std::size_t>(n), -1);
  for (std::size_t i = 0; i < c.materials.size(); ++i) {
    const auto& m = c.materials[i];
    io::SourceLocation where{c.file, 0, 0, fmt::format("materials.{}", i)};
    const bool large = p.options.analysis == mpfem::MpfemAnalysisKind::large_deformation;
    if (m.spec.model == material::MaterialModel::neo_hookean && !large) {
      problems.push_back(at(where, ".model", "linear_elastic (neo_hookean needs mpfem.analysis: large_deformation)",
                            "neo_hookean"));
      continue;
    }
    if (m.spec.model != material::MaterialModel::linear_elastic && m.spec.model != material::MaterialModel::neo_hookean) {
      problems.push_back(at(where, ".model", "linear_elastic or neo_hookean (mpfem is elastic)", "another model"));
      continue;
    }
    p.materials.push_back(material::LinearElastic{m.spec.E, m.spec.nu});
    p.material_models.push_back(m.spec.model);
    const int id = static_cast<int>(p.materials.size() - 1);
    if (m.select) {
      for (Index q : model->material_nodes[i])
        if (p.material_of_particle[static_cast<std::size_t>(q)] < 0) p.material_of_particle[static_cast<std::size_t>(q)] = id;
    } else {
      for (auto& q : p.material_of_particle)
        if (q < 0) q = id;
    }
  }
  if (problems.empty())
    for (Index q = 0; q < n; ++q)
      if (p.material_of_particle[static_cast<std::size_t>(q)] < 0) {
        problems.push_back(Diagnostic{c.file, 0, 0, "materials",
                                      "a material for every particle (add one without select:)",
                                      fmt::format("particle {} without a material", q)});
        break;
      }

  // essential conditions on particle dofs, as the case states them (mpfem/particle_conditions.hpp)
  p.prescribed = mpfem::prescribed_dofs(model->constraints, model->cloud.positions, problems);

  // loads
  for (const auto& l : model->loads) {
    using Kind = model::Load::Kind;
    if (l.kind != Kind::force && l.kind != Kind::traction && l.kind != Kind::pressure && l.kind != Kind::body_force) {
      problems.push_back(at(l.location, "", "force, traction, pressure or body_force (mpfem is a static analysis)",
                            "mass or initial_velocity"));
      continue;
    }
    if (l.kind != Kind::pressure && !(l.vector[2].is_constant() && l.vector[2].constant == 0.0)) {
      problems.push_back(at(l.location, ".2", "a zero z component (mpfem is 2D in x-y)",
                            l.vector[2].is_constant() ? fmt::format("{}", l.vector[2].constant) : l.vector[2].expression));
      continue;
    }
    p.loads.push_back(l);
  }
  if (!problems.empty()) throw InputError(problems);
  // the particle set's problems (coincident or isolated particles, cells) at the key the case names it with
  const std::string source = g.type == geometry::GeometryType::mesh ? "geometry.file"
                             : c.discretization.particles_file  ? "discretization.particles.file"
                                                                : "discretization.particles";
  try {
    return std::make_unique<mpfem::MpfemAnalysis>(std::move(p), model->probes);
  } catch (const InputError& e) {
    std::vector<Diagnostic> located = e.diagnostics();
    for (auto& d : located)
      if (d.file.empty() && d.key_path == "discretization.particles") d.key_path = source;
    throw InputError(located);
  }
}

}  // namespace

MethodEntry mpfem_method_entry() {
  return MethodEntry{io::MethodKeys{"mpfem", {"particles", "jitter"}, true},
                     "moving particle finite element method, 2D elastostatics, linear and large deformation (seed 001)", read_mpfem, create_mpfem,
                     {}, /*distributed=*/true};
}

}  // namespace lamina::app
