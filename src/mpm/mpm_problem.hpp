#pragma once
// Everything an MPM shell analysis needs, free of files and YAML: the shell mesh (CPDI2 domains),
// material, shell section, nodal conditions and loads, and the solver options (seed 000 eqs (1)-(14), (38)-(40)).
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "core/shell_mesh.hpp"
#include "core/ramp.hpp"
#include "core/types.hpp"
#include "geometry/expression.hpp"
#include "material/material_spec.hpp"
#include "model/constraint.hpp"
#include "model/load.hpp"
#include "shell/belytschko_tsay_shell.hpp"

namespace lamina::mpm {

struct MpmOptions {
  enum class Kind { quasi_static, dynamic };
  Kind analysis = Kind::quasi_static;
  /// quasi-static: how each load level reaches its static state. newton (default): Newton's method on the
  /// shell nodes (no grid; mpm_newton.cpp), a level it cannot finish going on by explicit dynamics;
  /// explicit: damped explicit dynamics through the grid (seed 000). Dynamic analyses are explicit.
  enum class Solver { explicit_dynamics, newton };
  Solver solver = Solver::newton;
  int load_levels = 10;           // quasi-static output levels (load factor k / load_levels)
  Real end_time = 1.0;            // dynamic
  int output_points = 10;         // dynamic: number of evenly spaced output times
  Real alpha = 0.5;               // grid time-step factor of eq (38)
  Real shell_safety = 0.9;        // factor on the shell's own stable step
  Real fixed_time_step = 0.0;     // > 0: this step instead of the adaptive one (no stability check)
  Real grid_cell = 0.0;           // 0: half the median element edge
  Real flip = 0.0;                // FLIP fraction of the G2P velocity update (0 = PIC)
  bool kinetic_damping = true;    // zero the velocities at every kinetic-energy peak (quasi-static default with physical mass)
  /// quasi-static only: fictitious nodal masses and rotational inertias from the Gershgorin bound of the
  /// element tangent stiffness (m_i = 1/4 dt^2 sum_j |K_ij|, dt = 1; seed 002 eq (5)) instead of the physical ones.
  bool mass_scaling = false;
  /// with mass_scaling: adaptive dynamic relaxation damping c = 2 sqrt(u^T K u / u^T M u) (seed 002 eqs (6)-(7)).
  bool adaptive_damping = true;
  Real mass_damping = 0.0;        // c in f = -c m v, m_rot = -c I omega (1/time)
  Real tolerance = 1e-4;          // quasi-static: residual ratio that ends a load level
  Index max_steps_per_level = 2000000;
  /// quasi-static: steps over which the load factor rises linearly from one level to the next (0: a
  /// step change). A ramp keeps path-dependent materials (j2_plasticity) from yielding under the
  /// dynamic overshoot of a sudden increment (a reflected step wave doubles the stress).
  Index level_ramp_steps = 0;
  Index max_steps = 50000000;     // dynamic
};

struct MpmProblem {
  ShellMesh mesh;
  /// The case's material entry as read (a density is required); the plane-stress shell kernel comes from
  /// material::make_shell_material (corotational linear elastic, neo-Hookean or J2).
  material::MaterialSpec material;
  shell::ShellSection section;
  /// Velocity conditions at shell nodes (fix = zero velocity; a zero displacement is a fixed component),
  /// applied on the grid and at the nodes (eq (7)); ramps over the load factor (quasi-static) or t / end_time.
  std::vector<model::Constraint> constraints;
  /// force, traction, pressure, body_force (per unit mass), moment, edge_moment, mass, initial_velocity.
  std::vector<model::Load> loads;
  MpmOptions options;
};

}  // namespace lamina::mpm
