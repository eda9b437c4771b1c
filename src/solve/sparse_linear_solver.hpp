#pragma once
// Direct solution of the sparse linear systems of the static methods.
//
//   solve_symmetric: K x = b with K symmetric, given by its upper triangle (column-major).
//     1. CHOLMOD supernodal Cholesky (solve/sparse_cholesky.hpp; CHOLMOD orders with both AMD and
//        METIS and keeps the sparser factor). Accepted when the factorisation succeeds and the reciprocal condition estimate
//        of the factor (cholmod_rcond: (min diag L / max diag L)^2) is above `min_rcond`. A small, nearly
//        full K (at most 2000 rows, at least half of the triangle stored) is factored dense instead
//        (solve/dense_cholesky.hpp), accepted and checked the same way.
//     2. Otherwise (not positive definite): Eigen::SimplicialLDLT as the fallback (indefinite
//        symmetric systems without pivoting).
//   solve_general: A x = b with A square and unsymmetric (or a symmetric saddle-point system):
//     Eigen::SparseLU with COLAMD ordering.
//
// Both refine the solution iteratively (up to 2 steps) and check the result: finite, and normwise
// backward error |A x - b| / (|A| |x| + |b|) <= residual_tolerance (a stable direct solve gives
// ~1e-16 however ill-conditioned the system; a singular one much more);
// otherwise they throw AnalysisError with a message saying what is wrong (a singular system means
// the boundary conditions leave a rigid-body motion free).
#include <Eigen/Sparse>
#include <string>

#include "core/types.hpp"

namespace lamina::solve {

using SparseMatrix = Eigen::SparseMatrix<Real, Eigen::ColMajor, int>;

struct SolverReport {
  std::string method;       // "dense_llt", "cholmod_supernodal_llt", "simplicial_ldlt", "sparse_lu"
  Index rows = 0;
  Index nonzeros = 0;       // stored entries (upper triangle for symmetric systems)
  Real factor_seconds = 0;  // analysis + factorisation
  Real solve_seconds = 0;
  Real rcond = 0;           // reciprocal condition estimate (Cholesky only; 0 otherwise)
  Real residual = 0;        // |A x - b| / |b|
  Real backward_error = 0;  // |A x - b|_inf / (|A|_inf |x|_inf + |b|_inf)
  std::string note;         // why a fallback was used
};

struct SolverOptions {
  Real min_rcond = 1e-20;            // below: treated as singular (rigid-body mode)
  Real residual_tolerance = 1e-9;    // on the normwise backward error
  /// On |A x - b| / |b|: a backward-stable solve of a nearly singular system can still return a
  /// solution that misses the equations by orders of magnitude (x = 0 would give 1); above this the
  /// solve is treated as singular. Ill-conditioned but sound systems stay far below (the thin
  /// cantilever 2000 x 2 x 2 at 101 x 5 x 5 nodes: 1.5e-3).
  Real max_relative_residual = 1e-2;
  /// OpenMP threads of the Cholesky factorisation (0: all). Its parallel regions copy update matrices
  /// and are memory-bound: on the 2-core reference machine one thread factors the 41 x 41 x 5 EFG
  /// plate (25k dofs, 7.8M stored entries) in 3.7 s, two threads in 5.8 s.
  int factor_threads = 1;
  bool allow_fallback = true;        // symmetric: try SimplicialLDLT when CHOLMOD fails
  bool force_fallback = false;       // symmetric: skip CHOLMOD (tests)
};

/// K x = b, K symmetric given as its upper triangle. Throws AnalysisError if singular.
Eigen::VectorXd solve_symmetric(const SparseMatrix& upper, const Eigen::VectorXd& b, SolverReport& report,
                                const SolverOptions& options = {});

/// A x = b, A square (full storage). Throws AnalysisError if singular.
Eigen::VectorXd solve_general(const SparseMatrix& a, const Eigen::VectorXd& b, SolverReport& report,
                              const SolverOptions& options = {});

/// y = K x for K symmetric stored as its upper triangle.
Eigen::VectorXd multiply_symmetric_upper(const SparseMatrix& upper, const Eigen::VectorXd& x);

}  // namespace lamina::solve
