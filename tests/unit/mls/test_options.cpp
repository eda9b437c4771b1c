// MLS options validation, basis sizes and batch evaluation (parallel, deterministic).
#include <gtest/gtest.h>

#include "core/error.hpp"
#include "mls/basis.hpp"
#include "mls/mls_shape_functions.hpp"
#include "test_helpers.hpp"

namespace lamina::mls {
namespace {

using testing::jittered_grid;
using testing::random_points;

TEST(MlsOptions, BasisSizes) {
  EXPECT_EQ(basis_size(1, Basis::linear), 2);
  EXPECT_EQ(basis_size(1, Basis::quadratic), 3);
  EXPECT_EQ(basis_size(2, Basis::linear), 3);
  EXPECT_EQ(basis_size(2, Basis::quadratic), 6);
  EXPECT_EQ(basis_size(3, Basis::linear), 4);
  EXPECT_EQ(basis_size(3, Basis::quadratic), 10);
  EXPECT_EQ((PolynomialBasis<3, Basis::quadratic>::size), 10);
  Real p[10];
  const Real z[3] = {2.0, 3.0, 5.0};
  PolynomialBasis<3, Basis::quadratic>::values(z, p);
  const Real expected[10] = {1, 2, 3, 5, 4, 9, 25, 6, 15, 10};
  for (int k = 0; k < 10; ++k) EXPECT_EQ(p[k], expected[k]) << k;
}

TEST(MlsOptions, InvalidValuesAreInputErrors) {
  const PointMatrix nodes = jittered_grid({4, 4, 4}, Vec3::Constant(0.1), 0.1, 3, 1);
  auto expect_invalid = [&](MlsOptions options, const std::string& key) {
    try {
      MlsShapeFunctions shape_functions(nodes, options);
      FAIL() << "expected InputError for " << key;
    } catch (const InputError& error) {
      EXPECT_NE(std::string(error.what()).find(key), std::string::npos) << error.what();
    }
  };
  MlsOptions options;
  options.dimension = 4;
  expect_invalid(options, "mls.dimension");
  options = {};
  options.kappa = 0.0;
  expect_invalid(options, "mls.kappa");
  options = {};
  options.mode = SupportMode::fixed_radius;  // radius left at zero
  expect_invalid(options, "mls.radius");
  options = {};
  options.mode = SupportMode::nearest;
  options.nearest = 0;
  expect_invalid(options, "mls.nearest");
  options = {};
  options.mode = SupportMode::variable;
  options.scale = -1.0;
  expect_invalid(options, "mls.scale");
  options = {};
  options.max_condition = 0.5;
  expect_invalid(options, "mls.max_condition");
  options = {};
  options.gauss_beta = 0.0;
  expect_invalid(options, "mls.gauss_beta");
  EXPECT_THROW(MlsShapeFunctions(PointMatrix(3, 0), MlsOptions{}), InputError);
  EXPECT_THROW(MlsShapeFunctions(nodes, MlsOptions{}, Eigen::Matrix3Xd::Ones(3, 5)), InputError);
  const MlsShapeFunctions valid(nodes, MlsOptions{});
  EXPECT_THROW(valid.evaluate(Vec3(0.1, 0.1, 0.1), 3), std::invalid_argument);
}

TEST(EvaluateAll, EqualsPointwiseEvaluationAndIsDeterministic) {
  const PointMatrix nodes = jittered_grid({8, 8, 8}, Vec3::Constant(0.1), 0.2, 3, 2);
  MlsOptions options;
  options.kappa = 2.2;
  const MlsShapeFunctions shape_functions(nodes, options);
  const PointMatrix points = random_points(500, Vec3::Zero(), Vec3::Constant(0.7), 3, 3);
  const std::vector<ShapeFunctionValues> first = shape_functions.evaluate_all(points, 2);
  const std::vector<ShapeFunctionValues> second = shape_functions.evaluate_all(points, 2);
  ASSERT_EQ(first.size(), static_cast<std::size_t>(points.cols()));
  for (Index p = 0; p < points.cols(); ++p) {
    const ShapeFunctionValues single = shape_functions.evaluate(points.col(p), 2);
    const auto& batch = first[static_cast<std::size_t>(p)];
    EXPECT_TRUE(std::is_sorted(batch.neighbours.begin(), batch.neighbours.end()));
    EXPECT_EQ(batch.neighbours, single.neighbours);
    EXPECT_EQ(batch.phi, single.phi);
    EXPECT_EQ(batch.dphi, single.dphi);
    EXPECT_EQ(batch.ddphi, single.ddphi);
    EXPECT_EQ(second[static_cast<std::size_t>(p)].dphi, batch.dphi);
  }
}

TEST(Approximate, ScalarFieldValueGradientHessian) {
  const PointMatrix nodes = jittered_grid({8, 8, 8}, Vec3::Constant(0.1), 0.2, 3, 4);
  const MlsShapeFunctions shape_functions(nodes, MlsOptions{});
  const testing::QuadraticField field = testing::QuadraticField::random(3, true, 5);
  const Vec3 x(0.33, 0.21, 0.42);
  const FieldValue value = shape_functions.approximate(x, field.nodal_values(nodes), 2);
  EXPECT_NEAR(value.value, field.value(x), 1e-10);
  EXPECT_LT((value.gradient - field.gradient(x)).norm(), 1e-10);
  EXPECT_LT((value.hessian - field.hessian).norm(), 1e-9);
  EXPECT_THROW(shape_functions.approximate(x, Eigen::VectorXd::Zero(3)), std::invalid_argument);
}

}  // namespace
}  // namespace lamina::mls
