#include "petsc_solvers/petsc_solvers.hpp"

#include <fmt/format.h>
#include <slepceps.h>

#include <algorithm>
#include <vector>

#include "core/error.hpp"
#include "petsc_solvers/petsc_matrix.hpp"

namespace lamina::solve::petsc {

namespace {

/// SLEPc on top of the PETSc that ensure_started() started (finalized with it).
void ensure_slepc() {
  static bool started = false;
  if (started) return;
  ensure_started();
  PetscBool initialised = PETSC_FALSE;
  SlepcInitialized(&initialised);
  if (!initialised && SlepcInitializeNoArguments() != 0) throw AnalysisError("SLEPc could not be initialised");
  started = true;
}

}  // namespace

EigenPairs largest_generalized_eigenpairs(const SparseMatrix& a_upper, const SparseMatrix& b_upper, int count,
                                          const parallel::Communicator& comm, Real tolerance, int max_iterations,
                                          int dofs_per_node) {
  ensure_slepc();
  const PetscInt n = static_cast<PetscInt>(b_upper.rows());
  const RowBlock rows = row_block(n, dofs_per_node, comm);
  Mat a = assemble_matrix(a_upper, true, SystemShares::replicated, rows);
  Mat b = assemble_matrix(b_upper, true, SystemShares::replicated, rows);
  check(MatSetOption(b, MAT_SPD, PETSC_TRUE), "MatSetOption");
  EPS eps;
  check(EPSCreate(PETSC_COMM_WORLD, &eps), "EPSCreate");
  check(EPSSetOperators(eps, a, b), "EPSSetOperators");
  check(EPSSetProblemType(eps, EPS_GHEP), "EPSSetProblemType");
  check(EPSSetType(eps, EPSKRYLOVSCHUR), "EPSSetType");
  check(EPSSetWhichEigenpairs(eps, EPS_LARGEST_REAL), "EPSSetWhichEigenpairs");
  const PetscInt nev = std::min<PetscInt>(count, n - 1);
  check(EPSSetDimensions(eps, nev, std::min<PetscInt>(std::max<PetscInt>(2 * nev + 1, 40), n), PETSC_DEFAULT),
        "EPSSetDimensions");
  check(EPSSetTolerances(eps, tolerance, max_iterations), "EPSSetTolerances");
  // the operator B^-1 A: B factorised by MUMPS Cholesky
  ST st;
  KSP ksp;
  PC pc;
  check(EPSGetST(eps, &st), "EPSGetST");
  check(STSetType(st, STSHIFT), "STSetType");
  check(STGetKSP(st, &ksp), "STGetKSP");
  check(KSPSetType(ksp, KSPPREONLY), "KSPSetType");
  check(KSPGetPC(ksp, &pc), "KSPGetPC");
  check(PCSetType(pc, PCCHOLESKY), "PCSetType");
  check(PCFactorSetMatSolverType(pc, MATSOLVERMUMPS), "PCFactorSetMatSolverType");
  const PetscErrorCode solved = EPSSolve(eps);
  PetscInt converged = 0;
  if (solved == 0) EPSGetConverged(eps, &converged);
  auto destroy = [&] {
    EPSDestroy(&eps);
    MatDestroy(&a);
    MatDestroy(&b);
  };
  if (solved != 0 || converged < nev) {
    destroy();
    throw AnalysisError(fmt::format("SLEPc: the eigenvalue solver did not converge ({} of {} eigenpairs{})", converged, nev,
                                    solved != 0 ? "; B not positive definite?" : ""));
  }
  EigenPairs out;
  out.values.resize(nev);
  out.vectors.resize(n, nev);
  Vec x, all;
  VecScatter scatter;
  check(MatCreateVecs(a, &x, nullptr), "MatCreateVecs");
  check(VecScatterCreateToAll(x, &scatter, &all), "VecScatterCreateToAll");
  for (PetscInt k = 0; k < nev; ++k) {
    PetscScalar value = 0;
    check(EPSGetEigenpair(eps, k, &value, nullptr, x, nullptr), "EPSGetEigenpair");
    check(VecScatterBegin(scatter, x, all, INSERT_VALUES, SCATTER_FORWARD), "VecScatterBegin");
    check(VecScatterEnd(scatter, x, all, INSERT_VALUES, SCATTER_FORWARD), "VecScatterEnd");
    const PetscScalar* data = nullptr;
    check(VecGetArrayRead(all, &data), "VecGetArrayRead");
    std::copy(data, data + n, out.vectors.col(k).data());
    VecRestoreArrayRead(all, &data);
    out.values[k] = value;
  }
  VecScatterDestroy(&scatter);
  VecDestroy(&all);
  VecDestroy(&x);
  destroy();
  return out;  // the largest first: SLEPc's order for EPS_LARGEST_REAL
}

}  // namespace lamina::solve::petsc
