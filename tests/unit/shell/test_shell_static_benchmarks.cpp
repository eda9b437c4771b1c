// The Belytschko-Tsay element with its default (physical) stabilisation on the linear MacNeal-Harder
// shell benchmarks, as a static FE solve: the element's tangent stiffness is assembled column by column
// from its internal force (zero state, unit rates, dt = 1: f = K u for the linear material), no MPM grid,
// no dynamics. The seed's coefficient springs are too flexible on faceted curved shells (issue 16:
// Scordelis-Lo 1.49 x the reference at 16 x 16); the physical model converges to the reference.
#include <gtest/gtest.h>

#include <Eigen/Sparse>
#include <cmath>
#include <cstdio>
#include <functional>
#include <vector>

#include "shell/belytschko_tsay_shell.hpp"

namespace lamina::shell {
namespace {

struct StaticShellModel {
  std::vector<Vec3> nodes;
  std::vector<std::array<int, 4>> quads;  // counter-clockwise about the outward normal
  std::vector<char> fixed;                // 6 per node: u_x u_y u_z theta_x theta_y theta_z
  Eigen::VectorXd load;
};

/// Assemble K from the element's internal force and solve K u = f on the free dofs. regularisation: added
/// times the largest diagonal entry of K to every diagonal entry (0: K itself, which must be definite).
Eigen::VectorXd solve_static(const StaticShellModel& m, const ShellSection& section, const material::ShellMaterial& material,
                             Real thickness, Real regularisation = 0.0) {
  BelytschkoTsayShell element(section, material);
  const Index ndof = 6 * static_cast<Index>(m.nodes.size());
  std::vector<Eigen::Triplet<Real>> triplets;
  for (const auto& q : m.quads) {
    NodeMatrix x;
    for (int a = 0; a < 4; ++a) x.col(a) = m.nodes[static_cast<std::size_t>(q[a])];
    for (int c = 0; c < 24; ++c) {
      NodeMatrix v = NodeMatrix::Zero(), w = NodeMatrix::Zero();
      (c % 6 < 3 ? v : w)(c % 3, c / 6) = 1.0;
      std::vector<Real> stress(static_cast<std::size_t>(element.stress_size()), 0.0);
      Real hourglass[BelytschkoTsayShell::kHourglassSize] = {};
      Real h = thickness;
      const ShellElementResult r = element.update(x, v, w, 1.0, stress.data(), hourglass, h);
      EXPECT_TRUE(r.valid);
      for (int a = 0; a < 4; ++a)
        for (int k = 0; k < 3; ++k) {
          triplets.emplace_back(6 * q[a] + k, 6 * q[c / 6] + c % 6, r.force(k, a));
          triplets.emplace_back(6 * q[a] + 3 + k, 6 * q[c / 6] + c % 6, r.moment(k, a));
        }
    }
  }
  std::vector<Index> free_index(static_cast<std::size_t>(ndof), -1);
  Index nfree = 0;
  for (Index d = 0; d < ndof; ++d)
    if (!m.fixed[static_cast<std::size_t>(d)]) free_index[static_cast<std::size_t>(d)] = nfree++;
  std::vector<Eigen::Triplet<Real>> reduced;
  for (const auto& t : triplets) {
    const Index i = free_index[static_cast<std::size_t>(t.row())], j = free_index[static_cast<std::size_t>(t.col())];
    if (i >= 0 && j >= 0) reduced.emplace_back(i, j, t.value());
  }
  Eigen::SparseMatrix<Real> K(nfree, nfree);
  K.setFromTriplets(reduced.begin(), reduced.end());
  if (regularisation > 0) {
    const Real shift = regularisation * K.diagonal().cwiseAbs().maxCoeff();
    for (Index d = 0; d < nfree; ++d) K.coeffRef(d, d) += shift;
  }
  Eigen::VectorXd f(nfree);
  for (Index d = 0; d < ndof; ++d)
    if (free_index[static_cast<std::size_t>(d)] >= 0) f(free_index[static_cast<std::size_t>(d)]) = m.load(d);
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<Real>> ldlt(K);
  EXPECT_EQ(ldlt.info(), Eigen::Success);
  const Eigen::VectorXd uf = ldlt.solve(f);
  EXPECT_LT((K * uf - f).norm(), 1e-8 * f.norm() + 1e-12 * K.norm() * uf.norm());  // backward stable
  Eigen::VectorXd u = Eigen::VectorXd::Zero(ndof);
  for (Index d = 0; d < ndof; ++d)
    if (free_index[static_cast<std::size_t>(d)] >= 0) u(d) = uf(free_index[static_cast<std::size_t>(d)]);
  return u;
}

/// Structured n_c x n_a mesh of a surface map (s, t) in [0, 1]^2 -> 3D, quads oriented along +normal_hint.
StaticShellModel structured(int nc, int na, const std::function<Vec3(Real, Real)>& map,
                            const std::function<Vec3(const Vec3&)>& outward) {
  StaticShellModel m;
  for (int j = 0; j <= na; ++j)
    for (int i = 0; i <= nc; ++i) m.nodes.push_back(map(Real(i) / nc, Real(j) / na));
  auto id = [&](int i, int j) { return j * (nc + 1) + i; };
  for (int j = 0; j < na; ++j)
    for (int i = 0; i < nc; ++i) {
      std::array<int, 4> q{id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)};
      const auto& x = m.nodes;
      const Vec3 n = (x[q[2]] - x[q[0]]).cross(x[q[3]] - x[q[1]]);
      const Vec3 c = 0.25 * (x[q[0]] + x[q[1]] + x[q[2]] + x[q[3]]);
      if (n.dot(outward(c)) < 0) std::swap(q[1], q[3]);
      m.quads.push_back(q);
    }
  m.fixed.assign(6 * m.nodes.size(), 0);
  m.load = Eigen::VectorXd::Zero(6 * static_cast<Index>(m.nodes.size()));
  return m;
}

/// Scordelis-Lo roof (MacNeal & Harder 1985): R 25, L 50, 40 deg, t 0.25, E 4.32e8, nu 0, self weight 90
/// per unit area, rigid diaphragms; quarter model. Returns u_z at mid-span of the free edge / 0.3024.
Real scordelis_lo(int n, const ShellSection& section, Real regularisation = 0.0) {
  const Real R = 25, half_length = 25, phi = 40.0 * M_PI / 180.0, t = 0.25, q = 90;
  material::LinearElasticShellMaterial material(4.32e8, 0.0, 1.0);
  StaticShellModel m = structured(
      n, n, [&](Real s, Real a) { return Vec3(R * std::sin(phi * s), half_length * a, R * std::cos(phi * s)); },
      [](const Vec3& c) { return Vec3(c.x(), 0.0, c.z()); });
  auto id = [&](int i, int j) { return j * (n + 1) + i; };
  for (const auto& quad : m.quads) {
    const Real area = 0.5 * (m.nodes[quad[2]] - m.nodes[quad[0]]).cross(m.nodes[quad[3]] - m.nodes[quad[1]]).norm();
    for (int node : quad) m.load(6 * node + 2) -= q * area / 4.0;
  }
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      char* f = &m.fixed[6 * static_cast<std::size_t>(id(i, j))];
      if (j == 0) f[0] = f[2] = 1;               // diaphragm: u_x = u_z = 0
      if (j == n) f[1] = f[3] = f[5] = 1;        // mid-span symmetry
      if (i == 0) f[0] = f[4] = f[5] = 1;        // crown symmetry
    }
  const Eigen::VectorXd u = solve_static(m, section, material, t, regularisation);
  return -u(6 * id(n, n) + 2) / 0.3024;
}

