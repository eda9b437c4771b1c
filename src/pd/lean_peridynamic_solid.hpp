#pragma once
// LeanPeridynamicSolid: the linear peridynamic solid of linear_peridynamic_solid.hpp (same energy,
// forces and kinematics, Silling 2007 eq (93), seed 002 eqs (1)-(4)) over a body with lean bond
// storage: per bond only the neighbour index is kept; the reference bond, influence, partial volume,
// dilatation weights w^a_ij = omega x (d^a_i . n^2) and bond modulus c_ij = omega (g_i . phi(n)) are
// recomputed from the positions and per-node constants in each pass, for both ends of the bond (so no
// reverse-bond index either). Two gather passes over each node's bonds per force evaluation:
//   update:         e_ij, theta_i = sum_j w_ij e_ij beta V_j, Q_i theta_i, sum_j c_ij e_ij^2 beta V_j
//   internal_force: F_i = sum_j V_i beta V_j (t_ij + t_ji) M_ij
// Deterministic for any thread count. No stiffness (explicit dynamics with a given time step).
#include "pd/peridynamic_body.hpp"
#include "pd/peridynamic_model.hpp"

namespace lamina::pd {

/// Per-node state of one configuration: the displacement it was made from and the dilatations.
struct LeanState : ModelState {
  PointMatrix u;                 // 3 x N
  bool linearised = false;
  Eigen::Matrix3Xd dilatation;   // theta_a per node (a < 3; plain LPS: row 0 only)
  Eigen::Matrix3Xd dilatation_force;  // Q theta per node
  Eigen::VectorXd bond_energy;   // sum_j c_ij e_ij^2 beta V_j per node
};

class LeanPeridynamicSolid : public PeridynamicModel {
 public:
  /// The body must use lean storage (BodyOptions::lean_bonds) and be calibrated.
  explicit LeanPeridynamicSolid(const PeridynamicBody& body);

  std::string name() const override { return "lattice"; }
  std::unique_ptr<ModelState> make_state() const override { return std::make_unique<LeanState>(); }
  void update(const PointMatrix& u, ModelState& state, bool linearised) const override;
  PointMatrix internal_force(const ModelState& state) const override;
  Real strain_energy(const ModelState& state) const override;
  /// Not available with lean storage: throws AnalysisError (give pd.explicit.time_step).
  solve::SparseMatrix stiffness(const ModelState& state, bool material, bool geometric) const override;
  Eigen::VectorXd nodal_dilatation(const ModelState& state) const override;

 private:
  template <int K>
  void update_kernel(LeanState& s) const;
  template <int K>
  void force_kernel(const LeanState& s, PointMatrix& f) const;

  const PeridynamicBody& body_;
  int components_ = 3;  // dilatations in use: 1 (plain LPS) or 3 (energy correction)
};

}  // namespace lamina::pd
