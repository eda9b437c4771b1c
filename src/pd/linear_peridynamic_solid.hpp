#pragma once
// LinearPeridynamicSolid: internal forces, strain energy and stiffness of the linear peridynamic
// solid with geometrically exact kinematics (seed 002 eqs (1)-(4); Silling 2007 eq (93)).
//
//   e_ij = |Y_ij| - |xi_ij|, M_ij = Y_ij / |Y_ij|            (deformed length and direction)
//   theta_i,a = sum_j w^a_ij e_ij beta V_j (a < 6: three normal, three shear - plate correction only),   t_ij = (Q_i theta_i) . w_ij + c_ij e_ij
//   F_i = sum_j P_ij M_ij,   P_ij = V_i beta V_j (t_ij + t_ji)  (nodal force, N)
//   Pi  = sum_i V_i (1/2 theta_i^T Q_i theta_i + 1/2 sum_j c_ij e_ij^2 beta V_j)
// Stiffness (seed 002 section 2.2, Silling 2010 modulus state): K = d^2 Pi / dU^2 =
//   sum_i V_i grad(theta_i) Q_i grad(theta_i)^T                     (couples neighbours of neighbours: 2 delta)
//   + sum_bonds V_i beta V_j (c_ij + c_ji) M M^T pattern [[1,-1],[-1,1]]
//   + sum_bonds P_ij (I - M M^T) / |Y| same pattern                   (geometric stiffness)
// Forces are gathered per node over its own bond list (deterministic for any thread count).
#include "pd/peridynamic_body.hpp"
#include "pd/peridynamic_model.hpp"
#include "solve/sparse_linear_solver.hpp"

namespace lamina::pd {

/// Bond kinematics and forces of one configuration.
struct BondState : ModelState {
  Eigen::Matrix3Xd direction;     // M per directed bond
  Eigen::VectorXd length;         // |Y|
  Eigen::VectorXd extension;      // e
  Eigen::Matrix3Xd dilatation;        // normal generalized dilatations theta_a per node (zero padded to 3 rows)
  Eigen::Matrix3Xd shear_dilatation;  // theta_yz, theta_xz, theta_xy (surface_correction: plate; else zero)
  Matrix6X dilatation_force;          // Q theta per node (6 rows)
  Eigen::VectorXd pair_force;     // P per directed bond (equal for b and reverse(b))
};

class LinearPeridynamicSolid : public PeridynamicModel {
 public:
  /// The body must be complete (calibrated): the solid caches its reverse-bond data.
  explicit LinearPeridynamicSolid(const PeridynamicBody& body);

  /// Bond state of displacement u (3 x N). linearised: e = M0 . (u_j - u_i), M = xi / |xi| (small-strain theory).
  BondState bond_state(const PointMatrix& u, bool linearised = false) const;
  /// The same into an existing state (no allocation when its sizes already fit).
  void bond_state(const PointMatrix& u, BondState& state, bool linearised = false) const;
  /// Internal nodal forces F_int = -dPi/dU (3 x N) of a bond state.
  PointMatrix internal_force(const BondState& state) const;
  PointMatrix internal_force(const PointMatrix& u) const { return internal_force(bond_state(u)); }
  /// Strain energy Pi of a bond state.
  Real strain_energy(const BondState& state) const;
  /// Strain energy density W_i per node.
  Eigen::VectorXd energy_density(const BondState& state) const;

  /// Stiffness at a bond state, upper triangle of the 3N x 3N matrix (dof 3 i + a).
  /// material: the first two terms; geometric: the third.
  solve::SparseMatrix stiffness(const BondState& state, bool material = true, bool geometric = true) const;

  /// Row sums of |K| of a symmetric matrix stored as its upper triangle.
  static Eigen::VectorXd absolute_row_sums(const solve::SparseMatrix& upper) { return pd::absolute_row_sums(upper); }

  // PeridynamicModel
  std::string name() const override { return "lattice"; }
  std::unique_ptr<ModelState> make_state() const override { return std::make_unique<BondState>(); }
  void update(const PointMatrix& u, ModelState& state, bool linearised) const override {
    bond_state(u, static_cast<BondState&>(state), linearised);
  }
  PointMatrix internal_force(const ModelState& state) const override {
    return internal_force(static_cast<const BondState&>(state));
  }
  Real strain_energy(const ModelState& state) const override { return strain_energy(static_cast<const BondState&>(state)); }
  solve::SparseMatrix stiffness(const ModelState& state, bool material, bool geometric) const override {
    return stiffness(static_cast<const BondState&>(state), material, geometric);
  }
  Eigen::VectorXd nodal_dilatation(const ModelState& state) const override {
    return static_cast<const BondState&>(state).dilatation.colwise().sum().transpose();
  }

  const PeridynamicBody& body() const { return body_; }

 private:
  /// Stages 1-2 of bond_state for K dilatation components in use (1: plain LPS, 3: energy, 6: plate).
  template <int K>
  void bond_state_kernel(const PointMatrix& u, BondState& s, bool linearised) const;

  const PeridynamicBody& body_;
  // c of the reverse bond j->i stored at bond i->j, so the pair-force pass reads it in order
  Eigen::VectorXd reverse_modulus_;
  // w of bond i->j and of its reverse j->i, compacted to the K components in use (K x bonds), and Q_i
  // (K x K per node): the per-iteration passes stream K doubles per bond instead of 6
  int components_ = 6;
  Eigen::MatrixXd weight_used_, reverse_weight_used_, coupling_used_;
};

}  // namespace lamina::pd
