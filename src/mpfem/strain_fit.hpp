#pragma once
// Particle strains recovered from cell-mean strains: at each particle, the value at the particle of
// the least-squares linear fit of the mean strains at the cell centroids of its two-ring of stars.
#include <vector>

#include "mpfem/particle_elements.hpp"

namespace lamina::mpfem {

/// cell_mean: 3 x N mean strains over the cells; centroids: 2 x N cell centroids. The fit at
/// particle I uses I and the nodes of the five-node elements of I and of I's element nodes (the
/// two-ring), so it reproduces any linear strain field exactly. A particle whose two-ring has
/// fewer than three particles, or whose centroids lie on one line, keeps its cell mean.
Eigen::Matrix3Xd fit_particle_strains(const Points2& positions, const Points2& centroids,
                                      const std::vector<ParticleElement>& elements, const Eigen::Matrix3Xd& cell_mean);

}  // namespace lamina::mpfem
