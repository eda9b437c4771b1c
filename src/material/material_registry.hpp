#pragma once
// The material models a case can name (PRODUCT.md section 3, `materials[].model`), each with the
// constants it reads besides E, nu and density: the one list the case reader checks entries against.
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "material/material_spec.hpp"

namespace lamina::material {

/// A constant of a material model: its key in the case, default (none = required) and admissible range.
struct MaterialConstant {
  std::string key;
  std::optional<Real> fallback;     // none: the key is required
  Real lower = -INFINITY, upper = INFINITY;
  bool lower_open = false, upper_open = false;
  std::string meaning;
};

struct MaterialModelInfo {
  MaterialModel model = MaterialModel::linear_elastic;
  std::string name;
  std::string description;
  std::vector<MaterialConstant> constants;  // beyond E, nu, density
};

/// Every registered model, in the order the case file's `model` key lists them (linear_elastic first:
/// the default).
const std::vector<MaterialModelInfo>& material_models();

/// The model of that name, or nullptr.
const MaterialModelInfo* find_material_model(const std::string& name);

}  // namespace lamina::material
