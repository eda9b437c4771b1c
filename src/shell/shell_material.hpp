#pragma once
// Plane-stress constitutive update at one through-thickness point of a shell, in the element's
// corotational frame (seed 000 eqs (27)-(29): stresses updated by plain increments of the local rates).
#include <cmath>
#include <memory>

#include "core/types.hpp"
#include "material/linear_elastic.hpp"

namespace lamina::shell {

/// Local stress components at one through-thickness point: xx, yy, xy, yz, zx.
constexpr int kStressComponents = 5;

/// A plane-stress (sigma_zz = 0) material in the corotational frame. The update is called once per
/// element, through-thickness point and step; implementations keep any history they need in the
/// stress array (and later in extra per-point state), so plasticity fits the same interface.
class ShellMaterial {
 public:
  virtual ~ShellMaterial() = default;
  /// sigma (5 components, followed by state_size() history values) is advanced by the rates over dt.
  /// rate = (d_xx, d_yy, 2 d_xy, 2 d_yz, 2 d_zx). Returns the thickness strain rate d_zz that keeps sigma_zz = 0.
  virtual Real update(Real* sigma, const Real* rate, Real dt) const = 0;
  /// History values stored after the 5 stresses at each through-thickness point (all zero initially).
  virtual int state_size() const { return 0; }
  /// Equivalent plastic strain stored in one point's values (sigma + history); 0 for elastic models.
  virtual Real plastic_strain(const Real* /*point*/) const { return 0.0; }
  virtual bool is_plastic() const { return false; }
  /// Largest stress the material carries (initial yield for J2; infinity for elastic models): bounds
  /// the physical hourglass stresses of BelytschkoTsayShell so that they yield with the material.
  virtual Real stress_limit() const { return INFINITY; }
  virtual Real young_modulus() const = 0;
  virtual Real poisson_ratio() const = 0;
  virtual Real density() const = 0;
  Real shear_modulus() const { return material::LinearElastic{young_modulus(), poisson_ratio()}.mu(); }
  /// Plane-stress dilatational wave speed sqrt(E / (rho (1 - nu^2))) (shell stable step).
  Real plate_wave_speed() const;
  /// 3D dilatational wave speed sqrt((K + 4G/3) / rho) of seed 000 eq (40).
  Real dilatational_wave_speed() const;
};

/// Linear elastic (hypoelastic) plane stress in the corotational frame.
class LinearElasticShellMaterial final : public ShellMaterial {
 public:
  LinearElasticShellMaterial(Real young, Real poisson, Real density);
  Real update(Real* sigma, const Real* rate, Real dt) const override;
  Real young_modulus() const override { return young_; }
  Real poisson_ratio() const override { return poisson_; }
  Real density() const override { return density_; }

 private:
  Real young_, poisson_, density_;
};

/// Compressible neo-Hookean plane stress in the corotational frame (PRODUCT.md / notes: hyperelastic
/// option using the deformation accumulated in the local frame). The logarithmic strain H = int D dt of
/// the in-plane rates is accumulated in the frame (history: H_xx, H_yy, H_xy, ln lambda_3); the left
/// stretch is V = exp(H), b = V^2, and the Kirchhoff stress tau = mu (b - I) + lambda ln J I with
/// lambda_3 from tau_zz = 0 (Newton), sigma = tau / J. Exact for stretching along axes fixed in the
/// frame; transverse shear stays linear (G). Reduces to LinearElasticShellMaterial at small strain.
class NeoHookeanShellMaterial final : public ShellMaterial {
 public:
  NeoHookeanShellMaterial(Real young, Real poisson, Real density);
  Real update(Real* sigma, const Real* rate, Real dt) const override;
  int state_size() const override { return 4; }
  Real young_modulus() const override { return young_; }
  Real poisson_ratio() const override { return poisson_; }
  Real density() const override { return density_; }

 private:
  Real young_, poisson_, density_, mu_, lambda_;
};

/// J2 (von Mises) plasticity in plane stress with linear isotropic hardening, hypoelastic in the
/// corotational frame: sigma_y = yield + hardening * eps_p (eps_p the equivalent plastic strain, the one
/// history value). Elastic trial C : d dt, then the closest-point return of Simo & Hughes (Computational
/// Inelasticity, section 3.4, plane stress): with the trial stress in the common eigenbasis of C and P,
/// xi_1 = (s_xx + s_yy)/sqrt2, xi_2 = (s_yy - s_xx)/sqrt2, xi_3 = s_xy, the returned stress is
/// xi_1 / (1 + E dg / (3 (1 - nu))), xi_2,3 / (1 + 2 G dg), and dg solves sigma_vm(dg) = sigma_y(eps_p
/// + 2/3 dg sigma_vm(dg)) (safeguarded Newton). Transverse shear stays elastic (G). The thickness rate
/// is the elastic -nu/E (sigma_xx + sigma_yy)' plus the plastic -dg (sigma_xx + sigma_yy) / 3 (plastic
/// incompressibility).
class J2PlasticShellMaterial final : public ShellMaterial {
 public:
  J2PlasticShellMaterial(Real young, Real poisson, Real density, Real yield, Real hardening);
  Real update(Real* sigma, const Real* rate, Real dt) const override;
  int state_size() const override { return 1; }
  Real plastic_strain(const Real* point) const override { return point[kStressComponents]; }
  bool is_plastic() const override { return true; }
  Real stress_limit() const override { return yield_; }
  Real young_modulus() const override { return young_; }
  Real poisson_ratio() const override { return poisson_; }
  Real density() const override { return density_; }
  Real yield_stress() const { return yield_; }
  Real hardening() const { return hardening_; }

 private:
  Real young_, poisson_, density_, yield_, hardening_;
};

}  // namespace lamina::shell
