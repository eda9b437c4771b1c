#include "shell/shell_material.hpp"

#include <cmath>

namespace lamina::shell {

Real ShellMaterial::plate_wave_speed() const {
  const Real nu = poisson_ratio();
  return std::sqrt(young_modulus() / (density() * (1.0 - nu * nu)));
}

Real ShellMaterial::dilatational_wave_speed() const {
  const Real E = young_modulus(), nu = poisson_ratio();
  const Real bulk = E / (3.0 * (1.0 - 2.0 * nu));
  const Real shear = E / (2.0 * (1.0 + nu));
  return std::sqrt((bulk + 4.0 * shear / 3.0) / density());
}

LinearElasticShellMaterial::LinearElasticShellMaterial(Real young, Real poisson, Real density)
    : young_(young), poisson_(poisson), density_(density) {}

Real LinearElasticShellMaterial::update(Real* sigma, const Real* rate, Real dt) const {
  const Real c = young_ / (1.0 - poisson_ * poisson_);
  const Real g = young_ / (2.0 * (1.0 + poisson_));
  sigma[0] += dt * c * (rate[0] + poisson_ * rate[1]);
  sigma[1] += dt * c * (rate[1] + poisson_ * rate[0]);
  sigma[2] += dt * g * rate[2];
  sigma[3] += dt * g * rate[3];
  sigma[4] += dt * g * rate[4];
  return -poisson_ / (1.0 - poisson_) * (rate[0] + rate[1]);
}

}  // namespace lamina::shell
