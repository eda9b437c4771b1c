#pragma once
// Registration of `method: pd` (linearized ordinary state-based peridynamics, seed 002): reading
// the `pd:` section and `imperfection:`, and translating io::Case + Model into a pd::PeridynamicProblem.
//
// discretization: spacing: [dx, dy, dz] (cell-centred lattice over a box or plate; required),
//   horizon: value | horizon_factor: f (x the largest spacing; default 3.015)
// The `pd:` section (every key optional; defaults shown; docs/pd.md has the details)
//   analysis: quasi_static             # quasi_static | linear_static | explicit | buckling
//   kinematics: three_dimensional      # three_dimensional | plane_stress | plane_strain (nodes in one layer)
//   influence: one                     # one | inverse_distance (omega = delta / |xi|)
//   surface_correction: energy         # energy | none
//   partial_volume: false              # neighbour volume ramp over delta -/+ h/2, h = cell size
//   quasi_static: {increments: 10, tolerance: 1e-5, absolute_tolerance: auto, switch_iteration: 2000,
//                  max_iterations: 20000, max_cuts: 6, density_factor: 1, velocity_guard: 1e-10,
//                  predictor: secant}      # secant | previous
//   explicit: {end_time: 1e-3, safety_factor: 0.8, time_step: auto, outputs: 20, damping: 0}
//   buckling: {modes: 3}
// imperfection: {shape: sine, half_waves: [m, n], amplitude: a} | {shape: buckling_mode, mode: k, amplitude: a}
//   | {file: mode.csv, amplitude: a}   (CSV x,y,z,ux,uy,uz; nearest point onto each node)
// Loads: force (total, shared equally by the selected nodes), body_force (per unit volume),
// initial_velocity; boundary: fix / symmetry / displacement (values may be expressions of x y z),
// velocity (explicit only). Loads and prescribed values follow their ramp over the load factor
// (quasi_static) or over end_time (explicit).
#include "app/method_registry.hpp"
#include "pd/peridynamic_problem.hpp"

namespace lamina::app {

MethodEntry pd_method_entry();

}  // namespace lamina::app
