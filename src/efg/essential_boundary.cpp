#include "efg/essential_boundary.hpp"

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

Index nitsche_columns(const mls::ShapeFunctionValues& sv, const ConstraintPoint& p, const material::LinearElastic& material,
                      Real beta, Eigen::MatrixXd& n_columns, Eigen::MatrixXd& v_columns, Index column, Eigen::VectorXd& f) {
  const Index m = static_cast<Index>(sv.neighbours.size());
  const auto T = traction_operator(sv, material, p.normal);
  const Real w = p.weight;
  for (int a = 0; a < 3; ++a) {
    if (!p.constrained[static_cast<std::size_t>(a)]) continue;
    auto n = n_columns.col(column);
    auto v = v_columns.col(column);
    n.setZero();
    for (Index k = 0; k < m; ++k) n[3 * k + a] = sv.phi[k];
    v = -w * T.row(a).transpose() + (0.5 * w * beta) * n;
    f += (w * beta * p.value[a]) * n - (w * p.value[a]) * T.row(a).transpose();
    ++column;
  }
  return column;
}

void add_nitsche_products(const Eigen::MatrixXd& n_columns, const Eigen::MatrixXd& v_columns, Index columns,
                          Eigen::MatrixXd& K, bool upper_only) {
  if (columns == 0) return;
  const auto n = n_columns.leftCols(columns);
  const auto v = v_columns.leftCols(columns);
  if (upper_only) {
    K.triangularView<Eigen::Upper>() += n * v.transpose();
    K.triangularView<Eigen::Upper>() += v * n.transpose();
  } else {
    K.noalias() += n * v.transpose();
    K.noalias() += v * n.transpose();
  }
}

}  // namespace lamina::efg
