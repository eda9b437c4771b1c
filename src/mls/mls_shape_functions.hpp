#pragma once
// Moving least squares shape functions phi_I(x) and their first and second derivatives
// (seed 004, eqs 1-4..1-25: phi^T = p^T A^-1 B, eqs 1-18..1-21), over a fixed set of nodes.
#include <vector>

#include "core/types.hpp"
#include "mls/mls_options.hpp"
#include "mls/neighbour_search.hpp"
#include "mls/singular_moment_matrix.hpp"
#include "mls/weight_function.hpp"

namespace lamina::mls {

namespace detail {
struct MlsWorkspace;
}

/// Shape functions at one evaluation point. Columns follow `neighbours` (sorted ascending).
/// dphi has 3 rows (x y z) and n columns if derivative_order >= 1, else 0 columns; ddphi has 6 rows
/// (xx yy zz xy yz zx) and n columns if derivative_order >= 2, else 0 columns. Rows of unused
/// dimensions (dimension < 3) are zero.
struct ShapeFunctionValues {
  IndexList neighbours;
  Eigen::VectorXd phi;
  Eigen::Matrix3Xd dphi;
  Eigen::Matrix<Real, 6, Eigen::Dynamic> ddphi;
  Real condition = 0.0;    // estimated condition number of the Jacobi-scaled moment matrix
  int remedy_steps = 0;    // SINCHECK steps taken (0 unless options.singular_remedy)
};

/// An approximated scalar field at a point: u^h, grad u^h, Hessian of u^h (zero if not requested).
struct FieldValue {
  Real value = 0.0;
  Vec3 gradient = Vec3::Zero();
  Mat3 hessian = Mat3::Zero();
};

/// u^h(x) = sum_I phi_I(x) u_I from shape functions already evaluated at x.
FieldValue approximate_field(const ShapeFunctionValues& shape, const Eigen::Ref<const Eigen::VectorXd>& nodal_values);

/// MLS shape functions of a node set.
///
/// Method: at an evaluation point x the basis is shifted to x and scaled by the support size rho:
/// p((y - x) / rho), centre x held fixed while differentiating in y (the MLS approximant does not
/// depend on the centre of a complete polynomial basis). Then p(x) = [1, 0, ...], A_,i = sum w_I,i p_I p_I^T,
/// B_,i = [w_I,i p_I], and eqs 1-18..1-21 give, with A r = p:
///   phi_I = w_I p_I.r,   phi_I,i = w_I,i p_I.r + w_I p_I.r_,i,   r_,i = A^-1 (p_,i - A_,i r),
///   phi_I,ij = w_I,ij p_I.r + w_I,i p_I.r_,j + w_I,j p_I.r_,i + w_I p_I.r_,ij,
///   r_,ij = A^-1 (p_,ij - A_,i r_,j - A_,j r_,i - A_,ij r),
/// where the products A_,i v = sum_I w_I,i (p_I.v) p_I are formed without building A_,i.
/// In the point-centred mode (variable) the radius R(x) is frozen at x while differentiating:
/// the derivatives are those of the MLS approximant with that radius (R(x) is only piecewise smooth).
///
/// Evaluation is thread-safe: scratch memory is thread-local, nothing shared is modified.
class MlsShapeFunctions {
 public:
  /// nodes: 3 x N. spacing: 3 x N local nodal spacing for mode kappa (empty => estimate_nodal_spacing).
  /// Throws lamina::InputError on invalid options, nodes or spacing.
  MlsShapeFunctions(PointMatrix nodes, MlsOptions options, Eigen::Matrix3Xd spacing = {});

  /// Shape functions at x with derivatives up to derivative_order (0, 1 or 2).
  /// Throws SingularMomentMatrix if A(x) is singular or its condition exceeds options.max_condition
  /// (after the SINCHECK remedy if enabled, or if grow_if_singular asks for it at this point);
  /// std::invalid_argument for another derivative_order.
  void evaluate(const Vec3& x, int derivative_order, ShapeFunctionValues& out, bool grow_if_singular = false) const;
  ShapeFunctionValues evaluate(const Vec3& x, int derivative_order) const;

