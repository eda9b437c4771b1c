#include "core/gauss_legendre.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace lamina {

void gauss_legendre(int n, std::vector<Real>& points, std::vector<Real>& weights) {
  if (n < 1) throw std::invalid_argument("Gauss-Legendre order must be >= 1");
  points.assign(static_cast<std::size_t>(n), 0.0);
  weights.assign(static_cast<std::size_t>(n), 0.0);
  for (int i = 0; i < (n + 1) / 2; ++i) {
    Real x = std::cos(std::numbers::pi * (i + 0.75) / (n + 0.5));
    Real derivative = 1.0;
    for (int iteration = 0; iteration < 100; ++iteration) {
      Real p0 = 1.0, p1 = x;  // P_0, P_1
      for (int k = 2; k <= n; ++k) {
        const Real p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      if (n == 1) {
        p1 = x;
        p0 = 1.0;
      }
      derivative = n * (x * p1 - p0) / (x * x - 1.0);
      const Real dx = p1 / derivative;
      x -= dx;
      if (std::abs(dx) < 1e-16) break;
    }
    // recompute the derivative at the converged root
    Real p0 = 1.0, p1 = x;
    for (int k = 2; k <= n; ++k) {
      const Real p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
      p0 = p1;
      p1 = p2;
    }
    derivative = n * (x * p1 - p0) / (x * x - 1.0);
    const Real w = 2.0 / ((1.0 - x * x) * derivative * derivative);
    points[static_cast<std::size_t>(i)] = -x;
    points[static_cast<std::size_t>(n - 1 - i)] = x;
    weights[static_cast<std::size_t>(i)] = w;
    weights[static_cast<std::size_t>(n - 1 - i)] = w;
  }
  if (n % 2 == 1) points[static_cast<std::size_t>(n / 2)] = 0.0;
}

}  // namespace lamina
