#pragma once
// The Belytschko-Tsay (Belytschko-Lin-Tsay) 4-node shell element: corotational frame, one-point
// in-plane quadrature, Lobatto points through the thickness, hourglass resistance; seed 000 eqs (17)-(37).
//
// Kinematics (Mindlin, local frame, seed eqs (17)-(20)): v_x = v_x^m + z theta_y, v_y = v_y^m - z theta_x.
// Velocity strains (eqs (21)-(24)) at fibre height z:
//   d_x = B1.vx + z B1.ty,  d_y = B2.vy - z B2.tx,  2d_xy = B2.vx + B1.vy + z (B2.ty - B1.tx),
//   2d_xz = B1.vz + N.ty,   2d_yz = B2.vz - N.tx      (N_I = 1/4, B = dN/dx at the centre; the physical
//   model takes the transverse shear from MITC4's edge shears instead, exact for Kirchhoff fields on any quad)
// Resultants (eq (28)) over the Lobatto points (eq (29)); nodal forces and moments (eqs (25)-(26)) are
// the power conjugates of the rates; hourglass resistance (eqs (30)-(36), Belytschko-Tsay 1983 with the
// Flanagan-Belytschko gamma vectors) in the coefficient model, or the physical stabilisation of
// ShellSection (the default); global forces f = Q^T f_hat (eq (37)).
// Warping correction: a Belytschko-Wong-Chiang-type rigid-body projection (the in-plane velocities
// of warped nodes lose the part produced by the element's rigid rotation about its in-plane axes,
// and the transposed projection is applied to the forces), so a warped element under rigid rotation
// gives zero strain rates and no hourglass forces, and its forces are in moment equilibrium.
#include <array>
#include <vector>

#include "core/types.hpp"
#include "material/shell_material.hpp"

namespace lamina::shell {

using NodeMatrix = Eigen::Matrix<Real, 3, 4>;  // one column per element node (counter-clockwise)

/// Lobatto (Gauss-Lobatto) points and weights on [-1, 1] through the thickness (seed eq (29)).
struct ThroughThicknessRule {
  std::vector<Real> points, weights;
  /// n = 2 ... 7 points (n = 1: the mid-surface point with weight 2, membrane only).
  static ThroughThicknessRule lobatto(int n);
};

/// How the element resists its hourglass modes.
///  - physical (default): stiffnesses from the material and the element's geometry, no coefficient:
///    membrane and bending modes take the bending-exact (ASQBI-type, Belytschko-Bindeman 1993;
///    Belytschko-Leviathan 1994) stiffness E t A |b_i|^2 / 12 and E t^3 A |b_i|^2 / 144 (the membrane modes
///    along the natural directions xi, eta, |b_i| -> 1 / (2 |g_i|): exact in-plane bending of parallelograms),
///    the centre transverse shear is MITC4's assumed covariant shear at the centre, the transverse
///    shear takes the hourglass part of the MITC4 edge-tied shears (two modes, k G t A / 3 each: the
///    element is then MITC4's transverse shear exactly on parallelograms), and a Hughes-Brezzi drilling
///    penalty ties the nodal drilling rotation to the in-plane rotation. Right on curved (faceted) shells.
///  - coefficients: the Belytschko-Tsay 1983 springs r k_mode (seed eqs (30)-(36)) with the
///    coefficients below (the seed's form; too flexible on curved shells, see docs/mpm.md).
enum class HourglassModel { physical, coefficients };

struct ShellSection {
  /// Lobatto points through the thickness (1..7); 0 = the default for the material: 3 for elastic models
  /// (seed eq (29)), 7 for plastic ones (3 Lobatto points carry at most the first-yield moment, 7 carry
  /// 0.96 of the fully plastic one: docs/mpm.md, validation/mpm_plastic_bending)
  int thickness_points = 0;
  /// The count an element of this section uses with `material`.
  static int default_thickness_points(bool plastic) { return plastic ? 7 : 3; }
  Real shear_factor = 5.0 / 6.0;     // transverse shear correction k
  HourglassModel hourglass_model = HourglassModel::physical;
  /// Drilling penalty (physical model): energy 1/2 drilling G t A (theta_z - omega_z)^2 at the centre,
  /// omega_z = (dv/dx - du/dy) / 2 (Hughes-Brezzi 1989); 0 = free drilling rotations.
  Real drilling = 0.05;
  Real hourglass = 0.1;              // coefficient model: hourglass coefficient r (membrane, bending, transverse)
  /// Coefficient of the two rotational (bending) hourglass modes; negative = use `hourglass`.
  /// About 1 is the physical value: on a square element the mode theta_y = c h_I (h = [1,-1,1,-1])
  /// stores r (1 - nu^2) D c^2 with the stiffness r E h^3 A Bsq / 192, and the exactly integrated
  /// bending energy of the same bilinear rotation field is (2/3)(1 + (1 - nu)/2) D c^2
  /// (equal at r = 0.99 for nu = 0.3), as in Belytschko-Leviathan's physical stabilization.
  Real hourglass_bending = -1.0;
  /// Coefficient of the two in-plane (membrane) hourglass modes; negative = use `hourglass`.
  Real hourglass_membrane = -1.0;
  /// Coefficient of the transverse (w) hourglass mode; negative = use `hourglass`.
  Real hourglass_transverse = -1.0;
  bool warping_correction = true;    // BWC-type rigid-body projection for warped elements
  /// Transverse (w) hourglass strain: false = gamma . v_z (Belytschko-Tsay 1983); true = the hourglass
  /// part of the edge-tied transverse shears (MITC4-like: sum_e s_e [w_J - w_I + edge . (theta_y, -theta_x)_avg]),
  /// which is zero for rigid motions, constant curvature of parallelograms and the Kirchhoff twist
  /// w = c x y, so the spring resists only the spurious w mode, not twisting of the shell.
  bool kirchhoff_transverse_hourglass = false;
};

/// What one element evaluation returns (global frame).
struct ShellElementResult {
  // (not zero-initialised: update() assigns both, zero for an invalid element; two 96-byte fills per
  // element cost about 2 % of an explicit step)
  NodeMatrix force;   // internal nodal forces (resisting)
  NodeMatrix moment;  // internal nodal moments
  Real internal_power = 0.0;               // sigma : d over the element (mid-step stress)
  Real hourglass_power = 0.0;              // Q . q_dot (mid-step hourglass resultants)
  Real area = 0.0;
  Real characteristic_length = 0.0;       // area / longest diagonal (stable step length)
  bool valid = true;                       // false: degenerate or inverted element
};

/// Local stress resultants per unit width (for output): membrane N, moments M, shear Q.
struct ShellResultants {
  Real nxx = 0, nyy = 0, nxy = 0, mxx = 0, myy = 0, mxy = 0, qxz = 0, qyz = 0;
};

/// The element kernel. Stateless apart from the section and material: the per-element state
/// (stresses at the through-thickness points, hourglass resultants, thickness) is passed in.
class BelytschkoTsayShell {
 public:
  BelytschkoTsayShell(const ShellSection& section, const material::ShellMaterial& material);

