// Mid-surface shell meshes: element/node counts, orientation, area convergence, edge sets.
#include <gtest/gtest.h>

#include <map>
#include <set>
#include <string>

#include "core/error.hpp"
#include "geometry/generators.hpp"
#include "geometry_test_helpers.hpp"

namespace lamina::geometry {
namespace {

using namespace testing;
using Predicate = std::function<bool(const Vec3&)>;

struct ShellCase {
  std::string name;
  GeometrySpec spec;
  std::array<int, 2> elements;
  Index expected_nodes;
  Real scale;
  std::function<Vec3(const Vec3&)> normal;  // expected direction of the element normal at a point
  std::map<std::string, Predicate> sets;
  bool flat = false;  // the mesh represents the surface exactly
  bool slit = false;
  bool degenerate_pole = false;
};

std::ostream& operator<<(std::ostream& os, const ShellCase& c) { return os << c.name; }

constexpr Real kTol = 1e-9;

std::vector<ShellCase> shell_cases() {
  std::vector<ShellCase> cases;
  auto near = [](Real a, Real b, Real scale) { return std::abs(a - b) < kTol * scale; };
  auto all = [](const Vec3&) { return true; };
  auto plus_z = [](const Vec3&) { return Vec3(0, 0, 1); };
  auto radial_xy = [](const Vec3& x) { return Vec3(x.x(), x.y(), 0); };
  {
    ShellCase c{"plate", plate_spec(0, 0, 2, 1, 0.1), {4, 3}, 20, 2.0, plus_z, {}, true};
    c.sets = {{"xmin", [=](const Vec3& x) { return near(x.x(), 0, 2); }},
              {"xmax", [=](const Vec3& x) { return near(x.x(), 2, 2); }},
              {"ymin", [=](const Vec3& x) { return near(x.y(), 0, 2); }},
              {"ymax", [=](const Vec3& x) { return near(x.y(), 1, 2); }},
              {"top", all},
              {"bottom", all}};
    cases.push_back(c);
  }
  {
    // Thin in x: mid-surface x = 0.05, elements along y then z, normal +x.
    ShellCase c{"box_thin_x", box_spec({0, 0, 0}, {0.1, 3, 2}), {6, 4}, 35, 3.0, [](const Vec3&) { return Vec3(1, 0, 0); },
                {}, true};
    c.sets = {{"ymin", [=](const Vec3& x) { return near(x.y(), 0, 3); }},
              {"zmax", [=](const Vec3& x) { return near(x.z(), 2, 3); }},
              {"xmin", all},
              {"xmax", all}};
    cases.push_back(c);
  }
  {
    ShellCase c{"curved_beam", curved_beam_spec(4.12, 4.32, 90, 0, 0.1), {12, 2}, 39, 5.0, radial_xy, {}};
    c.sets = {{"start", [=](const Vec3& x) { return distance_to_half_plane(x.x(), x.y(), 0) < kTol * 5; }},
              {"end", [=](const Vec3& x) { return distance_to_half_plane(x.x(), x.y(), 0.5 * pi) < kTol * 5; }},
              {"zmax", [=](const Vec3& x) { return near(x.z(), 0.1, 5); }},
              {"outer", all}};
    cases.push_back(c);
  }
  {
    ShellCase c{"cylinder_tube", cylinder_spec(1.0, 3.0, 0, 0.01), {8, 3}, 32, 3.0,
                [](const Vec3& x) { return Vec3(0, x.y(), x.z()); }, {}};
    c.sets = {{"end0", [=](const Vec3& x) { return near(x.x(), 0, 3); }},
              {"end1", [=](const Vec3& x) { return near(x.x(), 3, 3); }}};
    cases.push_back(c);
  }
  {
    // Scordelis-Lo-like panel along y (theta from +z towards +x).
    ShellCase c{"cylinder_panel", cylinder_spec(25.0, 50.0, 1, 0.25, 80.0), {4, 4}, 25, 50.0,
                [](const Vec3& x) { return Vec3(x.x(), 0, x.z()); }, {}};
    c.sets = {{"edge0", [=](const Vec3& x) { return distance_to_half_plane(x.z(), x.x(), 0) < kTol * 50; }},
              {"edge1", [=](const Vec3& x) { return distance_to_half_plane(x.z(), x.x(), 80 * pi / 180) < kTol * 50; }},
              {"end0", [=](const Vec3& x) { return near(x.y(), 0, 50); }},
              {"end1", [=](const Vec3& x) { return near(x.y(), 50, 50); }}};
    cases.push_back(c);
  }
  {
    ShellCase c{"sphere_cap_full", sphere_cap_spec(10, 0.04, 18, 360), {4, 8}, 40, 10.0, [](const Vec3& x) { return x; }, {}};
    const Real h = 18 * pi / 180;
    c.sets = {{"hole", [=](const Vec3& x) { return near(std::atan2(std::hypot(x.x(), x.y()), x.z()), h, 1); }},
              {"base", [=](const Vec3& x) { return near(x.z(), 0, 10); }}};
    cases.push_back(c);
  }
  {
    ShellCase c{"sphere_cap_sector", sphere_cap_spec(10, 0.04, 18, 90), {4, 4}, 25, 10.0, [](const Vec3& x) { return x; }, {}};
    c.sets = {{"side0", [=](const Vec3& x) { return distance_to_half_plane(x.x(), x.y(), 0) < kTol * 10; }},
              {"side1", [=](const Vec3& x) { return distance_to_half_plane(x.x(), x.y(), 0.5 * pi) < kTol * 10; }},
              {"base", [=](const Vec3& x) { return near(x.z(), 0, 10); }}};
    cases.push_back(c);
  }
  {
    ShellCase c{"sphere_cap_closed", sphere_cap_spec(1, 0.01, 0, 360), {6, 8}, 1 + 6 * 8, 1.0, [](const Vec3& x) { return x; }, {}};
    c.degenerate_pole = true;
    c.sets = {{"hole", [=](const Vec3& x) { return std::hypot(x.x(), x.y()) < kTol; }},
              {"base", [=](const Vec3& x) { return near(x.z(), 0, 1); }}};
    cases.push_back(c);
  }
  {
    ShellCase c{"annulus", annulus_spec(6, 10, 0.03, false), {2, 12}, 36, 10.0, plus_z, {}};
    c.sets = {{"inner", [=](const Vec3& x) { return near(std::hypot(x.x(), x.y()), 6, 10); }},
              {"outer", [=](const Vec3& x) { return near(std::hypot(x.x(), x.y()), 10, 10); }},
              {"top", all}};
    cases.push_back(c);
  }
  {
    ShellCase c{"annulus_slit", annulus_spec(6, 10, 0.03, true), {2, 12}, 39, 10.0, plus_z, {}};
    c.slit = true;
    c.sets = {{"inner", [=](const Vec3& x) { return near(std::hypot(x.x(), x.y()), 6, 10); }},
              {"outer", [=](const Vec3& x) { return near(std::hypot(x.x(), x.y()), 10, 10); }}};
    cases.push_back(c);
  }
  for (Real rc : {0.2, 0.0}) {
    ShellCase c{rc > 0 ? "square_tube_rounded" : "square_tube_sharp", square_tube_spec(1.0, 4.0, rc, 0.05), {16, 4}, 80, 4.0,
                [](const Vec3& x) {
                  // outward: the dominant section coordinate direction (corners: diagonal)
                  return Vec3(std::abs(x.x()) >= std::abs(x.y()) - 1e-12 ? x.x() : 0.0,
                              std::abs(x.y()) >= std::abs(x.x()) - 1e-12 ? x.y() : 0.0, 0.0);
                },
                {}};
    c.flat = rc == 0.0;  // 16 around the perimeter puts nodes on the sharp corners
    c.sets = {{"end0", [=](const Vec3& x) { return near(x.z(), 0, 4); }},
              {"end1", [=](const Vec3& x) { return near(x.z(), 4, 4); }}};
    cases.push_back(c);
  }
  return cases;
}

class ShellMeshes : public ::testing::TestWithParam<ShellCase> {};

TEST_P(ShellMeshes, CountsConnectivityAndOrientation) {
  const ShellCase& c = GetParam();
  const ShellMesh mesh = generate_shell_mesh(c.spec, c.elements);
  EXPECT_EQ(mesh.node_count(), c.expected_nodes);
  EXPECT_EQ(mesh.element_count(), static_cast<Index>(c.elements[0]) * c.elements[1]);
  EXPECT_GT(mesh.thickness, 0.0);
  for (Index e = 0; e < mesh.element_count(); ++e) {
    std::set<Index> distinct;
    for (int a = 0; a < 4; ++a) {
      ASSERT_GE(mesh.quads(a, e), 0);
      ASSERT_LT(mesh.quads(a, e), mesh.node_count());
      distinct.insert(mesh.quads(a, e));
    }
    EXPECT_GE(distinct.size(), c.degenerate_pole ? 3u : 4u) << "element " << e;
    Vec3 x[4];
    for (int a = 0; a < 4; ++a) x[a] = mesh.nodes.col(mesh.quads(a, e));
    const Vec3 normal = (x[2] - x[0]).cross(x[3] - x[1]);
    const Vec3 centre = 0.25 * (x[0] + x[1] + x[2] + x[3]);
    EXPECT_GT(normal.dot(c.normal(centre)), 0.0) << "element " << e << " at " << centre.transpose();
  }
}

TEST_P(ShellMeshes, NoCoincidentNodesExceptSlit) {
  const ShellCase& c = GetParam();
  const ShellMesh mesh = generate_shell_mesh(c.spec, c.elements);
  const auto pairs = coincident_pairs(mesh.nodes, 1e-8 * c.scale);
  if (!c.slit) {
    EXPECT_TRUE(pairs.empty());
    return;
  }
  const IndexList& start = mesh.sets.at("slit_start");
  const IndexList& end = mesh.sets.at("slit_end");
  EXPECT_EQ(start.size(), static_cast<std::size_t>(c.elements[0] + 1));
  ASSERT_EQ(pairs.size(), start.size());
  for (const auto& [i, j] : pairs) {
    EXPECT_TRUE(std::binary_search(start.begin(), start.end(), i));
    EXPECT_TRUE(std::binary_search(end.begin(), end.end(), j));
  }
  // The two sides of the slit share no element.
  for (Index e = 0; e < mesh.element_count(); ++e) {
    bool has_start = false, has_end = false;
    for (int a = 0; a < 4; ++a) {
      has_start |= std::binary_search(start.begin(), start.end(), mesh.quads(a, e));
      has_end |= std::binary_search(end.begin(), end.end(), mesh.quads(a, e));
    }
    EXPECT_FALSE(has_start && has_end) << e;
  }
}

TEST_P(ShellMeshes, AreaConvergesToMidSurfaceArea) {
  const ShellCase& c = GetParam();
  const Real exact = mid_surface_area(c.spec);
  Real previous = INFINITY;
  for (int refine : {1, 2, 4, 8}) {
    const ShellMesh mesh = generate_shell_mesh(c.spec, {c.elements[0] * refine, c.elements[1] * refine});
    const Real error = std::abs(mesh.area() - exact) / exact;
    if (c.flat) {
      EXPECT_LT(error, 1e-12) << "refinement " << refine;
    } else {
      EXPECT_LT(error, previous) << "refinement " << refine;
      EXPECT_LT(mesh.area(), exact) << "inscribed bilinear facets underestimate the area";
    }
    previous = error;
  }
  EXPECT_LT(previous, 1e-3);
}

TEST_P(ShellMeshes, EdgeSets) {
  const ShellCase& c = GetParam();
  const ShellMesh mesh = generate_shell_mesh(c.spec, c.elements);
  for (const auto& [name, on] : c.sets) {
    ASSERT_TRUE(mesh.sets.count(name)) << "missing set " << name;
    EXPECT_FALSE(mesh.sets.at(name).empty()) << name;
    EXPECT_EQ(mesh.sets.at(name), matching(mesh.nodes, on)) << "set " << name;
  }
}

TEST_P(ShellMeshes, NodesOnTheMidSurfaceInsideTheBody) {
  const ShellCase& c = GetParam();
  const ShellMesh mesh = generate_shell_mesh(c.spec, c.elements);
  for (Index i = 0; i < mesh.node_count(); ++i) EXPECT_TRUE(body_contains(c.spec, mesh.nodes.col(i), kTol * c.scale)) << i;
}

INSTANTIATE_TEST_SUITE_P(Generators, ShellMeshes, ::testing::ValuesIn(shell_cases()),
                         [](const ::testing::TestParamInfo<ShellCase>& info) { return info.param.name; });

TEST(ShellMeshes, AnnulusMidSurfaceAtHalfThickness) {
  const ShellMesh mesh = generate_shell_mesh(annulus_spec(1, 2, 0.2, false), {2, 8});
  for (Index i = 0; i < mesh.node_count(); ++i) EXPECT_DOUBLE_EQ(mesh.nodes(2, i), 0.1);
  EXPECT_DOUBLE_EQ(mesh.thickness, 0.2);
}

TEST(ShellMeshes, ThicknessOfEachGenerator) {
  EXPECT_DOUBLE_EQ(generate_shell_mesh(curved_beam_spec(4, 5, 45, 0, 1), {2, 2}).thickness, 1.0);
  EXPECT_DOUBLE_EQ(generate_shell_mesh(box_spec({0, 0, 0}, {10, 10, 0.5}), {2, 2}).thickness, 0.5);
  EXPECT_DOUBLE_EQ(generate_shell_mesh(plate_spec(0, 0, 1, 1, 0.01), {2, 2}).thickness, 0.01);
}

TEST(ShellMeshes, SolidCylinderHasNoMidSurface) {
  try {
    generate_shell_mesh(cylinder_spec(1, 1, 2, 0.0), {8, 2});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.diagnostics().front().key_path, "geometry.thickness");
    EXPECT_NE(std::string(e.what()).find("solid cylinder has no shell mid-surface"), std::string::npos);
  }
  EXPECT_THROW(mid_surface_area(cylinder_spec(1, 1, 2, 0.0)), InputError);
}

TEST(ShellMeshes, RejectsTooFewElementsAroundClosedSections) {
  EXPECT_THROW(generate_shell_mesh(cylinder_spec(1, 1, 2, 0.1), {2, 2}), InputError);
  EXPECT_THROW(generate_shell_mesh(square_tube_spec(1, 1, 0.1, 0.05), {2, 2}), InputError);
  EXPECT_THROW(generate_shell_mesh(plate_spec(0, 0, 1, 1, 0.1), {0, 2}), InputError);
  EXPECT_NO_THROW(generate_shell_mesh(plate_spec(0, 0, 1, 1, 0.1), {1, 1}));
}

}  // namespace
}  // namespace lamina::geometry
