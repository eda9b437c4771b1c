#pragma once
// Plane-stress constitutive update at one through-thickness point of a shell, in the element's
// corotational frame (seed 000 eqs (27)-(29): stresses updated by plain increments of the local rates).
#include <cmath>
#include <memory>

#include "core/types.hpp"
#include "material/linear_elastic.hpp"
#include "material/material_spec.hpp"

namespace lamina::material {

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
  /// The whole section at once: `count` through-thickness points, point q's values (5 stresses, then the
  /// history) at sigma + q * stride and its rates at rates + 5 q; its d_zz into dzz[q]. The element calls
  /// this once per update (one virtual call, not one per point); the default calls update() per point.
  virtual void update_section(Real* sigma, int stride, const Real* rates, int count, Real dt, Real* dzz) const {
    for (int q = 0; q < count; ++q) dzz[q] = update(sigma + stride * q, rates + kStressComponents * q, dt);
  }
  /// History values stored after the 5 stresses at each through-thickness point (all zero initially).
  virtual int state_size() const { return 0; }
  /// Equivalent plastic strain stored in one point's values (sigma + history); 0 for elastic models.
  virtual Real plastic_strain(const Real* /*point*/) const { return 0.0; }
  virtual bool is_plastic() const { return false; }
  /// Largest stress the material carries (initial yield for J2; infinity for elastic models): bounds
  /// the physical hourglass stresses of BelytschkoTsayShell so that they yield with the material.
  virtual Real stress_limit() const { return INFINITY; }
  /// How much more stress the point (its 5 stresses and history) takes before it yields: the current flow
  /// stress less the in-plane von Mises stress (infinity for elastic models).
  virtual Real yield_margin(const Real* /*point*/) const { return INFINITY; }
  /// How much of an elastic stress increment a flowing point keeps under further uniaxial straining: the
  /// tangent over Young's modulus, H / (E + H) with H the hardening slope at the point (0 perfectly plastic,
  /// 1 for elastic models).
  virtual Real hardening_share(const Real* /*point*/) const { return 1.0; }
  virtual Real young_modulus() const = 0;
  virtual Real poisson_ratio() const = 0;
  virtual Real density() const = 0;
  Real shear_modulus() const { return LinearElastic{young_modulus(), poisson_ratio()}.mu(); }
  /// Plane-stress dilatational wave speed sqrt(E / (rho (1 - nu^2))) (shell stable step).
  Real plate_wave_speed() const;
  /// 3D dilatational wave speed sqrt((K + 4G/3) / rho) of seed 000 eq (40).
  Real dilatational_wave_speed() const;
};

/// Linear elastic (hypoelastic) plane stress in the corotational frame.
class LinearElasticShellMaterial final : public ShellMaterial {
 public:
  LinearElasticShellMaterial(Real young, Real poisson, Real density);
  Real update(Real* sigma, const Real* rate, Real dt) const override { return advance(sigma, rate, dt); }
  void update_section(Real* sigma, int stride, const Real* rates, int count, Real dt, Real* dzz) const override {
    for (int q = 0; q < count; ++q) dzz[q] = advance(sigma + stride * q, rates + kStressComponents * q, dt);
  }
  Real young_modulus() const override { return young_; }
  Real poisson_ratio() const override { return poisson_; }
  Real density() const override { return density_; }

 private:
  /// One point's update, inline in both entry points.
  Real advance(Real* sigma, const Real* rate, Real dt) const {
    sigma[0] += dt * plane_stress_ * (rate[0] + poisson_ * rate[1]);
    sigma[1] += dt * plane_stress_ * (rate[1] + poisson_ * rate[0]);
    sigma[2] += dt * shear_ * rate[2];
    sigma[3] += dt * shear_ * rate[3];
    sigma[4] += dt * shear_ * rate[4];
    return thickness_ratio_ * (rate[0] + rate[1]);
  }

  Real young_, poisson_, density_;
  Real plane_stress_, shear_, thickness_ratio_;  // E / (1 - nu^2), mu, -nu / (1 - nu): from LinearElastic, once
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

/// The plane-stress shell material of a case's material entry, by its model name (linear_elastic,
/// neo_hookean, j2_plasticity; material_registry.hpp lists them with their constants).
std::unique_ptr<ShellMaterial> make_shell_material(const MaterialSpec& spec);

}  // namespace lamina::material
