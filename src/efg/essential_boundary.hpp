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
#include <vector>

#include "material/linear_elastic.hpp"
#include "mls/mls_shape_functions.hpp"
#include "solve/block_pattern.hpp"

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

/// Nitsche terms of the surface points of a group that share their m neighbours (a boundary cell face):
/// K += w (-N^T S T - T^T S N + beta N^T S N), f += w (-T^T S u-bar + beta N^T S u-bar) summed over the
/// points. K is the sum over points and held components a of n v^T + v n^T with n = N_a^T (phi_k in the
/// rows 3k + a, zero in the others) and v = -w T_a^T + (w beta / 2) n. The columns are kept by
/// component: phi[a] holds the points' phi (m values each), v[a] their v (3m values each). Then
/// (N V^T)(3I + a, j) = P_a(I, j) with P_a = phi_a v_a^T (m x 3m), and V N^T is its transpose: three
/// m x P_a by P_a x 3m products (P_a points holding a) instead of two 3m x 3P by 3P x 3m products whose
/// n columns are two thirds zeros, and no dense 3m x 3m block to clear, fill and read back.
struct NitscheColumns {
  std::array<Eigen::MatrixXd, 3> phi;  // m x count[a]
  std::array<Eigen::MatrixXd, 3> v;    // 3m x count[a]
  std::array<Index, 3> count{0, 0, 0};
  Eigen::MatrixXd products;            // workspace: P_0 P_1 P_2 side by side (m x 9m)
  std::vector<int> rank_of;            // workspace of scatter_nitsche_products (one per node)
  /// No columns, room for `points` points over m nodes (allocates only when larger than before).
  void reset(Index m, Index points);
  Index nodes() const { return phi[0].rows(); }
  /// Forms `products`: P_a(I, j) at products(I, 3m a + j).
  void form_products();
};

/// Adds one surface point's columns (one per held component) to `columns` and its load terms to f (3m).
void nitsche_columns(const mls::ShapeFunctionValues& sv, const ConstraintPoint& p, const material::LinearElastic& material,
                     Real beta, NitscheColumns& columns, Eigen::VectorXd& f);
/// K += N V^T + V N^T into a dense 3m x 3m block (for groups that also hold penalty terms).
void add_nitsche_products(NitscheColumns& columns, Eigen::MatrixXd& K);
/// The same added straight into the values of a global matrix with `pattern`, over the group's nodes
/// (sorted ascending, every pair of them in the pattern) at values[index - offset]. Symmetric patterns take
/// the upper triangle.
void scatter_nitsche_products(NitscheColumns& columns, const solve::BlockPattern& pattern, const IndexList& nodes,
                              Real* values, Index offset = 0);

}  // namespace lamina::efg
