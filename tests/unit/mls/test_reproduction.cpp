// Polynomial reproduction (consistency) of the MLS shape functions and their derivatives, and the
// partition-of-unity identities (seed 004, eqs 1-18..1-21).
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <tuple>

#include "mls/mls_shape_functions.hpp"
#include "test_helpers.hpp"

namespace lamina::mls {
namespace {

using testing::jittered_grid;
using testing::QuadraticField;
using testing::random_points;
using testing::regular_grid;

constexpr Real reproduction_tolerance = 1e-10;  // relative to max(1, |exact|); fields are O(1) on [0,1]^d
constexpr Real identity_tolerance = 1e-12;      // absolute, partition-of-unity identities

struct Layout {
  PointMatrix nodes;
  Vec3 low, high;  // evaluation box
};

/// Unit box [0,1]^dimension covered by a grid with 7 nodes per axis (h = 1/6), optionally jittered
/// by +-0.25 h.
Layout unit_layout(int dimension, bool jitter, unsigned seed) {
  const int per_axis = 7;
  const Real h = 1.0 / (per_axis - 1);
  std::array<int, 3> counts{per_axis, dimension >= 2 ? per_axis : 1, dimension >= 3 ? per_axis : 1};
  Layout layout;
  layout.nodes = jitter ? jittered_grid(counts, Vec3::Constant(h), 0.25, dimension, seed)
                        : regular_grid(counts, Vec3::Constant(h));
  layout.low = Vec3::Zero();
  layout.high = Vec3::Zero();
  layout.high.head(dimension).setOnes();
  return layout;
}

/// Checks value, gradient and Hessian of the MLS approximation of `field` at `count` random points.
/// Tolerance for the k-th derivative: reproduction_tolerance * max(1, |exact|) / length^k; length = 1
/// on the unit layouts (fields and their derivatives are O(1) there). Rounding errors of shape function
/// derivatives grow like 1 / h^k, so layouts with a much finer spacing pass a smaller length.
void expect_reproduces(const MlsShapeFunctions& shape_functions, const QuadraticField& field, const Layout& layout,
                       int count, unsigned seed, int derivative_order = 2, Real length = 1.0) {
  const int dimension = shape_functions.options().dimension;
  const Eigen::VectorXd nodal = field.nodal_values(shape_functions.nodes());
  const PointMatrix points = random_points(count, layout.low, layout.high, dimension, seed);
  for (Index p = 0; p < points.cols(); ++p) {
    const Vec3 x = points.col(p);
    const FieldValue approximation = shape_functions.approximate(x, nodal, derivative_order);
    const Real exact = field.value(x);
    EXPECT_NEAR(approximation.value, exact, reproduction_tolerance * std::max(1.0, std::abs(exact))) << "x = " << x.transpose();
    const Vec3 gradient = field.gradient(x);
    for (int i = 0; i < 3; ++i) {
      const Real expected = i < dimension ? gradient[i] : 0.0;
      EXPECT_NEAR(approximation.gradient[i], expected, reproduction_tolerance * std::max(1.0, std::abs(expected)) / length)
          << "d/dx" << i << " at x = " << x.transpose();
    }
    if (derivative_order < 2) continue;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        const Real expected = i < dimension && j < dimension ? field.hessian(i, j) : 0.0;
        EXPECT_NEAR(approximation.hessian(i, j), expected,
                    reproduction_tolerance * std::max(1.0, std::abs(expected)) / (length * length))
            << "d2/dx" << i << "dx" << j << " at x = " << x.transpose();
      }
  }
}

// ---------------------------------------------------------------------------------------------
// 3D quadratic basis: every weight x shape x {regular, jittered} x {kappa, nearest}.

using QuadraticCase = std::tuple<Weight, SupportShape, bool /*jitter*/, SupportMode>;

class QuadraticReproduction3D : public ::testing::TestWithParam<QuadraticCase> {};

TEST_P(QuadraticReproduction3D, ReproducesQuadraticFieldsAndDerivatives) {
  const auto [weight, shape, jitter, mode] = GetParam();
  const Layout layout = unit_layout(3, jitter, 11);
  MlsOptions options;
  options.weight = weight;
  options.shape = shape;
  options.mode = mode;
  options.kappa = jitter ? 2.3 : 2.0;
  options.nearest = shape == SupportShape::box ? 30 : 33;
  const MlsShapeFunctions shape_functions(layout.nodes, options);
  for (unsigned seed = 0; seed < 3; ++seed)
    expect_reproduces(shape_functions, QuadraticField::random(3, true, 100 + seed), layout, 15, 200 + seed);
}

std::string quadratic_case_name(const ::testing::TestParamInfo<QuadraticCase>& info) {
  const auto [weight, shape, jitter, mode] = info.param;
  return to_string(weight) + "_" + to_string(shape) + (jitter ? "_jittered_" : "_regular_") + to_string(mode);
}

INSTANTIATE_TEST_SUITE_P(AllWeightsShapesModes, QuadraticReproduction3D,
                         ::testing::Combine(::testing::Values(Weight::gauss, Weight::cubic_spline, Weight::quartic_spline),
                                            ::testing::Values(SupportShape::box, SupportShape::sphere),
                                            ::testing::Bool(),
                                            ::testing::Values(SupportMode::kappa, SupportMode::nearest)),
                         quadratic_case_name);

// ---------------------------------------------------------------------------------------------
// The other support modes (3D quadratic, jittered nodes).

TEST(QuadraticReproductionModes, FixedRadiusAllAndVariable) {
  const Layout layout = unit_layout(3, true, 5);
  const Real h = 1.0 / 6.0;
  for (SupportShape shape : {SupportShape::box, SupportShape::sphere}) {
    MlsOptions fixed;
    fixed.shape = shape;
    fixed.mode = SupportMode::fixed_radius;
    fixed.radius = Vec3(2.4 * h, 2.4 * h, 2.4 * h);
    expect_reproduces(MlsShapeFunctions(layout.nodes, fixed), QuadraticField::random(3, true, 1), layout, 10, 2);

    MlsOptions all;
    all.shape = shape;
    all.mode = SupportMode::all;
    all.nearest = 30;
    all.scale = 1.2;
    expect_reproduces(MlsShapeFunctions(layout.nodes, all), QuadraticField::random(3, true, 3), layout, 10, 4);

    MlsOptions variable;
    variable.shape = shape;
    variable.mode = SupportMode::variable;
    variable.nearest = 30;
    variable.scale = 1.1;
    expect_reproduces(MlsShapeFunctions(layout.nodes, variable), QuadraticField::random(3, true, 5), layout, 10, 6);
  }
}

// Anisotropic spacing and a fixed anisotropic box (OMLL "INFLENCEDOMAIN Fix" style, here 2.01 h per
// axis with h_z = h_x / 5: three node layers through the thickness). A quadratic basis needs three layers
// inside every support, hence 2.01 h_z and not 1.01 h_z through the thickness.
TEST(QuadraticReproductionModes, AnisotropicGridAndSupport) {
  const Vec3 h(0.1, 0.1, 0.02);
  Layout layout;
  layout.nodes = regular_grid({9, 9, 3}, h);
  layout.low = Vec3::Zero();
  layout.high = Vec3(0.8, 0.8, 0.04);
  MlsOptions fixed;
  fixed.mode = SupportMode::fixed_radius;
  fixed.radius = Vec3(2.01 * h[0], 2.01 * h[1], 2.01 * h[2]);
  const Real length = 0.1;  // h_z = 0.02: second derivatives of phi ~ 1 / h_z^2 = 2500
  expect_reproduces(MlsShapeFunctions(layout.nodes, fixed), QuadraticField::random(3, true, 8), layout, 20, 9, 2, length);
  MlsOptions kappa;  // estimated per-axis spacing
  kappa.kappa = 2.0;
  const MlsShapeFunctions estimated(layout.nodes, kappa);
  EXPECT_NEAR(estimated.nodal_spacing()(2, 0), 0.02, 1e-15);
  expect_reproduces(estimated, QuadraticField::random(3, true, 10), layout, 20, 11, 2, length);
}

// First derivatives on thin-plate lattices (the EFG plates: 3-5 node layers, box kappa 2-3): their moment
// matrices have condition estimates of 1e2-1e4, where first derivatives are formed with A^-1 directly
// (second derivatives in the orthonormal basis above 1e2). Reproduction within the same tolerance there
// (measured 2026-12-07: 291 of the 1,600 points between 1e2 and 1e4, worst condition 1.6e3, worst gradient
// error 7.8e-13 relative).
TEST(QuadraticReproductionModes, FirstDerivativesOnThinPlateLattices) {
  struct Plate {
    std::array<int, 3> nodes;
    Real kappa;
  };
  Real worst_condition = 0.0;
  int direct_above_100 = 0;
  for (const Plate& plate : {Plate{{6, 6, 4}, 3.0}, Plate{{11, 11, 3}, 3.0}, Plate{{11, 11, 5}, 2.0}, Plate{{9, 9, 4}, 2.5}}) {
    const Vec3 h(10.0 / (plate.nodes[0] - 1), 10.0 / (plate.nodes[1] - 1), 1.0 / (plate.nodes[2] - 1));
    Layout layout;
    layout.nodes = regular_grid(plate.nodes, h);
    layout.low = Vec3::Zero();
    layout.high = Vec3(10.0, 10.0, 1.0);
    MlsOptions options;
    options.kappa = plate.kappa;
    const MlsShapeFunctions shape_functions(layout.nodes, options);
    const QuadraticField field = QuadraticField::random(3, true, 21);
    const Eigen::VectorXd nodal = field.nodal_values(shape_functions.nodes());
    const PointMatrix points = random_points(400, layout.low, layout.high, 3, 22);
    for (Index p = 0; p < points.cols(); ++p) {
      const Vec3 x = points.col(p);
      const ShapeFunctionValues values = shape_functions.evaluate(x, 1);
      worst_condition = std::max(worst_condition, values.condition);
      if (values.condition > 1e2 && values.condition <= 1e4) ++direct_above_100;
      Real value = 0.0;
      Vec3 gradient = Vec3::Zero();
      for (std::size_t k = 0; k < values.neighbours.size(); ++k) {
        value += values.phi[static_cast<Index>(k)] * nodal[values.neighbours[k]];
        gradient += values.dphi.col(static_cast<Index>(k)) * nodal[values.neighbours[k]];
      }
      // field values up to about 100 on this box: tolerance relative to max(1, |exact|) as above
      EXPECT_NEAR(value, field.value(x), reproduction_tolerance * std::max(1.0, std::abs(field.value(x))));
      const Vec3 expected = field.gradient(x);
      for (int i = 0; i < 3; ++i)
        EXPECT_NEAR(gradient[i], expected[i], reproduction_tolerance * std::max(1.0, std::abs(expected[i])))
            << "d/dx" << i << " at x = " << x.transpose() << ", condition " << values.condition;
    }
  }
  EXPECT_GT(direct_above_100, 100) << "the lattices should exercise conditions between 1e2 and 1e4";
  EXPECT_LT(worst_condition, 1e6);
}

// A rigid translation strains nothing: sum_J phi_J,i = 0 to the rounding of the sum itself, also where the
// moment matrices are ill-conditioned (the thin cantilever of efg_thin_cantilever: 51 x 3 x 3 nodes over
// 2000 x 2 x 2, box radius 2.5 h). Measured 2026-12-07: worst 2.8e-16 of sum |phi_J,i|; 1.5e-15 without
// the correction.
TEST(QuadraticReproductionModes, FirstDerivativesSumToZeroExactly) {
  const Vec3 h(40.0, 1.0, 1.0);
  const PointMatrix nodes = regular_grid({51, 3, 3}, h);
  MlsOptions options;
  options.kappa = 2.5;
  options.delta = 0.0;
  const MlsShapeFunctions shape_functions(nodes, options);
  const PointMatrix points = random_points(500, Vec3::Zero(), Vec3(2000.0, 2.0, 2.0), 3, 31);
  Real worst = 0.0;
  for (Index p = 0; p < points.cols(); ++p) {
    const ShapeFunctionValues values = shape_functions.evaluate(points.col(p), 1);
    for (int i = 0; i < 3; ++i)
      worst = std::max(worst, std::abs(values.dphi.row(i).sum()) / values.dphi.row(i).cwiseAbs().sum());
  }
  EXPECT_LT(worst, 1e-15);
}

// ---------------------------------------------------------------------------------------------
// 2D and 1D quadratic bases.

TEST(QuadraticReproductionLowDimension, TwoDimensions) {
  for (bool jitter : {false, true})
    for (Weight weight : {Weight::gauss, Weight::cubic_spline, Weight::quartic_spline})
      for (SupportShape shape : {SupportShape::box, SupportShape::sphere}) {
        const Layout layout = unit_layout(2, jitter, 21);
        MlsOptions options;
        options.dimension = 2;
        options.weight = weight;
        options.shape = shape;
        // A circle of radius 2 h near an edge can hold only two rows of nodes (singular for a quadratic
        // basis, correctly detected): circles get 0.5 h more.
        options.kappa = (jitter ? 2.3 : 2.0) + (shape == SupportShape::sphere ? 0.5 : 0.0);
        expect_reproduces(MlsShapeFunctions(layout.nodes, options), QuadraticField::random(2, true, 22), layout, 15, 23);
        options.mode = SupportMode::nearest;
        options.nearest = 12;
        expect_reproduces(MlsShapeFunctions(layout.nodes, options), QuadraticField::random(2, true, 24), layout, 15, 25);
      }
}

TEST(QuadraticReproductionLowDimension, OneDimension) {
  for (bool jitter : {false, true})
    for (Weight weight : {Weight::gauss, Weight::cubic_spline, Weight::quartic_spline})
      for (SupportShape shape : {SupportShape::box, SupportShape::sphere}) {
        const Layout layout = unit_layout(1, jitter, 31);
        MlsOptions options;
        options.dimension = 1;
        options.weight = weight;
        options.shape = shape;
        options.kappa = jitter ? 2.3 : 2.0;
        expect_reproduces(MlsShapeFunctions(layout.nodes, options), QuadraticField::random(1, true, 32), layout, 15, 33);
        options.mode = SupportMode::nearest;
        options.nearest = 5;
        expect_reproduces(MlsShapeFunctions(layout.nodes, options), QuadraticField::random(1, true, 34), layout, 15, 35);
      }
}

// Unused coordinates are ignored: nodes and evaluation points with arbitrary z in a 2D problem.
TEST(QuadraticReproductionLowDimension, UnusedCoordinatesAreIgnored) {
  Layout layout = unit_layout(2, true, 41);
  PointMatrix lifted = layout.nodes;
  for (Index i = 0; i < lifted.cols(); ++i) lifted(2, i) = 0.37 * std::sin(static_cast<Real>(i));
  MlsOptions options;
  options.dimension = 2;
  options.kappa = 2.3;
  const MlsShapeFunctions flat(layout.nodes, options);
  const MlsShapeFunctions raised(lifted, options);
  const Vec3 x(0.41, 0.57, 0.0);
  const ShapeFunctionValues a = flat.evaluate(x, 2);
  const ShapeFunctionValues b = raised.evaluate(Vec3(0.41, 0.57, 5.0), 2);
  ASSERT_EQ(a.neighbours, b.neighbours);
  EXPECT_LT((a.phi - b.phi).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_LT((a.dphi - b.dphi).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((a.ddphi - b.ddphi).cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_EQ(a.dphi.row(2).cwiseAbs().maxCoeff(), 0.0);
  for (int row : {2, 4, 5}) EXPECT_EQ(a.ddphi.row(row).cwiseAbs().maxCoeff(), 0.0) << "row " << row;
}

// ---------------------------------------------------------------------------------------------
// Linear bases reproduce linear fields and their first derivatives.

TEST(LinearReproduction, AllDimensionsWeightsShapes) {
  for (int dimension = 1; dimension <= 3; ++dimension)
    for (bool jitter : {false, true})
      for (Weight weight : {Weight::gauss, Weight::cubic_spline, Weight::quartic_spline})
        for (SupportShape shape : {SupportShape::box, SupportShape::sphere}) {
          const Layout layout = unit_layout(dimension, jitter, 51);
          MlsOptions options;
          options.dimension = dimension;
          options.basis = Basis::linear;
          options.weight = weight;
          options.shape = shape;
          options.kappa = jitter ? 1.8 : 1.5;
          SCOPED_TRACE(::testing::Message() << dimension << "D " << to_string(weight) << " " << to_string(shape)
                                            << (jitter ? " jittered" : " regular"));
          expect_reproduces(MlsShapeFunctions(layout.nodes, options), QuadraticField::random(dimension, false, 52),
                            layout, 15, 53, 1);
        }
}

// ---------------------------------------------------------------------------------------------
// Partition of unity: sum phi = 1, sum dphi = 0, sum ddphi = 0, sum phi x_I = x,
// sum dphi_i x_I,j = delta_ij (tolerance identity_tolerance, absolute, h = 1/6).

TEST(PartitionOfUnity, IdentitiesHoldForBothBases) {
  for (Basis basis : {Basis::linear, Basis::quadratic})
    for (SupportShape shape : {SupportShape::box, SupportShape::sphere}) {
      const Layout layout = unit_layout(3, true, 61);
      MlsOptions options;
      options.basis = basis;
      options.shape = shape;
      options.kappa = 2.3;
      const MlsShapeFunctions shape_functions(layout.nodes, options);
      const PointMatrix points = random_points(20, layout.low, layout.high, 3, 62);
      for (Index p = 0; p < points.cols(); ++p) {
        const Vec3 x = points.col(p);
        const ShapeFunctionValues values = shape_functions.evaluate(x, 2);
        const Index n = static_cast<Index>(values.neighbours.size());
        PointMatrix local(3, n);
        for (Index j = 0; j < n; ++j) local.col(j) = layout.nodes.col(values.neighbours[j]);
        EXPECT_NEAR(values.phi.sum(), 1.0, identity_tolerance);
        EXPECT_LT(values.dphi.rowwise().sum().cwiseAbs().maxCoeff(), identity_tolerance);
        EXPECT_LT((local * values.phi - x).cwiseAbs().maxCoeff(), identity_tolerance);
        EXPECT_LT((values.dphi * local.transpose() - Mat3::Identity()).cwiseAbs().maxCoeff(), identity_tolerance);
        // Second derivatives are ~1/h^2 larger: still within 1e-12 absolute on this layout.
        EXPECT_LT(values.ddphi.rowwise().sum().cwiseAbs().maxCoeff(), identity_tolerance);
        EXPECT_LT((values.ddphi * local.transpose()).cwiseAbs().maxCoeff(), identity_tolerance);
      }
    }
}

// Interface enrichment: with the term |d(y)| in the basis where supports cross the plane, a field with a
// kink across the plane, u = linear + c |z - 0.5|, is reproduced exactly on both sides (value and
// one-sided gradient); without it the kink is smeared.
TEST(InterfaceEnrichment, ReproducesAFieldWithAKinkAcrossThePlane) {
  const Real h = 0.125;
  PointMatrix nodes = testing::jittered_grid({9, 9, 9}, Vec3::Constant(h), 0.2, 3, 21);
  for (Index i = 0; i < nodes.cols(); ++i)  // a node layer on the plane z = 0.5 (index 4), as at a material interface
    if (std::abs(nodes(2, i) - 0.5) < 0.3 * h) nodes(2, i) = 0.5;
  auto field = [](const Vec3& y) { return 1.0 + 0.5 * y[0] - 2.0 * y[1] + 0.7 * y[2] + 3.0 * std::abs(y[2] - 0.5); };
  auto gradient = [](const Vec3& y) { return Vec3(0.5, -2.0, 0.7 + 3.0 * (y[2] > 0.5 ? 1.0 : -1.0)); };
  Eigen::VectorXd values(nodes.cols());
  for (Index i = 0; i < nodes.cols(); ++i) values[i] = field(nodes.col(i));
  MlsOptions options;
  options.kappa = 2.6;
  options.interface_enrichment = true;
  options.interface_point = Vec3(0, 0, 0.5);
  options.interface_normal = Vec3::UnitZ();
  const MlsShapeFunctions enriched(nodes, options);
  options.interface_enrichment = false;
  const MlsShapeFunctions plain(nodes, options);
  const PointMatrix points = testing::random_points(200, Vec3::Constant(0.15), Vec3::Constant(0.85), 3, 22);
  Real plain_error = 0.0;
  for (Index q = 0; q < points.cols(); ++q) {
    const Vec3 x = points.col(q);
    if (std::abs(x[2] - 0.5) < 1e-6) continue;
    const FieldValue u = enriched.approximate(x, values, 1);
    EXPECT_NEAR(u.value, field(x), 1e-10) << "point " << q;
    // looser for the gradient: where a node across the plane barely enters a support, the enriched
    // moment matrix is ill-conditioned (measured worst 2.4e-7 here)
    EXPECT_LE((u.gradient - gradient(x)).norm(), 1e-6) << "point " << q;
    plain_error = std::max(plain_error, (plain.approximate(x, values, 1).gradient - gradient(x)).norm());
  }
  EXPECT_GT(plain_error, 0.1);  // the polynomial basis alone cannot follow the kink
  // partition of unity and linear reproduction still hold
  const ShapeFunctionValues at = enriched.evaluate(Vec3(0.4, 0.45, 0.52), 1);
  EXPECT_NEAR(at.phi.sum(), 1.0, 1e-12);
  EXPECT_LE(at.dphi.rowwise().sum().norm(), 1e-10);
}

}  // namespace
}  // namespace lamina::mls
