#pragma once
// Sparse per-particle gradient lists of the strain smoothing (tributary and Voronoi cells): add a
// contribution to a particle's entry, appending the particle on its first contribution.
#include <utility>
#include <vector>

#include "mpfem/particle_elements.hpp"  // Vec2

namespace lamina::mpfem {

inline void add_gradient(std::vector<std::pair<Index, Vec2>>& list, Index particle, const Vec2& value) {
  for (auto& [p, v] : list)
    if (p == particle) {
      v += value;
      return;
    }
  list.emplace_back(particle, value);
}

}  // namespace lamina::mpfem