  int thickness_points() const { return static_cast<int>(rule_.points.size()); }
  const material::ShellMaterial& material() const { return material_; }
  /// Doubles per through-thickness point: 5 stresses and the material's history values.
  int point_stride() const { return material::kStressComponents + material_.state_size(); }
  /// Doubles of stress state per element (point_stride() per through-thickness point).
  int stress_size() const { return point_stride() * thickness_points(); }
  /// Hourglass (stabilisation) modes: bending x, bending y, transverse w (coefficient model) or transverse
  /// xi (physical), membrane x, membrane y, transverse eta, drilling (physical).
  static constexpr int kHourglassModes = 7;
  /// Hourglass state per element: the kHourglassModes resultants Q_i, then (plastic materials, physical
  /// stabilisation) the held (hardening) parts H_0, H_1 of the two bending modes (update()).
  static constexpr int kHourglassSize = kHourglassModes + 2;

  /// Advance the element by one step: rates from the node velocities v and angular velocities
  /// omega at the configuration x (global frame), stress update over dt, internal forces.
  /// stress (stress_size()), hourglass (5) and thickness are updated in place.
  ShellElementResult update(const NodeMatrix& x, const NodeMatrix& v, const NodeMatrix& omega, Real dt, Real* stress,
                            Real* hourglass, Real& thickness) const;

  /// Stress resultants of the current state (local frame).
  ShellResultants resultants(const Real* stress, Real thickness) const;

  /// Corotational frame: rows e1, e2, e3 (seed eq (17)). Returns false for a degenerate element.
  static bool corotational_frame(const NodeMatrix& x, Mat3& rotation);
  /// Element stable time step L_s / c with L_s = area / longest diagonal (LS-DYNA's conservative
  /// choice; area / longest edge is unconservative for skewed quads), c = plate wave speed
  /// stiffened by the hourglass coefficient; no safety factor.
  Real stable_time_step(const NodeMatrix& x) const;
  /// The same from a characteristic length (area / longest diagonal).
  Real stable_time_step(Real characteristic_length) const;

