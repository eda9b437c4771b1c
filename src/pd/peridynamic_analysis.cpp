#include "pd/peridynamic_analysis.hpp"

#include <fmt/format.h>

#include <Eigen/CholmodSupport>
#include <Spectra/MatOp/SparseSymMatProd.h>
#include <Spectra/SymGEigsSolver.h>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>

#include "core/error.hpp"
#include "material/linear_elastic.hpp"
#include "pd/load_path_events.hpp"
#include "pd/peridynamic_plate.hpp"
#include "pd/zero_energy_check.hpp"

namespace lamina::pd {

namespace {

using Clock = std::chrono::steady_clock;
Real seconds_since(Clock::time_point t) { return std::chrono::duration<Real>(Clock::now() - t).count(); }

/// The free-free part of a symmetric matrix stored as its upper triangle (free dofs renumbered in order).
solve::SparseMatrix reduce_upper(const solve::SparseMatrix& upper, const std::vector<Index>& map, Index free_count) {
  std::vector<Eigen::Triplet<Real, int>> entries;
  entries.reserve(static_cast<std::size_t>(upper.nonZeros()));
  for (Index col = 0; col < upper.outerSize(); ++col) {
    const Index c = map[static_cast<std::size_t>(col)];
    if (c < 0) continue;
    for (solve::SparseMatrix::InnerIterator it(upper, col); it; ++it) {
      const Index r = map[static_cast<std::size_t>(it.row())];
      if (r >= 0) entries.emplace_back(static_cast<int>(r), static_cast<int>(c), it.value());
    }
  }
  solve::SparseMatrix reduced(free_count, free_count);
  reduced.setFromTriplets(entries.begin(), entries.end());
  return reduced;
}

/// B-operator of Spectra's regular-inverse mode for B = K0 (symmetric positive definite, given by its
/// upper triangle): CHOLMOD's supernodal Cholesky for y = B^-1 x, the symmetric product for y = B x.
class CholmodRegularInverse {
 public:
  using Scalar = Real;
  explicit CholmodRegularInverse(const solve::SparseMatrix& upper) : upper_(upper) {
    llt_.compute(upper_);
    ok_ = llt_.info() == Eigen::Success;
  }
  bool ok() const { return ok_; }
  Index rows() const { return upper_.rows(); }
  Index cols() const { return upper_.cols(); }
  void solve(const Scalar* x_in, Scalar* y_out) const {
    const Eigen::Map<const Eigen::VectorXd> x(x_in, rows());
    Eigen::Map<Eigen::VectorXd>(y_out, rows()) = llt_.solve(x);
  }
  void perform_op(const Scalar* x_in, Scalar* y_out) const {
    const Eigen::Map<const Eigen::VectorXd> x(x_in, rows());
    Eigen::Map<Eigen::VectorXd>(y_out, rows()).noalias() = upper_.selfadjointView<Eigen::Upper>() * x;
  }

