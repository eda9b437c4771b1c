#pragma once
// Explicit CPDI2 material point method with Belytschko-Tsay shell domains (seed 000): the analysis
// driver — explicit step eqs (1)-(14), adaptive time step eqs (38)-(40), quasi-static load levels.
//
// One explicit step is an ordered list of named stages (NairnMPM's tasks; mpm_step_stages.cpp), each
// timed into summary.json timing.stage_<name>_s; x^n and velocities at n-1/2 on entry:
//  element      every BT domain updates its stresses with the node velocities that moved it to x^n and
//               returns nodal forces/moments (eqs (17)-(37)); nodes gather them (no atomics); internal
//               and hourglass energies.
//  mass_scaling (mass-scaled quasi-static list only, mpm.mass_scaling: stiffness) fictitious masses
//               m_i = 1/4 sum_j |K_ij| from the element tangents (seed 002 eq (5)), refreshed every level
//               and every 1000 steps; adaptive damping c = 2 sqrt(u^T K u / u^T M u) on the level's
//               increment (seed 002 eq (6)).
//  time_step    dt = min(shell_safety * min_e L_e / c, alpha * cell / (c_dil + max |v_i|)) (eqs (38)-(40));
//               dt = 1 with mass scaling (Gershgorin bound).
//  loads        external loads at the load factor / time, damping forces, the residual ratio.
//  p2g          (eqs (1)-(4)) grid mass, momentum and force m_I = sum_c S_I(x_c) m_c, ... (each free
//               component separately, so a fixed component of a node adds nothing to the grid), and in
//               the same pass over the grid nodes the grid update (eqs (5)-(7)) v_I = (p_I + dt f_I) / m_I
//               (central adaptive damping: seed 002 eq (7)); grid nodes without free mass stay at rest.
//  g2p          (eq (8)) v_c = sum_I S_I(x_c) v_I (PIC) blended with the FLIP update v_c + dt sum_I S_I a_I
//               (options.flip; default 0 = PIC); rotations integrated at the nodes, omega += dt (m_ext -
//               m_int) / I; prescribed components imposed at the nodes.
//  damping      kinetic-energy damping (quasi-static default: velocities zeroed at each kinetic-energy
//               peak); damping, kinetic, external-work and transfer energies.
//  update       (eq (9)) x_c += dt sum_I S_I(x_c) v_I (the corners are shared by the domains, which
//               therefore stay gap-free); grid connectivity refreshed.
// A variant of the step is another list (step_stages), not an edit inside one long function.
#include <algorithm>
#include <array>
#include <map>
#include <initializer_list>
#include <memory>
#include <string>
#include <vector>

#include "core/analysis.hpp"
#include "core/step_stage.hpp"
#include "mpm/background_grid.hpp"
#include "mpm/cpdi2_domains.hpp"
#include "mpm/mpm_problem.hpp"
#include "mpm/shell_statics.hpp"
#include "parallel/communicator.hpp"
#include "shell/belytschko_tsay_shell.hpp"

namespace lamina::mpm {

/// Energy bookkeeping (LS-DYNA GLSTAT style).
struct EnergyBalance {
  Real kinetic = 0, internal = 0, hourglass = 0, external = 0, damping = 0;
  Real transfer = 0;  // kinetic energy lost in the grid transfer (PIC part of G2P), >= 0
  Real initial_kinetic = 0;  // kinetic energy of the initial velocities (an energy input like the external work)
  /// kinetic + internal + hourglass + damping + transfer - external - initial kinetic (0 = balanced).
  Real total() const { return kinetic + internal + hourglass + damping + transfer - external - initial_kinetic; }
  /// (kinetic + internal + hourglass + damping + transfer) / (external work + initial kinetic) (1 = balanced).
  Real ratio() const {
    const Real input = external + initial_kinetic;
    return input != 0 ? (kinetic + internal + hourglass + damping + transfer) / input : 1.0;
  }
};

class MpmAnalysis : public Analysis {
 public:
  /// Throws InputError for a bad mesh (defects), a grid too coarse for the elements, bad options.
  /// On several ranks (element decomposition): each rank updates the shell elements of its block and
  /// the element results are gathered every step; the nodes, grid and transfers are computed on every
  /// rank alike, so the result is the one-process result, bit for bit (docs/scaling.md).
  MpmAnalysis(MpmProblem problem, std::vector<Probe> probes,
              const parallel::Communicator& comm = parallel::Communicator::world());
  ~MpmAnalysis() override;

