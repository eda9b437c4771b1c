#pragma once
// Registration of `method: efg` (EFG, 3D linear elastostatics, seed 004 eqs 1-30..1-35): reading
// the `efg:` section and translating io::Case + Model into an efg::EfgProblem.
//
// The `efg:` section (every key optional; defaults shown)
//   formulation: galerkin              # galerkin | collocation | weighted_least_squares (seed 004 section 1.2.2)
//   weighted_least_squares:            # only with formulation: weighted_least_squares (eq 1-35)
//     traction_weight: 1e5             #   beta, weight of the squared traction residuals
//     displacement_weight: <alpha>     #   default beta [E / (1 - nu^2)]^2 (stiffest material)
//     points: nodes                    #   nodes | nodes_and_cell_centres (auxiliary equilibrium points)
//   basis: quadratic                   # linear | quadratic
//   weight: quartic_spline             # gauss | cubic_spline | quartic_spline   (gauss_beta: 2.5)
//   support: {shape: box, kappa: 2.0}  # {shape: sphere, kappa: 2.5} | {nearest: N, kappa: k} (SELECT) | {radius: [rx, ry, rz]}
//                                      # | {mode: all|variable, nearest: N, scale: s}  (see mls_options.hpp)
//                                      # a quadratic basis needs kappa > 2 on a body's faces (2.5 or 3)
//   singular_remedy: false             # true: grow the support where the moment matrix is singular (SINCHECK)
//   integration:
//     cells: [cx, cy, cz]              # background cells per parametric direction (default: one per node interval)
//     gauss: 2                         # Gauss points per cell and direction, or [gx, gy, gz]
//     correction: none                 # vci: variationally consistent integration (exact patch test;
//                                      #   unsymmetric system, sparse LU)
//     volumetric: full                 # reduced: lambda term on a lower-order rule (nearly incompressible)
//     volumetric_gauss: gauss - 1      # order of that rule (at least 1)
//   essential_bc: penalty              # penalty | penalty_nodes | nitsche | lagrange (essential_boundary.hpp)
//   penalty: <alpha>                   # absolute penalty value; default penalty_factor x stiffness scale
//   penalty_factor: 1e5
//   nitsche: {factor: 100}             # beta = factor (lambda + 2 mu) / h
//   exact_displacement: [ux, uy, uz]   # expressions of x y z: builtin probes err_displacement, err_stress
//
// Strong forms (collocation, weighted_least_squares; src/efg/strong_form_residuals.hpp): equilibrium
// div sigma + b = 0, traction sigma n = t and u = u-bar as residual rows at the nodes, using the MLS
// second derivatives. They need basis: quadratic (kappa 2.5 or more), one material, and generated
// nodes; loads are traction / pressure (pointwise at the nodes of the loaded faces, so a patch
// smaller than the node spacing loses its resultant) and body_force (a `force` load is an input
// error). Essential conditions act at the selected nodes (essential_bc,
// penalty, nitsche and integration keys are ignored). Collocation: 3 rows per node, square system,
// sparse LU; on edges and corners the traction row uses the normalised sum of the faces' normals.
// Weighted least squares: normal equations, CHOLMOD. Reactions: sigma(u^h) n integrated over the
// constrained faces (none for point selections). Use Galerkin for production: the strong forms
// pass the patch test but degrade with stiff (fully clamped) conditions (seed 004 section 3.3).
//
// Loads: force = total over the selected nodes, applied at their positions through the shape
// functions (f_I += phi_I(x_c) F / n); traction / pressure integrated over the boundary faces where
// the selection holds at the quadrature point (faces selected only in part are split 8 x 8);
// body_force per unit volume, where the selection holds at the quadrature point.
// Boundary: fix / symmetry / displacement (constants or expressions of x y z) per translation;
// rotations (rx ry rz) are ignored, a condition with rotations only is an error.
#include "app/method_registry.hpp"
#include "efg/efg_problem.hpp"

namespace lamina::app {

MethodEntry efg_method_entry();

/// Reads the `efg:` section (problems go to the reader's sink).
efg::EfgOptions read_efg_options(const io::NodeReader& section);

/// Builds the EFG problem from the case and the prepared model (InputError on unsupported input).
efg::EfgProblem make_efg_problem(const io::Case& c, const Model& model, const efg::EfgOptions& options);

}  // namespace lamina::app
