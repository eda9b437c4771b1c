#pragma once
// Options of the moving least squares (MLS) approximation: polynomial basis, weight function,
// support shape and how support sizes are chosen (seed 004, eqs 1-4..1-8; OMLL program names).
#include <string>

#include "core/types.hpp"

namespace lamina::mls {

/// Complete polynomial basis p(x) of u^h = p^T A^-1 B u: linear (m = d + 1) or quadratic (m = (d+1)(d+2)/2).
enum class Basis { linear, quadratic };

/// Weight function w(s), s = distance / support radius in [0, 1] (eqs 1-6, 1-7, 1-8).
enum class Weight { gauss, cubic_spline, quartic_spline };

/// Support of a weight: box = tensor product w(|dx|/Rx) w(|dy|/Ry) w(|dz|/Rz); sphere = w(|x - x_I|/R).
enum class SupportShape { box, sphere };

/// How support sizes are chosen (names of the seed's OMLL program in brackets).
///  kappa        node-centred, R_I,d = kappa * h_I,d (h_I = local nodal spacing)        [default]
///  fixed_radius node-centred, R_d = radius[d] for every node                          [INFLENCEDOMAIN Fix]
///  nearest      node-centred supports sized as in mode kappa; of the nodes whose supports cover x,
///               only the N nearest are neighbours                                      [SELECT]
///  all          node-centred, R_I = scale * (distance from node I to its N-th nearest other node) [ALL]
///  variable     point-centred: neighbours = the N nearest nodes of x, weighted from x with
///               R(x) = scale * (distance from x to its N-th nearest node)              [VARIABLE]
/// (seed 004 section 2.3.1, the OMLL member InflType_.) "Nearest" and the distances of modes all and
/// variable are measured in units of the mean nodal spacing per axis when those spacings differ by more
/// than a factor 1.5 (a plate or shell lattice: the 27 nearest then span three layers as on a cube
/// lattice; on an isotropic cloud plain distances). Sphere supports then become ellipsoids of per-axis
/// radii R_d = R / (spacing units per length)_d. Distances use the first `dimension` coordinates only.
/// In mode variable with scale = 1 the N-th nearest node lies just inside the support (radius times
/// 1 + support_epsilon), so its weight is negligible (about 1e-27 for the quartic spline): choose
/// scale > 1. In modes nearest and variable the neighbour set changes abruptly where the N nearest do,
/// so the shape functions jump there; in mode variable the derivatives are taken with R(x) held fixed
/// (R(x) is only piecewise smooth), see MlsShapeFunctions.
enum class SupportMode { kappa, fixed_radius, nearest, all, variable };

/// Every radius is multiplied by (1 + support_epsilon) so that nodes lying exactly at kappa * h
/// (regular grids) or at the N-th nearest distance are inside the support ("radius s + delta").
inline constexpr Real support_epsilon = 1e-9;

/// Default Gaussian sharpness beta of eq 1-6. The seed gives the formula without a value; 2.5 is our
/// choice: exp(-beta^2) = 1.9e-3, so the truncation shift is small and the bell resembles the splines.
inline constexpr Real default_gauss_beta = 2.5;

/// Default delta_i / h_i of the seed's support radius s_i + delta_i (see MlsOptions::kappa).
inline constexpr Real default_support_delta = 0.1;

struct MlsOptions {
  int dimension = 3;                        // 1, 2 or 3: only the first `dimension` coordinates are used
  Basis basis = Basis::quadratic;
  Weight weight = Weight::quartic_spline;
  Real gauss_beta = default_gauss_beta;     // only for Weight::gauss
  SupportShape shape = SupportShape::box;
  SupportMode mode = SupportMode::kappa;
  /// Mode kappa: the seed's support size kappa_i = s_i / h_i (eq 3-6). Box supports take the radius
  /// s_i + delta_i ("to avoid truncation, the radius is s_i + Delta_i, Delta_i any small quantity", seed 004
  /// section 3.2.2): R_I,d = (kappa + delta) * h_I,d, so a box kappa 2 reaches 3 nodes per direction with
  /// non-zero weight (the seed's non-singularity condition kappa_i >= 2.0). Sphere supports keep
  /// R_I = kappa * max_d h_I,d: the seed's sphere errU of Table 3-2 is reproduced within 0.1 % by it (and
  /// missed by 15 % with + 0.1 h). Builds before 2026-12-02 used kappa * h_I,d for boxes too: an old box
  /// kappa k is the new k - delta.
  Real kappa = 2.0;
  /// delta_i / h_i of the box radius s_i + delta_i. 0.1 reproduces the seed's Table 3-2 box errU to all 7
  /// printed digits (validation/mls_fit_sine); 0 gives the bare radius kappa * h (nodes at exactly kappa h
  /// then get zero weight with the splines, and a box kappa 2 is singular on a face).
  Real delta = default_support_delta;
  /// Mode kappa, box supports: per-axis factors R_I,d = (kappa_axes[d] + delta) * h_I,d instead of kappa (all
  /// zero: unused). For example a shorter reach through a plate's thickness than in its plane.
  Vec3 kappa_axes = Vec3::Zero();
  Vec3 radius = Vec3::Zero();               // mode fixed_radius: [rx, ry, rz] (sphere uses radius[0])
  /// Interface enrichment (Krongauz & Belytschko, CMAME 1998): the basis gets the term |d(y)| with
  /// d(y) = interface_normal . (y - interface_point), at evaluation points whose support holds nodes on
  /// both sides of that plane. The approximation stays continuous and can have a kink across the plane
  /// (a strain jump at a material interface). Elsewhere the polynomial basis is used unchanged.
  bool interface_enrichment = false;
  Vec3 interface_point = Vec3::Zero();
  Vec3 interface_normal = Vec3::UnitZ();     // unit vector
  int nearest = 27;                         // modes nearest / all / variable: N
  Real scale = 1.0;                         // modes all / variable: radius = scale * distance to N-th
  /// SINCHECK remedy. Radius modes (kappa, fixed_radius, all, and nearest where fewer than N supports
  /// cover x): the radii used at this evaluation point are multiplied by 1.25 per step (at most
  /// remedy_max_steps steps); N grows by 1 per step in mode variable and in mode nearest where more than
  /// N supports cover x (at most remedy_max_steps steps or all nodes).
  bool singular_remedy = false;
  int remedy_max_steps = 64;
  /// Largest accepted estimate of the 1-norm condition number of the Jacobi-scaled moment matrix A.
  /// 1e12 keeps about 4 significant digits of the shape functions in the worst case (eps = 2.2e-16);
  /// healthy supports give 1e1..1e5, singular ones 1e16 and more.
  Real max_condition = 1e12;

  /// Throws lamina::InputError (key paths "mls.<field>") if a value is out of range.
  void validate() const;
};

/// Number of basis terms m for the given dimension and basis (2/3, 3/6, 4/10).
int basis_size(int dimension, Basis basis);

std::string to_string(Basis basis);
std::string to_string(Weight weight);
std::string to_string(SupportShape shape);
std::string to_string(SupportMode mode);

}  // namespace lamina::mls
