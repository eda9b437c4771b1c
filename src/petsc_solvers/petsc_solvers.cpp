// The entry point of the module lamina_petsc_solvers: PETSc and SLEPc (about 90 shared libraries: hypre,
// MUMPS, Trilinos, HDF5, ...; about 35 ms of dynamic loading at every process start) are loaded with
// this module by solve/petsc_module.cpp at the first PETSc solve, so only runs that use them pay for them.
#include "petsc_solvers/petsc_solvers.hpp"

#include "solve/petsc_module.hpp"

/// The module's one entry point; errors of the solvers are thrown as lamina::AnalysisError, caught by the
/// caller (same compiler and libstdc++, type compared by name).
extern "C" __attribute__((visibility("default"))) const lamina::solve::PetscSolvers* lamina_petsc_solvers() {
  namespace petsc = lamina::solve::petsc;
  static const lamina::solve::PetscSolvers table{lamina::solve::petsc_solvers_abi, &petsc::solve_symmetric,
                                                 &petsc::solve_general, &petsc::largest_generalized_eigenpairs,
                                                 &petsc::finalize};
  return &table;
}
