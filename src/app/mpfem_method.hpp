#pragma once
// Registration of `method: mpfem` (2D moving particle finite element method, seed 001 eqs 1-6):
// reading the `mpfem:` section and translating io::Case + Model into an mpfem::MpfemProblem.
//
// The `mpfem:` section (every key optional; defaults shown; docs/mpfem.md)
//   plane: stress                      # stress | strain
//   element: five_node                 # five_node (MPFEM) | t3 (reference linear triangles on the same grid particles)
//   stabilization: 0.1                 # beta in (0, 1]: weight of the element-deviation term of the stiffness
//   particle_strain: auto              # auto (cell on grid particle sets, voronoi on other sets of convex bodies,
//                                      #   else star) | cell | voronoi | star (docs/mpfem.md section 4)
//   neighbours: auto                   # auto (grid for generated particles, else sectors) | grid | sectors
//   max_neighbour_distance: 3.0        # sectors: neighbours within this x the median nearest-particle distance
//   traction_quadrature: gauss         # gauss (2 points per boundary segment) | particle (seed eq 6: t(x_I) dS_I)
//   refine: 1                          # divide the particle spacing by this integer: n -> refine (n - 1) + 1 per direction
//   hole: {radius: 1.0, grading: 1.0}  # box geometry only: quarter plate with a hole of this radius centred at
//                                      #   the box's (min x, min y) corner; particles: [n_radial, n_angular]
//                                      #   (mpfem/plate_with_hole.hpp); sets hole, outer, xmin, ymin, xmax, ymax
//   exact_displacement: [ux, uy]       # expressions of x y: builtin probes err_displacement, err_stress,
//                                      #   err_l2, err_energy, err_energy_particles
//
// Geometry: box (z extent = thickness), plate (thickness), curved_beam (z range), annulus
// (thickness; periodic without slit). Particles: discretization.particles: [n0, n1] over the
// generator's first two directions (optional jitter), or {file: particles.csv} / a mesh's nodes
// (neighbours: sectors).
// Boundary: fix / symmetry / displacement in x and y (z and rotations are ignored: 2D). Loads:
// force (total, shared equally), traction / pressure (per area, on the boundary segments between
// selected particles, times the thickness), body_force (per volume, f_I = b dV_I); z components must be 0.
#include "app/method_registry.hpp"

namespace lamina::app {

MethodEntry mpfem_method_entry();

}  // namespace lamina::app
