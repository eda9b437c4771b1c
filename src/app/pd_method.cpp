#include "app/pd_method.hpp"

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

#include "core/error.hpp"
#include "geometry/expression.hpp"
#include "pd/nodal_conditions.hpp"
#include "pd/peridynamic_analysis.hpp"

namespace lamina::app {

namespace {

struct ImperfectionOptions {
  enum class Kind { none, sine, buckling_mode, file };
  Kind kind = Kind::none;
  std::array<int, 2> half_waves{1, 1};
  int mode = 1;
  std::string file;
  Real amplitude = 0.0;
};

struct PdMethodOptions : MethodOptions {
  pd::PdAnalysisKind analysis = pd::PdAnalysisKind::quasi_static;
  pd::BodyOptions body;
  pd::AdaptiveDynamicRelaxationOptions relaxation;
  pd::ExplicitOptions explicit_options;
  pd::BucklingOptions buckling;
  ImperfectionOptions imperfection;
  bool check_zero_energy = true;
  std::optional<Real> horizon, horizon_factor;  // discretization.horizon / horizon_factor
  /// surface_correction: plate puts the layers of a plate lattice at the Gauss points of the thickness.
  ModelRequest model_request() const override {
    return ModelRequest{false, body.surface_correction == pd::SurfaceCorrection::plate};
  }
};

void read_imperfection(const io::NodeReader& r, ImperfectionOptions& o) {
  if (!r.defined() || !r.expect_map()) return;
  o.amplitude = r.real("amplitude", std::nullopt, 0.0, INFINITY);
  if (r.has("file")) {
    o.kind = ImperfectionOptions::Kind::file;
    o.file = r.file_path("file", "a readable CSV file x,y,z,ux,uy,uz");
  } else {
    const std::string shape = r.word("shape", {"sine", "buckling_mode"}, std::nullopt);
    if (shape == "sine") {
      o.kind = ImperfectionOptions::Kind::sine;
      io::NodeReader waves = r.child("half_waves");
      if (waves.defined()) {
        if (auto v = waves.as_integers(2)) {
          if ((*v)[0] < 1 || (*v)[1] < 1) waves.error("two positive half-wave counts [m, n]");
          else o.half_waves = {static_cast<int>((*v)[0]), static_cast<int>((*v)[1])};
        }
      }
    } else if (shape == "buckling_mode") {
      o.kind = ImperfectionOptions::Kind::buckling_mode;
      o.mode = static_cast<int>(r.integer("mode", 1, 1, 50));
    }
  }
  r.reject_unknown_keys();
}

std::unique_ptr<MethodOptions> read_pd(const io::Case& c, const io::NodeReader& section) {
  auto o = std::make_unique<PdMethodOptions>();
  io::NodeReader imperfection(c.resolved["imperfection"], "imperfection", &section.sink());
  read_imperfection(imperfection, o->imperfection);
  io::NodeReader discretization(c.resolved["discretization"], "discretization", &section.sink());
  if (discretization.defined() && discretization.is_map()) {
    if (discretization.has("horizon")) o->horizon = discretization.real("horizon", 1.0, 0.0, INFINITY, true);
    if (discretization.has("horizon_factor"))
      o->horizon_factor = discretization.real("horizon_factor", 3.0, 0.0, INFINITY, true);
  }
  if (!section.defined()) return o;
  if (!section.expect_map()) return o;
  const std::string analysis = section.word("analysis", {"quasi_static", "linear_static", "explicit", "buckling"}, "quasi_static");
  o->analysis = analysis == "linear_static" ? pd::PdAnalysisKind::linear_static
                : analysis == "explicit"    ? pd::PdAnalysisKind::explicit_dynamics
                : analysis == "buckling"    ? pd::PdAnalysisKind::buckling
                                            : pd::PdAnalysisKind::quasi_static;
  const std::string kinematics =
      section.word("kinematics", {"three_dimensional", "plane_stress", "plane_strain"}, "three_dimensional");
  o->body.kinematics = kinematics == "plane_stress"   ? pd::Kinematics::plane_stress
                       : kinematics == "plane_strain" ? pd::Kinematics::plane_strain
                                                      : pd::Kinematics::three_dimensional;
  o->body.influence = section.word("influence", {"one", "inverse_distance"}, "one") == "one" ? pd::Influence::one
                                                                                             : pd::Influence::inverse_distance;
  const std::string correction = section.word("surface_correction", {"energy", "none", "plate"}, "energy");
  o->body.surface_correction = correction == "energy" ? pd::SurfaceCorrection::energy
                               : correction == "plate" ? pd::SurfaceCorrection::plate
                                                       : pd::SurfaceCorrection::none;
  o->body.partial_volume = section.boolean("partial_volume", false);
  o->body.plate_model = section.word("plate_model", {"auto", "lattice"}, "auto") == "auto" ? pd::PlateModel::automatic
                                                                                          : pd::PlateModel::lattice;
  o->body.plate_stabilization = section.real("plate_stabilization", 0.25, 0.0, 100.0, true);
  o->body.plate_edge_mirror = section.word("plate_edges", {"mirror", "one_sided"}, "mirror") == "mirror";
  const std::string storage = section.word("bond_storage", {"auto", "full", "lean"}, "auto");
  o->body.bond_storage = storage == "full"   ? pd::BodyOptions::BondStorage::full
                         : storage == "lean" ? pd::BodyOptions::BondStorage::lean
                                             : pd::BodyOptions::BondStorage::automatic;
  o->check_zero_energy = section.boolean("zero_energy_check", true);
  io::NodeReader qs = section.child("quasi_static");
  if (qs.defined() && qs.expect_map()) {
    auto& r = o->relaxation;
    r.increments = static_cast<int>(qs.integer("increments", 10, 1, 1000000));
    r.tolerance = qs.real("tolerance", 1e-5, 0.0, 1.0, true, true);
    if (qs.has("absolute_tolerance")) r.absolute_tolerance = qs.real("absolute_tolerance", std::nullopt, 0.0, INFINITY, true);
    r.switch_iteration = static_cast<int>(qs.integer("switch_iteration", 2000, 0, 1000000000));
    r.max_iterations = static_cast<int>(qs.integer("max_iterations", 20000, 1, 1000000000));
    r.max_cuts = static_cast<int>(qs.integer("max_cuts", 6, 0, 30));
    r.continuations = static_cast<int>(qs.integer("continuations", 4, 0, 1000));
    r.density_factor = qs.real("density_factor", 1.0, 0.0, 1e6, true);
    r.velocity_guard = qs.real("velocity_guard", 1e-10, 0.0, 1.0);
    const std::string predictor = qs.word("predictor", {"quadratic", "secant", "previous"}, "secant");
    using Options = pd::AdaptiveDynamicRelaxationOptions;
    r.predictor = predictor == "quadratic" ? Options::Predictor::quadratic
                  : predictor == "secant"  ? Options::Predictor::secant
                                           : Options::Predictor::previous;
    r.damping_estimate = qs.word("damping_estimate", {"total", "increment"}, "increment") == "increment"
                             ? Options::DampingEstimate::increment
                             : Options::DampingEstimate::total;
    r.linear_start = qs.word("start", {"interpolated", "linear"}, "interpolated") == "linear";
    r.kinetic_fallback = qs.boolean("kinetic_fallback", true);
    r.coordinates = qs.word("coordinates", {"columns", "nodes"}, "columns") == "columns" ? Options::Coordinates::columns
                                                                                         : Options::Coordinates::nodes;
    qs.reject_unknown_keys();
  }
  io::NodeReader ex = section.child("explicit");
  if (ex.defined() && ex.expect_map()) {
    auto& e = o->explicit_options;
    e.end_time = ex.real("end_time", 1e-3, 0.0, INFINITY, true);
    e.safety_factor = ex.real("safety_factor", 0.8, 0.0, 1.0, true);
    if (ex.has("time_step")) e.time_step = ex.real("time_step", std::nullopt, 0.0, INFINITY, true);
    e.outputs = static_cast<int>(ex.integer("outputs", 20, 1, 1000000));
    e.damping = ex.real("damping", 0.0, 0.0);
    ex.reject_unknown_keys();
  }
  io::NodeReader bk = section.child("buckling");
  if (bk.defined() && bk.expect_map()) {
    o->buckling.modes = static_cast<int>(bk.integer("modes", 3, 1, 50));
    bk.reject_unknown_keys();
  }
  section.reject_unknown_keys();
  if (o->imperfection.kind == ImperfectionOptions::Kind::buckling_mode && o->imperfection.mode > 50)
    imperfection.error("mode <= 50");
  return o;
}

PointMatrix read_imperfection_file(const std::string& path, const PointMatrix& nodes) {
  std::ifstream in(path);
  std::vector<std::array<Real, 6>> rows;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty() || line[0] == '#') continue;
    for (char& ch : line)
      if (ch == ',' || ch == ';' || ch == '\t') ch = ' ';
    std::istringstream fields(line);
    std::array<Real, 6> row{};
    bool ok = true;
    for (auto& v : row) ok = ok && static_cast<bool>(fields >> v);
    if (!ok) {
      if (rows.empty()) continue;  // header
      throw InputError(Diagnostic{path, number, 1, "imperfection.file", "x, y, z, ux, uy, uz numbers", "'" + line + "'"});
    }
    rows.push_back(row);
  }
  if (rows.empty()) throw InputError(Diagnostic{path, 0, 0, "imperfection.file", "at least one row x,y,z,ux,uy,uz", "none"});
  PointMatrix shape(3, nodes.cols());
  for (Index i = 0; i < nodes.cols(); ++i) {
    Real best = INFINITY;
    for (const auto& r : rows) {
      const Real d = (Vec3(r[0], r[1], r[2]) - nodes.col(i)).squaredNorm();
      if (d < best) {
        best = d;
        shape.col(i) = Vec3(r[3], r[4], r[5]);
      }
    }
  }
  return shape;
}

