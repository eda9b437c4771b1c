#pragma once
// A boundary condition of the case (PRODUCT.md section 4): fixed components, prescribed displacements
// or velocities on a selection, with a ramp. One type for every method (the reader fills it, the model
// builder resolves its nodes).
#include <array>
#include <optional>

#include "core/ramp.hpp"
#include "geometry/expression.hpp"
#include "model/selection.hpp"

namespace lamina::model {

struct Constraint {
  Selection select;
  std::array<bool, 6> fixed{};                                       // x y z rx ry rz held at zero
  std::array<std::optional<geometry::ScalarField>, 3> displacement;  // prescribed u_i (expressions of x y z)
  std::array<std::optional<geometry::ScalarField>, 3> velocity;      // prescribed v_i (explicit methods)
  Ramp ramp;
  SourceLocation location;  // of the entry

  /// Whether translation a is held: fixed or given a displacement.
  bool constrains(int a) const { return fixed[static_cast<std::size_t>(a)] || displacement[static_cast<std::size_t>(a)].has_value(); }
  /// The translations held, x y z.
  std::array<bool, 3> held() const { return {constrains(0), constrains(1), constrains(2)}; }
  /// The displacement prescribed on translation a: its field, or zero where it is only fixed.
  geometry::ScalarField displacement_of(int a) const {
    const auto& d = displacement[static_cast<std::size_t>(a)];
    return d ? *d : geometry::ScalarField{};
  }
};

}  // namespace lamina::model
