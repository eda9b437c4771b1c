#include "core/shell_mesh.hpp"

#include <cmath>

namespace lamina {

Real ShellMesh::area() const {
  const Real g = 1.0 / std::sqrt(3.0);
  Real total = 0.0;
  for (Index e = 0; e < quads.cols(); ++e) {
    Eigen::Matrix<Real, 3, 4> x;
    for (int a = 0; a < 4; ++a) x.col(a) = nodes.col(quads(a, e));
    for (Real xi : {-g, g})
      for (Real eta : {-g, g}) {
        const Vec3 dxi = 0.25 * (-(1 - eta) * x.col(0) + (1 - eta) * x.col(1) + (1 + eta) * x.col(2) - (1 + eta) * x.col(3));
        const Vec3 deta = 0.25 * (-(1 - xi) * x.col(0) - (1 + xi) * x.col(1) + (1 + xi) * x.col(2) + (1 - xi) * x.col(3));
        total += dxi.cross(deta).norm();
      }
  }
  return total;
}

}  // namespace lamina
