#include "material/j2_plasticity.hpp"

#include <algorithm>
#include <cmath>

namespace lamina::material {

namespace {
/// sigma_vm of an in-plane stress state (xx, yy, xy), the J2 yield function's measure in plane stress.
Real plane_stress_von_mises(Real a, Real b, Real s) { return std::sqrt(std::max(0.0, a * a - a * b + b * b + 3.0 * s * s)); }
}  // namespace

MaterialModelInfo j2_plasticity_model() {
  MaterialModelInfo info;
  info.model = MaterialModel::j2_plasticity;
  info.name = "j2_plasticity";
  info.description = "J2 plasticity, isotropic hardening: sigma_y = yield + hardening * eps_p^n (mpm shells)";
  info.constants = {
      {"yield", std::nullopt, 0.0, INFINITY, true, false, "initial yield stress"},
      {"hardening", 0.0, 0.0, INFINITY, false, false, "isotropic hardening modulus"},
      {"hardening_exponent", 1.0, 0.0, 1.0, true, false, "n of sigma_y = yield + hardening eps_p^n (1: linear)"},
  };
  return info;
}

J2PlasticShellMaterial::J2PlasticShellMaterial(const MaterialSpec& spec)
    : J2PlasticShellMaterial(spec.E, spec.nu, spec.density.value_or(0.0), spec.constant("yield"), spec.constant("hardening"),
                             spec.constant("hardening_exponent")) {}

J2PlasticShellMaterial::J2PlasticShellMaterial(Real young, Real poisson, Real density, Real yield, Real hardening, Real exponent)
    : young_(young), poisson_(poisson), density_(density), yield_(yield), hardening_(hardening), exponent_(exponent) {}

Real J2PlasticShellMaterial::flow_stress(Real eps_p) const {
  return yield_ + hardening_ * (exponent_ == 1.0 ? eps_p : std::pow(std::max(eps_p, 0.0), exponent_));
}

Real J2PlasticShellMaterial::flow_slope(Real eps_p) const {
  if (exponent_ == 1.0) return hardening_;
  // infinite at eps_p = 0 for n < 1: the return's Newton then falls back to bisection inside its bracket
  return eps_p > 0.0 ? hardening_ * exponent_ * std::pow(eps_p, exponent_ - 1.0) : INFINITY;
}

Real J2PlasticShellMaterial::yield_margin(const Real* point) const {
  return flow_stress(point[kStressComponents]) - plane_stress_von_mises(point[0], point[1], point[2]);
}

Real J2PlasticShellMaterial::hardening_share(const Real* point) const {
  const Real slope = flow_slope(point[kStressComponents]);
  if (!std::isfinite(slope)) return 1.0;
  const Real h = std::max(slope, 0.0);
  return h / (young_ + h);
}

Real J2PlasticShellMaterial::update(Real* sigma, const Real* rate, Real dt) const {
  const LinearElastic elastic{young_, poisson_};
  const Real E = young_, nu = poisson_, c = elastic.plane_stress_modulus(), g = elastic.mu();
  Real& eps_p = sigma[kStressComponents];
  const Real old_sum = sigma[0] + sigma[1];
  // elastic trial
  Real sxx = sigma[0] + dt * c * (rate[0] + nu * rate[1]);
  Real syy = sigma[1] + dt * c * (rate[1] + nu * rate[0]);
  Real sxy = sigma[2] + dt * g * rate[2];
  sigma[3] += dt * g * rate[3];
  sigma[4] += dt * g * rate[4];
  Real plastic_zz = 0.0;
  const Real trial_von_mises = plane_stress_von_mises(sxx, syy, sxy);
  // (a non-finite trial is left as it is: the analysis stops on the non-finite energy it causes)
  if (std::isfinite(trial_von_mises) && trial_von_mises > flow_stress(eps_p)) {
    // return in the eigenbasis of C and P (seed-independent; Simo & Hughes 3.4)
    const Real xi1 = (sxx + syy) / std::sqrt(2.0), xi2 = (syy - sxx) / std::sqrt(2.0), xi3 = sxy;
    const Real k1 = E / (3.0 * (1.0 - nu)), k2 = 2.0 * g;
    const Real a = xi1 * xi1 / 6.0, b = 0.5 * xi2 * xi2 + xi3 * xi3;  // (1/3) sigma_vm^2 = a / d1^2 + b / d2^2
    const auto residual = [&](Real dg, Real& slope) {
      const Real d1 = 1.0 + k1 * dg, d2 = 1.0 + k2 * dg;
      const Real f2 = a / (d1 * d1) + b / (d2 * d2);
      const Real vm = std::sqrt(3.0 * f2);
      const Real df2 = -2.0 * a * k1 / (d1 * d1 * d1) - 2.0 * b * k2 / (d2 * d2 * d2);
      const Real dvm = vm > 0.0 ? 1.5 * df2 / vm : 0.0;
      const Real eps_new = eps_p + 2.0 / 3.0 * dg * vm;
      slope = dvm - flow_slope(eps_new) * (2.0 / 3.0) * (vm + dg * dvm);
      return vm - flow_stress(eps_new);
    };
    // bracket: residual(0) > 0 and residual decreases; grow hi until the sign changes
    Real lo = 0.0, hi = 1.0 / k2, slope = 0.0;
    for (int doubling = 0; doubling < 200 && residual(hi, slope) > 0.0; ++doubling) hi *= 2.0;
    Real dg = 0.0;
    for (int iteration = 0; iteration < 100; ++iteration) {
      const Real r = residual(dg, slope);
      if (std::abs(r) <= 1e-13 * yield_) break;
      if (r > 0.0) lo = dg;
      else hi = dg;
      Real next = slope < 0.0 ? dg - r / slope : 0.5 * (lo + hi);
      if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);  // keep Newton inside the bracket
      dg = next;
    }
    const Real d1 = 1.0 + k1 * dg, d2 = 1.0 + k2 * dg;
    const Real r1 = xi1 / d1, r2 = xi2 / d2;
    sxx = (r1 - r2) / std::sqrt(2.0);
    syy = (r1 + r2) / std::sqrt(2.0);
    sxy = xi3 / d2;
    const Real vm = plane_stress_von_mises(sxx, syy, sxy);
    eps_p += 2.0 / 3.0 * dg * vm;
    plastic_zz = -dg * (sxx + syy) / 3.0;
  }
  sigma[0] = sxx;
  sigma[1] = syy;
  sigma[2] = sxy;
  if (!(dt > 0.0)) return 0.0;
  return (-nu / E * (sxx + syy - old_sum) + plastic_zz) / dt;
}

}  // namespace lamina::material