pd::PeridynamicProblem make_problem(const io::Case& c, const Model& model, const PdMethodOptions& o) {
  pd::PeridynamicProblem p;
  std::vector<Diagnostic> problems;
  auto problem_at = [&](const io::SourceLocation& where, const std::string& key, const std::string& expected,
                        const std::string& found) {
    problems.push_back(model::diagnostic_at(where, key, expected, found));
  };
  const io::SourceLocation disc{c.file, c.discretization_location.line, c.discretization_location.column, "discretization"};
  const Index n = model.cloud.size();
  p.positions = model.cloud.positions;
  p.volumes = model.cloud.volumes;
  p.analysis = o.analysis;
  p.body = o.body;
  p.relaxation = o.relaxation;
  p.explicit_options = o.explicit_options;
  p.buckling = o.buckling;
  p.check_zero_energy = o.check_zero_energy;
  p.solver = c.solver;
  if (!c.discretization.spacing) {
    problem_at(disc, ".spacing", "lattice cell sizes [dx, dy, dz] (method pd)", "nothing");
    throw InputError(problems);
  }
  const Vec3 spacing = model.cloud.spacing.cols() ? Vec3(model.cloud.spacing.col(0)) : *c.discretization.spacing;
  const bool planar = o.body.kinematics != pd::Kinematics::three_dimensional;
  p.body.horizon = o.horizon ? *o.horizon
                             : o.horizon_factor.value_or(3.015) * (planar ? spacing.head<2>().maxCoeff() : spacing.maxCoeff());
  p.body.cell_size = planar ? std::sqrt(spacing.x() * spacing.y()) : std::cbrt(spacing.prod());
  if (planar && model.cloud.counts[2] > 1)
    problem_at(disc, ".spacing", "one node layer through the thickness for plane kinematics (dz = thickness)",
               fmt::format("{} layers", model.cloud.counts[2]));
  // Materials: the last entry whose selection holds wins.
  p.young = Eigen::VectorXd::Constant(n, NAN);
  p.poisson = Eigen::VectorXd::Constant(n, NAN);
  p.density = Eigen::VectorXd::Constant(n, 1.0);
  for (std::size_t m = 0; m < c.materials.size(); ++m) {
    const auto& spec = c.materials[m].spec;
    const io::SourceLocation where{c.file, 0, 0, fmt::format("materials.{}", m)};
    if (spec.model != material::MaterialModel::linear_elastic) {
      problem_at(where, ".model", "linear_elastic (the linear peridynamic solid)", "another model");
      continue;
    }
    if (o.analysis == pd::PdAnalysisKind::explicit_dynamics && !spec.density)
      problem_at(where, ".density", "a density (explicit dynamics)", "nothing");
    for (Index i : model.material_nodes[m]) {
      p.young[i] = spec.E;
      p.poisson[i] = spec.nu;
      p.density[i] = spec.density.value_or(1.0);
    }
  }
  if (!c.materials.empty() && p.young.hasNaN())
    problem_at(io::SourceLocation{c.file, 0, 0, "materials"}, "", "a material for every node", "nodes without one");
  // Boundary conditions and loads, as the case states them (pd/nodal_conditions.hpp).
  pd::apply_conditions(model.constraints, model.loads, p, problems);
  if (o.analysis == pd::PdAnalysisKind::linear_static || o.analysis == pd::PdAnalysisKind::buckling ||
      o.analysis == pd::PdAnalysisKind::quasi_static)
    if (p.prescribed.empty())
      problem_at(io::SourceLocation{c.file, 0, 0, "boundary"}, "",
                 "boundary conditions that suppress the rigid-body motions (static pd analysis)", "none");
  // Imperfection.
  const auto& imp = o.imperfection;
  p.imperfection.amplitude = imp.amplitude;
  if (imp.kind == ImperfectionOptions::Kind::sine) {
    const Vec3 lo = p.positions.rowwise().minCoeff(), hi = p.positions.rowwise().maxCoeff();
    p.imperfection.kind = pd::Imperfection::Kind::shape;
    p.imperfection.shape = PointMatrix::Zero(3, n);
    const Real pi = std::acos(-1.0);
    for (Index i = 0; i < n; ++i) {
      const Real sx = hi.x() > lo.x() ? (p.positions(0, i) - lo.x()) / (hi.x() - lo.x()) : 0.5;
      const Real sy = hi.y() > lo.y() ? (p.positions(1, i) - lo.y()) / (hi.y() - lo.y()) : 0.5;
      p.imperfection.shape(2, i) = std::sin(imp.half_waves[0] * pi * sx) * std::sin(imp.half_waves[1] * pi * sy);
    }
  } else if (imp.kind == ImperfectionOptions::Kind::file) {
    p.imperfection.kind = pd::Imperfection::Kind::shape;
    p.imperfection.shape = read_imperfection_file(imp.file, p.positions);
  } else if (imp.kind == ImperfectionOptions::Kind::buckling_mode) {
    p.imperfection.kind = pd::Imperfection::Kind::buckling_mode;
    p.imperfection.mode = imp.mode;
    if (imp.mode > p.buckling.modes) p.buckling.modes = imp.mode;
  }
  if (!problems.empty()) throw InputError(problems);
  return p;
}

std::unique_ptr<Analysis> create_pd(const io::Case& c, const Model& model, const MethodOptions& options) {
  const auto& o = static_cast<const PdMethodOptions&>(options);
  return std::make_unique<pd::PeridynamicAnalysis>(make_problem(c, model, o), model.probes);
}

}  // namespace

MethodEntry pd_method_entry() {
  return MethodEntry{io::MethodKeys{"pd", {"spacing", "horizon", "horizon_factor"}, true, {"imperfection"}, {"horizon", "horizon_factor"}},
                     "Linearized state-based peridynamics: ADR quasi-static, explicit, linear, buckling (seed 002)",
                     read_pd, create_pd, {"pd.explicit.end_time"}, /*distributed=*/true};
}

}  // namespace lamina::app
