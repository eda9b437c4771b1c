#pragma once
// Shared fixtures of the MLS unit tests: regular / jittered node grids and random quadratic fields.
#include <array>
#include <random>

#include "core/types.hpp"

namespace lamina::mls::testing {

/// Regular grid of counts[0] x counts[1] x counts[2] nodes with spacing h, starting at the origin.
inline PointMatrix regular_grid(const std::array<int, 3>& counts, const Vec3& h) {
  PointMatrix nodes(3, counts[0] * counts[1] * counts[2]);
  Index column = 0;
  for (int k = 0; k < counts[2]; ++k)
    for (int j = 0; j < counts[1]; ++j)
      for (int i = 0; i < counts[0]; ++i) nodes.col(column++) = Vec3(i * h[0], j * h[1], k * h[2]);
  return nodes;
}

/// Regular grid with every node moved by a uniform random amount in [-amplitude, amplitude] * h per
/// axis (only along the first `dimension` axes).
inline PointMatrix jittered_grid(const std::array<int, 3>& counts, const Vec3& h, Real amplitude, int dimension,
                                 unsigned seed) {
  PointMatrix nodes = regular_grid(counts, h);
  std::mt19937 generator(seed);
  std::uniform_real_distribution<Real> uniform(-amplitude, amplitude);
  for (Index i = 0; i < nodes.cols(); ++i)
    for (int d = 0; d < dimension; ++d) nodes(d, i) += uniform(generator) * h[d];
  return nodes;
}

/// Uniform random points in the box [low, high] (coordinates d >= dimension are zero).
inline PointMatrix random_points(Index count, const Vec3& low, const Vec3& high, int dimension, unsigned seed) {
  std::mt19937 generator(seed);
  std::uniform_real_distribution<Real> uniform(0.0, 1.0);
  PointMatrix points = PointMatrix::Zero(3, count);
  for (Index i = 0; i < count; ++i)
    for (int d = 0; d < dimension; ++d) points(d, i) = low[d] + uniform(generator) * (high[d] - low[d]);
  return points;
}

/// u(x) = c + g.x + x^T H x / 2 (H symmetric) restricted to the first `dimension` coordinates.
struct QuadraticField {
  Real constant = 0.0;
  Vec3 linear = Vec3::Zero();
  Mat3 hessian = Mat3::Zero();

  static QuadraticField random(int dimension, bool quadratic, unsigned seed) {
    std::mt19937 generator(seed);
    std::uniform_real_distribution<Real> uniform(-1.0, 1.0);
    QuadraticField field;
    field.constant = uniform(generator);
    for (int d = 0; d < dimension; ++d) field.linear[d] = uniform(generator);
    if (quadratic) {
      for (int a = 0; a < dimension; ++a)
        for (int b = a; b < dimension; ++b) field.hessian(a, b) = field.hessian(b, a) = uniform(generator);
    }
    return field;
  }
  Real value(const Vec3& x) const { return constant + linear.dot(x) + 0.5 * x.dot(hessian * x); }
  Vec3 gradient(const Vec3& x) const { return linear + hessian * x; }
  Eigen::VectorXd nodal_values(const PointMatrix& nodes) const {
    Eigen::VectorXd values(nodes.cols());
    for (Index i = 0; i < nodes.cols(); ++i) values[i] = value(nodes.col(i));
    return values;
  }
};

}  // namespace lamina::mls::testing