/// Pinched cylinder with rigid diaphragms (MacNeal & Harder 1985): R 300, L 600, t 3, E 3e6, nu 0.3,
/// P = 1 pinching loads; one-eighth model. Returns the radial deflection under the load / 1.8248e-5.
Real pinched_cylinder(int n, const ShellSection& section) {
  const Real R = 300, half_length = 300, t = 3;
  material::LinearElasticShellMaterial material(3.0e6, 0.3, 1.0);
  // theta from 0 (load line, +z) to 90 deg (+x); y from 0 (mid-length, the load) to 300 (diaphragm)
  StaticShellModel m = structured(
      n, n, [&](Real s, Real a) { return Vec3(R * std::sin(0.5 * M_PI * s), half_length * a, R * std::cos(0.5 * M_PI * s)); },
      [](const Vec3& c) { return Vec3(c.x(), 0.0, c.z()); });
  auto id = [&](int i, int j) { return j * (n + 1) + i; };
  m.load(6 * id(0, 0) + 2) = -0.25;  // a quarter of P at the symmetric corner
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      char* f = &m.fixed[6 * static_cast<std::size_t>(id(i, j))];
      if (j == n) f[0] = f[2] = 1;               // diaphragm: u_x = u_z = 0
      if (j == 0) f[1] = f[3] = f[5] = 1;        // mid-length symmetry (y)
      if (i == 0) f[0] = f[4] = f[5] = 1;        // symmetry plane x = 0
      if (i == n) f[2] = f[4] = f[3] = 1;        // symmetry plane z = 0: u_z, theta_x, theta_y
    }
  const Eigen::VectorXd u = solve_static(m, section, material, t);
  return -u(6 * id(0, 0) + 2) / 1.8248e-5;
}

