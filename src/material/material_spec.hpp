#pragma once
// A material entry of the case file: constitutive model and its constants (PRODUCT.md section 3).
#include <optional>
#include <string>

#include "core/types.hpp"
#include "material/linear_elastic.hpp"

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

  /// The elastic constants, whose moduli LinearElastic computes.
  LinearElastic elastic() const { return LinearElastic{E, nu}; }
};

}  // namespace lamina::material
