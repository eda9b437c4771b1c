#pragma once
// A load of the case (PRODUCT.md section 4): kind, selection, vector / scalar field and ramp. One type
// for every method: the reader fills it, the model builder resolves its nodes, each family applies it.
#include <array>

#include "core/ramp.hpp"
#include "geometry/expression.hpp"
#include "model/selection.hpp"

namespace lamina::model {

struct Load {
  /// force (total, shared), traction (per area), pressure (per area, positive pushes inwards), body_force
  /// (per volume; mpm: per mass), moment / edge_moment (shell rotations: total / per unit edge length),
  /// mass (added point mass), initial_velocity. Each family states which kinds it applies.
  enum class Kind { force, traction, pressure, body_force, moment, edge_moment, mass, initial_velocity };
  Kind kind = Kind::force;
  Selection select;
  std::array<geometry::ScalarField, 3> vector;  // force, traction, body_force, moment, initial_velocity
  geometry::ScalarField scalar;                 // pressure, mass
  Ramp ramp;                                    // over the load factor (static) or t / end_time (dynamic)
  SourceLocation location;                      // of the entry
};

}  // namespace lamina::model
