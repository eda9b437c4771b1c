// CPDI2 domains (seed 000 eqs (15)-(16)) and the sparse background grid: weights reproduce
// constants and linear fields, mass shares equal the exact integrals of the corner shape
// functions, bad elements are found, transfers do not depend on the thread count.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <random>

#include "mpm/background_grid.hpp"
#include "mpm/cpdi2_domains.hpp"

namespace lamina::mpm {
namespace {

TEST(mpm_Cpdi2Domains, CornerWeightsAreExactIntegralsOfTheBilinearShapes) {
  Eigen::Matrix<Real, 2, 4> p;
  p << 0.0, 2.0, 2.6, -0.3, 0.0, 0.2, 1.7, 1.1;  // a general convex quad
  const Cpdi2CornerWeights w = cpdi2_corner_weights(p);
  // reference: 2 x 2 Gauss integration of N_c over the quad, divided by its area
  const Real g = 1.0 / std::sqrt(3.0);
  Eigen::Matrix<Real, 1, 4> integral = Eigen::Matrix<Real, 1, 4>::Zero();
  Real area = 0;
  for (Real xi : {-g, g})
    for (Real eta : {-g, g}) {
      const Real N[4] = {0.25 * (1 - xi) * (1 - eta), 0.25 * (1 + xi) * (1 - eta), 0.25 * (1 + xi) * (1 + eta), 0.25 * (1 - xi) * (1 + eta)};
      const Eigen::Vector2d dxi = 0.25 * (-(1 - eta) * p.col(0) + (1 - eta) * p.col(1) + (1 + eta) * p.col(2) - (1 + eta) * p.col(3));
      const Eigen::Vector2d deta = 0.25 * (-(1 - xi) * p.col(0) - (1 + xi) * p.col(1) + (1 + xi) * p.col(2) + (1 - xi) * p.col(3));
      const Real J = dxi.x() * deta.y() - dxi.y() * deta.x();
      area += J;
      for (int c = 0; c < 4; ++c) integral[c] += N[c] * J;
    }
  EXPECT_NEAR(w.area, area, 1e-12);
  for (int c = 0; c < 4; ++c) EXPECT_NEAR(w.value[c], integral[c] / area, 1e-12) << "corner " << c;
  EXPECT_NEAR(w.value.sum(), 1.0, 1e-14);
  // gradient weights: sum zero, exact for linear fields (sum_c g_c x_c^T = I)
  EXPECT_LT(w.gradient.rowwise().sum().cwiseAbs().maxCoeff(), 1e-14);
  const Eigen::Matrix2d identity = w.gradient * p.transpose();
  EXPECT_LT((identity - Eigen::Matrix2d::Identity()).cwiseAbs().maxCoeff(), 1e-13);
  // parallelogram: a quarter each
  Eigen::Matrix<Real, 2, 4> q;
  q << 0, 2, 2.5, 0.5, 0, 0, 1, 1;
  const Cpdi2CornerWeights wq = cpdi2_corner_weights(q);
  for (int c = 0; c < 4; ++c) EXPECT_NEAR(wq.value[c], 0.25, 1e-14);
}

ShellMesh strip(int nx, int ny, Real lx, Real ly) {
  ShellMesh m;
  m.thickness = 0.1;
  m.nodes.resize(3, (nx + 1) * (ny + 1));
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) m.nodes.col(j * (nx + 1) + i) = Vec3(lx * i / nx, ly * j / ny, 0.0);
  m.quads.resize(4, nx * ny);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const Index n0 = j * (nx + 1) + i;
      m.quads.col(j * nx + i) << n0, n0 + 1, n0 + nx + 2, n0 + nx + 1;
    }
  return m;
}

TEST(mpm_Cpdi2Domains, MassAndScaledRotationalInertia) {
  const ShellMesh m = strip(4, 2, 4.0, 1.0);
  const Cpdi2Domains d(m, 2.0);
  ASSERT_TRUE(d.defects().empty());
  EXPECT_NEAR(d.node_mass().sum(), 2.0 * 0.1 * 4.0, 1e-12);
  // each element 1 x 0.5: A/8 = 0.0625 > h^2/12
  EXPECT_NEAR(d.node_inertia().sum(), 2.0 * 0.1 * 4.0 * 0.0625, 1e-12);
}

