#pragma once
// PeridynamicBody: the reference configuration of an ordinary state-based peridynamic body -
// families (bond lists), partial volumes, influence function and the calibrated constants of the
// linear peridynamic solid (Silling et al. 2007 eqs (91)-(94); seed 002 section 2.1).
//
// Energy of node i (per unit volume), geometrically exact extension e_ij = |Y_ij| - |xi_ij|:
//   W_i = 1/2 theta_i^T Q_i theta_i + 1/2 sum_j c_ij e_ij^2 beta_ij V_j,
//   theta_i,a = sum_j w^a_ij e_ij beta_ij V_j                    (generalized dilatations, a < D)
// (standard LPS: one dilatation, Q = kappa = C12 - mu).
// Standard LPS (surface_correction: none) is w_ij = D omega x / m_i, c_ij = (15 or 8) mu omega / m_i,
// kappa_i = C12 - mu (= K - 5 mu / 3 in 3D, K2 - 2 mu in 2D; Le, Silling & Bobaru 2014), m_i the
// numerical weighted volume sum omega x^2 beta V.
// surface_correction: energy ("position-aware" energy matching per direction, an equivalent of the
// Madenci-Oterkus per-direction energy factors): per node, w^a_ij = omega x (d^a_i . n^2) so that
// theta_a = eps_aa for every homogeneous strain; c_ij = omega (g_i . phi(n)) >= 0 with phi the quartic
// monomials of the bond direction n, g_i >= 0 fitted (non-negative least squares) to the shear
// moduli; Q_i = C_normal - B_normal(g_i) makes the normal block exact. Result: W_i equals the classical
// energy density for every homogeneous strain at each node with a mirror-symmetric family, except
// shear moduli the family cannot carry with positive bonds (reported: transverse shear of a
// two-layer plate lattice is too soft). Energy is positive (c >= 0, Q projected to PSD).
// surface_correction: plate (3D plate lattices, z = thickness): six generalized dilatations, the
// strain tensor estimate theta = (xx, yy, zz, yz, xz, xy) (tensor components) with weights exact for
// every homogeneous strain and, as far as the family allows (least squares in the null space of the
// exactness conditions), blind to first and second strain gradients - so a node sees the strain at its
// own height in bending (no spurious theta_zz) and curvature gradients do not read as transverse shear;
// Q_i = C_plate - B(c) with C_plate the plane-stress law (in-plane block E/(1-nu^2), sigma_zz = E
// eps_zz uncoupled, shear moduli mu); bond moduli: same-layer bonds isotropic (half the in-plane
// shear), vertical bonds half of E_zz, all cross-layer bonds 10 % of the in-plane modulus (against the
// zig-zag w hourglass). Exact homogeneous energy of the plate law at every node; bending energy = sum
// over the layers of V_k 1/2 eps(z_k) C eps(z_k) less the cross-layer share (exact lumping when the
// layers sit at the Gauss points of the thickness, see geometry/cell_lattice.hpp).
#include <algorithm>
#include <cstdint>
#include <functional>
#include <vector>

#include "core/types.hpp"

