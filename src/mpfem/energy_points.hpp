#pragma once
// The MPFEM particle quadrature written as a weighted sum of stored energies at "energy points",
// each with a displacement-gradient operator linear in the particle displacements: the form the
// large-deformation analysis needs (docs/mpfem.md section 9). With W quadratic it reproduces the
// linear particle stiffness of mpfem_analysis.hpp exactly:
//   cell / voronoi:  t [ Omega W(F_c)  +  1/2 sum_ab M_ab G_a:A:G_b  +  beta deviation ]
//     -> the first two: 4 points c +- sqrt(2) l_i (M / Omega = L L^T), weight Omega / 4 each,
//        F = I + sum_J u_J (b_cJ + sum_a d_a g_aJ)^T (exact for the second moments);
//     -> beta deviation sum_T (A_T/A)(B_T - B_c)^T C (B_T - B_c) = sum_T (A_T/A) B_T C B_T + B^ C B^
//        + 2 B_c C B_c - 4 B_m C B_m (B^ the star mean, B_m = (B^ + B_c)/2): points with weights
//        beta Omega A_T/A, beta Omega, 2 beta Omega, -4 beta Omega. Each is W of a deformation
//        gradient, so the whole energy is objective (frame-invariant) at any rotation.
//   star: dV [(1 - beta) W(F^) + beta sum_T (A_T/A) W(F_T)].
#include <array>
#include <utility>
#include <vector>

#include "mpfem/particle_elements.hpp"

namespace lamina::mpfem {

using GradientList = std::vector<std::pair<Index, Vec2>>;

struct EnergyPoint {
  Real weight = 0;        // reference volume (per unit thickness); may be negative (stabilisation)
  GradientList gradient;  // F = I + sum_J u_J gradient_J^T
};

/// cell_mean: b_cJ; strain_gradient: g_aJ (the gradient of the cell-mean gradient, axis a);
/// omega, moment: |Omega_I| and its second moments about the centroid.
std::vector<EnergyPoint> cell_energy_points(const ParticleElement& e, const GradientList& cell_mean,
                                            const std::array<GradientList, 2>& strain_gradient, Real omega,
                                            const Eigen::Matrix2d& moment, Real beta);

/// particle_strain: star; dv = A_I / covering.
std::vector<EnergyPoint> star_energy_points(const ParticleElement& e, Real dv, Real beta);

}  // namespace lamina::mpfem
