// PeridynamicAnalysis checkpoint state: the fields a restart of a quasi-static or explicit run needs,
// listed once for writing and reading (docs/restart.md; core/state_archive.hpp).
#include <fmt/format.h>

#include <cmath>
#include <cstdint>
#include <string>

#include "core/error.hpp"
#include "pd/peridynamic_analysis.hpp"

namespace lamina::pd {

bool PeridynamicAnalysis::can_checkpoint() const {
  if (ranks_) return false;  // checkpoints of distributed runs: not yet (docs/scaling.md)
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
