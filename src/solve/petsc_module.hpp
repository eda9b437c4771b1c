#pragma once
// The interface between solve (solve/petsc_module.cpp, the loader) and the module that holds PETSc and
// SLEPc (src/petsc_solvers, loaded with dlopen at the first PETSc solve): one table of function pointers.
#include "parallel/communicator.hpp"
#include "solve/petsc_linear_solver.hpp"
#include "solve/slepc_eigen_solver.hpp"

namespace lamina::solve {

/// Raised when the table or the types it passes change: a module from another build is refused.
inline constexpr int petsc_solvers_abi = 1;

/// What the module's entry point returns (static storage); the functions are those of the public
/// headers, errors thrown as lamina::AnalysisError (same compiler and libstdc++: caught by type name).
struct PetscSolvers {
  int abi = petsc_solvers_abi;
  Eigen::VectorXd (*solve_symmetric)(const SparseMatrix& upper, const Eigen::VectorXd& b, const LinearSolverChoice& choice,
                                     const parallel::Communicator& comm, SolverReport& report, SystemShares shares,
                                     bool positive_definite, int dofs_per_node) = nullptr;
  Eigen::VectorXd (*solve_general)(const SparseMatrix& a, const Eigen::VectorXd& b, const LinearSolverChoice& choice,
                                   const parallel::Communicator& comm, SolverReport& report, SystemShares shares,
                                   int dofs_per_node) = nullptr;
  EigenPairs (*largest_generalized_eigenpairs)(const SparseMatrix& a_upper, const SparseMatrix& b_upper, int count,
                                               const parallel::Communicator& comm, Real tolerance, int max_iterations,
                                               int dofs_per_node) = nullptr;
  /// PetscFinalize when the module started PETSc and it is not finalised yet (else nothing); the loader
  /// calls it before lamina's MPI_Finalize (parallel::Environment) and at exit.
  void (*finalize)() = nullptr;
};

}  // namespace lamina::solve

/// The module's entry point (C linkage, found by dlsym under this name).
extern "C" __attribute__((visibility("default"))) const lamina::solve::PetscSolvers* lamina_petsc_solvers();
