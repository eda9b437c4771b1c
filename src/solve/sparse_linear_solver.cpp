#include "solve/sparse_linear_solver.hpp"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>

#include <fmt/format.h>

#include "core/error.hpp"
#include "core/stopwatch.hpp"
#include "solve/dense_cholesky.hpp"
#include "solve/sparse_cholesky.hpp"

namespace lamina::solve {

namespace {

Real relative_residual(const Eigen::VectorXd& r, const Eigen::VectorXd& b) {
  const Real nb = b.norm();
  return nb > 0 ? r.norm() / nb : r.norm();
}

/// Normwise backward error |r|_inf / (|A|_inf |x|_inf + |b|_inf): small (~1e-16) for a stable
/// solve even when the system is ill-conditioned (thin structures), unlike |r| / |b|.
Real backward_error(const Eigen::VectorXd& r, Real norm_a, const Eigen::VectorXd& x, const Eigen::VectorXd& b) {
  const Real scale = norm_a * x.lpNorm<Eigen::Infinity>() + b.lpNorm<Eigen::Infinity>();
  return scale > 0 ? r.lpNorm<Eigen::Infinity>() / scale : r.lpNorm<Eigen::Infinity>();
}

/// Infinity norm (max absolute row sum) of a symmetric matrix stored as its upper triangle.
Real norm_symmetric_upper(const SparseMatrix& upper) {
  Eigen::VectorXd sums = Eigen::VectorXd::Zero(upper.rows());
  for (Index col = 0; col < upper.outerSize(); ++col)
    for (SparseMatrix::InnerIterator it(upper, col); it; ++it) {
      sums[it.row()] += std::abs(it.value());
      if (it.row() != col) sums[col] += std::abs(it.value());
    }
  return sums.size() ? sums.maxCoeff() : 0.0;
}

Real norm_general(const SparseMatrix& a) {
  Eigen::VectorXd sums = Eigen::VectorXd::Zero(a.rows());
  for (Index col = 0; col < a.outerSize(); ++col)
    for (SparseMatrix::InnerIterator it(a, col); it; ++it) sums[it.row()] += std::abs(it.value());
  return sums.size() ? sums.maxCoeff() : 0.0;
}

/// Up to `steps` rounds of iterative refinement x += A^-1 (b - A x); returns the final residual.
template <class Multiply, class Solve>
Eigen::VectorXd refine(Eigen::VectorXd& x, const Eigen::VectorXd& b, Real norm_a, Multiply multiply, Solve solve, int steps) {
  Eigen::VectorXd r = b - multiply(x);
  for (int k = 0; k < steps && backward_error(r, norm_a, x, b) > 1e-15; ++k) {
    x += solve(r);
    r = b - multiply(x);
  }
  return r;
}

/// A backward-stable solve whose solution still misses the equations: the system is nearly singular.
[[noreturn]] void nearly_singular(const SolverReport& report) {
  throw AnalysisError(fmt::format(
      "the linear system is nearly singular: the solution misses the equations by a relative residual of {:.3g} "
      "(backward error {:.3g}, {}). Check for a free rigid-body motion or a support that is too small; a constraint "
      "method can also be unstable with the chosen integration (e.g. essential_bc: lagrange with reduced "
      "volumetric integration): try penalty or nitsche",
      report.residual, report.backward_error, report.method));
}

[[noreturn]] void singular(const std::string& detail) {
  throw AnalysisError(
      "the stiffness matrix is singular (" + detail +
      "): the boundary conditions leave a rigid-body motion free, or a support is too small; fix the components "
      "of enough nodes (e.g. a symmetry plane per direction and one point against the remaining motion)");
}

}  // namespace

Eigen::VectorXd multiply_symmetric_upper(const SparseMatrix& upper, const Eigen::VectorXd& x) {
  return upper.selfadjointView<Eigen::Upper>() * x;
}

Eigen::VectorXd solve_symmetric(const SparseMatrix& upper, const Eigen::VectorXd& b, SolverReport& report,
                                const SolverOptions& options) {
  report = SolverReport{};
  report.rows = upper.rows();
  report.nonzeros = upper.nonZeros();
  if (upper.rows() == 0) return Eigen::VectorXd();
  Eigen::VectorXd x;
  if (!options.force_fallback) {
    // dense for a small, nearly full K (solve/dense_cholesky.hpp), else CHOLMOD (loaded on first use)
    const bool dense = dense_cholesky_pays(upper);
    auto start = std::chrono::steady_clock::now();
    const std::unique_ptr<SparseCholesky> llt = dense ? std::make_unique<DenseCholesky>() : make_sparse_cholesky();
    const int saved_threads = omp_get_max_threads();
    if (options.factor_threads > 0) omp_set_num_threads(std::min(options.factor_threads, saved_threads));
    const bool factored = llt->compute(upper);
    omp_set_num_threads(saved_threads);
    report.factor_seconds = seconds_since(start);
    if (factored) {
      report.rcond = llt->rcond();
      if (!(report.rcond > options.min_rcond)) singular(fmt::format("Cholesky pivot ratio estimate {:.3g}", report.rcond));
      start = std::chrono::steady_clock::now();
      x = llt->solve(b);
      if (x.allFinite())
        refine(x, b, norm_symmetric_upper(upper), [&](const Eigen::VectorXd& v) { return multiply_symmetric_upper(upper, v); },
               [&](const Eigen::VectorXd& r) -> Eigen::VectorXd { return llt->solve(r); }, 2);
      report.solve_seconds = seconds_since(start);
      report.method = dense ? "dense_llt" : "cholmod_supernodal_llt";
    } else {
      report.note = dense ? "dense Cholesky: matrix not positive definite" : "CHOLMOD: matrix not positive definite";
      if (!options.allow_fallback)
        singular("not positive definite; with Nitsche boundary conditions increase efg.nitsche.factor");
    }
  }
  if (report.method.empty()) {
    auto start = std::chrono::steady_clock::now();
    Eigen::SimplicialLDLT<SparseMatrix, Eigen::Upper> ldlt;
    ldlt.compute(upper);
    report.factor_seconds += seconds_since(start);
    if (ldlt.info() != Eigen::Success) singular("LDLT factorisation failed");
    const Eigen::VectorXd d = ldlt.vectorD();
    const Real dmax = d.cwiseAbs().maxCoeff();
    const Real dmin = d.cwiseAbs().minCoeff();
    report.rcond = dmax > 0 ? dmin / dmax : 0.0;
    if (!(report.rcond > std::sqrt(options.min_rcond))) singular(fmt::format("LDLT pivot ratio {:.3g}", report.rcond));
    start = std::chrono::steady_clock::now();
    x = ldlt.solve(b);
    if (x.allFinite())
      refine(x, b, norm_symmetric_upper(upper), [&](const Eigen::VectorXd& v) { return multiply_symmetric_upper(upper, v); },
             [&](const Eigen::VectorXd& r) -> Eigen::VectorXd { return ldlt.solve(r); }, 2);
    report.solve_seconds = seconds_since(start);
    report.method = "simplicial_ldlt";
  }
  if (!x.allFinite()) singular("non-finite solution");
  const Eigen::VectorXd r = multiply_symmetric_upper(upper, x) - b;
  report.residual = relative_residual(r, b);
  report.backward_error = backward_error(r, norm_symmetric_upper(upper), x, b);
  if (!(report.backward_error <= options.residual_tolerance))
    singular(fmt::format("backward error {:.3g} (relative residual {:.3g}) after the solve", report.backward_error, report.residual));
  if (!(report.residual <= options.max_relative_residual)) nearly_singular(report);
  return x;
}

Eigen::VectorXd solve_general(const SparseMatrix& a, const Eigen::VectorXd& b, SolverReport& report,
                              const SolverOptions& options) {
  report = SolverReport{};
  report.rows = a.rows();
  report.nonzeros = a.nonZeros();
  if (a.rows() == 0) return Eigen::VectorXd();
  auto start = std::chrono::steady_clock::now();
  Eigen::SparseLU<SparseMatrix, Eigen::COLAMDOrdering<int>> lu;
  lu.analyzePattern(a);
  lu.factorize(a);
  report.factor_seconds = seconds_since(start);
  if (lu.info() != Eigen::Success) singular("sparse LU: " + lu.lastErrorMessage());
  start = std::chrono::steady_clock::now();
  Eigen::VectorXd x = lu.solve(b);
  const Real norm_a = norm_general(a);
  if (x.allFinite())
    refine(x, b, norm_a, [&](const Eigen::VectorXd& v) -> Eigen::VectorXd { return a * v; },
           [&](const Eigen::VectorXd& r) -> Eigen::VectorXd { return lu.solve(r); }, 2);
  report.solve_seconds = seconds_since(start);
  report.method = "sparse_lu";
  if (!x.allFinite()) singular("non-finite solution");
  const Eigen::VectorXd r = a * x - b;
  report.residual = relative_residual(r, b);
  report.backward_error = backward_error(r, norm_a, x, b);
  if (!(report.backward_error <= options.residual_tolerance))
    singular(fmt::format("backward error {:.3g} (relative residual {:.3g}) after the solve", report.backward_error, report.residual));
  if (!(report.residual <= options.max_relative_residual)) nearly_singular(report);
  return x;
}

}  // namespace lamina::solve
