#pragma once
// Essential (displacement) boundary conditions of the Galerkin EFG method. MLS shape functions
// are not interpolating (u^h(x_I) != u_I), so prescribed values cannot be set on nodal unknowns.
//
// Where a condition acts
//   A condition's selection is tested at the boundary-surface quadrature points (see
//   region_test.hpp); where it holds on a part of the surface, the condition is imposed on that
//   surface ("surface constraint"): u_i^h = u_i-bar for the constrained components i. Selections
//   that contain no surface quadrature point (a `nearest` node, a line of nodes, a single node)
//   are imposed at the positions of their selected nodes instead ("point constraint":
//   u_i^h(x_c) = u_i-bar(x_c)).
//
// Methods (efg.essential_bc)
//   penalty        alpha * sum_s w_s (u^h - u-bar)_i v_i over the surface points (and alpha * sum_c
//                  at point constraints). Simple and symmetric positive definite; it converges to
//                  the constrained solution only as alpha -> infinity (error ~ 1/alpha), which is
//                  fine for the benchmarks but not exact in a patch test.
//   penalty_nodes  the seed's (OMLL) form: penalty at the positions of the selected nodes only,
//                  even for surface selections (u^h = u-bar holds at the nodes, not between them).
//   nitsche        variationally consistent and symmetric (Nitsche 1971): on every surface point
//                   - (sigma(u^h) n)_i v_i - (sigma(v) n)_i (u^h - u-bar)_i + beta (u^h - u-bar)_i v_i,
//                  beta = factor * (lambda + 2 mu) / h, h the background cell size along the normal;
//                  point constraints fall back to the penalty form. Exact in the patch test (with
//                  VCI), optimal convergence, mild conditioning. Use it for accuracy studies.
//   lagrange       Lagrange multipliers enforcing u_i^h(x_c) = u_i-bar exactly at the positions of
//                  the selected nodes (all conditions as point constraints); saddle-point system
//                  solved by sparse LU. Exact at the nodes, like penalty_nodes with alpha = infinity.
//
// Default penalty: alpha = penalty_factor (1e5) * max diag(K) * E / (lambda + 2 mu) / max_I (sum_s w_s
// phi_I(x_s)^2), separately for the surface and the point constraints (E, lambda, mu of the
// material with the largest lambda + 2 mu): the penalty terms are about 1e5 times stiffer than the
// stiffest node of the body, measured with Young's modulus (not lambda + 2 mu, which grows without
// bound as nu -> 0.5 and would lock a nearly incompressible body at its constrained faces). efg.penalty gives alpha directly (force per length per
// area for surface constraints, force per length for point constraints).
#include <array>

#include "material/linear_elastic.hpp"
#include "mls/mls_shape_functions.hpp"

namespace lamina::efg {

/// One point where a condition is imposed (a surface quadrature point or a node position).
struct ConstraintPoint {
  Vec3 x = Vec3::Zero();
  Real weight = 1.0;           // surface: area weight; point: 1
  Vec3 normal = Vec3::Zero();  // surface only
  Real size = 0.0;             // surface: cell size along the normal (Nitsche h)
  int material = 0;            // surface: material index at the point
  bool surface = false;
  int condition = 0;           // index into EfgProblem::constraints
  std::array<bool, 3> constrained{false, false, false};
  Vec3 value = Vec3::Zero();   // prescribed displacement (constrained components)
};

/// Traction operator: T(i, 3k + b) = (sigma(phi_k e_b) n)_i for the neighbours k of sv.
Eigen::Matrix<Real, 3, Eigen::Dynamic> traction_operator(const mls::ShapeFunctionValues& sv,
                                                         const material::LinearElastic& material, const Vec3& n);

/// Penalty terms of one constraint point: K += alpha w N^T S N, f += alpha w N^T S u-bar (K: 3m x 3m and
/// f: 3m for the m neighbours of sv, sized and zeroed by the caller, so that the points of a boundary cell,
/// which share their neighbours, add up in one block).
void penalty_terms(const mls::ShapeFunctionValues& sv, const ConstraintPoint& p, Real alpha, Eigen::MatrixXd& K,
                   Eigen::VectorXd& f);

/// Nitsche terms of the surface points of a group that share their neighbours (a boundary cell face):
/// K += w (-N^T S T - T^T S N + beta N^T S N), f += w (-T^T S u-bar + beta N^T S u-bar) summed over the
/// points (K: 3m x 3m and f: 3m, sized and zeroed by the caller, as for penalty_terms), formed as
/// matrix products: K = sum over points and held components a of (n v^T + v n^T) with n = N_a^T and
/// v = -w T_a^T + (w beta / 2) n. nitsche_columns writes the point's n and v as columns of `n_columns`
/// and `v_columns` from `column` on (3m rows; at most 3 columns a point) and adds its f; it returns the
/// next free column. add_nitsche_products adds N V^T + V N^T over the first `columns` columns to K
/// (upper triangle only if upper_only): two matrix-matrix products instead of one rank-2 update of
/// the whole block per point and component.
Index nitsche_columns(const mls::ShapeFunctionValues& sv, const ConstraintPoint& p, const material::LinearElastic& material,
                      Real beta, Eigen::MatrixXd& n_columns, Eigen::MatrixXd& v_columns, Index column, Eigen::VectorXd& f);
void add_nitsche_products(const Eigen::MatrixXd& n_columns, const Eigen::MatrixXd& v_columns, Index columns,
                          Eigen::MatrixXd& K, bool upper_only);

}  // namespace lamina::efg
