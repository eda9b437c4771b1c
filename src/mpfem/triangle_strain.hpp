#pragma once
// Strain operator of a linear (t3) triangle: [exx, eyy, gxy] of its six dofs (u_x, u_y per corner)
// from the corner shape-function gradients; the t3 reference element and the error norms use it.
#include <Eigen/Dense>

#include "core/types.hpp"

namespace lamina::mpfem {

inline Eigen::Matrix<Real, 3, 6> triangle_strain_operator(const Eigen::Matrix<Real, 2, 3>& g) {
  Eigen::Matrix<Real, 3, 6> b = Eigen::Matrix<Real, 3, 6>::Zero();
  for (int a = 0; a < 3; ++a) {
    b(0, 2 * a) = g(0, a);
    b(1, 2 * a + 1) = g(1, a);
    b(2, 2 * a) = g(1, a);
    b(2, 2 * a + 1) = g(0, a);
  }
  return b;
}

}  // namespace lamina::mpfem
