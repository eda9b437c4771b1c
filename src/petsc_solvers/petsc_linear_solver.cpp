#include "petsc_solvers/petsc_solvers.hpp"

#include <fmt/format.h>
#include <petscksp.h>

#include <vector>

#include "core/error.hpp"
#include "core/stopwatch.hpp"
#include "petsc_solvers/petsc_matrix.hpp"

namespace lamina::solve::petsc {

namespace {

enum class Storage { symmetric_upper, full };

Eigen::VectorXd solve_petsc(const SparseMatrix& upper, const Eigen::VectorXd& b, const LinearSolverChoice& choice,
                            const parallel::Communicator& comm, SolverReport& report, SystemShares shares, Storage storage,
                            bool positive_definite, int dofs_per_node) {
  const bool mirror = storage == Storage::symmetric_upper;  // the lower triangle from the upper one
  ensure_started();
  const auto start = Clock::now();
  const PetscInt n = static_cast<PetscInt>(upper.rows());
  const int ranks = comm.size();
  const RowBlock block = row_block(n, dofs_per_node, comm);
  const PetscInt first = block.first, last = block.last;
  // a replicated system: this rank passes the entries of its rows only
  auto passes = [&](Index row) { return shares == SystemShares::summed || (row >= first && row < last); };
  Mat a = assemble_matrix(upper, mirror, shares, block);
  check(MatSetOption(a, MAT_SPD, mirror && positive_definite ? PETSC_TRUE : PETSC_FALSE), "MatSetOption");

  Vec rhs, x;
  check(MatCreateVecs(a, &x, &rhs), "MatCreateVecs");
  {
    std::vector<PetscInt> rows;
    std::vector<PetscScalar> values;
    for (Index i = 0; i < b.size(); ++i)
      if (b[i] != 0.0 && passes(i)) rows.push_back(static_cast<PetscInt>(i)), values.push_back(b[i]);
    check(VecSetValues(rhs, static_cast<PetscInt>(rows.size()), rows.data(), values.data(), ADD_VALUES), "VecSetValues");
    check(VecAssemblyBegin(rhs), "VecAssemblyBegin");
    check(VecAssemblyEnd(rhs), "VecAssemblyEnd");
  }
  const Real assembly_seconds = seconds_since(start);

  KSP ksp;
  PC pc;
  check(KSPCreate(PETSC_COMM_WORLD, &ksp), "KSPCreate");
  check(KSPSetOperators(ksp, a, a), "KSPSetOperators");
  check(KSPGetPC(ksp, &pc), "KSPGetPC");
  const bool direct = choice.type != LinearSolverChoice::Type::cg;
  if (direct) {
    check(KSPSetType(ksp, KSPPREONLY), "KSPSetType");
    check(PCSetType(pc, mirror ? PCCHOLESKY : PCLU), "PCSetType");
    check(PCFactorSetMatSolverType(pc, MATSOLVERMUMPS), "PCFactorSetMatSolverType");
    report.method = mirror ? "petsc_mumps_cholesky" : "petsc_mumps_lu";
  } else {
    check(KSPSetType(ksp, mirror ? KSPCG : KSPGMRES), "KSPSetType");
    check(KSPSetTolerances(ksp, choice.relative_tolerance, 0.0, PETSC_DEFAULT, choice.max_iterations), "KSPSetTolerances");
    // the tolerance is on |b - K x| / |b| (PETSc's CG would test the preconditioned residual)
    check(KSPSetNormType(ksp, KSP_NORM_UNPRECONDITIONED), "KSPSetNormType");
    if (choice.preconditioner == LinearSolverChoice::Preconditioner::hypre) {
      check(PCSetType(pc, PCHYPRE), "PCSetType");
      check(PCHYPRESetType(pc, "boomeramg"), "PCHYPRESetType");
      report.method = mirror ? "petsc_cg_hypre_boomeramg" : "petsc_gmres_hypre_boomeramg";
    } else {
      check(PCSetType(pc, PCGAMG), "PCSetType");
      report.method = mirror ? "petsc_cg_gamg" : "petsc_gmres_gamg";
    }
  }
  const auto factor_start = Clock::now();
  check(KSPSetUp(ksp), "KSPSetUp");
  report.factor_seconds = seconds_since(factor_start);
  const auto solve_start = Clock::now();
  check(KSPSolve(ksp, rhs, x), "KSPSolve");
  report.solve_seconds = seconds_since(solve_start);
  KSPConvergedReason reason;
  check(KSPGetConvergedReason(ksp, &reason), "KSPGetConvergedReason");
  PetscInt iterations = 0;
  KSPGetIterationNumber(ksp, &iterations);
  if (reason < 0) {
    KSPDestroy(&ksp);
    VecDestroy(&x);
    VecDestroy(&rhs);
    MatDestroy(&a);
    throw AnalysisError(fmt::format("PETSc {}: the solve failed ({}, after {} iterations): a singular system (a rigid-body "
                                    "motion left free) or, for cg, too few iterations",
                                    report.method, KSPConvergedReasons[reason], static_cast<long>(iterations)));
  }
  // residual |A x - b| / |b|
  Vec residual;
  check(VecDuplicate(rhs, &residual), "VecDuplicate");
  check(MatMult(a, x, residual), "MatMult");
  check(VecAXPY(residual, -1.0, rhs), "VecAXPY");
  PetscReal rnorm = 0, bnorm = 0;
  VecNorm(residual, NORM_2, &rnorm);
  VecNorm(rhs, NORM_2, &bnorm);
  report.residual = bnorm > 0 ? rnorm / bnorm : rnorm;
  report.rows = n;
  MatInfo info;
  MatGetInfo(a, MAT_GLOBAL_SUM, &info);
  report.nonzeros = static_cast<Index>(info.nz_used);
  report.note = fmt::format("{} ranks, {} iterations, assembly {:.3f} s", ranks, static_cast<long>(iterations), assembly_seconds);

  // the whole solution on every rank
  Vec all;
  VecScatter scatter;
  check(VecScatterCreateToAll(x, &scatter, &all), "VecScatterCreateToAll");
  check(VecScatterBegin(scatter, x, all, INSERT_VALUES, SCATTER_FORWARD), "VecScatterBegin");
  check(VecScatterEnd(scatter, x, all, INSERT_VALUES, SCATTER_FORWARD), "VecScatterEnd");
  Eigen::VectorXd solution(n);
  const PetscScalar* data = nullptr;
  check(VecGetArrayRead(all, &data), "VecGetArrayRead");
  std::copy(data, data + n, solution.data());
  VecRestoreArrayRead(all, &data);
  VecScatterDestroy(&scatter);
  VecDestroy(&all);
  VecDestroy(&residual);
  KSPDestroy(&ksp);
  VecDestroy(&x);
  VecDestroy(&rhs);
  MatDestroy(&a);
  if (!solution.allFinite()) throw AnalysisError("PETSc " + report.method + ": non-finite solution");
  return solution;
}

}  // namespace

Eigen::VectorXd solve_symmetric(const SparseMatrix& upper, const Eigen::VectorXd& b, const LinearSolverChoice& choice,
                                const parallel::Communicator& comm, SolverReport& report, SystemShares shares,
                                bool positive_definite, int dofs_per_node) {
  return solve_petsc(upper, b, choice, comm, report, shares, Storage::symmetric_upper, positive_definite, dofs_per_node);
}

Eigen::VectorXd solve_general(const SparseMatrix& a, const Eigen::VectorXd& b, const LinearSolverChoice& choice,
                              const parallel::Communicator& comm, SolverReport& report, SystemShares shares, int dofs_per_node) {
  return solve_petsc(a, b, choice, comm, report, shares, Storage::full, false, dofs_per_node);
}

}  // namespace lamina::solve::petsc
