#pragma once
// Tributary cells of grid particle sets and the strain smoothed over them: the particle quadrature
// of seed 001 eq (4) with dV_I = |Omega_I| and a cell-mean strain operator (exact patch test on any non-tangled grid).
//
// Each grid cell (a, b, c, d) is split at the intersection X of its diagonals into four quarters
// (a, mid ab, X, mid da). The quarters around a particle form its tributary cell Omega_I; they
// tile the body. The strain of particle I is the mean over Omega_I of the gradient of the
// blended MPFEM interpolant phi (particle_elements.hpp), by the divergence theorem
//   B_I = (1 / |Omega_I|) sum_segments integral phi n ds,
// exact because phi is linear along every quarter edge (the two element triangles covering a
// point of a quarter edge are the cell triangles of the two diagonals). phi is continuous, so
// the sum over all cells of |Omega_I| B_I telescopes to the boundary integral of phi n: the
// integration constraint of nodal integration holds and the linear patch test is exact.
// B_I involves particle I, its four neighbours and the four diagonal particles of its cells.
// Also returned: the centroid and second moments of each cell (for the strain-gradient term).
#include <utility>
#include <vector>

#include "mpfem/particle_elements.hpp"

namespace lamina::mpfem {

struct TributaryCells {
  /// Per particle: (particle J, (1/|Omega_I|) integral over Omega_I of grad phi_J).
  std::vector<std::vector<std::pair<Index, Vec2>>> mean_gradient;
  Eigen::VectorXd area;                   // |Omega_I| (per unit thickness)
  Points2 centroid;                       // 2 x N
  std::vector<Eigen::Matrix2d> second_moment;  // integral (x - c)(x - c)^T over Omega_I
};

/// Needs layout.grid; InputError if a grid cell is tangled (its diagonals do not cross inside).
TributaryCells build_tributary_cells(const ParticleLayout& layout);

}  // namespace lamina::mpfem
