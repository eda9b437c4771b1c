#pragma once
// K x = b through PETSc (petsc-dev): each rank passes its share of K (a symmetric matrix as the upper
// triangle of the rank's partial sums, e.g. the contribution of its cells) and of b; PETSc adds the
// shares into a distributed AIJ matrix (rows in contiguous blocks per rank) and solves with MUMPS
// (Cholesky) or CG preconditioned by GAMG or hypre BoomerAMG. The solution comes back whole on every
// rank. Works on one process too (solver: {type: mumps | cg}).
#include "parallel/communicator.hpp"
#include "core/linear_solver_choice.hpp"
#include "solve/sparse_linear_solver.hpp"

namespace lamina::solve {

/// Throws AnalysisError when PETSc reports a failure (a singular matrix, CG not converged).
Eigen::VectorXd solve_symmetric_petsc(const SparseMatrix& upper_share, const Eigen::VectorXd& b_share,
                                      const LinearSolverChoice& choice, const parallel::Communicator& comm,
                                      SolverReport& report);

}  // namespace lamina::solve