TEST(shell_StaticBenchmarks, ScordelisLoRoofConvergesToMacNealHarder) {
  const ShellSection physical;  // the default
  const Real r4 = scordelis_lo(4, physical), r8 = scordelis_lo(8, physical), r16 = scordelis_lo(16, physical);
  std::printf("Scordelis-Lo u / 0.3024: 4x4 %.4f, 8x8 %.4f, 16x16 %.4f\n", r4, r8, r16);
  // issue 16 acceptance: within 2 % at the literature's finest mesh (16 x 16), converging
  EXPECT_NEAR(r16, 1.0, 0.02) << "4: " << r4 << " 8: " << r8 << " 16: " << r16;
  EXPECT_LT(std::abs(r16 - 1.0), std::abs(r4 - 1.0));
  EXPECT_LT(std::abs(r16 - r8), std::abs(r8 - r4));
  // the seed's coefficient springs (r = 0.1) on the same mesh: the defect the physical model removes
  // (the springs give the drilling rotation no stiffness: where two coplanar facets meet, along the free
  // edge, it is a zero-energy mode of K, a pivot of either sign at round-off; the load does no work on it,
  // and a shift of 1e-12 of the largest diagonal makes K definite without moving u measurably)
  ShellSection seed;
  seed.hourglass_model = HourglassModel::coefficients;
  EXPECT_GT(scordelis_lo(8, seed, 1e-12), 1.3);
}

TEST(shell_StaticBenchmarks, PinchedCylinderApproachesMacNealHarder) {
  const ShellSection physical;
  const Real r8 = pinched_cylinder(8, physical), r16 = pinched_cylinder(16, physical), r32 = pinched_cylinder(32, physical);
  std::printf("pinched cylinder u / 1.8248e-5: 8x8 %.4f, 16x16 %.4f, 32x32 %.4f\n", r8, r16, r32);
  EXPECT_GT(r32, r16);
  EXPECT_NEAR(r32, 1.0, 0.03);
  // one-point / MITC4-class elements reach about 0.95 at 16 x 16 (MacNeal-Harder; Belytschko-Leviathan 1994)
  EXPECT_GT(r16, r8);
  EXPECT_NEAR(r16, 1.0, 0.1) << "8: " << r8 << " 16: " << r16;
}

/// Twisted beam (MacNeal & Harder 1985): L 12, width 1.1, 90 deg pretwist, E 29e6, nu 0.22, clamped root,
/// unit tip load along the tip's width (in-plane) or its normal (out-of-plane); warped elements.
/// Returns the tip displacement along the load / the reference.
Real twisted_beam(int nl, int nw, Real t, bool in_plane, const ShellSection& section) {
  material::LinearElasticShellMaterial material(29.0e6, 0.22, 1.0);
  const Real L = 12.0, w = 1.1, P = t > 0.1 ? 1.0 : 1e-6;
  const Real reference = t > 0.1 ? (in_plane ? 5.424e-3 : 1.754e-3) : (in_plane ? 5.256e-3 : 1.294e-3);
  StaticShellModel m = structured(
      nw, nl,
      [&](Real s, Real a) {
        const Real th = 0.5 * M_PI * a, y = w * (s - 0.5);
        return Vec3(L * a, y * std::cos(th), y * std::sin(th));
      },
      [&](const Vec3& c) {
        const Real th = 0.5 * M_PI * c.x() / L;
        return Vec3(0.0, -std::sin(th), std::cos(th));
      });
  auto id = [&](int i, int j) { return j * (nw + 1) + i; };
  for (int i = 0; i <= nw; ++i) {
    for (int k = 0; k < 6; ++k) m.fixed[6 * static_cast<std::size_t>(id(i, 0)) + k] = 1;
    // tip: width direction +z, normal -y at 90 deg; the load shared equally by the tip nodes
    m.load(6 * id(i, nl) + (in_plane ? 2 : 1)) = P / (nw + 1);
  }
  const Eigen::VectorXd u = solve_static(m, section, material, t);
  Real tip = 0;
  for (int i = 0; i <= nw; ++i) tip += u(6 * id(i, nl) + (in_plane ? 2 : 1)) / (nw + 1);
  return tip / reference;
}

