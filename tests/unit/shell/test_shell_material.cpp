// Shell materials at one through-thickness point: the neo-Hookean plane-stress model against its closed
// form (principal stretches, lambda_3 from sigma_zz = 0) and against linear elasticity at small strain;
// J2 plane-stress plasticity against equibiaxial and pure-shear closed forms, consistency and unloading.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <vector>

#include "material/j2_plasticity.hpp"
#include "material/shell_material.hpp"

namespace lamina::shell {
namespace {

constexpr Real kE = 2.0e5, kNu = 0.3, kRho = 7.8e-3;

/// Closed-form neo-Hookean plane-stress Cauchy stresses for the in-plane principal stretches l1, l2:
/// lambda_3 by bisection on tau_zz = mu (l3^2 - 1) + lambda ln(l1 l2 l3) = 0 (independent of the Newton solve).
struct PrincipalState {
  Real s1, s2, log_l3;
};
PrincipalState closed_form(Real l1, Real l2) {
  const Real mu = kE / (2 * (1 + kNu)), lambda = kE * kNu / ((1 + kNu) * (1 - 2 * kNu));
  auto tau_zz = [&](Real l3) { return mu * (l3 * l3 - 1) + lambda * std::log(l1 * l2 * l3); };
  Real lo = 1e-3, hi = 10.0;
  for (int i = 0; i < 200; ++i) {
    const Real mid = 0.5 * (lo + hi);
    (tau_zz(mid) > 0 ? hi : lo) = mid;
  }
  const Real l3 = 0.5 * (lo + hi), J = l1 * l2 * l3;
  return {(mu * (l1 * l1 - 1) + lambda * std::log(J)) / J, (mu * (l2 * l2 - 1) + lambda * std::log(J)) / J, std::log(l3)};
}

/// Drive one point with a constant rate for n steps; returns the point data and the integrated d_zz.
std::vector<Real> drive(const material::ShellMaterial& m, const Real rate[5], Real total_time, int steps, Real& log_thickness) {
  std::vector<Real> point(static_cast<std::size_t>(material::kStressComponents + m.state_size()), 0.0);
  log_thickness = 0.0;
  const Real dt = total_time / steps;
  for (int k = 0; k < steps; ++k) log_thickness += dt * m.update(point.data(), rate, dt);
  return point;
}

TEST(shell_NeoHookean, UniaxialInPlaneStretchMatchesClosedForm) {
  const material::NeoHookeanShellMaterial m(kE, kNu, kRho);
  EXPECT_EQ(m.state_size(), 4);
  for (Real stretch : {1.5, 0.7}) {
    const Real rate[5] = {std::log(stretch), 0, 0, 0, 0};  // over unit time: H_xx = ln(stretch)
    Real log_thickness = 0;
    const auto p = drive(m, rate, 1.0, 400, log_thickness);
    const PrincipalState exact = closed_form(stretch, 1.0);
    EXPECT_NEAR(p[0] / exact.s1, 1.0, 1e-10) << stretch;
    EXPECT_NEAR(p[1] / exact.s2, 1.0, 1e-10) << stretch;
    EXPECT_NEAR(p[2], 0.0, 1e-9 * std::abs(exact.s1));
    EXPECT_NEAR(log_thickness, exact.log_l3, 1e-12) << "integrated d_zz is ln lambda_3";
  }
}

TEST(shell_NeoHookean, RotatedPrincipalAxesMatchClosedForm) {
  const material::NeoHookeanShellMaterial m(kE, kNu, kRho);
  const Real hxx = 0.3, hyy = -0.1, hxy = 0.2;  // logarithmic strain reached at t = 1
  const Real rate[5] = {hxx, hyy, 2 * hxy, 0, 0};
  Real log_thickness = 0;
  const auto p = drive(m, rate, 1.0, 100, log_thickness);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig((Eigen::Matrix2d() << hxx, hxy, hxy, hyy).finished());
  const PrincipalState exact = closed_form(std::exp(eig.eigenvalues()[0]), std::exp(eig.eigenvalues()[1]));
  const Eigen::Matrix2d sigma = eig.eigenvectors() * Eigen::Vector2d(exact.s1, exact.s2).asDiagonal() * eig.eigenvectors().transpose();
  const Real scale = sigma.norm();
  EXPECT_NEAR(p[0], sigma(0, 0), 1e-10 * scale);
  EXPECT_NEAR(p[1], sigma(1, 1), 1e-10 * scale);
  EXPECT_NEAR(p[2], sigma(0, 1), 1e-10 * scale);
  EXPECT_NEAR(log_thickness, exact.log_l3, 1e-12);
}

TEST(shell_NeoHookean, SmallStrainIsLinearElastic) {
  const material::NeoHookeanShellMaterial hyper(kE, kNu, kRho);
  const material::LinearElasticShellMaterial linear(kE, kNu, kRho);
  const Real rate[5] = {1e-6, -4e-7, 6e-7, 3e-7, -2e-7};
  Real t_hyper = 0, t_linear = 0;
  const auto a = drive(hyper, rate, 1.0, 10, t_hyper);
  const auto b = drive(linear, rate, 1.0, 10, t_linear);
  for (int c = 0; c < material::kStressComponents; ++c) EXPECT_NEAR(a[c], b[c], 1e-5 * std::abs(b[0])) << c;
  EXPECT_NEAR(t_hyper / t_linear, 1.0, 1e-5);
}

TEST(shell_NeoHookean, UnloadingReturnsToZeroStress) {
  // hyperelastic: the stress depends on the current strain only, not on the path
  const material::NeoHookeanShellMaterial m(kE, kNu, kRho);
  std::vector<Real> point(static_cast<std::size_t>(material::kStressComponents + m.state_size()), 0.0);
  const Real out[5] = {0.4, 0.1, 0.3, 0, 0}, back[5] = {-0.4, -0.1, -0.3, 0, 0};
  for (int k = 0; k < 50; ++k) m.update(point.data(), out, 0.02);
  EXPECT_GT(std::abs(point[0]), 1e3);
  for (int k = 0; k < 50; ++k) m.update(point.data(), back, 0.02);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(point[c], 0.0, 1e-6) << c;
  EXPECT_NEAR(point[material::kStressComponents + 3], 0.0, 1e-12);  // ln lambda_3 back to zero
}

// J2 plane-stress plasticity (Simo-Hughes return). Proportional paths with linear hardening are
// integrated exactly by the backward-Euler return, so they are compared with closed forms tightly.
constexpr Real kYield = 250.0, kHardening = 2.0e3;

Real von_mises(const std::vector<Real>& s) { return std::sqrt(s[0] * s[0] - s[0] * s[1] + s[1] * s[1] + 3 * s[2] * s[2]); }

TEST(shell_J2Plasticity, EquibiaxialStretchMatchesClosedForm) {
  // sigma_xx = sigma_yy = sigma: eps = sigma (1 - nu) / E + eps_p / 2, sigma = yield + H eps_p,
  // thickness strain -2 nu sigma / E - eps_p (plastic incompressibility)
  const material::J2PlasticShellMaterial m(kE, kNu, kRho, kYield, kHardening);
  const Real rate[5] = {1, 1, 0, 0, 0};
  for (const Real eps : {0.5e-3, 5e-3, 2e-2}) {
    for (const int steps : {1, 7, 100}) {
      Real thickness = 0.0;
      const auto p = drive(m, rate, eps, steps, thickness);
      const Real elastic = kE / (1 - kNu) * eps;
      const Real sigma = elastic <= kYield ? elastic : (kYield + 2 * kHardening * eps) / (1 + 2 * kHardening * (1 - kNu) / kE);
      const Real eps_p = elastic <= kYield ? 0.0 : (sigma - kYield) / kHardening;
      EXPECT_NEAR(p[0], sigma, 1e-10 * sigma) << eps << " " << steps;
      EXPECT_NEAR(p[1], sigma, 1e-10 * sigma);
      EXPECT_NEAR(p[material::kStressComponents], eps_p, 1e-12 + 1e-10 * eps_p);
      EXPECT_NEAR(thickness, -2 * kNu * sigma / kE - eps_p, 1e-12 + 1e-10 * eps);
    }
  }
}

TEST(shell_J2Plasticity, PowerLawHardeningEquibiaxialMatchesClosedForm) {
  // sigma_y = yield + H eps_p^n: equibiaxial eps = sigma (1 - nu) / E + eps_p / 2 with sigma = sigma_y(eps_p),
  // solved here for eps_p by bisection; thickness strain -2 nu sigma / E - eps_p
  for (const Real n : {0.5, 0.2}) {
    const material::J2PlasticShellMaterial m(kE, kNu, kRho, kYield, 10 * kHardening, n);
    EXPECT_EQ(m.hardening_exponent(), n);
    const Real rate[5] = {1, 1, 0, 0, 0};
    for (const Real eps : {5e-3, 2e-2}) {
      Real lo = 0.0, hi = 2.0 * eps;
      for (int k = 0; k < 200; ++k) {
        const Real mid = 0.5 * (lo + hi);
        const Real f = (kYield + 10 * kHardening * std::pow(mid, n)) * (1 - kNu) / kE + 0.5 * mid - eps;
        (f > 0 ? hi : lo) = mid;
      }
      const Real eps_p = 0.5 * (lo + hi), sigma = kYield + 10 * kHardening * std::pow(eps_p, n);
      for (const int steps : {1, 50}) {
        Real thickness = 0.0;
        const auto p = drive(m, rate, eps, steps, thickness);
        EXPECT_NEAR(p[0], sigma, 1e-9 * sigma) << n << " " << eps << " " << steps;
        EXPECT_NEAR(p[1], sigma, 1e-9 * sigma);
        EXPECT_NEAR(p[material::kStressComponents], eps_p, 1e-9 * eps_p);
        EXPECT_NEAR(thickness, -2 * kNu * sigma / kE - eps_p, 1e-9 * eps);
      }
    }
  }
}

TEST(shell_J2Plasticity, ExponentOneIsLinearHardening) {
  const material::J2PlasticShellMaterial linear(kE, kNu, kRho, kYield, kHardening), power(kE, kNu, kRho, kYield, kHardening, 1.0);
  const Real rate[5] = {1, -0.3, 0.4, 0, 0};
  Real t1 = 0.0, t2 = 0.0;
  EXPECT_EQ(drive(linear, rate, 2e-2, 9, t1), drive(power, rate, 2e-2, 9, t2));
  for (const Real e : {0.0, 1e-3, 0.1}) EXPECT_EQ(power.flow_stress(e), kYield + kHardening * e);
}

TEST(shell_J2Plasticity, PureShearMatchesClosedForm) {
  // tau = (yield + H eps_p) / sqrt3, gamma = tau / G + sqrt3 eps_p; no thickness change
  const material::J2PlasticShellMaterial m(kE, kNu, kRho, kYield, kHardening);
  const Real g = kE / (2 * (1 + kNu)), rate[5] = {0, 0, 1, 0, 0};
  for (const Real gamma : {1e-3, 1e-2, 5e-2}) {
    Real thickness = 0.0;
    const auto p = drive(m, rate, gamma, 13, thickness);
    const Real tau = g * gamma <= kYield / std::sqrt(3.0) ? g * gamma
                                                           : (gamma + std::sqrt(3.0) * kYield / kHardening) / (1 / g + 3 / kHardening);
    EXPECT_NEAR(p[2], tau, 1e-10 * tau) << gamma;
    EXPECT_NEAR(p[0], 0.0, 1e-9);
    EXPECT_NEAR(p[1], 0.0, 1e-9);
    EXPECT_NEAR(thickness, 0.0, 1e-12);
  }
}

TEST(shell_J2Plasticity, StressStaysOnTheYieldSurfaceAndUnloadsElastically) {
  for (const Real hardening : {0.0, kHardening}) {
    const material::J2PlasticShellMaterial m(kE, kNu, kRho, kYield, hardening);
    std::vector<Real> p(static_cast<std::size_t>(material::kStressComponents + m.state_size()), 0.0);
    Real previous_eps_p = 0.0;
    for (int k = 0; k < 400; ++k) {  // a non-proportional path: rotating in-plane strain rate
      const Real angle = 0.05 * k;
      const Real rate[5] = {std::cos(angle), 0.5 * std::sin(1.3 * angle), 0.8 * std::sin(angle), 0.1, -0.1};
      m.update(p.data(), rate, 2e-4);
      const Real eps_p = p[material::kStressComponents], limit = kYield + hardening * eps_p;
      EXPECT_LE(von_mises(p), limit * (1 + 1e-12)) << k;
      if (eps_p > previous_eps_p) {
        EXPECT_NEAR(von_mises(p), limit, 1e-10 * limit) << k;
      }
      EXPECT_GE(eps_p, previous_eps_p);
      previous_eps_p = eps_p;
    }
    EXPECT_GT(previous_eps_p, 1e-3);  // the path went well into the plastic range
    // unloading: the strain increment -0.01 C^-1 sigma scales the in-plane stress by 0.99 (elastic)
    const std::vector<Real> before = p;
    const Real g = kE / (2 * (1 + kNu));
    const Real back[5] = {-0.01 * (before[0] - kNu * before[1]) / kE, -0.01 * (before[1] - kNu * before[0]) / kE,
                          -0.01 * before[2] / g, 0, 0};
    m.update(p.data(), back, 1.0);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(p[c], 0.99 * before[c], 1e-12 * kYield) << c;
    EXPECT_EQ(p[material::kStressComponents], before[material::kStressComponents]);
  }
}

TEST(shell_J2Plasticity, BelowYieldEqualsLinearElastic) {
  const material::J2PlasticShellMaterial plastic(kE, kNu, kRho, kYield, kHardening);
  const material::LinearElasticShellMaterial linear(kE, kNu, kRho);
  const Real rate[5] = {3e-4, -1e-4, 2e-4, 1e-4, -2e-4};
  Real t_plastic = 0.0, t_linear = 0.0;
  const auto a = drive(plastic, rate, 1.0, 10, t_plastic);
  const auto b = drive(linear, rate, 1.0, 10, t_linear);
  for (int c = 0; c < material::kStressComponents; ++c) EXPECT_NEAR(a[c], b[c], 1e-12 * kE) << c;
  EXPECT_NEAR(t_plastic, t_linear, 1e-15);
  EXPECT_EQ(a[material::kStressComponents], 0.0);
}

}  // namespace
}  // namespace lamina::shell
