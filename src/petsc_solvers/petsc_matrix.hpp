#pragma once
// The PETSc plumbing shared by the linear and eigen solvers of the PETSc module (src/petsc_solvers):
// PETSc started once per process, error codes turned into AnalysisError, and a distributed AIJ
// matrix built from an Eigen matrix that every rank holds (its share, or the whole replicated system).
#include <petscmat.h>

#include "parallel/communicator.hpp"
#include "solve/petsc_linear_solver.hpp"
#include "solve/sparse_linear_solver.hpp"

namespace lamina::solve::petsc {

/// PETSc, started once per process (on MPI_COMM_WORLD when lamina runs on several ranks); finalize()
/// (petsc_solvers.hpp) ends it, called by the loader before MPI (parallel::Environment) or at exit.
void ensure_started();
/// Throws AnalysisError naming `what` when code is not 0.
void check(PetscErrorCode code, const char* what);

/// The rows [first, last) that rank `rank` of `ranks` owns: whole nodes of dofs_per_node rows (when the
/// size divides), in contiguous blocks.
struct RowBlock {
  PetscInt block = 1, first = 0, last = 0;
};
RowBlock row_block(PetscInt n, int dofs_per_node, const parallel::Communicator& comm);

/// A distributed AIJ matrix of `m`: symmetric_upper = m holds the upper triangle of a symmetric matrix
/// (mirrored), else m is whole. shares: summed (each rank's m is a share, all entries passed) or
/// replicated (each rank passes the entries of its rows). Assembled; the caller destroys it.
Mat assemble_matrix(const SparseMatrix& m, bool symmetric_upper, SystemShares shares, const RowBlock& rows);

}  // namespace lamina::solve::petsc
