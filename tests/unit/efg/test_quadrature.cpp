// Background quadrature: Gauss-Legendre rules, weights summing to the body volume (box and
// curved bodies), boundary faces (area, closed-surface normals).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "efg/background_quadrature.hpp"
#include "efg_test_helpers.hpp"
#include "geometry/body_maps.hpp"
#include "geometry/generators.hpp"

namespace lamina::efg {
namespace {

using testing::curved_beam_spec;

TEST(GaussLegendre, IntegratesPolynomialsOfDegree2nMinus1Exactly) {
  for (int n = 1; n <= 12; ++n) {
    std::vector<Real> x, w;
    gauss_legendre(n, x, w);
    ASSERT_EQ(static_cast<int>(x.size()), n);
    for (int k = 0; k <= 2 * n - 1; ++k) {
      Real sum = 0;
      for (int i = 0; i < n; ++i) sum += w[static_cast<std::size_t>(i)] * std::pow(x[static_cast<std::size_t>(i)], k);
      const Real exact = k % 2 == 1 ? 0.0 : 2.0 / (k + 1);
      EXPECT_NEAR(sum, exact, 1e-14) << "n = " << n << ", degree " << k;
    }
    // ascending points in (-1, 1)
    for (int i = 1; i < n; ++i) EXPECT_LT(x[static_cast<std::size_t>(i - 1)], x[static_cast<std::size_t>(i)]);
  }
}

TEST(GaussLegendre, DoesNotIntegrateDegree2nExactly) {
  std::vector<Real> x, w;
  gauss_legendre(2, x, w);
  Real sum = 0;
  for (int i = 0; i < 2; ++i) sum += w[static_cast<std::size_t>(i)] * std::pow(x[static_cast<std::size_t>(i)], 4);
  EXPECT_GT(std::abs(sum - 0.4), 1e-3);
}

geometry::GeometrySpec box_spec() {
  geometry::GeometrySpec g;
  g.type = geometry::GeometryType::box;
  g.min = Vec3(0, -1, 2);
  g.max = Vec3(4, 1, 2.5);
  return g;
}

geometry::GeometrySpec tube_spec() { return testing::cylinder_spec(2.0, 3.0, 2, 0.2); }

geometry::GeometrySpec cap_spec() {
  geometry::GeometrySpec g;
  g.type = geometry::GeometryType::sphere_cap;
  g.radius = 10;
  g.thickness = 0.5;
  g.polar_hole_deg = 18;
  g.sector_deg = 90;
  return g;
}

Real quadrature_volume(const geometry::GeometrySpec& g, const std::array<int, 3>& cells, int gauss) {
  const BackgroundCells c = make_background_cells(geometry::make_volume_map(g), cells);
  return volume_quadrature(c, {gauss, gauss, gauss}).weights.sum();
}

TEST(VolumeQuadrature, WeightsSumToTheBoxVolume) {
  const Real exact = geometry::body_volume(box_spec());
  EXPECT_NEAR(exact, 4.0, 1e-14);
  for (int g = 1; g <= 4; ++g) EXPECT_NEAR(quadrature_volume(box_spec(), {5, 3, 2}, g), exact, 1e-10 * exact);
}

TEST(VolumeQuadrature, WeightsSumToTheCurvedBeamVolume) {
  const Real exact = geometry::body_volume(curved_beam_spec());
  EXPECT_NEAR(exact, 0.25 * std::numbers::pi * (25 - 9) * 2, 1e-12);
  for (int g = 1; g <= 4; ++g) EXPECT_NEAR(quadrature_volume(curved_beam_spec(), {4, 20, 2}, g), exact, 1e-10 * exact);
}

TEST(VolumeQuadrature, WeightsSumToOtherMappedBodies) {
  for (const auto& g : {tube_spec(), cap_spec()}) {
    const Real exact = geometry::body_volume(g);
    EXPECT_NEAR(quadrature_volume(g, {2, 24, 3}, 3), exact, 1e-10 * exact) << geometry::to_string(g.type);
  }
}

TEST(VolumeQuadrature, PointsLieInTheBody) {
  const auto g = curved_beam_spec();
  const BackgroundCells c = make_background_cells(geometry::make_volume_map(g), {4, 20, 2});
  const VolumeQuadrature q = volume_quadrature(c, {3, 3, 3});
  EXPECT_EQ(q.size(), 4 * 20 * 2 * 27);
  EXPECT_EQ(q.cell_begin.back(), q.size());
  for (Index i = 0; i < q.size(); ++i) EXPECT_TRUE(geometry::body_contains(g, q.points.col(i), 1e-12));
}

TEST(VolumeQuadrature, DefaultCellsFollowTheNodeGrid) {
  const auto map = geometry::make_volume_map(curved_beam_spec());
  const auto cells = default_cell_counts(map, {5, 21, 3});
  EXPECT_EQ(cells[0], 4);
  EXPECT_EQ(cells[1], 20);
  EXPECT_EQ(cells[2], 2);
  const auto tube = geometry::make_volume_map(tube_spec());
  EXPECT_EQ(default_cell_counts(tube, {3, 24, 4})[1], 24);  // periodic: one cell per node
  EXPECT_EQ(default_cell_counts(tube, {1, 24, 4})[0], 1);
}

TEST(BoundaryQuadrature, AreaAndClosedSurfaceOfTheBox) {
  const BackgroundCells c = make_background_cells(geometry::make_volume_map(box_spec()), {5, 3, 2});
  const SurfaceQuadrature s = boundary_quadrature(c, {2, 2, 2});
  EXPECT_NEAR(s.weights.sum(), 2 * (4 * 2 + 2 * 0.5 + 0.5 * 4), 1e-10 * 22);
  Vec3 closed = Vec3::Zero();
  for (Index i = 0; i < s.size(); ++i) {
    closed += s.weights[i] * s.normals.col(i);
    EXPECT_NEAR(s.normals.col(i).norm(), 1.0, 1e-12);
  }
  EXPECT_LT(closed.norm(), 1e-12);
  // outward: the normal points away from the centre
  const Vec3 centre(2, 0, 2.25);
  for (Index i = 0; i < s.size(); ++i) EXPECT_GT(s.normals.col(i).dot(s.points.col(i) - centre), 0.0);
}

TEST(BoundaryQuadrature, AreaAndClosedSurfaceOfTheCurvedBeam) {
  const BackgroundCells c = make_background_cells(geometry::make_volume_map(curved_beam_spec()), {4, 20, 2});
  const SurfaceQuadrature s = boundary_quadrature(c, {3, 3, 3});
  const Real pi = std::numbers::pi;
  const Real area = 2 * 0.25 * pi * (25 - 9) + 2 * 2 * 2 + 2 * (0.5 * pi * 3 + 0.5 * pi * 5);
  EXPECT_NEAR(s.weights.sum(), area, 1e-9 * area);
  Vec3 closed = Vec3::Zero();
  for (Index i = 0; i < s.size(); ++i) closed += s.weights[i] * s.normals.col(i);
  EXPECT_LT(closed.norm(), 1e-8);
  // the inner face (r = 3) has normals pointing to the origin
  for (Index i = 0; i < s.size(); ++i) {
    if (s.face[static_cast<std::size_t>(i)] == 0) {
      EXPECT_LT(s.normals.col(i).dot(Vec3(s.points(0, i), s.points(1, i), 0)), 0.0);
    }
  }
}

/// The R1a quarter plate [0, 10] x [0, 10] x [0, 1] (validation/efg_clamped_plate).
geometry::GeometrySpec quarter_plate_spec() {
  geometry::GeometrySpec g;
  g.type = geometry::GeometryType::box;
  g.min = Vec3(0, 0, 0);
  g.max = Vec3(10, 10, 1);
  return g;
}

TEST(BoundaryQuadrature, RefinedSelectionResolvesAPatchInsideACell) {
  const geometry::GeometrySpec g = quarter_plate_spec();
  const BackgroundCells c = make_background_cells(geometry::make_volume_map(g), {10, 10, 2});
  const SurfaceQuadrature s = boundary_quadrature(c, {3, 3, 3});
  auto patch = [](const Vec3& x, int face) { return face == 5 && x[0] > 9.5 && x[1] > 9.5; };
  const SurfaceQuadrature part = refine_selected_faces(c, s, {3, 3, 3}, 8, patch);
  EXPECT_NEAR(part.weights.sum(), 0.25, 1e-12);
  // without the refinement the Gauss points of the corner cell give a wrong area
  Real coarse = 0;
  for (Index i = 0; i < s.size(); ++i)
    if (patch(s.points.col(i), s.face[static_cast<std::size_t>(i)])) coarse += s.weights[i];
  EXPECT_GT(std::abs(coarse - 0.25), 0.01);
}

TEST(BoundaryQuadrature, ARegionBoundaryOffTheSubFaceGridKeepsTheAreaAndTheCentroid) {
  // 9 x 9 nodes on the R1a quarter plate: cells 1.25 wide, so the patch edge x = 9.5 lies inside a
  // sub-face (between its Gauss points and its edge); with the 8 x 8 sub-faces alone the patch came
  // out 12 % small (the R1a load 87.9 instead of 100)
  const geometry::GeometrySpec g = quarter_plate_spec();
  const BackgroundCells c = make_background_cells(geometry::make_volume_map(g), {8, 8, 3});
  const SurfaceQuadrature s = boundary_quadrature(c, {2, 2, 2});
  auto patch = [](const Vec3& x, int face) { return face == 5 && x[0] > 9.5 && x[1] > 9.5; };
  const SurfaceQuadrature part = refine_selected_faces(c, s, {2, 2, 2}, 8, patch);
  const Real area = part.weights.sum();
  EXPECT_NEAR(area, 0.25, 1e-3 * 0.25);
  Vec3 moment = Vec3::Zero();
  for (Index i = 0; i < part.size(); ++i) moment += part.weights[i] * part.points.col(i);
  EXPECT_NEAR(moment[0] / area, 9.75, 1e-3);
  EXPECT_NEAR(moment[1] / area, 9.75, 1e-3);
  // a disc of radius 0.7 around (3.1, 4.3), inside four cells and crossing their edges: area pi r^2, centroid
  const Vec3 centre(3.1, 4.3, 1.0);
  auto disc = [&](const Vec3& x, int face) { return face == 5 && (x - centre).head<2>().norm() < 0.7; };
  const SurfaceQuadrature round = refine_selected_faces(c, s, {2, 2, 2}, 8, disc);
  const Real disc_area = round.weights.sum();
  EXPECT_NEAR(disc_area, std::numbers::pi * 0.49, 2e-3 * std::numbers::pi * 0.49);
  Vec3 disc_moment = Vec3::Zero();
  for (Index i = 0; i < round.size(); ++i) disc_moment += round.weights[i] * round.points.col(i);
  EXPECT_NEAR(disc_moment[0] / disc_area, 3.1, 1e-3);
  EXPECT_NEAR(disc_moment[1] / disc_area, 4.3, 1e-3);
}

TEST(BoundaryQuadrature, APartOfACurvedFaceKeepsItsArea) {
  // the curved beam's outer face (r = 5, 90 degrees, z in [-1, 1]) where the polar angle is below 0.3 rad
  // and z above 0.37: an angle and a height that fall inside cells of the 4 x 20 x 2 background
  const BackgroundCells c = make_background_cells(geometry::make_volume_map(curved_beam_spec()), {4, 20, 2});
  const SurfaceQuadrature s = boundary_quadrature(c, {2, 2, 2});
  auto part = [](const Vec3& x, int) { return std::hypot(x[0], x[1]) > 5 - 1e-9 && std::atan2(x[1], x[0]) < 0.3 && x[2] > 0.37; };
  const SurfaceQuadrature selected = refine_selected_faces(c, s, {2, 2, 2}, 8, part);
  const Real area = 5 * 0.3 * (1 - 0.37);
  EXPECT_NEAR(selected.weights.sum(), area, 2e-3 * area);
  for (Index i = 0; i < selected.size(); ++i) EXPECT_NEAR(std::hypot(selected.points(0, i), selected.points(1, i)), 5.0, 1e-9);
}

TEST(BoundaryQuadrature, ASelectionOfAnAdjacentFacePlaneAddsNothingAlongTheSharedEdge) {
  // "x < 1e-9" holds on the face x = 0 and along the top face's edge x = 0: the top face gets no points
  const geometry::GeometrySpec g = quarter_plate_spec();
  const BackgroundCells c = make_background_cells(geometry::make_volume_map(g), {10, 10, 3});
  const SurfaceQuadrature s = boundary_quadrature(c, {2, 2, 2});
  auto clamp = [](const Vec3& x, int) { return x[0] < 1e-9; };
  const SurfaceQuadrature part = refine_selected_faces(c, s, {2, 2, 2}, 8, clamp);
  EXPECT_NEAR(part.weights.sum(), 10.0, 1e-10);
  for (Index i = 0; i < part.size(); ++i) EXPECT_EQ(part.face[static_cast<std::size_t>(i)], 0);
}

}  // namespace
}  // namespace lamina::efg
