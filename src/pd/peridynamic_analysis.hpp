#pragma once
// `method: pd` - linearized ordinary state-based peridynamics (seed 002): linear static (CHOLMOD on
// the stiffness matrix), quasi-static by adaptive dynamic relaxation with displacement-controlled
// increments, explicit dynamics (velocity Verlet) and linear buckling (Spectra).
//
// Results
//   Probes: displacement / velocity x|y|z|magnitude at the nearest node (or the nearest node of a
//   set); strain / stress xx..zx (stress also von_mises) at the nearest node from the node's
//   least-squares displacement gradient over its family and the classical elasticity of its
//   material; reaction_force x|y|z|magnitude: sum over the selected nodes of -(F_int + F_ext)
//   (the support forces at prescribed dofs); energy internal|kinetic|external|total|damping;
//   eigenvalue k (buckling: the k-th load factor of the reference load).
//   Builtin probes (history.csv): quasi_static: iterations, total_iterations, residual, damping_energy,
//   path_load, path_displacement (P and Delta along the unit reference load), tangent_stiffness_ratio,
//   stiffness_changes and stiffness_change_k_load / _ratio (k <= 3; pd/load_path_events.hpp),
//   linear_buckling_load and first_buckling_ratio (imperfection: buckling_mode);
//   explicit: kinetic_energy, strain_energy, external_work, energy_error; buckling: load_factor_k.
// On several ranks (mpirun): explicit dynamics of the lattice model, each rank owning a part of the
// nodes (pd/rank_nodes.hpp); probes, energies and counts are of the whole body on every rank, frames
// hold the rank's own nodes (one VTU piece per rank).
#include <map>
#include <optional>
#include <memory>
#include <string>
#include <vector>

#include "core/analysis.hpp"
#include "pd/adaptive_dynamic_relaxation.hpp"
#include "pd/force_split.hpp"
#include "pd/linear_peridynamic_solid.hpp"
#include "parallel/communicator.hpp"
#include "pd/peridynamic_problem.hpp"
#include "pd/rank_nodes.hpp"

namespace lamina::pd {

class PeridynamicAnalysis : public Analysis {
 public:
  /// Checks the probes (InputError for unsupported fields / components).
  /// On a communicator of several ranks (collective) the problem (the whole body, the same on every
  /// rank) is partitioned (explicit) or kept whole with the force work split (quasi_static; linear_static
  /// solves through PETSc); SingleProcessOnly for the analyses that run on one process only.
  PeridynamicAnalysis(PeridynamicProblem problem, std::vector<Probe> probes,
                      const parallel::Communicator& comm = parallel::Communicator::world());

  /// One-layer plates: a buckling mode with wavenumber x horizon above this is named as too short.
  static constexpr Real kShortModeResolution = 0.9;

  std::string method() const override { return "pd"; }
  void run(OutputSink& sink) override;
  Real probe(const Probe& probe) const override;
  std::map<std::string, Real> builtin_probes() const override;
  OutputFrame frame() const override;
  bool frame_is_rank_piece() const override { return ranks_ != nullptr; }
  RunCounts counts() const override;
  std::map<std::string, Real> timings() const override { return timings_; }
  /// quasi_static and explicit runs write checkpoints (after each increment / step).
  bool can_checkpoint() const override;
  /// Several ranks: the per-node state of the whole body on every rank (rank 0 writes it), and back.
  void before_checkpoint() override;
  void after_checkpoint() override;
  void save_state(StateWriter& out) const override;
  void restore_state(const StateReader& in) override;

  /// Runs without an output sink (tests).
  void solve();

  const PeridynamicBody& body() const { return *body_; }
  const PeridynamicModel& model() const { return *model_; }
  const PointMatrix& displacement() const { return u_; }
  const PointMatrix& internal_force() const { return internal_force_; }
  Vec3 reaction(const IndexList& nodes) const;
  Vec3 strain_gradient_at(Index node, Mat3& gradient) const;
  const std::vector<Real>& eigenvalues() const { return eigenvalues_; }
  const std::vector<PointMatrix>& modes() const { return modes_; }
  Real internal_energy() const { return energy_internal_; }
  Real kinetic_energy() const { return energy_kinetic_; }
  Real external_work() const { return energy_external_; }
  Real damping_energy() const { return energy_damping_; }
  /// Per-increment ADR iteration counts (quasi_static).
  const std::vector<int>& increment_iterations() const { return increment_iterations_; }
  /// Load path P(Delta) of a quasi_static run (first entry: the unloaded state).
  const std::vector<Real>& path_load() const { return path_load_; }
  const std::vector<Real>& path_displacement() const { return path_displacement_; }

