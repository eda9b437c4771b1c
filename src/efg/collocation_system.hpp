#pragma once
// Point collocation EFG system (seed 004 section 1.2.2 (2), eq 1-30 with v_i = delta(x - x_i)):
// three strong-form residual rows per node (strong_form_residuals.hpp) form a square system.
//
// Row I*3 + i is the row of node I and component i. Every row is divided by its largest absolute
// coefficient (row equilibration: equilibrium rows scale like E/h^2, traction rows like E/h,
// displacement rows like 1; scaling rows does not change the solution of a square system). The
// system is unsymmetric and solved by sparse LU (Eigen::SparseLU, COLAMD ordering, see
// sparse_linear_solver.hpp). A singular system (a rigid-body motion left free, or a support too
// small for the second derivatives) stops with AnalysisError.
#include <vector>

#include "efg/strong_form_residuals.hpp"
#include "solve/sparse_linear_solver.hpp"

namespace lamina::efg {

/// node_residuals[I]: exactly 3 rows (components x y z) of node I. Returns the 3N nodal parameters.
Eigen::VectorXd solve_collocation(const std::vector<PointResiduals>& node_residuals, solve::SolverReport& report);

}  // namespace lamina::efg
