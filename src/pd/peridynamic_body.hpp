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
#include <cstdint>
#include <vector>

#include "core/types.hpp"

namespace lamina::pd {

enum class Influence { one, inverse_distance };            // omega = 1 | delta / x
enum class Kinematics { three_dimensional, plane_stress, plane_strain };
enum class SurfaceCorrection { none, energy };

struct BodyOptions {
  Real horizon = 1.0;
  Influence influence = Influence::one;
  Kinematics kinematics = Kinematics::three_dimensional;
  SurfaceCorrection surface_correction = SurfaceCorrection::energy;
  bool partial_volume = false;  // linear ramp of the neighbour volume over delta +- h/2
  Real cell_size = 0.0;         // h of the partial-volume ramp (default: cube root of the node volume)
};

struct BodyStatistics {
  Real mean_family = 0, min_family = 0, max_family = 0;
  Real min_bond_modulus_ratio = 0;  // min c_ij / mean c_ij (negative: the correction had to soften some bonds)
  Real family_kinds = 0;            // distinct families calibrated (energy correction)
  Real max_dilatation_error = 0;    // over the nodes: |theta - tr eps| for the unit normal strains
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
  const Eigen::VectorXd& bond_length() const { return length_; }
  const Eigen::VectorXd& bond_volume() const { return bond_volume_; }  // beta_ij V_j
  /// w^a_ij: column b holds the weights of the generalized dilatations theta_a (a < dimension; zero padded to 3).
  const Eigen::Matrix3Xd& dilatation_weight() const { return weight_; }
  /// Q_i (3 x 3, zero padded) coupling the dilatations of node i: 1/2 theta^T Q theta.
  const Mat3& dilatation_coupling(Index i) const { return coupling_[static_cast<std::size_t>(i)]; }
  const Eigen::VectorXd& bond_modulus() const { return modulus_; }      // c_ij
  const Eigen::VectorXd& dilatation_modulus() const { return kappa_; }  // kappa_i
  const BodyStatistics& statistics() const { return statistics_; }

  /// Per-node classical stiffness used for the calibration (Voigt 6x6 in 3D; 2D: the 3x3 in-plane part).
  Eigen::MatrixXd classical_stiffness(Index i) const;

 private:
  void build_families();
  void calibrate(const Eigen::VectorXd& young, const Eigen::VectorXd& poisson);

  PointMatrix positions_;
  Eigen::VectorXd volumes_;
  BodyOptions options_;
  std::vector<Index> family_start_;
  std::vector<std::int32_t> neighbour_, reverse_;
  Eigen::VectorXd length_, bond_volume_, modulus_, kappa_;
  Eigen::Matrix3Xd weight_;
  std::vector<Mat3> coupling_;
  Eigen::VectorXd young_, poisson_;
  BodyStatistics statistics_;
};

}  // namespace lamina::pd
