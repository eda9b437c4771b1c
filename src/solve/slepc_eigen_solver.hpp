#pragma once
// The largest eigenvalues of a symmetric-definite pencil A x = mu B x (B positive definite) through
// SLEPc (libslepc-real-dev): Krylov-Schur on the generalised Hermitian problem with B-inner products,
// B factorised once by MUMPS Cholesky (spectral transformation "shift" at 0: the operator B^-1 A).
// Every rank holds A and B whole (replicated) and passes its block of rows; the eigenvectors come back
// whole on every rank. Used by the pd buckling analysis on several ranks (docs/scaling.md).
#include "core/types.hpp"
#include "parallel/communicator.hpp"
#include "solve/sparse_linear_solver.hpp"

namespace lamina::solve {

struct EigenPairs {
  Eigen::VectorXd values;   // the largest first
  Eigen::MatrixXd vectors;  // one column per value, B-normalised
};

/// a_upper, b_upper: upper triangles. Throws AnalysisError when SLEPc does not converge `count` pairs
/// to `tolerance` (relative) within max_iterations restarts, or B is not positive definite.
EigenPairs largest_generalized_eigenpairs(const SparseMatrix& a_upper, const SparseMatrix& b_upper, int count,
                                          const parallel::Communicator& comm, Real tolerance = 1e-10,
                                          int max_iterations = 2000, int dofs_per_node = 1);

}  // namespace lamina::solve
