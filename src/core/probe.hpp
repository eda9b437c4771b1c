#pragma once
// A probe as the solvers see it: a named scalar to evaluate at every output point
// (value at a point, sum over a resolved node selection, or a global energy).
#include <optional>
#include <string>

#include "core/types.hpp"

namespace lamina {

struct Probe {
  std::string name;
  std::string field;        // displacement, velocity, stress, strain, reaction_force, energy, eigenvalue, ...
  std::string component;    // x y z xx yy zz xy yz zx magnitude von_mises internal kinetic ... or an index
  std::optional<Vec3> at;   // evaluation point (field value probes)
  IndexList nodes;          // resolved selection (reaction_force sums) or the node set for `set:` probes
  bool nearest_in_set = false;  // `at` + `set`: take the nearest node of `nodes`
};

/// Index of a vector component name: x 0, y 1, z 2; -1 for any other name.
inline int vector_component(const std::string& c) {
  return c == "x" ? 0 : c == "y" ? 1 : c == "z" ? 2 : -1;
}

/// Index of a tensor component name in Voigt order (material::Voigt): xx yy zz xy yz zx -> 0..5; -1 otherwise.
inline int tensor_component(const std::string& c) {
  static const char* const names[] = {"xx", "yy", "zz", "xy", "yz", "zx"};
  for (int k = 0; k < 6; ++k)
    if (c == names[k]) return k;
  return -1;
}

}  // namespace lamina
