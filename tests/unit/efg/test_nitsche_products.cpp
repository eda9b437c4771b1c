// The Nitsche stiffness of a boundary group, K = sum over points and held components of n v^T + v n^T
// (essential_boundary.hpp), formed from the columns kept by component: into a dense block and straight
// into a sparse pattern, against the sum of the outer products written out here.
#include <gtest/gtest.h>

#include <random>

#include "efg/essential_boundary.hpp"

namespace lamina::efg {
namespace {

TEST(NitscheProducts, DenseBlockAndPatternScatterEqualTheSumOfOuterProducts) {
  const Index m = 7;
  std::mt19937 generator(5);
  std::uniform_real_distribution<Real> uniform(-1.0, 1.0);
  // three points: the first holds x y z, the second z only, the third x and z (component y: one point)
  const std::array<std::array<bool, 3>, 3> held{{{true, true, true}, {false, false, true}, {true, false, true}}};
  NitscheColumns columns;
  columns.reset(m, 3);
  Eigen::MatrixXd reference = Eigen::MatrixXd::Zero(3 * m, 3 * m);
  for (const auto& point : held) {
    Eigen::VectorXd phi(m);
    for (Index k = 0; k < m; ++k) phi[k] = uniform(generator);
    for (int a = 0; a < 3; ++a) {
      if (!point[static_cast<std::size_t>(a)]) continue;
      Eigen::VectorXd n = Eigen::VectorXd::Zero(3 * m), v(3 * m);
      for (Index k = 0; k < m; ++k) n[3 * k + a] = phi[k];
      for (Index i = 0; i < 3 * m; ++i) v[i] = uniform(generator);
      const Index c = columns.count[static_cast<std::size_t>(a)]++;
      columns.phi[static_cast<std::size_t>(a)].col(c) = phi;
      columns.v[static_cast<std::size_t>(a)].col(c) = v;
      reference += n * v.transpose() + v * n.transpose();
    }
  }
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(3 * m, 3 * m);
  add_nitsche_products(columns, dense);
  EXPECT_LT((dense - reference).cwiseAbs().maxCoeff(), 1e-14);

  // nodes 2, 4, ..., 14 of 16 in a symmetric pattern that also holds other groups
  IndexList nodes;
  for (Index k = 0; k < m; ++k) nodes.push_back(2 * k + 2);
  const std::vector<IndexList> groups{nodes, {0, 1, 2}, {13, 14, 15}};
  for (const bool symmetric : {true, false}) {
    const solve::BlockPattern pattern(16, 3, groups, symmetric);
    std::vector<Real> values(static_cast<std::size_t>(pattern.nonzeros()), 0.0);
    scatter_nitsche_products(columns, pattern, nodes, values.data());
    const solve::SparseMatrix K = pattern.matrix(values);
    for (Index J = 0; J < m; ++J)
      for (Index I = 0; I < m; ++I)
        for (int b = 0; b < 3; ++b)
          for (int a = 0; a < 3; ++a) {
            const Index row = 3 * nodes[static_cast<std::size_t>(I)] + a, column = 3 * nodes[static_cast<std::size_t>(J)] + b;
            if (symmetric && row > column) continue;
            EXPECT_NEAR(K.coeff(row, column), reference(3 * I + a, 3 * J + b), 1e-14) << row << ", " << column;
          }
    Real total = 0.0;
    for (const Real value : values) total += std::abs(value);
    Real expected = 0.0;
    for (Index j = 0; j < 3 * m; ++j)
      for (Index i = 0; i < 3 * m; ++i)
        if (!symmetric || 3 * nodes[static_cast<std::size_t>(i / 3)] + i % 3 <= 3 * nodes[static_cast<std::size_t>(j / 3)] + j % 3)
          expected += std::abs(reference(i, j));
    EXPECT_NEAR(total, expected, 1e-12) << "nothing written outside the group's entries";
  }
}

}  // namespace
}  // namespace lamina::efg
