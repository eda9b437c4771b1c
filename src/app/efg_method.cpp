#include "app/efg_method.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "app/mls_options_reader.hpp"
#include "core/error.hpp"
#include "efg/efg_analysis.hpp"

namespace lamina::app {

namespace {

struct EfgMethodOptions : MethodOptions {
  efg::EfgOptions options;
};

/// Three counts per direction, each in [lower, 100000] (`what`: "cell", "node"); none after an error.
std::optional<std::array<int, 3>> read_counts(const io::NodeReader& node, int lower, const std::string& what) {
  const auto v = node.as_integers(3);
  if (!v) return std::nullopt;
  std::array<int, 3> counts{};
  for (int d = 0; d < 3; ++d) {
    const auto value = (*v)[static_cast<std::size_t>(d)];
    if (value < lower || value > 100000) {
      node.error(fmt::format("three {} counts between {} and 100000", what, lower));
      return std::nullopt;
    }
    counts[static_cast<std::size_t>(d)] = static_cast<int>(value);
  }
  return counts;
}

std::unique_ptr<MethodOptions> read_efg(const io::Case&, const io::NodeReader& section) {
  auto result = std::make_unique<EfgMethodOptions>();
  result->options = read_efg_options(section);
  return result;
}

std::unique_ptr<Analysis> create_efg(const io::Case& c, const Model& model, const MethodOptions& options) {
  const auto& o = static_cast<const EfgMethodOptions&>(options);
  return std::make_unique<efg::EfgAnalysis>(make_efg_problem(c, model, o.options), model.probes);
}

}  // namespace

efg::EfgOptions read_efg_options(const io::NodeReader& section) {
  efg::EfgOptions o;
  if (!section.defined()) {
    o.mls.dimension = 3;
    return o;  // all defaults
  }
  if (!section.expect_map()) return o;
  const std::string formulation =
      section.word("formulation", {"galerkin", "collocation", "weighted_least_squares"}, "galerkin");
  o.formulation = formulation == "collocation"              ? efg::Formulation::collocation
                  : formulation == "weighted_least_squares" ? efg::Formulation::weighted_least_squares
                                                            : efg::Formulation::galerkin;
  io::NodeReader wlsm = section.child("weighted_least_squares");
  if (wlsm.defined() && wlsm.expect_map()) {
    if (o.formulation != efg::Formulation::weighted_least_squares)
      wlsm.error("no weighted_least_squares section unless formulation: weighted_least_squares", "the section");
    o.least_squares.traction_weight = wlsm.real("traction_weight", 1e5, 0.0, 1e30, true);
    if (wlsm.has("displacement_weight"))
      o.least_squares.displacement_weight = wlsm.real("displacement_weight", std::nullopt, 0.0, 1e40, true);
    const std::string points = wlsm.word("points", {"nodes", "nodes_and_cell_centres"}, "nodes");
    o.least_squares.cell_centre_points = points == "nodes_and_cell_centres";
    wlsm.reject_unknown_keys();
  }
  o.mls = read_mls_options(section, 3);

  io::NodeReader integration = section.child("integration");
  if (integration.defined() && integration.expect_map()) {
    io::NodeReader cells = integration.child("cells");
    if (cells.defined()) o.cells = read_counts(cells, 1, "cell");
    io::NodeReader gauss = integration.child("gauss");
    if (gauss.defined()) {
      if (gauss.is_sequence()) {
        if (auto v = gauss.as_integers(3)) {
          bool ok = true;
          for (int d = 0; d < 3; ++d) {
            if ((*v)[static_cast<std::size_t>(d)] < 1 || (*v)[static_cast<std::size_t>(d)] > 20) ok = false;
            o.gauss[static_cast<std::size_t>(d)] = static_cast<int>((*v)[static_cast<std::size_t>(d)]);
          }
          if (!ok) gauss.error("Gauss orders between 1 and 20");
        }
      } else {
        const int g = static_cast<int>(integration.integer("gauss", 2, 1, 20));
        o.gauss = {g, g, g};
      }
    }
    const std::string volumetric = integration.word("volumetric", {"full", "reduced", "projected"}, "full");
    o.reduced_volumetric = volumetric == "reduced";
    o.projected_volumetric = volumetric == "projected";
    if (integration.has("pressure_kappa")) {
      if (!o.projected_volumetric) integration.child("pressure_kappa").error("no pressure_kappa unless volumetric: projected", "pressure_kappa with volumetric: " + volumetric);
      else o.pressure_kappa = integration.real("pressure_kappa", 1.1, 1.0, 10.0, true);
    }
    io::NodeReader pressure_nodes = integration.child("pressure_nodes");
    if (pressure_nodes.defined()) {
      if (!o.projected_volumetric) pressure_nodes.error("no pressure_nodes unless volumetric: projected", "pressure_nodes with volumetric: " + volumetric);
      else o.pressure_nodes = read_counts(pressure_nodes, 2, "node");
    }
    for (int d = 0; d < 3; ++d) o.volumetric_gauss[static_cast<std::size_t>(d)] = std::max(o.gauss[static_cast<std::size_t>(d)] - 1, 1);
    if (integration.has("volumetric_gauss")) {
      const int g = static_cast<int>(integration.integer("volumetric_gauss", 1, 1, 20));
      o.volumetric_gauss = {g, g, g};
    }
    const std::string correction = integration.word("correction", {"auto", "none", "vci", "smoothed"}, "auto");
    o.correction = correction == "vci"        ? efg::IntegrationCorrection::vci
                   : correction == "smoothed" ? efg::IntegrationCorrection::smoothed
                   : correction == "none"     ? efg::IntegrationCorrection::none
                                              : efg::IntegrationCorrection::automatic;
    const int fewest_points = *std::min_element(o.gauss.begin(), o.gauss.end());
    if (o.correction == efg::IntegrationCorrection::smoothed && fewest_points < 2)
      integration.child("correction").error("gauss >= 2 with correction: smoothed (the linear fields of a cell need 2 points per direction)",
                                            "gauss " + std::to_string(fewest_points));
    integration.reject_unknown_keys();
  }
  const std::string bc = section.word("essential_bc", {"auto", "penalty", "penalty_nodes", "nitsche", "lagrange"}, "auto");
  o.essential = bc == "nitsche"         ? efg::EssentialMethod::nitsche
                : bc == "lagrange"      ? efg::EssentialMethod::lagrange
                : bc == "penalty_nodes" ? efg::EssentialMethod::penalty_nodes
                : bc == "penalty"       ? efg::EssentialMethod::penalty
                                        : efg::EssentialMethod::automatic;
  if (section.has("penalty")) o.penalty = section.real("penalty", std::nullopt, 0.0, INFINITY, true);
  o.penalty_factor = section.real("penalty_factor", 1e5, 0.0, 1e16, true);
  // a penalty value given without essential_bc asks for the penalty (auto would choose Nitsche and ignore it)
  if (o.essential == efg::EssentialMethod::automatic && (section.has("penalty") || section.has("penalty_factor")))
    o.essential = efg::EssentialMethod::penalty;
  io::NodeReader nitsche = section.child("nitsche");
  if (nitsche.defined() && nitsche.expect_map()) {
    o.nitsche_factor = nitsche.real("factor", 100.0, 0.0, 1e12, true);
    nitsche.reject_unknown_keys();
  }
  io::NodeReader exact = section.child("exact_displacement");
  if (exact.defined()) {
    if (exact.is_sequence() && exact.node().size() == 3) {
      std::array<std::string, 3> e;
      const auto items = exact.elements();
      for (std::size_t i = 0; i < 3; ++i) {
        geometry::ScalarField f = io::read_scalar_field(items[i]);
        e[i] = f.is_constant() ? fmt::format("{:.17g}", f.constant) : f.expression;
      }
      o.exact_displacement = e;
    } else {
      exact.error("three expressions [ux, uy, uz] of x, y, z");
    }
  }
  section.reject_unknown_keys();
  return o;
}

efg::EfgProblem make_efg_problem(const io::Case& c, const Model& model, const efg::EfgOptions& options) {
  efg::EfgProblem p;
  p.geometry = c.geometry;
  p.cloud = model.cloud;
  p.options = options;
  p.options.solver = c.solver;
  std::vector<Diagnostic> problems;
  auto problem_at = [&](const io::SourceLocation& where, const std::string& key, const std::string& expected,
                        const std::string& found) {
    problems.push_back(Diagnostic{where.file, where.line, where.column, where.key_path + key, expected, found});
  };
  for (std::size_t i = 0; i < c.materials.size(); ++i) {
    const auto& m = c.materials[i];
    io::SourceLocation where{c.file, 0, 0, fmt::format("materials.{}", i)};
    if (m.spec.model != material::MaterialModel::linear_elastic) {
      problem_at(where, ".model", "linear_elastic (efg is a linear analysis)", "another model");
      continue;
    }
    efg::EfgMaterial em;
    em.name = m.spec.name;
    em.elastic = material::LinearElastic{m.spec.E, m.spec.nu};
    if (m.select) {
      em.region = *m.select;
      em.region->nodes = model.material_nodes[i];
      em.region->label = fmt::format("materials.{}.select", i);
    }
    p.materials.push_back(em);
  }
  for (const auto& b : model.constraints) {
    if (b.velocity[0] || b.velocity[1] || b.velocity[2]) {
      problem_at(b.location, ".velocity", "fix, symmetry or displacement (velocity is for explicit methods)", "velocity");
      continue;
    }
    if (!b.constrains(0) && !b.constrains(1) && !b.constrains(2)) {
      problem_at(b.location, ".fix", "translations x, y or z (a 3D continuum has no rotational degrees of freedom)",
                 "only rotations");
      continue;
    }
    p.constraints.push_back(b);
  }
  for (const auto& l : model.loads) {
    using Kind = model::Load::Kind;
    if (l.kind != Kind::force && l.kind != Kind::traction && l.kind != Kind::pressure && l.kind != Kind::body_force) {
      problem_at(l.location, "", "force, traction, pressure or body_force (efg is a static analysis)",
                 "mass or initial_velocity");
      continue;
    }
    p.loads.push_back(l);
  }
  if (!problems.empty()) throw InputError(problems);
  return p;
}

MethodEntry efg_method_entry() {
  return MethodEntry{io::MethodKeys{"efg", {"nodes", "jitter"}, true},
                     "element-free Galerkin / collocation / weighted least squares, 3D linear elastostatics (seed 004)", read_efg, create_efg,
                     {}, /*distributed=*/true};
}

}  // namespace lamina::app
