#pragma once
// SparseCholesky: the Cholesky factorisation of a sparse symmetric positive definite matrix (given by its
// upper triangle) that every sparse lamina factorisation uses: solve_symmetric, the pd buckling operator and
// its zero-energy check. The body is CHOLMOD's supernodal Cholesky in the module lamina_cholmod_factor
// (src/cholmod_factor): CHOLMOD with BLAS, LAPACK and METIS cost about 5.6 ms of dynamic loading at every
// process start (measured on the reference machine), so only a process that factors a sparse matrix loads them.
#include <memory>

#include "solve/sparse_linear_solver.hpp"

namespace lamina::solve {

class SparseCholesky {
 public:
  virtual ~SparseCholesky() = default;
  /// Factors K = L L^T (fill-reducing ordering: the sparser of AMD and METIS). False if K is not
  /// positive definite. Nothing is printed: a failed factorisation is reported by the caller.
  virtual bool compute(const SparseMatrix& upper) = 0;
  /// Reciprocal condition estimate of the factor, (min diag L / max diag L)^2 (0 before a factorisation).
  virtual Real rcond() const = 0;
  /// x = K^-1 b with the last successful factorisation.
  virtual Eigen::VectorXd solve(const Eigen::VectorXd& b) const = 0;
};

/// A new factorisation object; loads the module on first use. Throws SolverUnavailable if it cannot.
std::unique_ptr<SparseCholesky> make_sparse_cholesky();

/// The interface to the module (solve/sparse_cholesky.cpp loads it): raised when the table changes.
inline constexpr int cholmod_factor_abi = 1;
struct CholmodFactorModule {
  int abi = cholmod_factor_abi;
  std::unique_ptr<SparseCholesky> (*create)() = nullptr;
};

}  // namespace lamina::solve

/// The module's entry point (C linkage, found by dlsym under this name).
extern "C" __attribute__((visibility("default"))) const lamina::solve::CholmodFactorModule* lamina_cholmod_factor();
