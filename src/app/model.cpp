#include "app/model.hpp"

#include <fmt/format.h>

#include <fstream>
#include <random>
#include <sstream>

#include "core/error.hpp"
#include "geometry/expression.hpp"
#include "geometry/generators.hpp"
#include "geometry/gmsh_import.hpp"
#include "geometry/selection.hpp"
#include "geometry/cell_lattice.hpp"
#include "io/yaml_reader.hpp"

namespace lamina::app {

namespace {

Diagnostic diagnostic_at(const io::SourceLocation& location, const std::string& expected, const std::string& found) {
  return Diagnostic{location.file, location.line, location.column, location.key_path, expected, found};
}

/// Nodes at given positions; each carries an equal share of the body's volume.
PointCloud cloud_of(const std::vector<Vec3>& points, const geometry::GeometrySpec& spec) {
  PointCloud cloud;
  cloud.positions.resize(3, static_cast<Index>(points.size()));
  for (std::size_t i = 0; i < points.size(); ++i) cloud.positions.col(static_cast<Index>(i)) = points[i];
  const Real volume = spec.type == geometry::GeometryType::mesh ? 0.0 : geometry::body_volume(spec);
  cloud.volumes = Eigen::VectorXd::Constant(cloud.size(), volume / static_cast<Real>(cloud.size()));
  return cloud;
}

PointCloud read_nodes_csv(const std::string& path, const geometry::GeometrySpec& spec, const std::string& key) {
  std::ifstream in(path);
  if (!in) throw InputError(Diagnostic{path, 0, 0, key, "a readable CSV file of x,y,z", fmt::format("cannot open file '{}'", path)});
  std::vector<Vec3> points;
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.empty() || line[0] == '#') continue;
    for (char& ch : line)
      if (ch == ',' || ch == ';' || ch == '\t') ch = ' ';
    std::istringstream fields(line);
    Vec3 p;
    if (!(fields >> p.x() >> p.y() >> p.z())) {
      if (points.empty()) continue;  // a header line
      throw InputError(Diagnostic{path, line_number, 1, key, "x, y, z numbers", "'" + line + "'"});
    }
    points.push_back(p);
  }
  if (points.empty()) throw InputError(Diagnostic{path, 0, 0, key, "at least one node", "none"});
  return cloud_of(points, spec);
}

/// Random perturbation of the nodes by up to `amount` local spacings per direction; nodes keep
/// their position along a direction in which they lie on the bounding box (faces stay planar).
void jitter_nodes(PointCloud& cloud, const io::Jitter& jitter, const geometry::GeometrySpec& spec) {
  std::mt19937_64 generator(jitter.seed);
  std::uniform_real_distribution<Real> uniform(-1.0, 1.0);
  const Vec3 lower = cloud.positions.rowwise().minCoeff(), upper = cloud.positions.rowwise().maxCoeff();
  const Real tolerance = 1e-9 * (upper - lower).norm();
  for (Index i = 0; i < cloud.size(); ++i) {
    Vec3 p = cloud.positions.col(i);
    Vec3 moved = p;
    for (int d = 0; d < 3; ++d) {
      const Real step = uniform(generator);
      if (std::abs(p[d] - lower[d]) < tolerance || std::abs(p[d] - upper[d]) < tolerance) continue;
      const Real h = cloud.spacing.cols() == cloud.size() ? cloud.spacing(d, i) : 0.0;
      moved[d] += jitter.amount * h * step;
    }
    if (spec.type == geometry::GeometryType::mesh || geometry::body_contains(spec, moved, tolerance))
      cloud.positions.col(i) = moved;
  }
}

}  // namespace

Model build_point_model_unlocated(const io::Case& c, const ModelRequest& request);

IndexList resolve_or_throw(const io::Selection& selection, const PointCloud& cloud) {
  IndexList nodes;
  try {
    nodes = geometry::resolve_selection(selection.spec, cloud.positions, cloud.sets);
  } catch (const geometry::ExpressionError& e) {
    throw InputError(diagnostic_at(selection.location, "a valid expression", e.what()));
  } catch (const std::out_of_range& e) {
    throw InputError(diagnostic_at(selection.location, e.what(), "'" + selection.spec.set_name + "'"));
  }
  if (nodes.empty())
    throw InputError(diagnostic_at(selection.location, "a selection that matches at least one node",
                                   selection.spec.describe() + " matches none of the " + std::to_string(cloud.size()) + " nodes"));
  return nodes;
}

namespace {

}  // namespace

InputError locate(const InputError& e, const io::Case& c) {
  std::vector<Diagnostic> located = e.diagnostics();
  for (auto& d : located) {
    if (!d.file.empty()) continue;
    d.file = c.file;
    std::optional<std::pair<int, int>> position;
    if (!d.key_path.empty()) position = io::position_of(c.resolved, d.key_path);
    if (!position) {
      // a case built in code (OMLL deck): the recorded position of the key or its nearest ancestor
      for (std::string path = d.key_path; !path.empty() && !position;) {
        if (auto it = c.source_positions.find(path); it != c.source_positions.end()) position = it->second;
        const auto dot = path.rfind('.');
        path = dot == std::string::npos ? std::string() : path.substr(0, dot);
      }
    }
    if (position) {
      d.line = position->first;
      d.column = position->second;
    } else if (d.key_path.rfind("geometry", 0) == 0) {
      d.line = c.geometry_location.line;
      d.column = c.geometry_location.column;
    } else if (d.key_path.rfind("discretization", 0) == 0) {
      d.line = c.discretization_location.line;
      d.column = c.discretization_location.column;
    }
  }
  io::sort_by_position(located);
  return InputError(located);
}