  std::string method() const override { return "mpm"; }
  void run(OutputSink& sink) override;
  Real probe(const Probe& probe) const override;
  std::map<std::string, Real> builtin_probes() const override;
  OutputFrame frame() const override;
  RunCounts counts() const override;
  std::map<std::string, Real> timings() const override;
  /// j2_plasticity set-ups that run but mislead: 3 or fewer thickness points (the section cannot carry
  /// much more than the first-yield moment), sudden quasi-static increments (early yield from the
  /// overshoot), a membrane hourglass coefficient of 0.05 or more with the coefficient springs (stiffens plastic folds).
  std::vector<std::string> warnings() const override;
  /// Checkpoints after any step (docs/restart.md).
  bool can_checkpoint() const override { return true; }
  void before_checkpoint() override { gather_state(); }
  void save_state(StateWriter& out) const override;
  void restore_state(const StateReader& in) override;

  /// One explicit step at load factor `load` (quasi-static) or the current time (dynamic).
  /// Returns the step size used. Throws AnalysisError on instability.
  Real advance(Real load);
  const EnergyBalance& energy() const { return energy_; }
  Real residual_ratio() const { return residual_ratio_; }
  Real time() const { return time_; }
  Index steps() const { return steps_; }
  const PointMatrix& positions() const { return x_; }
  const PointMatrix& reference_positions() const { return reference_; }
  Real grid_cell() const { return grid_.cell(); }
  Real node_mass_total() const { return mass_.sum(); }
  /// "shell" or "grid": which bound controlled the last time step.
  const std::string& time_step_control() const { return dt_control_; }
  const std::vector<Real>& level_residuals() const { return level_residual_; }
  const std::vector<int>& unconverged_levels() const { return unconverged_levels_; }
  /// Equivalent plastic strain of element e: the largest over its through-thickness points (0 if elastic).
  Real element_plastic_strain(Index e) const;
  /// Node value: the mean of element_plastic_strain over the elements at node i.
  Real nodal_plastic_strain(Index i) const;

 private:
  void compute_internal_forces(Real dt_stress);
  /// Several ranks: every element's stress and hourglass state on every rank (each rank advances its
  /// block only; before outputs and the fictitious-mass refresh).
  void gather_element_state();
  void prepare_loads();
  void compute_external_forces(Real load);
  void apply_prescribed(Real load);
  Real node_velocity_limit() const;
  /// Mass scaling: fictitious node masses / inertias from the row sums of the element tangents (finite
  /// differences of the element update at the current state), m_i = 1/4 sum_j |K_ij| (dt = 1).
  void compute_fictitious_masses();
  /// Adaptive damping coefficient from the Rayleigh quotient of the level's increment (seed 002 eq (6)).
  Real adaptive_damping_coefficient() const;
  /// Start of a quasi-static level: the increment of the damping estimate restarts, the masses are refreshed.
  void begin_level();
  /// mpm.solver newton (mpm_newton.cpp): the static state at load factor `to` from the one at `from`, in
  /// as many sub-increments as Newton's method needs. Returns false, at the last converged state and with
  /// the reason in the progress line, if it cannot get there (the level then goes on by explicit dynamics).
  bool solve_level_newton(Real from, Real to, OutputSink& sink);
  /// For the internal forces f_int, m_int and the loads f_ext_, m_ext_: the squared residual norm of
  /// stage_loads_and_residual (components weighted by 1 / mass, 1 / inertia) and its scale, the larger of
  /// the external and internal squared norms (residual ratio = sqrt(first / second)).
  std::pair<Real, Real> weighted_residual(const Eigen::Matrix3Xd& f_int, const Eigen::Matrix3Xd& m_int) const;
  std::unique_ptr<ShellStatics> statics_;
  Real newton_step_ = 0;            // the last sub-increment (load factor) size
  Index newton_increments_ = 0, newton_iterations_ = 0, newton_stopped_levels_ = 0;
  Real newton_first_stop_load_ = 0;  // load factor where Newton first stopped (under load control: a limit point); 0 = never
  Index newton_jumps_ = 0;           // sub-increments that converged on another branch (a limit point crossed)
  Real newton_first_jump_load_ = 0;  // the load factor before the first of them; 0 = none
  Real newton_largest_gap_ = 0;      // largest share of a sub-increment's work not stored, 0 if none (diagnostic)
  Real newton_last_rate_ = 0;        // largest nodal displacement per unit load factor of the last accepted
                                     // sub-increment; 0 = none since the start or the last stop
  std::array<Real, 3> newton_time_{};  // seconds: forces, tangent, linear solve

