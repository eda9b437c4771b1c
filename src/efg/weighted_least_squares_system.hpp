#pragma once
// Weighted least squares EFG system (WLSM, seed 004 section 1.2.2 (5), eq 1-35): minimise
//   sum_points |div sigma(u^h) + b|^2 + beta sum_{traction rows} (sigma n - t-bar)_i^2
//                                     + alpha sum_{displacement rows} (u^h - u-bar)_i^2
// over the nodal parameters. The rows are those of least_squares_residuals() at every node (and at
// the auxiliary points, equilibrium only); the minimum solves the normal equations
//   (R^T W R) u = R^T W rhs,   W = diag(1 | beta | alpha by row kind),
// a symmetric positive definite system (once the conditions remove the rigid-body motions),
// assembled over the points' neighbour blocks and solved by CHOLMOD (sparse_linear_solver.hpp).
// The seed's penalty weights: beta = 1e5, alpha = beta [E / (1 - nu^2)]^2 (unscaled residuals, so
// the weights carry the units: alpha makes the displacement rows, ~u, comparable to the traction
// rows, ~E u / h). The normal equations square the condition number of the rows. Assembly is
// parallel over chunks of points (OpenMP) and deterministic for a given thread count.
#include <vector>

#include "efg/strong_form_residuals.hpp"
#include "solve/sparse_linear_solver.hpp"

namespace lamina::efg {

struct LeastSquaresWeights {
  Real equilibrium = 1.0;
  Real traction = 1e5;      // beta
  Real displacement = 0.0;  // alpha
};

/// The seed's alpha = beta [E / (1 - nu^2)]^2.
Real seed_displacement_weight(Real traction_weight, const material::LinearElastic& material);

/// Assembles and solves the normal equations over `nodes` nodal parameter triples; equations =
/// number of residual rows.
Eigen::VectorXd solve_weighted_least_squares(const std::vector<PointResiduals>& point_residuals, Index nodes,
                                             const LeastSquaresWeights& weights, solve::SolverReport& report,
                                             Index& equations);

}  // namespace lamina::efg
