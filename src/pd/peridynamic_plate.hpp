#pragma once
// PeridynamicPlate: the director plate model of a 2-4 layer plate lattice (docs/pd.md, "The plate
// model"): non-ordinary state-based (correspondence) membrane and bending over an in-plane family of
// node columns, bond-based transverse shear, a plane-stress thickness stretch, and bond-level
// stabilisation of the non-affine in-plane and director deformation (Silling 2017).
//
// Column c: mid-surface m_c and director a_c (plate_columns.hpp), d = a / |a|. Family of column i:
// columns j within the horizon (in-plane, reference X), v_b = omega beta V_j, K_i = sum v xi xi^T,
// B_b = K_i^-1 xi_b (xi: 2D reference bond).
//   F_i = sum_b v_b (m_j - m_i) B_b^T,  D_i = sum_b v_b (d_j - d_i) B_b^T          (3 x 2 each)
//   E = 1/2 (F^T F - A0),  kappa = sym(F^T D) - kappa0,  s = |a| - |a0|,  q = s + nu/(1-nu) tr E
//   gamma_b = (m_j - m_i) . (d_i + d_j) / (2 L0_b) - gamma0_b          (transverse shear of bond b)
//   z_b = P_i (m_j - m_i - F xi_b) - z0_b,  P_i = I - d_i d_i^T;   y_b = d_j - d_i - D xi_b - y0_b
//   gamma_i = F^T d - gamma0   (transverse shear of the column, 2-vector)
//   W_i = 1/2 E:C:E + 1/2 E q^2 + t^2/24 kappa:C:kappa + 5/12 mu |gamma_i|^2
//         + 1/2 sum_b [k_b (|z_b|^2 + t^2/12 |y_b|^2) + g_b v_b gamma_b^2],   Pi = sum_i V_i W_i (+ layer residual)
// C: plane stress; k_b = s mu v_b / (|xi_b|^2 sum v) (4 k_b for z_b); g_b = s (5/6) mu (t / |xi_b|)^2 / (1/2 sum v),
// s = plate_stabilization (default 0.25). The bond terms vanish for affine fields (gamma_b: for
// quadratic w with linear d) and give the hourglass modes (zig-zag w, d) their stiffness.
// Every measure is invariant under rigid rotation (geometrically exact kinematics); a homogeneous
// membrane strain, curvature or transverse shear gives the classical plate energy at every column
// (the non-affine parts vanish; shear exact for mirror-symmetric families).
// Supported edges (clamps, simple supports, symmetry planes): the families reach into mirror columns
// that move with real ones, and a column on a mirror line weighs half (plate_edge_mirror.hpp).
#include <memory>
#include <vector>

#include "pd/plate_edge_mirror.hpp"
#include "pd/peridynamic_body.hpp"
#include "pd/peridynamic_model.hpp"
#include "pd/plate_columns.hpp"

namespace lamina::pd {

struct PlateState : ModelState {
  PointMatrix m, a, d;              // per column (current)
  Eigen::VectorXd a_norm;
  PointMatrix residual;             // per node (3-4 layers)
  Eigen::VectorXd energy;           // per column: V_i W_i
  Eigen::Matrix3Xd membrane_stress; // per column: S11, S22, S12 (second Piola-Kirchhoff, thickness-coupled)
  Eigen::VectorXd membrane_trace;   // per column: tr E
  Eigen::Matrix3Xd membrane_strain, curvature;  // per column: E11, E22, 2 E12 and kappa11, kappa22, 2 kappa12
  Eigen::Matrix2Xd shear;           // per column: gamma
  PointMatrix bond_m, bond_d, bond_dj;  // per bond: d Pi / d(m_j - m_i), d Pi / d(d_j - d_i), d Pi / d d_j direct
  PointMatrix self_d, self_a;           // per column: direct d Pi / d d_i and d Pi / d a_i
};

struct PlateStatistics {
  Real mean_family = 0, min_family = 0;
  int fit_degree_min = 3;   // lowest polynomial degree of the column gradient fits (3: cubic everywhere)
  Real thickness = 0;
  int layers = 0;
};

class PeridynamicPlate : public PeridynamicModel {
 public:
  /// reference: the stress-free node positions (with any imperfection); lattice: the same nodes without
  /// it (columns and families are built on it); per-node volume, E and nu; held: per node dof, whether
  /// it is fixed or prescribed (the families reach across clamped edges into mirror columns,
  /// plate_edge_mirror.hpp; empty: no mirrors).
  PeridynamicPlate(PlateColumns columns, const PointMatrix& reference, const PointMatrix& lattice,
                   const Eigen::VectorXd& volumes, const Eigen::VectorXd& young, const Eigen::VectorXd& poisson,
                   const BodyOptions& options, const std::vector<char>& held = {});

