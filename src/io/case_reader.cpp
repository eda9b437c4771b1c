#include "io/case_reader.hpp"

#include <fmt/format.h>

#include <filesystem>
#include <regex>
#include <set>

#include "geometry/generators.hpp"
#include "material/material_registry.hpp"

namespace lamina::io {

using geometry::GeometryType;
using geometry::ScalarField;
using geometry::SelectionSpec;

SourceLocation location_of(const NodeReader& reader) {
  SourceLocation location;
  location.file = reader.sink().file();
  location.key_path = reader.path();
  if (reader.node().IsDefined() && reader.node().Mark().line >= 0) {
    location.line = reader.node().Mark().line + 1;
    location.column = reader.node().Mark().column + 1;
  } else if (auto position = reader.sink().source_position(reader.path())) {
    location.line = position->first;  // a case built in code (OMLL deck): the recorded position
    location.column = position->second;
  }
  return location;
}

ScalarField read_scalar_field(const NodeReader& reader) {
  ScalarField field;
  if (!reader.is_scalar()) {
    reader.error("a number or an expression string in x, y, z, t");
    return field;
  }
  const std::string& text = reader.node().Scalar();
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (!text.empty() && end && *end == '\0' && reader.node().Tag() != "!") {
    if (!std::isfinite(value)) reader.error("a finite number");
    field.constant = value;
    return field;
  }
  try {
    geometry::Expression expression(text);
    (void)expression.evaluate(Vec3::Zero(), 0.0);
    field.expression = text;
  } catch (const geometry::ExpressionError& e) {
    reader.error("a number or a valid expression in x, y, z, t", e.what());
  }
  return field;
}

std::optional<Selection> read_selection(const NodeReader& reader) {
  Selection selection;
  selection.location = location_of(reader);
  if (reader.is_scalar() && reader.node().Scalar() == "all") {
    selection.spec.kind = SelectionSpec::Kind::all;
    return selection;
  }
  if (!reader.is_map()) {
    reader.error("'all' or one of {where: EXPR}, {nearest: [x,y,z]}, {box: {min, max}}, {set: NAME}");
    return std::nullopt;
  }
  const std::vector<std::string> forms{"where", "nearest", "box", "set", "all"};
  int count = 0;
  for (const auto& form : forms) count += reader.has(form) ? 1 : 0;
  if (count != 1) {
    reader.error("exactly one of where, nearest, box, set, all", count == 0 ? "none" : fmt::format("{} of them", count));
    reader.reject_unknown_keys();
    return std::nullopt;
  }
  bool ok = true;
  if (reader.has("where")) {
    selection.spec.kind = SelectionSpec::Kind::where;
    NodeReader where = reader.child("where");
    auto text = where.as_string();
    if (!text) ok = false;
    else {
      try {
        geometry::Expression expression(*text);
        (void)expression.evaluate(Vec3::Zero());
        selection.spec.expression = *text;
      } catch (const geometry::ExpressionError& e) {
        where.error("a valid expression over x, y, z, r, theta", e.what());
        ok = false;
      }
    }
  } else if (reader.has("nearest")) {
    selection.spec.kind = SelectionSpec::Kind::nearest;
    auto p = reader.child("nearest").as_reals(3);
    if (p) selection.spec.point = Vec3((*p)[0], (*p)[1], (*p)[2]);
    else ok = false;
  } else if (reader.has("box")) {
    selection.spec.kind = SelectionSpec::Kind::box;
    NodeReader box = reader.child("box");
    if (box.expect_map()) {
      const std::size_t problems_before = reader.sink().diagnostics().size();
      selection.spec.box_min = box.vec3("min", std::nullopt);
      selection.spec.box_max = box.vec3("max", std::nullopt);
      const bool read_cleanly = reader.sink().diagnostics().size() == problems_before;
      if (!read_cleanly) ok = false;
      box.reject_unknown_keys();
      if (read_cleanly && (selection.spec.box_min.array() > selection.spec.box_max.array()).any())
        box.error("min <= max in every component", "min > max");
    } else ok = false;
  } else if (reader.has("set")) {
    selection.spec.kind = SelectionSpec::Kind::set;
    auto name = reader.child("set").as_string();
    if (name) selection.spec.set_name = *name;
    else ok = false;
  } else {
    selection.spec.kind = SelectionSpec::Kind::all;
    auto flag = reader.child("all").as_bool();
    if (!flag || !*flag) {
      if (flag) reader.child("all").error("true", "false");
      ok = false;
    }
  }
  reader.reject_unknown_keys();
  if (!ok) return std::nullopt;
  return selection;
}

Ramp read_ramp(const NodeReader& parent) {
  Ramp ramp;
  NodeReader r = parent.child("ramp");
  if (!r.defined()) return ramp;
  if (r.is_scalar()) {
    auto word = r.as_word({"linear", "step"});
    if (word) ramp.kind = *word == "step" ? Ramp::Kind::step : Ramp::Kind::linear;
    return ramp;
  }
  if (!r.is_sequence() || r.node().size() < 2) {
    r.error("linear, step, or a table [[t0, f0], [t1, f1], ...] with at least two rows");
    return ramp;
  }
  ramp.kind = Ramp::Kind::table;
  for (const auto& row : r.elements()) {
    auto pair = row.as_reals(2);
    if (!pair) continue;
    if (!ramp.table.empty() && (*pair)[0] <= ramp.table.back()[0]) row.error("times increasing down the table", fmt::format("{}", (*pair)[0]));
    ramp.table.push_back({(*pair)[0], (*pair)[1]});
  }
  return ramp;
}

namespace {

std::array<ScalarField, 3> read_vector_field(const NodeReader& reader) {
  std::array<ScalarField, 3> out;
  if (!reader.is_sequence() || reader.node().size() != 3) {
    reader.error("a list of 3 components (numbers or expressions)");
    return out;
  }
  auto items = reader.elements();
  for (int i = 0; i < 3; ++i) out[i] = read_scalar_field(items[i]);
  return out;
}

std::array<std::optional<ScalarField>, 3> read_component_map(const NodeReader& reader) {
  std::array<std::optional<ScalarField>, 3> out;
  if (!reader.expect_map()) return out;
  const char* names[3] = {"x", "y", "z"};
  for (int i = 0; i < 3; ++i)
    if (reader.has(names[i])) out[i] = read_scalar_field(reader.child(names[i]));
  reader.reject_unknown_keys();
  if (!out[0] && !out[1] && !out[2]) reader.error("at least one of x, y, z");
  return out;
}

const std::vector<std::string> kProbeFields{"displacement", "velocity", "stress", "strain", "reaction_force", "energy",
                                            "eigenvalue", "critical_load", "damage", "plastic_strain", "approximation"};
const std::vector<std::string> kComponents{"x", "y", "z", "xx", "yy", "zz", "xy", "yz", "zx", "magnitude", "von_mises"};
const std::vector<std::string> kEnergyComponents{"internal", "kinetic", "external", "hourglass", "contact", "damping", "total"};

}  // namespace

CaseReader::CaseReader(const std::string& path, const std::vector<std::string>& overrides,
                       std::vector<MethodKeys> methods)
    : path_(path), methods_(std::move(methods)), sink_(std::make_unique<DiagnosticSink>(path)) {
  document_ = load_yaml_file(path, *sink_);
  sink_->throw_if_any();
  apply_overrides(overrides);
}

CaseReader::CaseReader(const std::string& path, YAML::Node document,
                       std::map<std::string, std::pair<int, int>> positions, const std::vector<std::string>& overrides,
                       std::vector<MethodKeys> methods)
    : path_(path), methods_(std::move(methods)), sink_(std::make_unique<DiagnosticSink>(path)), document_(std::move(document)) {
  sink_->set_source_positions(std::move(positions));
  apply_overrides(overrides);
}

void CaseReader::apply_overrides(const std::vector<std::string>& overrides) {
  if (!document_.IsDefined() || document_.IsNull()) document_ = YAML::Node(YAML::NodeType::Map);
  for (const auto& assignment : overrides) {
    if (!document_.IsMap()) break;
    apply_override(document_, assignment, *sink_);
  }
  root_ = std::make_unique<NodeReader>(document_, "", sink_.get());
}

NodeReader CaseReader::method_section(const std::string& name) { return root_->child(name); }

void CaseReader::finish() {
  if (!method_known_) {
    // Without a valid method its sections cannot be judged: no follow-on "unknown key" errors.
    for (const auto& m : methods_) {
      (void)root_->child(m.method);
      for (const auto& other : m.other_sections) (void)root_->child(other);
    }
  }
  root_->reject_unknown_keys();
  sink_->throw_if_any();
}

Case CaseReader::read() {
  Case c;
  c.file = path_;
  c.stem = std::filesystem::path(path_).stem().string();
  c.resolved = document_;
  c.source_positions = sink_->source_positions();
  const NodeReader& root = *root_;
  if (!root.expect_map()) {
    sink_->throw_if_any();
  }

  c.title = root.string("title", c.stem);
  c.units = root.string("units", "");
  std::vector<std::string> method_names;
  for (const auto& m : methods_) method_names.push_back(m.method);
  c.method = root.word("method", method_names, std::nullopt);
  const MethodKeys* keys = nullptr;
  for (const auto& m : methods_)
    if (m.method == c.method) keys = &m;
  method_known_ = keys != nullptr;
  if (keys)
    for (const auto& other : keys->other_sections) (void)root.child(other);

  // materials
  NodeReader materials = root.child("materials");
  if (materials.defined()) {
    if (materials.expect_sequence() && materials.node().size() == 0) materials.error("at least one material");
    std::set<std::string> names;
    int index = 0;
    for (const auto& m : materials.elements()) {
      if (!m.expect_map()) continue;
      MaterialEntry entry;
      entry.spec.name = m.string("name", fmt::format("material{}", index++));
      if (!names.insert(entry.spec.name).second) m.child("name").error("a unique material name", "'" + entry.spec.name + "' again");
      std::vector<std::string> model_names;
      for (const auto& info : material::material_models()) model_names.push_back(info.name);
      const material::MaterialModelInfo* info = material::find_material_model(m.word("model", model_names, model_names.front()));
      if (!info) info = &material::material_models().front();  // the word's problem is reported
      entry.spec.model = info->model;
      entry.spec.E = m.real("E", std::nullopt, 0.0, INFINITY, true);
      entry.spec.nu = m.real("nu", std::nullopt, -1.0, 0.5, true, true);
      if (m.has("density")) entry.spec.density = m.real("density", 1.0, 0.0, INFINITY, true);
      for (const auto& k : info->constants)
        entry.spec.constants[k.key] = m.real(k.key, k.fallback, k.lower, k.upper, k.lower_open, k.upper_open);
      if (m.has("where") && m.has("select")) m.error("either where or select, not both");
      if (m.has("where")) {
        NodeReader where = m.child("where");
        auto text = where.as_string();
        if (text) {
          try {
            geometry::Expression e(*text);
            (void)e.evaluate(Vec3::Zero());
            Selection s;
            s.spec.kind = SelectionSpec::Kind::where;
            s.spec.expression = *text;
            s.location = location_of(where);
            entry.select = s;
          } catch (const geometry::ExpressionError& e) {
            where.error("a valid expression over x, y, z, r, theta", e.what());
          }
        }
      } else if (m.has("select")) {
        entry.select = read_selection(m.child("select"));
      }
      m.reject_unknown_keys();
      c.materials.push_back(entry);
    }
  } else if (keys && keys->needs_materials) {
    root.required("materials");
  }

  // geometry
  bool geometry_clean = false;  // geometry read without problems (c.geometry holds the user's values)
  NodeReader g = root.required("geometry");
  c.geometry_location = location_of(g);
  if (g.defined() && g.expect_map()) {
    // Cross-checks between values (max > min ...) only when every value read cleanly, never
    // against the defaults that stand in for a bad or missing value.
    const std::size_t problems_before = sink_->diagnostics().size();
    auto read_cleanly = [&] { return sink_->diagnostics().size() == problems_before; };
    const std::string type =
        g.word("type", {"box", "plate", "curved_beam", "cylinder", "sphere_cap", "annulus", "square_tube", "mesh"}, std::nullopt);
    auto& s = c.geometry;
    const Real inf = INFINITY;
    if (type == "box") {
      s.type = GeometryType::box;
      s.min = g.vec3("min", std::nullopt);
      s.max = g.vec3("max", std::nullopt);
      if (read_cleanly() && (s.max.array() <= s.min.array()).any()) g.child("max").error("max > min in every component",
          fmt::format("[{}, {}, {}]", s.max.x(), s.max.y(), s.max.z()));
    } else if (type == "plate") {
      s.type = GeometryType::plate;
      auto lo = g.required("min").as_reals(2), hi = g.required("max").as_reals(2);
      s.thickness = g.real("thickness", std::nullopt, 0.0, inf, true);
      if (lo && hi) {
        s.min = Vec3((*lo)[0], (*lo)[1], -0.5 * s.thickness);
        s.max = Vec3((*hi)[0], (*hi)[1], 0.5 * s.thickness);
        if (read_cleanly() && ((*hi)[0] <= (*lo)[0] || (*hi)[1] <= (*lo)[1])) g.child("max").error("max > min in x and y");
      }
    } else if (type == "curved_beam") {
      s.type = GeometryType::curved_beam;
      s.inner_radius = g.real("inner_radius", std::nullopt, 0.0, inf, true);
      s.outer_radius = g.real("outer_radius", std::nullopt, 0.0, inf, true);
      // a full ring is an annulus: the generator needs a sector below 360 degrees
      s.angle_deg = g.real("angle", std::nullopt, 0.0, 360.0, true, true);
      auto z = g.required("z").as_reals(2);
      if (z) {
        s.z_range = {(*z)[0], (*z)[1]};
        if ((*z)[1] <= (*z)[0]) g.child("z").error("[z0, z1] with z1 > z0");
      }
      if (read_cleanly() && s.outer_radius <= s.inner_radius) g.child("outer_radius").error("outer_radius > inner_radius", fmt::format("{}", s.outer_radius));
    } else if (type == "cylinder") {
      s.type = GeometryType::cylinder;
      s.radius = g.real("radius", std::nullopt, 0.0, inf, true);
      s.length = g.real("length", std::nullopt, 0.0, inf, true);
      const std::string axis = g.word("axis", {"x", "y", "z"}, "z");
      s.axis = axis == "x" ? 0 : axis == "y" ? 1 : 2;
      s.angle_deg = g.real("angle", 360.0, 0.0, 360.0, true);
      s.thickness = g.real("thickness", 0.0, 0.0);
      if (read_cleanly() && s.thickness >= 2.0 * s.radius && s.radius > 0) g.child("thickness").error("thickness < 2 * radius", fmt::format("{}", s.thickness));
    } else if (type == "sphere_cap") {
      s.type = GeometryType::sphere_cap;
      s.radius = g.real("radius", std::nullopt, 0.0, inf, true);
      s.thickness = g.real("thickness", std::nullopt, 0.0, inf, true);
      s.polar_hole_deg = g.real("polar_hole", 0.0, 0.0, 90.0, false, true);
      s.sector_deg = g.real("sector", 360.0, 0.0, 360.0, true);
      if (read_cleanly() && s.thickness >= s.radius && s.radius > 0) g.child("thickness").error("thickness < radius", fmt::format("{}", s.thickness));
    } else if (type == "annulus") {
      s.type = GeometryType::annulus;
      s.inner_radius = g.real("inner_radius", std::nullopt, 0.0, inf, true);
      s.outer_radius = g.real("outer_radius", std::nullopt, 0.0, inf, true);
      s.slit = g.boolean("slit", false);
      s.thickness = g.real("thickness", std::nullopt, 0.0, inf, true);
      s.z_range = {0.0, s.thickness};
      if (read_cleanly() && s.outer_radius <= s.inner_radius) g.child("outer_radius").error("outer_radius > inner_radius", fmt::format("{}", s.outer_radius));
    } else if (type == "square_tube") {
      s.type = GeometryType::square_tube;
      s.width = g.real("width", std::nullopt, 0.0, inf, true);
      s.length = g.real("length", std::nullopt, 0.0, inf, true);
      s.corner_radius = g.real("corner_radius", 0.0, 0.0);
      s.thickness = g.real("thickness", std::nullopt, 0.0, inf, true);
      if (read_cleanly() && s.corner_radius >= 0.5 * s.width && s.width > 0) g.child("corner_radius").error("corner_radius < width / 2", fmt::format("{}", s.corner_radius));
    } else if (type == "mesh") {
      s.type = GeometryType::mesh;
      s.file = g.file_path("file", "an existing Gmsh .msh file");
      // shells: the shell's thickness (required by the shell methods); 2D methods: out of plane (default 1)
      if (g.has("thickness")) s.thickness = g.real("thickness", std::nullopt, 0.0, inf, true);
    }
    g.reject_unknown_keys();
    geometry_clean = read_cleanly() && !type.empty();
  }

  // discretization
  NodeReader d = root.child("discretization");
  c.discretization_location = location_of(d);
  if (!d.defined()) c.discretization_location = location_of(root);
  if (d.defined() && d.expect_map() && !keys) {
    // No valid method: its discretization keys cannot be judged (no follow-on errors).
    for (const auto& key : d.keys()) (void)d.child(key);
  } else if (d.defined() && d.is_map()) {
    auto allowed = [&](const std::string& key) {
      return keys && std::find(keys->discretization_keys.begin(), keys->discretization_keys.end(), key) != keys->discretization_keys.end();
    };
    auto& disc = c.discretization;
    if (allowed("nodes") && d.has("nodes")) {
      NodeReader n = d.child("nodes");
      if (n.is_map() && n.has("coordinates")) {
        // inline node list (what `lamina convert` writes for an OMLL deck's irregular nodes)
        NodeReader list = n.child("coordinates");
        if (list.expect_sequence()) {
          if (list.node().size() == 0) list.error("at least one node [x, y, z]");
          else if (static_cast<long long>(list.node().size()) > kMaxDiscretizationCount)
            list.error(fmt::format("at most {} nodes", kMaxDiscretizationCount), fmt::format("{}", list.node().size()));
          else {
            std::vector<Vec3> points;
            bool ok = true;
            for (const auto& e : list.elements()) {
              if (auto p = e.as_reals(3)) points.emplace_back((*p)[0], (*p)[1], (*p)[2]);
              else ok = false;
            }
            if (ok) disc.node_coordinates = points;
          }
        }
        n.reject_unknown_keys();
      } else if (n.is_map()) {
        disc.nodes_file = n.file_path("file", "an existing CSV file of x,y,z");
        n.reject_unknown_keys();
      } else if (auto counts = n.as_integers(3)) {
        std::array<int, 3> v{};
        bool in_range = true;
        for (int i = 0; i < 3; ++i) {
          if ((*counts)[i] < 1 || (*counts)[i] > 100000) {
            n.error("node counts in [1, 100000]", fmt::format("{}", (*counts)[i]));
            in_range = false;
          }
          v[i] = static_cast<int>(std::clamp<long long>((*counts)[i], 1, 100000));
        }
        // each count <= 1e5, so the product (<= 1e15) fits a long long
        const long long total = static_cast<long long>(v[0]) * v[1] * v[2];
        if (in_range && total > kMaxDiscretizationCount)
          n.error(fmt::format("at most {} nodes in total (nx * ny * nz)", kMaxDiscretizationCount),
                  fmt::format("{} x {} x {} = {} nodes", v[0], v[1], v[2], total));
        disc.nodes = v;
      }
    }
    if (allowed("jitter") && d.has("jitter")) {
      NodeReader j = d.child("jitter");
      if (j.expect_map()) {
        Jitter jitter;
        jitter.amount = j.real("amount", std::nullopt, 0.0, 0.5, false, true);
        jitter.seed = static_cast<unsigned>(j.integer("seed", 1, 0, 4294967295LL));
        disc.jitter = jitter;
        j.reject_unknown_keys();
      }
    }
    if (allowed("spacing") && d.has("spacing")) {
      const std::size_t problems_before = sink_->diagnostics().size();
      Vec3 spacing = d.vec3("spacing", std::nullopt);
      if (sink_->diagnostics().size() == problems_before) {
        if ((spacing.array() <= 0).any()) {
          d.child("spacing").error("positive spacings");
        } else if (c.geometry.type != GeometryType::mesh && geometry_clean) {
          // lattice cells in the body: about volume / (dx dy dz)
          Real volume = 0.0;
          try {
            volume = geometry::body_volume(c.geometry);
          } catch (const std::exception&) {
            volume = 0.0;
          }
          const Real cells = volume / (spacing.x() * spacing.y() * spacing.z());
          if (std::isfinite(volume) && cells > static_cast<Real>(kMaxDiscretizationCount))
            d.child("spacing").error(fmt::format("spacings giving at most {} lattice nodes in the body", kMaxDiscretizationCount),
                                     fmt::format("about {:.3g} nodes", cells));
        }
      }
      disc.spacing = spacing;
    }
    if (allowed("elements") && d.has("elements")) {
      if (c.geometry.type == GeometryType::mesh) {  // the file's elements are used: counts would be ignored
        d.child("elements").error("no element counts with geometry.type: mesh (the mesh file's elements are used; "
                                  "refine the mesh file instead)");
      } else if (auto e = d.child("elements").as_integers(2)) {
        if ((*e)[0] < 1 || (*e)[1] < 1)
          d.child("elements").error("element counts >= 1", fmt::format("[{}, {}]", (*e)[0], (*e)[1]));
        else if ((*e)[0] > kMaxDiscretizationCount / (*e)[1])
          d.child("elements").error(fmt::format("at most {} elements in total", kMaxDiscretizationCount),
                                    fmt::format("{} x {}", (*e)[0], (*e)[1]));
        disc.elements = std::array<int, 2>{static_cast<int>(std::max(1LL, (*e)[0])), static_cast<int>(std::max(1LL, (*e)[1]))};
      }
    }
    for (const auto& key : keys->own_discretization_keys) (void)d.child(key);  // read by the method
    if (allowed("particles") && d.has("particles")) {
      NodeReader p = d.child("particles");
      if (p.is_map()) {
        disc.particles_file = p.file_path("file", "an existing CSV file of x,y,z");
        p.reject_unknown_keys();
      } else if (auto counts = p.as_integers(2)) {
        if ((*counts)[0] < 2 || (*counts)[1] < 2)
          p.error("particle counts >= 2", fmt::format("[{}, {}]", (*counts)[0], (*counts)[1]));
        else if ((*counts)[0] > kMaxDiscretizationCount / (*counts)[1])
          p.error(fmt::format("at most {} particles in total", kMaxDiscretizationCount),
                  fmt::format("{} x {}", (*counts)[0], (*counts)[1]));
        disc.particles = std::array<int, 2>{static_cast<int>((*counts)[0]), static_cast<int>((*counts)[1])};
      }
    }
    d.reject_unknown_keys();
  }

  // boundary conditions
  NodeReader b = root.child("boundary");
  if (b.defined() && b.expect_sequence()) {
    for (const auto& e : b.elements()) {
      if (!e.expect_map()) continue;
      model::Constraint bc;
      bc.location = location_of(e);
      if (NodeReader select = e.required("select"); select.defined())
        if (auto s = read_selection(select)) bc.select = *s;
      bool any = false;
      if (e.has("fix")) {
        any = true;
        NodeReader fix = e.child("fix");
        const std::vector<std::string> names{"x", "y", "z", "rx", "ry", "rz"};
        std::vector<NodeReader> items;
        if (fix.is_scalar()) items.push_back(fix);
        else if (fix.is_sequence() && fix.node().size() > 0) items = fix.elements();
        else fix.error("a list of components among x, y, z, rx, ry, rz");
        for (const auto& item : items) {
          if (item.is_scalar() && item.node().Scalar() == "all") {
            bc.fixed.fill(true);
            continue;
          }
          if (auto w = item.as_word({"x", "y", "z", "rx", "ry", "rz", "all"}))
            bc.fixed[std::find(names.begin(), names.end(), *w) - names.begin()] = true;
        }
      }
      if (e.has("symmetry")) {
        any = true;
        if (auto w = e.child("symmetry").as_word({"x", "y", "z"})) bc.fixed[*w == "x" ? 0 : *w == "y" ? 1 : 2] = true;
      }
      if (e.has("displacement")) any = true, bc.displacement = read_component_map(e.child("displacement"));
      if (e.has("velocity")) any = true, bc.velocity = read_component_map(e.child("velocity"));
      if (!any) e.error("one of fix, symmetry, displacement, velocity", "none");
      bc.ramp = read_ramp(e);
      e.reject_unknown_keys();
      c.boundary.push_back(bc);
    }
  }

  // loads
  NodeReader l = root.child("loads");
  if (l.defined() && l.expect_sequence()) {
    const std::vector<std::pair<std::string, model::Load::Kind>> kinds{
        {"force", model::Load::Kind::force}, {"traction", model::Load::Kind::traction}, {"pressure", model::Load::Kind::pressure},
        {"body_force", model::Load::Kind::body_force}, {"mass", model::Load::Kind::mass}, {"initial_velocity", model::Load::Kind::initial_velocity}};
    for (const auto& e : l.elements()) {
      if (!e.expect_map()) continue;
      model::Load load;
      load.location = location_of(e);
      if (NodeReader select = e.required("select"); select.defined())
        if (auto s = read_selection(select)) load.select = *s;
      int count = 0;
      for (const auto& [name, kind] : kinds) {
        if (!e.has(name)) continue;
        ++count;
        load.kind = kind;
        if (kind == model::Load::Kind::pressure || kind == model::Load::Kind::mass) {
          load.scalar = read_scalar_field(e.child(name));
          if (kind == model::Load::Kind::mass && load.scalar.is_constant() && !(load.scalar.constant > 0))
            e.child(name).error("a positive mass", fmt::format("{}", load.scalar.constant));
        } else {
          load.vector = read_vector_field(e.child(name));
        }
      }
      if (count != 1) e.error("exactly one of force, traction, pressure, body_force, mass, initial_velocity",
                              count == 0 ? "none" : fmt::format("{} of them", count));
      load.ramp = read_ramp(e);
      e.reject_unknown_keys();
      c.loads.push_back(load);
    }
  }

  // probes
  NodeReader p = root.child("probes");
  if (p.defined() && p.expect_sequence()) {
    std::set<std::string> names{"step", "time", "load_factor"};
    static const std::regex valid_name("[A-Za-z_][A-Za-z0-9_]*");
    for (const auto& e : p.elements()) {
      if (!e.expect_map()) continue;
      ProbeEntry probe;
      probe.location = location_of(e);
      probe.name = e.string("name", std::nullopt);
      if (!probe.name.empty()) {
        if (!std::regex_match(probe.name, valid_name))
          e.child("name").error("a name of letters, digits and _ (it becomes a CSV column)", "'" + probe.name + "'");
        else if (!names.insert(probe.name).second)
          e.child("name").error("a unique probe name (not step, time, load_factor)", "'" + probe.name + "' again");
      }
      probe.field = e.word("field", kProbeFields, std::nullopt);
      NodeReader component = e.child("component");
      if (probe.field == "energy") probe.component = e.word("component", kEnergyComponents, "total");
      else if (probe.field == "eigenvalue" || probe.field == "critical_load")
        probe.component = std::to_string(e.integer("component", 1, 1, 1000));
      else if (probe.field == "approximation") probe.component = e.word("component", {"value", "x", "y", "z", "xx", "yy", "zz", "xy", "yz", "zx"}, "value");
      else if (probe.field == "plastic_strain") probe.component = e.word("component", {"value", "max"}, "value");
      else probe.component = e.word("component", kComponents, std::nullopt);
      if (e.has("at")) {
        Vec3 at = e.vec3("at", Vec3::Zero());
        probe.at = at;
      }
      if (e.has("set")) probe.set = e.string("set", "");
      if (e.has("select")) probe.select = read_selection(e.child("select"));
      const bool needs_point = probe.field != "reaction_force" && probe.field != "energy" && probe.field != "eigenvalue" &&
                               probe.field != "critical_load" && !(probe.field == "plastic_strain" && probe.component == "max");
      if ((probe.field == "reaction_force" || probe.field == "critical_load") && !e.has("select") && !e.has("set"))
        e.error(fmt::format("a select: (or set:) for a {} probe", probe.field), "none");
      if (needs_point && !e.has("at") && !probe.field.empty())
        e.error(fmt::format("an at: [x, y, z] point for {} {} probe",
                            std::string("aeiou").find(probe.field[0]) != std::string::npos ? "an" : "a", probe.field),
                "none");
      e.reject_unknown_keys();
      c.probes.push_back(probe);
    }
  }

  // output
  NodeReader o = root.child("output");
  if (o.defined() && o.expect_map()) {
    c.output.vtu = o.boolean("vtu", true);
    c.output.every = static_cast<int>(o.integer("every", 1, 1, 1000000));
    NodeReader checkpoint = o.child("checkpoint");
    if (checkpoint.defined() && checkpoint.expect_map()) {
      if (checkpoint.has("every")) c.output.checkpoint_every = static_cast<int>(checkpoint.integer("every", 1, 1, 1000000000));
      if (checkpoint.has("seconds")) c.output.checkpoint_seconds = checkpoint.real("seconds", 60.0, 0.0, INFINITY, true);
      if (!checkpoint.has("every") && !checkpoint.has("seconds"))
        checkpoint.error("every: N (output points) or seconds: S (wall-clock)", "neither");
      checkpoint.reject_unknown_keys();
    }
    o.reject_unknown_keys();
  }

  // solver (PRODUCT.md section 5): the linear solves of efg and mpfem
  NodeReader sv = root.child("solver");
  if (sv.defined() && sv.expect_map()) {
    const std::string type = sv.word("type", {"cholmod", "mumps", "cg"}, std::string("cholmod"));
    c.solver.type = type == "mumps" ? LinearSolverChoice::Type::mumps
                    : type == "cg"  ? LinearSolverChoice::Type::cg
                                    : LinearSolverChoice::Type::cholmod;
    if (!sv.has("type")) c.solver.type = LinearSolverChoice::Type::automatic;
    c.solver.preconditioner = sv.word("preconditioner", {"gamg", "hypre"}, std::string("gamg")) == "hypre"
                                  ? LinearSolverChoice::Preconditioner::hypre
                                  : LinearSolverChoice::Preconditioner::gamg;
    c.solver.relative_tolerance = sv.real("tolerance", 1e-10, 0.0, 1.0, true);
    c.solver.max_iterations = static_cast<int>(sv.integer("max_iterations", 10000, 1, 100000000));
    sv.reject_unknown_keys();
  }

  // the method's other top-level sections (mpm: shell, pd: imperfection) are read by its own reader
  if (keys)
    for (const auto& other : keys->other_sections) (void)root.child(other);
  if (keys) c.method_section = root.child(c.method).node();
  return c;
}

}  // namespace lamina::io
