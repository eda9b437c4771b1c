#pragma once
// KirchhoffPlate: the plate model of a one-layer plate lattice (docs/pd.md, "One node layer"):
// a rotation-free Kirchhoff-Love plate over the in-plane family of each node, with the membrane strain
// and the curvature read by the family's polynomial fit (plate_fit.hpp) at the node itself.
//
// Node i (mid-surface point m_i), family: nodes j within the horizon, reference bond xi_b, v_b = omega V_j.
//   F = sum_b v_b (m_j - m_i) B_b^T,  H_ab = sum_b v_b (m_j - m_i) C_b,ab      (3 x 2; three 3-vectors)
//   n = F_1 x F_2 / |F_1 x F_2|,  E = (F^T F - A0) / 2,  kappa_ab = -(n . H_ab) - kappa0_ab
//   z_b = P (m_j - m_i - F xi_b) - z0_b   (P = I - n n^T: in-plane part the fit leaves)
//   r_b = n . (m_j - m_i - F xi_b - H(xi_b, xi_b) / 2) / |xi_b| - r0_b   (transverse part the fit leaves)
//   W_i = 1/2 E:C:E + t^2/24 kappa:C:kappa + 1/2 sum_b [k_b |z_b|^2 + g_b v_b r_b^2],   Pi = sum_i V_i W_i
// C: plane stress; B_b, C_b: first and second derivative weights of the fit (degree 2 or 3; a family too
// small for a quadratic fit is refused); k_b, g_b: the stabilisation moduli of the director model
// (peridynamic_plate.hpp) on the non-polynomial remainder only, so a field the fit reproduces has exactly
// the classical energy. Every measure is invariant under rigid rotation. No transverse shear (Kirchhoff).
// Held rotations (`fix: [rx, ry]`, a clamp): a penalty on the change of the fitted tangents at the node,
// 1/2 k_h V_i sum q^2 with q = e_z . dF_2 (rx), e_z . dF_1 (ry), k_h = 1e3 E t^2 / (12 (1 - nu^2) s^2) (s the
// in-plane spacing: 1e3 x the node's bending stiffness); only the slopes the supports of the neighbours do
// not already fix (hold_rotations). rz has no effect: there is no drilling rotation (the in-plane rotation
// follows x and y; holding it would also hold the in-plane shear at a clamped edge).
// Behzadinasab, Alaydin, Trask, Bazilevs (2022), a rotation-free Kirchhoff-Love shell for peridynamics;
// Silling (2017) for the bond-level stabilisation.
#include <cstdint>
#include <memory>
#include <vector>

#include "pd/peridynamic_body.hpp"
#include "pd/peridynamic_model.hpp"
#include "pd/peridynamic_problem.hpp"
#include "pd/plate_columns.hpp"

namespace lamina::pd {

struct KirchhoffPlateState : ModelState {
  PointMatrix m;                    // per node: current position
  Eigen::VectorXd energy;           // per node: V_i W_i
  Eigen::Matrix3Xd membrane_stress; // per node: S11, S22, S12
  Eigen::Matrix3Xd membrane_strain, curvature;  // per node: E11, E22, 2 E12 and kappa11, kappa22, 2 kappa12
  PointMatrix bond_gradient;        // per bond b of node i: d(V_i W_i) / d(m_j - m_i)
};

class KirchhoffPlate : public PeridynamicModel {
 public:
  /// columns: a one-layer plate lattice (find_plate_columns); reference: the stress-free node positions
  /// (with any imperfection); lattice: the same nodes without it (families are built on it).
  /// Throws InputError if a family is too small or too one-sided for the quadratic fit.
  KirchhoffPlate(PlateColumns columns, const PointMatrix& reference, const PointMatrix& lattice,
                 const Eigen::VectorXd& volumes, const Eigen::VectorXd& young, const Eigen::VectorXd& poisson,
                 const BodyOptions& options);

  std::string name() const override { return "kirchhoff_plate"; }
  std::unique_ptr<ModelState> make_state() const override { return std::make_unique<KirchhoffPlateState>(); }
  void update(const PointMatrix& u, ModelState& state, bool linearised) const override;
  PointMatrix internal_force(const ModelState& state) const override;
  Real strain_energy(const ModelState& state) const override;
  /// Material part: the Hessian of each node's V_i W_i by central differences of its exact gradient
  /// (relative error about 1e-9); geometric part: the membrane stress on the in-plane fit.
  solve::SparseMatrix stiffness(const ModelState& state, bool material, bool geometric) const override;
  Eigen::VectorXd nodal_dilatation(const ModelState& state) const override;
  bool node_strain(const ModelState& state, Index node, Mat3& strain) const override;

  /// Holds the rotations of `held` at its nodes (those of this plate; a node of no column is ignored).
  /// prescribed (3 per node, x y z): the translations the case prescribes. A slope that the prescribed w
  /// of the node's lattice neighbours along it already fixes (the slope along a supported edge, both
  /// slopes at a corner) is not penalised: in the discrete fit that would constrain the non-polynomial
  /// part of w as well (over-constraint, stiff at coarse lattices). rz is ignored (see the header).
  void hold_rotations(const HeldRotations& held, const std::vector<char>& prescribed);
  /// The held-rotation penalty relative to the node's bending stiffness (see the header).
  static constexpr Real kRotationPenalty = 1e3;

  /// Transverse wavenumber k of a field (3 x nodes; its z components w): k^2 = sum V |grad grad w|^2 /
  /// sum V |grad w|^2 with the fit's derivatives (a^2 + b^2 for w = sin(a x) sin(b y)). The curvature is a
  /// second derivative of a cubic fit, so k * horizon above about 0.9 means the model is soft for the field.
  Real transverse_wavenumber(const PointMatrix& field) const;

  const PlateColumns& columns() const { return columns_; }
  Real thickness() const { return thickness_; }
  /// Lowest polynomial degree of the fits (2 or 3).
  int fit_degree_min() const { return fit_degree_min_; }

 private:
  struct Measures {
    Vec3 stress, strain, curvature;
  };
  /// V_i W_i of node i with its family at the positions slot[0] (node i), slot[1 + t] (bond t), and
  /// its gradient with respect to the bond vectors m_j - m_i (bond_gradient, nf entries).
  Real node_energy(Index i, const Vec3* slot, Vec3* bond_gradient, Measures* measures) const;

  PlateColumns columns_;
  std::unique_ptr<PeridynamicBody> family_;  // 2D families over the nodes (bond volumes, reverse bonds)
  PointMatrix reference_;
  Index nodes_ = 0;
  Real thickness_ = 0, bending_factor_ = 0;
  int fit_degree_min_ = 3;
  // per node
  Eigen::VectorXd volume_, young_, poisson_;
  std::vector<Mat3> plane_stress_;
  Eigen::Matrix3Xd metric0_, curvature0_;
  // per bond
  Eigen::Matrix2Xd xi_, first_;   // reference bond; v_b B_b
  Eigen::Matrix3Xd second_;       // v_b C_b (xx, yy, xy)
  std::vector<std::uint8_t> held_axes_;  // per column: bit a = rotation about axis a held (x, y)
  std::vector<Eigen::Matrix<Real, 3, 2>> held_tangents0_;  // per column with held axes: reference F_1, F_2
  Eigen::VectorXd membrane_stabilizer_, transverse_stabilizer_, inverse_length_, r0_;
  PointMatrix z0_;
};

}  // namespace lamina::pd
