// Shell materials at one through-thickness point: the neo-Hookean plane-stress model against its closed
// form (principal stretches, lambda_3 from sigma_zz = 0) and against linear elasticity at small strain.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <vector>

#include "shell/shell_material.hpp"

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
std::vector<Real> drive(const ShellMaterial& m, const Real rate[5], Real total_time, int steps, Real& log_thickness) {
  std::vector<Real> point(static_cast<std::size_t>(kStressComponents + m.state_size()), 0.0);
  log_thickness = 0.0;
  const Real dt = total_time / steps;
  for (int k = 0; k < steps; ++k) log_thickness += dt * m.update(point.data(), rate, dt);
  return point;
}

TEST(shell_NeoHookean, UniaxialInPlaneStretchMatchesClosedForm) {
  const NeoHookeanShellMaterial m(kE, kNu, kRho);
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
  const NeoHookeanShellMaterial m(kE, kNu, kRho);
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
  const NeoHookeanShellMaterial hyper(kE, kNu, kRho);
  const LinearElasticShellMaterial linear(kE, kNu, kRho);
  const Real rate[5] = {1e-6, -4e-7, 6e-7, 3e-7, -2e-7};
  Real t_hyper = 0, t_linear = 0;
  const auto a = drive(hyper, rate, 1.0, 10, t_hyper);
  const auto b = drive(linear, rate, 1.0, 10, t_linear);
  for (int c = 0; c < kStressComponents; ++c) EXPECT_NEAR(a[c], b[c], 1e-5 * std::abs(b[0])) << c;
  EXPECT_NEAR(t_hyper / t_linear, 1.0, 1e-5);
}

TEST(shell_NeoHookean, UnloadingReturnsToZeroStress) {
  // hyperelastic: the stress depends on the current strain only, not on the path
  const NeoHookeanShellMaterial m(kE, kNu, kRho);
  std::vector<Real> point(static_cast<std::size_t>(kStressComponents + m.state_size()), 0.0);
  const Real out[5] = {0.4, 0.1, 0.3, 0, 0}, back[5] = {-0.4, -0.1, -0.3, 0, 0};
  for (int k = 0; k < 50; ++k) m.update(point.data(), out, 0.02);
  EXPECT_GT(std::abs(point[0]), 1e3);
  for (int k = 0; k < 50; ++k) m.update(point.data(), back, 0.02);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(point[c], 0.0, 1e-6) << c;
  EXPECT_NEAR(point[kStressComponents + 3], 0.0, 1e-12);  // ln lambda_3 back to zero
}

}  // namespace
}  // namespace lamina::shell