  std::string name() const override { return "plate"; }
  std::unique_ptr<ModelState> make_state() const override { return std::make_unique<PlateState>(); }
  void update(const PointMatrix& u, ModelState& state, bool linearised) const override;
  PointMatrix internal_force(const ModelState& state) const override;
  Real strain_energy(const ModelState& state) const override;
  solve::SparseMatrix stiffness(const ModelState& state, bool material, bool geometric) const override;
  Eigen::VectorXd nodal_dilatation(const ModelState& state) const override;
  bool node_strain(const ModelState& state, Index node, Mat3& strain) const override;

  /// Force decomposition over ranks (replicated data, split work): from now on update() and
  /// internal_force() compute only what the forces of the marked nodes need - their columns, those
  /// columns' families (the bond terms) and theirs (m, d); the rest of the state and force is left
  /// unspecified. Empty: every column (the state is whole again).
  void restrict_to_nodes(const std::vector<char>& nodes);

  const PlateColumns& columns() const { return columns_; }
  const PeridynamicBody& family() const { return *family_; }
  const PlateStatistics& statistics() const { return statistics_; }
  const PlateEdgeMirror& mirror() const { return mirror_; }

 private:
  /// Per real column i: the real columns its energy depends on - i, its family, and the columns that
  /// move its family's mirror columns - sorted.
  std::vector<std::vector<Index>> expanded_families() const;
  /// Calls f(term) for each term of column c's motion (a real column: itself, factors 1).
  template <class F>
  void for_each_term(Index c, const F& f) const {
    const Index real = columns_.columns();
    if (c < real) f(MirrorTerm{c, Vec3::Ones(), Vec3::Ones()});
    else
      for (const MirrorTerm& t : mirror_.motion[static_cast<std::size_t>(c - real)]) f(t);
  }
  /// B_b of the bonds [b0, b1) of one column; returns the polynomial degree used.
  int gradient_weights(Index b0, Index b1, Real horizon);

  PlateColumns columns_;
  // mirror columns across supported edges: family members nc .. nc + G - 1, moving with real columns
  PlateEdgeMirror mirror_;
  // restrict_to_nodes: the columns whose force, bond terms and kinematics are computed (empty: all)
  std::vector<char> force_column_, bond_column_, kinematic_column_;
  static bool marked(const std::vector<char>& set, Index c) { return set.empty() || set[static_cast<std::size_t>(c)]; }
  std::unique_ptr<PeridynamicBody> family_;  // 2D families over the column centres (bond volumes, reverse bonds)
  PointMatrix reference_;                    // node positions of the stress-free configuration
  Index nodes_ = 0;
  Real thickness_ = 0, bending_factor_ = 0;  // t, t^2 / 12
  Real residual_modulus_ = 0;
  // in-plane stabilisation / director stabilisation: the in-plane one at the shear modulus (damps
  // the boundary-layer ringing of a loaded edge; no effect on bending), the director one at s mu
  Real membrane_factor_ = 4;                // layer residual stiffness per volume (3-4 layers)
  // per column
  // per column (volume_, young_, poisson_, a0_norm_, m0_, d0_: mirror columns too); weight_: the
  // energy weight V_i x the mirror's energy factor
  Eigen::VectorXd volume_, weight_, shear_modulus_, young_, poisson_, a0_norm_;
  std::vector<Mat3> plane_stress_;           // C (Voigt, engineering shear)
  Eigen::Matrix3Xd metric0_, curvature0_;    // A0 (11, 22, 12), kappa0 (11, 22, 2 x 12)
  // per bond
  Eigen::Matrix2Xd xi_, shape_b_;            // reference in-plane bond, B_b = K^-1 xi
  Eigen::VectorXd v_, length0_, stabilizer_, bond_shear_, gamma0_;
  Eigen::Matrix2Xd shear0_;                  // per column: F0^T d0
  PointMatrix z0_, y0_;
  // reference configuration: column mid-surface, director, F0 and D0 (3 x 2, column-major), layer residual
  PointMatrix m0_, d0_, reference_residual_;
  Eigen::Matrix<Real, 6, Eigen::Dynamic> f0_, dd0_;
  Eigen::VectorXd layer_volume_;             // per node
  // the per-bond constants of update(), packed bond by bond (one cache stream in the hot loop)
  struct BondConstants {
    Eigen::Vector2d weighted_shape;  // v_b B_b
    Eigen::Vector2d xi;              // reference in-plane bond
    Real inverse_length = 0;         // 1 / |xi_b|
    Real membrane = 0, director = 0; // 4 k_b and t^2/12 k_b (stabilisation)
    Real shear = 0;                  // g_b v_b (bond-shear stabilisation)
    Index neighbour = 0;
  };
  std::vector<BondConstants> bond_constants_;
  PlateStatistics statistics_;
};

}  // namespace lamina::pd
