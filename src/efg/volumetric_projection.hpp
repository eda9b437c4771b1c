#pragma once
// Projected volumetric term (B-bar with an averaged nodal pressure) for nearly incompressible
// Galerkin EFG: lambda div u div v is replaced by lambda (P div u)(P div v), with P the projection of
// the divergence onto a pressure space spanned by non-negative partition-of-unity functions psi_I
// (Shepard functions of the pressure nodes' small supports), using the row-sum (lumped) Gram matrix:
//   theta_I = (G u)_I / M_I,   G_I = sum_q w_q psi_I(x_q) div N(x_q),   M_I = sum_q w_q psi_I(x_q) > 0,
//   K_lambda = G^T diag(lambda_I / M_I) G,   lambda_I = sum_q w_q psi_I(x_q) lambda(x_q) / M_I,
// and the pressure is p(x) = sum_I psi_I(x) lambda_I theta_I. The mu part stays on the full rule.
// B-bar: Hughes, IJNME 15 (1980) 1413; nodal averaging: Bonet & Burton, CNME 14 (1998) 437. With the
// pressure nodes at every other displacement node (the vertices of Taylor-Hood Q2/Q1 elements) there
// are about 1/24 as many constraints as displacement dofs, and the pressure still varies through a
// plate's thickness, so bending's linear-in-z div u is constrained. Shepard functions rather than a
// linear MLS: they stay non-negative on curved bodies and near boundaries, so K_lambda is positive
// semi-definite for any node layout (a linear MLS gave a negative M_I on a tube).
#include <vector>

#include "efg/background_quadrature.hpp"
#include "mls/mls_shape_functions.hpp"
#include "mls/weight_function.hpp"
#include "solve/block_pattern.hpp"

namespace lamina::efg {

/// Shepard pressure functions psi_I(x) = w_I(x) / sum_J w_J(x) over the pressure nodes in reach of x
/// (the node-centred box or sphere supports of `nodes`, mode kappa): non-negative and a partition of
/// unity wherever a pressure node is in reach, so every lumped integral M_I is positive.
class ShepardPressure {
 public:
  explicit ShepardPressure(const mls::MlsShapeFunctions& nodes) : nodes_(nodes), weight_(nodes.options().weight, nodes.options().gauss_beta) {}
  /// Values at x in out.phi over out.neighbours; false if no pressure node is in reach.
  bool evaluate(const Vec3& x, mls::ShapeFunctionValues& out) const;
  const mls::MlsShapeFunctions& nodes() const { return nodes_; }

 private:
  const mls::MlsShapeFunctions& nodes_;
  mls::WeightFunction weight_;
};

struct ProjectedVolumetric {
  std::vector<IndexList> nodes;              // per pressure node I: the displacement nodes of G_I (sorted)
  std::vector<Eigen::Matrix3Xd> divergence;  // per pressure node I: G_I, 3 x nodes[I].size() (dof 3 j + a)
  Eigen::VectorXd lumped;                    // M_I
  Eigen::VectorXd lambda;                    // lambda_I

  Index pressure_nodes() const { return lumped.size(); }
  /// Nodal projected divergence theta_I = (G u)_I / M_I (u: 3N interleaved).
  Eigen::VectorXd nodal_divergence(const Eigen::VectorXd& u) const;
  /// Adds K_lambda to `values` of a symmetric 3-dof block pattern built with `nodes` among its
  /// groups (every pair of nodes of one G_I must be in the pattern). Parallel over columns.
  void add_stiffness(const solve::BlockPattern& pattern, Real* values) const;
};

/// Builds G, M and lambda_I on the quadrature `volume` (normally the full rule) with the displacement
/// shape functions `shapes` and the pressure functions `pressure`; lambda_at_point: lambda at each
/// quadrature point. Keeps the displacement shape function derivatives of all quadrature points in
/// memory while it runs. Throws InputError if a pressure function has no positive integral.
ProjectedVolumetric project_volumetric(const mls::MlsShapeFunctions& shapes, const ShepardPressure& pressure,
                                       const VolumeQuadrature& volume, const Eigen::VectorXd& lambda_at_point);

}  // namespace lamina::efg