  /// The ordered stages of one step (core/step_stage.hpp); mass_scaled adds the fictitious-mass stage
  /// after the element stage.
  std::vector<StepStage> step_stages(bool mass_scaled);
  void stage_element_forces();
  void stage_mass_scaling();
  void stage_time_step();
  void stage_loads_and_residual();
  void stage_particle_to_grid();
  void stage_grid_to_particle();
  void stage_damping_and_energy();
  void stage_position_update();
  /// What one stage hands to the next within a step (set afresh by advance()).
  struct StepContext {
    Real dt = 0;               // this step's size
    Real damping = 0;          // c of the mass-proportional (or central adaptive) damping
    bool central_damping = false;
    Real keep = 1, divide = 1;  // central damping factors 1 -/+ c dt / 2
  };
  std::vector<StepStage> stages_;
  std::vector<Real> stage_time_;  // seconds per entry of stages_
  StepContext step_;

  MpmProblem problem_;
  std::vector<Probe> probes_;
  const parallel::Communicator& comm_;
  std::unique_ptr<material::ShellMaterial> material_;
  std::unique_ptr<shell::BelytschkoTsayShell> element_;
  BackgroundGrid grid_;

  // nodes (corners): structure of arrays
  PointMatrix reference_, x_, v_, vpos_, omega_;
  Eigen::VectorXd mass_, inertia_;            // physical (also the weights of the residual norm)
  Eigen::VectorXd dyn_mass_, dyn_inertia_;    // the masses of the motion: physical, or fictitious (mass scaling)
  bool scaled_ = false;                       // quasi-static with mass scaling
  // mass-scaled quasi-static state: level start, rotation increment, previous internal forces, damping
  PointMatrix level_start_, theta_;
  Eigen::Matrix3Xd f_int_previous_, m_int_previous_;
  Real adaptive_c_ = 0;
  Index masses_age_ = 0;                      // steps since the fictitious masses were computed
  bool masses_stale_ = true;
  std::vector<int> level_step_counts_;        // steps of each finished level (progress ETA)
  Eigen::Matrix3Xd free_, rotation_free_;  // 1 = free, 0 = prescribed (per component)
  Eigen::Matrix3Xd f_int_, m_int_, f_ext_, m_ext_, f_net_;
  // per-step work arrays, kept to avoid re-allocating them every step
  Eigen::Matrix3Xd m_net_, grid_velocity_, grid_acceleration_;
  std::vector<Index> incidence_begin_, incidence_;  // node -> element * 4 + corner

  struct PreparedLoad {
    std::vector<std::pair<Index, Real>> weights;  // node, share (force), edge length share (traction), mass (body force)
    std::vector<Index> elements;                  // pressure
    std::array<std::shared_ptr<geometry::Expression>, 3> expressions;
    std::shared_ptr<geometry::Expression> scalar_expression;
  };
  std::vector<PreparedLoad> prepared_loads_;
  Eigen::VectorXd transfer_loss_;

