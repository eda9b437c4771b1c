// EfgAnalysis: set-up (nodes, background cells and quadrature, MLS shape functions), materials,
// essential-condition points, loads, and the ordered stage list of the static analysis; warnings.
#include "efg/efg_analysis.hpp"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <set>

#include <fmt/format.h>

#include "core/error.hpp"
#include "core/step_stage.hpp"
#include "core/stopwatch.hpp"
#include "efg/collocation_system.hpp"
#include "efg/galerkin_assembly.hpp"
#include "efg/weighted_least_squares_system.hpp"
#include "geometry/body_maps.hpp"
#include "geometry/generators.hpp"
#include "mls/singular_moment_matrix.hpp"
#include "solve/block_pattern.hpp"

namespace lamina::efg {

namespace {


/// Boundary faces where a selection holds only in part are split into kSurfaceSplit^2 sub-faces.
constexpr int kSurfaceSplit = 8;

/// correction auto smooths curved cells that turn by at most this angle (35 degrees; docs/efg.md section 6:
/// a tube of 8 sectors, 45 degrees, is 9 % stiff with smoothed gradients, one of 12 sectors within 1.1 %).
constexpr Real largest_smoothed_turn = 35.0 * std::numbers::pi / 180.0;


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

}  // namespace

std::string to_string(EssentialMethod method) {
  switch (method) {
    case EssentialMethod::automatic: return "auto";
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

namespace {
/// Several ranks: the galerkin system is assembled in shares and solved by PETSc; the strong forms and
/// the Lagrange-multiplier system are computed whole on every rank (replicated: the same numbers).
const parallel::Communicator& working_communicator(const EfgProblem& problem, const parallel::Communicator& comm) {
  const auto& o = problem.options;
  const bool replicated = o.formulation != Formulation::galerkin || o.essential == EssentialMethod::lagrange;
  return comm.distributed() && replicated ? parallel::Communicator::single() : comm;
}
}  // namespace

EfgAnalysis::EfgAnalysis(EfgProblem problem, std::vector<Probe> probes, const parallel::Communicator& comm)
    : problem_(std::move(problem)), probes_(std::move(probes)), comm_(working_communicator(problem_, comm)) {
  problem_.options.solver.check_ranks(comm_.size());
  for (const auto& p : probes_) {
    const std::string where = "probes." + p.name;
    if (p.field == "displacement") {
      if (vector_component(p.component) < 0 && p.component != "magnitude")
        throw InputError(where + ".component", "x, y, z or magnitude for a displacement probe", p.component);
    } else if (p.field == "strain" || p.field == "stress") {
      if (tensor_component(p.component) < 0 && !(p.field == "stress" && p.component == "von_mises"))
        throw InputError(where + ".component",
                         fmt::format("xx, yy, zz, xy, yz, zx{} for a {} probe", p.field == "stress" ? " or von_mises" : "", p.field),
                         p.component);
    } else if (p.field == "reaction_force") {
      if (vector_component(p.component) < 0 && p.component != "magnitude")
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
  if (problem_.options.essential == EssentialMethod::automatic) {
    // Nitsche is consistent and does not lock; the surface penalty binds the shape functions at every face
    // Gauss point and locks on irregular nodes and thin or curved bodies (docs/efg.md sections 3, 6). Nitsche's
    // beta ~ lambda + 2 mu and its traction term would lock a nearly incompressible body, and its traction
    // is not the projected one: penalty there.
    bool nearly_incompressible = false;
    for (const auto& m : materials_) nearly_incompressible |= m.nu > 0.45;
    problem_.options.essential = problem_.options.formulation == Formulation::galerkin && !nearly_incompressible &&
                                         !problem_.options.projected_volumetric
                                     ? EssentialMethod::nitsche
                                     : EssentialMethod::penalty;
  }
  timings_["essential_nitsche"] = problem_.options.essential == EssentialMethod::nitsche ? 1.0 : 0.0;
  if (problem_.options.projected_volumetric) {
    if (problem_.options.formulation != Formulation::galerkin)
      throw InputError("efg.integration.volumetric", "full with a strong-form formulation (projected is a Galerkin option)",
                       "projected");
    if (problem_.options.essential == EssentialMethod::nitsche)
      throw InputError("efg.essential_bc",
                       "penalty, penalty_nodes or lagrange with volumetric: projected (Nitsche's consistency term "
                       "uses the unprojected stress)",
                       "nitsche");
    if (problem_.options.correction == IntegrationCorrection::vci ||
        problem_.options.correction == IntegrationCorrection::smoothed)
      throw InputError("efg.integration.correction", "none with volumetric: projected (no correction is combined with it)",
                       problem_.options.correction == IntegrationCorrection::vci ? "vci" : "smoothed");
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
  if (problem_.options.correction == IntegrationCorrection::automatic) {
    // Gauss points are consistent (patch test to round-off) only when the nodes are the cells' own grid and
    // the cells are not curved; elsewhere the smoothed gradients are (docs/efg.md section 6), except on
    // coarse curved cells: where a cell turns by more than 35 degrees (a polar grid of 8 sectors), 2 x 2 face
    // points under-resolve the shape functions across a face and plain Gauss points are the closer.
    bool on_grid = cloud.parametric.cols() == n;
    for (Index i = 0; on_grid && i < n; ++i)
      on_grid = (cloud.positions.col(i) - cells_->map.position(cloud.parametric.col(i))).norm() <= 1e-9 * size;
    const Real turn = largest_cell_turn(*cells_);
    const bool curved = turn > 1e-6;
    const auto& o = problem_.options;
    // (with the N nearest nodes as neighbours the shape functions jump where the set changes, and the
    // face sums of neighbouring cells would not cancel)
    const bool can_smooth = o.formulation == Formulation::galerkin && !o.projected_volumetric &&
                            *std::min_element(o.gauss.begin(), o.gauss.end()) >= 2 &&
                            o.mls.mode != mls::SupportMode::nearest && o.mls.mode != mls::SupportMode::variable;
    const bool smooth = can_smooth && (!on_grid || (curved && turn <= largest_smoothed_turn));
    problem_.options.correction = smooth ? IntegrationCorrection::smoothed : IntegrationCorrection::none;
    if (smooth)
      notices_.push_back(!on_grid ? "efg.integration.correction: auto chose smoothed gradients (the nodes are not the background "
                                    "cells' grid: jittered or irregular; docs/efg.md section 6)"
                                  : "efg.integration.correction: auto chose smoothed gradients (curved background cells; "
                                    "docs/efg.md section 6)");
  }
  timings_["integration_smoothed"] = problem_.options.correction == IntegrationCorrection::smoothed ? 1.0 : 0.0;
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
  // Points other than the volume Gauss points (conditions, surface loads, the smoothing's face points, the
  // nodes, probes) include the body's edges and corners, where a box of kappa 2 on a polar layout holds two
  // node rings only (the third sits on the support's edge): there the support grows until A is regular
  // (the seed's SINCHECK). The volume Gauss points keep the case's setting (a support too small there is
  // an input error).
  grow_at_points_ = problem_.options.formulation == Formulation::galerkin;
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

SelectorFactory EfgAnalysis::surface_selector(const model::Selection& region, Real tolerance) const {
  return [this, &region, tolerance] {
    auto test = std::make_shared<const RegionTest>(region, &cells_->map, [this](const Vec3& x) { return nearest_node(x); },
                                                   tolerance);
    return std::function<bool(const Vec3&, int)>([test](const Vec3& x, int face) { return test->on_surface(x, face); });
  };
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
    if (!c.constrains(0) && !c.constrains(1) && !c.constrains(2)) continue;
    std::array<std::unique_ptr<geometry::FieldEvaluator>, 3> value;
    for (int a = 0; a < 3; ++a) value[static_cast<std::size_t>(a)] = std::make_unique<geometry::FieldEvaluator>(c.displacement_of(a), 1.0);
    auto prescribed = [&](const Vec3& x) {
      Vec3 v = Vec3::Zero();
      for (int a = 0; a < 3; ++a)
        if (c.constrains(a)) v[a] = (*value[static_cast<std::size_t>(a)])(x);
      return v;
    };
    bool any_surface = false;
    if (surface_methods) {
      RegionTest test(c.select, &cells_->map, [this](const Vec3& x) { return nearest_node(x); }, tolerance);
      if (test.can_select_surface()) {
        const SurfaceQuadrature part = refine_selected_faces(*cells_, surface_, problem_.options.gauss, kSurfaceSplit,
                                                             surface_selector(c.select, tolerance));
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
          p.constrained = c.held();
          p.value = prescribed(x);
          constraint_points_.push_back(p);
          any_surface = true;
        }
      }
    }
    if (!any_surface) {
      for (Index node : c.select.nodes) {
        ConstraintPoint p;
        p.x = problem_.cloud.positions.col(node);
        p.weight = 1.0;
        p.material = std::max(material_at(p.x), 0);
        p.surface = false;
        p.condition = static_cast<int>(e);
        p.constrained = c.held();
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
    std::array<std::unique_ptr<geometry::FieldEvaluator>, 3> vec;
    for (int a = 0; a < 3; ++a) vec[static_cast<std::size_t>(a)] = std::make_unique<geometry::FieldEvaluator>(load.vector[static_cast<std::size_t>(a)], 1.0);
    auto vector_at = [&](const Vec3& x) {
      return Vec3((*vec[0])(x), (*vec[1])(x), (*vec[2])(x));
    };
    RegionTest test(load.select, &cells_->map, [this](const Vec3& x) { return nearest_node(x); }, tolerance);
    switch (load.kind) {
      case model::Load::Kind::force: {
        if (problem_.options.formulation != Formulation::galerkin)
          throw InputError(load.select.label,
                           fmt::format("traction, pressure or body_force with formulation: {} (the strong form has no "
                                       "point forces: spread the force as a traction over a face, or use formulation: "
                                       "galerkin)",
                                       to_string(problem_.options.formulation)),
                           "force");
        const Real share = 1.0 / static_cast<Real>(load.select.nodes.size());
        for (Index node : load.select.nodes) {
          const Vec3 x = problem_.cloud.positions.col(node);
          point_loads_.push_back({x, share * vector_at(x)});
        }
        break;
      }
      case model::Load::Kind::traction:
      case model::Load::Kind::pressure: {
        geometry::FieldEvaluator pressure(load.scalar, 1.0);
        bool any = false;
        if (test.can_select_surface()) {
          const SurfaceQuadrature part = refine_selected_faces(*cells_, surface_, problem_.options.gauss, kSurfaceSplit,
                                                               surface_selector(load.select, tolerance));
          for (Index s = 0; s < part.size(); ++s) {
            const Vec3 x = part.points.col(s);
            const Vec3 t = load.kind == model::Load::Kind::traction ? vector_at(x) : Vec3(-pressure(x) * part.normals.col(s));
            point_loads_.push_back({x, part.weights[s] * t});
            any = true;
          }
        }
        if (!any)
          throw InputError(load.select.label,
                           "a selection that holds on part of the body's boundary surface (traction and pressure are "
                           "integrated over the boundary faces where the selection holds)",
                           load.select.spec.describe() + " holds at no boundary quadrature point");
        break;
      }
      case model::Load::Kind::body_force: {
        if (body_force_.cols() != volume_.size()) body_force_ = Eigen::Matrix3Xd::Zero(3, volume_.size());
        for (Index q = 0; q < volume_.size(); ++q) {
          const Vec3 x = volume_.points.col(q);
          if (test.in_volume(x)) body_force_.col(q) += vector_at(x);
        }
        break;
      }
      default:  // moment, edge_moment, mass, initial_velocity: not efg loads (refused when the case is read)
        break;
    }
  }
}

std::vector<StepStage> EfgAnalysis::stages(OutputSink* sink) {
  std::vector<StepStage> list{{"setup",
                               [this, sink] {
                                 if (sink) sink->progress(0.0, "setup");
                                 setup();
                               }},
                              {"materials", [this] { assign_materials(); }},
                              {"constraints", [this] { build_constraints(); }},
                              {"loads", [this] { build_loads(); }}};
  if (problem_.options.formulation == Formulation::galerkin) {
    list.insert(list.end(), {{"assemble",
                              [this, sink] {
                                if (sink) sink->progress(0.1, "quadrature");
                                assemble_galerkin(sink);
                              }},
                             {"linear_solve", [this, sink] { solve_galerkin(sink); }},
                             {"energy", [this] { galerkin_energies(); }}});
  } else {
    list.push_back({"strong_form", [this, sink] {
                      if (sink) sink->progress(0.1, "quadrature");
                      solve_strong_form(sink);
                    }});
  }
  list.push_back({"post", [this] { postprocess(); }});
  return list;
}

void EfgAnalysis::run_static(OutputSink* sink) {
  const auto start = Clock::now();
  grown_boundary_points_ = 0;
  const std::vector<StepStage> list = stages(sink);
  std::vector<Real> seconds(list.size(), 0.0);
  try {
    run_stages(list, seconds);
  } catch (const mls::SingularMomentMatrix& e) {
    support_too_small(e, problem_.options.mls);
  } catch (const geometry::ExpressionError& e) {
    throw InputError("efg", "valid expressions in selections and prescribed values", e.what());
  }
  for (std::size_t k = 0; k < list.size(); ++k) timings_[std::string(list[k].name) + "_s"] = seconds[k];
  timings_["boundary_points_grown"] = static_cast<Real>(grown_boundary_points_);
  if (grown_boundary_points_ > 0 && !problem_.options.mls.singular_remedy)
    notices_.push_back(fmt::format("efg: at {} point(s) off the volume Gauss points (conditions, loads, smoothing's face "
                                   "points, nodes) the moment matrix was singular with the case's support; there the support "
                                   "grew until it was regular (the seed's SINCHECK; docs/efg.md section 6)",
                                   grown_boundary_points_));
  if (!u_.allFinite()) throw AnalysisError("the EFG solution contains non-finite values");
  solved_ = true;
  timings_["total_s"] = seconds_since(start);
}

void EfgAnalysis::solve() { run_static(nullptr); }

void EfgAnalysis::run(OutputSink& sink) {
  run_static(&sink);
  for (const auto& text : notices_) sink.notice(text);
  sink.progress(1.0, "done");
  sink.output_point(1, 1.0, 1.0);
}

Real EfgAnalysis::quadrature_volume() const { return volume_.weights.sum(); }

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
  // which factorisation: CHOLMOD (sparse) or dense (a small, nearly full K); both Cholesky
  timings_["solver_cholmod"] = solver_report_.method == "cholmod_supernodal_llt" ? 1.0 : 0.0;
  timings_["solver_dense"] = solver_report_.method == "dense_llt" ? 1.0 : 0.0;
}

}  // namespace lamina::efg
