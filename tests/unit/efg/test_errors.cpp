// Bad EFG input stops with an InputError (exit 2) or AnalysisError (exit 3) and a message that
// says what to change; nothing returns NaN.
#include <gtest/gtest.h>

#include "core/error.hpp"
#include "efg_test_helpers.hpp"

namespace lamina::efg {
namespace {

using namespace testing;

EfgProblem cantilever() {
  EfgProblem p = make_problem(box(Vec3::Zero(), Vec3(4, 1, 1)), {9, 3, 3}, 1e4, 0.3);
  fix_set(p, "xmin");
  traction_on_set(p, "xmax", Vec3(0, -1, 0));
  p.options.mls.basis = mls::Basis::quadratic;
  p.options.mls.kappa = 2.5;
  return p;
}

TEST(EfgErrors, CantileverRunsAndIsFinite) {
  EfgAnalysis a(cantilever(), {});
  a.solve();
  EXPECT_TRUE(a.nodal_parameters().allFinite());
  EXPECT_LT(a.displacement_at(Vec3(4, 0.5, 0.5))[1], 0.0);
}

TEST(EfgErrors, SupportTooSmallForTheBasisIsAnInputError) {
  EfgProblem p = cantilever();
  p.options.mls.kappa = 1.5;  // three nodes per direction are needed for a quadratic basis
  EfgAnalysis a(p, {});
  try {
    a.solve();
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("efg.support"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("kappa"), std::string::npos) << e.what();
  }
}

TEST(EfgErrors, FreeRigidBodyModeIsAnAnalysisError) {
  EfgProblem p = cantilever();
  p.constraints[0].fixed = {true, false, false};  // y and z translations free
  EfgAnalysis a(p, {});
  EXPECT_THROW(a.solve(), AnalysisError);
}

/// Lagrange multipliers on a nearly incompressible body with a one-point volumetric rule give a
/// system that the sparse LU solves backward-stably (backward error ~1e-25) yet whose solution
/// misses the equations by a relative residual of ~1e7: it must stop (exit 3), not return garbage.
TEST(EfgErrors, NearlySingularSystemIsAnAnalysisError) {
  EfgProblem p = make_problem(box(Vec3::Zero(), Vec3(10, 10, 1)), {11, 11, 3}, 1e4, 0.4999);
  model::Constraint clamp;
  clamp.select = set("xmin", p.cloud);
  clamp.fixed = {true, true, true};
  p.constraints.push_back(clamp);
  model::Constraint clamp_y = clamp;
  clamp_y.select = set("ymin", p.cloud);
  p.constraints.push_back(clamp_y);
  model::Load load;
  load.kind = model::Load::Kind::traction;
  load.select = set("zmax", p.cloud);
  load.vector = {constant(0.0), constant(0.0), constant(-1.0)};
  p.loads.push_back(load);
  p.options.mls.basis = mls::Basis::quadratic;
  p.options.mls.kappa = 2.5;
  p.options.reduced_volumetric = true;
  p.options.volumetric_gauss = {1, 1, 1};
  p.options.essential = EssentialMethod::lagrange;
  EfgAnalysis a(p, {});
  try {
    a.solve();
    FAIL() << "expected AnalysisError; displacement " << a.displacement_at(Vec3(10, 10, 0.5)).transpose();
  } catch (const AnalysisError& e) {
    EXPECT_NE(std::string(e.what()).find("nearly singular"), std::string::npos) << e.what();
  }
}

TEST(EfgErrors, NodeOutsideTheBodyIsAnInputError) {
  EfgProblem p = cantilever();
  p.cloud.positions(0, 5) = 7.0;
  EfgAnalysis a(p, {});
  EXPECT_THROW(a.solve(), InputError);
}

TEST(EfgErrors, TractionOnNoSurfaceIsAnInputError) {
  EfgProblem p = cantilever();
  p.loads[0].select = where("x > 1.9 and x < 2.1 and y > 0.4 and y < 0.6 and z > 0.4 and z < 0.6", p.cloud);
  ASSERT_FALSE(p.loads[0].select.nodes.empty());
  EfgAnalysis a(p, {});
  EXPECT_THROW(a.solve(), InputError);
}

TEST(EfgErrors, UncoveredMaterialRegionIsAnInputError) {
  EfgProblem p = cantilever();
  p.materials[0].region = where("x < 2", p.cloud);
  EfgAnalysis a(p, {});
  EXPECT_THROW(a.solve(), InputError);
}

TEST(EfgErrors, UnsupportedProbeIsRejectedUpFront) {
  Probe probe;
  probe.name = "v";
  probe.field = "velocity";
  probe.component = "x";
  probe.at = Vec3::Zero();
  EXPECT_THROW(EfgAnalysis(cantilever(), {probe}), InputError);
}

TEST(EfgErrors, NearlyIncompressibleMaterialRunsWithoutNaN) {
  EfgProblem p = cantilever();
  p.materials[0].elastic.nu = 0.4999;
  p.options.reduced_volumetric = true;
  EfgAnalysis a(p, {});
  a.solve();
  EXPECT_TRUE(a.nodal_parameters().allFinite());
}

/// A tube wall (radius 1, thickness 0.1, length 10 along x) with node counts in the given order.
EfgProblem tube(const std::array<int, 3>& nodes, mls::SupportShape shape) {
  EfgProblem p = make_problem(cylinder_spec(1.0, 10.0, 0, 0.1), nodes, 1e4, 0.3);
  p.options.mls.basis = mls::Basis::quadratic;
  p.options.mls.shape = shape;
  p.options.mls.kappa = shape == mls::SupportShape::sphere ? 2.5 : 2.0;
  return p;
}

bool mentions(const std::vector<std::string>& warnings, const std::string& text) {
  for (const auto& w : warnings)
    if (w.find(text) != std::string::npos) return true;
  return false;
}

// Node counts in the wrong order ([axial, circumferential, thickness] instead of [thickness,
// circumferential, axial]) give spacings 78 times apart: a sphere support then holds every node,
// the run takes minutes and ends singular. It is named up front.
TEST(EfgErrors, CrowdedSupportsAreWarnedAboutBeforeTheRun) {
  const auto wrong = EfgAnalysis(tube({33, 17, 3}, mls::SupportShape::sphere), {}).warnings();
  ASSERT_EQ(wrong.size(), 1u);
  EXPECT_TRUE(mentions(wrong, "discretization.nodes"));
  EXPECT_TRUE(mentions(wrong, "shape: box"));
  // the intended order: box supports are quiet; a sphere is told about the 12.6 x spacing ratio
  EXPECT_TRUE(EfgAnalysis(tube({3, 33, 17}, mls::SupportShape::box), {}).warnings().empty());
  const auto sphere = EfgAnalysis(tube({3, 33, 17}, mls::SupportShape::sphere), {}).warnings();
  ASSERT_EQ(sphere.size(), 1u);
  EXPECT_FALSE(mentions(sphere, "discretization.nodes")) << sphere[0];
  EXPECT_TRUE(mentions(sphere, "shape: box"));
  // a uniform cloud with a sphere support: no warning
  EfgProblem cube = make_problem(box(Vec3::Zero(), Vec3::Ones()), {5, 5, 5}, 1e4, 0.3);
  cube.options.mls.shape = mls::SupportShape::sphere;
  cube.options.mls.kappa = 2.5;
  EXPECT_TRUE(EfgAnalysis(cube, {}).warnings().empty());
}

}  // namespace
}  // namespace lamina::efg