TEST(shell_StaticBenchmarks, TwistedBeamMatchesMacNealHarder) {
  const ShellSection physical;
  const Real thick_in = twisted_beam(12, 2, 0.32, true, physical), thick_out = twisted_beam(12, 2, 0.32, false, physical);
  const Real thin_in = twisted_beam(12, 2, 0.0032, true, physical), thin_out = twisted_beam(12, 2, 0.0032, false, physical);
  const Real fine_in = twisted_beam(24, 4, 0.32, true, physical), fine_out = twisted_beam(24, 4, 0.32, false, physical);
  const Real thin_fine_in = twisted_beam(24, 4, 0.0032, true, physical), thin_fine_out = twisted_beam(24, 4, 0.0032, false, physical);
  std::printf("twisted beam u / ref, 12 x 2: thick in-plane %.4f out-of-plane %.4f, thin in-plane %.4f out-of-plane %.4f;"
              " 24 x 4: thick %.4f %.4f, thin %.4f %.4f\n", thick_in, thick_out, thin_in, thin_out, fine_in, fine_out, thin_fine_in,
              thin_fine_out);
  // the MacNeal-Harder 12 x 2 mesh (warped quads) and 24 x 4: within 5 %, thick and thin; the thick beam
  // within 2 % at both meshes and within 1 % at 24 x 4 (the default drilling penalty 0.05; 0.01 left it
  // 3 % flexible and drifting away under refinement, docs/mpm.md)
  for (Real r : {thick_in, thick_out, thin_in, thin_out, fine_in, fine_out, thin_fine_in, thin_fine_out})
    EXPECT_NEAR(r, 1.0, 0.05);
  for (Real r : {thick_in, thick_out}) EXPECT_NEAR(r, 1.0, 0.02);
  for (Real r : {fine_in, fine_out}) EXPECT_NEAR(r, 1.0, 0.01);
  // the thin beam at 12 x 2 within 2 % (issue 16): 0.987 / 0.981; 0.954 / 0.974 before the warped-facet
  // corrections of the drilling strain's in-plane spin and the shear hourglass's corner directors
  // (test_belytschko_tsay_shell.cpp), 0.980 / 0.977 before the membrane hourglass read the nodes' projections
  EXPECT_NEAR(thin_in, 1.0, 0.02);
  EXPECT_NEAR(thin_out, 1.0, 0.02);
  // with shell.drilling: 0.1 the thick beam converges to the reference: within 1 % at 24 x 4
  ShellSection stiff_drilling;
  stiff_drilling.drilling = 0.1;
  const Real d_in = twisted_beam(24, 4, 0.32, true, stiff_drilling), d_out = twisted_beam(24, 4, 0.32, false, stiff_drilling);
  std::printf("twisted beam 24 x 4 thick, drilling 0.1: %.4f %.4f\n", d_in, d_out);
  EXPECT_NEAR(d_in, 1.0, 0.01);
  EXPECT_NEAR(d_out, 1.0, 0.01);
  // the drilling penalty matters here: without it the thick beam is a near-mechanism
  ShellSection free_drilling;
  free_drilling.drilling = 1e-4;
  EXPECT_GT(twisted_beam(12, 2, 0.32, true, free_drilling), 2.0);
}

}  // namespace
}  // namespace lamina::shell
