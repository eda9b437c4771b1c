#pragma once
// The case's boundary conditions (model::Constraint with their particles resolved), taken as the case
// states them, as prescribed particle dofs of the 2D problem: fix and displacement on x and y
// (expressions of x, y, z at the particles, t = 1); velocities, and conditions on z or rotations
// only, are refused at the entry's position in the case.
#include <vector>

#include "core/error.hpp"
#include "core/prescribed_dof.hpp"
#include "model/constraint.hpp"

namespace lamina::mpfem {

/// positions: 3 x N particle coordinates. Problems are added to `problems`.
std::vector<PrescribedDof> prescribed_dofs(const std::vector<model::Constraint>& constraints, const PointMatrix& positions,
                                           std::vector<Diagnostic>& problems);

}  // namespace lamina::mpfem
