#pragma once
// `method: efg` — element-free analysis of 3D linear elastostatics (seed 004, eqs 1-30..1-35):
// MLS shape functions over the nodes, background cells with Gauss quadrature mapped onto the
// generator body, essential conditions by penalty / Nitsche / Lagrange multipliers, CHOLMOD solve
// (efg.formulation galerkin). The strong forms (collocation, weighted_least_squares: residual rows
// at the nodes, strong_form_residuals.hpp) share the setup, loads, results and probes; their
// reactions are sigma(u^h) n integrated over the constrained faces, their energies the volume
// integral of the strain energy density and the work of the loads.
//
// Results
//   The nodal unknowns u_I are MLS parameters, not displacements: the displacement anywhere is
//   u^h(x) = sum_I phi_I(x) u_I. Probes and VTU fields report u^h, its strain and the stress
//   D(material at x) strain. VTU: displacement (3), strain (6, engineering shear), stress (6),
//   von_mises, material_id, nodal_parameter (3: u_I).
//   Probes: displacement x|y|z|magnitude, strain and stress xx|yy|zz|xy|yz|zx (stress also
//   von_mises) at `at` (or the nearest node of `set`), or, with a selection and no `at`, the
//   value of largest magnitude over the selected nodes (sign kept); reaction_force x|y|z|magnitude
//   over a selection: the constraint forces of the essential conditions (penalty, Nitsche flux
//   or multiplier) at the constraint points whose nearest node is selected (the total over all
//   nodes equals minus the applied load; with integration.correction: vci the test space no longer
//   contains the constants, so global equilibrium and this balance hold only approximately,
//   e.g. 0.5 % on the clamped plate, 8 % on the coarse curved beam); energy internal (1/2 u^T K u without the constraint
//   terms, the strain energy), external (Clapeyron: 1/2 (f . u + reactions . prescribed
//   displacements), equal to internal at equilibrium), kinetic (0), total (internal).
//   Builtin probes with efg.exact_displacement: err_displacement, err_stress (max over the nodes
//   of |error| / max |exact|).
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/analysis.hpp"
#include "core/step_stage.hpp"
#include "efg/background_quadrature.hpp"
#include "efg/efg_problem.hpp"
#include "efg/essential_boundary.hpp"
#include "efg/region_test.hpp"
#include "efg/strong_form_residuals.hpp"
#include "efg/volumetric_projection.hpp"
#include "mls/mls_shape_functions.hpp"
#include "mls/neighbour_search.hpp"
#include "parallel/communicator.hpp"
#include "solve/sparse_linear_solver.hpp"

namespace lamina::efg {

class EfgAnalysis : public Analysis {
 public:
  /// Checks the probes (InputError for unsupported fields / components).
  /// On several ranks (mpirun) every rank builds the whole model, assembles its slab of the background
  /// cells and the system is solved by PETSc (solver: mumps, the default there, or cg); results are
  /// then whole on every rank. InputError for the formulations that run on one process only.
  EfgAnalysis(EfgProblem problem, std::vector<Probe> probes,
              const parallel::Communicator& comm = parallel::Communicator::world());
  ~EfgAnalysis() override;

  std::string method() const override { return "efg"; }
  void run(OutputSink& sink) override;
  Real probe(const Probe& probe) const override;
  std::map<std::string, Real> builtin_probes() const override;
  OutputFrame frame() const override;
  RunCounts counts() const override;
  std::map<std::string, Real> timings() const override { return timings_; }

  /// Runs without an output sink (tests, benchmarks).
  void solve();

  // Results (after run/solve).
  Vec3 displacement_at(const Vec3& x) const;
  material::Voigt strain_at(const Vec3& x) const;
  material::Voigt stress_at(const Vec3& x) const;
  const Eigen::VectorXd& nodal_parameters() const { return u_; }
  Real quadrature_volume() const;
  /// Likely set-up mistakes that still run: nu > 0.45 without a volumetric remedy; supports holding a
  /// large share of the body (slow, nearly global shape functions); sphere supports on spacings that
  /// differ more than kSphereAnisotropy times between directions.
  std::vector<std::string> warnings() const override;
  static constexpr double kCrowdedSupport = 400.0;   // mean support population that counts as crowded
  static constexpr double kSphereAnisotropy = 4.0;   // spacing ratio beyond which a sphere is a poor fit
  Real internal_energy() const { return energy_internal_; }
  Real external_energy() const { return energy_external_; }
  /// Sum of the constraint (reaction) forces attributed to the given nodes (all if empty).
  Vec3 reaction(const IndexList& nodes) const;
  const solve::SolverReport& solver_report() const { return solver_report_; }
  const VolumeQuadrature& volume_points() const { return volume_; }
  const SurfaceQuadrature& surface_points() const { return surface_; }
  const std::vector<ConstraintPoint>& constraint_points() const { return constraint_points_; }
  const EfgProblem& problem() const { return problem_; }

