#include "pd/plate_fit.hpp"

#include <Eigen/Eigenvalues>

#include <cmath>

namespace lamina::pd {

int plate_fit_weights(const Eigen::Matrix2Xd& xi, const Eigen::VectorXd& v, Real horizon, int max_degree,
                      Eigen::Matrix2Xd& first, Eigen::Matrix3Xd* second) {
  const Index count = xi.cols();
  first.resize(2, count);
  for (int degree = max_degree; degree >= 1; --degree) {
    const int terms = degree == 3 ? 9 : degree == 2 ? 5 : 2;
    if (degree > 1 && count < terms + 2) continue;
    // monomials of the scaled bond (x, y) = xi / horizon: x, y, x^2, x y, y^2, x^3, x^2 y, x y^2, y^3
    Eigen::MatrixXd basis(terms, count);
    for (Index b = 0; b < count; ++b) {
      const Real x = xi(0, b) / horizon, y = xi(1, b) / horizon;
      Eigen::VectorXd phi(terms);
      phi.head<2>() << x, y;
      if (degree >= 2) phi.segment<3>(2) << x * x, x * y, y * y;
      if (degree >= 3) phi.segment<4>(5) << x * x * x, x * x * y, x * y * y, y * y * y;
      basis.col(b) = phi;
    }
    const Eigen::MatrixXd gram = basis * v.asDiagonal() * basis.transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(gram);
    const Real smallest = eig.eigenvalues()[0], largest = eig.eigenvalues()[terms - 1];
    if (degree > 1 && !(smallest > 1e-7 * largest)) continue;
    // coefficients c = G^-1 sum_b v_b phi_b (f_j - f_i): per bond, G^-1 phi_b (terms x count)
    const Eigen::MatrixXd solved =
        eig.eigenvectors() * eig.eigenvalues().cwiseInverse().asDiagonal() * eig.eigenvectors().transpose() * basis;
    first = solved.topRows<2>() / horizon;
    if (second && degree >= 2) {
      const Real h2 = horizon * horizon;
      second->resize(3, count);
      second->row(0) = 2.0 * solved.row(2) / h2;  // f = c x^2 / h^2: f_,xx = 2 c / h^2
      second->row(1) = 2.0 * solved.row(4) / h2;
      second->row(2) = solved.row(3) / h2;
    }
    return degree;
  }
  return 1;
}

std::unique_ptr<PeridynamicBody> column_families(const PointMatrix& centres, const Eigen::VectorXd& volumes,
                                                 const Eigen::VectorXd& young, const Eigen::VectorXd& poisson,
                                                 const BodyOptions& options, Real thickness) {
  BodyOptions in_plane = options;
  in_plane.kinematics = Kinematics::plane_stress;
  in_plane.surface_correction = SurfaceCorrection::none;
  in_plane.cell_size = std::sqrt(volumes.mean() / thickness);
  return std::make_unique<PeridynamicBody>(centres, volumes, young, poisson, in_plane);
}

}  // namespace lamina::pd