Model build_point_model(const io::Case& c, const ModelRequest& request) {
  try {
    return build_point_model_unlocated(c, request);
  } catch (const InputError& e) {
    throw locate(e, c);
  }
}

Model build_point_model_unlocated(const io::Case& c, const ModelRequest& request) {
  Model model;
  const auto& d = c.discretization;
  if (d.elements || request.shell_mesh) {
    // shell methods: the mid-surface quadrilateral mesh; its nodes and edge sets are the cloud
    model.shell = geometry::generate_shell_mesh(c.geometry, d.elements.value_or(std::array<int, 2>{1, 1}));
    model.cloud.positions = model.shell->nodes;
    model.cloud.sets = model.shell->sets;
    model.cloud.volumes = Eigen::VectorXd::Constant(model.cloud.size(), model.shell->area() * model.shell->thickness /
                                                                            static_cast<Real>(std::max<Index>(model.cloud.size(), 1)));
  } else if (c.geometry.type == geometry::GeometryType::mesh) {
    geometry::ImportedMesh mesh = geometry::import_gmsh(c.geometry.file);
    model.cloud = std::move(mesh.cloud);
    model.triangles = std::move(mesh.triangles);
  } else if (d.nodes_file) {
    model.cloud = read_nodes_csv(*d.nodes_file, c.geometry, "discretization.nodes.file");
  } else if (d.node_coordinates) {
    model.cloud = cloud_of(*d.node_coordinates, c.geometry);
  } else if (d.spacing) {  // pd: cell-centred lattice over a box or plate
    const auto& g = c.geometry;
    if (g.type != geometry::GeometryType::box && g.type != geometry::GeometryType::plate)
      throw InputError(Diagnostic{c.file, c.geometry_location.line, 0, "geometry.type",
                                  "box or plate (a lattice from discretization.spacing)", geometry::to_string(g.type)});
    const bool plate = g.type == geometry::GeometryType::plate;
    const Vec3 lower = plate ? Vec3(g.min.x(), g.min.y(), -0.5 * g.thickness) : g.min;
    const Vec3 upper = plate ? Vec3(g.max.x(), g.max.y(), 0.5 * g.thickness) : g.max;
    const bool gauss_layers = plate && request.lattice_layers_at_gauss_points;
    model.cloud = geometry::lattice_point_cloud(geometry::make_cell_lattice(lower, upper, *d.spacing), plate, gauss_layers);
  } else if (d.nodes) {
    model.cloud = geometry::generate_volume_nodes(c.geometry, *d.nodes);
  } else if (d.particles) {  // 2D particle methods (mpfem): one layer in the generator's third direction
    model.cloud = geometry::generate_volume_nodes(c.geometry, {(*d.particles)[0], (*d.particles)[1], 1});
  } else if (d.particles_file) {
    model.cloud = read_nodes_csv(*d.particles_file, c.geometry, "discretization.particles.file");
  } else {
    // reported where the key is missing: the discretization mapping, or the document's root
    throw InputError(Diagnostic{c.file, c.discretization_location.line, c.discretization_location.column,
                                "discretization.nodes", "node counts [nx, ny, nz] or {file: nodes.csv}", "nothing"});
  }
  if (d.jitter && d.jitter->amount > 0) jitter_nodes(model.cloud, *d.jitter, c.geometry);

  resolve_selections(c, model);
  return model;
}

void resolve_selections(const io::Case& c, Model& model) {
  std::vector<Diagnostic> problems;
  auto resolve = [&](const io::Selection& s) -> IndexList {
    try {
      return resolve_or_throw(s, model.cloud);
    } catch (const InputError& e) {
      problems.insert(problems.end(), e.diagnostics().begin(), e.diagnostics().end());
      return {};
    }
  };
  model.constraints = c.boundary;
  for (std::size_t i = 0; i < model.constraints.size(); ++i) {
    auto& select = model.constraints[i].select;
    select.nodes = resolve(select);
    select.label = fmt::format("boundary.{}", i);
  }
  model.loads = c.loads;
  for (std::size_t i = 0; i < model.loads.size(); ++i) {
    auto& select = model.loads[i].select;
    select.nodes = resolve(select);
    select.label = fmt::format("loads.{}", i);
  }
  for (const auto& m : c.materials) {
    if (m.select) model.material_nodes.push_back(resolve(*m.select));
    else {
      IndexList all(model.cloud.size());
      for (Index i = 0; i < model.cloud.size(); ++i) all[i] = i;
      model.material_nodes.push_back(all);
    }
  }
  for (const auto& p : c.probes) {
    Probe probe;
    probe.name = p.name;
    probe.field = p.field;
    probe.component = p.component;
    probe.at = p.at;
    if (p.select) probe.nodes = resolve(*p.select);
    if (p.set) {
      io::Selection s;
      s.spec.kind = geometry::SelectionSpec::Kind::set;
      s.spec.set_name = *p.set;
      s.location = p.location;
      s.location.key_path += ".set";
      probe.nodes = resolve(s);
      probe.nearest_in_set = p.at.has_value();
    }
    model.probes.push_back(probe);
  }
  if (!problems.empty()) throw InputError(problems);
}

}  // namespace lamina::app
