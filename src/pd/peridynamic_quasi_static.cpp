// PeridynamicAnalysis::run_quasi_static: load increments relaxed to equilibrium by adaptive dynamic
// relaxation (seed 002 section 2.2, eqs (5)-(9)); predictor, relaxation, acceptance per increment; the load path.
#include <fmt/format.h>

#include <array>
#include <cmath>
#include <optional>

#include "core/error.hpp"
#include "core/stopwatch.hpp"
#include "pd/peridynamic_analysis.hpp"
#include "pd/relaxation_coordinates.hpp"

namespace lamina::pd {

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
  if (!resumed_) quasi_.density_doublings = 0;
  lambda *= std::pow(2.0, quasi_.density_doublings);  // a resumed run keeps the doublings it had made
  AdaptiveDynamicRelaxation relaxation(*model_, lambda, free, options, coordinates ? &*coordinates : nullptr);
  timings_["density_doublings"] = quasi_.density_doublings;
  // several ranks: every rank holds the whole body and relaxation vectors and computes the forces of its
  // block of nodes (split_force_work); the blocks are all-gathered each iteration, so every rank runs the
  // same iterations on the same numbers as one process would
  const bool split = comm_.distributed();
  if (split) {
    split_force_work(true);
    relaxation.set_force_completion([this](PointMatrix& f) { force_split_->complete(f); });
  }
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
    if (split) split_force_work(true);
    const auto relax_start = Clock::now();
    RelaxationResult result = relaxation.relax(u, fext);
    total_iterations_ += result.iterations;
    // A block that ends far above its start residual has not dissipated: the fictitious dynamics is
    // unstable. Seed eq (5) bounds K0; a plate that has rotated carries part of its in-plane stiffness
    // into the global z dofs, whose density a one-layer plate takes from its (bending-scale) K0 alone.
    // Double the density and restart the increment (at most 4 times in a run; docs/pd.md).
    if (!result.converged && std::isfinite(result.residual) && result.residual > 10.0 * result.initial_residual &&
        quasi_.density_doublings < 4) {
      relaxation.scale_density(2.0);
      ++quasi_.density_doublings;
      timings_["density_doublings"] = quasi_.density_doublings;
      sink->notice(fmt::format("ADR diverged towards load factor {:.6g} (residual {:.3e}, start {:.3e} after {} "
                               "iterations): fictitious density doubled ({} of 4), increment restarted",
                               target, result.residual, result.initial_residual, result.iterations,
                               quasi_.density_doublings));
      continue;
    }
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
    timings_["relaxation_s"] += seconds_since(relax_start);
    if (split) {  // the whole state again (energy, probes, fields); its forces equal the gathered ones
      split_force_work(false);
      if (result.converged) {
        model_->update(u, *result.state);
        result.internal_force = model_->internal_force(*result.state);
      }
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

}  // namespace lamina::pd