 private:
  void build_body(const PointMatrix& positions);
  /// Whether the body keeps lean bond storage (BodyOptions::bond_storage resolved for this analysis).
  bool lean_bond_storage() const;
  PointMatrix external_force(Real factor) const;
  void apply_prescribed(PointMatrix& u, Real factor, bool velocities) const;
  Real ramp(int index, Real factor) const;
  std::vector<char> free_dofs(bool include_velocity) const;
  void run_linear_static(OutputSink* sink);
  void run_quasi_static(OutputSink* sink);
  void run_explicit(OutputSink* sink);
  void run_buckling(OutputSink* sink);
  /// Linear static solution at load factor 1 (used by linear_static and buckling).
  /// petsc: solved through PETSc (solver: mumps | cg; linear_static on several ranks), else CHOLMOD.
  PointMatrix linear_solution(solve::SparseMatrix& k0_upper, bool check = false, bool petsc = false);
  /// Refuses (InputError, exit 2) an unloaded stiffness with a zero-energy mode on the free dofs:
  /// a rigid-body motion the supports leave free, or a spurious mode of the lattice / horizon.
  void check_unloaded_stiffness(const solve::SparseMatrix& k0_upper);
  /// Buckling load factors and modes of the current body under the reference load.
  void buckling_modes(int count);
  Index nearest_node(const Vec3& x, const IndexList& candidates) const;
  /// A probe over this rank's nodes (all of them on one process); probe() combines the ranks'.
  Real local_probe(const Probe& probe) const;
  Real distributed_probe(const Probe& probe) const;
  /// Refuses (InputError) what a distributed run does not do, before the partition.
  void check_distributable() const;
  /// The body is a 1-4 layer plate lattice that a plate model (director: 2-4 layers, Kirchhoff: one) will discretise.
  bool plate_lattice() const;
  /// Several ranks without a node partition (quasi_static: replicated data, split work): from now on the
  /// model computes the internal forces of this rank's block of nodes only (on, force_split.hpp), or every
  /// node (off).
  void split_force_work(bool on);

  void update_energy();

  PeridynamicProblem problem_;
  std::vector<Probe> probes_;
  std::unique_ptr<PeridynamicBody> body_;
  std::unique_ptr<PeridynamicModel> model_;  // the lattice solid, or the plate model of a plate lattice
  PointMatrix u_, velocity_, internal_force_, external_force_;
  std::unique_ptr<ModelState> state_;
  std::vector<Real> eigenvalues_;
  std::vector<PointMatrix> modes_;
  std::vector<int> increment_iterations_;
  std::vector<Real> path_load_, path_displacement_;  // quasi_static: P and Delta per converged increment (0 first)
  long long total_iterations_ = 0;                   // quasi_static: all ADR iterations, failed attempts included
  Real path_total_ = 0;                              // |sum of the reference pattern| (total reference load)
  Real imperfection_load_factor_ = 0;                // first buckling load factor (imperfection: buckling_mode)
  Real energy_internal_ = 0, energy_kinetic_ = 0, energy_external_ = 0, energy_damping_ = 0;
  Real last_residual_ = 0, energy_error_ = 0;
  int last_iterations_ = 0;
  Index steps_ = 0;
  std::map<std::string, Real> timings_;
  const PlateColumns* plate_columns_ = nullptr;  // the plate model's columns (owned by model_), else null
  std::string model_reason_;  // why a 3D body is not a plate lattice (the lattice model applies)
  const parallel::Communicator& comm_;
  std::unique_ptr<ForceSplit> force_split_;  // several ranks, quasi_static: the force decomposition
  std::unique_ptr<RankNodes> ranks_;  // several ranks: this rank's nodes; null on one process
  /// Several ranks, between before_ and after_checkpoint: the rank's own per-node arrays (the members
  /// hold the whole body's meanwhile).
  std::vector<PointMatrix> local_during_checkpoint_;
  Eigen::VectorXd local_acceleration_during_checkpoint_;
  PointMatrix whole_body(const PointMatrix& local) const;  // owned columns of every rank, all ranks
  PointMatrix this_rank(const PointMatrix& whole) const;   // the local columns of a whole-body array
  Eigen::VectorXd owned_dof_;         // several ranks: 1 on the owned dofs, 0 on the halo's

  // The loop state between increments / steps (checkpointed with the fields above).
  bool resumed_ = false;  // restore_state was called: run() continues from it
  struct QuasiStaticLoop {
    Real step = 0, factor = 0, previous_factor = 0;
    Real third_factor = 0;               // the load factor of `third`
    PointMatrix previous, before_previous, third, generalized_force;  // converged fields at factor, previous_factor, third_factor
    bool have_two = false, have_three = false;
    int cuts = 0;
    int density_doublings = 0;           // times the ADR density was doubled after a diverged block
    Index increment = 0;
  } quasi_;
  struct ExplicitLoop {
    Index step = 0;                   // steps done
    Real time_step = 0;               // dt of the run (end_time / steps)
    Index origin_step = 0;            // t = origin_time + (step - origin_step) dt (a restart with a new end time
    Real origin_time = 0;             //   re-divides the rest of the run)
    Real end_time = 0;                // of the run that wrote the state
    Real initial_total = 0;           // energy at t = 0
    Eigen::VectorXd acceleration;     // at the end of the last step
    PointMatrix support_force;        // generalized external force at the end of the last step
  } explicit_;
  /// The checkpointed fields, listed once for save_state and restore_state.
  template <class Self, class Archive>
  static void state_fields(Self& self, Archive& archive);
};

}  // namespace lamina::pd
