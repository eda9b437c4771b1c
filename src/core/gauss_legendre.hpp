#pragma once
// Gauss-Legendre quadrature on [-1, 1]: the points (ascending, symmetric) and weights of the n-point rule,
// for the EFG background cells and the Gauss-point layers of the peridynamic plate lattice.
#include <vector>

#include "core/types.hpp"

namespace lamina {

/// Gauss-Legendre points (ascending) and weights on [-1, 1] (n >= 1), by Newton iteration on P_n;
/// exact for polynomials up to degree 2 n - 1. Throws std::invalid_argument for n < 1.
void gauss_legendre(int n, std::vector<Real>& points, std::vector<Real>& weights);

}  // namespace lamina