namespace lamina::pd {

enum class Influence { one, inverse_distance };            // omega = 1 | delta / x
enum class Kinematics { three_dimensional, plane_stress, plane_strain };
enum class SurfaceCorrection { none, energy, plate };
/// automatic: a 2-4 layer plate lattice (plate_columns.hpp) gets the director plate model
/// (peridynamic_plate.hpp), a one-layer plate lattice the Kirchhoff plate model (kirchhoff_plate.hpp), any
/// other body the lattice model; lattice: always the lattice model.
enum class PlateModel { automatic, lattice };
/// A node's part on one rank of a distributed run (pd/rank_nodes.hpp): its own, a halo node whose
/// dilatation this rank computes (within one reach of an owned node), or a halo node that only
/// completes those families.
enum class NodeRole : std::int8_t { outer_halo = 0, inner_halo = 1, owned = 2 };

using Vec6 = Eigen::Matrix<Real, 6, 1>;
using Mat6 = Eigen::Matrix<Real, 6, 6>;
using Matrix6X = Eigen::Matrix<Real, 6, Eigen::Dynamic>;

struct BodyOptions {
  Real horizon = 1.0;
  Influence influence = Influence::one;
  Kinematics kinematics = Kinematics::three_dimensional;
  SurfaceCorrection surface_correction = SurfaceCorrection::energy;
  bool partial_volume = false;  // linear ramp of the neighbour volume over delta +- h/2
  Real cell_size = 0.0;         // h of the partial-volume ramp (default: cube root of the node volume)
  PlateModel plate_model = PlateModel::automatic;
  Real plate_stabilization = 0.25;  // plate model: non-affine stabilisation modulus / shear modulus
  bool plate_edge_mirror = true;    // plate model: families reach across supported edges (plate_edge_mirror.hpp)
  /// pd.bond_storage: full (every bond's length, volume, weights, modulus and reverse index), lean (the
  /// neighbour index only, 4 bytes; LeanPeridynamicSolid recomputes the rest from the positions and
  /// per-node constants: explicit dynamics with a given time step, surface_correction none or energy),
  /// automatic (lean exactly then). lean_bonds is the resolved choice (PeridynamicAnalysis::build_body).
  enum class BondStorage { automatic, full, lean };
  BondStorage bond_storage = BondStorage::automatic;
  bool lean_bonds = false;
};

struct BodyStatistics {
  Real mean_family = 0, min_family = 0, max_family = 0;
  Real min_bond_modulus_ratio = 0;  // min c_ij / mean c_ij (negative: the correction had to soften some bonds)
  Real family_kinds = 0;            // distinct families calibrated (energy correction)
  Real max_dilatation_error = 0;    // over the nodes: |theta - tr eps| for the unit normal strains
  Real max_gradient_residual = 0;   // plate: largest response of theta to a unit first or second strain gradient (x horizon, horizon^2)
};

class PeridynamicBody {
 public:
  /// positions 3 x N (z ignored for plane kinematics), node volumes, per-node E and nu.
  PeridynamicBody(PointMatrix positions, Eigen::VectorXd volumes, const Eigen::VectorXd& young,
                  const Eigen::VectorXd& poisson, const BodyOptions& options);

  Index nodes() const { return positions_.cols(); }
  Index bonds() const { return static_cast<Index>(neighbour_.size()); }
  int dimension() const { return options_.kinematics == Kinematics::three_dimensional ? 3 : 2; }
  const BodyOptions& options() const { return options_; }
  const PointMatrix& positions() const { return positions_; }
  const Eigen::VectorXd& volumes() const { return volumes_; }

  // Bond b of node i: b in [first_bond(i), first_bond(i + 1)).
  Index first_bond(Index i) const { return family_start_[static_cast<std::size_t>(i)]; }
  Index end_bond(Index i) const { return family_start_[static_cast<std::size_t>(i) + 1]; }
  Index neighbour(Index b) const { return neighbour_[static_cast<std::size_t>(b)]; }
  Index reverse(Index b) const { return reverse_[static_cast<std::size_t>(b)]; }  // bond j -> i of bond i -> j
  bool lean() const { return options_.lean_bonds; }
  /// Distributed runs: the role of each node on this rank. The models then compute dilatations for the
  /// owned and inner-halo nodes only, and forces and energies for the owned ones. None set: all owned.
  void set_node_roles(std::vector<NodeRole> roles) { roles_ = std::move(roles); }
  /// Distributed runs: a refresh of the halo's columns of a rows x nodes array from their owners. Once set,
  /// the models compute dilatations on the owned nodes only and take the halo's dilatation forces from it
  /// (without it: computed here for the inner halo, as the stiffness needs its bond directions).
  void set_halo_exchange(std::function<void(Real*, int)> exchange) { halo_exchange_ = std::move(exchange); }
  void exchange_halo(Real* data, int rows) const {
    if (halo_exchange_) halo_exchange_(data, rows);
  }
  bool computes_state(Index i) const {
    if (roles_.empty()) return true;
    const NodeRole r = roles_[static_cast<std::size_t>(i)];
    return r == NodeRole::owned || (r == NodeRole::inner_halo && !halo_exchange_);
  }
  bool owns(Index i) const { return roles_.empty() || roles_[static_cast<std::size_t>(i)] == NodeRole::owned; }
  bool has_halo() const { return !roles_.empty(); }

