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
    a.field("pd.qs.density_doublings", q.density_doublings);
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

PointMatrix PeridynamicAnalysis::whole_body(const PointMatrix& local) const {
  PointMatrix whole = PointMatrix::Zero(local.rows(), ranks_->global_count);
  for (std::size_t k = 0; k < ranks_->global.size(); ++k)
    if (ranks_->owns(static_cast<Index>(k))) whole.col(ranks_->global[k]) = local.col(static_cast<Index>(k));
  std::vector<Real> values(whole.data(), whole.data() + whole.size());
  comm_.sum(values);  // each column is one rank's (the others add zeros): exact
  return Eigen::Map<const PointMatrix>(values.data(), whole.rows(), whole.cols());
}

PointMatrix PeridynamicAnalysis::this_rank(const PointMatrix& whole) const {
  PointMatrix local(whole.rows(), static_cast<Index>(ranks_->global.size()));
  for (std::size_t k = 0; k < ranks_->global.size(); ++k) local.col(static_cast<Index>(k)) = whole.col(ranks_->global[k]);
  return local;
}

// The per-node arrays a distributed explicit run checkpoints, whole (in global order) while it is written.
// The local arrays are swapped out (their buffers kept: the explicit loop holds views of them) and swapped
// back afterwards.
void PeridynamicAnalysis::before_checkpoint() {
  if (!ranks_) return;
  auto& e = explicit_;
  local_during_checkpoint_.assign(5, PointMatrix());
  local_acceleration_during_checkpoint_.resize(0);
  PointMatrix* arrays[] = {&u_, &velocity_, &internal_force_, &external_force_, &e.support_force};
  for (std::size_t k = 0; k < 5; ++k) {
    local_during_checkpoint_[k].swap(*arrays[k]);
    *arrays[k] = whole_body(local_during_checkpoint_[k]);
  }
  local_acceleration_during_checkpoint_.swap(e.acceleration);
  const PointMatrix whole_acceleration = whole_body(
      Eigen::Map<const PointMatrix>(local_acceleration_during_checkpoint_.data(), 3, local_acceleration_during_checkpoint_.size() / 3));
  e.acceleration = Eigen::Map<const Eigen::VectorXd>(whole_acceleration.data(), whole_acceleration.size());
}

void PeridynamicAnalysis::after_checkpoint() {
  if (!ranks_ || local_during_checkpoint_.empty()) return;
  PointMatrix* arrays[] = {&u_, &velocity_, &internal_force_, &external_force_, &explicit_.support_force};
  for (std::size_t k = 0; k < 5; ++k) arrays[k]->swap(local_during_checkpoint_[k]);
  explicit_.acceleration.swap(local_acceleration_during_checkpoint_);
  local_during_checkpoint_.clear();
  local_acceleration_during_checkpoint_.resize(0);
}

void PeridynamicAnalysis::save_state(StateWriter& out) const {
  out.put("pd.analysis", static_cast<int>(problem_.analysis));
  // several ranks: the whole body's nodes and bonds (the arrays are whole during a checkpoint)
  out.put("pd.nodes", ranks_ ? ranks_->global_count : body_->nodes());
  out.put("pd.bonds", ranks_ && timings_.count("bonds") ? static_cast<Index>(timings_.at("bonds")) : body_->bonds());
  state_fields(*this, out);
  if (problem_.analysis == PdAnalysisKind::explicit_dynamics)  // the energy error of the last output point
    out.put("pd.explicit.energy_error_reported", timings_.count("energy_error") ? timings_.at("energy_error") : std::nan(""));
}

void PeridynamicAnalysis::restore_state(const StateReader& in) {
  if (in.integer("pd.analysis") != static_cast<int>(problem_.analysis)) throw StateError("written by another pd.analysis");
  const Index nodes = ranks_ ? ranks_->global_count : body_->nodes();
  if (in.integer("pd.nodes") != nodes)
    throw StateError(fmt::format("written for {} nodes, this lattice has {}", in.integer("pd.nodes"), nodes));
  if (!ranks_ && in.integer("pd.bonds") != body_->bonds())
    throw StateError(fmt::format("written for {} bonds, this lattice has {}", in.integer("pd.bonds"), body_->bonds()));
  const Index n = nodes;  // the sizes the records must have (the whole body's)
  quasi_.previous.resize(3, n);
  quasi_.before_previous.resize(3, n);
  quasi_.third.resize(3, n);
  quasi_.generalized_force.resize(3, n);
  explicit_.acceleration.resize(3 * n);
  explicit_.support_force.resize(3, n);
  if (ranks_) {
    u_.resize(3, n);
    velocity_.resize(3, n);
    internal_force_.resize(3, n);
    external_force_.resize(3, n);
  }
  state_fields(*this, in);
  if (ranks_) {  // the whole body's arrays: this rank's columns
    u_ = this_rank(u_);
    velocity_ = this_rank(velocity_);
    internal_force_ = this_rank(internal_force_);
    external_force_ = this_rank(external_force_);
    const PointMatrix a = this_rank(Eigen::Map<const PointMatrix>(explicit_.acceleration.data(), 3, n));
    explicit_.acceleration = Eigen::Map<const Eigen::VectorXd>(a.data(), a.size());
    explicit_.support_force = this_rank(explicit_.support_force);
  }
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
                quasi_.cuts >= 0 && quasi_.density_doublings >= 0 && quasi_.density_doublings <= 4 &&
                std::isfinite(quasi_.previous_factor),
            "load-stepping state");
  else
    require(explicit_.step >= 0 && explicit_.origin_step >= 0 && explicit_.origin_step <= explicit_.step &&
                explicit_.time_step > 0 && std::isfinite(explicit_.time_step) && std::isfinite(explicit_.origin_time) &&
                explicit_.end_time > 0 && std::isfinite(explicit_.end_time),
            "explicit step state");
  resumed_ = true;
}

}  // namespace lamina::pd
