#pragma once
// The solvers of the PETSc module (src/petsc_solvers, loaded by solve/petsc_module.cpp): the bodies of
// solve/petsc_linear_solver.hpp and solve/slepc_eigen_solver.hpp, and PETSc's finalisation.
#include "solve/petsc_linear_solver.hpp"
#include "solve/slepc_eigen_solver.hpp"

namespace lamina::solve::petsc {

Eigen::VectorXd solve_symmetric(const SparseMatrix& upper, const Eigen::VectorXd& b, const LinearSolverChoice& choice,
                                const parallel::Communicator& comm, SolverReport& report, SystemShares shares,
                                bool positive_definite, int dofs_per_node);
Eigen::VectorXd solve_general(const SparseMatrix& a, const Eigen::VectorXd& b, const LinearSolverChoice& choice,
                              const parallel::Communicator& comm, SolverReport& report, SystemShares shares, int dofs_per_node);
EigenPairs largest_generalized_eigenpairs(const SparseMatrix& a_upper, const SparseMatrix& b_upper, int count,
                                          const parallel::Communicator& comm, Real tolerance, int max_iterations,
                                          int dofs_per_node);
/// PetscFinalize when ensure_started() initialised PETSc and it is not finalised yet; else nothing.
void finalize();

}  // namespace lamina::solve::petsc
