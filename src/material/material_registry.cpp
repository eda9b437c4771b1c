#include "material/material_registry.hpp"

#include "material/j2_plasticity.hpp"

namespace lamina::material {

const std::vector<MaterialModelInfo>& material_models() {
  static const std::vector<MaterialModelInfo> models{
      {MaterialModel::linear_elastic, "linear_elastic", "linear elasticity (corotational in shells)", {}},
      {MaterialModel::neo_hookean, "neo_hookean", "compressible neo-Hookean hyperelasticity", {}},
      j2_plasticity_model(),
  };
  return models;
}

const MaterialModelInfo* find_material_model(const std::string& name) {
  for (const auto& m : material_models())
    if (m.name == name) return &m;
  return nullptr;
}

}  // namespace lamina::material
