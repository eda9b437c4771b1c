#pragma once
// A material entry of the case file: constitutive model and its constants (PRODUCT.md section 3).
// The models and the constants each reads are listed in material_registry.hpp.
#include <map>
#include <optional>
#include <stdexcept>
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
  /// The model's further constants by key (e.g. j2_plasticity: yield, hardening), read and range-checked
  /// against its MaterialModelInfo.
  std::map<std::string, Real> constants;

  /// The elastic constants, whose moduli LinearElastic computes.
  LinearElastic elastic() const { return LinearElastic{E, nu}; }
  /// A constant of the model (std::out_of_range if the entry has none of that key).
  Real constant(const std::string& key) const { return constants.at(key); }
};

}  // namespace lamina::material
