#pragma once
// `method: mpfem` — moving particle finite element method for 2D elastostatics (seed 001):
// five-node particle elements, particle quadrature of eqs (4)-(6), essential conditions on particle dofs, CHOLMOD.
// analysis large_deformation (mpfem_large_deformation.cpp, docs/mpfem.md section 9): total-Lagrangian
// Newton over the same quadrature written as energy points (energy_points.hpp), neighbourhoods rebuilt
// from the current positions.
//
// Stiffness with particle_strain: cell (default on grid particle sets; tributary_cells.hpp) or voronoi
// (default on other particle sets of convex bodies; Voronoi cells clipped to the hull, voronoi_cells.hpp):
//   K = sum_I t [ |Omega_I| B_I^T C B_I + sum_ab M_ab,I G_a,I^T C G_b,I
//                 + beta |Omega_I| / A_I sum_{T in E_I} A_T (B_T - B_I)^T C (B_T - B_I) ]
//   B_I: cell-mean strain; G_a,I = sum_{J in E_I} dN_J/dx_a B_J: the strain gradient from the
//   five-node element built on the cell centroids; M_I: second moments of Omega_I about its
//   centroid. The M term restores the energy of the strain variation inside a cell that
//   one-point particle quadrature loses; G vanishes for linear fields (patch test kept).
//   Particle strain reported: B_I u + G_I u (x_I - c_I) (the cell mean moved to the particle).
// Stiffness with particle_strain: star (seed eq 4, stabilised; docs/mpfem.md)
//   K = sum_I dV_I [ B_I^T C B_I + beta (1/A_I) sum_{T in E_I} A_T (B_T - B_I)^T C (B_T - B_I) ]
//   B_I: the mean strain operator of particle I's five-node element, B_T: that of one of its
//   triangles. The second term vanishes for every linear field (B_T u = B_I u), so it does not
//   disturb the patch test; it removes the zero-energy (odd-even) modes of pure particle
//   quadrature. beta = mpfem.stabilization (0 < beta <= 1).
//   Body force (eq 5): f_I = b(x_I) dV_I. Tractions (eq 6): f_I = t(x_I) dS_I (particle) or the
//   2-point Gauss rule on each boundary segment (gauss, default).
//   Point forces: the total shared equally by the selected particles (Kronecker delta).
// Essential conditions: prescribed particle dofs are eliminated (K_ff u_f = f_f - K_fp u_p).
// Results: particle displacements u_I; particle strain B_I u, stress C B_I u (plane stress:
//   szz = 0, ezz from nu; plane strain: ezz = 0, szz = nu (sxx + syy)); reactions K u - f at the
//   prescribed dofs. With element t3: strains/stresses at particles are the area-weighted means of
//   the adjacent triangles.
// Probes: displacement at `at`: the blended interpolant (nearest particle outside the body);
//   strain/stress: the nearest particle's value; reaction_force: sum over the selected particles;
//   energy: internal 1/2 u.K u, external (Clapeyron) 1/2 (f.u + R.u_prescribed), total = internal.
//   Builtin probes: h (sqrt(area / N)); with exact_displacement: err_displacement, err_stress
//   (max particle error / max exact), err_l2 (relative L2 displacement error over the element
//   triangles), err_energy (relative energy-norm error of the element interpolants),
//   err_energy_particles (same with the particle strains and the particle quadrature).
#include <map>
#include <string>
#include <vector>

#include "core/analysis.hpp"
#include "core/step_stage.hpp"
#include "material/hyperelastic.hpp"
#include "mpfem/energy_points.hpp"
#include "mpfem/mpfem_problem.hpp"
#include "mpfem/particle_elements.hpp"
#include "mpfem/tributary_cells.hpp"
#include "mpfem/voronoi_cells.hpp"
#include "parallel/communicator.hpp"
#include "solve/sparse_linear_solver.hpp"

namespace lamina::mpfem {

class MpfemAnalysis : public Analysis {
 public:
  /// Builds the particle elements (InputError for degenerate particle sets) and checks probes.
  /// On several ranks every rank builds and assembles the whole (2D) model and PETSc solves the
  /// systems, each rank passing its block of rows (solver: mumps by default there, or cg).
  MpfemAnalysis(MpfemProblem problem, std::vector<Probe> probes,
                const parallel::Communicator& comm = parallel::Communicator::world());

  std::string method() const override { return "mpfem"; }
  void run(OutputSink& sink) override;
  Real probe(const Probe& probe) const override;
  std::map<std::string, Real> builtin_probes() const override;
  OutputFrame frame() const override;
  RunCounts counts() const override;
  std::map<std::string, Real> timings() const override { return timings_; }

