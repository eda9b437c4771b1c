// MpmAnalysis checkpoint state: the fields a restart needs, listed once for writing and reading
// (docs/restart.md; core/state_archive.hpp).
#include <fmt/format.h>

#include <cmath>
#include <cstdint>
#include <string>

#include "core/error.hpp"
#include "mpm/mpm_analysis.hpp"

namespace lamina::mpm {

// The state after a step: node motion, element stresses and hourglass resultants, clocks and the
// energy balance, listed once for writing and reading; the grid connectivity is rebuilt from the
// positions (a function of them alone).
template <class Self, class Archive>
void MpmAnalysis::state_fields(Self& self, Archive& a) {
  a.field("mpm.x", self.x_);
  a.field("mpm.v", self.v_);
  a.field("mpm.vpos", self.vpos_);
  a.field("mpm.omega", self.omega_);
  a.field("mpm.stress", self.stress_);
  a.field("mpm.hourglass", self.hourglass_);
  a.field("mpm.thickness", self.thickness_);
  a.field("mpm.element_length", self.element_length_);
  a.field("mpm.time", self.time_);
  a.field("mpm.dt", self.dt_);
  a.field("mpm.dt_previous", self.dt_previous_);
  a.field("mpm.residual_ratio", self.residual_ratio_);
  a.field("mpm.kinetic_previous", self.kinetic_previous_);
  a.field("mpm.current_load", self.current_load_);
  a.field("mpm.steps", self.steps_);
  a.field("mpm.dt_control", self.dt_control_);
  a.field("mpm.unconverged_levels", self.unconverged_levels_);
  a.field("mpm.level_residual", self.level_residual_);
  auto& e = self.energy_;
  a.field("mpm.energy.kinetic", e.kinetic);
  a.field("mpm.energy.internal", e.internal);
  a.field("mpm.energy.hourglass", e.hourglass);
  a.field("mpm.energy.external", e.external);
  a.field("mpm.energy.damping", e.damping);
  a.field("mpm.energy.transfer", e.transfer);
  a.field("mpm.energy.initial_kinetic", e.initial_kinetic);
  a.field("mpm.loop.level", self.loop_.level);
  a.field("mpm.loop.level_steps", self.loop_.level_steps);
  a.field("mpm.loop.level_done", self.loop_.level_done);
  a.field("mpm.loop.next_output", self.loop_.next_output);
  if (self.problem_.options.solver == MpmOptions::Solver::newton) {  // the sub-increment size carried between levels
    a.field("mpm.newton.step", self.newton_step_);
    a.field("mpm.newton.iterations", self.newton_iterations_);
    a.field("mpm.newton.increments", self.newton_increments_);
    a.field("mpm.newton.stopped_levels", self.newton_stopped_levels_);
    a.field("mpm.newton.first_stop_load", self.newton_first_stop_load_);
    a.field("mpm.newton.jumps", self.newton_jumps_);
    a.field("mpm.newton.first_jump_load", self.newton_first_jump_load_);
    a.field("mpm.newton.largest_energy_gap", self.newton_largest_gap_);
    a.field("mpm.newton.last_rate", self.newton_last_rate_);
  }
  if (self.scaled_) {  // mass-scaled quasi-static: the fictitious masses and the damping estimate's state
    a.field("mpm.mass_scaling.mass", self.dyn_mass_);
    a.field("mpm.mass_scaling.inertia", self.dyn_inertia_);
    a.field("mpm.mass_scaling.level_start", self.level_start_);
    a.field("mpm.mass_scaling.theta", self.theta_);
    a.field("mpm.mass_scaling.f_int_previous", self.f_int_previous_);
    a.field("mpm.mass_scaling.m_int_previous", self.m_int_previous_);
    a.field("mpm.mass_scaling.damping", self.adaptive_c_);
    a.field("mpm.mass_scaling.age", self.masses_age_);
    a.field("mpm.mass_scaling.stale", self.masses_stale_);
    a.field("mpm.mass_scaling.level_steps", self.level_step_counts_);
  }
}

void MpmAnalysis::save_state(StateWriter& out) const {
  out.put("mpm.nodes", static_cast<std::int64_t>(x_.cols()));
  out.put("mpm.elements", problem_.mesh.element_count());
  state_fields(*this, out);
}

void MpmAnalysis::restore_state(const StateReader& in) {
  if (in.integer("mpm.nodes") != x_.cols() || in.integer("mpm.elements") != problem_.mesh.element_count())
    throw StateError(fmt::format("written for {} nodes and {} elements, this mesh has {} and {}", in.integer("mpm.nodes"),
                                 in.integer("mpm.elements"), x_.cols(), problem_.mesh.element_count()));
  state_fields(*this, in);  // (every array has its size from the set-up)
  const MpmOptions& o = problem_.options;
  auto require = [](bool ok, const char* what) {
    if (!ok) throw StateError(std::string("checkpoint value out of range: ") + what);
  };
  require(std::isfinite(time_) && time_ >= 0 && std::isfinite(dt_previous_) && dt_previous_ >= 0 && std::isfinite(dt_), "time");
  require(steps_ >= 0 && loop_.level_steps >= 0, "step counts");
  require(loop_.level >= 1 && loop_.level <= o.load_levels + 1, "quasi-static level");
  require(loop_.next_output >= 1 && loop_.next_output <= o.output_points + 1, "next output point");
  if (scaled_) {
    require(dyn_mass_.allFinite() && dyn_mass_.minCoeff() > 0 && dyn_inertia_.allFinite() && dyn_inertia_.minCoeff() > 0,
            "fictitious masses");
  }
  if (loop_.level_done) {  // written after the level's output point: continue with the next level
    ++loop_.level;
    loop_.level_steps = 0;
    loop_.level_done = false;
  }
  try {
    locate_grid();
  } catch (const AnalysisError& e) {
    throw StateError(std::string("checkpoint record 'mpm.x': ") + e.what());
  }
  resumed_ = true;
}

}  // namespace lamina::mpm
