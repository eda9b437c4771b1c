// The explicit step of MpmAnalysis as an ordered list of named stages (NairnMPM's "tasks"): each
// stage is one member function, advance() runs the list and times every stage (summary.json
// timing.stage_<name>_s). The mass-scaled quasi-static list has one more stage; see mpm_analysis.hpp.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "mpm/mpm_analysis.hpp"

namespace lamina::mpm {

namespace {
// mass scaling: the fictitious masses are recomputed from the current tangent this often (and at each level)
constexpr Index kMassRefreshSteps = 1000;
}  // namespace

std::vector<StepStage> MpmAnalysis::step_stages(bool mass_scaled) {
  std::vector<StepStage> stages{{"element", [this] { stage_element_forces(); }}};
  if (mass_scaled) stages.push_back({"mass_scaling", [this] { stage_mass_scaling(); }});
  stages.insert(stages.end(), {{"time_step", [this] { stage_time_step(); }},
                               {"loads", [this] { stage_loads_and_residual(); }},
                               {"p2g", [this] { stage_particle_to_grid(); }},
                               {"g2p", [this] { stage_grid_to_particle(); }},
                               {"damping", [this] { stage_damping_and_energy(); }},
                               {"update", [this] { stage_position_update(); }}});
  return stages;
}

Real MpmAnalysis::advance(Real load) {
  current_load_ = load;
  step_ = StepContext{};
  run_stages(stages_, stage_time_);
  dt_previous_ = step_.dt;
  time_ += step_.dt;
  ++steps_;
  return step_.dt;
}

// 1. element stage: stresses advanced over the step that brought the nodes to x^n; nodal forces gathered.
void MpmAnalysis::stage_element_forces() {
  compute_internal_forces(dt_previous_);
  energy_.internal += dt_previous_ * power_sum_;
  energy_.hourglass += dt_previous_ * hourglass_power_sum_;
}

// 1b. mass-scaled quasi-static only: fictitious masses refreshed, adaptive damping estimate.
void MpmAnalysis::stage_mass_scaling() {
  if (masses_stale_ || masses_age_ >= kMassRefreshSteps) compute_fictitious_masses();
  ++masses_age_;
  if (problem_.options.adaptive_damping) adaptive_c_ = steps_ > 0 ? adaptive_damping_coefficient() : 0.0;
  f_int_previous_ = f_int_;
  m_int_previous_ = m_int_;
}

// 2. time step (eqs (38)-(40)) combined with the shell stable step.
void MpmAnalysis::stage_time_step() {
  const MpmOptions& o = problem_.options;
  const Real vmax = vpos_.cwiseAbs().maxCoeff();
  if (!std::isfinite(vmax) || vmax > node_velocity_limit())
    throw AnalysisError(fmt::format("unstable: a node velocity of {:.3g} exceeds 10 x the wave speed ({:.3g}) at step {} "
                                    "(time {:.6g}); reduce mpm.time_step",
                                    vmax, wave_speed_, steps_, time_));
  const Real dt_grid = o.alpha * grid_.cell() / (wave_speed_ + vmax);
  const Real dt_shell = o.shell_safety * element_->stable_time_step(shortest_element_);
  Real dt = std::min(dt_grid, dt_shell);
  dt_control_ = dt_grid < dt_shell ? "grid" : "shell";
  if (o.fixed_time_step > 0) {
    dt = o.fixed_time_step;
    dt_control_ = "fixed";
  }
  if (scaled_) {  // the fictitious masses make dt = 1 stable (Gershgorin bound)
    dt = 1.0;
    dt_control_ = "mass_scaling";
  }
  if (!(dt > 0) || !std::isfinite(dt)) throw AnalysisError(fmt::format("time step {} at step {}: degenerate elements", dt, steps_));
  dt_ = step_.dt = dt;
}

// 3. external forces, damping, residual.
void MpmAnalysis::stage_loads_and_residual() {
  const MpmOptions& o = problem_.options;
  const Index n = x_.cols();
  compute_external_forces(current_load_);
  const Real c = scaled_ && o.adaptive_damping ? adaptive_c_ : o.mass_damping;
  step_.damping = c;
  f_net_.resize(3, n);
  m_net_.resize(3, n);
#pragma omp parallel for schedule(static) if (n > 4096)
  for (Index i = 0; i < n; ++i) {
    f_net_.col(i) = f_ext_.col(i) - f_int_.col(i);
    m_net_.col(i) = m_ext_.col(i) - m_int_.col(i);
  }
  {
    // adaptive damping: the damping force c m v joins the imbalance, so that a node swinging through
    // equilibrium (zero residual at full velocity) does not end the level
    const bool damping_force = scaled_ && o.adaptive_damping && c > 0;
    const auto [r2, ext2, int2] = node_sums<3>([&](Index i, std::array<Real, 3>& s) {
      s[0] += f_net_.col(i).cwiseProduct(free_.col(i)).squaredNorm() / mass_[i] +
              m_net_.col(i).cwiseProduct(rotation_free_.col(i)).squaredNorm() / inertia_[i];
      if (damping_force)
        s[0] += (c * dyn_mass_[i]) * (c * dyn_mass_[i]) * v_.col(i).cwiseProduct(free_.col(i)).squaredNorm() / mass_[i] +
                (c * dyn_inertia_[i]) * (c * dyn_inertia_[i]) * omega_.col(i).cwiseProduct(rotation_free_.col(i)).squaredNorm() / inertia_[i];
      s[1] += f_ext_.col(i).squaredNorm() / mass_[i] + m_ext_.col(i).squaredNorm() / inertia_[i];
      s[2] += f_int_.col(i).cwiseProduct(free_.col(i)).squaredNorm() / mass_[i] +
              m_int_.col(i).cwiseProduct(rotation_free_.col(i)).squaredNorm() / inertia_[i];
    });
    const Real scale = std::max({ext2, int2, std::numeric_limits<Real>::min()});
    residual_ratio_ = std::sqrt(r2 / scale);
  }
  // adaptive damping is central (seed 002 eq (7)): v^{n+1/2} = ((1 - c dt/2) v^{n-1/2} + dt f / m) / (1 + c dt/2),
  // applied in the grid update and the rotation update (an explicit -c m v^{n-1/2} would shrink the
  // stable step to omega^2 dt^2 < 4 - 2 c dt)
  const Real dt = step_.dt;
  step_.central_damping = scaled_ && o.adaptive_damping;
  step_.keep = step_.central_damping ? 1.0 - 0.5 * c * dt : 1.0;
  step_.divide = step_.central_damping ? 1.0 + 0.5 * c * dt : 1.0;
  if (c > 0 && !step_.central_damping) {
    for (Index i = 0; i < n; ++i) {
      f_net_.col(i) -= c * dyn_mass_[i] * v_.col(i);
      m_net_.col(i) -= c * dyn_inertia_[i] * omega_.col(i);
    }
  }
}

// 4. P2G and the grid update in one pass over the grid's slots (eqs (1)-(7)): mass, momentum and force
// per free component summed from the corners, then v_I = (p_I + dt f_I) / m_I and a_I = f_I / m_I (central
// adaptive damping: seed 002 eq (7)) while the sums are in registers; grid nodes without free mass stay at
// rest. (One pass instead of two: the grid has about 8 slots per shell node at the default cell of half
// an element edge, and the sums' three arrays written and read back cost more than the update itself.)
void MpmAnalysis::stage_particle_to_grid() {
  const Real dt = step_.dt, keep = step_.keep, divide = step_.divide;
  const bool central_damping = step_.central_damping;
  const Index active = grid_.active_nodes();
  Eigen::Matrix3Xd &grid_velocity = grid_velocity_, &grid_acceleration = grid_acceleration_;
  grid_velocity.resize(3, active);
  grid_acceleration.resize(3, active);
  // several ranks: every grid node of the rank's grid; those the block's nodes touch get the whole sum
  // (every rank holds every node's mass, velocity and force; the grid holds the nodes near the block)
  grid_.scatter_and_finish(dyn_mass_, v_, f_net_, free_, [&](Index s, const Vec3& m, const Vec3& p, const Vec3& f) {
    // 1 / m where there is free mass, 0 where there is none (masses are >= 0), without a branch
    const Eigen::Array3d has_mass = (m.array() > 0).cast<Real>();
    const Eigen::Array3d inverse = has_mass / (m.array() + (1.0 - has_mass));
    if (central_damping) {
      const Eigen::Array3d v = (keep * p.array() + dt * f.array()) * (inverse / divide);
      grid_velocity.col(s) = v.matrix();
      grid_acceleration.col(s) = ((v - p.array() * inverse) / dt).matrix();
    } else {
      grid_acceleration.col(s) = (f.array() * inverse).matrix();
      grid_velocity.col(s) = ((p.array() + dt * f.array()) * inverse).matrix();
    }
  });
}

// 5. G2P velocities (eq (8), PIC blended with FLIP by options.flip); rotations integrated at the nodes;
// prescribed components imposed.
void MpmAnalysis::stage_grid_to_particle() {
  const Index n = x_.cols();
  const Real dt = step_.dt, keep = step_.keep, divide = step_.divide;
  const bool central_damping = step_.central_damping;
  const Eigen::Matrix3Xd& m_net = m_net_;
  const Real flip = problem_.options.flip;
  transfer_loss_.setZero(n);
  // this rank's nodes (all on one process): grid velocity (PIC) and acceleration at the node, then its update
  grid_.gather_and_finish(grid_velocity_, grid_acceleration_, node_first_, node_last_, [&](Index i, const Vec3& v_pic, const Vec3& a_grid) {
    for (int a = 0; a < 3; ++a) {
      if (free_(a, i) > 0) {
        const Real v_flip = v_(a, i) + dt * a_grid[a];
        v_(a, i) = flip * v_flip + (1.0 - flip) * v_pic[a];
        transfer_loss_[i] += 0.5 * dyn_mass_[i] * (v_flip * v_flip - v_(a, i) * v_(a, i));
        vpos_(a, i) = v_pic[a];
      } else {
        v_(a, i) = vpos_(a, i) = 0.0;
      }
      if (central_damping)
        omega_(a, i) = rotation_free_(a, i) > 0 ? (keep * omega_(a, i) + dt * m_net(a, i) / dyn_inertia_[i]) / divide : 0.0;
      else
        omega_(a, i) = rotation_free_(a, i) > 0 ? omega_(a, i) + dt * m_net(a, i) / dyn_inertia_[i] : 0.0;
    }
  });
  // several ranks: every node's position velocity on every rank (the positions stay whole everywhere),
  // the halo's velocities and rotation rates (P2G and the elements of the block)
  gather_node_blocks({{vpos_.data(), 3}});
  exchange_halo({{v_.data(), 3}, {omega_.data(), 3}});
  apply_prescribed(current_load_);
}

// 6. damping bookkeeping, kinetic-energy damping, external work, kinetic and transfer energies.
void MpmAnalysis::stage_damping_and_energy() {
  const MpmOptions& o = problem_.options;
  const Index n = x_.cols();
  const Real dt = step_.dt, c = step_.damping;
  // kinetic energy, damping power, transfer loss (this rank's block; node_sums adds the blocks)
  auto [kinetic, damping_power, transfer] = node_sums<3>([&](Index i, std::array<Real, 3>& s) {
    const Real twice = dyn_mass_[i] * v_.col(i).squaredNorm() + dyn_inertia_[i] * omega_.col(i).squaredNorm();
    s[0] += 0.5 * twice;
    s[1] += c * twice;
    s[2] += transfer_loss_[i];
  });
  if (c > 0) energy_.damping += dt * damping_power;
  // kinetic damping: the option, or the fallback of adaptive damping where its estimate is zero (a
  // negative local stiffness, e.g. past a limit point: the motion would stay undamped)
  const bool kinetic_on = o.kinetic_damping || (scaled_ && o.adaptive_damping && c == 0.0);
  if (kinetic_on && kinetic < kinetic_previous_) {
    energy_.damping += kinetic;
    for (Index i = 0; i < n; ++i)
      for (int a = 0; a < 3; ++a) {
        if (free_(a, i) > 0) v_(a, i) = vpos_(a, i) = 0.0;
        omega_(a, i) = 0.0;
      }
    kinetic_previous_ = 0.0;
    kinetic = node_sums<1>([&](Index i, std::array<Real, 1>& s) { s[0] += 0.5 * dyn_mass_[i] * v_.col(i).squaredNorm(); })[0];
  } else {
    kinetic_previous_ = kinetic;
  }
  // external work over this step (loads at n, displacement with the velocity that moves the nodes,
  // after kinetic damping: a step whose velocities were zeroed at a peak moves nothing and does no work)
  const Real work = node_sums<1>([&](Index i, std::array<Real, 1>& s) {
    s[0] += f_ext_.col(i).dot(vpos_.col(i)) + m_ext_.col(i).dot(omega_.col(i));
  })[0];
  energy_.external += dt * work;
  energy_.kinetic = kinetic;
  energy_.transfer += transfer;
}

// 7. positions (eq (9)) and grid connectivity; a non-finite energy stops the run.
void MpmAnalysis::stage_position_update() {
  const Index n = x_.cols();
  const Real dt = step_.dt;
  const bool rotations = scaled_;
#pragma omp parallel for schedule(static) if (n > 4096)
  for (Index i = 0; i < n; ++i) {
    x_.col(i) += dt * vpos_.col(i);
    if (rotations) theta_.col(i) += dt * omega_.col(i);
  }
  locate_grid();
  if (!std::isfinite(energy_.kinetic) || !std::isfinite(energy_.internal))
    throw AnalysisError(fmt::format("non-finite energy at step {} (time {:.6g}): the run is unstable", steps_, time_));
}

}  // namespace lamina::mpm
