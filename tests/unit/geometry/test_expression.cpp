// geometry::Expression: the case file's expressions of x, y, z, t, r, theta (muParser).
#include <gtest/gtest.h>

#include <cmath>

#include "geometry/expression.hpp"

using lamina::Vec3;
using lamina::geometry::Expression;

TEST(Expression, CylindricalVariablesAreTheRadiusAndTheAngleFromPlusX) {
  const Vec3 p(-1.0, 1.0, 2.0);
  EXPECT_DOUBLE_EQ(Expression("r").evaluate(p), std::sqrt(2.0));
  EXPECT_DOUBLE_EQ(Expression("theta").evaluate(p), 0.75 * M_PI);
  EXPECT_DOUBLE_EQ(Expression("r * cos(theta) + z * t").evaluate(p, 3.0), -1.0 + 6.0);
  // evaluated one after the other at different points: each value is the point's own
  const Expression both("r + 10 * theta");
  EXPECT_DOUBLE_EQ(both.evaluate(Vec3(0.0, 2.0, 0.0)), 2.0 + 5.0 * M_PI);
  EXPECT_DOUBLE_EQ(both.evaluate(Vec3(3.0, 0.0, 0.0)), 3.0);
}

TEST(Expression, SelectionsWithoutCylindricalVariablesGiveTheSameValues) {
  const Expression selection("x > 9.5 - 1e-9 and y > 9.5 - 1e-9 or not (z < 1)");
  EXPECT_EQ(selection.evaluate(Vec3(9.6, 9.7, 0.0)), 1.0);
  EXPECT_EQ(selection.evaluate(Vec3(9.6, 9.0, 0.5)), 0.0);
  EXPECT_EQ(selection.evaluate(Vec3(0.0, 0.0, 1.0)), 1.0);
  EXPECT_DOUBLE_EQ(Expression("atan2(y, x)").evaluate(Vec3(0.0, -1.0, 0.0)), -0.5 * M_PI);
}
