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
  K.setZero(3 * m, 3 * m);
  f.setZero(3 * m);
  const Real s = alpha * p.weight;
  for (int a = 0; a < 3; ++a) {
    if (!p.constrained[static_cast<std::size_t>(a)]) continue;
    for (Index l = 0; l < m; ++l) {
      f[3 * l + a] += s * sv.phi[l] * p.value[a];
      for (Index k = 0; k < m; ++k) K(3 * k + a, 3 * l + a) += s * sv.phi[k] * sv.phi[l];
    }
  }
}

void nitsche_terms(const mls::ShapeFunctionValues& sv, const ConstraintPoint& p, const material::LinearElastic& material,
                   Real beta, Eigen::MatrixXd& K, Eigen::VectorXd& f) {
  const Index m = static_cast<Index>(sv.neighbours.size());
  const auto T = traction_operator(sv, material, p.normal);
  K.setZero(3 * m, 3 * m);
  f.setZero(3 * m);
  const Real w = p.weight;
  for (int a = 0; a < 3; ++a) {
    if (!p.constrained[static_cast<std::size_t>(a)]) continue;
    // N_a(3k + a) = phi_k: rows/columns of component a
    for (Index k = 0; k < m; ++k) {
      const Real phik = sv.phi[k];
      for (Index col = 0; col < 3 * m; ++col) {
        const Real v = -w * phik * T(a, col);
        K(3 * k + a, col) += v;  // - N^T S T
        K(col, 3 * k + a) += v;  // - T^T S N
      }
      for (Index l = 0; l < m; ++l) K(3 * k + a, 3 * l + a) += w * beta * phik * sv.phi[l];
      f[3 * k + a] += w * beta * phik * p.value[a];
    }
    for (Index col = 0; col < 3 * m; ++col) f[col] -= w * T(a, col) * p.value[a];
  }
}

}  // namespace lamina::efg
