// PeridynamicAnalysis::run_explicit: explicit dynamics by velocity Verlet (seed 002 section 2.3) with the
// critical step from the Gershgorin bound of M^-1 K0; the step is an ordered list of named, timed stages.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "core/error.hpp"
#include "core/step_stage.hpp"
#include "core/stopwatch.hpp"
#include "pd/peridynamic_analysis.hpp"

namespace lamina::pd {

void PeridynamicAnalysis::run_explicit(OutputSink* sink) {
  const Index n = body_->nodes();
  const auto& options = problem_.explicit_options;
  Eigen::VectorXd mass(3 * n);
  for (Index i = 0; i < n; ++i) mass.segment<3>(3 * i).setConstant(problem_.density[i] * problem_.volumes[i]);
  // Critical time step: Gershgorin bound of the largest eigenvalue of M^-1 K0. K0 reaches two
  // horizons (about 8 x family blocks per row); above ~2 GB it is not formed, and then the case
  // must give explicit.time_step (used unchecked), as with the lean bond storage, which keeps no stiffness.
  // (several ranks: each forms the rows of its own nodes; the largest rank decides, the same on all)
  const Real k0_bytes = comm_.max(8.0 * static_cast<Real>(body_->bonds()) * 9.0 * 12.0);
  Real dt = options.time_step;
  if (options.time_step <= 0 || (k0_bytes < 2.0e9 && !body_->lean())) {
    if (k0_bytes >= 2.0e9)
      throw AnalysisError(fmt::format(
          "explicit dynamics: the lattice ({} nodes, {} bonds) is too large to form the stiffness for the critical "
          "time step (~{:.1f} GB); give pd.explicit.time_step", n, body_->bonds(), k0_bytes / 1e9));
    const solve::SparseMatrix k0 = model_->stiffness(*model_->state_of(PointMatrix::Zero(3, n), true), true, false);
    const Eigen::VectorXd rows = absolute_row_sums(k0);
    // the halo's rows are incomplete: the owned dofs' only (owned_dof_ is 1 there, 0 on the halo)
    const Real omega_max = std::sqrt(ranks_ ? comm_.max((rows.array() / mass.array() * owned_dof_.array()).maxCoeff())
                                            : (rows.array() / mass.array()).maxCoeff());
    const Real critical = 2.0 / omega_max;
    if (options.time_step <= 0) dt = options.safety_factor * critical;
    if (dt > critical)
      throw AnalysisError(fmt::format("explicit time step {:.4g} exceeds the critical step {:.4g}", dt, critical));
    timings_["critical_time_step"] = critical;
  }
  // several ranks: from here on the halo's dilatation forces come from their owners (the stiffness above
  // needed the inner halo's own bond directions)
  if (ranks_) body_->set_halo_exchange([this](Real* data, int rows) { ranks_->halo.exchange(data, rows); });
  // several ranks on a plate lattice (no partition): every rank the whole body, the forces of its block
  // of columns, gathered (force_split.hpp); the strain energy and probes at output points need the whole state
  const bool split = comm_.distributed() && !ranks_;
  if (split) split_force_work(true);
  auto strain_energy = [&] {
    if (!split) return comm_.sum(model_->strain_energy(*state_));
    split_force_work(false);
    model_->update(u_, *state_);
    const Real energy = model_->strain_energy(*state_);
    split_force_work(true);
    return energy;
  };
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
  // the body's directed bonds (several ranks: those of the owned nodes, summed)
  Index owned_bonds = body_->bonds();
  if (ranks_) {
    owned_bonds = 0;
    for (Index i = 0; i < n; ++i)
      if (body_->owns(i)) owned_bonds += body_->end_bond(i) - body_->first_bond(i);
    owned_bonds = comm_.sum(owned_bonds);
  }
  timings_["bonds"] = static_cast<Real>(owned_bonds);
  const Index every = std::max<Index>(1, steps / std::max(1, options.outputs));
  const std::vector<char> free = free_dofs(true);
  Eigen::Map<Eigen::VectorXd> u(u_.data(), 3 * n), v(velocity_.data(), 3 * n);
  if (!resumed_) {
    if (problem_.initial_velocity.cols() == n) velocity_ = problem_.initial_velocity;
    apply_prescribed(u_, 0.0, false);
    apply_prescribed(velocity_, 0.0, true);
  }
  // several ranks: the halo's displacements from their owners, before every force evaluation
  auto exchange_halo = [&] {
    if (ranks_) ranks_->halo.exchange(u_.data(), 3);
  };
  exchange_halo();
  auto time_of = [&](Index step) { return loop.origin_time + static_cast<Real>(step - loop.origin_step) * dt; };
  auto forces = [&](Real t) {
    model_->update(u_, *state_);
    internal_force_ = model_->internal_force(*state_);
    if (split) force_split_->complete(internal_force_);
    external_force_ = external_force(t / options.end_time);
  };
  Eigen::VectorXd& acceleration = loop.acceleration;
  auto accelerate = [&]() {
    const Eigen::Map<const Eigen::VectorXd> fi(internal_force_.data(), 3 * n), fe(external_force_.data(), 3 * n);
    acceleration = ((fi + fe).array() / mass.array()).matrix() - options.damping * v;
  };
  // External generalized force: the loads on free dofs; on prescribed ones the support force that moves the
  // node as prescribed, R = m a - f_int - f_ext, with a the prescribed motion's acceleration over the last
  // step (v_start: the velocities at its start; none at t = 0). (`acceleration` there is the free-body one,
  // (f_int + f_ext) / m, which would make R ~0 and leave the prescribed motion's work out.)
  auto support_force = [&](const Eigen::VectorXd* v_start) {
    PointMatrix g = external_force_;
    for (Index d = 0; d < 3 * n; ++d)
      if (!free[static_cast<std::size_t>(d)]) {
        const Real a = v_start ? (v[d] - (*v_start)[d]) / dt : 0.0;
        g.data()[d] = mass[d] * a - internal_force_.data()[d] - external_force_.data()[d];
      }
    return g;
  };
  if (resumed_) {
    forces(time_of(loop.step));  // the bond state and forces of the saved displacements (as computed then)
  } else {
    forces(0.0);
    acceleration.resize(3 * n);
    accelerate();
    energy_internal_ = strain_energy();
    energy_kinetic_ = ranks_ ? comm_.sum(0.5 * (mass.array() * v.array().square() * owned_dof_.array()).sum())
                             : 0.5 * (mass.array() * v.array().square()).sum();
    loop.initial_total = energy_internal_ + energy_kinetic_;
    energy_external_ = 0;
    sink->output_point(0, 0.0, 0.0);
    loop.support_force = support_force(nullptr);  // the end-of-step value of the previous step
  }
  const Real initial_total = loop.initial_total;
  const auto loop_start = Clock::now();
  PointMatrix& g_old = loop.support_force;
  // One step (velocity Verlet) as its ordered list of named stages (core/step_stage.hpp), each timed
  // (summary.json timing.stage_<name>_s).
  Index step = 0;
  Real t = 0;
  Eigen::VectorXd u_old, v_start;
  const std::vector<StepStage> step_stages{
      {"kick_drift",  // half-step velocity, positions, prescribed motion
       [&] {
         u_old = u;
         v_start = v;
         for (Index d = 0; d < 3 * n; ++d)
           if (free[static_cast<std::size_t>(d)]) v[d] += 0.5 * dt * acceleration[d];
         apply_prescribed(velocity_, (t - 0.5 * dt) / options.end_time, true);
         for (Index d = 0; d < 3 * n; ++d) u[d] += dt * v[d];
         apply_prescribed(u_, t / options.end_time, false);
         exchange_halo();
       }},
      {"forces",  // bond state, internal and external forces, accelerations (the bond loop)
       [&] {
         forces(t);
         accelerate();
       }},
      {"kick",  // second half-step velocity
       [&] {
         for (Index d = 0; d < 3 * n; ++d)
           if (free[static_cast<std::size_t>(d)]) v[d] += 0.5 * dt * acceleration[d];
         apply_prescribed(velocity_, t / options.end_time, true);
         for (Index d = 0; d < 3 * n; ++d)
           if (!free[static_cast<std::size_t>(d)] && !std::isfinite(v[d])) v[d] = 0;
       }},
      {"energies",  // external work (trapezoidal in the generalized forces), kinetic energy
       [&] {
         const PointMatrix g_new = support_force(&v_start);
         const Eigen::Map<const Eigen::VectorXd> go(g_old.data(), 3 * n), gn(g_new.data(), 3 * n);
         if (ranks_) {  // the owned dofs of every rank, one reduction
           std::vector<Real> sums{0.5 * ((go + gn).array() * (u - u_old).array() * owned_dof_.array()).sum(),
                                  0.5 * (mass.array() * v.array().square() * owned_dof_.array()).sum()};
           comm_.sum(sums);
           energy_external_ += sums[0];
           energy_kinetic_ = sums[1];
         } else {
           energy_external_ += 0.5 * (go + gn).dot(u - u_old);
           energy_kinetic_ = 0.5 * (mass.array() * v.array().square()).sum();
         }
         g_old = g_new;
         if (!std::isfinite(energy_kinetic_))
           throw AnalysisError(fmt::format("explicit dynamics: non-finite velocity at step {} (t = {:.4g})", step, t));
       }}};
  std::vector<Real> stage_seconds(step_stages.size(), 0.0);
  for (step = loop.step + 1; step <= steps; ++step) {
    t = time_of(step);
    run_stages(step_stages, stage_seconds);
    steps_ = step;
    if (step % every == 0 || step == steps) {
      // the strain energy (one more pass over the bonds) only where it is reported
      energy_internal_ = strain_energy();
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
  for (std::size_t k = 0; k < step_stages.size(); ++k) timings_[std::string(step_stages[k].name) + "_s"] += stage_seconds[k];
  timings_["explicit_loop_s"] = seconds_since(loop_start);
  timings_.erase("energy_error");
  energy_error_ = (energy_internal_ + energy_kinetic_ - energy_external_ - initial_total) /
                  std::max({std::abs(initial_total), std::abs(energy_external_), 1e-300});
}

}  // namespace lamina::pd
