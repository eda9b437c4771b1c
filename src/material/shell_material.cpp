#include "material/shell_material.hpp"

#include "material/j2_plasticity.hpp"

#include <algorithm>
#include <cmath>

namespace lamina::material {

Real ShellMaterial::plate_wave_speed() const {
  const Real nu = poisson_ratio();
  return std::sqrt(young_modulus() / (density() * (1.0 - nu * nu)));
}

Real ShellMaterial::dilatational_wave_speed() const {
  const LinearElastic elastic{young_modulus(), poisson_ratio()};
  const Real bulk = elastic.bulk_modulus();
  const Real shear = elastic.mu();
  return std::sqrt((bulk + 4.0 * shear / 3.0) / density());
}

LinearElasticShellMaterial::LinearElasticShellMaterial(Real young, Real poisson, Real density)
    : young_(young),
      poisson_(poisson),
      density_(density),
      plane_stress_(LinearElastic{young, poisson}.plane_stress_modulus()),
      shear_(LinearElastic{young, poisson}.mu()),
      thickness_ratio_(-poisson / (1.0 - poisson)) {}

NeoHookeanShellMaterial::NeoHookeanShellMaterial(Real young, Real poisson, Real density)
    : young_(young),
      poisson_(poisson),
      density_(density),
      mu_(LinearElastic{young, poisson}.mu()),
      lambda_(LinearElastic{young, poisson}.lambda()) {}

Real NeoHookeanShellMaterial::update(Real* sigma, const Real* rate, Real dt) const {
  Real* state = sigma + kStressComponents;  // H_xx, H_yy, H_xy, ln lambda_3
  state[0] += dt * rate[0];
  state[1] += dt * rate[1];
  state[2] += dt * 0.5 * rate[2];
  // principal logarithmic strains and directions of H (2 x 2 symmetric)
  const Real mean = 0.5 * (state[0] + state[1]), half_diff = 0.5 * (state[0] - state[1]);
  const Real radius = std::hypot(half_diff, state[2]);
  const Real e1 = mean + radius, e2 = mean - radius;
  const Real cos2 = radius > 0.0 ? half_diff / radius : 1.0, sin2 = radius > 0.0 ? state[2] / radius : 0.0;
  // ln lambda_3 from tau_zz = mu (lambda_3^2 - 1) + lambda (e1 + e2 + e3) = 0 (increasing in e3: Newton)
  const Real e3_old = state[3];
  Real e3 = e3_old;
  for (int iteration = 0; iteration < 50; ++iteration) {
    const Real g = mu_ * (std::exp(2.0 * e3) - 1.0) + lambda_ * (e1 + e2 + e3);
    const Real slope = 2.0 * mu_ * std::exp(2.0 * e3) + lambda_;
    const Real step = g / slope;
    e3 -= step;
    if (std::abs(step) < 1e-15) break;
  }
  state[3] = e3;
  const Real log_j = e1 + e2 + e3, j = std::exp(log_j);
  const Real s1 = (mu_ * (std::exp(2.0 * e1) - 1.0) + lambda_ * log_j) / j;
  const Real s2 = (mu_ * (std::exp(2.0 * e2) - 1.0) + lambda_ * log_j) / j;
  const Real s_mean = 0.5 * (s1 + s2), s_half = 0.5 * (s1 - s2);
  sigma[0] = s_mean + s_half * cos2;
  sigma[1] = s_mean - s_half * cos2;
  sigma[2] = s_half * sin2;
  sigma[3] += dt * mu_ * rate[3];
  sigma[4] += dt * mu_ * rate[4];
  return dt > 0.0 ? (e3 - e3_old) / dt : 0.0;
}

std::unique_ptr<ShellMaterial> make_shell_material(const MaterialSpec& spec) {
  const Real density = spec.density.value_or(0.0);
  switch (spec.model) {
    case MaterialModel::neo_hookean: return std::make_unique<NeoHookeanShellMaterial>(spec.E, spec.nu, density);
    case MaterialModel::j2_plasticity: return std::make_unique<J2PlasticShellMaterial>(spec);
    case MaterialModel::linear_elastic: break;
  }
  return std::make_unique<LinearElasticShellMaterial>(spec.E, spec.nu, density);
}

}  // namespace lamina::material
