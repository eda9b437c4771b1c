#pragma once
// J2 (von Mises) plasticity in plane stress with isotropic (linear or power-law) hardening, hypoelastic in the
// corotational frame of a shell (seed 000 section 2.3; Simo & Hughes, Computational Inelasticity, 3.4).
#include "material/material_registry.hpp"
#include "material/material_spec.hpp"
#include "material/shell_material.hpp"

namespace lamina::material {

/// J2 (von Mises) plasticity in plane stress with isotropic (linear or power-law) hardening, hypoelastic in the
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
  J2PlasticShellMaterial(Real young, Real poisson, Real density, Real yield, Real hardening, Real exponent = 1.0);
  /// From a case's material entry: E, nu, density and the constants `yield`, `hardening`, `hardening_exponent`.
  explicit J2PlasticShellMaterial(const MaterialSpec& spec);
  Real update(Real* sigma, const Real* rate, Real dt) const override;
  int state_size() const override { return 1; }
  Real plastic_strain(const Real* point) const override { return point[kStressComponents]; }
  bool is_plastic() const override { return true; }
  Real stress_limit() const override { return yield_; }
  Real yield_margin(const Real* point) const override;
  Real hardening_share(const Real* point) const override;
  Real young_modulus() const override { return young_; }
  Real poisson_ratio() const override { return poisson_; }
  Real density() const override { return density_; }
  Real yield_stress() const { return yield_; }
  Real hardening() const { return hardening_; }
  Real hardening_exponent() const { return exponent_; }
  /// sigma_y(eps_p) and its slope d sigma_y / d eps_p.
  Real flow_stress(Real eps_p) const;
  Real flow_slope(Real eps_p) const;

 private:
  Real young_, poisson_, density_, yield_, hardening_, exponent_;
};

/// The model's entry in the material registry: its name and constants (yield, hardening, hardening_exponent).
MaterialModelInfo j2_plasticity_model();

}  // namespace lamina::material