  /// Assemble and solve without an output sink (tests).
  void solve();
  /// Counters of the large-deformation analysis (summary.json builtin probes).
  struct LargeDeformationStats {
    Index increments = 0, newton_iterations = 0, cuts = 0, rebuilds = 0, rebuilt_particles = 0;
  };
  const LargeDeformationStats& large_deformation_stats() const { return stats_; }
  /// Internal force vector and (optionally) tangent stiffness (full storage) of the large-deformation
  /// energy at particle displacements u (2N); false if a deformation gradient has J <= 0. Tests.
  bool internal_forces(const Eigen::VectorXd& u, Eigen::VectorXd& force, solve::SparseMatrix* tangent, Real* energy) const;
  /// The energy points of the current elements (done by the large-deformation solve; tests).
  void build_energy_points();
  /// Re-discretise: rebuild the five-node elements and weights from new particle positions.
  void rebuild(const Points2& positions);

  const ParticleDiscretization& discretization() const { return discretization_; }
  const Points2& positions() const { return problem_.layout.positions; }
  Vec2 displacement(Index particle) const { return u_.segment<2>(2 * particle); }
  Eigen::Vector3d particle_stress(Index particle) const { return stress_.col(particle); }  // sxx syy sxy
  Eigen::Vector3d particle_strain(Index particle) const { return strain_.col(particle); }  // exx eyy gxy
  Vec2 displacement_at(const Vec2& x) const;
  Vec2 reaction(const IndexList& particles) const;
  Real internal_energy() const { return energy_internal_; }
  Real total_volume() const;
  const solve::SolverReport& solver_report() const { return solver_report_; }
  /// Assembled stiffness (full storage, 2N x 2N, after solve).
  const solve::SparseMatrix& stiffness() const { return stiffness_; }
  /// Relative errors against options.exact_displacement (-1 if none).
  struct Errors {
    Real l2 = -1, energy = -1, energy_particles = -1, max_displacement = -1, max_stress = -1;
  };
  const Errors& errors() const { return errors_; }

 private:
  /// The ordered stages of the analysis (core/step_stage.hpp): linear: assemble, solve (essential
  /// conditions eliminated; reactions, energies), strains (particle strains and stresses); large
  /// deformation: the Newton increments (mpfem_large_deformation.cpp); then errors. Timed <name>_s.
  std::vector<StepStage> stages(OutputSink* sink);
  void assemble_linear();
  void solve_linear();
  void particle_strains_and_stresses();
  void solve_with(OutputSink* sink);
  void solve_large_deformation(OutputSink* sink);  // mpfem_large_deformation.cpp
  /// Particles whose neighbours chosen on the current positions differ from their element's.
  Index changed_neighbourhoods(const Eigen::VectorXd& u, std::vector<std::array<Index, 4>>& chosen) const;
  void large_deformation_results();
  void build_cell_operators();
  /// Sparse 3 x 2N strain operator: (particle, 3 x 2 block) pairs.
  using StrainBlocks = std::vector<std::pair<Index, Eigen::Matrix<Real, 3, 2>>>;
  void assemble_cell_stiffness(std::vector<Eigen::Triplet<Real, int>>& triplets) const;
  void compute_errors();
  Eigen::VectorXd load_vector() const;
  Index nearest_particle(const Vec2& x) const;
  Real field_probe(const Probe& probe) const;

  struct Triangle {  // for error integration and the t3 reference element
    std::array<Index, 3> nodes;
    Real area;
    Eigen::Matrix<Real, 2, 3> gradient;
    Real weight;  // 1 / covering
  };
  std::vector<Triangle> error_triangles() const;
  std::vector<Triangle> grid_triangles() const;

  /// The solve of the linear systems: CHOLMOD, or PETSc (several ranks or solver: mumps | cg).
  Eigen::VectorXd solve_system(const solve::SparseMatrix& upper, const Eigen::VectorXd& rhs,
                               const solve::SolverOptions& options, bool positive_definite);

  MpfemProblem problem_;
  std::vector<Probe> probes_;
  const parallel::Communicator& comm_;
  ParticleDiscretization discretization_;
  bool cell_strain_ = false;
  TributaryCells cells_;
  std::vector<StrainBlocks> cell_strain_ops_;                // B_I (cell mean)
  std::vector<std::array<StrainBlocks, 2>> strain_gradient_;  // G_x,I and G_y,I
  std::vector<std::array<GradientList, 2>> strain_gradient_vectors_;  // the same as gradient lists
  std::vector<std::vector<EnergyPoint>> energy_points_;    // large deformation (energy_points.hpp)
  std::vector<material::Hyperelastic> hyperelastic_;      // per material
  LargeDeformationStats stats_;
  std::vector<PlaneMaterial> materials_;
  solve::SparseMatrix stiffness_;  // full (both triangles), 2N x 2N
  Eigen::VectorXd f_, u_, reactions_;
  Eigen::Matrix3Xd strain_, stress_;
  Eigen::VectorXd out_of_plane_;
  Real energy_internal_ = 0, energy_external_ = 0;
  Errors errors_;
  solve::SolverReport solver_report_;
  std::map<std::string, Real> timings_;
  bool solved_ = false;
};

}  // namespace lamina::mpfem
