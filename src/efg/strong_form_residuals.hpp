#pragma once
// Strong-form residuals of linear elastostatics at points (seed 004 eq 1-30), the rows of the
// collocation (section 1.2.2 (2)) and weighted least squares (section 1.2.2 (5), eq 1-35) EFG systems.
//
// With u^h(x) = sum_k phi_k(x) u_k (MLS, quadratic basis, second derivatives from
// mls_shape_functions.hpp) the three residuals of eq 1-30 are linear in the nodal parameters:
//   equilibrium   (div sigma(u^h) + b)_i = sum_k [ mu lap(phi_k) u_ki + (lambda + mu) phi_k,ib u_kb ] + b_i
//                 (Navier form: material homogeneous around the point)
//   traction      (sigma(u^h) n - t-bar)_i = sum_k T_i,kb(n) u_kb - t-bar_i   (T: traction_operator)
//   displacement  (u^h - u-bar)_i = sum_k phi_k u_ki - u-bar_i
// A row stores the coefficients of u_kb over the point's MLS neighbours (column 3 k + b) and the
// right-hand side (row . u = rhs when the residual vanishes).
//
// Which rows a point gets
//   Collocation (square system, 3 rows per node): for each component i,
//     constrained i                 -> displacement row
//     else on the boundary surface  -> traction row with the node's boundary normal: on a face the
//                                      face's outward normal; on an edge or corner, where several
//                                      faces meet, the normalised sum of their normals n-bar =
//                                      sum_f n_f / |sum_f n_f| with t-bar = sum_f t_f / |sum_f n_f|
//                                      (sigma n-bar = t-bar is the sum of the faces' conditions, so
//                                      an exact solution satisfies it)
//     else (interior)               -> equilibrium row.
//   Weighted least squares (eq 1-35, every condition that holds at the point, weighted later):
//     equilibrium rows (3) at every node and auxiliary point (boundary nodes included: the equation
//     holds on the closed domain), a traction row per boundary face of the node and unconstrained
//     component, a displacement row per constrained component.
#include <array>
#include <vector>

#include "material/linear_elastic.hpp"
#include "mls/mls_shape_functions.hpp"

namespace lamina::efg {

/// What holds at one node (or auxiliary point) in the strong form.
struct StrongFormPoint {
  Vec3 x = Vec3::Zero();
  int material = 0;
  Vec3 body_force = Vec3::Zero();                 // b (force per volume)
  std::array<bool, 3> constrained{false, false, false};
  Vec3 value = Vec3::Zero();                      // u-bar (constrained components)
  std::vector<Vec3> face_normals;                 // outward unit normals of the boundary faces at x (empty: interior)
  std::vector<Vec3> face_tractions;               // prescribed traction on each of those faces (zero: free)
  bool on_boundary() const { return !face_normals.empty(); }
};

enum class ResidualKind { equilibrium, traction, displacement };

/// The residual rows of one point over its MLS neighbours.
struct PointResiduals {
  IndexList neighbours;             // columns 3 k + b follow these nodes
  Eigen::MatrixXd rows;             // r x 3m
  Eigen::VectorXd rhs;              // r
  std::vector<ResidualKind> kinds;  // r
};

/// Navier operator: N(i, 3k + b) = mu lap(phi_k) delta_ib + (lambda + mu) phi_k,ib (needs second derivatives).
Eigen::Matrix<Real, 3, Eigen::Dynamic> navier_operator(const mls::ShapeFunctionValues& sv,
                                                       const material::LinearElastic& material);

/// Normal and traction used by collocation on the boundary (n-bar, t-bar of the header comment).
/// Throws AnalysisError if the face normals cancel (a node on two opposite faces).
std::pair<Vec3, Vec3> collocation_boundary_condition(const StrongFormPoint& p);

/// Exactly three rows (one per component) for the square collocation system.
PointResiduals collocation_residuals(const StrongFormPoint& p, const mls::ShapeFunctionValues& sv,
                                     const material::LinearElastic& material);

/// All rows of the weighted least squares functional at the point.
PointResiduals least_squares_residuals(const StrongFormPoint& p, const mls::ShapeFunctionValues& sv,
                                       const material::LinearElastic& material);

/// Throws AnalysisError if the displacement conditions of the points leave a rigid-body motion
/// free. The MLS approximation reproduces linear fields, so a rigid motion m makes every
/// equilibrium and traction residual vanish and changes a constrained u_i by m_i(x): the motions
/// are fixed iff the 6 x 6 Gram matrix sum_(points, constrained i) m_k,i(x) m_l,i(x) is regular.
void require_no_free_rigid_body_motion(const std::vector<StrongFormPoint>& points);

}  // namespace lamina::efg
