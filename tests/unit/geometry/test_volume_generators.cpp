// Structured volume nodes of every generator: counts, exact node volumes, containment,
// distinct nodes, named sets on the right faces, parametric coordinates and spacing.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <string>

#include "core/error.hpp"
#include "geometry/generators.hpp"
#include "geometry_test_helpers.hpp"

namespace lamina::geometry {
namespace {

using namespace testing;
using Predicate = std::function<bool(const Vec3&)>;

struct VolumeCase {
  std::string name;
  GeometrySpec spec;
  std::array<int, 3> counts;
  Index expected_nodes;
  Real scale;                                // body size, for tolerances
  std::map<std::string, Predicate> sets;     // set name -> which positions must be in it
  bool slit = false;
};

std::ostream& operator<<(std::ostream& os, const VolumeCase& c) { return os << c.name; }

constexpr Real kTol = 1e-9;  // relative position tolerance

std::vector<VolumeCase> volume_cases() {
  std::vector<VolumeCase> cases;
  auto near = [](Real a, Real b, Real scale) { return std::abs(a - b) < kTol * scale; };
  {
    VolumeCase c{"box", box_spec({0, -1, 2}, {3, 1, 2.5}), {4, 3, 2}, 24, 3.0, {}};
    c.sets = {{"xmin", [=](const Vec3& x) { return near(x.x(), 0, 3); }},
              {"xmax", [=](const Vec3& x) { return near(x.x(), 3, 3); }},
              {"ymin", [=](const Vec3& x) { return near(x.y(), -1, 3); }},
              {"ymax", [=](const Vec3& x) { return near(x.y(), 1, 3); }},
              {"zmin", [=](const Vec3& x) { return near(x.z(), 2, 3); }},
              {"zmax", [=](const Vec3& x) { return near(x.z(), 2.5, 3); }}};
    cases.push_back(c);
  }
  {
    // One node through z: the single layer sits at the middle and belongs to both z faces.
    VolumeCase c{"box_single_layer", box_spec({0, -6, 0}, {48, 6, 1}), {7, 4, 1}, 28, 48.0, {}};
    c.sets = {{"xmin", [=](const Vec3& x) { return near(x.x(), 0, 48); }},
              {"zmin", [=](const Vec3& x) { return near(x.z(), 0.5, 48); }},
              {"zmax", [=](const Vec3& x) { return near(x.z(), 0.5, 48); }}};
    cases.push_back(c);
  }
  {
    VolumeCase c{"plate", plate_spec(0, 0, 2, 1, 0.1), {5, 3, 3}, 45, 2.0, {}};
    c.sets = {{"xmin", [=](const Vec3& x) { return near(x.x(), 0, 2); }},
              {"xmax", [=](const Vec3& x) { return near(x.x(), 2, 2); }},
              {"ymin", [=](const Vec3& x) { return near(x.y(), 0, 2); }},
              {"ymax", [=](const Vec3& x) { return near(x.y(), 1, 2); }},
              {"bottom", [=](const Vec3& x) { return near(x.z(), -0.05, 2); }},
              {"top", [=](const Vec3& x) { return near(x.z(), 0.05, 2); }}};
    cases.push_back(c);
  }
  for (Real angle : {90.0, 200.0}) {
    // The seed's thick curved beam: 5 radial x 21 along the arc x 3 through z.
    VolumeCase c{angle == 90.0 ? "curved_beam_90" : "curved_beam_200", curved_beam_spec(4.12, 4.32, angle, 0.0, 0.1),
                 {5, 21, 3}, 315, 5.0, {}};
    const Real a = angle * pi / 180.0;
    c.sets = {{"inner", [=](const Vec3& x) { return near(std::hypot(x.x(), x.y()), 4.12, 5); }},
              {"outer", [=](const Vec3& x) { return near(std::hypot(x.x(), x.y()), 4.32, 5); }},
              {"start", [=](const Vec3& x) { return distance_to_half_plane(x.x(), x.y(), 0.0) < kTol * 5; }},
              {"end", [=](const Vec3& x) { return distance_to_half_plane(x.x(), x.y(), a) < kTol * 5; }},
              {"zmin", [=](const Vec3& x) { return near(x.z(), 0.0, 5); }},
              {"zmax", [=](const Vec3& x) { return near(x.z(), 0.1, 5); }}};
    cases.push_back(c);
  }
  {
    // Solid cylinder along x: the axis is one node per axial station (1 + 3 * 12 per station).
    VolumeCase c{"cylinder_solid", cylinder_spec(1.0, 2.0, 0, 0.0), {4, 12, 3}, 111, 2.0, {}};
    c.sets = {{"end0", [=](const Vec3& x) { return near(x.x(), 0, 2); }},
              {"end1", [=](const Vec3& x) { return near(x.x(), 2, 2); }},
              {"outer", [=](const Vec3& x) { return near(std::hypot(x.y(), x.z()), 1.0, 2); }}};
    cases.push_back(c);
  }
  {
    VolumeCase c{"cylinder_tube", cylinder_spec(1.0, 3.0, 2, 0.1), {3, 16, 4}, 192, 3.0, {}};
    c.sets = {{"end0", [=](const Vec3& x) { return near(x.z(), 0, 3); }},
              {"end1", [=](const Vec3& x) { return near(x.z(), 3, 3); }},
              {"inner", [=](const Vec3& x) { return near(std::hypot(x.x(), x.y()), 0.95, 3); }},
              {"outer", [=](const Vec3& x) { return near(std::hypot(x.x(), x.y()), 1.05, 3); }}};
    cases.push_back(c);
  }
  {
    // Tube panel along y: theta runs from +z towards +x.
    VolumeCase c{"cylinder_panel", cylinder_spec(2.0, 1.5, 1, 0.2, 60.0), {2, 7, 3}, 42, 2.0, {}};
    const Real a = 60.0 * pi / 180.0;
    c.sets = {{"end0", [=](const Vec3& x) { return near(x.y(), 0, 2); }},
              {"end1", [=](const Vec3& x) { return near(x.y(), 1.5, 2); }},
              {"edge0", [=](const Vec3& x) { return distance_to_half_plane(x.z(), x.x(), 0.0) < kTol * 2; }},
              {"edge1", [=](const Vec3& x) { return distance_to_half_plane(x.z(), x.x(), a) < kTol * 2; }},
              {"inner", [=](const Vec3& x) { return near(std::hypot(x.z(), x.x()), 1.9, 2); }},
              {"outer", [=](const Vec3& x) { return near(std::hypot(x.z(), x.x()), 2.1, 2); }}};
    cases.push_back(c);
  }
  {
    // Solid quarter cylinder: the axis nodes belong to both edges.
    VolumeCase c{"cylinder_solid_panel", cylinder_spec(1.0, 1.0, 2, 0.0, 90.0), {3, 5, 2}, 22, 1.0, {}};
    c.sets = {{"edge0", [=](const Vec3& x) { return distance_to_half_plane(x.x(), x.y(), 0.0) < kTol; }},
              {"edge1", [=](const Vec3& x) { return distance_to_half_plane(x.x(), x.y(), 0.5 * pi) < kTol; }},
              {"outer", [=](const Vec3& x) { return near(std::hypot(x.x(), x.y()), 1.0, 1); }}};
    cases.push_back(c);
  }
  {
    VolumeCase c{"sphere_cap_full", sphere_cap_spec(10.0, 0.5, 18.0, 360.0), {3, 9, 16}, 432, 10.0, {}};
    const Real h = 18.0 * pi / 180.0;
    c.sets = {{"hole", [=](const Vec3& x) { return near(std::atan2(std::hypot(x.x(), x.y()), x.z()), h, 1); }},
              {"base", [=](const Vec3& x) { return near(x.z(), 0.0, 10); }},
              {"inner", [=](const Vec3& x) { return near(x.norm(), 9.75, 10); }},
              {"outer", [=](const Vec3& x) { return near(x.norm(), 10.25, 10); }}};
    cases.push_back(c);
  }
  {
    VolumeCase c{"sphere_cap_sector", sphere_cap_spec(10.0, 0.04, 18.0, 90.0), {2, 8, 6}, 96, 10.0, {}};
    c.sets = {{"side0", [=](const Vec3& x) { return distance_to_half_plane(x.x(), x.y(), 0.0) < kTol * 10; }},
              {"side1", [=](const Vec3& x) { return distance_to_half_plane(x.x(), x.y(), 0.5 * pi) < kTol * 10; }},
              {"base", [=](const Vec3& x) { return near(x.z(), 0.0, 10); }}};
    cases.push_back(c);
  }
  {
    // No hole: the pole is one node per layer (1 + 5 * 8 per layer).
    VolumeCase c{"sphere_cap_closed", sphere_cap_spec(1.0, 0.1, 0.0, 360.0), {2, 6, 8}, 82, 1.0, {}};
    c.sets = {{"hole", [=](const Vec3& x) { return std::hypot(x.x(), x.y()) < kTol; }},
              {"base", [=](const Vec3& x) { return near(x.z(), 0.0, 1); }}};
    cases.push_back(c);
  }
  {
    VolumeCase c{"annulus", annulus_spec(6.0, 10.0, 0.03, false), {5, 24, 2}, 240, 10.0, {}};
    c.sets = {{"inner", [=](const Vec3& x) { return near(std::hypot(x.x(), x.y()), 6, 10); }},
              {"outer", [=](const Vec3& x) { return near(std::hypot(x.x(), x.y()), 10, 10); }},
              {"bottom", [=](const Vec3& x) { return near(x.z(), 0, 10); }},
              {"top", [=](const Vec3& x) { return near(x.z(), 0.03, 10); }}};
    cases.push_back(c);
  }
  {
    VolumeCase c{"annulus_slit", annulus_spec(6.0, 10.0, 0.03, true), {4, 25, 2}, 200, 10.0, {}, true};
    c.sets = {{"inner", [=](const Vec3& x) { return near(std::hypot(x.x(), x.y()), 6, 10); }},
              {"outer", [=](const Vec3& x) { return near(std::hypot(x.x(), x.y()), 10, 10); }}};
    cases.push_back(c);
  }
  for (Real rc : {0.1, 0.0}) {
    const GeometrySpec s = square_tube_spec(1.0, 2.0, rc, 0.05);
    VolumeCase c{rc > 0 ? "square_tube_rounded" : "square_tube_sharp", s, {rc > 0 ? 2 : 3, rc > 0 ? 32 : 24, 3},
                 rc > 0 ? 192 : 216, 2.0, {}};
    c.sets = {{"end0", [=](const Vec3& x) { return near(x.z(), 0, 2); }},
              {"end1", [=](const Vec3& x) { return near(x.z(), 2, 2); }},
              {"inner", [=](const Vec3& x) { return near(square_tube_offset(s, x.x(), x.y()), -0.025, 2); }},
              {"outer", [=](const Vec3& x) { return near(square_tube_offset(s, x.x(), x.y()), 0.025, 2); }}};
    cases.push_back(c);
  }
  return cases;
}

class VolumeNodes : public ::testing::TestWithParam<VolumeCase> {};

TEST_P(VolumeNodes, CountsAndLayout) {
  const VolumeCase& c = GetParam();
  const PointCloud cloud = generate_volume_nodes(c.spec, c.counts);
  EXPECT_EQ(cloud.size(), c.expected_nodes);
  EXPECT_EQ(cloud.volumes.size(), cloud.size());
  EXPECT_EQ(cloud.parametric.cols(), cloud.size());
  EXPECT_EQ(cloud.spacing.cols(), cloud.size());
  for (int d = 0; d < 3; ++d) EXPECT_EQ(cloud.counts[d], c.counts[d]);
}

TEST_P(VolumeNodes, VolumesSumToBodyVolume) {
  const VolumeCase& c = GetParam();
  const PointCloud cloud = generate_volume_nodes(c.spec, c.counts);
  const Real exact = body_volume(c.spec);
  ASSERT_GT(exact, 0.0);
  EXPECT_NEAR(cloud.volumes.sum() / exact, 1.0, 1e-10);
  EXPECT_GT(cloud.volumes.minCoeff(), 0.0);
}

TEST_P(VolumeNodes, NodesInsideBody) {
  const VolumeCase& c = GetParam();
  const PointCloud cloud = generate_volume_nodes(c.spec, c.counts);
  for (Index i = 0; i < cloud.size(); ++i)
    EXPECT_TRUE(body_contains(c.spec, cloud.point(i), kTol * c.scale)) << "node " << i << " at " << cloud.point(i).transpose();
}

TEST_P(VolumeNodes, NoCoincidentNodesExceptSlit) {
  const VolumeCase& c = GetParam();
  const PointCloud cloud = generate_volume_nodes(c.spec, c.counts);
  const auto pairs = coincident_pairs(cloud.positions, 1e-8 * c.scale);
  if (!c.slit) {
    EXPECT_TRUE(pairs.empty()) << pairs.size() << " coincident pairs, first " << pairs.front().first << ", "
                               << pairs.front().second;
    return;
  }
  const IndexList& start = cloud.sets.at("slit_start");
  const IndexList& end = cloud.sets.at("slit_end");
  ASSERT_EQ(start.size(), end.size());
  EXPECT_EQ(pairs.size(), start.size());
  for (const auto& [i, j] : pairs) {
    EXPECT_TRUE(std::binary_search(start.begin(), start.end(), i)) << i;
    EXPECT_TRUE(std::binary_search(end.begin(), end.end(), j)) << j;
  }
  for (Index i : start) EXPECT_NEAR(cloud.parametric(1, i), 0.0, 1e-14);
  for (Index i : end) EXPECT_NEAR(cloud.parametric(1, i), 2.0 * pi, 1e-14);
  EXPECT_EQ(static_cast<Index>(start.size()), static_cast<Index>(c.counts[0]) * c.counts[2]);
}

TEST_P(VolumeNodes, NamedSetsLieOnTheirFaces) {
  const VolumeCase& c = GetParam();
  const PointCloud cloud = generate_volume_nodes(c.spec, c.counts);
  for (const auto& [name, on] : c.sets) {
    ASSERT_TRUE(cloud.sets.count(name)) << "missing set " << name;
    const IndexList& set = cloud.sets.at(name);
    EXPECT_FALSE(set.empty()) << name;
    EXPECT_EQ(set, matching(cloud.positions, on)) << "set " << name;
  }
}

TEST_P(VolumeNodes, SpacingPositiveAndBoundedByBody) {
  const VolumeCase& c = GetParam();
  const PointCloud cloud = generate_volume_nodes(c.spec, c.counts);
  const Vec3 extent = cloud.positions.rowwise().maxCoeff() - cloud.positions.rowwise().minCoeff();
  for (Index i = 0; i < cloud.size(); ++i) {
    EXPECT_GT(cloud.spacing.col(i).maxCoeff(), 0.0) << i;
    EXPECT_GE(cloud.spacing.col(i).minCoeff(), 0.0) << i;
    for (int d = 0; d < 3; ++d)
      if (extent[d] > 0 && c.counts[2] > 1) {
        EXPECT_LE(cloud.spacing(d, i), extent[d] * (1 + 1e-12)) << i;
      }
  }
}

INSTANTIATE_TEST_SUITE_P(Generators, VolumeNodes, ::testing::ValuesIn(volume_cases()),
                         [](const ::testing::TestParamInfo<VolumeCase>& info) { return info.param.name; });

TEST(VolumeNodes, BoxSpacingVolumesAndOrdering) {
  const PointCloud cloud = generate_volume_nodes(box_spec({0, 0, 0}, {3, 2, 1}), {4, 3, 2});
  // i fastest: node 1 is one step along x, node 4 one along y, node 12 one along z.
  EXPECT_TRUE(cloud.point(1).isApprox(Vec3(1, 0, 0)));
  EXPECT_TRUE(cloud.point(4).isApprox(Vec3(0, 1, 0)));
  EXPECT_TRUE(cloud.point(12).isApprox(Vec3(0, 0, 1)));
  for (Index i = 0; i < cloud.size(); ++i) EXPECT_TRUE(cloud.spacing.col(i).isApprox(Vec3(1, 1, 1))) << i;
  // Corner node: an eighth of a cell; interior-of-face (x) node on an edge: a quarter.
  EXPECT_NEAR(cloud.volumes[0], 0.125, 1e-15);
  EXPECT_NEAR(cloud.volumes[1], 0.25, 1e-15);
  EXPECT_NEAR(cloud.volumes[5], 0.5, 1e-15);  // (1, 1, 0): interior in x and y, half in z
}

TEST(VolumeNodes, SingleLayerSpacingIsTheWholeExtent) {
  const PointCloud cloud = generate_volume_nodes(box_spec({0, -6, 0}, {48, 6, 1}), {49, 13, 1});
  for (Index i = 0; i < cloud.size(); ++i) EXPECT_TRUE(cloud.spacing.col(i).isApprox(Vec3(1, 1, 1))) << i;
  EXPECT_NEAR(cloud.volumes.sum(), 48.0 * 12.0, 1e-10);
}

TEST(VolumeNodes, CurvedNodeVolumesMatchTheirRings) {
  // Tributary volume of one radial ring of an annulus (interior ring: r +- dr/2, full turn).
  const GeometrySpec s = annulus_spec(1.0, 2.0, 0.5, false);
  const PointCloud cloud = generate_volume_nodes(s, {5, 10, 3});
  const Real dr = 0.25, r = 1.5;
  Real ring = 0;
  for (Index i = 0; i < cloud.size(); ++i)
    if (std::abs(cloud.parametric(0, i) - r) < 1e-12) ring += cloud.volumes[i];
  EXPECT_NEAR(ring, pi * ((r + dr / 2) * (r + dr / 2) - (r - dr / 2) * (r - dr / 2)) * 0.5, 1e-12);
}

TEST(VolumeNodes, ThroughThicknessLayersCarryTheirHalfOfTheWall) {
  // With 2 nodes through the wall, the inner/outer layers carry exactly the inner/outer half of
  // the wall (the whole-body sum cannot see a wrong split between them).
  struct Case {
    GeometrySpec spec;
    std::array<int, 3> counts;
    std::function<GeometrySpec(const GeometrySpec&, Real sign)> half;  // the half wall at sign * t/4
  };
  auto shifted = [](const GeometrySpec& s, Real sign) {
    GeometrySpec h = s;
    h.radius += sign * 0.25 * s.thickness;
    h.thickness *= 0.5;
    return h;
  };
  const std::vector<Case> cases = {
      {cylinder_spec(1.0, 2.0, 2, 0.3), {2, 12, 2}, shifted},
      {cylinder_spec(1.0, 2.0, 0, 0.3, 75), {2, 5, 2}, shifted},
      {sphere_cap_spec(2.0, 0.4, 18, 360), {2, 6, 12}, shifted},
      {sphere_cap_spec(2.0, 0.4, 0, 90), {2, 6, 4}, shifted},
      {square_tube_spec(1.0, 2.0, 0.1, 0.2), {2, 24, 2},
       [](const GeometrySpec& s, Real sign) {
         GeometrySpec h = s;
         h.width += sign * 0.5 * s.thickness;
         h.corner_radius += sign * 0.25 * s.thickness;
         h.thickness *= 0.5;
         return h;
       }},
      {square_tube_spec(1.0, 2.0, 0.0, 0.2), {2, 12, 2},
       [](const GeometrySpec& s, Real sign) {
         GeometrySpec h = s;
         h.width += sign * 0.5 * s.thickness;
         h.thickness *= 0.5;
         return h;
       }},
  };
  for (const Case& c : cases) {
    const PointCloud cloud = generate_volume_nodes(c.spec, c.counts);
    for (const auto& [set, sign] : {std::pair<std::string, Real>{"inner", -1.0}, {"outer", 1.0}}) {
      Real layer = 0;
      for (Index i : cloud.sets.at(set)) layer += cloud.volumes[i];
      EXPECT_NEAR(layer / body_volume(c.half(c.spec, sign)), 1.0, 1e-12) << to_string(c.spec.type) << " " << set;
    }
  }
}

TEST(VolumeNodes, SolidCylinderCentreCarriesTheInnerDisc) {
  const PointCloud cloud = generate_volume_nodes(cylinder_spec(1.0, 1.0, 2, 0.0), {3, 8, 2});
  // Node 0 is the axis node of the first station: disc r < 0.25, half the axial cell.
  EXPECT_TRUE(cloud.point(0).isZero());
  EXPECT_NEAR(cloud.volumes[0], pi * 0.25 * 0.25 * 0.5, 1e-14);
  // Its spacing covers the first ring in every transverse direction.
  EXPECT_NEAR(cloud.spacing(0, 0), 0.5, 1e-14);
  EXPECT_NEAR(cloud.spacing(1, 0), 0.5, 1e-14);
}

TEST(VolumeNodes, SquareTubeMultipleOfEightHitsSharpCorners) {
  const GeometrySpec s = square_tube_spec(2.0, 1.0, 0.0, 0.1);
  const PointCloud cloud = generate_volume_nodes(s, {2, 16, 2});
  // Outer layer, perimeter index 2 (s = 1 = quarter side beyond the start): the mitred corner.
  const Index corner = 1 + 2 * 2;
  EXPECT_TRUE(cloud.point(corner).isApprox(Vec3(1.05, 1.05, 0.0), 1e-14)) << cloud.point(corner).transpose();
}

TEST(VolumeNodes, RejectsBadCounts) {
  auto key_of = [](auto&& f) {
    try {
      f();
    } catch (const InputError& e) {
      return e.diagnostics().front().key_path;
    }
    return std::string("no error");
  };
  EXPECT_EQ(key_of([] { generate_volume_nodes(box_spec({0, 0, 0}, {1, 1, 1}), {0, 2, 2}); }), "discretization.nodes.0");
  EXPECT_EQ(key_of([] { generate_volume_nodes(cylinder_spec(1, 1, 2, 0.1), {2, 2, 2}); }), "discretization.nodes.1");
  EXPECT_EQ(key_of([] { generate_volume_nodes(cylinder_spec(1, 1, 2, 0.0), {1, 8, 2}); }), "discretization.nodes.0");
  EXPECT_EQ(key_of([] { generate_volume_nodes(annulus_spec(1, 2, 0.1, true), {2, 2, 2}); }), "discretization.nodes.1");
}

}  // namespace
}  // namespace lamina::geometry