  // Several ranks (docs/scaling.md, "MPM decomposition"): this rank's block of nodes [node_first_,
  // node_last_), whole chunks of kSumChunk nodes (node_block_begins_: every rank's); the elements that
  // touch it (their forces complete the block's nodal forces; those on the block's edge are computed by
  // both neighbours); the elements it owns (first node in the block: the energies and the element-state
  // gather); the nodes near the block (within two grid cells of its bounding box: every node that shares
  // a grid node with it), the only ones the rank's grid locates. One process: every node and element.
  static constexpr Index kSumChunk = 64;
  Index node_first_ = 0, node_last_ = 0;
  std::vector<Index> node_block_begins_;
  std::vector<Index> rank_elements_;
  std::vector<char> owns_element_;
  std::vector<char> near_block_;
  std::vector<std::vector<char>> element_nodes_of_rank_;  // per rank: the nodes of the elements touching its block
  std::vector<std::vector<Index>> halo_send_, halo_receive_;  // per rank: the nodes this rank sends it / gets from it
  /// Locates the nodes in the background grid: all of them on one process, those near the block on several
  /// ranks (the same P2G sums on the grid nodes the block touches, hence the same G2P on the block); and
  /// the halo: the other ranks' nodes near the block or on its elements (their forces and velocities are
  /// exchanged every step), found from the positions every rank holds, so sender and receiver agree.
  void locate_grid();
  /// Sums of Q per-node terms (terms(i, sums) adds node i's) over every node, in chunks of kSumChunk
  /// nodes whose partial sums are added in chunk order: the same bits on one process and on any number of
  /// ranks (each sums its block's chunks; the partials are all-gathered). Collective.
  template <int Q, class Terms>
  std::array<Real, Q> node_sums(const Terms& terms) const;
  mutable std::vector<Real> sum_partials_;  // node_sums' chunk partials (kept: no allocation per step)
  Real power_sum_ = 0, hourglass_power_sum_ = 0, shortest_element_ = 0;  // element stage: sums and min over all elements
  /// Several ranks: every rank gets the node columns that their owners computed, of each (rows x nodes
  /// array, rows) listed.
  void gather_node_blocks(std::initializer_list<std::pair<Real*, int>> arrays);
  /// Several ranks: the halo columns of each (rows x nodes array, rows) listed, from their owners.
  void exchange_halo(std::initializer_list<std::pair<Real*, int>> arrays);
  /// Several ranks: the whole state on every rank (element state and every node's velocities, rotation
  /// rates and internal forces), before output points and checkpoints.
  void gather_state();

  // elements
  Eigen::MatrixXd stress_;                         // 5 * points x E
  Eigen::Matrix<Real, shell::BelytschkoTsayShell::kHourglassSize, Eigen::Dynamic> hourglass_;
  Eigen::VectorXd thickness_, element_power_, element_hourglass_power_, element_length_;
  Eigen::Matrix<Real, 12, Eigen::Dynamic> element_force_, element_moment_;

  // state
  Real time_ = 0, dt_ = 0, dt_previous_ = 0, residual_ratio_ = 1, kinetic_previous_ = 0;
  Real current_load_ = 0;
  Index steps_ = 0;
  std::string dt_control_ = "shell";
  Real wave_speed_ = 0;
  std::vector<int> unconverged_levels_;   // quasi-static levels that hit max_steps_per_level
  std::vector<Real> level_residual_;      // residual ratio at each recorded load level
  EnergyBalance energy_;
  // where run() is (checkpointed): quasi-static level and its steps, or the next output point
  struct RunLoop {
    int level = 1;
    Index level_steps = 0;
    bool level_done = false;  // the checkpoint was written after the level's output point
    int next_output = 1;
  } loop_;
  bool resumed_ = false;
  /// The checkpointed fields, listed once for save_state and restore_state.
  template <class Self, class Archive>
  static void state_fields(Self& self, Archive& archive);
};

template <int Q, class Terms>
std::array<Real, Q> MpmAnalysis::node_sums(const Terms& terms) const {
  const Index n = x_.cols(), chunks = (n + kSumChunk - 1) / kSumChunk;
  std::vector<Real>& partial = sum_partials_;
  partial.assign(static_cast<std::size_t>(Q * chunks), 0.0);
  // chunks in parallel: each writes its own partial, summed in chunk order below (the same bits for any
  // thread count)
  const Index first_chunk = node_first_ / kSumChunk, end_chunk = (node_last_ + kSumChunk - 1) / kSumChunk;
#pragma omp parallel for schedule(static) if (end_chunk - first_chunk > 16)
  for (Index k = first_chunk; k < end_chunk; ++k) {
    std::array<Real, Q> chunk{};
    for (Index i = k * kSumChunk; i < std::min(n, (k + 1) * kSumChunk); ++i) terms(i, chunk);
    std::copy(chunk.begin(), chunk.end(), partial.begin() + Q * k);
  }
  comm_.all_gather_blocks(partial.data(), Q, chunks);  // the chunk blocks of node_block_begins_
  std::array<Real, Q> total{};
  for (Index k = 0; k < chunks; ++k)
    for (int q = 0; q < Q; ++q) total[static_cast<std::size_t>(q)] += partial[static_cast<std::size_t>(Q * k + q)];
  return total;
}

}  // namespace lamina::mpm