 private:
  using Row4 = Eigen::Matrix<Real, 1, 4>;
  /// The local nodal velocities (rows 0-2) over the angular velocities (rows 3-5), one column per node; also
  /// the local nodal forces over the moments.
  using NodeMotion = Eigen::Matrix<Real, 6, 4>;
  /// A strain rate as rows on the local nodal velocities and angular velocities: rate = vx . v_x + ... + tz . theta_z,
  /// held as one 6 x 4 block laid out as NodeMotion (so rate and force are one vectorised product each).
  struct RateRows {
    NodeMotion m;  // (not initialised: zero() or a full assignment; small zero fills cost a string store each)
    static RateRows zero() {
      RateRows r;
      r.m.setZero();
      return r;
    }
    auto vx() { return m.row(0); }
    auto vy() { return m.row(1); }
    auto vz() { return m.row(2); }
    auto tx() { return m.row(3); }
    auto ty() { return m.row(4); }
    auto tz() { return m.row(5); }
    auto vx() const { return m.row(0); }
    auto vy() const { return m.row(1); }
    /// The rate of the local motion vw (velocities over angular velocities).
    Real rate(const NodeMotion& vw) const { return m.cwiseProduct(vw).sum(); }
    /// Its conjugate resultant q into the local nodal forces over moments fm (fm += q rows).
    void add_force(Real q, NodeMotion& fm) const { fm += q * m; }
  };
  /// Hourglass generalised strain rates q_i = rows[i].rate(v, w) (local frame) and the stiffness of each
  /// (Q_i += dt stiffness_i q_i; the forces are the conjugates Q_i * the rows).
  struct HourglassRates {
    std::array<RateRows, kHourglassModes> rows;
    std::array<Real, kHourglassModes> stiffness{};
    std::array<Real, kHourglassModes> limit;   // |Q_i| bound (the mode's peak stress at the yield stress)
    /// |Q_i - H_i| bound of the two bending modes of a plastic material: the section's own margin to yield
    /// (infinity otherwise; see update())
    std::array<Real, kHourglassModes> margin;
    /// >= 0: mode i reads (and its force acts on) only this row of the local motion, the rest of its
    /// rows being left unset; -1: all six rows
    std::array<int, kHourglassModes> only_row;
    HourglassRates() {
      limit.fill(INFINITY);
      margin.fill(INFINITY);
      only_row.fill(-1);
    }
  };
  /// Unit normals of the element's bilinear surface x(xi, eta) at its corners (local frame, columns);
  /// all e3 on a flat element.
  using CornerNormals = Eigen::Matrix<Real, 3, 4>;
  static CornerNormals corner_normals(const Row4& xh, const Row4& yh, const Row4& zh);
  /// Covariant transverse shears at the edge midpoints (MITC4, Bathe-Dvorkin 1985), with the bilinear surface's
  /// normal n_K at each corner as the director: g = [(v_J - v_I) . d + E . (theta_I x n_I + theta_J x n_J) / 2] / 2,
  /// d = (n_I + n_J) / 2, E = x_J - x_I; for an edge along xi, g = g_xi . gamma at its midpoint. Every node lies
  /// on one edge along xi (0-1 or 3-2) and one along eta (0-3 or 1-2), so the rows of the two xi edges fill one
  /// NodeMotion block (column K: node K's part of its edge's rate) and those of the two eta edges another.
  struct EdgeShears {
    RateRows xi, eta;
  };
  static EdgeShears edge_shears(const Row4& xh, const Row4& yh, const Row4& zh, const CornerNormals& n);
  /// The Cartesian transverse shear rates (2 d_xz, 2 d_yz) at the centre from the MITC4 assumed covariant
  /// shears (the mean of the two edges along xi and of the two along eta), so that a Kirchhoff field
  /// (quadratic w, linear rotations) gives no shear on any quadrilateral, trapezoids included.
  /// jinv: the inverse of centre_jacobian.
  static std::array<RateRows, 2> centre_shear(const EdgeShears& edges, const Eigen::Matrix<Real, 2, 2>& jinv);
  /// The bilinear map's natural basis at the centre as the rows of J: g_xi = sum xi_I x_I / 4, g_eta.
  static Eigen::Matrix<Real, 2, 2> centre_jacobian(const Row4& xh, const Row4& yh);
  HourglassRates coefficient_hourglass(const Row4& xh, const Row4& yh, const Row4& b1, const Row4& b2, Real h,
                                       Real area) const;
  /// tangent_membrane / tangent_bending: the material's current stiffness ratio (1 = elastic);
  /// corrected: the in-plane velocities the rows act on carry the warping correction.
  HourglassRates physical_hourglass(const Row4& xh, const Row4& yh, const Row4& zh, const EdgeShears& edges,
                                    const Eigen::Matrix<Real, 2, 2>& jacobian, const Eigen::Matrix<Real, 2, 2>& jinv,
                                    bool corrected, const Row4& b1, const Row4& b2, Real h, Real area,
                                    Real tangent_membrane, Real tangent_bending, Real margin_bending) const;

  ShellSection section_;
  const material::ShellMaterial& material_;
  // the material's constants, read once: E, nu, G, E / (1 - nu^2), the yield stress (infinite if elastic)
  Real young_, poisson_, shear_, plane_stress_, stress_limit_;
  bool plastic_;
  ThroughThicknessRule rule_;
};

}  // namespace lamina::shell