  /// Reference geometry of bond i -> j (z dropped for plane kinematics), computed (both storage modes).
  struct BondGeometry {
    Vec3 xi;          // x_j - x_i
    Real length;      // |xi|
    Real influence;   // omega(|xi|)
    Real volume;      // beta(|xi|) V_j (partial volume ramp)
  };
  BondGeometry bond_geometry(Index i, Index j) const {
    BondGeometry g;
    g.xi = positions_.col(j) - positions_.col(i);
    if (options_.kinematics != Kinematics::three_dimensional) g.xi.z() = 0;
    g.length = g.xi.norm();
    g.influence = options_.influence == Influence::one ? 1.0 : options_.horizon / g.length;
    Real beta = 1.0;
    if (options_.partial_volume)
      beta = std::clamp((options_.horizon + 0.5 * options_.cell_size - g.length) / options_.cell_size, 0.0, 1.0);
    g.volume = beta * volumes_[j];
    return g;
  }
  /// beta V_j of bond b of node i (stored, or computed with lean storage).
  Real bond_volume_of(Index i, Index b) const {
    return lean() ? bond_geometry(i, neighbour(b)).volume : bond_volume_[b];
  }
  /// Lean storage: the dilatation weights w^a_ij (a < 3) and the bond modulus c_ij of node i for a bond
  /// of direction n, length x and influence omega (the calibrated per-node constants, see the header).
  Vec3 lean_weight(Index i, const Vec3& n, Real x, Real omega) const {
    const Vec3 n2 = n.cwiseProduct(n);
    return omega * x * (node_weight_[static_cast<std::size_t>(i)].transpose() * n2);
  }
  /// w^0_ij alone (plain LPS uses one dilatation).
  Real lean_weight_first(Index i, const Vec3& n, Real x, Real omega) const {
    return omega * x * node_weight_[static_cast<std::size_t>(i)].col(0).dot(n.cwiseProduct(n));
  }
  Real lean_modulus(Index i, const Vec3& n, Real omega) const;
  const Eigen::VectorXd& bond_length() const { return length_; }
  const Eigen::VectorXd& bond_volume() const { return bond_volume_; }  // beta_ij V_j
  /// w^a_ij: column b holds the weights of the generalized dilatations theta_a: rows 0-2 the normal
  /// ones (a < dimension), rows 3-5 (yz, xz, xy) used by surface_correction: plate only; zero padded.
  const Matrix6X& dilatation_weight() const { return weight_; }
  /// Q_i (6 x 6, zero padded) coupling the dilatations of node i: 1/2 theta^T Q theta.
  const Mat6& dilatation_coupling(Index i) const { return coupling_[static_cast<std::size_t>(i)]; }
  const Eigen::VectorXd& bond_modulus() const { return modulus_; }      // c_ij
  const Eigen::VectorXd& dilatation_modulus() const { return kappa_; }  // kappa_i
  const BodyStatistics& statistics() const { return statistics_; }

  /// Per-node classical stiffness used for the calibration (Voigt 6x6 in 3D; 2D: the 3x3 in-plane part).
  Eigen::MatrixXd classical_stiffness(Index i) const;

 private:
  void build_families();
  void calibrate(const Eigen::VectorXd& young, const Eigen::VectorXd& poisson);
  void calibrate_plate();

  PointMatrix positions_;
  Eigen::VectorXd volumes_;
  BodyOptions options_;
  std::vector<Index> family_start_;
  std::vector<std::int32_t> neighbour_, reverse_;
  Eigen::VectorXd length_, bond_volume_, modulus_, kappa_;
  Matrix6X weight_;
  std::vector<Mat6> coupling_;
  // lean storage: column a of node_weight_ is d^a_i; node_modulus_ the quartic-monomial coefficients g_i
  // (energy) or, in entry 0, the plain LPS modulus (15 or 8) mu / m_i (surface_correction none)
  std::vector<Mat3> node_weight_;
  std::vector<Vec6> node_modulus_;
  Eigen::VectorXd young_, poisson_;
  BodyStatistics statistics_;
  std::vector<NodeRole> roles_;
  std::function<void(Real*, int)> halo_exchange_;
};

}  // namespace lamina::pd
