#pragma once
// The case's boundary conditions and loads, taken as the case states them (model::Constraint,
// model::Load with their nodes resolved), applied to the pd nodes: prescribed degrees of freedom (a
// later condition on the same dof replaces an earlier one; velocities only in explicit dynamics, a
// step by default), nodal forces (force: the total shared equally; body_force: per unit volume) and
// initial velocities. Expressions of x, y, z are evaluated at the nodes' reference positions (t = 0).
#include <vector>

#include "core/error.hpp"
#include "model/constraint.hpp"
#include "model/load.hpp"
#include "pd/peridynamic_problem.hpp"

namespace lamina::pd {

/// Fills p.prescribed, p.forces, p.initial_velocity and p.ramps (p.positions, p.volumes and p.analysis
/// set); what the pd nodes cannot take is added to `problems` at the entry's position in the case.
void apply_conditions(const std::vector<model::Constraint>& constraints, const std::vector<model::Load>& loads,
                      PeridynamicProblem& p, std::vector<Diagnostic>& problems);

}  // namespace lamina::pd
