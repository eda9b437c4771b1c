// Belytschko-Tsay shell kernel (seed 000 eqs (17)-(37)): rigid-body motion gives no force, membrane and
// bending patches give the analytic resultants and nodal forces, the stable step is conservative.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

#include "material/j2_plasticity.hpp"
#include "shell/belytschko_tsay_shell.hpp"

namespace lamina::shell {
namespace {

Mat3 some_rotation() {
  return (Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()) * Eigen::AngleAxisd(-0.4, Vec3(0, 1, 0))).toRotationMatrix();
}

/// Element corners in a local plane (a x b rectangle, optional skew), rotated into 3D.
NodeMatrix element(const Mat3& R, Real a, Real b, Real skew = 0.0, Real warp = 0.0) {
  NodeMatrix local;
  local << 0, a, a + skew, skew, 0, 0, b, b, warp, -warp, warp, -warp;
  return R * local + Vec3(1.0, -2.0, 0.5).replicate<1, 4>();
}

struct Fixture {
  ShellSection section;
  material::LinearElasticShellMaterial material{2.0e5, 0.3, 7.8e-3};
  Real h = 0.1;
};

/// One element update from a zero state (fresh stresses, hourglass resultants and thickness); the
/// hourglass resultants after it go to hourglass_out if given (kHourglassSize values).
ShellElementResult update_once(const Fixture& f, const NodeMatrix& x, const NodeMatrix& v, const NodeMatrix& w, Real dt,
                               Real* hourglass_out = nullptr) {
  BelytschkoTsayShell shell(f.section, f.material);
  std::vector<Real> stress(shell.stress_size(), 0.0);
  Real hourglass[BelytschkoTsayShell::kHourglassSize] = {};
  Real h = f.h;
  const ShellElementResult r = shell.update(x, v, w, dt, stress.data(), hourglass, h);
  if (hourglass_out) std::copy(hourglass, hourglass + BelytschkoTsayShell::kHourglassSize, hourglass_out);
  return r;
}

TEST(shell_BelytschkoTsay, LobattoRulesIntegratePolynomialsExactly) {
  for (int n = 2; n <= 7; ++n) {
    const auto r = ThroughThicknessRule::lobatto(n);
    const int degree = 2 * n - 3;
    for (int p = 0; p <= degree; ++p) {
      Real sum = 0;
      for (int q = 0; q < n; ++q) sum += r.weights[q] * std::pow(r.points[q], p);
      const Real exact = p % 2 ? 0.0 : 2.0 / (p + 1);
      EXPECT_NEAR(sum, exact, 1e-13) << "n = " << n << ", degree " << p;
    }
  }
}

TEST(shell_BelytschkoTsay, RigidBodyMotionGivesNoForce) {
  Fixture f;
  for (HourglassModel model : {HourglassModel::physical, HourglassModel::coefficients})
  for (bool kirchhoff : {false, true})
  for (Real warp : {0.0, 0.05}) {
    f.section.hourglass_model = model;
    f.section.kirchhoff_transverse_hourglass = kirchhoff;
    BelytschkoTsayShell shell(f.section, f.material);
    const NodeMatrix x = element(some_rotation(), 2.0, 1.0, 0.3, warp);
    const Vec3 w(0.3, -1.2, 0.8), v0(1.0, 2.0, -3.0), centre = x.rowwise().mean();
    NodeMatrix v, omega;
    for (int a = 0; a < 4; ++a) {
      v.col(a) = v0 + w.cross(x.col(a) - centre);
      omega.col(a) = w;
    }
    std::vector<Real> stress(shell.stress_size(), 0.0);
    Real hourglass[BelytschkoTsayShell::kHourglassSize] = {};
    Real h = f.h;
    const auto r = shell.update(x, v, omega, 1e-3, stress.data(), hourglass, h);
    ASSERT_TRUE(r.valid);
    const Real scale = f.material.young_modulus() * f.h * 1e-3;  // force of a unit strain rate over dt
    EXPECT_LT(r.force.cwiseAbs().maxCoeff(), 1e-12 * scale) << "warp " << warp;
    EXPECT_LT(r.moment.cwiseAbs().maxCoeff(), 1e-12 * scale) << "warp " << warp;
    for (Real s : stress) EXPECT_NEAR(s, 0.0, 1e-9);
    EXPECT_NEAR(h, f.h, 1e-15);
  }
}

TEST(shell_BelytschkoTsay, MembranePatchGivesAnalyticResultantsAndNodalForces) {
  Fixture f;
  f.section.hourglass = 0.1;
  BelytschkoTsayShell shell(f.section, f.material);
  const Mat3 R = some_rotation();
  const Real a = 2.0, b = 1.0;
  const NodeMatrix x = element(R, a, b);
  // uniform local strain rate: d_x, d_y, 2 d_xy
  const Real dx = 1e-3, dy = -4e-4, gxy = 6e-4, dt = 0.5;
  Eigen::Matrix3d D;
  D << dx, 0.5 * gxy, 0, 0.5 * gxy, dy, 0, 0, 0, 0;
  const Vec3 centre = x.rowwise().mean();
  NodeMatrix v;
  for (int a2 = 0; a2 < 4; ++a2) v.col(a2) = R * (D * (R.transpose() * (x.col(a2) - centre)));
  std::vector<Real> stress(shell.stress_size(), 0.0);
  Real hourglass[BelytschkoTsayShell::kHourglassSize] = {};
  Real h = f.h;
  const auto r = shell.update(x, v, NodeMatrix::Zero(), dt, stress.data(), hourglass, h);
  ASSERT_TRUE(r.valid);
  const Real E = 2.0e5, nu = 0.3, c = E / (1 - nu * nu), G = E / (2 * (1 + nu));
  const ShellResultants n = shell.resultants(stress.data(), f.h);
  const Real nxx = c * f.h * (dx + nu * dy) * dt, nyy = c * f.h * (dy + nu * dx) * dt, nxy = G * f.h * gxy * dt;
  EXPECT_NEAR(n.nxx, nxx, 1e-10 * std::abs(nxx));
  EXPECT_NEAR(n.nyy, nyy, 1e-10 * std::abs(nxx));
  EXPECT_NEAR(n.nxy, nxy, 1e-10 * std::abs(nxx));
  EXPECT_NEAR(n.mxx, 0.0, 1e-12 * std::abs(nxx));
  // rectangle: nodes at x = a carry +N_xx b/2 (and N_xy b/2 along y), nodes at y = b carry N_yy a/2
  const NodeMatrix local = R.transpose() * r.force;
  const Real fx[4] = {-nxx * b / 2 - nxy * a / 2, nxx * b / 2 - nxy * a / 2, nxx * b / 2 + nxy * a / 2, -nxx * b / 2 + nxy * a / 2};
  const Real fy[4] = {-nyy * a / 2 - nxy * b / 2, -nyy * a / 2 + nxy * b / 2, nyy * a / 2 + nxy * b / 2, nyy * a / 2 - nxy * b / 2};
  for (int k = 0; k < 4; ++k) {
    EXPECT_NEAR(local(0, k), fx[k], 1e-9 * std::abs(nxx)) << "node " << k;
    EXPECT_NEAR(local(1, k), fy[k], 1e-9 * std::abs(nxx)) << "node " << k;
    EXPECT_NEAR(local(2, k), 0.0, 1e-9 * std::abs(nxx)) << "node " << k;
  }
  EXPECT_LT(r.moment.cwiseAbs().maxCoeff(), 1e-9 * std::abs(nxx));
  // plane stress thickness change: d_zz = -nu/(1-nu) (d_x + d_y)
  EXPECT_NEAR(h, f.h * (1 - dt * nu / (1 - nu) * (dx + dy)), 1e-15);
  // power = N : d over the area (mid-step stress = half the final one)
  EXPECT_NEAR(r.internal_power, a * b * 0.5 * (nxx * dx + nyy * dy + nxy * gxy), 1e-9 * std::abs(r.internal_power));
}

TEST(shell_BelytschkoTsay, BendingPatchGivesAnalyticMomentsAndNodalMoments) {
  Fixture f;
  BelytschkoTsayShell shell(f.section, f.material);
  const Mat3 R = some_rotation();
  const Real a = 2.0, b = 1.0, dt = 0.25;
  const NodeMatrix x = element(R, a, b);
  const Real kx = 2e-3, ky = -1e-3;  // curvature rates: theta_y = kx x, theta_x = -ky y, w = -(kx x^2 + ky y^2)/2
  const Vec3 centre = x.rowwise().mean();
  NodeMatrix v, omega;
  for (int k = 0; k < 4; ++k) {
    const Vec3 p = R.transpose() * (x.col(k) - centre);
    v.col(k) = R * Vec3(0, 0, -0.5 * (kx * p.x() * p.x() + ky * p.y() * p.y()));
    omega.col(k) = R * Vec3(-ky * p.y(), kx * p.x(), 0);
  }
  std::vector<Real> stress(shell.stress_size(), 0.0);
  Real hourglass[BelytschkoTsayShell::kHourglassSize] = {};
  Real h = f.h;
  const auto r = shell.update(x, v, omega, dt, stress.data(), hourglass, h);
  ASSERT_TRUE(r.valid);
  const Real E = 2.0e5, nu = 0.3, D = E * f.h * f.h * f.h / (12 * (1 - nu * nu));
  const ShellResultants m = shell.resultants(stress.data(), f.h);
  const Real mxx = D * (kx + nu * ky) * dt, myy = D * (ky + nu * kx) * dt;
  EXPECT_NEAR(m.mxx, mxx, 1e-10 * std::abs(mxx));
  EXPECT_NEAR(m.myy, myy, 1e-10 * std::abs(mxx));
  EXPECT_NEAR(m.mxy, 0.0, 1e-10 * std::abs(mxx));
  EXPECT_NEAR(m.nxx, 0.0, 1e-10 * std::abs(mxx));
  EXPECT_NEAR(m.qxz, 0.0, 1e-10 * std::abs(mxx));
  EXPECT_NEAR(m.qyz, 0.0, 1e-10 * std::abs(mxx));
  // nodal moments (local): m_y = +-M_xx b/2 at x = a / x = 0; m_x = -+M_yy a/2 at y = b / y = 0
  const NodeMatrix local = R.transpose() * r.moment;
  const Real my[4] = {-mxx * b / 2, mxx * b / 2, mxx * b / 2, -mxx * b / 2};
  const Real mx[4] = {myy * a / 2, myy * a / 2, -myy * a / 2, -myy * a / 2};
  for (int k = 0; k < 4; ++k) {
    EXPECT_NEAR(local(1, k), my[k], 1e-9 * std::abs(mxx)) << "node " << k;
    EXPECT_NEAR(local(0, k), mx[k], 1e-9 * std::abs(mxx)) << "node " << k;
  }
  EXPECT_LT((R.transpose() * r.force).cwiseAbs().maxCoeff(), 1e-9 * std::abs(mxx));
}

TEST(shell_BelytschkoTsay, HourglassModeIsResistedAndItsEnergyReported) {
  Fixture f;
  f.section.hourglass_model = HourglassModel::coefficients;  // the seed's springs
  f.section.hourglass = 0.1;
  BelytschkoTsayShell shell(f.section, f.material);
  const NodeMatrix x = element(Mat3::Identity(), 1.0, 1.0);
  NodeMatrix v = NodeMatrix::Zero();
  v.row(2) << 1e-3, -1e-3, 1e-3, -1e-3;  // transverse hourglass (twist) pattern
  std::vector<Real> stress(shell.stress_size(), 0.0);
  Real hourglass[BelytschkoTsayShell::kHourglassSize] = {};
  Real h = f.h;
  const auto r = shell.update(x, v, NodeMatrix::Zero(), 1.0, stress.data(), hourglass, h);
  EXPECT_GT(r.force.row(2).dot(v.row(2)), 0.0);          // resisting
  EXPECT_GT(r.hourglass_power, 0.0);
  EXPECT_NEAR(r.internal_power, 0.0, 1e-20);             // one-point rule does not see it
  f.section.hourglass = 0.0;
  BelytschkoTsayShell free_shell(f.section, f.material);
  Real hg2[BelytschkoTsayShell::kHourglassSize] = {};
  std::fill(stress.begin(), stress.end(), 0.0);
  const auto r0 = free_shell.update(x, v, NodeMatrix::Zero(), 1.0, stress.data(), hg2, h);
  EXPECT_LT(r0.force.cwiseAbs().maxCoeff(), 1e-15);
}

/// hourglass_bending = 1 is the physical stiffness of the rotational hourglass modes: on a square the
/// energy it stores for theta_y = c h_I equals the exactly integrated bending energy of the bilinear
/// rotation field theta_y = c x y / a^2, (2/3)(1 + (1 - nu)/2) D c^2 (within 1.2 % at nu = 0.3).
/// It leaves the transverse and membrane hourglass modes to `hourglass`; unset, it is `hourglass`.
TEST(shell_BelytschkoTsay, PhysicalBendingHourglassMatchesIntegratedBendingEnergy) {
  Fixture f;
  f.section.hourglass_model = HourglassModel::coefficients;  // the seed's springs
  const Real a = 0.5;  // half side
  const NodeMatrix x = element(some_rotation(), 2 * a, 2 * a);
  const Mat3 R = some_rotation();
  const Real c = 1e-4, dt = 1.0;
  NodeMatrix omega = NodeMatrix::Zero(), vz = NodeMatrix::Zero();
  const Real hpat[4] = {1, -1, 1, -1};
  for (int k = 0; k < 4; ++k) {
    omega.col(k) = R * Vec3(0, c * hpat[k], 0);
    vz.col(k) = R * Vec3(0, 0, c * hpat[k]);
  }
  auto hourglass_energy = [&](Real r, Real r_bend, const NodeMatrix& v, const NodeMatrix& w) {
    f.section.hourglass = r;
    f.section.hourglass_bending = r_bend;
    const auto res = update_once(f, x, v, w, dt);
    EXPECT_NEAR(res.internal_power, 0.0, 1e-20);  // invisible to the one-point rule
    return res.hourglass_power * dt;
  };
  const Real nu = 0.3, D = 2.0e5 * f.h * f.h * f.h / (12 * (1 - nu * nu));
  const Real physical = 2.0 / 3.0 * (1 + (1 - nu) / 2) * D * c * c * dt * dt;
  EXPECT_NEAR(hourglass_energy(0.1, 1.0, NodeMatrix::Zero(), omega) / physical, 1.0, 0.012);
  // unset (negative): the common coefficient, as before the option existed
  EXPECT_NEAR(hourglass_energy(0.1, -1.0, NodeMatrix::Zero(), omega), 0.1 * hourglass_energy(0.1, 1.0, NodeMatrix::Zero(), omega),
              1e-12 * physical);
  // the transverse mode does not depend on hourglass_bending; with hourglass = 0 only the rotations are resisted
  EXPECT_DOUBLE_EQ(hourglass_energy(0.1, 1.0, vz, NodeMatrix::Zero()), hourglass_energy(0.1, -1.0, vz, NodeMatrix::Zero()));
  EXPECT_EQ(hourglass_energy(0.0, 1.0, vz, NodeMatrix::Zero()), 0.0);
  EXPECT_GT(hourglass_energy(0.0, 1.0, NodeMatrix::Zero(), omega), 0.0);
}

/// A facet of the hyperbolic paraboloid z = c x y (corners (+-a, +-a), offsets +-c a^2 from its mean plane)
/// moving with a Kirchhoff field of that surface: velocity u(x, y) given by its value and gradient at each
/// corner, rotation from the normal's rate n_dot = -(n . u_,a) a^a and the in-plane spin
/// (1/2) n . (a^a x u_,a) about n (so no transverse shear and no drilling strain, exactly).
struct WarpedFacetMotion {
  NodeMatrix x, v, omega;
};
template <class Field>
WarpedFacetMotion kirchhoff_motion_of_warped_facet(Real a, Real c, Field field) {
  WarpedFacetMotion m;
  const Real xs[4] = {-a, a, a, -a}, ys[4] = {-a, -a, a, a};
  for (int k = 0; k < 4; ++k) {
    const Real X = xs[k], Y = ys[k];
    m.x.col(k) = Vec3(X, Y, c * X * Y);
    const Vec3 ax(1, 0, c * Y), ay(0, 1, c * X), n = ax.cross(ay).normalized();
    Eigen::Matrix2d g;
    g << ax.dot(ax), ax.dot(ay), ay.dot(ax), ay.dot(ay);
    const Eigen::Matrix2d gi = g.inverse();
    const Vec3 dual_x = gi(0, 0) * ax + gi(0, 1) * ay, dual_y = gi(1, 0) * ax + gi(1, 1) * ay;
    Vec3 u, u_x, u_y;
    field(X, Y, u, u_x, u_y);
    const Vec3 n_dot = -(n.dot(u_x) * dual_x + n.dot(u_y) * dual_y);
    const Real spin = 0.5 * n.dot(dual_x.cross(u_x) + dual_y.cross(u_y));
    m.v.col(k) = u;
    m.omega.col(k) = n.cross(n_dot) + spin * n;
  }
  return m;
}

/// A Kirchhoff bending field on a warped facet gives no drilling strain (u = (0, 0, x^2 / 2), curvature 1).
/// The element's drilling strain rate theta_z - omega_z must be second order in the facet's size; with the
/// in-plane spin taken from velocities corrected by the facet's rigid rotation only it was of order
/// curvature x warp (-0.036 here, -0.0093 at half the size), which a stiff penalty turned into locking
/// (thin twisted beam).
TEST(shell_BelytschkoTsay, KirchhoffBendingOfAWarpedFacetGivesNoDrillingStrain) {
  Fixture f;
  const Real dt = 1e-3;
  auto drilling_rate = [&](Real a) {
    const auto m = kirchhoff_motion_of_warped_facet(a, 0.3, [](Real X, Real, Vec3& u, Vec3& u_x, Vec3& u_y) {
      u = Vec3(0, 0, 0.5 * X * X);
      u_x = Vec3(0, 0, X);
      u_y = Vec3::Zero();
    });
    Real hourglass[BelytschkoTsayShell::kHourglassSize];
    const auto r = update_once(f, m.x, m.v, m.omega, dt, hourglass);
    EXPECT_TRUE(r.valid);
    const Real k_drill = f.section.drilling * f.material.shear_modulus() * f.h * r.area;
    return hourglass[6] / (dt * k_drill);  // theta_z - omega_z
  };
  const Real coarse = drilling_rate(0.5), fine = drilling_rate(0.25);
  std::printf("drilling strain rate of a Kirchhoff bending field (curvature 1), facet 1 x 1: %.3g, 0.5 x 0.5: %.3g\n",
              coarse, fine);
  EXPECT_LT(std::abs(coarse), 5e-3);
  EXPECT_LT(std::abs(fine), 0.3 * std::abs(coarse) + 1e-12);  // second order: a quarter at half the size
}

/// The Kirchhoff twist w = x y of a warped facet leaves the MITC4 transverse-shear hourglass unstrained:
/// with the corners' surface normals as directors the edge shears' differences vanish. With e3 as every
/// corner's director they were of order twist x warp, and on this facet (t = 0.1, a = 0.5, c = 0.3) the
/// shear hourglass took 8 % of the twisting power; on the thin twisted beam that locked the twist.
TEST(shell_BelytschkoTsay, KirchhoffTwistOfAWarpedFacetLeavesTheShearHourglassFree) {
  Fixture f;
  const auto m = kirchhoff_motion_of_warped_facet(0.5, 0.3, [](Real X, Real Y, Vec3& u, Vec3& u_x, Vec3& u_y) {
    u = Vec3(0, 0, X * Y);
    u_x = Vec3(0, 0, Y);
    u_y = Vec3(0, 0, X);
  });
  const auto r = update_once(f, m.x, m.v, m.omega, 1e-3);
  ASSERT_TRUE(r.valid);
  std::printf("twist of a warped facet: hourglass / internal power %.3g\n", r.hourglass_power / r.internal_power);
  EXPECT_GT(r.internal_power, 0.0);
  EXPECT_LT(std::abs(r.hourglass_power), 1e-9 * r.internal_power);
}

/// A Kirchhoff bending-and-twisting field (w quadratic, rotations its slopes) leaves a trapezoid and a
/// skewed trapezoid free of transverse shear: the centre shear is MITC4's assumed covariant shear (the mean
/// of the opposite edges' tangential shears, exact for such a field on any quadrilateral). The one-point
/// Cartesian shear (b . w + mean rotation) missed it by taper x skew terms: on MacNeal-Harder's trapezoidal
/// straight cantilever the tip deflection under a tip shear was 0.037 of the reference.
TEST(shell_BelytschkoTsay, KirchhoffBendingOfATrapezoidGivesNoTransverseShear) {
  Fixture f;
  const Mat3 R = some_rotation();
  const Real kx = 0.02, ky = -0.01, kxy = 0.015, dt = 1e-3;
  for (Real skew : {0.0, 0.15}) {
    NodeMatrix local;
    local << -0.6, 0.6, 0.35 + skew, -0.35 + skew, -0.2, -0.2, 0.2, 0.2, 0, 0, 0, 0;
    const NodeMatrix x = R * local;
    NodeMatrix v, omega;
    for (int k = 0; k < 4; ++k) {
      const Real X = local(0, k), Y = local(1, k);
      const Real w = -0.5 * (kx * X * X + ky * Y * Y) + kxy * X * Y;
      const Real w_x = -kx * X + kxy * Y, w_y = -ky * Y + kxy * X;
      v.col(k) = R * Vec3(0, 0, w);
      omega.col(k) = R * Vec3(w_y, -w_x, 0);  // gamma_x = w_,x + theta_y = 0, gamma_y = w_,y - theta_x = 0
    }
    BelytschkoTsayShell shell(f.section, f.material);
    std::vector<Real> stress(shell.stress_size(), 0.0);
    Real hourglass[BelytschkoTsayShell::kHourglassSize] = {};
    Real h = f.h;
    const auto r = shell.update(x, v, omega, dt, stress.data(), hourglass, h);
    ASSERT_TRUE(r.valid);
    const Real bending = std::abs(stress[0]);  // sigma_xx at the bottom fibre
    ASSERT_GT(bending, 0.0);
    for (int q = 0; q < shell.thickness_points(); ++q)
      for (int c : {3, 4}) EXPECT_LT(std::abs(stress[shell.point_stride() * q + c]), 1e-12 * bending) << "skew " << skew;
    EXPECT_LT(std::abs(hourglass[2]) + std::abs(hourglass[5]), 1e-12 * bending * f.h) << "skew " << skew;
  }
}

/// In-plane pure bending of a parallelogram (u_x = -k x y, u_y = k (x^2 + nu y^2) / 2, the elements of
/// MacNeal-Harder's skewed straight cantilever) stores exactly the bending energy E t k^2 int y^2 dA / 2 in
/// the membrane hourglass modes, taken along the element's natural directions xi, eta. In Cartesian
/// x / y modes the skew made the field a y-mode of stiffness E t A |b2|^2 / 12 too, 2 orders of magnitude
/// too stiff on a 5:1 element (tip deflection 0.036 of the reference on the all-parallelogram beam).
TEST(shell_BelytschkoTsay, InPlaneBendingOfAParallelogramStoresTheBendingEnergy) {
  Fixture f;
  const Mat3 R = some_rotation();
  const Real nu = f.material.poisson_ratio(), k = 1e-3, dt = 1.0;
  for (Real skew : {0.0, 0.2, -0.35}) {
    const Real a = 0.5, b = 0.1;  // half length, half height: a 1 x 0.2 element, top edge shifted by 2 skew
    NodeMatrix local;
    local << -a - skew, a - skew, a + skew, -a + skew, -b, -b, b, b, 0, 0, 0, 0;
    const NodeMatrix x = R * local;
    NodeMatrix v, omega;
    for (int c = 0; c < 4; ++c) {
      const Real X = local(0, c), Y = local(1, c);
      v.col(c) = R * Vec3(-k * X * Y, 0.5 * k * (X * X + nu * Y * Y), 0);
      omega.col(c) = R * Vec3(0, 0, k * X);  // the field's in-plane spin (no drilling strain)
    }
    const auto r = update_once(f, x, v, omega, dt);
    ASSERT_TRUE(r.valid);
    const Real area = 4 * a * b, exact = 0.5 * f.material.young_modulus() * f.h * k * k * area * b * b / 3.0;
    const Real stored = (r.internal_power + r.hourglass_power) * dt;
    std::printf("in-plane bending of a parallelogram, skew %.2f: stored / exact %.6f\n", skew, stored / exact);
    EXPECT_NEAR(stored / exact, 1.0, 1e-9) << "skew " << skew;
  }
}

/// Largest frequency of one free element (lumped mass, rotational inertia m max(h^2/12, A/8)) by
/// eigenvalues of the numerical stiffness: the element's stable step must not exceed 2 / omega_max.
TEST(shell_BelytschkoTsay, StableTimeStepIsConservative) {
  Fixture f;
  f.section.hourglass = 0.1;
  for (HourglassModel model : {HourglassModel::physical, HourglassModel::coefficients})
  for (bool kirchhoff : {false, true})
  for (Real r_mem : {-1.0, 0.33})  // also with the physical membrane hourglass stiffness
  for (Real r_bend : {-1.0, 1.0})  // also with the physical rotational hourglass stiffness
  for (Real nu : {0.3, 0.0})
  for (Real aspect : {1.0, 3.0, 0.75}) {
    f.section.hourglass_model = model;
    f.section.kirchhoff_transverse_hourglass = kirchhoff;
    f.section.hourglass_membrane = r_mem;
    f.section.hourglass_bending = r_bend;
    f.material = material::LinearElasticShellMaterial(2.0e5, nu, 7.8e-3);
    BelytschkoTsayShell shell(f.section, f.material);
    const NodeMatrix x = element(some_rotation(), aspect, 1.0, aspect == 0.75 ? 0.0 : 0.2);
    Eigen::Matrix<Real, 24, 24> K;
    for (int j = 0; j < 24; ++j) {
      NodeMatrix v = NodeMatrix::Zero(), w = NodeMatrix::Zero();
      if (j < 12) v(j % 3, j / 3) = 1.0;
      else w((j - 12) % 3, (j - 12) / 3) = 1.0;
      std::vector<Real> stress(shell.stress_size(), 0.0);
      Real hourglass[BelytschkoTsayShell::kHourglassSize] = {};
      Real h = f.h;
      const auto r = shell.update(x, v, w, 1.0, stress.data(), hourglass, h);
      Eigen::Matrix<Real, 24, 1> column;
      column << Eigen::Map<const Eigen::Matrix<Real, 12, 1>>(r.force.data()), Eigen::Map<const Eigen::Matrix<Real, 12, 1>>(r.moment.data());
      K.col(j) = column;
    }
    EXPECT_LT((K - K.transpose()).cwiseAbs().maxCoeff(), 1e-8 * K.cwiseAbs().maxCoeff());
    const Real area = 0.5 * (x.col(2) - x.col(0)).cross(x.col(3) - x.col(1)).norm();
    const Real m = f.material.density() * f.h * area / 4, I = m * std::max(f.h * f.h / 12, area / 8);
    Eigen::Matrix<Real, 24, 1> mass;
    mass << Eigen::Matrix<Real, 12, 1>::Constant(m), Eigen::Matrix<Real, 12, 1>::Constant(I);
    const Eigen::Matrix<Real, 24, 24> A = mass.cwiseInverse().cwiseSqrt().asDiagonal() * (0.5 * (K + K.transpose())) *
                                          mass.cwiseInverse().cwiseSqrt().asDiagonal();
    const Real omega_max = std::sqrt(Eigen::SelfAdjointEigenSolver<Eigen::Matrix<Real, 24, 24>>(A).eigenvalues().maxCoeff());
    const Real critical = 2.0 / omega_max;
    const Real estimate = shell.stable_time_step(x);
    EXPECT_LE(estimate, critical) << "aspect " << aspect << " nu " << nu << " r_bend " << r_bend << " r_mem " << r_mem
                                  << " physical " << (model == HourglassModel::physical);
    EXPECT_GE(estimate, 0.3 * critical) << "aspect " << aspect << " nu " << nu << " r_bend " << r_bend;  // not uselessly small
  }
}

/// transverse_hourglass: kirchhoff. The transverse hourglass strain is the hourglass part of the edge-tied
/// shears, so the Kirchhoff twist w = c x y (theta_x = c x, theta_y = -c y: no transverse shear anywhere)
/// and constant curvature of a parallelogram store no hourglass energy, while the standard gamma . v_z
/// spring resists the twist; the spurious w mode (w = c h_I, no rotation) is resisted by both.
TEST(shell_BelytschkoTsay, KirchhoffTransverseHourglassLeavesTwistFree) {
  Fixture f;
  f.section.hourglass_model = HourglassModel::coefficients;  // the seed's springs
  f.section.hourglass = 0.0;
  f.section.hourglass_transverse = 0.1;
  const Mat3 R = some_rotation();
  for (Real skew : {0.0, 0.4}) {
    const NodeMatrix x = element(R, 2.0, 1.0, skew);
    const NodeMatrix xl = R.transpose() * (x.colwise() - x.rowwise().mean());
    auto energy = [&](bool kirchhoff, auto field) {
      f.section.kirchhoff_transverse_hourglass = kirchhoff;
      NodeMatrix v, omega;
      for (int k = 0; k < 4; ++k) {
        const auto [w, tx, ty] = field(xl(0, k), xl(1, k));
        v.col(k) = R * Vec3(0, 0, w);
        omega.col(k) = R * Vec3(tx, ty, 0);
      }
      const auto res = update_once(f, x, v, omega, 1.0);
      EXPECT_NEAR(res.force.rowwise().sum().norm(), 0.0, 1e-9);  // forces stay self-equilibrated
      return res.hourglass_power;
    };
    const Real c = 1e-4;
    auto twist = [c](Real x, Real y) { return std::array<Real, 3>{c * x * y, c * x, -c * y}; };
    auto curvature = [c](Real x, Real) { return std::array<Real, 3>{-0.5 * c * x * x, 0.0, c * x}; };
    int node = 0;
    auto spurious = [c, &node](Real, Real) { return std::array<Real, 3>{c * ((node++ % 2) ? -1.0 : 1.0), 0.0, 0.0}; };
    const Real scale = f.material.young_modulus() * f.h * c * c;
    EXPECT_LT(std::abs(energy(true, twist)), 1e-12 * scale) << "skew " << skew;
    EXPECT_GT(energy(false, twist), 1e-6 * scale) << "skew " << skew;
    EXPECT_LT(std::abs(energy(true, curvature)), 1e-12 * scale) << "skew " << skew;
    node = 0;
    const Real kirchhoff_w = energy(true, spurious);
    node = 0;
    const Real standard_w = energy(false, spurious);
    EXPECT_GT(kirchhoff_w, 1e-6 * scale);
    EXPECT_GT(standard_w, 1e-6 * scale);
    if (skew == 0.0) {
      EXPECT_NEAR(kirchhoff_w / standard_w, 1.0, 1e-12);  // same spring on a rectangle
    }
  }
}

/// hourglass_membrane / hourglass_transverse replace `hourglass` for their own modes only.
TEST(shell_BelytschkoTsay, PerModeHourglassCoefficients) {
  Fixture f;
  f.section.hourglass_model = HourglassModel::coefficients;  // the seed's springs
  const NodeMatrix x = element(some_rotation(), 2.0, 1.0, 0.2);
  const Mat3 R = some_rotation();
  NodeMatrix vx = NodeMatrix::Zero(), vz = NodeMatrix::Zero();
  const Real hpat[4] = {1, -1, 1, -1};
  for (int k = 0; k < 4; ++k) {
    vx.col(k) = R * Vec3(1e-4 * hpat[k], 0, 0);
    vz.col(k) = R * Vec3(0, 0, 1e-4 * hpat[k]);
  }
  auto energy = [&](Real r, Real r_mem, Real r_w, const NodeMatrix& v) {
    f.section.hourglass = r;
    f.section.hourglass_membrane = r_mem;
    f.section.hourglass_transverse = r_w;
    return update_once(f, x, v, NodeMatrix::Zero(), 1.0).hourglass_power;
  };
  EXPECT_NEAR(energy(0.1, 0.3, -1.0, vx), 3.0 * energy(0.1, -1.0, -1.0, vx), 1e-9 * energy(0.1, -1.0, -1.0, vx));
  EXPECT_DOUBLE_EQ(energy(0.1, 0.3, -1.0, vz), energy(0.1, -1.0, -1.0, vz));
  EXPECT_NEAR(energy(0.1, -1.0, 0.5, vz), 5.0 * energy(0.1, -1.0, -1.0, vz), 1e-9 * energy(0.1, -1.0, -1.0, vz));
  EXPECT_DOUBLE_EQ(energy(0.1, -1.0, 0.5, vx), energy(0.1, -1.0, -1.0, vx));
  EXPECT_EQ(energy(0.0, -1.0, -1.0, vx), 0.0);
}

/// Physical stabilisation (the default): each mode's stored energy is the closed form of its source.
/// Membrane u_x = q xi eta on a 2a x 2b rectangle: the bending-exact (1/2)(4/3) E t (b/a) q^2; rotation
/// theta_y = q xi eta: (1/2)(4/3)(E t^3 / 12)(b/a) q^2; the spurious w mode w = s h_I: MITC4's transverse
/// shear energy (1/2)(k G t A / 3)(s^2 / a^2 + s^2 / b^2); the Kirchhoff twist w = c x y stores nothing;
/// a drilling rotation theta_z alone: (1/2) drilling G t A theta_z^2.
TEST(shell_BelytschkoTsay, PhysicalStabilisationStoresTheClosedFormEnergies) {
  Fixture f;
  const Real a = 1.0, b = 0.5, q = 1e-4, t = f.h, E = 2.0e5, nu = 0.3, G = E / (2 * (1 + nu)), k = 5.0 / 6.0;
  const Real A = 4 * a * b;
  const Mat3 R = some_rotation();
  const NodeMatrix x = element(R, 2 * a, 2 * b);
  const Real hpat[4] = {1, -1, 1, -1};
  auto energy = [&](auto field) {  // field(node, local x, local y) -> {u_local, theta_local}
    const NodeMatrix xl = R.transpose() * (x.colwise() - x.rowwise().mean());
    NodeMatrix v, w;
    for (int n = 0; n < 4; ++n) {
      const auto [u, th] = field(n, xl(0, n), xl(1, n));
      v.col(n) = R * u;
      w.col(n) = R * th;
    }
    const auto r = update_once(f, x, v, w, 1.0);
    EXPECT_NEAR(r.force.rowwise().sum().norm(), 0.0, 1e-12 * E * t);  // self-equilibrated
    return r.hourglass_power;  // dt = 1: the energy of the displacement v
  };
  using Pair = std::pair<Vec3, Vec3>;
  EXPECT_NEAR(energy([&](int n, Real, Real) { return Pair(Vec3(q * hpat[n], 0, 0), Vec3::Zero()); }),
              0.5 * 4.0 / 3.0 * E * t * (b / a) * q * q, 1e-10 * E * t * q * q);
  EXPECT_NEAR(energy([&](int n, Real, Real) { return Pair(Vec3(0, q * hpat[n], 0), Vec3::Zero()); }),
              0.5 * 4.0 / 3.0 * E * t * (a / b) * q * q, 1e-10 * E * t * q * q);
  EXPECT_NEAR(energy([&](int n, Real, Real) { return Pair(Vec3::Zero(), Vec3(0, q * hpat[n], 0)); }),
              0.5 * 4.0 / 3.0 * E * t * t * t / 12 * (b / a) * q * q, 1e-10 * E * t * t * t * q * q);
  EXPECT_NEAR(energy([&](int n, Real, Real) { return Pair(Vec3(0, 0, q * hpat[n]), Vec3::Zero()); }),
              0.5 * k * G * t * A / 3 * (q * q / (a * a) + q * q / (b * b)), 1e-10 * G * t * q * q);
  EXPECT_NEAR(energy([&](int, Real xx, Real yy) { return Pair(Vec3(0, 0, q * xx * yy), Vec3(q * xx, -q * yy, 0)); }), 0.0,
              1e-14 * G * t * q * q);
  EXPECT_NEAR(energy([&](int, Real, Real) { return Pair(Vec3::Zero(), Vec3(0, 0, q)); }), 0.5 * f.section.drilling * G * t * A * q * q,
              1e-10 * G * t * A * q * q);
  // an in-plane rigid rotation with the matching drilling rotation stores nothing
  EXPECT_NEAR(energy([&](int, Real xx, Real yy) { return Pair(Vec3(-q * yy, q * xx, 0), Vec3(0, 0, q)); }), 0.0,
              1e-14 * G * t * q * q);
}

/// The default number of Lobatto points follows the material: 3 for an elastic one (seed eq (29)), 7 for a
/// plastic one (3 points carry at most the first-yield moment); a number in the section is used as it is.
TEST(shell_BelytschkoTsay, DefaultThicknessPointsFollowTheMaterial) {
  const material::J2PlasticShellMaterial steel(2.0e5, 0.3, 7.8e-3, 200.0, 0.0);
  const material::LinearElasticShellMaterial elastic(2.0e5, 0.3, 7.8e-3);
  ShellSection automatic;
  EXPECT_EQ(BelytschkoTsayShell(automatic, steel).thickness_points(), 7);
  EXPECT_EQ(BelytschkoTsayShell(automatic, elastic).thickness_points(), 3);
  ShellSection three;
  three.thickness_points = 3;
  EXPECT_EQ(BelytschkoTsayShell(three, steel).thickness_points(), 3);
  ShellSection five;
  five.thickness_points = 5;
  EXPECT_EQ(BelytschkoTsayShell(five, elastic).thickness_points(), 5);
}

/// With a plastic material the physical stabilisation yields with it: the membrane hourglass resultant of
/// u_x = q xi eta is bounded where the mode's peak stress reaches the yield stress, Q <= sigma_y t A |b_x| / 6,
/// and in an element that is flowing plastically (uniaxial stretch beyond yield) the hourglass stiffness
/// falls with the material's tangent; an elastic material keeps the full stiffness.
TEST(shell_BelytschkoTsay, PhysicalStabilisationYieldsWithAPlasticMaterial) {
  const Real E = 2.0e5, nu = 0.3, rho = 7.8e-3, sy = 200.0, t = 0.1, a = 1.0, b = 0.5, A = 4 * a * b;
  const material::J2PlasticShellMaterial steel(E, nu, rho, sy, 0.0);
  ShellSection section;  // physical
  BelytschkoTsayShell shell(section, steel);
  const NodeMatrix x = element(Mat3::Identity(), 2 * a, 2 * b);
  const Real hpat[4] = {1, -1, 1, -1};
  NodeMatrix v = NodeMatrix::Zero();
  for (int n = 0; n < 4; ++n) v(0, n) = hpat[n];
  // elastic range: Q = (E t A |b_x|^2 / 12) gamma . u; far beyond it: the bound
  const Real bx = 1.0 / (2.0 * a), gamma_u_per_q = 4.0;
  auto hourglass_resultant = [&](Real q) {
    std::vector<Real> stress(static_cast<std::size_t>(shell.stress_size()), 0.0);
    Real hg[BelytschkoTsayShell::kHourglassSize] = {};
    Real h = t;
    shell.update(x, q * v, NodeMatrix::Zero(), 1.0, stress.data(), hg, h);
    return hg[3];
  };
  const Real q_small = 1e-6;
  EXPECT_NEAR(hourglass_resultant(q_small), E * t * A * bx * bx / 12.0 * gamma_u_per_q * q_small, 1e-9 * E * t * A * q_small);
  EXPECT_NEAR(hourglass_resultant(1e-1), sy * t * A * bx / 6.0, 1e-12 * sy * t * A);
  // an element stretched beyond yield: the hourglass increment of the next step is much softer
  std::vector<Real> stress(static_cast<std::size_t>(shell.stress_size()), 0.0);
  Real hg[BelytschkoTsayShell::kHourglassSize] = {};
  Real h = t;
  NodeMatrix stretch = NodeMatrix::Zero();
  for (int n = 0; n < 4; ++n) stretch(0, n) = 0.01 * x(0, n);  // d_xx = 0.01 per unit time: yields in one step
  shell.update(x, stretch, NodeMatrix::Zero(), 1.0, stress.data(), hg, h);
  const Real flowing = [&] {
    const Real before = hg[3];
    shell.update(x, stretch + q_small * v, NodeMatrix::Zero(), 1.0, stress.data(), hg, h);
    return hg[3] - before;
  }();
  EXPECT_LT(std::abs(flowing), 0.5 * E * t * A * bx * bx / 12.0 * gamma_u_per_q * q_small);
}

// Bending modes of a plastic section: the mode's moment stays within the section's margin to yield around its
// held (hardening) part. A section flowing in bending takes no moment gradient when perfectly plastic, and the
// hardening share H / (E + H) of the elastic increment when it hardens; a section at rest takes it elastically.
TEST(shell_BelytschkoTsay, BendingHourglassOfAFlowingSectionIsBoundedByItsMargin) {
  const Real E = 2.0e5, nu = 0.3, rho = 7.8e-3, sy = 200.0, t = 0.1, a = 1.0, b = 0.5, A = 4 * a * b;
  const NodeMatrix x = element(Mat3::Identity(), 2 * a, 2 * b);
  const Real hpat[4] = {1, -1, 1, -1};
  const Real bx = 1.0 / (2.0 * a), c = 1e-6;  // |b_x|; the hourglass rotation rate (theta_y = c h_I)
  // elastic increment of Q_1 (the theta_y mode) for gamma . theta = 4 c over dt = 1, material tangent 1
  const Real elastic = E * t * t * t / 12.0 * A / 12.0 * bx * bx * 4.0 * c;
  const Real kappa = 100.0 * (sy / E) / (0.5 * t);  // outer fibre strain 100 x the yield strain in one step
  for (const Real hardening : {0.0, 2000.0}) {
    const material::J2PlasticShellMaterial steel(E, nu, rho, sy, hardening);
    ShellSection section;  // physical, 7 Lobatto points (the plastic default)
    BelytschkoTsayShell shell(section, steel);
    std::vector<Real> stress(static_cast<std::size_t>(shell.stress_size()), 0.0);
    Real hg[BelytschkoTsayShell::kHourglassSize] = {};
    Real h = t;
    NodeMatrix bend = NodeMatrix::Zero(), mode = NodeMatrix::Zero();
    for (int n = 0; n < 4; ++n) {
      bend(1, n) = kappa * x(0, n);  // uniform kappa_xx: no hourglass rate
      mode(1, n) = c * hpat[n];
    }
    // at rest: the elastic increment
    {
      std::vector<Real> fresh(static_cast<std::size_t>(shell.stress_size()), 0.0);
      Real q[BelytschkoTsayShell::kHourglassSize] = {};
      Real thickness = t;
      shell.update(x, NodeMatrix::Zero(), mode, 1.0, fresh.data(), q, thickness);
      EXPECT_NEAR(q[1], elastic, 1e-9 * elastic) << "H = " << hardening;
    }
    shell.update(x, NodeMatrix::Zero(), bend, 1.0, stress.data(), hg, h);
    EXPECT_EQ(hg[1], 0.0);
    shell.update(x, NodeMatrix::Zero(), bend + mode, 1.0, stress.data(), hg, h);  // flowing, and the mode on top
    const Real share = hardening / (E + hardening);
    if (hardening == 0.0) {
      EXPECT_LE(std::abs(hg[1]), 1e-4 * elastic);
    } else {
      EXPECT_GT(hg[1], 0.0);
      EXPECT_LE(hg[1], share * elastic * (1.0 + 1e-9));
      EXPECT_NEAR(hg[BelytschkoTsayShell::kHourglassSize - 1], hg[1], 1e-4 * elastic);  // all of it held
    }
  }
  // non-proportional flow (stretched along y past yield, then along x): the centre's stress moves along the
  // yield surface, so its tangent ratio is far from 0, but the section has no margin for a moment gradient
  const material::J2PlasticShellMaterial steel(E, nu, rho, sy, 0.0);
  ShellSection section;
  BelytschkoTsayShell shell(section, steel);
  std::vector<Real> stress(static_cast<std::size_t>(shell.stress_size()), 0.0);
  Real hg[BelytschkoTsayShell::kHourglassSize] = {};
  Real h = t;
  NodeMatrix stretch_y = NodeMatrix::Zero(), stretch_x = NodeMatrix::Zero(), mode = NodeMatrix::Zero();
  for (int n = 0; n < 4; ++n) {
    stretch_y(1, n) = 0.01 * x(1, n);
    stretch_x(0, n) = 0.01 * x(0, n);
    mode(1, n) = c * hpat[n];
  }
  shell.update(x, stretch_y, NodeMatrix::Zero(), 1.0, stress.data(), hg, h);
  shell.update(x, stretch_x, mode, 1.0, stress.data(), hg, h);
  EXPECT_LE(std::abs(hg[1]), 1e-4 * elastic);
}

}  // namespace
}  // namespace lamina::shell
