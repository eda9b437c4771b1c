// The seed's support convention (seed 004 section 3.2.2, eq 3-6): a box kappa_i = 2.0 with the radius
// s_i + delta_i holds 3 nodes per direction with non-zero weight, so the quadratic moment matrix is
// regular at every Gauss point of plates and bricks of 3-5 node layers, regular and jittered.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <set>

#include "mls/mls_shape_functions.hpp"
#include "test_helpers.hpp"

namespace lamina::mls {
namespace {

using testing::jittered_grid;
using testing::QuadraticField;

/// Gauss points (rule of `order` points per axis) of the (n - 1)^3 cells between the node planes of
/// the unjittered grid: the corner points lie 0.21 h (2 points) or 0.11 h (3 points) from a corner node.
PointMatrix volume_gauss_points(const std::array<int, 3>& counts, const Vec3& h, int order) {
  const std::array<Real, 3> abscissae = order == 2 ? std::array<Real, 3>{-1.0 / std::sqrt(3.0), 1.0 / std::sqrt(3.0), 0.0}
                                                   : std::array<Real, 3>{-std::sqrt(0.6), 0.0, std::sqrt(0.6)};
  const Index cells = Index(counts[0] - 1) * (counts[1] - 1) * (counts[2] - 1);
  PointMatrix points(3, cells * order * order * order);
  Index column = 0;
  for (int k = 0; k + 1 < counts[2]; ++k)
    for (int j = 0; j + 1 < counts[1]; ++j)
      for (int i = 0; i + 1 < counts[0]; ++i)
        for (int c = 0; c < order; ++c)
          for (int b = 0; b < order; ++b)
            for (int a = 0; a < order; ++a)
              points.col(column++) = Vec3((i + 0.5 + 0.5 * abscissae[a]) * h[0], (j + 0.5 + 0.5 * abscissae[b]) * h[1],
                                          (k + 0.5 + 0.5 * abscissae[c]) * h[2]);
  return points;
}

/// The volume Gauss points and their projections onto the six faces of the grid's box (the surface
/// points of boundary integrals, e.g. Nitsche's): on a face x_d = 0 the node plane 2 h away lies at
/// exactly kappa h, where a bare radius kappa h gives it zero weight and A is singular.
PointMatrix gauss_points(const std::array<int, 3>& counts, const Vec3& h, int order) {
  const PointMatrix volume = volume_gauss_points(counts, h, order);
  PointMatrix points(3, 7 * volume.cols());
  points.leftCols(volume.cols()) = volume;
  for (int d = 0; d < 3; ++d)
    for (int side = 0; side < 2; ++side) {
      PointMatrix face = volume;
      face.row(d).setConstant(side * (counts[d] - 1) * h[d]);
      points.middleCols((1 + 2 * d + side) * volume.cols(), volume.cols()) = face;
    }
  return points;
}

struct Body {
  const char* name;
  std::array<int, 3> counts;
  Vec3 spacing;
};

// plates (thin direction z) of 3, 4 and 5 node layers and bricks; spacings as in the seed's examples
const Body bodies[] = {
    {"plate 11x11x3", {11, 11, 3}, Vec3(1.0, 1.0, 0.5)},     {"plate 9x9x4", {9, 9, 4}, Vec3(2.5, 2.5, 1.0 / 3.0)},
    {"plate 11x11x5", {11, 11, 5}, Vec3(1.0, 1.0, 0.25)},    {"brick 13x5x5", {13, 5, 5}, Vec3(1.0 / 3.0, 0.5, 0.5)},
    {"brick 6x6x6", {6, 6, 6}, Vec3(0.4, 0.4, 0.4)},         {"brick 5x4x3", {5, 4, 3}, Vec3(1.0, 1.0, 1.0)},
};

TEST(SeedSupport, DefaultRadiusIsKappaPlusDeltaTimesTheSpacing) {
  MlsOptions options;
  EXPECT_EQ(options.kappa, 2.0);
  EXPECT_EQ(options.delta, 0.1);
  const Vec3 h(1.0, 0.5, 0.25);
  const MlsShapeFunctions shape_functions(jittered_grid({4, 4, 4}, h, 0.0, 3, 1), options,
                                          Eigen::Matrix3Xd(h.replicate(1, 64)));
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(shape_functions.support_radii()(d, 5), 2.1 * h[d], 1e-8);
  options.delta = 0.0;  // the bare radius kappa h
  const MlsShapeFunctions bare(jittered_grid({4, 4, 4}, h, 0.0, 3, 1), options, Eigen::Matrix3Xd(h.replicate(1, 64)));
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(bare.support_radii()(d, 5), 2.0 * h[d], 1e-8);
}

TEST(SeedSupport, BoxKappaTwoQuadraticIsRegularOnPlatesAndBricks) {
  for (const Body& body : bodies)
    for (Real jitter : {0.0, 0.1, 0.2})
      for (Weight weight : {Weight::quartic_spline, Weight::cubic_spline, Weight::gauss})
        for (int order : {2, 3}) {
          MlsOptions options;  // the seed's: quadratic basis, box support, kappa 2.0
          options.weight = weight;
          const PointMatrix nodes = jittered_grid(body.counts, body.spacing, jitter, 3, 7);
          const MlsShapeFunctions shape_functions(nodes, options);
          const PointMatrix points = gauss_points(body.counts, body.spacing, order);
          const QuadraticField field = QuadraticField::random(3, true, 3);
          const Eigen::VectorXd u = field.nodal_values(nodes);
          Real worst_value = 0.0, worst_gradient = 0.0;
          int fewest_planes = 1000;
          for (Index q = 0; q < points.cols(); ++q) {
            const Vec3 x = points.col(q);
            ShapeFunctionValues values;
            ASSERT_NO_THROW(values = shape_functions.evaluate(x, 1))
                << body.name << " jitter " << jitter << " weight " << int(weight) << " point " << x.transpose();
            Real value = 0.0;
            Vec3 gradient = Vec3::Zero();
            std::array<std::set<long>, 3> planes;  // node planes (of the unjittered grid) with non-zero weight
            for (std::size_t n = 0; n < values.neighbours.size(); ++n) {
              const Index node = values.neighbours[n];
              value += values.phi[Index(n)] * u[node];
              gradient += values.dphi.col(Index(n)) * u[node];
              if (values.phi[Index(n)] != 0.0)
                for (int d = 0; d < 3; ++d) planes[d].insert(std::lround(nodes(d, node) / body.spacing[d]));
            }
            worst_value = std::max(worst_value, std::abs(value - field.value(x)));
            worst_gradient = std::max(worst_gradient, (gradient - field.gradient(x)).norm());
            for (int d = 0; d < 3; ++d) fewest_planes = std::min(fewest_planes, int(planes[d].size()));
          }
          // quadratic completeness: exact up to the conditioning of A
          EXPECT_LT(worst_value, 1e-8) << body.name << " jitter " << jitter;
          EXPECT_LT(worst_gradient, 1e-6) << body.name << " jitter " << jitter;
          // the seed's condition: at least 3 nodes per direction with non-zero weight
          if (jitter == 0.0) {
            EXPECT_GE(fewest_planes, 3) << body.name << " Gauss order " << order;
          }
        }
}

// The point where a new user's plate stopped (issue 20): the face Gauss point next to a clamped corner,
// (0, 0.211 h, 0.211 h), has 27 nodes in its support. With the bare radius 2 h (delta 0) the node plane
// x = 2 h lies exactly on the support boundary with zero weight, so only 2 planes carry weight along x and
// the quadratic A is singular; with the seed's s + delta all 27 weights are positive and A is well conditioned.
TEST(SeedSupport, CornerFaceGaussPointHoldsThreePlanesPerDirection) {
  for (const Body& body : bodies)
    for (Weight weight : {Weight::quartic_spline, Weight::cubic_spline}) {
      MlsOptions options;
      options.weight = weight;
      const PointMatrix nodes = jittered_grid(body.counts, body.spacing, 0.0, 3, 1);
      const Real g = 0.5 - 0.5 / std::sqrt(3.0);  // first 2-point Gauss abscissa in a unit interval
      for (int d = 0; d < 3; ++d) {
        Vec3 x = g * body.spacing;
        x[d] = 0.0;  // on the face x_d = 0, next to the corner node
        const ShapeFunctionValues values = MlsShapeFunctions(nodes, options).evaluate(x, 1);
        EXPECT_EQ(values.neighbours.size(), 27u) << body.name;
        EXPECT_EQ((values.phi.array() != 0.0).count(), 27) << body.name << " face " << d;
        EXPECT_LT(values.condition, 1e8) << body.name << " face " << d;
        MlsOptions bare = options;
        bare.delta = 0.0;
        EXPECT_THROW(MlsShapeFunctions(nodes, bare).evaluate(x, 1), SingularMomentMatrix) << body.name << " face " << d;
      }
    }
}

// The OMLL deck's INFLENCEDOMAIN Fix radii are the seed's s + delta written out (section 2.2: "Fix 2.01 2.01
// 1.01", "set to 2.0" on spacings 1, 1, 0.5): on a regular grid the fixed radii (kappa + delta) h_d are the same
// supports as kappa with delta, and give the same shape functions.
TEST(SeedSupport, FixedRadiusEqualsKappaPlusDelta) {
  const Vec3 h(1.0, 1.0, 0.5);
  const PointMatrix nodes = jittered_grid({6, 6, 3}, h, 0.0, 3, 1);
  MlsOptions seed_kappa;  // kappa 2, delta 0.1
  seed_kappa.delta = 0.01;
  MlsOptions fixed;
  fixed.mode = SupportMode::fixed_radius;
  fixed.radius = Vec3(2.01, 2.01, 1.005);
  const MlsShapeFunctions a(nodes, seed_kappa), b(nodes, fixed);
  EXPECT_LT((a.support_radii() - b.support_radii()).cwiseAbs().maxCoeff(), 1e-12);
  const Vec3 x(0.0, 0.2113, 0.1057);  // a face Gauss point next to the corner
  const ShapeFunctionValues va = a.evaluate(x, 1), vb = b.evaluate(x, 1);
  ASSERT_EQ(va.neighbours, vb.neighbours);
  EXPECT_LT((va.phi - vb.phi).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((va.dphi - vb.dphi).cwiseAbs().maxCoeff(), 1e-10);
}

}  // namespace
}  // namespace lamina::mls
