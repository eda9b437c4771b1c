#pragma once
// Registration of `method: mpm` (CPDI2 material point method with Belytschko-Tsay shell domains,
// seed 000): reading the `mpm:` and `shell:` sections and translating io::Case + Model into an mpm::MpmProblem.
//
// shell:                              (every key optional; defaults shown)
//   thickness_points: 3               # Lobatto points through the thickness, 1..7 (seed eq (29)); default 3, 7 with a plastic material
//   hourglass: 0.1                    # hourglass coefficient r of eqs (30)-(36), 0..1 (0 = off)
//   shear_factor: 0.8333              # transverse shear factor k
//   warping_correction: true          # BWC-type rigid-body projection for warped elements
// mpm:
//   analysis: quasi_static            # quasi_static | dynamic
//   load_levels: 10                   # quasi-static: load factor k/levels held until static (output per level)
//   tolerance: 1.0e-4                 # quasi-static: residual ratio that ends a level
//   max_steps_per_level: 2000000
//   end_time: 1.0                     # dynamic
//   output_points: 10                 # dynamic: evenly spaced output times
//   max_steps: 50000000               # dynamic
//   time_step: {alpha: 0.5, shell_safety: 0.9}   # eq (38) factor; factor on the shell stable step;
//                                     #   {fixed: dt} replaces the adaptive step (no stability check)
//   damping: {kinetic: true, mass: 0.0}           # kinetic-energy damping (default on for quasi_static,
//                                     #   off for dynamic); mass-proportional c (1/time): f = -c m v
//   flip: 0.0                         # FLIP fraction of the G2P velocity update (0 = PIC)
//   moments:                          # nodal moments (total, shared equally by the selected nodes)
//     - {select: {set: xmax}, moment: [0, M, 0], ramp: linear}
// discretization: {elements: [n1, n2], grid: {cell: h}}   (cell default: half the median element edge)
// Boundary: fix x y z rx ry rz (global axes), symmetry (one translation; add the rotations with fix),
// velocity (prescribed, ramped). Loads: force, traction (edges: force per unit length), pressure
// (follower, on elements whose four nodes are selected), body_force (per unit mass), mass,
// initial_velocity. Ramps: linear over the load factor (quasi-static) or over end_time (dynamic).
#include "app/method_registry.hpp"
#include "mpm/mpm_problem.hpp"

namespace lamina::app {

MethodEntry mpm_method_entry();

}  // namespace lamina::app
