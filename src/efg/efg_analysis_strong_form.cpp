// EfgAnalysis: the strong-form formulations (efg.formulation collocation / weighted_least_squares,
// seed 004 section 1.2.2 (2) and (5)). Node classification, assembly and solve live in
// strong_form_residuals.hpp, collocation_system.hpp and weighted_least_squares_system.hpp.
#include <algorithm>
#include <chrono>
#include <cmath>

#include <fmt/format.h>

#include "core/error.hpp"
#include "core/stopwatch.hpp"
#include "efg/background_quadrature.hpp"
#include "efg/collocation_system.hpp"
#include "efg/efg_analysis.hpp"
#include "efg/nodal_field.hpp"
#include "efg/weighted_least_squares_system.hpp"

namespace lamina::efg {

namespace {

/// Fraction of the way from a boundary node towards its face's centre at which a load's selection
/// is tested: an edge node then belongs to a face's load only if the selection holds on that face
/// itself (a `where: x > 4 - 1e-9` load holds on the face x = 4, not on the side faces it touches).
constexpr Real kFaceNudge = 1e-3;

}  // namespace

std::vector<StrongFormPoint> EfgAnalysis::strong_form_nodes() const {
  const PointCloud& cloud = problem_.cloud;
  const Index n = cloud.size();
  const geometry::VolumeMap& map = cells_->map;
  if (cloud.parametric.cols() != n)
    throw InputError("discretization.nodes",
                     "generated nodes with parametric coordinates (collocation and weighted_least_squares find the "
                     "boundary faces of a node from them)",
                     "nodes without parametric coordinates");
  const Vec3 lower = cloud.positions.rowwise().minCoeff(), upper = cloud.positions.rowwise().maxCoeff();
  const Real tolerance = 1e-9 * (upper - lower).norm();
  auto nearest = [this](const Vec3& x) { return nearest_node(x); };

  std::vector<StrongFormPoint> points(static_cast<std::size_t>(n));
  Vec3 lo_box, hi_box, mid;
  for (int d = 0; d < 3; ++d) {
    lo_box[d] = map.axes[static_cast<std::size_t>(d)].lo;
    hi_box[d] = map.axes[static_cast<std::size_t>(d)].hi;
  }
  mid = 0.5 * (lo_box + hi_box);
  const Vec3 step = 1e-4 * (hi_box - lo_box);
  std::vector<std::vector<int>> faces(static_cast<std::size_t>(n));
  std::vector<std::vector<Vec3>> face_centres(static_cast<std::size_t>(n));
  for (Index i = 0; i < n; ++i) {
    StrongFormPoint& p = points[static_cast<std::size_t>(i)];
    p.x = cloud.positions.col(i);
    p.material = std::max(material_at(p.x), 0);
    const Vec3 u = cloud.parametric.col(i);
    for (int d = 0; d < 3; ++d) {
      const auto& axis = map.axes[static_cast<std::size_t>(d)];
      if (axis.periodic) continue;
      for (int side = 0; side < 2; ++side) {
        const Real bound = side == 0 ? axis.lo : axis.hi;
        if (std::abs(u[d] - bound) > 1e-9 * (axis.hi - axis.lo)) continue;
        const int a = (d + 1) % 3, b = (d + 2) % 3;
        // the normal a hair inside the face (tangential directions only): defined also where the
        // face meets a collapsed axis (the centre node of a solid cylinder's end face)
        Vec3 inside = u;
        for (int t : {a, b})
          if (!map.axes[static_cast<std::size_t>(t)].periodic) inside[t] += 1e-6 * (mid[t] - u[t]);
        const Mat3 J = map_jacobian(map, inside, step);
        const Vec3 cross = J.col(a).cross(J.col(b));
        const Real area = cross.norm();
        if (!(area > 1e-12 * (J.col(a).norm() + 1e-300) * (J.col(b).norm() + 1e-300))) continue;  // collapsed face
        Vec3 normal = cross / area;
        const Real orientation = normal.dot(J.col(d));
        if ((side == 1 && orientation < 0) || (side == 0 && orientation > 0)) normal = -normal;
        p.face_normals.push_back(normal);
        p.face_tractions.push_back(Vec3::Zero());
        faces[static_cast<std::size_t>(i)].push_back(2 * d + side);
        Vec3 centre = mid;
        centre[d] = bound;
        for (int t : {a, b})
          if (map.axes[static_cast<std::size_t>(t)].periodic) centre[t] = u[t];
        face_centres[static_cast<std::size_t>(i)].push_back(map.position(centre));
      }
    }
  }

  // essential conditions at their selected nodes (a later condition overrides an earlier one per component)
  for (const auto& c : problem_.constraints) {
    std::array<std::unique_ptr<geometry::FieldEvaluator>, 3> value;
    for (int a = 0; a < 3; ++a) value[static_cast<std::size_t>(a)] = std::make_unique<geometry::FieldEvaluator>(c.displacement_of(a), 1.0);
    for (Index node : c.select.nodes) {
      StrongFormPoint& p = points[static_cast<std::size_t>(node)];
      for (int a = 0; a < 3; ++a)
        if (c.constrains(a)) {
          p.constrained[static_cast<std::size_t>(a)] = true;
          p.value[a] = (*value[static_cast<std::size_t>(a)])(p.x);
        }
    }
  }

  // tractions on the faces of boundary nodes, body forces at all nodes
  for (const auto& load : problem_.loads) {
    RegionTest test(load.select, &map, nearest, tolerance);
    std::array<std::unique_ptr<geometry::FieldEvaluator>, 3> vec;
    for (int a = 0; a < 3; ++a) vec[static_cast<std::size_t>(a)] = std::make_unique<geometry::FieldEvaluator>(load.vector[static_cast<std::size_t>(a)], 1.0);
    geometry::FieldEvaluator pressure(load.scalar, 1.0);
    bool any = false;
    for (Index i = 0; i < n; ++i) {
      StrongFormPoint& p = points[static_cast<std::size_t>(i)];
      if (load.kind == model::Load::Kind::body_force) {
        if (test.in_volume(p.x)) p.body_force += Vec3((*vec[0])(p.x), (*vec[1])(p.x), (*vec[2])(p.x));
        continue;
      }
      for (std::size_t f = 0; f < p.face_normals.size(); ++f) {
        const Vec3 inside = p.x + kFaceNudge * (face_centres[static_cast<std::size_t>(i)][f] - p.x);
        if (!test.on_surface(inside, faces[static_cast<std::size_t>(i)][f])) continue;
        any = true;
        if (load.kind == model::Load::Kind::traction) p.face_tractions[f] += Vec3((*vec[0])(p.x), (*vec[1])(p.x), (*vec[2])(p.x));
        else p.face_tractions[f] -= pressure(p.x) * p.face_normals[f];
      }
    }
    if (!any && load.kind != model::Load::Kind::body_force)
      throw InputError(load.select.label,
                       "a selection that holds on a boundary face at some node (collocation and weighted least "
                       "squares impose tractions at the boundary nodes)",
                       load.select.spec.describe() + " holds on no boundary face at a node");
  }
  return points;
}

void EfgAnalysis::solve_strong_form(OutputSink* sink) {
  const Index n = problem_.cloud.size();
  const auto& options = problem_.options;
  const bool collocation = options.formulation == Formulation::collocation;
  auto progress = [&](Real fraction, const std::string& status) {
    if (sink) sink->progress(fraction, status);
  };

  auto start = Clock::now();
  std::vector<StrongFormPoint> points = strong_form_nodes();
  require_no_free_rigid_body_motion(points);
  if (!collocation && options.least_squares.cell_centre_points) {
    for (Index c = 0; c < cells_->size(); ++c) {
      Vec3 lo, hi;
      cells_->bounds(c, lo, hi);
      StrongFormPoint p;
      p.x = cells_->map.position(0.5 * (lo + hi));
      p.material = std::max(material_at(p.x), 0);
      points.push_back(p);
    }
    // body forces at the auxiliary points
    const Vec3 lower = problem_.cloud.positions.rowwise().minCoeff(), upper = problem_.cloud.positions.rowwise().maxCoeff();
    for (const auto& load : problem_.loads) {
      if (load.kind != model::Load::Kind::body_force) continue;
      RegionTest test(load.select, &cells_->map, [this](const Vec3& x) { return nearest_node(x); },
                      1e-9 * (upper - lower).norm());
      std::array<std::unique_ptr<geometry::FieldEvaluator>, 3> vec;
      for (int a = 0; a < 3; ++a) vec[static_cast<std::size_t>(a)] = std::make_unique<geometry::FieldEvaluator>(load.vector[static_cast<std::size_t>(a)], 1.0);
      for (std::size_t i = static_cast<std::size_t>(n); i < points.size(); ++i)
        if (test.in_volume(points[i].x)) points[i].body_force += Vec3((*vec[0])(points[i].x), (*vec[1])(points[i].x), (*vec[2])(points[i].x));
    }
  }
  PointMatrix x(3, static_cast<Index>(points.size()));
  for (std::size_t i = 0; i < points.size(); ++i) x.col(static_cast<Index>(i)) = points[i].x;
  const auto shapes = shapes_->evaluate_all(x, 2);
  timings_["neighbours_s"] = seconds_since(start);
  progress(0.2, "shape functions");

  start = Clock::now();
  std::vector<PointResiduals> residuals(points.size());
  std::vector<std::string> failures(points.size());
#pragma omp parallel for schedule(static)
  for (Index i = 0; i < static_cast<Index>(points.size()); ++i) {
    const auto& p = points[static_cast<std::size_t>(i)];
    const auto& mat = materials_[static_cast<std::size_t>(p.material)];
    try {
      residuals[static_cast<std::size_t>(i)] = collocation ? collocation_residuals(p, shapes[static_cast<std::size_t>(i)], mat)
                                                           : least_squares_residuals(p, shapes[static_cast<std::size_t>(i)], mat);
    } catch (const std::exception& e) {
      failures[static_cast<std::size_t>(i)] = e.what();
    }
  }
  for (const auto& f : failures)
    if (!f.empty()) throw AnalysisError(f);
  timings_["assembly_s"] = seconds_since(start);
  progress(0.5, "residual rows");

  start = Clock::now();
  Index equations = 3 * n;
  if (collocation) {
    u_ = solve_collocation(residuals, solver_report_);
  } else {
    LeastSquaresWeights w;
    w.traction = options.least_squares.traction_weight;
    if (options.least_squares.displacement_weight) {
      w.displacement = *options.least_squares.displacement_weight;
    } else {
      for (const auto& m : materials_) w.displacement = std::max(w.displacement, seed_displacement_weight(w.traction, m));
    }
    timings_["wlsm_traction_weight"] = w.traction;
    timings_["wlsm_displacement_weight"] = w.displacement;
    u_ = solve_weighted_least_squares(residuals, n, w, solver_report_, equations);
    timings_["assembly_normal_equations_s"] = solver_report_.factor_seconds < 0 ? 0.0 : seconds_since(start) - solver_report_.factor_seconds - solver_report_.solve_seconds;
  }
  timings_["dofs"] = static_cast<Real>(3 * n);
  timings_["equations"] = static_cast<Real>(equations);
  timings_["nonzeros"] = static_cast<Real>(solver_report_.nonzeros);
  record_solver_report();
  timings_["solve_total_s"] = seconds_since(start);
  if (!u_.allFinite())
    throw AnalysisError(fmt::format("the {} solution contains non-finite values; use a larger support (kappa 2.5 to 3)",
                                    to_string(options.formulation)));
  progress(0.9, "solved (" + solver_report_.method + ")");

  start = Clock::now();
  strong_form_reactions_and_energies();
  timings_["energy_s"] = seconds_since(start);
}

void EfgAnalysis::strong_form_reactions_and_energies() {
  // reactions: the traction sigma(u^h) n on the constrained surface (surface constraint points);
  // point constraints (`nearest` selections) get none in the strong form
  PointMatrix cx(3, static_cast<Index>(constraint_points_.size()));
  for (std::size_t i = 0; i < constraint_points_.size(); ++i) cx.col(static_cast<Index>(i)) = constraint_points_[i].x;
  const auto constraint_shapes = shapes_->evaluate_all(cx, 1);
  reactions_.assign(constraint_points_.size(), Vec3::Zero());
  constraint_nearest_.assign(constraint_points_.size(), 0);
  Real reaction_work = 0.0;
  for (std::size_t i = 0; i < constraint_points_.size(); ++i) {
    const auto& p = constraint_points_[i];
    constraint_nearest_[i] = nearest_node(p.x);
    if (!p.surface) continue;
    const auto& mat = materials_[static_cast<std::size_t>(p.material)];
    const Vec3 t = material::traction(mat.stress(material::strain_from_gradient(gradient_of(constraint_shapes[i], u_))), p.normal);
    for (int a = 0; a < 3; ++a)
      if (p.constrained[static_cast<std::size_t>(a)]) reactions_[i][a] = p.weight * t[a];
    reaction_work += reactions_[i].dot(p.value);
  }
  // strain energy over the background quadrature; work of the applied loads
  const auto volume_shapes = shapes_->evaluate_all(volume_.points, 1);
  Real internal = 0.0, load_work = 0.0;
  for (Index q = 0; q < volume_.size(); ++q) {
    const auto& sv = volume_shapes[static_cast<std::size_t>(q)];
    const auto& mat = materials_[static_cast<std::size_t>(material_of_point_[static_cast<std::size_t>(q)])];
    internal += volume_.weights[q] * mat.energy_density(material::strain_from_gradient(gradient_of(sv, u_)));
    if (body_force_.cols() == volume_.size()) load_work += volume_.weights[q] * body_force_.col(q).dot(value_of(sv, u_));
  }
  PointMatrix lx(3, static_cast<Index>(point_loads_.size()));
  for (std::size_t i = 0; i < point_loads_.size(); ++i) lx.col(static_cast<Index>(i)) = point_loads_[i].x;
  const auto load_shapes = shapes_->evaluate_all(lx, 0);
  for (std::size_t i = 0; i < point_loads_.size(); ++i) load_work += point_loads_[i].force.dot(value_of(load_shapes[i], u_));
  energy_internal_ = internal;
  energy_external_ = 0.5 * (load_work + reaction_work);
}

}  // namespace lamina::efg
