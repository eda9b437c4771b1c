#include "solve/petsc_module.hpp"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <string>
#include <vector>

#include "core/error.hpp"

namespace lamina::solve {

namespace {

using EntryPoint = const PetscSolvers* (*)();

/// The module file: beside the running program (the installed layout), else where the build put it
/// (the test and bench programs one folder down, the Python module anywhere).
std::vector<std::filesystem::path> module_candidates() {
  std::vector<std::filesystem::path> candidates;
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    candidates.push_back(exe.parent_path() / LAMINA_PETSC_SOLVERS_NAME);
    candidates.push_back(exe.parent_path().parent_path() / LAMINA_PETSC_SOLVERS_NAME);  // tests/, bench/
  }
  candidates.push_back(LAMINA_PETSC_SOLVERS_PATH);
  return candidates;
}

/// The module, loaded once per process. On loading, its finalize is registered to run before this
/// program's MPI_Finalize (parallel::Environment) or at exit where there is none (Python).
const PetscSolvers& solvers() {
  static std::mutex mutex;
  static const PetscSolvers* table = nullptr;
  std::lock_guard<std::mutex> lock(mutex);
  if (table) return *table;
  std::string why;
  for (const auto& candidate : module_candidates()) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(candidate, ec)) continue;
    void* handle = dlopen(candidate.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
      why = dlerror();
      continue;
    }
    const auto entry = reinterpret_cast<EntryPoint>(dlsym(handle, "lamina_petsc_solvers"));
    const PetscSolvers* loaded = entry ? entry() : nullptr;
    if (!loaded || loaded->abi != petsc_solvers_abi) {
      why = candidate.string() + (loaded ? " is from another lamina build (interface version " + std::to_string(loaded->abi) +
                                               ", expected " + std::to_string(petsc_solvers_abi) + ")"
                                         : " has no lamina_petsc_solvers");
      dlclose(handle);
      continue;
    }
    table = loaded;  // the module stays loaded until the process ends
    parallel::Environment::before_finalize([] { table->finalize(); });
    std::atexit([] { table->finalize(); });
    return *table;
  }
  throw AnalysisError("the PETSc solvers module " + std::string(LAMINA_PETSC_SOLVERS_NAME) + " could not be loaded" +
                      (why.empty() ? " (not found beside the program or at " + std::string(LAMINA_PETSC_SOLVERS_PATH) + ")"
                                   : ": " + why));
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