TEST(mpm_Cpdi2Domains, BadElementsAreReported) {
  ShellMesh inverted = strip(3, 1, 3.0, 1.0);
  std::swap(inverted.quads(1, 1), inverted.quads(3, 1));  // clockwise element between counter-clockwise ones
  const Cpdi2Domains a(inverted, 1.0);
  ASSERT_FALSE(a.defects().empty());
  EXPECT_NE(a.defects().front().what.find("orientation"), std::string::npos);

  ShellMesh zero = strip(2, 1, 2.0, 1.0);
  zero.nodes.col(1) = zero.nodes.col(0);  // collapse an edge... and make the element a triangle with zero area
  zero.nodes.col(4) = zero.nodes.col(3);
  const Cpdi2Domains b(zero, 1.0);
  ASSERT_FALSE(b.defects().empty());

  ShellMesh bowtie = strip(1, 1, 1.0, 1.0);
  bowtie.nodes.col(2).swap(bowtie.nodes.col(3));  // self-intersecting
  const Cpdi2Domains c(bowtie, 1.0);
  ASSERT_FALSE(c.defects().empty());
}

TEST(mpm_BackgroundGrid, ShapeFunctionsReproduceLinearFields) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<Real> u(-2.0, 5.0);
  PointMatrix x(3, 200);
  for (Index c = 0; c < x.cols(); ++c) x.col(c) = Vec3(u(rng), u(rng), 0.1 * u(rng));
  BackgroundGrid grid(Vec3(-3, -3, -3), 0.37);
  grid.locate(x);
  for (Index c = 0; c < x.cols(); ++c) {
    Real sum = 0;
    Vec3 position = Vec3::Zero();
    for (int k = 0; k < BackgroundGrid::kNodesPerCorner; ++k) {
      sum += grid.weight(c, k);
      position += grid.weight(c, k) * grid.node_position(grid.slot(c, k));
    }
    EXPECT_NEAR(sum, 1.0, 1e-13);
    EXPECT_LT((position - x.col(c)).norm(), 1e-12);
  }
}

TEST(mpm_BackgroundGrid, TransfersConserveAndDoNotDependOnThreads) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<Real> u(0.0, 30.0);
  PointMatrix x(3, 5000), q(3, 5000);
  for (Index c = 0; c < x.cols(); ++c) {
    x.col(c) = Vec3(u(rng), u(rng), u(rng));
    q.col(c) = Vec3(u(rng), -u(rng), 1.0);
  }
  const Eigen::Matrix3Xd mask = Eigen::Matrix3Xd::Ones(3, x.cols());
  BackgroundGrid grid(Vec3::Zero(), 1.0);
  grid.locate(x);
  Eigen::Matrix3Xd g1, g2;
  PointMatrix back1, back2;
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  grid.scatter(q, mask, g1);
  grid.gather(g1, back1);
  omp_set_num_threads(2);
  grid.scatter(q, mask, g2);
  grid.gather(g2, back2);
  omp_set_num_threads(threads);
  EXPECT_EQ((g1 - g2).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((back1 - back2).cwiseAbs().maxCoeff(), 0.0);
  // P2G conserves the total
  EXPECT_LT((g1.rowwise().sum() - q.rowwise().sum()).cwiseAbs().maxCoeff(), 1e-9 * q.cwiseAbs().sum());
  // moving without changing cells keeps the connectivity
  PointMatrix y = x;
  y.array() += 0.0;
  EXPECT_FALSE(grid.locate(y));
}