 private:
  std::vector<std::string> support_warnings() const;
  void setup();
  void assign_materials();
  void build_constraints();
  void build_loads();
  /// The ordered stages of the static analysis (core/step_stage.hpp): set-up, materials, constraints,
  /// loads, then assemble / linear_solve / energy (galerkin) or strong_form, then post; each timed
  /// into timings <name>_s. run() and solve() run this list.
  std::vector<StepStage> stages(OutputSink* sink);
  void run_static(OutputSink* sink);
  void assemble_galerkin(OutputSink* sink);
  void solve_galerkin(OutputSink* sink);
  void galerkin_energies();
  /// Collocation / weighted least squares (efg.formulation): strong-form rows at the nodes, solve,
  /// then reactions (traction sigma(u^h) n integrated over the constrained surfaces) and energies.
  void solve_strong_form(OutputSink* sink);
  std::vector<StrongFormPoint> strong_form_nodes() const;
  void strong_form_reactions_and_energies();
  void postprocess();
  int material_at(const Vec3& x) const;
  /// Copies the solver report (factor and solve times, residuals, rcond, method) into the timings.
  void record_solver_report();
  /// Stress of material m from the strain at x (with the projected pressure when projected).
  material::Voigt stress_of(int m, const material::Voigt& strain, const Vec3& x) const;
  Index nearest_node(const Vec3& x) const;
  /// One RegionTest of `region` on the boundary surface per thread (refine_selected_faces).
  SelectorFactory surface_selector(const model::Selection& region, Real tolerance) const;
  Real field_probe(const Probe& probe) const;

  EfgProblem problem_;
  std::vector<Probe> probes_;
  const parallel::Communicator& comm_;
  std::vector<material::LinearElastic> materials_;
  std::unique_ptr<BackgroundCells> cells_;
  VolumeQuadrature volume_;
  VolumeQuadrature reduced_;                 // selective reduced integration rule (empty if unused)
  SurfaceQuadrature surface_;
  std::vector<int> material_of_point_;
  std::vector<int> material_of_reduced_point_;
  std::unique_ptr<mls::MlsShapeFunctions> shapes_;
  // Points other than the volume Gauss points (conditions, surface loads, the smoothing's face points, the
  // nodes, probes) are evaluated with the singular remedy (shapes_->evaluate(..., grow_at_points_)): points
  // on the body's faces, edges and corners can see too few node planes with a support that is regular at
  // every Gauss point. Set by setup() for the Galerkin formulation.
  bool grow_at_points_ = false;
  Index grown_boundary_points_ = 0;  // evaluations at such points where the support grew (noted in the log)
  static Index count_grown(const std::vector<mls::ShapeFunctionValues>& values) {
    Index grown = 0;
    for (const auto& v : values) grown += v.remedy_steps > 0 ? 1 : 0;
    return grown;
  }
  // projected volumetric term (efg.integration.volumetric: projected)
  std::unique_ptr<mls::MlsShapeFunctions> pressure_shapes_;  // pressure nodes: support search and radii
  std::unique_ptr<ShepardPressure> pressure_;                  // the pressure functions over them
  std::unique_ptr<ProjectedVolumetric> projection_;
  std::vector<material::LinearElastic> deviatoric_materials_;  // lambda = 0, same mu
  Eigen::VectorXd nodal_pressure_;           // lambda_I theta_I per node (projected only)
  std::unique_ptr<mls::CellList> node_search_;
  std::vector<std::unique_ptr<RegionTest>> material_tests_;
  std::vector<ConstraintPoint> constraint_points_;
  std::vector<Vec3> reactions_;            // per constraint point: force on the body
  std::vector<Index> constraint_nearest_;  // per constraint point: nearest node
  struct PointLoad {
    Vec3 x;
    Vec3 force;
  };
  std::vector<PointLoad> point_loads_;       // nodal forces and surface tractions (times weight)
  Eigen::Matrix3Xd body_force_;              // 3 x Q (empty without body forces)
  Eigen::VectorXd f_loads_;                  // 3N load vector of the applied loads
  Eigen::VectorXd u_;                        // 3N nodal parameters
  Eigen::VectorXd multipliers_;
  Real alpha_surface_ = 0, alpha_point_ = 0;
  Real energy_internal_ = 0, energy_external_ = 0;
  Real error_displacement_ = -1, error_stress_ = -1;
  // nodal fields
  Eigen::Matrix3Xd node_displacement_;
  Eigen::Matrix<Real, 6, Eigen::Dynamic> node_strain_, node_stress_;
  std::vector<int> node_material_;
  /// The assembled Galerkin system between the assemble, linear_solve and energy stages (released after).
  struct GalerkinSystem {
    solve::SparseMatrix K;        // upper triangle when symmetric
    Eigen::VectorXd f;
    bool symmetric = true;
    std::vector<mls::ShapeFunctionValues> constraint_shapes;  // at the constraint points (first derivatives)
    std::vector<Eigen::Triplet<Real>> multiplier_entries;     // Lagrange: rows 3N + k of the constraint matrix
    Eigen::VectorXd multiplier_rhs;
    Index multipliers = 0;
  };
  std::unique_ptr<GalerkinSystem> system_;
  solve::SolverReport solver_report_;
  std::map<std::string, Real> timings_;
  std::vector<std::string> notices_;  // choices the defaults made, for the run's log (OutputSink::notice)
  bool solved_ = false;
};

}  // namespace lamina::efg
