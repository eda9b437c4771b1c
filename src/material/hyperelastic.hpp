#pragma once
// Isotropic hyperelastic stress and consistent tangent over plain arguments (no files, no case keys):
// stored energy W(F), first Piola-Kirchhoff stress P = dW/dF and the tangent A = dP/dF (material and
// geometric parts together), in 3D and in plane strain / plane stress (docs/mpfem.md section 9).
//   neo_hookean (compressible; Ciarlet 1988 / Simo & Pister 1984 form):
//     W = mu/2 (I1 - 3 - 2 ln J) + lambda/2 (ln J)^2,   P = mu (F - F^-T) + lambda ln J F^-T,
//     A_iJkL = mu d_ik d_JL + (mu - lambda ln J) F^-1_Li F^-1_Jk + lambda F^-1_Ji F^-1_Lk.
//   saint_venant_kirchhoff (the geometrically nonlinear extension of linear elasticity):
//     E = (F^T F - I)/2, S = lambda tr(E) I + 2 mu E, P = F S, A_iJkL = d_ik S_JL + F_iM C_MJNL F_kN.
//   Both reduce to linear elasticity with the same lambda, mu for small strains.
// Plane strain: F_33 = 1. Plane stress: F_33 from P_33 = 0 (local Newton), tangent by static
// condensation A_ab - A_a,33 A_33,b / A_33,33 (exact consistent tangent of the condensed energy).
// 2D index of a gradient component (i, J): 2 i + J; 3D: 3 i + J.
#include <Eigen/Dense>

#include "core/types.hpp"
#include "material/linear_elastic.hpp"

namespace lamina::material {

enum class HyperelasticKind { neo_hookean, saint_venant_kirchhoff };

struct Hyperelastic {
  HyperelasticKind kind = HyperelasticKind::neo_hookean;
  Real mu = 0.0;
  Real lambda = 0.0;
  /// Moduli from E and nu (LinearElastic::mu / lambda: one place for the conversion).
  static Hyperelastic from(HyperelasticKind kind, const LinearElastic& elastic) {
    return Hyperelastic{kind, elastic.mu(), elastic.lambda()};
  }
};

struct HyperelasticResponse3 {
  Real energy = 0;             // W per unit reference volume
  Mat3 stress;                 // P
  Eigen::Matrix<Real, 9, 9> tangent;  // A(3 i + J, 3 k + L)
  bool valid = true;           // false if J <= 0 (neo-Hookean undefined)
};

struct HyperelasticResponse2 {
  Real energy = 0;
  Eigen::Matrix2d stress;               // in-plane P
  Eigen::Matrix4d tangent;              // A(2 i + J, 2 k + L)
  Real stretch33 = 1;                   // F_33 (plane stress: from P_33 = 0)
  Real stress33 = 0;                    // P_33 (plane strain: the out-of-plane stress)
  bool valid = true;
};

HyperelasticResponse3 hyperelastic_response(const Hyperelastic& m, const Mat3& F);

/// plane_stress: F_33 from P_33 = 0 (Newton to 1e-12); plane strain: F_33 = 1.
HyperelasticResponse2 hyperelastic_response_2d(const Hyperelastic& m, const Eigen::Matrix2d& F, bool plane_stress);

/// Cauchy stress sigma = P F^T / J (3D).
Mat3 cauchy_stress(const Mat3& P, const Mat3& F);

}  // namespace lamina::material
