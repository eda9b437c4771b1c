#include "efg/efg_analysis.hpp"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <set>

#include <fmt/format.h>

#include "core/error.hpp"
#include "efg/collocation_system.hpp"
#include "efg/galerkin_assembly.hpp"
#include "efg/weighted_least_squares_system.hpp"
#include "efg/mls_fit_analysis.hpp"
#include "geometry/body_maps.hpp"
#include "geometry/generators.hpp"
#include "mls/singular_moment_matrix.hpp"
#include "solve/block_pattern.hpp"

namespace lamina::efg {

namespace {

using Clock = std::chrono::steady_clock;

/// Boundary faces where a selection holds only in part are split into kSurfaceSplit^2 sub-faces.
constexpr int kSurfaceSplit = 8;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

const std::map<std::string, int> kVector{{"x", 0}, {"y", 1}, {"z", 2}};
const std::map<std::string, int> kTensor{{"xx", 0}, {"yy", 1}, {"zz", 2}, {"xy", 3}, {"yz", 4}, {"zx", 5}};

std::string describe_point(const Vec3& x) { return fmt::format("({:.6g}, {:.6g}, {:.6g})", x[0], x[1], x[2]); }

/// What the seed's support convention says about a kappa support that left A singular (docs/efg.md), or "".
std::string kappa_hint(const mls::MlsOptions& o) {
  if (o.mode != mls::SupportMode::kappa) return "";
  if (o.shape == mls::SupportShape::box && o.delta == 0.0)
    return "; with delta 0 the nodes kappa h away lie on the support boundary with zero weight: the seed's radius is "
           "s + delta (efg.support.delta, default 0.1, docs/efg.md)";
  if (o.shape == mls::SupportShape::sphere && o.kappa < 2.5)
    return "; a sphere of kappa 2 leaves the node plane 2 h from a face outside (the seed's sphere is kappa 2.5, its box "
           "kappa 2: docs/efg.md)";
  return "";
}

/// A singular MLS moment matrix is an input problem: the support is too small for the basis.
[[noreturn]] void support_too_small(const mls::SingularMomentMatrix& e, const mls::MlsOptions& o) {
  throw InputError("efg.support",
                   fmt::format("supports large enough for the {} basis ({} terms: every point needs more well-spread "
                               "neighbours than that)",
                               mls::to_string(o.basis), e.basis_size()),
                   fmt::format("a singular MLS moment matrix at {} with {} neighbours (condition {:.3g}); increase "
                               "efg.support.kappa (or nearest), use basis: linear, or set efg.singular_remedy: true (grow the support where A is singular, "
                               "the seed's SINCHECK){}",
                               describe_point(e.point()), e.neighbours(), e.condition(), kappa_hint(o)));
}

Mat3 gradient_of(const mls::ShapeFunctionValues& sv, const Eigen::VectorXd& u) {
  Mat3 G = Mat3::Zero();
  for (std::size_t k = 0; k < sv.neighbours.size(); ++k) {
    const Vec3 uk = u.segment<3>(3 * sv.neighbours[k]);
    G += uk * sv.dphi.col(static_cast<Index>(k)).transpose();
  }
  return G;
}

Vec3 value_of(const mls::ShapeFunctionValues& sv, const Eigen::VectorXd& u) {
  Vec3 v = Vec3::Zero();
  for (std::size_t k = 0; k < sv.neighbours.size(); ++k) v += sv.phi[static_cast<Index>(k)] * u.segment<3>(3 * sv.neighbours[k]);
  return v;
}

/// Gathers the local dofs (3 per neighbour) of a global vector.
Eigen::VectorXd gather(const mls::ShapeFunctionValues& sv, const Eigen::VectorXd& u) {
  Eigen::VectorXd local(3 * static_cast<Index>(sv.neighbours.size()));
  for (std::size_t k = 0; k < sv.neighbours.size(); ++k) local.segment<3>(3 * static_cast<Index>(k)) = u.segment<3>(3 * sv.neighbours[k]);
  return local;
}

void scatter_vector(const mls::ShapeFunctionValues& sv, const Eigen::VectorXd& local, Eigen::VectorXd& global) {
  for (std::size_t k = 0; k < sv.neighbours.size(); ++k)
    global.segment<3>(3 * sv.neighbours[k]) += local.segment<3>(3 * static_cast<Index>(k));
}

}  // namespace

std::string to_string(EssentialMethod method) {
  switch (method) {
    case EssentialMethod::penalty: return "penalty";
    case EssentialMethod::penalty_nodes: return "penalty_nodes";
    case EssentialMethod::nitsche: return "nitsche";
    case EssentialMethod::lagrange: return "lagrange";
  }
  return "?";
}

std::string to_string(Formulation formulation) {
  switch (formulation) {
    case Formulation::galerkin: return "galerkin";
    case Formulation::collocation: return "collocation";
    case Formulation::weighted_least_squares: return "weighted_least_squares";
  }
  return "?";
}

EfgAnalysis::EfgAnalysis(EfgProblem problem, std::vector<Probe> probes)
    : problem_(std::move(problem)), probes_(std::move(probes)) {
  for (const auto& p : probes_) {
    const std::string where = "probes." + p.name;
    if (p.field == "displacement") {
      if (!kVector.count(p.component) && p.component != "magnitude")
        throw InputError(where + ".component", "x, y, z or magnitude for a displacement probe", p.component);
    } else if (p.field == "strain" || p.field == "stress") {
      if (!kTensor.count(p.component) && !(p.field == "stress" && p.component == "von_mises"))
        throw InputError(where + ".component",
                         fmt::format("xx, yy, zz, xy, yz, zx{} for a {} probe", p.field == "stress" ? " or von_mises" : "", p.field),
                         p.component);
    } else if (p.field == "reaction_force") {
      if (!kVector.count(p.component) && p.component != "magnitude")
        throw InputError(where + ".component", "x, y, z or magnitude for a reaction_force probe", p.component);
      if (p.nodes.empty()) throw InputError(where + ".select", "a selection of nodes for a reaction_force probe", "none");
    } else if (p.field == "energy") {
      if (p.component != "internal" && p.component != "external" && p.component != "kinetic" && p.component != "total")
        throw InputError(where + ".component", "internal, external, kinetic or total for an energy probe", p.component);
    } else {
      throw InputError(where + ".field", "displacement, strain, stress, reaction_force or energy (efg is a static method)",
                       p.field);
    }
    if ((p.field == "displacement" || p.field == "strain" || p.field == "stress") && !p.at && p.nodes.empty())
      throw InputError(where + ".at", "a point `at: [x, y, z]` or a selection for a field probe", "neither");
  }
  if (problem_.materials.empty()) throw InputError("materials", "at least one linear_elastic material", "none");
  for (std::size_t i = 0; i < problem_.materials.size(); ++i) {
    problem_.materials[i].elastic.validate(fmt::format("materials.{}", i));
    materials_.push_back(problem_.materials[i].elastic);
    // the mu part alone: E' = 2 mu, nu' = 0 gives lambda' = 0, mu' = mu
    deviatoric_materials_.push_back(material::LinearElastic{2.0 * materials_.back().mu(), 0.0});
  }
  if (problem_.options.projected_volumetric) {
    if (problem_.options.formulation != Formulation::galerkin)
      throw InputError("efg.integration.volumetric", "full with a strong-form formulation (projected is a Galerkin option)",
                       "projected");
    if (problem_.options.essential == EssentialMethod::nitsche)
      throw InputError("efg.essential_bc",
                       "penalty, penalty_nodes or lagrange with volumetric: projected (Nitsche's consistency term "
                       "uses the unprojected stress)",
                       "nitsche");
    if (problem_.options.correction == IntegrationCorrection::vci)
      throw InputError("efg.integration.correction", "none with volumetric: projected (VCI is not combined with it)",
                       "vci");
  }
  if (problem_.options.formulation != Formulation::galerkin) {
    const std::string name = to_string(problem_.options.formulation);
    if (problem_.options.mls.basis != mls::Basis::quadratic)
      throw InputError("efg.basis",
                       fmt::format("basis: quadratic with formulation: {} (the strong form needs second derivatives "
                                   "of the MLS shape functions that reproduce quadratic fields)",
                                   name),
                       mls::to_string(problem_.options.mls.basis));
    if (problem_.materials.size() != 1)
      throw InputError("materials",
                       fmt::format("one material with formulation: {} (the strong form imposes no interface "
                                   "conditions between materials; use formulation: galerkin)",
                                   name),
                       fmt::format("{} materials", problem_.materials.size()));
    if (problem_.options.least_squares.traction_weight <= 0 ||
        (problem_.options.least_squares.displacement_weight && *problem_.options.least_squares.displacement_weight <= 0))
      throw InputError("efg.weighted_least_squares", "positive traction_weight and displacement_weight",
                       "a weight <= 0");
  }
}

EfgAnalysis::~EfgAnalysis() = default;

Index EfgAnalysis::nearest_node(const Vec3& x) const {
  std::vector<std::pair<Real, Index>> out;
  node_search_->nearest(x, 1, out);
  return out.empty() ? 0 : out.front().second;
}

void EfgAnalysis::setup() {
  const auto start = Clock::now();
  const PointCloud& cloud = problem_.cloud;
  const Index n = cloud.size();
  if (n == 0) throw InputError("discretization.nodes", "at least one node", "none");
  if (problem_.geometry.type == geometry::GeometryType::mesh)
    throw InputError("geometry.type",
                     "a generator body (box, plate, curved_beam, cylinder, sphere_cap, annulus, square_tube): efg "
                     "maps its background cells with the generator's parametric map",
                     "mesh");
  // nodes must lie in the body
  const Vec3 lower = cloud.positions.rowwise().minCoeff(), upper = cloud.positions.rowwise().maxCoeff();
  const Real size = std::max((upper - lower).norm(), 1e-300);
  for (Index i = 0; i < n; ++i)
    if (!geometry::body_contains(problem_.geometry, cloud.positions.col(i), 1e-6 * size))
      throw InputError("discretization.nodes",
                       "nodes inside the body (efg integrates over the generator body)",
                       fmt::format("node {} at {} outside it", i, describe_point(cloud.positions.col(i))));

  geometry::VolumeMap map = geometry::make_volume_map(problem_.geometry);
  std::array<int, 3> counts;
  if (problem_.options.cells) counts = *problem_.options.cells;
  else counts = default_cell_counts(map, cloud.counts);
  cells_ = std::make_unique<BackgroundCells>(make_background_cells(std::move(map), counts));
  volume_ = volume_quadrature(*cells_, problem_.options.gauss);
  if (problem_.options.reduced_volumetric) reduced_ = volume_quadrature(*cells_, problem_.options.volumetric_gauss);
  surface_ = boundary_quadrature(*cells_, problem_.options.gauss);
  const Real exact = geometry::body_volume(problem_.geometry);
  timings_["quadrature_volume_error"] = std::abs(volume_.weights.sum() - exact) / exact;
  timings_["quadrature_points"] = static_cast<Real>(volume_.size());
  timings_["cells"] = static_cast<Real>(cells_->size());

  node_search_ = std::make_unique<mls::CellList>(cloud.positions, std::max(size / std::cbrt(static_cast<Real>(n)), 1e-12));
  Eigen::Matrix3Xd spacing = cloud.spacing.cols() == n ? cloud.spacing : Eigen::Matrix3Xd();
  shapes_ = std::make_unique<mls::MlsShapeFunctions>(cloud.positions, problem_.options.mls, spacing);
  if (problem_.options.projected_volumetric) {
    // pressure nodes with small box supports: Shepard pressure functions (volumetric_projection.hpp)
    mls::MlsOptions pressure = problem_.options.mls;
    pressure.basis = mls::Basis::linear;  // only the support search and radii are used (Shepard functions)
    pressure.shape = mls::SupportShape::box;
    pressure.mode = mls::SupportMode::kappa;
    pressure.kappa = problem_.options.pressure_kappa;
    pressure.delta = 0.0;  // pressure_kappa is the bare radius factor (no seed s + delta convention)
    pressure.kappa_axes = Vec3::Zero();
    pressure.interface_enrichment = false;
    pressure.singular_remedy = false;
    std::optional<std::array<int, 3>> pressure_counts = problem_.options.pressure_nodes;
    if (!pressure_counts && cloud.counts[0] > 1 && cloud.counts[1] > 1 && cloud.counts[2] > 1) {
      pressure_counts = std::array<int, 3>{};
      for (int d = 0; d < 3; ++d)
        (*pressure_counts)[static_cast<std::size_t>(d)] = static_cast<int>(cloud.counts[static_cast<std::size_t>(d)] / 2 + 1);
    }
    if (pressure_counts) {
      const PointCloud coarse = geometry::generate_volume_nodes(problem_.geometry, *pressure_counts);
      timings_["pressure_nodes"] = static_cast<Real>(coarse.size());
      pressure_shapes_ = std::make_unique<mls::MlsShapeFunctions>(coarse.positions, pressure,
                                                                 coarse.spacing.cols() == coarse.size() ? coarse.spacing : Eigen::Matrix3Xd());
    } else {
      pressure_shapes_ = std::make_unique<mls::MlsShapeFunctions>(cloud.positions, pressure, spacing);
    }
    pressure_ = std::make_unique<ShepardPressure>(*pressure_shapes_);
  }

  for (const auto& m : problem_.materials)
    material_tests_.push_back(m.region ? std::make_unique<RegionTest>(*m.region, &cells_->map,
                                                                      [this](const Vec3& x) { return nearest_node(x); },
                                                                      1e-9 * size)
                                       : nullptr);
  timings_["setup_s"] = seconds_since(start);
}

int EfgAnalysis::material_at(const Vec3& x) const {
  for (std::size_t m = 0; m < material_tests_.size(); ++m)
    if (!material_tests_[m] || material_tests_[m]->in_volume(x)) return static_cast<int>(m);
  return -1;
}

void EfgAnalysis::assign_materials() {
  material_of_point_.assign(static_cast<std::size_t>(volume_.size()), 0);
  for (Index q = 0; q < volume_.size(); ++q) {
    const int m = material_at(volume_.points.col(q));
    if (m < 0)
      throw InputError("materials",
                       "materials whose selections cover the whole body (the first matching material applies)",
                       fmt::format("no material at the quadrature point {}", describe_point(volume_.points.col(q))));
    material_of_point_[static_cast<std::size_t>(q)] = m;
  }
  material_of_reduced_point_.assign(static_cast<std::size_t>(reduced_.size()), 0);
  for (Index q = 0; q < reduced_.size(); ++q) {
    const int m = material_at(reduced_.points.col(q));
    if (m < 0)
      throw InputError("materials",
                       "materials whose selections cover the whole body (the first matching material applies)",
                       fmt::format("no material at the quadrature point {}", describe_point(reduced_.points.col(q))));
    material_of_reduced_point_[static_cast<std::size_t>(q)] = m;
  }
}

void EfgAnalysis::build_constraints() {
  constraint_points_.clear();
  const auto method = problem_.options.essential;
  // strong forms impose the conditions at the nodes; the surface points serve their reactions
  const bool surface_methods = method == EssentialMethod::penalty || method == EssentialMethod::nitsche ||
                               problem_.options.formulation != Formulation::galerkin;
  const Vec3 lower = problem_.cloud.positions.rowwise().minCoeff(), upper = problem_.cloud.positions.rowwise().maxCoeff();
  const Real tolerance = 1e-9 * (upper - lower).norm();
  for (std::size_t e = 0; e < problem_.constraints.size(); ++e) {
    const auto& c = problem_.constraints[e];
    if (!c.constrained[0] && !c.constrained[1] && !c.constrained[2]) continue;
    std::array<std::unique_ptr<FieldEvaluator>, 3> value;
    for (int a = 0; a < 3; ++a) value[static_cast<std::size_t>(a)] = std::make_unique<FieldEvaluator>(c.value[static_cast<std::size_t>(a)]);
    auto prescribed = [&](const Vec3& x) {
      Vec3 v = Vec3::Zero();
      for (int a = 0; a < 3; ++a)
        if (c.constrained[static_cast<std::size_t>(a)]) v[a] = (*value[static_cast<std::size_t>(a)])(x);
      return v;
    };
    bool any_surface = false;
    if (surface_methods) {
      RegionTest test(c.region, &cells_->map, [this](const Vec3& x) { return nearest_node(x); }, tolerance);
      if (test.can_select_surface()) {
        const SurfaceQuadrature part = refine_selected_faces(
            *cells_, surface_, problem_.options.gauss, kSurfaceSplit,
            [&](const Vec3& x, int face) { return test.on_surface(x, face); });
        for (Index s = 0; s < part.size(); ++s) {
          const Vec3 x = part.points.col(s);
          ConstraintPoint p;
          p.x = x;
          p.weight = part.weights[s];
          p.normal = part.normals.col(s);
          p.size = part.cell_size[s];
          p.material = std::max(material_at(x), 0);
          p.surface = true;
          p.condition = static_cast<int>(e);
          p.constrained = c.constrained;
          p.value = prescribed(x);
          constraint_points_.push_back(p);
          any_surface = true;
        }
      }
    }
    if (!any_surface) {
      for (Index node : c.region.nodes) {
        ConstraintPoint p;
        p.x = problem_.cloud.positions.col(node);
        p.weight = 1.0;
        p.material = std::max(material_at(p.x), 0);
        p.surface = false;
        p.condition = static_cast<int>(e);
        p.constrained = c.constrained;
        p.value = prescribed(p.x);
        constraint_points_.push_back(p);
      }
    }
  }
}

void EfgAnalysis::build_loads() {
  point_loads_.clear();
  body_force_.resize(3, 0);
  const Vec3 lower = problem_.cloud.positions.rowwise().minCoeff(), upper = problem_.cloud.positions.rowwise().maxCoeff();
  const Real tolerance = 1e-9 * (upper - lower).norm();
  for (std::size_t l = 0; l < problem_.loads.size(); ++l) {
    const auto& load = problem_.loads[l];
    std::array<std::unique_ptr<FieldEvaluator>, 3> vec;
    for (int a = 0; a < 3; ++a) vec[static_cast<std::size_t>(a)] = std::make_unique<FieldEvaluator>(load.vector[static_cast<std::size_t>(a)]);
    auto vector_at = [&](const Vec3& x) {
      return Vec3((*vec[0])(x), (*vec[1])(x), (*vec[2])(x));
    };
    RegionTest test(load.region, &cells_->map, [this](const Vec3& x) { return nearest_node(x); }, tolerance);
    switch (load.kind) {
      case EfgLoad::Kind::force: {
        if (problem_.options.formulation != Formulation::galerkin)
          throw InputError(load.region.label,
                           fmt::format("traction, pressure or body_force with formulation: {} (the strong form has no "
                                       "point forces: spread the force as a traction over a face, or use formulation: "
                                       "galerkin)",
                                       to_string(problem_.options.formulation)),
                           "force");
        const Real share = 1.0 / static_cast<Real>(load.region.nodes.size());
        for (Index node : load.region.nodes) {
          const Vec3 x = problem_.cloud.positions.col(node);
          point_loads_.push_back({x, share * vector_at(x)});
        }
        break;
      }
      case EfgLoad::Kind::traction:
      case EfgLoad::Kind::pressure: {
        FieldEvaluator pressure(load.scalar);
        bool any = false;
        if (test.can_select_surface()) {
          const SurfaceQuadrature part = refine_selected_faces(
              *cells_, surface_, problem_.options.gauss, kSurfaceSplit,
              [&](const Vec3& x, int face) { return test.on_surface(x, face); });
          for (Index s = 0; s < part.size(); ++s) {
            const Vec3 x = part.points.col(s);
            const Vec3 t = load.kind == EfgLoad::Kind::traction ? vector_at(x) : Vec3(-pressure(x) * part.normals.col(s));
            point_loads_.push_back({x, part.weights[s] * t});
            any = true;
          }
        }
        if (!any)
          throw InputError(load.region.label,
                           "a selection that holds on part of the body's boundary surface (traction and pressure are "
                           "integrated over the boundary faces where the selection holds)",
                           load.region.spec.describe() + " holds at no boundary quadrature point");
        break;
      }
      case EfgLoad::Kind::body_force: {
        if (body_force_.cols() != volume_.size()) body_force_ = Eigen::Matrix3Xd::Zero(3, volume_.size());
        for (Index q = 0; q < volume_.size(); ++q) {
          const Vec3 x = volume_.points.col(q);
          if (test.in_volume(x)) body_force_.col(q) += vector_at(x);
        }
        break;
      }
    }
  }
}

void EfgAnalysis::assemble_and_solve(OutputSink* sink) {
  if (problem_.options.formulation != Formulation::galerkin) {
    solve_strong_form(sink);
    return;
  }
  const Index n = problem_.cloud.size();
  const auto& options = problem_.options;
  const bool vci = options.correction == IntegrationCorrection::vci;
  const bool lagrange = options.essential == EssentialMethod::lagrange;
  auto progress = [&](Real fraction, const std::string& status) {
    if (sink) sink->progress(fraction, status);
  };

  // pass 1: neighbours per cell (and VCI integrals)
  auto start = Clock::now();
  VolumeIntegrals integrals, reduced_integrals;
  const bool reduced = reduced_.size() > 0;
  std::vector<IndexList> groups;
  std::vector<IndexList> cell_nodes = cell_neighbours(*shapes_, volume_, vci ? &integrals : nullptr, &groups);
  if (reduced) {
    const std::vector<IndexList> extra = cell_neighbours(*shapes_, reduced_, vci ? &reduced_integrals : nullptr, &groups);
    IndexList merged;
    for (std::size_t c = 0; c < cell_nodes.size(); ++c) {
      merged.clear();
      std::set_union(cell_nodes[c].begin(), cell_nodes[c].end(), extra[c].begin(), extra[c].end(), std::back_inserter(merged));
      cell_nodes[c].swap(merged);
    }
  }
  Eigen::Matrix3Xd xi, xi_reduced;
  if (vci) {
    Eigen::Matrix3Xd boundary = Eigen::Matrix3Xd::Zero(3, n);
    const auto values = shapes_->evaluate_all(surface_.points, 0);
    for (Index s = 0; s < surface_.size(); ++s) {
      const auto& sv = values[static_cast<std::size_t>(s)];
      for (std::size_t k = 0; k < sv.neighbours.size(); ++k)
        boundary.col(sv.neighbours[k]) += surface_.weights[s] * sv.phi[static_cast<Index>(k)] * surface_.normals.col(s);
    }
    xi = vci_correction(integrals, boundary);
    if (reduced) xi_reduced = vci_correction(reduced_integrals, boundary);
  }
  timings_["neighbours_s"] = seconds_since(start);
  progress(0.2, "neighbours");

  // projected volumetric term (efg.integration.volumetric: projected): G, M and lambda per pressure node
  const bool projected = problem_.options.projected_volumetric;
  if (projected) {
    start = Clock::now();
    Eigen::VectorXd lambda(volume_.size());
    for (Index q = 0; q < volume_.size(); ++q)
      lambda[q] = materials_[static_cast<std::size_t>(material_of_point_[static_cast<std::size_t>(q)])].lambda();
    projection_ = std::make_unique<ProjectedVolumetric>(project_volumetric(*shapes_, *pressure_, volume_, lambda));
    for (const auto& list : projection_->nodes) groups.push_back(list);
    timings_["projection_s"] = seconds_since(start);
  }

  // shape functions at the constraint points
  start = Clock::now();
  PointMatrix constraint_x(3, static_cast<Index>(constraint_points_.size()));
  for (std::size_t i = 0; i < constraint_points_.size(); ++i) constraint_x.col(static_cast<Index>(i)) = constraint_points_[i].x;
  const auto constraint_shapes = shapes_->evaluate_all(constraint_x, 1);

  // pattern
  if (!lagrange)
    for (const auto& sv : constraint_shapes) groups.push_back(sv.neighbours);
  const bool symmetric = !vci;
  solve::BlockPattern pattern(n, 3, groups, symmetric);
  groups.clear();
  groups.shrink_to_fit();
  timings_["pattern_s"] = seconds_since(start);
  progress(0.3, "pattern");

  // volume stiffness
  start = Clock::now();
  solve::SparseMatrix K = pattern.zero_matrix();
  Real* values = K.valuePtr();
  Eigen::VectorXd f = Eigen::VectorXd::Zero(3 * n);
  VolumeAssembly input;
  input.shapes = shapes_.get();
  input.quadrature = &volume_;
  input.cell_nodes = &cell_nodes;
  input.material_of_point = &material_of_point_;
  input.materials = projected ? &deviatoric_materials_ : &materials_;
  input.body_force = body_force_.cols() == volume_.size() ? &body_force_ : nullptr;
  input.vci = vci ? &xi : nullptr;
  if (reduced) {
    input.reduced = &reduced_;
    input.material_of_reduced_point = &material_of_reduced_point_;
    input.vci_reduced = vci ? &xi_reduced : nullptr;
  }
  const VolumeAssemblyReport volume_report = assemble_volume(input, pattern, values, f);
  const Real volume_seconds = seconds_since(start);
  timings_["assembly_volume_s"] = volume_seconds;
  timings_["assembly_direct_writes"] = volume_report.direct ? 1.0 : 0.0;
  timings_["gauss_points_per_second"] =
      static_cast<Real>(volume_.size()) / std::max(volume_seconds + timings_["neighbours_s"], 1e-12);
  progress(0.6, "assembled");

  // loads
  start = Clock::now();
  {
    PointMatrix load_x(3, static_cast<Index>(point_loads_.size()));
    for (std::size_t i = 0; i < point_loads_.size(); ++i) load_x.col(static_cast<Index>(i)) = point_loads_[i].x;
    const auto load_shapes = shapes_->evaluate_all(load_x, 0);
    for (std::size_t i = 0; i < point_loads_.size(); ++i) {
      const auto& sv = load_shapes[i];
      for (std::size_t k = 0; k < sv.neighbours.size(); ++k)
        f.segment<3>(3 * sv.neighbours[k]) += sv.phi[static_cast<Index>(k)] * point_loads_[i].force;
    }
  }
  f_loads_ = f;

  // penalty scale: max diagonal of the volume stiffness over max nodal sum of w phi^2
  Real max_diagonal = 0;
  for (Index d = 0; d < 3 * n; ++d) {
    const Index p = pattern.position(d, d);
    if (p >= 0) max_diagonal = std::max(max_diagonal, std::abs(values[p]));
  }
  {
    Eigen::VectorXd surface_sum = Eigen::VectorXd::Zero(n), point_sum = Eigen::VectorXd::Zero(n);
    for (std::size_t i = 0; i < constraint_points_.size(); ++i) {
      const auto& sv = constraint_shapes[i];
      Eigen::VectorXd& sum = constraint_points_[i].surface ? surface_sum : point_sum;
      for (std::size_t k = 0; k < sv.neighbours.size(); ++k)
        sum[sv.neighbours[k]] += constraint_points_[i].weight * sv.phi[static_cast<Index>(k)] * sv.phi[static_cast<Index>(k)];
    }
    const Real s_max = surface_sum.size() ? surface_sum.maxCoeff() : 0.0, p_max = point_sum.size() ? point_sum.maxCoeff() : 0.0;
    // scale with Young's modulus rather than the P-wave modulus lambda + 2 mu that dominates the
    // diagonal: a nearly incompressible body would otherwise get a penalty ~ lambda and lock at the
    // constrained faces
    Real stiffest = 0.0, ratio = 1.0;
    for (std::size_t i = 0; i < materials_.size(); ++i) {
      const auto& m = materials_[i];
      const Real assembled = projected ? deviatoric_materials_[i].p_wave_modulus() : m.p_wave_modulus();
      if (m.p_wave_modulus() > stiffest) {
        stiffest = m.p_wave_modulus();
        ratio = m.E / assembled;
      }
    }
    max_diagonal *= ratio;
    alpha_surface_ = options.penalty ? *options.penalty : (s_max > 0 ? options.penalty_factor * max_diagonal / s_max : 0.0);
    alpha_point_ = options.penalty ? *options.penalty : (p_max > 0 ? options.penalty_factor * max_diagonal / p_max : 0.0);
  }
  timings_["penalty_surface"] = alpha_surface_;
  timings_["penalty_point"] = alpha_point_;
  // after the penalty scale, which is taken from the mu part (a lambda-sized penalty locks the constrained faces)
  if (projected) {
    const auto projection_start = Clock::now();
    projection_->add_stiffness(pattern, values);  // K += G^T diag(lambda_I / M_I) G
    timings_["projection_s"] += seconds_since(projection_start);
  }

  // constraint terms
  Eigen::MatrixXd Kc;
  Eigen::VectorXd fc;
  std::vector<Eigen::Triplet<Real>> multiplier_entries;
  Eigen::VectorXd multiplier_rhs;
  Index multipliers = 0;
  if (lagrange) {
    for (const auto& p : constraint_points_)
      for (int a = 0; a < 3; ++a) multipliers += p.constrained[static_cast<std::size_t>(a)] ? 1 : 0;
    multiplier_rhs.resize(multipliers);
    Index row = 0;
    for (std::size_t i = 0; i < constraint_points_.size(); ++i) {
      const auto& p = constraint_points_[i];
      const auto& sv = constraint_shapes[i];
      for (int a = 0; a < 3; ++a) {
        if (!p.constrained[static_cast<std::size_t>(a)]) continue;
        for (std::size_t k = 0; k < sv.neighbours.size(); ++k)
          multiplier_entries.emplace_back(static_cast<int>(3 * n + row), static_cast<int>(3 * sv.neighbours[k] + a),
                                          sv.phi[static_cast<Index>(k)]);
        multiplier_rhs[row] = p.value[a];
        ++row;
      }
    }
  } else {
    for (std::size_t i = 0; i < constraint_points_.size(); ++i) {
      const auto& p = constraint_points_[i];
      const auto& sv = constraint_shapes[i];
      if (options.essential == EssentialMethod::nitsche && p.surface) {
        const auto& mat = materials_[static_cast<std::size_t>(p.material)];
        const Real beta = options.nitsche_factor * mat.p_wave_modulus() / std::max(p.size, 1e-300);
        nitsche_terms(sv, p, mat, beta, Kc, fc);
      } else {
        penalty_terms(sv, p, p.surface ? alpha_surface_ : alpha_point_, Kc, fc);
      }
      pattern.scatter(sv.neighbours, Kc, values);
      scatter_vector(sv, fc, f);
    }
  }
  timings_["assembly_boundary_s"] = seconds_since(start);
  timings_["assembly_s"] = timings_["neighbours_s"] + timings_["pattern_s"] + volume_seconds + timings_["assembly_boundary_s"] +
                          (projected ? timings_["projection_s"] : 0.0);
  progress(0.7, "solving");

  // solve
  start = Clock::now();
  timings_["dofs"] = static_cast<Real>(3 * n + multipliers);
  timings_["nonzeros"] = static_cast<Real>(K.nonZeros());
  if (lagrange) {
    std::vector<Eigen::Triplet<Real>> entries;
    entries.reserve(static_cast<std::size_t>(symmetric ? 2 * K.nonZeros() : K.nonZeros()) + 2 * multiplier_entries.size());
    for (Index col = 0; col < K.outerSize(); ++col)
      for (solve::SparseMatrix::InnerIterator it(K, col); it; ++it) {
        entries.emplace_back(static_cast<int>(it.row()), static_cast<int>(col), it.value());
        if (symmetric && it.row() != col) entries.emplace_back(static_cast<int>(col), static_cast<int>(it.row()), it.value());
      }
    for (const auto& t : multiplier_entries) {
      entries.push_back(t);
      entries.emplace_back(t.col(), t.row(), t.value());
    }
    solve::SparseMatrix A(3 * n + multipliers, 3 * n + multipliers);
    A.setFromTriplets(entries.begin(), entries.end());
    Eigen::VectorXd rhs(3 * n + multipliers);
    rhs << f, multiplier_rhs;
    const Eigen::VectorXd x = solve::solve_general(A, rhs, solver_report_);
    u_ = x.head(3 * n);
    multipliers_ = x.tail(multipliers);
  } else if (symmetric) {
    u_ = solve::solve_symmetric(K, f, solver_report_);
  } else {
    u_ = solve::solve_general(K, f, solver_report_);
  }
  record_solver_report();
  timings_["solve_total_s"] = seconds_since(start);
  progress(0.9, "solved (" + solver_report_.method + ")");

  // energies: u^T K u over the whole system minus the constraint terms
  start = Clock::now();
  const Eigen::VectorXd Ku = symmetric ? solve::multiply_symmetric_upper(K, u_) : Eigen::VectorXd(K * u_);
  Real constraint_energy = 0.0;
  reactions_.assign(constraint_points_.size(), Vec3::Zero());
  constraint_nearest_.assign(constraint_points_.size(), 0);
  Index row = 0;
  for (std::size_t i = 0; i < constraint_points_.size(); ++i) {
    const auto& p = constraint_points_[i];
    const auto& sv = constraint_shapes[i];
    constraint_nearest_[i] = nearest_node(p.x);
    const Vec3 uh = value_of(sv, u_);
    Vec3 r = Vec3::Zero();
    if (lagrange) {
      for (int a = 0; a < 3; ++a)
        if (p.constrained[static_cast<std::size_t>(a)]) r[a] = -multipliers_[row++];
    } else if (options.essential == EssentialMethod::nitsche && p.surface) {
      const auto& mat = materials_[static_cast<std::size_t>(p.material)];
      const Real beta = options.nitsche_factor * mat.p_wave_modulus() / std::max(p.size, 1e-300);
      const Vec3 t = material::traction(mat.stress(material::strain_from_gradient(gradient_of(sv, u_))), p.normal);
      for (int a = 0; a < 3; ++a)
        if (p.constrained[static_cast<std::size_t>(a)]) r[a] = p.weight * (t[a] - beta * (uh[a] - p.value[a]));
      nitsche_terms(sv, p, mat, beta, Kc, fc);
      const Eigen::VectorXd ul = gather(sv, u_);
      constraint_energy += ul.dot(Kc * ul);
    } else {
      const Real alpha = p.surface ? alpha_surface_ : alpha_point_;
      for (int a = 0; a < 3; ++a)
        if (p.constrained[static_cast<std::size_t>(a)]) r[a] = -alpha * p.weight * (uh[a] - p.value[a]);
      for (int a = 0; a < 3; ++a)
        if (p.constrained[static_cast<std::size_t>(a)]) constraint_energy += alpha * p.weight * uh[a] * uh[a];
    }
    reactions_[i] = r;
  }
  energy_internal_ = 0.5 * (u_.dot(Ku) - constraint_energy);
  if (projection_) nodal_pressure_ = projection_->lambda.cwiseProduct(projection_->nodal_divergence(u_));
  Real reaction_work = 0.0;
  for (std::size_t i = 0; i < constraint_points_.size(); ++i) reaction_work += reactions_[i].dot(constraint_points_[i].value);
  energy_external_ = 0.5 * (f_loads_.dot(u_) + reaction_work);
  timings_["energy_s"] = seconds_since(start);
}

void EfgAnalysis::postprocess() {
  const auto start = Clock::now();
  const Index n = problem_.cloud.size();
  const auto values = shapes_->evaluate_all(problem_.cloud.positions, 1);
  node_displacement_.resize(3, n);
  node_strain_.resize(6, n);
  node_stress_.resize(6, n);
  node_material_.assign(static_cast<std::size_t>(n), 0);
  for (Index i = 0; i < n; ++i) {
    const Vec3 x = problem_.cloud.positions.col(i);
    const int m = material_at(x);
    node_material_[static_cast<std::size_t>(i)] = m < 0 ? 0 : m;
  }
#pragma omp parallel for schedule(static)
  for (Index i = 0; i < n; ++i) {
    const auto& sv = values[static_cast<std::size_t>(i)];
    node_displacement_.col(i) = value_of(sv, u_);
    const material::Voigt e = material::strain_from_gradient(gradient_of(sv, u_));
    node_strain_.col(i) = e;
    node_stress_.col(i) = stress_of(node_material_[static_cast<std::size_t>(i)], e, problem_.cloud.positions.col(i));
  }
  if (problem_.options.exact_displacement) {
    const auto& exact = *problem_.options.exact_displacement;
    const Vec3 lower = problem_.cloud.positions.rowwise().minCoeff(), upper = problem_.cloud.positions.rowwise().maxCoeff();
    const Real h = 1e-3 * std::max((upper - lower).maxCoeff(), 1e-300);
    Real du = 0, umax = 0, ds = 0, smax = 0;
    for (Index i = 0; i < n; ++i) {
      const Vec3 x = problem_.cloud.positions.col(i);
      Vec3 ue;
      Mat3 G;
      for (int a = 0; a < 3; ++a) {
        const FieldDerivatives d = differentiate_expression(exact[static_cast<std::size_t>(a)], x, h);
        ue[a] = d.value;
        G.row(a) = d.gradient.transpose();
      }
      const material::Voigt se = materials_[static_cast<std::size_t>(node_material_[static_cast<std::size_t>(i)])].stress(
          material::strain_from_gradient(G));  // the exact stress (full lambda tr eps)
      du = std::max(du, (node_displacement_.col(i) - ue).norm());
      umax = std::max(umax, ue.norm());
      ds = std::max(ds, (node_stress_.col(i) - se).norm());
      smax = std::max(smax, se.norm());
    }
    error_displacement_ = umax > 0 ? du / umax : du;
    error_stress_ = smax > 0 ? ds / smax : ds;
  }
  timings_["post_s"] = seconds_since(start);
}

void EfgAnalysis::solve() {
  const auto start = Clock::now();
  try {
    setup();
    assign_materials();
    build_constraints();
    build_loads();
    assemble_and_solve(nullptr);
    postprocess();
  } catch (const mls::SingularMomentMatrix& e) {
    support_too_small(e, problem_.options.mls);
  } catch (const geometry::ExpressionError& e) {
    throw InputError("efg", "valid expressions in selections and prescribed values", e.what());
  }
  solved_ = true;
  timings_["total_s"] = seconds_since(start);
}

void EfgAnalysis::run(OutputSink& sink) {
  const auto start = Clock::now();
  try {
    sink.progress(0.0, "setup");
    setup();
    assign_materials();
    build_constraints();
    build_loads();
    sink.progress(0.1, "quadrature");
    assemble_and_solve(&sink);
    postprocess();
  } catch (const mls::SingularMomentMatrix& e) {
    support_too_small(e, problem_.options.mls);
  } catch (const geometry::ExpressionError& e) {
    throw InputError("efg", "valid expressions in selections and prescribed values", e.what());
  }
  if (!u_.allFinite()) throw AnalysisError("the EFG solution contains non-finite values");
  solved_ = true;
  timings_["total_s"] = seconds_since(start);
  sink.progress(1.0, "done");
  sink.output_point(1, 1.0, 1.0);
}

Real EfgAnalysis::quadrature_volume() const { return volume_.weights.sum(); }

Vec3 EfgAnalysis::displacement_at(const Vec3& x) const {
  mls::ShapeFunctionValues sv;
  shapes_->evaluate(x, 0, sv);
  return value_of(sv, u_);
}

material::Voigt EfgAnalysis::strain_at(const Vec3& x) const {
  mls::ShapeFunctionValues sv;
  shapes_->evaluate(x, 1, sv);
  return material::strain_from_gradient(gradient_of(sv, u_));
}

material::Voigt EfgAnalysis::stress_at(const Vec3& x) const {
  int m = material_at(x);
  if (m < 0) m = node_material_.empty() ? 0 : node_material_[static_cast<std::size_t>(nearest_node(x))];
  return stress_of(m, strain_at(x), x);
}

std::vector<std::string> EfgAnalysis::warnings() const {
  std::vector<std::string> out = support_warnings();
  const auto& o = problem_.options;
  if (o.formulation != Formulation::galerkin || o.projected_volumetric || o.reduced_volumetric) return out;
  for (std::size_t i = 0; i < materials_.size(); ++i)
    if (materials_[i].nu > 0.45)
      out.push_back(fmt::format("materials.{} has nu = {:g} with efg.integration.volumetric: full; expect volumetric "
                                "locking (a too stiff result); use efg.integration: {{volumetric: projected}}",
                                i, materials_[i].nu));
  return out;
}

std::vector<std::string> EfgAnalysis::support_warnings() const {
  // Supports that gather far more nodes than the basis needs make the run slow and the stiffness
  // nearly rank-deficient (every shape function spans the whole body). The usual cause is a sphere
  // support (radius from the largest of a node's spacings) on strongly anisotropic spacing, e.g. node
  // counts given in the wrong order for a thin wall.
  std::vector<std::string> out;
  const mls::MlsOptions& mls = problem_.options.mls;
  const PointCloud& cloud = problem_.cloud;
  const Index n = cloud.size();
  if (mls.mode != mls::SupportMode::kappa || n == 0) return out;
  // warnings() runs before setup(): build the supports here (radii and a cell list, no shape functions)
  Real worst_ratio = 1.0;
  double mean = 0.0;
  try {
    std::unique_ptr<mls::MlsShapeFunctions> built;
    if (!shapes_)
      built = std::make_unique<mls::MlsShapeFunctions>(cloud.positions, mls,
                                                       cloud.spacing.cols() == n ? cloud.spacing : Eigen::Matrix3Xd());
    const mls::MlsShapeFunctions& supports = shapes_ ? *shapes_ : *built;
    const Eigen::Matrix3Xd& spacing = supports.nodal_spacing();
    for (Index i = 0; i < spacing.cols(); ++i) {
      const auto h = spacing.col(i);
      if (h.minCoeff() > 0.0) worst_ratio = std::max(worst_ratio, h.maxCoeff() / h.minCoeff());
    }
    const Index stride = std::max<Index>(1, n / 2000);  // sample at most ~2000 nodes
    IndexList neighbours;
    double total = 0.0;
    Index samples = 0;
    for (Index i = 0; i < n; i += stride, ++samples) {
      supports.neighbours(supports.nodes().col(i), neighbours);
      total += static_cast<double>(neighbours.size());
    }
    mean = total / static_cast<double>(samples);
  } catch (const std::exception&) {
    return out;  // setup() reports the problem as an input error
  }
  const bool sphere = mls.shape == mls::SupportShape::sphere;
  const std::string order_hint =
      "check the order of discretization.nodes (a cylinder wall takes [thickness, circumferential, axial])";
  if (mean > kCrowdedSupport && mean > 0.25 * static_cast<double>(n))
    out.push_back(fmt::format("efg.support: each node's support holds {:.0f} of the {} nodes on average, so the run will be "
                              "slow and the shape functions nearly global; the nodal spacings differ up to {:.3g} times "
                              "between directions{}; {}",
                              mean, n, worst_ratio,
                              sphere ? " and a sphere's radius follows the largest, so use efg.support.shape: box" : "",
                              order_hint));
  else if (sphere && worst_ratio > kSphereAnisotropy)
    out.push_back(fmt::format("efg.support: the nodal spacings differ up to {:.3g} times between directions and a sphere "
                              "support's radius follows the largest (supports hold {:.0f} nodes on average); "
                              "efg.support.shape: box scales each direction by its own spacing",
                              worst_ratio, mean));
  return out;
}

void EfgAnalysis::record_solver_report() {
  timings_["factor_s"] = solver_report_.factor_seconds;
  timings_["solve_s"] = solver_report_.solve_seconds;
  timings_["solver_residual"] = solver_report_.residual;
  timings_["solver_backward_error"] = solver_report_.backward_error;
  timings_["solver_rcond"] = solver_report_.rcond;
  timings_["solver_cholmod"] = solver_report_.method == "cholmod_supernodal_llt" ? 1.0 : 0.0;
}

material::Voigt EfgAnalysis::stress_of(int m, const material::Voigt& strain, const Vec3& x) const {
  if (!projection_ || nodal_pressure_.size() == 0) return materials_[static_cast<std::size_t>(m)].stress(strain);
  // sigma = 2 mu eps + p I with the projected pressure p(x) = sum_I psi_I(x) lambda_I theta_I
  material::Voigt s = deviatoric_materials_[static_cast<std::size_t>(m)].stress(strain);
  mls::ShapeFunctionValues pv;
  if (!pressure_->evaluate(x, pv)) return s;  // outside every pressure support
  Real p = 0.0;
  for (std::size_t k = 0; k < pv.neighbours.size(); ++k) p += pv.phi[static_cast<Index>(k)] * nodal_pressure_[pv.neighbours[k]];
  s.head<3>().array() += p;
  return s;
}

Vec3 EfgAnalysis::reaction(const IndexList& nodes) const {
  Vec3 sum = Vec3::Zero();
  for (std::size_t i = 0; i < reactions_.size(); ++i)
    if (nodes.empty() || std::binary_search(nodes.begin(), nodes.end(), constraint_nearest_[i])) sum += reactions_[i];
  return sum;
}

Real EfgAnalysis::field_probe(const Probe& p) const {
  auto component_of = [&](const Vec3& u, const material::Voigt& e, const material::Voigt& s) -> Real {
    if (p.field == "displacement") return p.component == "magnitude" ? u.norm() : u[kVector.at(p.component)];
    if (p.field == "strain") return e[kTensor.at(p.component)];
    return p.component == "von_mises" ? material::von_mises(s) : s[kTensor.at(p.component)];
  };
  auto at_point = [&](const Vec3& x) {
    if (p.field == "displacement") return component_of(displacement_at(x), material::Voigt::Zero(), material::Voigt::Zero());
    const material::Voigt e = strain_at(x);
    return component_of(Vec3::Zero(), e, p.field == "stress" ? stress_at(x) : material::Voigt::Zero());
  };
  if (p.at && !p.nearest_in_set) return at_point(*p.at);
  if (p.at && p.nearest_in_set) {
    Index best = p.nodes.front();
    Real distance = INFINITY;
    for (Index i : p.nodes) {
      const Real d = (problem_.cloud.positions.col(i) - *p.at).squaredNorm();
      if (d < distance) {
        distance = d;
        best = i;
      }
    }
    return component_of(node_displacement_.col(best), node_strain_.col(best), node_stress_.col(best));
  }
  // selection without a point: the value of largest magnitude over the selected nodes
  Real result = 0.0;
  for (Index i : p.nodes) {
    const Real v = component_of(node_displacement_.col(i), node_strain_.col(i), node_stress_.col(i));
    if (std::abs(v) > std::abs(result)) result = v;
  }
  return result;
}

Real EfgAnalysis::probe(const Probe& p) const {
  if (!solved_) return 0.0;
  if (p.field == "reaction_force") {
    const Vec3 r = reaction(p.nodes);
    return p.component == "magnitude" ? r.norm() : r[kVector.at(p.component)];
  }
  if (p.field == "energy") {
    if (p.component == "internal" || p.component == "total") return energy_internal_;
    if (p.component == "external") return energy_external_;
    return 0.0;
  }
  return field_probe(p);
}

std::map<std::string, Real> EfgAnalysis::builtin_probes() const {
  if (!problem_.options.exact_displacement) return {};
  return {{"err_displacement", error_displacement_}, {"err_stress", error_stress_}};
}

OutputFrame EfgAnalysis::frame() const {
  OutputFrame f;
  f.points = problem_.cloud.positions;
  const Index n = problem_.cloud.size();
  if (node_displacement_.cols() != n) return f;
  auto add = [&](const std::string& name, int components, const Real* data) {
    f.point_fields.push_back(PointField{name, components, std::vector<Real>(data, data + components * n)});
  };
  add("displacement", 3, node_displacement_.data());
  add("strain", 6, node_strain_.data());
  add("stress", 6, node_stress_.data());
  std::vector<Real> vm(static_cast<std::size_t>(n)), id(static_cast<std::size_t>(n));
  for (Index i = 0; i < n; ++i) {
    vm[static_cast<std::size_t>(i)] = material::von_mises(node_stress_.col(i));
    id[static_cast<std::size_t>(i)] = node_material_[static_cast<std::size_t>(i)];
  }
  add("von_mises", 1, vm.data());
  add("material_id", 1, id.data());
  add("nodal_parameter", 3, u_.data());
  if (problem_.cloud.volumes.size() == n) add("volume", 1, problem_.cloud.volumes.data());
  return f;
}

RunCounts EfgAnalysis::counts() const {
  const Index n = problem_.cloud.size();
  return RunCounts{n, 3 * n + multipliers_.size(), 1};
}

}  // namespace lamina::efg
