// Detection of a singular / ill-conditioned moment matrix A (seed: SINCHECK) and the optional remedy.
#include <gtest/gtest.h>

#include <string>

#include "core/error.hpp"
#include "mls/mls_shape_functions.hpp"
#include "mls/moment_matrix.hpp"
#include "test_helpers.hpp"

namespace lamina::mls {
namespace {

using testing::QuadraticField;
using testing::regular_grid;

const Real h = 1.0 / 6.0;

PointMatrix unit_grid() { return regular_grid({7, 7, 7}, Vec3::Constant(h)); }

TEST(SingularMomentMatrix, TooSmallKappaThrowsWithPointInMessage) {
  MlsOptions options;
  options.kappa = 0.9;  // fewer than 3 nodes per axis inside a box support: quadratic A is singular
  const MlsShapeFunctions shape_functions(unit_grid(), options);
  const Vec3 x(0.31, 0.47, 0.53);
  try {
    shape_functions.evaluate(x, 1);
    FAIL() << "expected SingularMomentMatrix";
  } catch (const SingularMomentMatrix& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("(0.31, 0.47, 0.53)"), std::string::npos) << message;
    EXPECT_NE(message.find("m = 10"), std::string::npos) << message;
    EXPECT_NE(message.find("kappa (now 0.9)"), std::string::npos) << message;
    EXPECT_NE(message.find(std::to_string(error.neighbours()) + " neighbour(s)"), std::string::npos) << message;
    EXPECT_EQ(error.basis_size(), 10);
    EXPECT_EQ(error.point(), x);
  }
  // Also at a node: only the node itself is inside its own support.
  EXPECT_THROW(shape_functions.evaluate(Vec3(3 * h, 3 * h, 3 * h), 0), SingularMomentMatrix);
  // It is an AnalysisError (exit code 3 of the application).
  EXPECT_THROW(shape_functions.evaluate(x, 0), AnalysisError);
}

TEST(SingularMomentMatrix, EvaluateAllRethrowsTheFirstFailingPoint) {
  MlsOptions options;
  options.kappa = 0.9;
  const MlsShapeFunctions shape_functions(unit_grid(), options);
  PointMatrix points(3, 3);
  points << 0.31, 0.32, 0.33, 0.47, 0.48, 0.49, 0.53, 0.54, 0.55;
  try {
    shape_functions.evaluate_all(points, 1);
    FAIL() << "expected SingularMomentMatrix";
  } catch (const SingularMomentMatrix& error) {
    EXPECT_EQ(error.point(), Vec3(0.31, 0.47, 0.53));
  }
}

TEST(SingularMomentMatrix, NearestModeWithTooFewNodesThrows) {
  MlsOptions options;
  options.mode = SupportMode::nearest;
  options.nearest = 6;  // < m = 10
  const MlsShapeFunctions shape_functions(unit_grid(), options);
  try {
    shape_functions.evaluate(Vec3(0.4, 0.5, 0.6), 0);
    FAIL() << "expected SingularMomentMatrix";
  } catch (const SingularMomentMatrix& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("nearest nodes (now 6)"), std::string::npos) << message;
  }
}

