#include "material/hyperelastic.hpp"

#include <cmath>

namespace lamina::material {

namespace {

int id3(int i, int j) { return 3 * i + j; }

}  // namespace

HyperelasticResponse3 hyperelastic_response(const Hyperelastic& m, const Mat3& F) {
  HyperelasticResponse3 r;
  r.tangent.setZero();
  const Real mu = m.mu, lambda = m.lambda;
  if (m.kind == HyperelasticKind::neo_hookean) {
    const Real J = F.determinant();
    if (!(J > 0)) {
      r.valid = false;
      r.energy = INFINITY;
      r.stress.setZero();
      return r;
    }
    const Real lnJ = std::log(J);
    const Mat3 Fi = F.inverse();  // Fi(J, i) = F^-1_Ji
    r.energy = 0.5 * mu * ((F.transpose() * F).trace() - 3 - 2 * lnJ) + 0.5 * lambda * lnJ * lnJ;
    r.stress = mu * (F - Fi.transpose()) + lambda * lnJ * Fi.transpose();
    for (int i = 0; i < 3; ++i)
      for (int J_ = 0; J_ < 3; ++J_)
        for (int k = 0; k < 3; ++k)
          for (int L = 0; L < 3; ++L)
            r.tangent(id3(i, J_), id3(k, L)) = (i == k && J_ == L ? mu : 0.0) +
                                               (mu - lambda * lnJ) * Fi(L, i) * Fi(J_, k) +
                                               lambda * Fi(J_, i) * Fi(L, k);
  } else {
    const Mat3 E = 0.5 * (F.transpose() * F - Mat3::Identity());
    const Mat3 S = lambda * E.trace() * Mat3::Identity() + 2 * mu * E;
    r.energy = 0.5 * lambda * E.trace() * E.trace() + mu * (E.array() * E.array()).sum();
    r.stress = F * S;
    for (int i = 0; i < 3; ++i)
      for (int J_ = 0; J_ < 3; ++J_)
        for (int k = 0; k < 3; ++k)
          for (int L = 0; L < 3; ++L) {
            // F_iM C_MJNL F_kN with C = lambda d_MJ d_NL + mu (d_MN d_JL + d_ML d_JN)
            Real a = (i == k ? S(J_, L) : 0.0) + lambda * F(i, J_) * F(k, L) + mu * F(i, L) * F(k, J_);
            if (J_ == L) a += mu * F.row(i).dot(F.row(k));
            r.tangent(id3(i, J_), id3(k, L)) = a;
          }
  }
  return r;
}

HyperelasticResponse2 hyperelastic_response_2d(const Hyperelastic& m, const Eigen::Matrix2d& F2, bool plane_stress) {
  HyperelasticResponse2 r;
  Mat3 F = Mat3::Identity();
  F.topLeftCorner<2, 2>() = F2;
  HyperelasticResponse3 full = hyperelastic_response(m, F);
  if (plane_stress && full.valid) {
    // P_33(F_33) = 0: Newton, monotone for both models in the admissible range
    for (int iteration = 0; iteration < 50; ++iteration) {
      const Real p33 = full.stress(2, 2), a33 = full.tangent(8, 8);
      if (std::abs(p33) <= 1e-13 * (m.mu + std::abs(m.lambda)) || !(a33 > 0)) break;
      Real step = p33 / a33;
      while (F(2, 2) - step <= 0) step *= 0.5;
      F(2, 2) -= step;
      full = hyperelastic_response(m, F);
      if (!full.valid) break;
    }
  }
  r.valid = full.valid;
  r.energy = full.energy;
  r.stretch33 = F(2, 2);
  r.stress33 = full.valid ? full.stress(2, 2) : 0.0;
  if (!full.valid) {
    r.stress.setZero();
    r.tangent.setZero();
    return r;
  }
  r.stress = full.stress.topLeftCorner<2, 2>();
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b) r.tangent(a, b) = full.tangent(id3(a / 2, a % 2), id3(b / 2, b % 2));
  if (plane_stress) {
    const Real a33 = full.tangent(8, 8);
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b)
        r.tangent(a, b) -= full.tangent(id3(a / 2, a % 2), 8) * full.tangent(8, id3(b / 2, b % 2)) / a33;
  }
  return r;
}

Mat3 cauchy_stress(const Mat3& P, const Mat3& F) { return P * F.transpose() / F.determinant(); }

}  // namespace lamina::material