  /// The sorted neighbour list evaluate() would return at x, without the shape functions (a support
  /// search only; with the singular remedy enabled a full evaluation, since the remedy may widen the
  /// support). Does not check the moment matrix.
  void neighbours(const Vec3& x, IndexList& out, bool grow_if_singular = false) const;

  /// evaluate() at every column of points, in parallel (OpenMP), results in the order of the points.
  /// Deterministic; if points fail, the error of the lowest failing column is rethrown.
  std::vector<ShapeFunctionValues> evaluate_all(const PointMatrix& points, int derivative_order,
                                                bool grow_if_singular = false) const;

  /// Convenience: u^h, grad u^h and (derivative_order 2) the Hessian of a nodal field (N values) at x.
  FieldValue approximate(const Vec3& x, const Eigen::Ref<const Eigen::VectorXd>& nodal_values,
                         int derivative_order = 1) const;

  const PointMatrix& nodes() const { return nodes_; }
  Index node_count() const { return nodes_.cols(); }
  const MlsOptions& options() const { return options_; }
  /// Number of basis terms m.
  int basis_size() const { return basis_size_; }
  /// Local nodal spacing h (3 x N; given or estimated in mode kappa; empty in the other modes).
  const Eigen::Matrix3Xd& nodal_spacing() const { return spacing_; }
  /// Support radii of the nodes (3 x N) in the node-centred modes kappa, fixed_radius and all,
  /// including the (1 + support_epsilon) factor; empty in the point-centred modes.
  const Eigen::Matrix3Xd& support_radii() const { return radii_; }
  const CellList& cell_list() const { return cells_; }

 private:
  /// Enriched: the basis gets the interface term (MlsOptions::interface_enrichment); returns false,
  /// leaving `out` unspecified, where the support does not hold nodes on both sides of the interface or
  /// the enriched moment matrix is ill-conditioned (the caller then uses the polynomial basis).
  /// The kernel for the options' basis in Dim dimensions, enriched first if `enrich`.
  template <int Dim>
  void evaluate_dimension(const Vec3& x, int derivative_order, bool enrich, bool remedy, ShapeFunctionValues& out) const;
  template <int Dim, Basis B, bool Enriched>
  bool evaluate_kernel(const Vec3& x, int derivative_order, bool remedy, ShapeFunctionValues& out) const;
  bool node_centred() const;
  /// Fills workspace.indices (sorted), .offsets (x - x_I) and .inverse_radii of the neighbours of x
  /// (x already projected), radii multiplied by radius_factor, N = nearest_count; sets rho (basis scale).
  template <int Dim>
  Index gather(const Vec3& x, Real radius_factor, Index nearest_count, detail::MlsWorkspace& workspace,
               Vec3& rho) const;
  [[noreturn]] void throw_singular(const Vec3& x, Index neighbours, Real condition, bool remedy) const;

  PointMatrix nodes_;             // as given
  PointMatrix projected_;         // unused dimensions zeroed
  MlsOptions options_;
  WeightFunction weight_function_;  // options_.weight with options_.gauss_beta
  int basis_size_ = 0;
  Eigen::Matrix3Xd spacing_;
  Eigen::Matrix3Xd radii_;        // node-centred modes: per node and axis (original order)
  Eigen::Matrix3Xd sorted_inverse_radii_;  // 1 / radii_ in the cell list's order (unused axes: 0)
  /// Node-centred modes: the same points and inverse radii as six rows (x y z 1/Rx 1/Ry 1/Rz) of
  /// node_count() + 4 values in the cell list's order, so that the support test runs four nodes at a
  /// time over each row of cells.
  std::vector<Real> sorted_rows_;
  std::vector<Index> sorted_order_;  // node-centred modes: cells_.order() and 4 padding entries
  std::vector<Index> position_of_node_;  // node-centred modes: the inverse of cells_.order()
  std::size_t row_stride_ = 0;
  Vec3 max_radius_ = Vec3::Zero();
  /// Point-centred modes: 1 / (mean nodal spacing) per axis; distances for "the N nearest" and the
  /// support radius are measured in these units (a regular lattice of any aspect is then a unit cube
  /// lattice). Zero on unused axes; unused in the node-centred modes.
  Vec3 metric_ = Vec3::Ones();
  PointMatrix metric_points_;     // point-centred modes: metric_ * projected_ (the cell list's points)
  CellList cells_;
};

}  // namespace lamina::mls