 private:
  const solve::SparseMatrix& upper_;
  Eigen::CholmodSupernodalLLT<solve::SparseMatrix, Eigen::Upper> llt_;
  bool ok_ = false;
};

const std::vector<std::string> vector_components{"x", "y", "z", "magnitude"};
const std::vector<std::string> tensor_components{"xx", "yy", "zz", "xy", "yz", "zx", "von_mises"};

}  // namespace

PeridynamicAnalysis::PeridynamicAnalysis(PeridynamicProblem problem, std::vector<Probe> probes)
    : problem_(std::move(problem)), probes_(std::move(probes)) {
  for (std::size_t k = 0; k < probes_.size(); ++k) {
    const Probe& p = probes_[k];
    const std::string where = fmt::format("probes.{}", k);
    auto in = [](const std::vector<std::string>& list, const std::string& s) {
      return std::find(list.begin(), list.end(), s) != list.end();
    };
    if (p.field == "displacement" || p.field == "velocity") {
      if (!in(vector_components, p.component)) throw InputError(where + ".component", "x, y, z or magnitude", p.component);
      if (!p.at && p.nodes.empty()) throw InputError(where + ".at", "a point (at: [x, y, z]) or a set", "none");
    } else if (p.field == "strain" || p.field == "stress") {
      if (!in(tensor_components, p.component) || (p.field == "strain" && p.component == "von_mises"))
        throw InputError(where + ".component", "xx, yy, zz, xy, yz or zx (stress also von_mises)", p.component);
      if (!p.at && p.nodes.empty()) throw InputError(where + ".at", "a point (at: [x, y, z]) or a set", "none");
    } else if (p.field == "reaction_force") {
      if (!in(vector_components, p.component)) throw InputError(where + ".component", "x, y, z or magnitude", p.component);
      if (p.nodes.empty()) throw InputError(where + ".select", "a selection of nodes for a reaction_force probe", "none");
    } else if (p.field == "energy") {
      if (!in({"internal", "kinetic", "external", "total", "damping"}, p.component))
        throw InputError(where + ".component", "internal, kinetic, external, total or damping", p.component);
    } else if (p.field == "eigenvalue" || p.field == "critical_load") {
      if (p.field == "critical_load" && p.nodes.empty())
        throw InputError(where + ".select", "a selection of the loaded (or displaced) nodes for a critical_load probe", "none");
      int k = 0;
      try {
        k = std::stoi(p.component);
      } catch (...) {
      }
      if (k < 1 || k > problem_.buckling.modes || problem_.analysis != PdAnalysisKind::buckling)
        throw InputError(where + ".component",
                         fmt::format("a mode number 1..{} of a buckling analysis (pd.analysis: buckling)", problem_.buckling.modes),
                         p.component);
    } else {
      throw InputError(where + ".field",
                       "displacement, velocity, strain, stress, reaction_force, energy, eigenvalue or critical_load", p.field);
    }
  }
  const auto start = Clock::now();
  PointMatrix positions = problem_.positions;
  const auto& imperfection = problem_.imperfection;
  auto scaled = [&](const PointMatrix& shape) {
    const Real largest = shape.colwise().norm().maxCoeff();
    if (!(largest > 0)) throw InputError("imperfection", "a non-zero imperfection shape", "a zero field");
    return PointMatrix(shape * (imperfection.amplitude / largest));
  };
  if (imperfection.kind == Imperfection::Kind::shape) positions += scaled(imperfection.shape);
  build_body(positions);
  if (imperfection.kind == Imperfection::Kind::buckling_mode) {
    buckling_modes(imperfection.mode);
    positions += scaled(modes_[static_cast<std::size_t>(imperfection.mode - 1)]);
    build_body(positions);
    imperfection_load_factor_ = eigenvalues_.empty() ? 0.0 : eigenvalues_.front();
    eigenvalues_.clear();
    modes_.clear();
  }
  const Index n = body_->nodes();
  u_ = PointMatrix::Zero(3, n);
  velocity_ = PointMatrix::Zero(3, n);
  internal_force_ = PointMatrix::Zero(3, n);
  external_force_ = PointMatrix::Zero(3, n);
  state_ = model_->state_of(u_);
  timings_["setup_s"] = seconds_since(start);
}

void PeridynamicAnalysis::build_body(const PointMatrix& positions) {
  model_.reset();
  plate_columns_ = nullptr;
  const BodyOptions& options = problem_.body;
  std::optional<PlateColumns> columns;
  if (options.plate_model == PlateModel::automatic && options.kinematics == Kinematics::three_dimensional &&
      options.surface_correction != SurfaceCorrection::plate)
    columns = find_plate_columns(problem_.positions, problem_.volumes, &model_reason_);
  if (columns) {
    // the node body only serves the strain probes (families, no calibration)
    BodyOptions probe_options = options;
    probe_options.surface_correction = SurfaceCorrection::none;
    body_ = std::make_unique<PeridynamicBody>(positions, problem_.volumes, problem_.young, problem_.poisson, probe_options);
    auto plate = std::make_unique<PeridynamicPlate>(std::move(*columns), positions, problem_.positions, problem_.volumes,
                                                    problem_.young, problem_.poisson, options);
    plate_columns_ = &plate->columns();
    model_ = std::move(plate);
  } else {
    body_ = std::make_unique<PeridynamicBody>(positions, problem_.volumes, problem_.young, problem_.poisson, options);
    model_ = std::make_unique<LinearPeridynamicSolid>(*body_);
  }
}

Real PeridynamicAnalysis::ramp(int index, Real factor) const {
  return index < 0 ? factor : problem_.ramps[static_cast<std::size_t>(index)].factor(factor);
}

PointMatrix PeridynamicAnalysis::external_force(Real factor) const {
  PointMatrix f = PointMatrix::Zero(3, body_->nodes());
  for (const auto& load : problem_.forces) f.col(load.node) += load.force * ramp(load.ramp, factor);
  return f;
}

void PeridynamicAnalysis::apply_prescribed(PointMatrix& u, Real factor, bool velocities) const {
  for (const auto& p : problem_.prescribed)
    if (p.velocity == velocities) u(p.component, p.node) = p.value * ramp(p.ramp, factor);
}

std::vector<char> PeridynamicAnalysis::free_dofs(bool include_velocity) const {
  std::vector<char> free(static_cast<std::size_t>(3 * body_->nodes()), 1);
  for (const auto& p : problem_.prescribed)
    if (!p.velocity || include_velocity) free[static_cast<std::size_t>(3 * p.node + p.component)] = 0;
  if (body_->dimension() == 2)
    for (Index i = 0; i < body_->nodes(); ++i) free[static_cast<std::size_t>(3 * i + 2)] = 0;
  return free;
}

void PeridynamicAnalysis::solve() {
  struct NullSink : OutputSink {
    void output_point(Index, Real, Real) override {}
    void progress(Real, const std::string&) override {}
  } sink;
  run(sink);
}

void PeridynamicAnalysis::run(OutputSink& sink) {
  const auto start = Clock::now();
  switch (problem_.analysis) {
    case PdAnalysisKind::linear_static: run_linear_static(&sink); break;
    case PdAnalysisKind::quasi_static: run_quasi_static(&sink); break;
    case PdAnalysisKind::explicit_dynamics: run_explicit(&sink); break;
    case PdAnalysisKind::buckling: run_buckling(&sink); break;
  }
  timings_["solve_s"] = seconds_since(start);
}

PointMatrix PeridynamicAnalysis::linear_solution(solve::SparseMatrix& k0_upper, bool check) {
  const Index n = body_->nodes();
  k0_upper = model_->stiffness(*model_->state_of(PointMatrix::Zero(3, n), true), true, false);
  if (check) check_unloaded_stiffness(k0_upper);
  const std::vector<char> free = free_dofs(true);
  std::vector<Index> map(free.size(), -1);
  Index count = 0;
  for (std::size_t d = 0; d < free.size(); ++d)
    if (free[d]) map[d] = count++;
  PointMatrix u = PointMatrix::Zero(3, n);
  apply_prescribed(u, 1.0, false);
  const PointMatrix f = external_force(1.0);
  const Eigen::Map<const Eigen::VectorXd> uc(u.data(), u.size()), fv(f.data(), f.size());
  const Eigen::VectorXd rhs_full = fv - solve::multiply_symmetric_upper(k0_upper, uc);
  Eigen::VectorXd rhs(count);
  for (std::size_t d = 0; d < free.size(); ++d)
    if (map[d] >= 0) rhs[map[d]] = rhs_full[static_cast<Index>(d)];
  const solve::SparseMatrix reduced = reduce_upper(k0_upper, map, count);
  solve::SolverReport report;
  const Eigen::VectorXd x = solve::solve_symmetric(reduced, rhs, report);
  timings_["factor_s"] = report.factor_seconds;
  for (std::size_t d = 0; d < free.size(); ++d)
    if (map[d] >= 0) u.data()[d] = x[map[d]];
  return u;
}

void PeridynamicAnalysis::check_unloaded_stiffness(const solve::SparseMatrix& k0_upper) {
  if (!problem_.check_zero_energy) return;
  const auto start = Clock::now();
  const std::vector<char> free = free_dofs(true);
  std::vector<Index> map(free.size(), -1), dofs;
  for (std::size_t d = 0; d < free.size(); ++d)
    if (free[d]) map[d] = static_cast<Index>(dofs.size()), dofs.push_back(static_cast<Index>(d));
  const ZeroEnergyReport r = find_zero_energy_modes(reduce_upper(k0_upper, map, static_cast<Index>(dofs.size())), dofs,
                                                    body_->positions());
  timings_["zero_energy_check_s"] = seconds_since(start);
  timings_["smallest_scaled_stiffness"] = r.smallest;
  if (!r.singular) return;
  const Vec3 x = r.node >= 0 ? Vec3(body_->positions().col(r.node)) : Vec3::Zero();
  if (r.rigid)
    throw InputError("boundary", "supports that hold every rigid-body motion of the body",
                     fmt::format("a free rigid-body motion of the unloaded body (largest at the node at ({:.4g}, {:.4g}, {:.4g}))",
                                 x.x(), x.y(), x.z()));
  throw InputError(
      "discretization.horizon", "a lattice and horizon whose unloaded stiffness has no zero-energy mode",
      fmt::format("a zero-energy mode of the {} model (smallest density-scaled stiffness eigenvalue {:.2g}, largest at the node at "
                  "({:.4g}, {:.4g}, {:.4g})): {}",
                  model_->name(), r.smallest, x.x(), x.y(), x.z(),
                  model_->name() == "plate"
                      ? "give the horizon at least 1.4 in-plane spacings"
                      : "use a horizon above the cell diagonal, or the plate model for a 2-4 layer plate (pd.plate_model: auto)"));
}

void PeridynamicAnalysis::run_linear_static(OutputSink* sink) {
  sink->output_point(0, 0.0, 0.0);
  solve::SparseMatrix k0;
  u_ = linear_solution(k0);
  state_ = model_->state_of(u_, true);
  internal_force_ = model_->internal_force(*state_);
  external_force_ = external_force(1.0);
  energy_internal_ = model_->strain_energy(*state_);
  // Clapeyron: 1/2 (f . u + reactions . prescribed displacements) = 1/2 sum (F_ext - F_int - F_ext) at constrained.
  const PointMatrix support = -(internal_force_ + external_force_);
  const std::vector<char> free = free_dofs(true);
  Real work = 0;
  for (Index d = 0; d < u_.size(); ++d)
    work += 0.5 * (external_force_.data()[d] + (free[static_cast<std::size_t>(d)] ? 0.0 : support.data()[d])) * u_.data()[d];
  energy_external_ = work;
  steps_ = 1;
  sink->output_point(1, 1.0, 1.0);
}

void PeridynamicAnalysis::run_quasi_static(OutputSink* sink) {
  const Index n = body_->nodes();
  const auto& options = problem_.relaxation;
  // Fictitious density from the reference stiffness (seed 002 eq (5)).
  solve::SparseMatrix k0;
  // Start field of the first increment: the linear solution (start: linear; a predictor only - the
  // relaxation decides the answer) or the interpolated prescribed values.
  PointMatrix linear_start;
  if (options.linear_start) {
    try {
      linear_start = linear_solution(k0);
    } catch (const AnalysisError&) {
      linear_start.resize(0, 0);  // singular reference stiffness: fall back to the interpolated start
    }
  }
  if (k0.rows() == 0) k0 = model_->stiffness(*model_->state_of(PointMatrix::Zero(3, n), true), true, false);
  if (!resumed_) check_unloaded_stiffness(k0);
  const std::vector<char> free = free_dofs(true);
  // ADR coordinates: the column modes on a plate lattice (relaxation_coordinates.hpp), else the nodes
  std::optional<RelaxationCoordinates> coordinates;
  if (plate_columns_ && options.coordinates == AdaptiveDynamicRelaxationOptions::Coordinates::columns)
    coordinates = column_coordinates(*plate_columns_, n, free);
  Eigen::VectorXd lambda = 0.25 * options.density_factor *
                           (coordinates ? generalised_absolute_row_sums(k0, *coordinates) : absolute_row_sums(k0));
  for (Index d = 0; d < lambda.size(); ++d)
    if (!(lambda[d] > 0)) {
      if (free[static_cast<std::size_t>(d)])
        throw AnalysisError(fmt::format("node {} has no stiffness in direction {} (isolated node?)", d / 3, d % 3));
      lambda[d] = 1.0;
    }
  AdaptiveDynamicRelaxation relaxation(*model_, lambda, free, options, coordinates ? &*coordinates : nullptr);
  if (!resumed_) sink->output_point(0, 0.0, 0.0);
  // Start field of the first increment: inverse-distance interpolation of the prescribed values.
  auto interpolated_start = [&](Real factor) {
    PointMatrix u = PointMatrix::Zero(3, n);
    std::array<std::vector<const PrescribedDof*>, 3> by_component;
    for (const auto& p : problem_.prescribed)
      if (!p.velocity) by_component[static_cast<std::size_t>(p.component)].push_back(&p);
#pragma omp parallel for schedule(static)
    for (Index i = 0; i < n; ++i)
      for (int a = 0; a < 3; ++a) {
        const auto& list = by_component[static_cast<std::size_t>(a)];
        if (list.empty() || !free[static_cast<std::size_t>(3 * i + a)]) continue;
        Real sw = 0, su = 0;
        for (const PrescribedDof* p : list) {
          const Real d2 = (body_->positions().col(p->node) - body_->positions().col(i)).squaredNorm();
          const Real w = 1.0 / (d2 * d2 + 1e-300);
          sw += w;
          su += w * p->value * ramp(p->ramp, factor);
        }
        u(a, i) = su / sw;
      }
    apply_prescribed(u, factor, false);
    return u;
  };
  const Real nominal = 1.0 / static_cast<Real>(options.increments);
  if (!resumed_) {
    quasi_ = QuasiStaticLoop{};
    quasi_.step = nominal;
    quasi_.previous = quasi_.before_previous = quasi_.third = PointMatrix::Zero(3, n);
    quasi_.generalized_force = PointMatrix::Zero(3, n);  // F_ext on free dofs, support force on prescribed ones
    energy_damping_ = 0;
    energy_external_ = 0;
  }
  Real &step = quasi_.step, &factor = quasi_.factor, &previous_factor = quasi_.previous_factor;
  PointMatrix &previous = quasi_.previous, &before_previous = quasi_.before_previous, &third = quasi_.third;
  Real& third_factor = quasi_.third_factor;
  bool &have_two = quasi_.have_two, &have_three = quasi_.have_three;
  using Predictor = AdaptiveDynamicRelaxationOptions::Predictor;
  int& cuts = quasi_.cuts;
  Index& increment = quasi_.increment;
  PointMatrix& generalized_force = quasi_.generalized_force;
  // Load path P(Delta) along the reference pattern g (the load at factor 1 or, displacement-controlled,
  // the prescribed field at factor 1): P = (F_generalized . g) / (g . g) G with G = |sum_i g_i| (the
  // total force of the pattern; half its absolute sum when it is self-equilibrated), Delta = g . u / G
  // (the mean displacement of the loaded nodes, or the shortening between two loaded ends), P Delta =
  // work; its stiffness changes are the buckling events.
  PointMatrix path_direction = external_force(1.0);
  for (Index d = 0; d < path_direction.size(); ++d)
    if (!free[static_cast<std::size_t>(d)]) path_direction.data()[d] = 0;
  if (path_direction.norm() == 0) {
    path_direction.setZero();
    apply_prescribed(path_direction, 1.0, false);
  }
  // a self-equilibrated pattern (equal and opposite end loads) transmits half its absolute sum
  path_total_ = path_direction.rowwise().sum().norm();
  const Real absolute_sum = path_direction.colwise().norm().sum();
  if (!(path_total_ > 1e-9 * absolute_sum)) path_total_ = 0.5 * absolute_sum;
  const Real path_norm2 = path_direction.squaredNorm();
  if (!resumed_) {
    path_load_.assign(1, 0.0);
    path_displacement_.assign(1, 0.0);
    total_iterations_ = 0;
  }
  while (factor < 1.0 - 1e-12) {
    const Real target = std::min(1.0, factor + step);
    // Stage 1: start field of the increment.
    PointMatrix u;
    if (factor == 0.0 && linear_start.size()) u = linear_start * target;
    else if (factor == 0.0) u = interpolated_start(target);
    else if (options.predictor == Predictor::quadratic && have_three) {
      // Lagrange extrapolation through the last three converged states
      const Real x0 = factor, x1 = previous_factor, x2 = third_factor;
      const Real l0 = (target - x1) * (target - x2) / ((x0 - x1) * (x0 - x2));
      const Real l1 = (target - x0) * (target - x2) / ((x1 - x0) * (x1 - x2));
      const Real l2 = (target - x0) * (target - x1) / ((x2 - x0) * (x2 - x1));
      u = l0 * previous + l1 * before_previous + l2 * third;
    } else if (options.predictor != Predictor::previous && have_two)
      u = previous + (target - factor) / (factor - previous_factor) * (previous - before_previous);
    else if (options.predictor != Predictor::previous) u = previous * (target / factor);
    else u = previous;
    apply_prescribed(u, target, false);
    // Stage 2: relax to equilibrium.
    const PointMatrix fext = external_force(target);
    RelaxationResult result = relaxation.relax(u, fext);
    total_iterations_ += result.iterations;
    // A snap-through under load control needs the fictitious dynamics to run on to the next stable
    // state: keep relaxing from where the block stopped (relative test against the increment's own
    // start residual) before giving the increment up.
    for (int block = 0; !result.converged && block < options.continuations && std::isfinite(result.residual); ++block) {
      const Real start = result.initial_residual, dissipated = result.damping_energy;
      const int used = result.iterations;
      result = relaxation.relax(u, fext, start);
      total_iterations_ += result.iterations;
      result.iterations += used;
      result.damping_energy += dissipated;
    }
    if (!result.converged) {
      if (++cuts > options.max_cuts)
        throw AnalysisError(fmt::format(
            "adaptive dynamic relaxation did not converge at load factor {:.6g} after {} increment cuts ({} iterations, "
            "residual {:.3e} of initial {:.3e})",
            target, options.max_cuts, result.iterations, result.residual, result.initial_residual));
      step *= 0.5;
      continue;
    }
    // Stage 3: accept the increment.
    ++increment;
    PointMatrix new_generalized = fext;
    for (Index d = 0; d < u.size(); ++d)
      if (!free[static_cast<std::size_t>(d)]) new_generalized.data()[d] = -result.internal_force.data()[d] - fext.data()[d] + fext.data()[d];
    energy_external_ += 0.5 * ((generalized_force + new_generalized).array() * (u - previous).array()).sum();
    generalized_force = new_generalized;
    have_three = have_two;
    third = before_previous;
    third_factor = previous_factor;
    before_previous = previous;
    have_two = factor > 0.0;
    previous_factor = factor;
    previous = u;
    factor = target;
    u_ = u;
    state_ = std::move(result.state);
    internal_force_ = std::move(result.internal_force);
    external_force_ = fext;
    energy_internal_ = model_->strain_energy(*state_);
    energy_damping_ += result.damping_energy;
    last_iterations_ = result.iterations;
    last_residual_ = result.residual;
    increment_iterations_.push_back(result.iterations);
    path_load_.push_back(path_norm2 > 0 ? path_direction.cwiseProduct(new_generalized).sum() / path_norm2 * path_total_ : 0.0);
    path_displacement_.push_back(path_total_ > 0 ? path_direction.cwiseProduct(u).sum() / path_total_ : 0.0);
    cuts = 0;
    steps_ = increment;
    sink->output_point(increment, factor, factor);
    sink->progress(factor, fmt::format("increment {} load factor {:.4f} iterations {}", increment, factor, result.iterations));
    step = std::min(nominal, 2.0 * step);
    sink->safe_point();
  }
}

void PeridynamicAnalysis::run_explicit(OutputSink* sink) {
  const Index n = body_->nodes();
  const auto& options = problem_.explicit_options;
  Eigen::VectorXd mass(3 * n);
  for (Index i = 0; i < n; ++i) mass.segment<3>(3 * i).setConstant(problem_.density[i] * problem_.volumes[i]);
  // Critical time step: Gershgorin bound of the largest eigenvalue of M^-1 K0. K0 reaches two
  // horizons (about 8 x family blocks per row); above ~2 GB it is not formed, and then the case
  // must give explicit.time_step (used unchecked).
  const Real k0_bytes = 8.0 * static_cast<Real>(body_->bonds()) * 9.0 * 12.0;
  Real dt = options.time_step;
  if (options.time_step <= 0 || k0_bytes < 2.0e9) {
    if (k0_bytes >= 2.0e9)
      throw AnalysisError(fmt::format(
          "explicit dynamics: the lattice ({} nodes, {} bonds) is too large to form the stiffness for the critical "
          "time step (~{:.1f} GB); give pd.explicit.time_step", n, body_->bonds(), k0_bytes / 1e9));
    const solve::SparseMatrix k0 = model_->stiffness(*model_->state_of(PointMatrix::Zero(3, n), true), true, false);
    const Eigen::VectorXd rows = absolute_row_sums(k0);
    const Real omega_max = std::sqrt((rows.array() / mass.array()).maxCoeff());
    const Real critical = 2.0 / omega_max;
    if (options.time_step <= 0) dt = options.safety_factor * critical;
    if (dt > critical)
      throw AnalysisError(fmt::format("explicit time step {:.4g} exceeds the critical step {:.4g}", dt, critical));
    timings_["critical_time_step"] = critical;
  }
  ExplicitLoop& loop = explicit_;
  Index steps = std::max<Index>(1, static_cast<Index>(std::ceil(options.end_time / dt - 1e-9)));
  dt = options.end_time / static_cast<Real>(steps);
  if (resumed_ && options.end_time != loop.end_time) {
    // a restart with another end time: the rest of the run, from the checkpoint's time, in steps of
    // at most the run's step
    const Real now = loop.origin_time + static_cast<Real>(loop.step - loop.origin_step) * loop.time_step;
    if (!(options.end_time > now))
      throw InputError("pd.explicit.end_time", fmt::format("an end time after the checkpoint's time {:.6g}", now),
                       fmt::format("{:.6g}", options.end_time));
    const Index rest = std::max<Index>(1, static_cast<Index>(std::ceil((options.end_time - now) / loop.time_step - 1e-9)));
    loop.origin_step = loop.step;
    loop.origin_time = now;
    dt = (options.end_time - now) / static_cast<Real>(rest);
    steps = loop.step + rest;
  } else if (!resumed_) {
    loop = ExplicitLoop{};
  }
  loop.time_step = dt;
  loop.end_time = options.end_time;
  timings_["time_step"] = dt;
  timings_["bonds"] = static_cast<Real>(body_->bonds());
  const Index every = std::max<Index>(1, steps / std::max(1, options.outputs));
  const std::vector<char> free = free_dofs(true);
  Eigen::Map<Eigen::VectorXd> u(u_.data(), 3 * n), v(velocity_.data(), 3 * n);
  if (!resumed_) {
    if (problem_.initial_velocity.cols() == n) velocity_ = problem_.initial_velocity;
    apply_prescribed(u_, 0.0, false);
    apply_prescribed(velocity_, 0.0, true);
  }
  auto time_of = [&](Index step) { return loop.origin_time + static_cast<Real>(step - loop.origin_step) * dt; };
  auto forces = [&](Real t) {
    model_->update(u_, *state_);
    internal_force_ = model_->internal_force(*state_);
    external_force_ = external_force(t / options.end_time);
  };
  Eigen::VectorXd& acceleration = loop.acceleration;
  auto accelerate = [&]() {
    const Eigen::Map<const Eigen::VectorXd> fi(internal_force_.data(), 3 * n), fe(external_force_.data(), 3 * n);
    acceleration = ((fi + fe).array() / mass.array()).matrix() - options.damping * v;
  };
  auto support_force = [&]() {  // external generalized force: loads on free dofs, support forces on prescribed ones
    PointMatrix g = external_force_;
    for (Index d = 0; d < 3 * n; ++d)
      if (!free[static_cast<std::size_t>(d)]) g.data()[d] = mass[d] * acceleration[d] - internal_force_.data()[d];
    return g;
  };
  if (resumed_) {
    forces(time_of(loop.step));  // the bond state and forces of the saved displacements (as computed then)
  } else {
    forces(0.0);
    acceleration.resize(3 * n);
    accelerate();
    energy_internal_ = model_->strain_energy(*state_);
    energy_kinetic_ = 0.5 * (mass.array() * v.array().square()).sum();
    loop.initial_total = energy_internal_ + energy_kinetic_;
    energy_external_ = 0;
    sink->output_point(0, 0.0, 0.0);
    loop.support_force = support_force();  // the end-of-step value of the previous step
  }
  const Real initial_total = loop.initial_total;
  const auto loop_start = Clock::now();
  PointMatrix& g_old = loop.support_force;
  for (Index step = loop.step + 1; step <= steps; ++step) {
    const Real t = time_of(step);
    const Eigen::VectorXd u_old = u;
    // Stage 1: half-step velocity; Stage 2: positions; Stage 3: prescribed motion.
    for (Index d = 0; d < 3 * n; ++d)
      if (free[static_cast<std::size_t>(d)]) v[d] += 0.5 * dt * acceleration[d];
    apply_prescribed(velocity_, (t - 0.5 * dt) / options.end_time, true);
    for (Index d = 0; d < 3 * n; ++d) u[d] += dt * v[d];
    apply_prescribed(u_, t / options.end_time, false);
    // Stage 4: forces and accelerations; Stage 5: second half-step velocity.
    forces(t);
    accelerate();
    for (Index d = 0; d < 3 * n; ++d)
      if (free[static_cast<std::size_t>(d)]) v[d] += 0.5 * dt * acceleration[d];
    apply_prescribed(velocity_, t / options.end_time, true);
    for (Index d = 0; d < 3 * n; ++d)
      if (!free[static_cast<std::size_t>(d)] && !std::isfinite(v[d])) v[d] = 0;
    // Stage 6: energies.
    const PointMatrix g_new = support_force();
    const Eigen::Map<const Eigen::VectorXd> go(g_old.data(), 3 * n), gn(g_new.data(), 3 * n);
    energy_external_ += 0.5 * (go + gn).dot(u - u_old);
    g_old = g_new;
    energy_kinetic_ = 0.5 * (mass.array() * v.array().square()).sum();
    if (!std::isfinite(energy_kinetic_))
      throw AnalysisError(fmt::format("explicit dynamics: non-finite velocity at step {} (t = {:.4g})", step, t));
    steps_ = step;
    if (step % every == 0 || step == steps) {
      // the strain energy (one more pass over the bonds) only where it is reported
      energy_internal_ = model_->strain_energy(*state_);
      if (!std::isfinite(energy_internal_))
        throw AnalysisError(fmt::format("explicit dynamics: non-finite strain energy at step {} (t = {:.4g})", step, t));
      timings_["energy_error"] = (energy_internal_ + energy_kinetic_ - energy_external_ - initial_total) /
                                 std::max({std::abs(initial_total), std::abs(energy_external_), 1e-300});
      sink->output_point(step, t, t / options.end_time);
      sink->progress(t / options.end_time, fmt::format("step {} t {:.4g} dt {:.3g}", step, t, dt));
    }
    loop.step = step;
    sink->safe_point();
  }
  timings_["explicit_loop_s"] = seconds_since(loop_start);
  timings_.erase("energy_error");
  energy_error_ = (energy_internal_ + energy_kinetic_ - energy_external_ - initial_total) /
                  std::max({std::abs(initial_total), std::abs(energy_external_), 1e-300});
}

void PeridynamicAnalysis::buckling_modes(int count) {
  const Index n = body_->nodes();
  solve::SparseMatrix k0;
  const PointMatrix reference = linear_solution(k0, true);
  std::unique_ptr<ModelState> reference_state = model_->state_of(reference, true);
  const solve::SparseMatrix kg = model_->stiffness(*reference_state, false, true);
  const std::vector<char> free = free_dofs(true);
  std::vector<Index> map(free.size(), -1);
  Index dofs = 0;
  for (std::size_t d = 0; d < free.size(); ++d)
    if (free[d]) map[d] = dofs++;
  const solve::SparseMatrix k_upper = reduce_upper(k0, map, dofs), g_upper = reduce_upper(kg, map, dofs);
  const solve::SparseMatrix minus_g = -g_upper;
  // K0 phi = lambda (-K_G) phi  <=>  (-K_G) phi = (1 / lambda) K0 phi: the largest 1/lambda first
  // (regular-inverse mode: K0-orthogonal Lanczos with CHOLMOD solves of K0).
  using OpType = Spectra::SparseSymMatProd<Real, Eigen::Upper>;
  using BOpType = CholmodRegularInverse;
  OpType op(minus_g);
  BOpType bop(k_upper);
  if (!bop.ok())
    throw AnalysisError("buckling: the stiffness matrix is not positive definite (rigid-body motion left free?)");
  const int nev = std::min<int>(count, static_cast<int>(dofs) - 1);
  const int ncv = std::min<int>(std::max(2 * nev + 1, 40), static_cast<int>(dofs));
  Spectra::SymGEigsSolver<OpType, BOpType, Spectra::GEigsMode::RegularInverse> eigs(op, bop, nev, ncv);
  eigs.init();
  eigs.compute(Spectra::SortRule::LargestAlge, 2000, 1e-10);
  if (eigs.info() != Spectra::CompInfo::Successful) throw AnalysisError("buckling: the eigenvalue solver did not converge");
  const Eigen::VectorXd mu = eigs.eigenvalues();
  const Eigen::MatrixXd vectors = eigs.eigenvectors();
  eigenvalues_.clear();
  modes_.clear();
  for (Index k = 0; k < mu.size(); ++k) {
    if (!(mu[k] > 0)) throw AnalysisError("buckling: the reference load does not compress the structure (no positive load factor)");
    eigenvalues_.push_back(1.0 / mu[k]);
    PointMatrix mode = PointMatrix::Zero(3, n);
    for (std::size_t d = 0; d < free.size(); ++d)
      if (map[d] >= 0) mode.data()[d] = vectors(map[d], k);
    const Real largest = mode.colwise().norm().maxCoeff();
    Index where = 0;
    mode.colwise().norm().maxCoeff(&where);
    const Real sign = mode.col(where).sum() < 0 ? -1.0 : 1.0;
    modes_.push_back(mode * (sign / largest));
  }
  u_ = reference;
  state_ = std::move(reference_state);
  internal_force_ = model_->internal_force(*state_);
  external_force_ = external_force(1.0);
}

void PeridynamicAnalysis::run_buckling(OutputSink* sink) {
  buckling_modes(problem_.buckling.modes);
  steps_ = 1;
  sink->output_point(1, 1.0, 1.0);
}

Index PeridynamicAnalysis::nearest_node(const Vec3& x, const IndexList& candidates) const {
  Index best = 0;
  Real best_distance = INFINITY;
  auto consider = [&](Index i) {
    const Real d = (problem_.positions.col(i) - x).squaredNorm();
    if (d < best_distance) {
      best_distance = d;
      best = i;
    }
  };
  if (candidates.empty())
    for (Index i = 0; i < body_->nodes(); ++i) consider(i);
  else
    for (Index i : candidates) consider(i);
  return best;
}

Vec3 PeridynamicAnalysis::reaction(const IndexList& nodes) const {
  Vec3 sum = Vec3::Zero();
  for (Index i : nodes) sum -= internal_force_.col(i) + external_force_.col(i);
  return sum;
}

Vec3 PeridynamicAnalysis::strain_gradient_at(Index i, Mat3& gradient) const {
  Mat3 shape = Mat3::Zero(), deformation = Mat3::Zero();
  const bool planar = body_->dimension() == 2;
  for (Index b = body_->first_bond(i); b < body_->end_bond(i); ++b) {
    const Index j = body_->neighbour(b);
    Vec3 xi = body_->positions().col(j) - body_->positions().col(i);
    Vec3 du = u_.col(j) - u_.col(i);
    if (planar) {
      xi.z() = 0;
      du.z() = 0;
    }
    shape += body_->bond_volume()[b] * xi * xi.transpose();
    deformation += body_->bond_volume()[b] * du * xi.transpose();
  }
  if (planar) shape(2, 2) = 1.0;
  gradient = deformation * shape.inverse();
  return gradient.diagonal();
}

Real PeridynamicAnalysis::probe(const Probe& p) const {
  auto component_of = [&](const Vec3& v) {
    if (p.component == "magnitude") return v.norm();
    return v[p.component == "x" ? 0 : p.component == "y" ? 1 : 2];
  };
  if (p.field == "displacement" || p.field == "velocity") {
    const Index i = p.at ? nearest_node(*p.at, p.nodes) : p.nodes.front();
    return component_of(p.field == "displacement" ? Vec3(u_.col(i)) : Vec3(velocity_.col(i)));
  }
  if (p.field == "reaction_force") return component_of(reaction(p.nodes));
  if (p.field == "energy") {
    if (p.component == "internal") return energy_internal_;
    if (p.component == "kinetic") return energy_kinetic_;
    if (p.component == "external") return energy_external_;
    if (p.component == "damping") return energy_damping_;
    return energy_internal_ + energy_kinetic_;
  }
  if (p.field == "eigenvalue") {
    const std::size_t k = static_cast<std::size_t>(std::stoi(p.component)) - 1;
    return k < eigenvalues_.size() ? eigenvalues_[k] : std::nan("");
  }
  if (p.field == "critical_load") {
    // eigenvalue k times the force the selection carries in the reference pre-buckling state (the
    // buckling load of a displacement-controlled pre-load: prescribed edge shortening, clamped edges)
    const std::size_t k = static_cast<std::size_t>(std::stoi(p.component)) - 1;
    if (k >= eigenvalues_.size()) return std::nan("");
    Vec3 carried = Vec3::Zero();
    for (Index i : p.nodes) carried += external_force_.col(i);
    if (carried.norm() == 0) carried = reaction(p.nodes);
    return eigenvalues_[k] * carried.norm();
  }
  // strain / stress at the nearest node
  const Index i = p.at ? nearest_node(*p.at, p.nodes) : p.nodes.front();
  Mat3 eps;
  if (!state_ || !model_->node_strain(*state_, i, eps)) {
    Mat3 g;
    strain_gradient_at(i, g);
    eps = 0.5 * (g + g.transpose());
  }
  const std::map<std::string, std::pair<int, int>> index{{"xx", {0, 0}}, {"yy", {1, 1}}, {"zz", {2, 2}},
                                                          {"xy", {0, 1}}, {"yz", {1, 2}}, {"zx", {2, 0}}};
  if (p.field == "strain") {
    const auto [a, b] = index.at(p.component);
    return eps(a, b);
  }
  const Real e = problem_.young[i], nu = problem_.poisson[i];
  const material::LinearElastic elastic{e, nu};
  const Real mu = elastic.mu(), lambda = elastic.lambda();
  Mat3 sigma;
  if (body_->options().kinematics == Kinematics::plane_stress) {
    const Real c = elastic.plane_stress_modulus();
    sigma.setZero();
    sigma(0, 0) = c * (eps(0, 0) + nu * eps(1, 1));
    sigma(1, 1) = c * (eps(1, 1) + nu * eps(0, 0));
    sigma(0, 1) = sigma(1, 0) = 2 * mu * eps(0, 1);
  } else {
    Mat3 strain = eps;
    if (body_->dimension() == 2) strain.row(2).setZero(), strain.col(2).setZero();
    sigma = lambda * strain.trace() * Mat3::Identity() + 2 * mu * strain;
  }
  if (p.component == "von_mises") {
    const Mat3 dev = sigma - sigma.trace() / 3 * Mat3::Identity();
    return std::sqrt(1.5 * dev.squaredNorm());
  }
  const auto [a, b] = index.at(p.component);
  return sigma(a, b);
}

std::map<std::string, Real> PeridynamicAnalysis::builtin_probes() const {
  switch (problem_.analysis) {
    case PdAnalysisKind::quasi_static: {
      std::map<std::string, Real> values{{"iterations", static_cast<Real>(last_iterations_)},
                                         {"total_iterations", static_cast<Real>(total_iterations_)},
                                         {"residual", last_residual_},
                                         {"damping_energy", energy_damping_},
                                         {"path_load", path_load_.empty() ? 0.0 : path_load_.back()},
                                         {"path_displacement", path_displacement_.empty() ? 0.0 : path_displacement_.back()}};
      Real ratio = 1.0;
      const std::size_t m = path_load_.size();
      if (m >= 3) {
        const Real k0 = (path_load_[1] - path_load_[0]) / (path_displacement_[1] - path_displacement_[0]);
        const Real k = (path_load_[m - 1] - path_load_[m - 2]) / (path_displacement_[m - 1] - path_displacement_[m - 2]);
        ratio = k / k0;
      }
      values["tangent_stiffness_ratio"] = std::isfinite(ratio) ? ratio : 0.0;
      const auto events = detect_stiffness_changes(path_load_, path_displacement_);
      values["stiffness_changes"] = static_cast<Real>(events.size());
      // the linear buckling load of the case's loads (imperfection: buckling_mode), and the first
      // stiffness change relative to it
      const Real linear = imperfection_load_factor_ * path_total_;
      values["linear_buckling_load"] = linear;
      values["first_buckling_ratio"] = linear > 0 && !events.empty() ? events[0].load / linear : 0.0;
      for (std::size_t k = 0; k < 3; ++k) {
        values[fmt::format("stiffness_change_{}_load", k + 1)] = k < events.size() ? events[k].load : 0.0;
        values[fmt::format("stiffness_change_{}_ratio", k + 1)] = k < events.size() ? events[k].stiffness_ratio : 0.0;
      }
      return values;
    }
    case PdAnalysisKind::explicit_dynamics:
      return {{"kinetic_energy", energy_kinetic_},
              {"strain_energy", energy_internal_},
              {"external_work", energy_external_},
              {"energy_error", timings_.count("energy_error") ? timings_.at("energy_error") : energy_error_}};
    case PdAnalysisKind::buckling: {
      std::map<std::string, Real> values;
      for (int k = 0; k < problem_.buckling.modes; ++k)
        values[fmt::format("load_factor_{}", k + 1)] =
            static_cast<std::size_t>(k) < eigenvalues_.size() ? eigenvalues_[static_cast<std::size_t>(k)] : 0.0;
      return values;
    }
    default: return {};
  }
}

OutputFrame PeridynamicAnalysis::frame() const {
  OutputFrame f;
  const Index n = body_->nodes();
  f.points = problem_.positions;
  auto vector_field = [&](const std::string& name, const PointMatrix& values) {
    PointField field{name, 3, std::vector<Real>(values.data(), values.data() + values.size())};
    f.point_fields.push_back(std::move(field));
  };
  vector_field("displacement", u_);
  vector_field("velocity", velocity_);
  vector_field("internal_force", internal_force_);
  const Eigen::VectorXd total_dilatation = model_->nodal_dilatation(*state_);
  PointField dilatation{"dilatation", 1, std::vector<Real>(total_dilatation.data(), total_dilatation.data() + n)};
  f.point_fields.push_back(std::move(dilatation));
  for (std::size_t k = 0; k < modes_.size(); ++k) vector_field(fmt::format("mode_{}", k + 1), modes_[k]);
  return f;
}

RunCounts PeridynamicAnalysis::counts() const {
  RunCounts c;
  c.nodes = body_->nodes();
  c.dofs = 3 * body_->nodes();
  c.steps = steps_;
  return c;
}

bool PeridynamicAnalysis::can_checkpoint() const {
  return problem_.analysis == PdAnalysisKind::quasi_static || problem_.analysis == PdAnalysisKind::explicit_dynamics;
}

// The state after a completed increment / step, listed once for writing and reading (Archive is a
// StateWriter or a const StateReader); the bond state is recomputed from u on restore (the same
// function of the same numbers, so the same bits).
template <class Self, class Archive>
void PeridynamicAnalysis::state_fields(Self& self, Archive& a) {
  a.field("pd.displacement", self.u_);
  a.field("pd.velocity", self.velocity_);
  a.field("pd.internal_force", self.internal_force_);
  a.field("pd.external_force", self.external_force_);
  a.field("pd.energy_internal", self.energy_internal_);
  a.field("pd.energy_kinetic", self.energy_kinetic_);
  a.field("pd.energy_external", self.energy_external_);
  a.field("pd.energy_damping", self.energy_damping_);
  a.field("pd.energy_error", self.energy_error_);
  a.field("pd.last_residual", self.last_residual_);
  a.field("pd.last_iterations", self.last_iterations_);
  a.field("pd.steps", self.steps_);
  if (self.problem_.analysis == PdAnalysisKind::quasi_static) {
    a.field("pd.increment_iterations", self.increment_iterations_);
    a.field("pd.path_load", self.path_load_);
    a.field("pd.path_displacement", self.path_displacement_);
    a.field("pd.total_iterations", self.total_iterations_);
    auto& q = self.quasi_;
    a.field("pd.qs.step", q.step);
    a.field("pd.qs.factor", q.factor);
    a.field("pd.qs.previous_factor", q.previous_factor);
    a.field("pd.qs.previous", q.previous);
    a.field("pd.qs.before_previous", q.before_previous);
    a.field("pd.qs.generalized_force", q.generalized_force);
    a.field("pd.qs.have_two", q.have_two);
    a.field("pd.qs.third", q.third);
    a.field("pd.qs.third_factor", q.third_factor);
    a.field("pd.qs.have_three", q.have_three);
    a.field("pd.qs.cuts", q.cuts);
    a.field("pd.qs.increment", q.increment);
  } else {
    auto& e = self.explicit_;
    a.field("pd.explicit.step", e.step);
    a.field("pd.explicit.time_step", e.time_step);
    a.field("pd.explicit.origin_step", e.origin_step);
    a.field("pd.explicit.origin_time", e.origin_time);
    a.field("pd.explicit.end_time", e.end_time);
    a.field("pd.explicit.initial_total", e.initial_total);
    a.field("pd.explicit.acceleration", e.acceleration);
    a.field("pd.explicit.support_force", e.support_force);
  }
}

void PeridynamicAnalysis::save_state(StateWriter& out) const {
  out.put("pd.analysis", static_cast<int>(problem_.analysis));
  out.put("pd.nodes", body_->nodes());
  out.put("pd.bonds", body_->bonds());
  state_fields(*this, out);
  if (problem_.analysis == PdAnalysisKind::explicit_dynamics)  // the energy error of the last output point
    out.put("pd.explicit.energy_error_reported", timings_.count("energy_error") ? timings_.at("energy_error") : std::nan(""));
}

void PeridynamicAnalysis::restore_state(const StateReader& in) {
  if (in.integer("pd.analysis") != static_cast<int>(problem_.analysis)) throw StateError("written by another pd.analysis");
  if (in.integer("pd.nodes") != body_->nodes() || in.integer("pd.bonds") != body_->bonds())
    throw StateError(fmt::format("written for {} nodes and {} bonds, this lattice has {} and {}", in.integer("pd.nodes"),
                                 in.integer("pd.bonds"), body_->nodes(), body_->bonds()));
  const Index n = body_->nodes();  // the sizes the records must have
  quasi_.previous.resize(3, n);
  quasi_.before_previous.resize(3, n);
  quasi_.third.resize(3, n);
  quasi_.generalized_force.resize(3, n);
  explicit_.acceleration.resize(3 * n);
  explicit_.support_force.resize(3, n);
  state_fields(*this, in);
  if (problem_.analysis == PdAnalysisKind::quasi_static) model_->update(u_, *state_);
  if (problem_.analysis == PdAnalysisKind::explicit_dynamics)
    if (const Real reported = in.real("pd.explicit.energy_error_reported"); std::isfinite(reported))
      timings_["energy_error"] = reported;
  auto require = [](bool ok, const char* what) {
    if (!ok) throw StateError(std::string("checkpoint value out of range: ") + what);
  };
  require(steps_ >= 0, "step count");
  if (problem_.analysis == PdAnalysisKind::quasi_static)
    require(quasi_.step > 0 && quasi_.step <= 1 && quasi_.factor >= 0 && quasi_.factor <= 1 && quasi_.increment >= 0 &&
                quasi_.cuts >= 0 && std::isfinite(quasi_.previous_factor),
            "load-stepping state");
  else
    require(explicit_.step >= 0 && explicit_.origin_step >= 0 && explicit_.origin_step <= explicit_.step &&
                explicit_.time_step > 0 && std::isfinite(explicit_.time_step) && std::isfinite(explicit_.origin_time) &&
                explicit_.end_time > 0 && std::isfinite(explicit_.end_time),
            "explicit step state");
  resumed_ = true;
}

}  // namespace lamina::pd
