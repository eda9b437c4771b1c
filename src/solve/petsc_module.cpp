#include "solve/petsc_module.hpp"

#include <cstdlib>
#include <mutex>
#include <string>

#include "core/error.hpp"
#include "core/runtime_module.hpp"

namespace lamina::solve {

namespace {

/// The module, loaded once per process. On loading, its finalize is registered to run before this
/// program's MPI_Finalize (parallel::Environment) or at exit where there is none (Python).
const PetscSolvers& solvers() {
  static std::mutex mutex;
  static const PetscSolvers* table = nullptr;
  std::lock_guard<std::mutex> lock(mutex);
  if (table) return *table;
  std::string why;
  table = open_module_table<PetscSolvers>(LAMINA_PETSC_SOLVERS_NAME, LAMINA_PETSC_SOLVERS_PATH, "lamina_petsc_solvers",
                                          petsc_solvers_abi, why);  // the module stays loaded until the process ends
  if (!table)
    throw SolverUnavailable("the PETSc solvers module " + std::string(LAMINA_PETSC_SOLVERS_NAME) + " could not be loaded: " + why);
  parallel::Environment::before_finalize([] { table->finalize(); });
  std::atexit([] { table->finalize(); });
  return *table;
}

}  // namespace

Eigen::VectorXd solve_symmetric_petsc(const SparseMatrix& upper, const Eigen::VectorXd& b, const LinearSolverChoice& choice,
                                      const parallel::Communicator& comm, SolverReport& report, SystemShares shares,
                                      bool positive_definite, int dofs_per_node) {
  return solvers().solve_symmetric(upper, b, choice, comm, report, shares, positive_definite, dofs_per_node);
}

Eigen::VectorXd solve_general_petsc(const SparseMatrix& a, const Eigen::VectorXd& b, const LinearSolverChoice& choice,
                                    const parallel::Communicator& comm, SolverReport& report, SystemShares shares,
                                    int dofs_per_node) {
  return solvers().solve_general(a, b, choice, comm, report, shares, dofs_per_node);
}

EigenPairs largest_generalized_eigenpairs(const SparseMatrix& a_upper, const SparseMatrix& b_upper, int count,
                                          const parallel::Communicator& comm, Real tolerance, int max_iterations,
                                          int dofs_per_node) {
  return solvers().largest_generalized_eigenpairs(a_upper, b_upper, count, comm, tolerance, max_iterations, dofs_per_node);
}

}  // namespace lamina::solve