// The one-pass P2G of a step equals three scatter() calls bit for bit. A grid that locates only the
// corners within two cells of a block's bounding box (several ranks) gives the block's corners the same
// G2P values (gather and the step's fused gather_and_finish), bit for bit, also after corners moved, left
// and joined that set (the re-binning's merge of the moved corners into the kept order).
TEST(mpm_BackgroundGrid, OnePassAndRestrictedTransfersEqualTheWholeOnes) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<Real> u(0.0, 20.0);
  const Index n = 3000;
  PointMatrix x(3, n), v(3, n), f(3, n);
  Eigen::VectorXd mass(n);
  Eigen::Matrix3Xd mask = Eigen::Matrix3Xd::Ones(3, n);
  for (Index c = 0; c < n; ++c) {
    // corners ordered along x: the block [first, last) is a slab
    x.col(c) = Vec3(20.0 * static_cast<Real>(c) / static_cast<Real>(n), u(rng), 0.1 * u(rng));
    v.col(c) = Vec3(u(rng), -u(rng), 0.5 * u(rng));
    f.col(c) = Vec3(-u(rng), u(rng), u(rng));
    mass[c] = 1.0 + u(rng);
    if (c % 7 == 0) mask(c % 3, c) = 0.0;
  }
  const Real cell = 0.7;
  BackgroundGrid grid(Vec3::Constant(-1.0), cell), near(Vec3::Constant(-1.0), cell);
  grid.locate(x);
  Eigen::Matrix3Xd m3(3, n), p3(3, n), gm, gp, gf;
  for (Index c = 0; c < n; ++c) m3.col(c).setConstant(mass[c]), p3.col(c) = mass[c] * v.col(c);
  grid.scatter(m3, mask, gm);
  grid.scatter(p3, mask, gp);
  grid.scatter(f, mask, gf);
  Eigen::Matrix3Xd om, op, of;
  grid.scatter_mass_momentum_force(mass, v, f, mask, om, op, of);
  EXPECT_EQ(om, gm);
  EXPECT_EQ(op, gp);
  EXPECT_EQ(of, gf);

  const Index first = 1000, last = 2000;
  std::vector<char> include(static_cast<std::size_t>(n));
  auto compare = [&](const char* when) {
    grid.locate(x);
    Vec3 low = x.block(0, first, 3, last - first).rowwise().minCoeff(), high = x.block(0, first, 3, last - first).rowwise().maxCoeff();
    low.array() -= 2.01 * cell;
    high.array() += 2.01 * cell;
    Index included = 0;
    for (Index c = 0; c < n; ++c) {
      include[static_cast<std::size_t>(c)] = (x.col(c).array() >= low.array()).all() && (x.col(c).array() <= high.array()).all();
      included += include[static_cast<std::size_t>(c)];
    }
    ASSERT_LT(included, n) << when;
    near.locate(x, &include);
    ASSERT_LT(near.active_nodes(), grid.active_nodes()) << when;
    Eigen::Matrix3Xd wm, wp, wf, nm, np, nf;
    grid.scatter_mass_momentum_force(mass, v, f, mask, wm, wp, wf);
    near.scatter_mass_momentum_force(mass, v, f, mask, nm, np, nf);
    PointMatrix whole, block;
    grid.gather(wf, whole);
    near.gather(nf, block, first, last);
    for (Index c = first; c < last; ++c) ASSERT_EQ(block.col(c), whole.col(c)) << when << " corner " << c;
    grid.gather(wp, whole);
    near.gather(np, block, first, last);
    for (Index c = first; c < last; ++c) ASSERT_EQ(block.col(c), whole.col(c)) << when << " corner " << c;
    // the step's fused G2P (two arrays in one pass, handed to a callback) gives the same values
    PointMatrix fused_f(3, n), fused_p(3, n);
    near.gather_and_finish(nf, np, first, last, [&](Index c, const Vec3& a, const Vec3& b) {
      fused_f.col(c) = a;
      fused_p.col(c) = b;
    });
    for (Index c = first; c < last; ++c) ASSERT_EQ(fused_p.col(c), whole.col(c)) << when << " corner " << c;
    grid.gather(wf, whole);
    for (Index c = first; c < last; ++c) ASSERT_EQ(fused_f.col(c), whole.col(c)) << when << " corner " << c;
  };
  compare("first locate");
  // move every corner by up to two cells: some change cell, some leave the set near the block, some join
  for (Index c = 0; c < n; ++c) x.col(c) += Vec3(2.0 * cell * (u(rng) / 10.0 - 1.0), 0.3 * u(rng), 0.0);
  compare("after a move");
  for (Index c = 0; c < n; c += 3) x(0, c) += 0.05;
  compare("after a small move");
}

}  // namespace
}  // namespace lamina::mpm
