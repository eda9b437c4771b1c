// MLS shape function derivatives (seed 004, eqs 1-20, 1-21) against central finite differences of
// phi (first derivatives) and of dphi (second derivatives).
#include <gtest/gtest.h>

#include "mls/mls_shape_functions.hpp"
#include "test_helpers.hpp"

namespace lamina::mls {
namespace {

using testing::jittered_grid;
using testing::random_points;

/// Shape functions as dense vectors over all nodes (zero outside the neighbour list), so that values at
/// neighbouring points with different neighbour lists can be subtracted.
struct Dense {
  Eigen::VectorXd phi;
  Eigen::MatrixXd dphi;   // 3 x N
  Eigen::MatrixXd ddphi;  // 6 x N
};

Dense dense(const MlsShapeFunctions& shape_functions, const Vec3& x, int order) {
  const ShapeFunctionValues values = shape_functions.evaluate(x, order);
  const Index count = shape_functions.node_count();
  Dense result{Eigen::VectorXd::Zero(count), Eigen::MatrixXd::Zero(3, count), Eigen::MatrixXd::Zero(6, count)};
  for (std::size_t j = 0; j < values.neighbours.size(); ++j) {
    const Index node = values.neighbours[j];
    result.phi[node] = values.phi[static_cast<Index>(j)];
    if (order >= 1) result.dphi.col(node) = values.dphi.col(static_cast<Index>(j));
    if (order >= 2) result.ddphi.col(node) = values.ddphi.col(static_cast<Index>(j));
  }
  return result;
}

// Step 1e-5 h: truncation O(step^2 phi''') ~ 1e-10 h^-1, rounding ~ 1e-16 / 1e-5 h ~ 1e-11 h^-1.
// Tolerance: 1e-6 of the largest derivative magnitude at the point.
constexpr Real relative_step = 1e-5;
constexpr Real finite_difference_tolerance = 1e-6;

void expect_matches_finite_differences(const MlsShapeFunctions& shape_functions, Real h, unsigned seed) {
  const int dimension = shape_functions.options().dimension;
  const Vec3 high = Vec3(1.0, dimension >= 2 ? 1.0 : 0.0, dimension >= 3 ? 1.0 : 0.0);
  const PointMatrix points = random_points(8, Vec3::Zero(), high, dimension, seed);
  const Real step = relative_step * h;
  const int row_of[3][3] = {{0, 3, 5}, {3, 1, 4}, {5, 4, 2}};
  for (Index p = 0; p < points.cols(); ++p) {
    const Vec3 x = points.col(p);
    const Dense centre = dense(shape_functions, x, 2);
    const Real first_scale = centre.dphi.cwiseAbs().maxCoeff();
    const Real second_scale = centre.ddphi.cwiseAbs().maxCoeff();
    for (int i = 0; i < dimension; ++i) {
      Vec3 forward = x, backward = x;
      forward[i] += step;
      backward[i] -= step;
      const Dense plus = dense(shape_functions, forward, 1);
      const Dense minus = dense(shape_functions, backward, 1);
      const Eigen::VectorXd first = (plus.phi - minus.phi) / (2.0 * step);
      EXPECT_LT((first.transpose() - centre.dphi.row(i)).cwiseAbs().maxCoeff(), finite_difference_tolerance * first_scale)
          << "dphi/dx" << i << " at x = " << x.transpose();
      for (int j = 0; j < dimension; ++j) {
        const Eigen::VectorXd second = (plus.dphi.row(j) - minus.dphi.row(j)).transpose() / (2.0 * step);
        EXPECT_LT((second.transpose() - centre.ddphi.row(row_of[i][j])).cwiseAbs().maxCoeff(),
                  finite_difference_tolerance * second_scale)
            << "d2phi/dx" << i << "dx" << j << " at x = " << x.transpose();
      }
    }
  }
}

TEST(Derivatives, MatchFiniteDifferencesIn3D) {
  const Real h = 1.0 / 6.0;
  const PointMatrix nodes = jittered_grid({7, 7, 7}, Vec3::Constant(h), 0.25, 3, 7);
  for (Basis basis : {Basis::linear, Basis::quadratic})
    for (Weight weight : {Weight::gauss, Weight::cubic_spline, Weight::quartic_spline})
      for (SupportShape shape : {SupportShape::box, SupportShape::sphere}) {
        MlsOptions options;
        options.basis = basis;
        options.weight = weight;
        options.shape = shape;
        options.kappa = 2.3;
        SCOPED_TRACE(::testing::Message() << to_string(basis) << " " << to_string(weight) << " " << to_string(shape));
        expect_matches_finite_differences(MlsShapeFunctions(nodes, options), h, 8);
      }
}

TEST(Derivatives, MatchFiniteDifferencesInOtherNodeCentredModes) {
  const Real h = 1.0 / 6.0;
  const PointMatrix nodes = jittered_grid({7, 7, 7}, Vec3::Constant(h), 0.25, 3, 9);
  MlsOptions fixed;
  fixed.mode = SupportMode::fixed_radius;
  fixed.radius = Vec3(2.5 * h, 2.2 * h, 2.7 * h);
  expect_matches_finite_differences(MlsShapeFunctions(nodes, fixed), h, 10);
  MlsOptions all;
  all.mode = SupportMode::all;
  all.shape = SupportShape::sphere;
  all.nearest = 30;
  all.scale = 1.3;
  expect_matches_finite_differences(MlsShapeFunctions(nodes, all), h, 11);
}

TEST(Derivatives, MatchFiniteDifferencesIn2DAnd1D) {
  const Real h = 1.0 / 6.0;
  for (int dimension : {1, 2})
    for (SupportShape shape : {SupportShape::box, SupportShape::sphere}) {
      const PointMatrix nodes =
          jittered_grid({7, dimension >= 2 ? 7 : 1, 1}, Vec3::Constant(h), 0.25, dimension, 12);
      MlsOptions options;
      options.dimension = dimension;
      options.shape = shape;
      options.kappa = 2.3;
      SCOPED_TRACE(::testing::Message() << dimension << "D " << to_string(shape));
      expect_matches_finite_differences(MlsShapeFunctions(nodes, options), h, 13);
    }
}

// In the point-centred modes the radius R(x) is frozen at x: the derivatives are those of the MLS
// approximant with that fixed radius, i.e. of the fixed_radius mode with R = R(x) and point-centred weights
// -- checked here through the reproduction property only (see test_reproduction.cpp); here we check
// that order 0/1/2 evaluations agree on phi and on dphi.
TEST(Derivatives, LowerOrdersAgreeWithHigherOrders) {
  const Real h = 1.0 / 6.0;
  const PointMatrix nodes = jittered_grid({7, 7, 7}, Vec3::Constant(h), 0.25, 3, 14);
  for (SupportMode mode : {SupportMode::kappa, SupportMode::nearest}) {
    MlsOptions options;
    options.mode = mode;
    options.kappa = 2.3;
    const MlsShapeFunctions shape_functions(nodes, options);
    const Vec3 x(0.43, 0.52, 0.61);
    const ShapeFunctionValues zero = shape_functions.evaluate(x, 0);
    const ShapeFunctionValues one = shape_functions.evaluate(x, 1);
    const ShapeFunctionValues two = shape_functions.evaluate(x, 2);
    EXPECT_EQ(zero.dphi.cols(), 0);
    EXPECT_EQ(zero.ddphi.cols(), 0);
    EXPECT_EQ(one.ddphi.cols(), 0);
    EXPECT_EQ(one.dphi.cols(), static_cast<Index>(one.neighbours.size()));
    EXPECT_EQ(zero.phi, two.phi);
    EXPECT_EQ(one.dphi, two.dphi);
  }
}

}  // namespace
}  // namespace lamina::mls