void expect_quadratic_reproduction(const MlsShapeFunctions& shape_functions, const Vec3& x) {
  const QuadraticField field = QuadraticField::random(3, true, 77);
  const FieldValue approximation = shape_functions.approximate(x, field.nodal_values(shape_functions.nodes()), 2);
  EXPECT_NEAR(approximation.value, field.value(x), 1e-10 * std::max(1.0, std::abs(field.value(x))));
  EXPECT_LT((approximation.gradient - field.gradient(x)).cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_LT((approximation.hessian - field.hessian).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(SingularRemedy, EnlargesRadiusUntilRegularAndReproducesQuadratics) {
  MlsOptions options;
  options.kappa = 0.9;
  options.singular_remedy = true;
  const MlsShapeFunctions shape_functions(unit_grid(), options);
  for (const Vec3& x : {Vec3(0.31, 0.47, 0.53), Vec3(3 * h, 3 * h, 3 * h), Vec3(0.0, 0.02, 0.99)}) {
    const ShapeFunctionValues values = shape_functions.evaluate(x, 2);
    EXPECT_GT(values.remedy_steps, 0);
    EXPECT_LE(values.condition, options.max_condition);
    expect_quadratic_reproduction(shape_functions, x);
  }
}

TEST(SingularRemedy, GrowsNearestCountUntilRegular) {
  MlsOptions options;
  options.mode = SupportMode::nearest;
  options.nearest = 6;
  options.singular_remedy = true;
  const MlsShapeFunctions shape_functions(unit_grid(), options);
  const Vec3 x(0.4, 0.5, 0.6);
  const ShapeFunctionValues values = shape_functions.evaluate(x, 2);
  EXPECT_GT(values.remedy_steps, 0);
  EXPECT_GE(values.neighbours.size(), 10u);
  expect_quadratic_reproduction(shape_functions, x);
}

TEST(SingularRemedy, GivesUpWhenAllNodesAreNeighbours) {
  // A flat layer of nodes cannot carry a 3D quadratic basis whatever the radius.
  MlsOptions options;
  options.singular_remedy = true;
  options.kappa = 2.0;
  const PointMatrix flat = regular_grid({5, 5, 1}, Vec3::Constant(0.25));
  const MlsShapeFunctions shape_functions(flat, options);
  try {
    shape_functions.evaluate(Vec3(0.5, 0.5, 0.0), 0);
    FAIL() << "expected SingularMomentMatrix";
  } catch (const SingularMomentMatrix& error) {
    EXPECT_NE(std::string(error.what()).find("singular remedy gave up"), std::string::npos) << error.what();
  }
}

TEST(MomentMatrixFactor, ConditionEstimateAndSolve) {
  // The estimate ||A_s||_1 trace(A_s^-1) of the Jacobi-scaled A_s bounds cond_2(A_s) from above and is
  // at most m^1.5 times too large.
  Eigen::Matrix4d a;
  a << 4, 1, 0.5, 0.2, 1, 3, 0.3, 0.1, 0.5, 0.3, 2, 0.4, 0.2, 0.1, 0.4, 1;
  MomentMatrixFactor<4> factor;
  ASSERT_TRUE(factor.factor(a, 1e12));
  const Eigen::Vector4d s = a.diagonal().cwiseSqrt().cwiseInverse();
  const Eigen::Matrix4d scaled = s.asDiagonal() * a * s.asDiagonal();
  const Eigen::Vector4d eigenvalues = Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d>(scaled).eigenvalues();
  const Real exact = eigenvalues.maxCoeff() / eigenvalues.minCoeff();
  EXPECT_GE(factor.condition(), exact * (1.0 - 1e-12));
  EXPECT_LE(factor.condition(), exact * 8.0);
  // A^-1 = T^T T and solve().
  const Eigen::Matrix4d transform = factor.transform();
  EXPECT_LT((transform.transpose() * transform * a - Eigen::Matrix4d::Identity()).cwiseAbs().maxCoeff(), 1e-14);
  const Eigen::Vector4d b(1, 2, 3, 4);
  EXPECT_LT((a * factor.solve(b) - b).norm(), 1e-13);
  // A singular matrix (rank 1) is rejected; so is one just above max_condition.
  const Eigen::Vector4d v(1, 2, 3, 4);
  EXPECT_FALSE(factor.factor(v * v.transpose(), 1e12));
  EXPECT_FALSE(factor.factor(-Eigen::Matrix4d::Identity(), 1e12));
  Eigen::Matrix2d nearly;
  nearly << 1, 1 - 1e-9, 1 - 1e-9, 1;  // cond_2 = (2 - 1e-9) / 1e-9, estimate: the same
  MomentMatrixFactor<2> small;
  EXPECT_TRUE(small.factor(nearly, 1e10));
  EXPECT_NEAR(small.condition(), 2e9, 2e9 * 1e-6);
  EXPECT_FALSE(small.factor(nearly, 1e9));
}

}  // namespace
}  // namespace lamina::mls
