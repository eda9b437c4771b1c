#pragma once
// K x = b through PETSc (petsc-dev): each rank passes its share of K (a symmetric matrix as the upper
// triangle of the rank's partial sums, e.g. the contribution of its cells, or an unsymmetric one whole)
// and of b; PETSc adds the shares into a distributed AIJ matrix (rows in contiguous blocks per rank) and
// solves with MUMPS (Cholesky / LDL^T / LU) or CG (GMRES when unsymmetric) preconditioned by GAMG or
// hypre BoomerAMG. The solution comes back whole on every
// rank. Works on one process too (solver: {type: mumps | cg}).
#include "parallel/communicator.hpp"
#include "core/linear_solver_choice.hpp"
#include "solve/sparse_linear_solver.hpp"

namespace lamina::solve {

/// How the ranks hold the system: each a share that the shares add up to (summed), or each the whole
/// system (replicated: each rank then passes the rows of its block).
enum class SystemShares { summed, replicated };

/// Throws AnalysisError when PETSc reports a failure (a singular matrix, CG not converged).
/// positive_definite: MUMPS Cholesky for SPD matrices, else its symmetric-indefinite LDL^T.
/// dofs_per_node: the unknowns of a node (the rows are split between the ranks by whole nodes, and
/// GAMG aggregates node blocks).
Eigen::VectorXd solve_symmetric_petsc(const SparseMatrix& upper, const Eigen::VectorXd& b, const LinearSolverChoice& choice,
                                      const parallel::Communicator& comm, SolverReport& report,
                                      SystemShares shares = SystemShares::summed, bool positive_definite = true,
                                      int dofs_per_node = 3);

/// A x = b, A square and unsymmetric, given whole (full storage) per share: MUMPS LU, or (type: cg) GMRES
/// with the chosen preconditioner.
Eigen::VectorXd solve_general_petsc(const SparseMatrix& a, const Eigen::VectorXd& b, const LinearSolverChoice& choice,
                                    const parallel::Communicator& comm, SolverReport& report,
                                    SystemShares shares = SystemShares::summed, int dofs_per_node = 3);

}  // namespace lamina::solve
