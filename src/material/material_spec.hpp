#pragma once
// A material entry of the case file: constitutive model and its constants (PRODUCT.md section 3).
#include <optional>
#include <string>

#include "core/types.hpp"

namespace lamina::material {

enum class MaterialModel { linear_elastic, neo_hookean, j2_plasticity };

struct MaterialSpec {
  std::string name;
  MaterialModel model = MaterialModel::linear_elastic;
  Real E = 0.0;
  Real nu = 0.0;
  std::optional<Real> density;
  Real yield_stress = 0.0;   // j2_plasticity
  Real hardening = 0.0;      // j2_plasticity: linear isotropic hardening modulus

  Real shear_modulus() const { return E / (2.0 * (1.0 + nu)); }
  Real lame_lambda() const { return E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)); }
  Real bulk_modulus() const { return E / (3.0 * (1.0 - 2.0 * nu)); }
};

}  // namespace lamina::material
