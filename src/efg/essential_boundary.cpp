#include "efg/essential_boundary.hpp"

#include <algorithm>
#include <stdexcept>
#include <vector>

namespace lamina::efg {

Eigen::Matrix<Real, 3, Eigen::Dynamic> traction_operator(const mls::ShapeFunctionValues& sv,
                                                         const material::LinearElastic& material, const Vec3& n) {
  const Index m = static_cast<Index>(sv.neighbours.size());
  const Real lambda = material.lambda(), mu = material.mu();
  Eigen::Matrix<Real, 3, Eigen::Dynamic> T(3, 3 * m);
  for (Index k = 0; k < m; ++k) {
    const Vec3 g = sv.dphi.col(k);
    const Real gn = g.dot(n);
    for (int b = 0; b < 3; ++b)
      for (int i = 0; i < 3; ++i) T(i, 3 * k + b) = lambda * g[b] * n[i] + mu * ((i == b ? gn : 0.0) + g[i] * n[b]);
  }
  return T;
}

void penalty_terms(const mls::ShapeFunctionValues& sv, const ConstraintPoint& p, Real alpha, Eigen::MatrixXd& K,
                   Eigen::VectorXd& f) {
  const Index m = static_cast<Index>(sv.neighbours.size());
  const Real s = alpha * p.weight;
  for (int a = 0; a < 3; ++a) {
    if (!p.constrained[static_cast<std::size_t>(a)]) continue;
    for (Index l = 0; l < m; ++l) {
      f[3 * l + a] += s * sv.phi[l] * p.value[a];
      for (Index k = 0; k < m; ++k) K(3 * k + a, 3 * l + a) += s * sv.phi[k] * sv.phi[l];
    }
  }
}

void NitscheColumns::reset(Index m, Index points) {
  for (int a = 0; a < 3; ++a) {
    if (phi[a].rows() != m || phi[a].cols() < points) phi[a].resize(m, points);
    if (v[a].rows() != 3 * m || v[a].cols() < points) v[a].resize(3 * m, points);
    count[a] = 0;
  }
}

void nitsche_columns(const mls::ShapeFunctionValues& sv, const ConstraintPoint& p, const material::LinearElastic& material,
                     Real beta, NitscheColumns& columns, Eigen::VectorXd& f) {
  const Index m = static_cast<Index>(sv.neighbours.size());
  const auto T = traction_operator(sv, material, p.normal);
  const Real w = p.weight;
  for (int a = 0; a < 3; ++a) {
    if (!p.constrained[static_cast<std::size_t>(a)]) continue;
    const Index column = columns.count[a]++;
    columns.phi[a].col(column) = sv.phi;
    auto v = columns.v[a].col(column);
    v = -w * T.row(a).transpose();
    const Real value = p.value[a];
    for (Index k = 0; k < m; ++k) {
      v[3 * k + a] += (0.5 * w * beta) * sv.phi[k];
      f[3 * k + a] += (w * beta * value) * sv.phi[k];
    }
    f -= (w * value) * T.row(a).transpose();
  }
}

void NitscheColumns::form_products() {
  // column by column (matrix-vector products): Eigen's GEMM is no gain for so few points, and above 50,000
  // multiply-adds it splits a product over the OpenMP threads and spins while the second one wakes
  const Index m = nodes();
  products.resize(m, 9 * m);
  for (int a = 0; a < 3; ++a) {
    const auto c = count[static_cast<std::size_t>(a)];
    const auto& p = phi[static_cast<std::size_t>(a)];
    const auto& w = v[static_cast<std::size_t>(a)];
    if (c == 0) {
      products.middleCols(3 * m * a, 3 * m).setZero();
      continue;
    }
    for (Index j = 0; j < 3 * m; ++j) products.col(3 * m * a + j).noalias() = p.leftCols(c) * w.row(j).head(c).transpose();
  }
}

void add_nitsche_products(NitscheColumns& columns, Eigen::MatrixXd& K) {
  columns.form_products();
  const Index m = K.rows() / 3;
  const Eigen::MatrixXd& P = columns.products;
  for (Index J = 0; J < m; ++J)
    for (int b = 0; b < 3; ++b)
      for (Index I = 0; I < m; ++I)
        for (int a = 0; a < 3; ++a) K(3 * I + a, 3 * J + b) += P(I, 3 * m * a + 3 * J + b) + P(J, 3 * m * b + 3 * I + a);
}

void scatter_nitsche_products(NitscheColumns& columns, const solve::BlockPattern& pattern, const IndexList& nodes,
                              Real* values, Index offset) {
  columns.form_products();
  const Index m = static_cast<Index>(nodes.size());
  const bool symmetric = pattern.symmetric();
  const Eigen::MatrixXd& P = columns.products;
  // rank of every pattern neighbour of J by a table (entries of earlier columns are stale: checked below)
  std::vector<int>& rank_of = columns.rank_of;
  if (rank_of.size() != static_cast<std::size_t>(pattern.nodes())) rank_of.assign(static_cast<std::size_t>(pattern.nodes()), -1);
  for (Index jj = 0; jj < m; ++jj) {
    const Index J = nodes[static_cast<std::size_t>(jj)];
    const Index* neighbour = pattern.neighbours_begin(J);
    const Index neighbours = static_cast<Index>(pattern.neighbours_end(J) - neighbour);
    for (Index k = 0; k < neighbours; ++k) rank_of[static_cast<std::size_t>(neighbour[k])] = static_cast<int>(k);
    const Index end = symmetric ? jj + 1 : m;
    Index start[3];
    for (int b = 0; b < 3; ++b) start[b] = pattern.column_start(3 * J + b) - offset;
    for (Index ii = 0; ii < end; ++ii) {
      const Index I = nodes[static_cast<std::size_t>(ii)];
      const Index rank = rank_of[static_cast<std::size_t>(I)];
      if (rank < 0 || rank >= neighbours || neighbour[rank] != I)
        throw std::logic_error("Nitsche terms: a node pair of a boundary group outside the pattern");
      const Index r = 3 * rank;
      for (int b = 0; b < 3; ++b) {
        Real* entry = values + start[b] + r;
        const int last_a = (symmetric && I == J) ? b : 2;
        for (int a = 0; a <= last_a; ++a) entry[a] += P(ii, 3 * m * a + 3 * jj + b) + P(jj, 3 * m * b + 3 * ii + a);
      }
    }
  }
}

}  // namespace lamina::efg
