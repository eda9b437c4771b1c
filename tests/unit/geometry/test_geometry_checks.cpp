// Parameter validation, analytic volumes/areas and the point-in-body test.
#include <gtest/gtest.h>

#include <string>

#include "core/error.hpp"
#include "geometry/generators.hpp"
#include "geometry_test_helpers.hpp"

namespace lamina::geometry {
namespace {

using namespace testing;

std::string rejected_key(const GeometrySpec& spec) {
  try {
    validate_geometry(spec);
  } catch (const InputError& e) {
    return e.diagnostics().front().key_path;
  }
  return "accepted";
}

TEST(GeometryValidation, RejectsImpossibleParametersWithKeyPath) {
  EXPECT_EQ(rejected_key(box_spec({0, 0, 0}, {1, 0, 1})), "geometry.max");
  EXPECT_EQ(rejected_key(plate_spec(0, 0, 1, 1, 0.0)), "geometry.thickness");
  EXPECT_EQ(rejected_key(plate_spec(0, 0, 1, 1, -0.1)), "geometry.thickness");
  EXPECT_EQ(rejected_key(curved_beam_spec(2, 1, 90, 0, 1)), "geometry.outer_radius");
  EXPECT_EQ(rejected_key(curved_beam_spec(0, 1, 90, 0, 1)), "geometry.inner_radius");
  EXPECT_EQ(rejected_key(curved_beam_spec(1, 2, 360, 0, 1)), "geometry.angle");
  EXPECT_EQ(rejected_key(curved_beam_spec(1, 2, 90, 1, 1)), "geometry.z");
  EXPECT_EQ(rejected_key(cylinder_spec(0, 1, 2, 0)), "geometry.radius");
  EXPECT_EQ(rejected_key(cylinder_spec(1, 0, 2, 0)), "geometry.length");
  EXPECT_EQ(rejected_key(cylinder_spec(1, 1, 3, 0)), "geometry.axis");
  EXPECT_EQ(rejected_key(cylinder_spec(1, 1, 2, 2.0)), "geometry.thickness");
  EXPECT_EQ(rejected_key(cylinder_spec(1, 1, 2, 0.1, 0.0)), "geometry.angle");
  EXPECT_EQ(rejected_key(sphere_cap_spec(10, 0.1, 90, 360)), "geometry.polar_hole");
  EXPECT_EQ(rejected_key(sphere_cap_spec(10, 0.1, -1, 360)), "geometry.polar_hole");
  EXPECT_EQ(rejected_key(sphere_cap_spec(10, 0.1, 18, 400)), "geometry.sector");
  EXPECT_EQ(rejected_key(sphere_cap_spec(10, 0.0, 18, 90)), "geometry.thickness");
  EXPECT_EQ(rejected_key(annulus_spec(6, 6, 0.1, true)), "geometry.outer_radius");
  EXPECT_EQ(rejected_key(annulus_spec(6, 10, 0, true)), "geometry.thickness");
  EXPECT_EQ(rejected_key(square_tube_spec(1, 1, 0.5, 0.05)), "geometry.corner_radius");
  EXPECT_EQ(rejected_key(square_tube_spec(1, 1, 0.01, 0.05)), "geometry.corner_radius");
  EXPECT_EQ(rejected_key(square_tube_spec(1, 1, 0.1, 1.0)), "geometry.thickness");
  EXPECT_EQ(rejected_key(square_tube_spec(0, 1, 0.0, 0.1)), "geometry.width");
  EXPECT_EQ(rejected_key(plate_spec(0, 0, 1, NAN, 0.1)), "geometry.max");
  GeometrySpec mesh;
  mesh.type = GeometryType::mesh;
  EXPECT_EQ(rejected_key(mesh), "geometry.file");
}

TEST(GeometryValidation, AcceptsTheProductExamples) {
  EXPECT_EQ(rejected_key(box_spec({0, 0, 0}, {10, 10, 1})), "accepted");
  EXPECT_EQ(rejected_key(sphere_cap_spec(10, 0.04, 18, 90)), "accepted");
  EXPECT_EQ(rejected_key(curved_beam_spec(4.12, 4.32, 90, 0, 0.1)), "accepted");
  EXPECT_EQ(rejected_key(square_tube_spec(1, 10, 0.0, 0.05)), "accepted");
  EXPECT_EQ(rejected_key(cylinder_spec(300, 600, 0, 3)), "accepted");
  EXPECT_EQ(rejected_key(annulus_spec(6, 10, 0.03, true)), "accepted");
}

TEST(GeometryValidation, ErrorMessagesSayWhatWasExpected) {
  try {
    validate_geometry(curved_beam_spec(2, 1, 90, 0, 1));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.diagnostics().front().expected, "outer_radius > inner_radius");
    EXPECT_EQ(e.diagnostics().front().found, "1");
  }
}

TEST(AnalyticMeasures, VolumesAndAreas) {
  EXPECT_NEAR(body_volume(box_spec({0, 0, 0}, {2, 3, 4})), 24.0, 1e-12);
  EXPECT_NEAR(mid_surface_area(box_spec({0, 0, 0}, {2, 3, 0.5})), 6.0, 1e-12);
  EXPECT_NEAR(body_volume(plate_spec(0, 0, 2, 3, 0.1)), 0.6, 1e-12);
  EXPECT_NEAR(body_volume(curved_beam_spec(1, 2, 90, 0, 1)), 0.5 * (0.5 * pi) * 3 * 1, 1e-12);
  EXPECT_NEAR(mid_surface_area(curved_beam_spec(1, 2, 90, 0, 1)), 1.5 * 0.5 * pi, 1e-12);
  EXPECT_NEAR(body_volume(cylinder_spec(1, 2, 2, 0)), 2 * pi, 1e-12);
  EXPECT_NEAR(body_volume(cylinder_spec(1, 2, 2, 0.2)), pi * (1.1 * 1.1 - 0.9 * 0.9) * 2, 1e-12);
  EXPECT_NEAR(body_volume(cylinder_spec(1, 2, 2, 0.2, 90)), 0.25 * pi * (1.1 * 1.1 - 0.9 * 0.9) * 2, 1e-12);
  EXPECT_NEAR(mid_surface_area(cylinder_spec(1, 2, 2, 0.2)), 2 * pi * 2, 1e-12);
  // Hemisphere shell without hole: 2/3 pi (ro^3 - ri^3); area 2 pi R^2.
  EXPECT_NEAR(body_volume(sphere_cap_spec(1, 0.2, 0, 360)), 2.0 / 3.0 * pi * (1.331 - 0.729), 1e-12);
  EXPECT_NEAR(mid_surface_area(sphere_cap_spec(1, 0.2, 0, 360)), 2 * pi, 1e-12);
  EXPECT_NEAR(mid_surface_area(sphere_cap_spec(10, 0.2, 60, 90)), 100 * 0.5 * 0.5 * pi, 1e-10);
  EXPECT_NEAR(body_volume(annulus_spec(1, 2, 0.5, true)), pi * 3 * 0.5, 1e-12);
  // Square tube: exact section area of the frame, sharp corners ((w+t)^2 - (w-t)^2 = 4 w t) ...
  EXPECT_NEAR(body_volume(square_tube_spec(1, 2, 0, 0.1)), (1.1 * 1.1 - 0.9 * 0.9) * 2, 1e-12);
  // ... and rounded ones: outer rounded square minus inner rounded square.
  const Real w = 1, rc = 0.2, t = 0.1;
  auto rounded_square = [](Real width, Real r) { return width * width - (4 - pi) * r * r; };
  EXPECT_NEAR(body_volume(square_tube_spec(w, 3, rc, t)),
              (rounded_square(w + t, rc + t / 2) - rounded_square(w - t, rc - t / 2)) * 3, 1e-12);
  EXPECT_NEAR(mid_surface_area(square_tube_spec(w, 3, rc, t)), (4 * (w - 2 * rc) + 2 * pi * rc) * 3, 1e-12);
}

TEST(BodyContains, InsideAndOutside) {
  const Real e = 1e-3;
  const GeometrySpec box = box_spec({0, 0, 0}, {1, 2, 3});
  EXPECT_TRUE(body_contains(box, Vec3(1, 2, 3), 0));
  EXPECT_FALSE(body_contains(box, Vec3(1 + e, 1, 1), 0));
  EXPECT_TRUE(body_contains(box, Vec3(1 + e, 1, 1), 2 * e));

  const GeometrySpec plate = plate_spec(0, 0, 1, 1, 0.1);
  EXPECT_TRUE(body_contains(plate, Vec3(0.5, 0.5, -0.05), 0));
  EXPECT_FALSE(body_contains(plate, Vec3(0.5, 0.5, 0.05 + e), 0));

  const GeometrySpec beam = curved_beam_spec(1, 2, 90, 0, 1);
  EXPECT_TRUE(body_contains(beam, Vec3(0, 1.5, 0.5), 1e-12));
  EXPECT_FALSE(body_contains(beam, Vec3(-e, 1.5, 0.5), 0));
  EXPECT_TRUE(body_contains(beam, Vec3(-e, 1.5, 0.5), 2 * e));
  EXPECT_FALSE(body_contains(beam, Vec3(1.5, -e, 0.5), 0));
  EXPECT_FALSE(body_contains(beam, Vec3(-1.5, -0.1, 0.5), 0));
  EXPECT_FALSE(body_contains(beam, Vec3(0.7, 0.7, 0.5), 0));  // r < inner

  const GeometrySpec tube = cylinder_spec(1, 2, 0, 0.2);
  EXPECT_TRUE(body_contains(tube, Vec3(1, 0, 1.05), 0));
  EXPECT_FALSE(body_contains(tube, Vec3(1, 0, 0.85), 0));
  EXPECT_FALSE(body_contains(tube, Vec3(2 + e, 0, 1), 0));
  const GeometrySpec solid = cylinder_spec(1, 2, 1, 0.0);
  EXPECT_TRUE(body_contains(solid, Vec3(0, 1, 0), 0));
  EXPECT_FALSE(body_contains(solid, Vec3(0.8, 1, 0.8), 0));
  const GeometrySpec panel = cylinder_spec(1, 2, 2, 0.2, 45);  // theta from +x towards +y
  EXPECT_TRUE(body_contains(panel, Vec3(0.7, 0.7, 1), 1e-12));
  EXPECT_FALSE(body_contains(panel, Vec3(0.5, 0.8, 1), 0));

  const GeometrySpec cap = sphere_cap_spec(10, 0.2, 18, 90);
  const Real h = 18 * pi / 180;
  EXPECT_TRUE(body_contains(cap, 10 * Vec3(std::sin(h + 0.01) * std::cos(0.3), std::sin(h + 0.01) * std::sin(0.3), std::cos(h + 0.01)), 0));
  EXPECT_FALSE(body_contains(cap, 10 * Vec3(std::sin(h - 0.01) * std::cos(0.3), std::sin(h - 0.01) * std::sin(0.3), std::cos(h - 0.01)), 0));
  EXPECT_FALSE(body_contains(cap, Vec3(10, 0, -e), 0));
  EXPECT_FALSE(body_contains(cap, Vec3(-7, 7, 1), 0));  // outside the 90-degree sector
  EXPECT_FALSE(body_contains(cap, Vec3(0, 0, 10), 0));  // the hole

  const GeometrySpec ring = annulus_spec(6, 10, 0.1, true);
  EXPECT_TRUE(body_contains(ring, Vec3(8, 0, 0.05), 0));
  EXPECT_FALSE(body_contains(ring, Vec3(5, 0, 0.05), 0));
  EXPECT_FALSE(body_contains(ring, Vec3(8, 0, 0.1 + e), 0));

  const GeometrySpec sharp = square_tube_spec(1, 2, 0, 0.1);
  EXPECT_TRUE(body_contains(sharp, Vec3(0.54, 0.54, 1), 0));   // the outer corner of the frame
  EXPECT_TRUE(body_contains(sharp, Vec3(0.46, 0.0, 1), 0));
  EXPECT_FALSE(body_contains(sharp, Vec3(0.44, 0.0, 1), 0));
  EXPECT_FALSE(body_contains(sharp, Vec3(0.0, 0.0, 1), 0));
  const GeometrySpec rounded = square_tube_spec(1, 2, 0.2, 0.1);
  EXPECT_FALSE(body_contains(rounded, Vec3(0.54, 0.54, 1), 0));  // cut off by the rounding
  const Real c = 0.3 + 0.2 / std::sqrt(2.0);                     // corner arc midpoint
  EXPECT_TRUE(body_contains(rounded, Vec3(c, c, 1), 0));
  EXPECT_FALSE(body_contains(rounded, Vec3(c, c, 2 + e), 0));
}

TEST(GeometryType, Names) {
  EXPECT_STREQ(to_string(GeometryType::box), "box");
  EXPECT_STREQ(to_string(GeometryType::curved_beam), "curved_beam");
  EXPECT_STREQ(to_string(GeometryType::sphere_cap), "sphere_cap");
  EXPECT_STREQ(to_string(GeometryType::square_tube), "square_tube");
  EXPECT_STREQ(to_string(GeometryType::mesh), "mesh");
}

}  // namespace
}  // namespace lamina::geometry
