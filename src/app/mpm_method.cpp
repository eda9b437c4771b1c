#include "app/mpm_method.hpp"

#include <fmt/format.h>

#include <cctype>

#include "core/error.hpp"
#include "mpm/mpm_analysis.hpp"

namespace lamina::app {

namespace {

struct MpmMethodOptions : MethodOptions {
  mpm::MpmOptions options;
  shell::ShellSection section;
  std::vector<model::Load> moments;  // mpm.moments: kind moment / edge_moment
  ModelRequest model_request() const override { return ModelRequest{true, false}; }  // the shell mesh
};

/// The case's ramp with its table's first column divided by `scale` (end_time of a dynamic run: the
/// analysis evaluates ramps at s = t / end_time).
Ramp scaled_ramp(const Ramp& r, Real scale) {
  Ramp out = r;
  for (auto& row : out.table) row[0] /= scale;
  return out;
}

void read_shell_section(const io::Case& c, const io::NodeReader& mpm_section, shell::ShellSection& s) {
  io::NodeReader section(c.resolved["shell"], "shell", &mpm_section.sink());
  if (!section.defined() || !section.expect_map()) return;
  s.thickness_points = static_cast<int>(section.integer("thickness_points", s.thickness_points, 1, 7));
  // hourglass: `physical` (default) or a coefficient r (the seed's springs, with the per-mode keys)
  const io::NodeReader hourglass = section.child("hourglass");
  const std::string text = hourglass.defined() && hourglass.is_scalar() ? hourglass.node().as<std::string>() : "";
  if (!text.empty() && std::isalpha(static_cast<unsigned char>(text[0]))) {  // a word, not a number
    if (hourglass.as_word({"physical"})) s.hourglass_model = shell::HourglassModel::physical;
  } else if (hourglass.defined()) {
    s.hourglass_model = shell::HourglassModel::coefficients;
    s.hourglass = section.real("hourglass", 0.1, 0.0, 1.0);
  }
  const bool coefficients = s.hourglass_model == shell::HourglassModel::coefficients;
  for (const char* key : {"hourglass_bending", "hourglass_membrane", "hourglass_transverse", "transverse_hourglass"})
    if (section.has(key) && !coefficients)
      section.child(key).error(fmt::format("no {} with the physical hourglass control (the default); it belongs to the "
                                           "coefficient springs: give shell.hourglass a coefficient (0.1 is the seed's)",
                                           key));
  if (section.has("hourglass_bending")) s.hourglass_bending = section.real("hourglass_bending", std::nullopt, 0.0, 2.0);
  if (section.has("hourglass_membrane")) s.hourglass_membrane = section.real("hourglass_membrane", std::nullopt, 0.0, 2.0);
  if (section.has("hourglass_transverse"))
    s.hourglass_transverse = section.real("hourglass_transverse", std::nullopt, 0.0, 2.0);
  s.drilling = section.real("drilling", s.drilling, 0.0, 1.0);
  s.shear_factor = section.real("shear_factor", s.shear_factor, 0.0, 1.0, true);
  s.warping_correction = section.boolean("warping_correction", s.warping_correction);
  s.kirchhoff_transverse_hourglass = section.word("transverse_hourglass", {"standard", "kirchhoff"}, "standard") == "kirchhoff";
  section.reject_unknown_keys();
}

std::unique_ptr<MethodOptions> read_mpm(const io::Case& c, const io::NodeReader& section) {
  auto result = std::make_unique<MpmMethodOptions>();
  mpm::MpmOptions& o = result->options;
  read_shell_section(c, section, result->section);
  io::NodeReader discretization(c.resolved["discretization"], "discretization", &section.sink());
  if (discretization.defined() && discretization.is_map() && discretization.has("grid")) {
    io::NodeReader grid = discretization.child("grid");
    if (grid.expect_map()) {
      o.grid_cell = grid.real("cell", std::nullopt, 0.0, INFINITY, true);
      grid.reject_unknown_keys();
    }
  }
  bool kinetic_default = true;
  if (section.defined() && section.expect_map()) {
    const std::string analysis = section.word("analysis", {"quasi_static", "dynamic"}, "quasi_static");
    o.analysis = analysis == "dynamic" ? mpm::MpmOptions::Kind::dynamic : mpm::MpmOptions::Kind::quasi_static;
    kinetic_default = o.analysis == mpm::MpmOptions::Kind::quasi_static;
    o.load_levels = static_cast<int>(section.integer("load_levels", 10, 1, 100000));
    o.tolerance = section.real("tolerance", 1e-4, 0.0, 1.0, true, true);
    o.max_steps_per_level = section.integer("max_steps_per_level", 2000000, 1, 1000000000000LL);
    o.level_ramp_steps = section.integer("level_ramp_steps", 0, 0, 1000000000LL);
    o.end_time = section.real("end_time", 1.0, 0.0, INFINITY, true);
    o.output_points = static_cast<int>(section.integer("output_points", 10, 1, 1000000));
    o.max_steps = section.integer("max_steps", 50000000, 1, 1000000000000LL);
    o.flip = section.real("flip", 0.0, 0.0, 1.0);
    io::NodeReader ts = section.child("time_step");
    if (ts.defined() && ts.expect_map()) {
      o.alpha = ts.real("alpha", 0.5, 0.0, 1.0, true, true);
      o.shell_safety = ts.real("shell_safety", 0.9, 0.0, 1.0, true);
      if (ts.has("fixed")) o.fixed_time_step = ts.real("fixed", std::nullopt, 0.0, INFINITY, true);
      ts.reject_unknown_keys();
    }
    // quasi-static: the physical masses (default) or fictitious stiffness-proportional ones; dynamic: physical
    const bool quasi_static = o.analysis == mpm::MpmOptions::Kind::quasi_static;
    const bool stiffness_mass = section.word("mass_scaling", {"physical", "stiffness"}, "physical") == "stiffness";
    {
      const bool newton = section.word("solver", {"explicit", "newton"}, quasi_static && !stiffness_mass ? "newton" : "explicit") == "newton";
      if (newton && !quasi_static) section.child("solver").error("newton solves the quasi_static levels; a dynamic analysis is explicit");
      if (newton && stiffness_mass) section.child("solver").error("newton needs no masses: leave out mass_scaling");
      o.solver = newton ? mpm::MpmOptions::Solver::newton : mpm::MpmOptions::Solver::explicit_dynamics;
    }
    o.mass_scaling = quasi_static && stiffness_mass;
    // with mass scaling: adaptive damping by default; kinetic damping is the default with physical mass
    kinetic_default = quasi_static && !o.mass_scaling;
    o.kinetic_damping = kinetic_default;
    o.adaptive_damping = o.mass_scaling;
    io::NodeReader damping = section.child("damping");
    if (damping.defined() && damping.expect_map()) {
      o.mass_damping = damping.real("mass", 0.0, 0.0);
      o.kinetic_damping = damping.boolean("kinetic", kinetic_default);
      if (o.mass_scaling) o.adaptive_damping = damping.boolean("adaptive", !o.kinetic_damping && !(o.mass_damping > 0));
      else if (damping.has("adaptive") && damping.boolean("adaptive", false))
        damping.child("adaptive").error("adaptive damping needs the fictitious masses of mpm.mass_scaling: stiffness (quasi_static)");
      damping.reject_unknown_keys();
    }
    io::NodeReader moments = section.child("moments");
    if (moments.defined() && moments.expect_sequence()) {
      for (const auto& m : moments.elements()) {
        if (!m.expect_map()) continue;
        model::Load entry;
        entry.location = io::location_of(m);
        if (auto s = io::read_selection(m.required("select"))) entry.select = *s;
        const bool per_edge_length = m.has("edge_moment");
        entry.kind = per_edge_length ? model::Load::Kind::edge_moment : model::Load::Kind::moment;
        if (per_edge_length && m.has("moment")) m.child("edge_moment").error("either moment (total) or edge_moment (per unit length), not both");
        io::NodeReader vector = per_edge_length ? m.child("edge_moment") : m.required("moment");
        if (vector.defined()) {
          if (vector.is_sequence() && vector.node().size() == 3) {
            const auto items = vector.elements();
            for (std::size_t a = 0; a < 3; ++a) entry.vector[a] = io::read_scalar_field(items[a]);
          } else {
            vector.error("three components [mx, my, mz]");
          }
        }
        entry.ramp = io::read_ramp(m);
        m.reject_unknown_keys();
        result->moments.push_back(entry);
      }
    }
    section.reject_unknown_keys();
  }
  return result;
}

std::unique_ptr<Analysis> create_mpm(const io::Case& c, const Model& model, const MethodOptions& options) {
  const auto& mo = static_cast<const MpmMethodOptions&>(options);
  mpm::MpmProblem p;
  std::vector<Diagnostic> problems;
  auto problem_at = [&](const io::SourceLocation& where, const std::string& key, const std::string& expected,
                        const std::string& found) {
    problems.push_back(Diagnostic{where.file.empty() ? c.file : where.file, where.line, where.column, where.key_path + key, expected, found});
  };
  if (!model.shell) throw InputError(Diagnostic{c.file, c.discretization_location.line, 0, "discretization.elements",
                                                "shell elements [n1, n2] of the generated mid-surface", "nothing"});
  p.mesh = *model.shell;
  p.options = mo.options;
  p.section = mo.section;
  const Real ramp_scale = p.options.analysis == mpm::MpmOptions::Kind::quasi_static ? 1.0 : p.options.end_time;

  if (c.materials.size() != 1) {
    problem_at(io::SourceLocation{c.file, 0, 0, "materials"}, "", "exactly one material (mpm shells are homogeneous in this build)",
               fmt::format("{} materials", c.materials.size()));
  } else {
    const auto& m = c.materials[0].spec;
    io::SourceLocation where{c.file, 0, 0, "materials.0"};
    if (!m.density || !(*m.density > 0)) problem_at(where, ".density", "a positive density (mpm is an explicit dynamic method)", "none");
    p.material = m;
  }
  for (const auto& b : model.constraints) {
    model::Constraint k = b;
    k.ramp = scaled_ramp(b.ramp, ramp_scale);
    bool displacement = false;
    for (std::size_t a = 0; a < 3; ++a) {
      if (!b.displacement[a]) continue;
      // a zero prescribed displacement is a fixed component; other values are not supported yet
      const auto& d = *b.displacement[a];
      if (d.is_constant() && d.constant == 0.0) k.fixed[a] = true;
      else displacement = true;
      k.displacement[a].reset();
    }
    if (displacement)
      problem_at(b.location, ".displacement", "fix or velocity (non-zero prescribed displacements are not in mpm yet)", "displacement");
    p.constraints.push_back(k);
  }
  for (const auto& l : model.loads) {
    if (l.kind == model::Load::Kind::mass && (!l.scalar.is_constant() || !(l.scalar.constant > 0)))
      problem_at(l.location, ".mass", "a positive constant mass", "an expression or <= 0");
    model::Load load = l;
    load.ramp = scaled_ramp(l.ramp, ramp_scale);
    p.loads.push_back(load);
  }
  for (std::size_t i = 0; i < mo.moments.size(); ++i) {
    model::Load load = mo.moments[i];
    try {
      load.select.nodes = resolve_or_throw(load.select, model.cloud);
    } catch (const InputError& e) {
      problems.insert(problems.end(), e.diagnostics().begin(), e.diagnostics().end());
      continue;
    }
    load.select.label = fmt::format("mpm.moments.{}", i);
    p.loads.push_back(load);
  }
  if (!problems.empty()) throw InputError(problems);
  try {
    return std::make_unique<mpm::MpmAnalysis>(std::move(p), model.probes);
  } catch (const InputError& e) {
    throw locate(e, c);  // key paths to lines (discretization / geometry errors: their section's line)
  }
}

}  // namespace

MethodEntry mpm_method_entry() {
  return MethodEntry{io::MethodKeys{"mpm", {"elements", "grid"}, true, {"shell"}, {"grid"}},
                     "CPDI2 material point method with Belytschko-Tsay shell domains, explicit / quasi-static (seed 000)",
                     read_mpm, create_mpm, {"mpm.end_time"}, /*distributed=*/true};
}

}  // namespace lamina::app
