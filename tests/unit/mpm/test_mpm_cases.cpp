// `method: mpm` end to end through the lamina binary: bad shell meshes and a grid too coarse for the
// elements are rejected with exit 2 and a clear message; a run made unstable stops with exit 3;
// a small linear cantilever matches beam theory (issue 5 acceptance 5); shell.hourglass_bending is
// read and range-checked; the Newton quasi-static solver (the default) against beam theory and the
// elastica, its input checks, and its fall-back to explicit dynamics beyond a collapse load.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

namespace {

namespace fs = std::filesystem;

struct Outcome {
  int exit_code = -1;
  std::string output;
};

Outcome run_case(const std::string& name, const std::string& yaml, const std::string& extra = "", bool check_only = false) {
  const fs::path dir = fs::temp_directory_path() / ("lamina_mpm_test_" + name);
  fs::create_directories(dir);
  const fs::path file = dir / (name + ".yaml");
  std::ofstream(file) << yaml;
  const std::string command = check_only ? std::string(LAMINA_BINARY) + " check " + file.string() + " " + extra + " 2>&1 >/dev/null"
                                         : std::string(LAMINA_BINARY) + " run " + file.string() + " -o " + (dir / "out").string() +
                                               " --quiet --threads 1 " + extra + " 2>&1";
  Outcome o;
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(command.c_str(), "r"), pclose);
  std::array<char, 4096> buffer{};
  while (fgets(buffer.data(), buffer.size(), pipe.get())) o.output += buffer.data();
  const int status = pclose(pipe.release());
  o.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return o;
}

const std::string kStrip = R"(
title: strip
method: mpm
materials:
  - {name: s, model: linear_elastic, E: 1.2e6, nu: 0.0, density: 1.0}
geometry: {type: plate, min: [0, 0], max: [10, 1], thickness: 0.1}
discretization: {elements: [10, 1]}
boundary:
  - {select: {set: xmin}, fix: [x, y, z, rx, ry, rz]}
loads:
  - {select: {set: xmax}, traction: [0, 0, 0.004]}
mpm: {load_levels: 1, tolerance: 1.0e-5}
probes:
  - {name: w_tip, field: displacement, component: z, at: [10, 0, 0]}
)";

TEST(mpm_Cases, LinearCantileverMatchesBeamTheory) {
  const Outcome o = run_case("linear", kStrip);
  ASSERT_EQ(o.exit_code, 0) << o.output;
  std::ifstream summary(fs::temp_directory_path() / "lamina_mpm_test_linear" / "out" / "summary.json");
  const std::string text((std::istreambuf_iterator<char>(summary)), std::istreambuf_iterator<char>());
  const auto at = text.find("\"w_tip\":");
  ASSERT_NE(at, std::string::npos);
  const double w = std::stod(text.substr(at + 8));
  // P L^3 / (3 EI) + P L / (k G A): P = 0.004, L = 10, EI = 100, k G A = 5/6 * 6e5 * 0.1
  const double exact = 0.004 * 1000.0 / 300.0 + 0.004 * 10.0 / (5.0 / 6.0 * 6.0e5 * 0.1);
  EXPECT_NEAR(w, exact, 0.01 * exact);
}

TEST(mpm_Cases, DegenerateElementsAreRejected) {
  // a sphere cap without a polar hole has quadrilaterals with the pole node repeated
  const std::string yaml = R"(
title: cap
method: mpm
materials:
  - {name: s, model: linear_elastic, E: 1.0e6, nu: 0.3, density: 1.0}
geometry: {type: sphere_cap, radius: 10, thickness: 0.1, polar_hole: 0, sector: 90}
discretization: {elements: [4, 4]}
loads:
  - {select: all, body_force: [0, 0, -1]}
)";
  const Outcome o = run_case("degenerate", yaml);
  EXPECT_EQ(o.exit_code, 2) << o.output;
  EXPECT_NE(o.output.find("discretization.elements"), std::string::npos) << o.output;
  EXPECT_NE(o.output.find("repeated node"), std::string::npos) << o.output;
}

TEST(mpm_Cases, GridTooCoarseIsRejected) {
  const Outcome o = run_case("coarse", kStrip, "--set discretization.grid.cell=5.0");
  EXPECT_EQ(o.exit_code, 2) << o.output;
  EXPECT_NE(o.output.find("discretization.grid.cell"), std::string::npos) << o.output;
  EXPECT_NE(o.output.find("median element edge"), std::string::npos) << o.output;
}

TEST(mpm_Cases, UnstableRunStopsWithExitThree) {
  const Outcome o = run_case("unstable", kStrip, "--set mpm.solver=explicit --set mpm.time_step.fixed=0.01");
  EXPECT_EQ(o.exit_code, 3) << o.output;
  EXPECT_NE(o.output.find("unstable"), std::string::npos) << o.output;
}

/// The text of a result file of run_case(name, ...): summary.json, log.txt, ...
std::string output_file(const std::string& name, const std::string& file) {
  std::ifstream in(fs::temp_directory_path() / ("lamina_mpm_test_" + name) / "out" / file);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

/// Checks with `lamina check` that the case with `extra` settings is refused (exit 2) naming `needle`.
void expect_refused(const std::string& name, const std::string& yaml, const std::string& extra, const std::string& needle) {
  const Outcome o = run_case(name, yaml, extra, true);
  EXPECT_EQ(o.exit_code, 2) << o.output;
  EXPECT_NE(o.output.find(needle), std::string::npos) << o.output;
}

double summary_value(const std::string& name, const std::string& key) {
  const std::string text = output_file(name, "summary.json");
  const auto at = text.find("\"" + key + "\":");
  if (at == std::string::npos) return std::nan("");
  return std::stod(text.substr(at + key.size() + 3));
}

// Mass scaling (mpm.mass_scaling: stiffness) and the physical-mass default reach the same static answer;
// the fictitious masses (Gershgorin bound) keep the run stable at dt = 1 and the energy balance closed.
TEST(mpm_Cases, MassScaledAndPhysicalQuasiStaticAgree) {
  const double exact = 0.004 * 1000.0 / 300.0 + 0.004 * 10.0 / (5.0 / 6.0 * 6.0e5 * 0.1);
  const Outcome scaled = run_case("scaled", kStrip, "--set mpm.mass_scaling=stiffness");
  ASSERT_EQ(scaled.exit_code, 0) << scaled.output;
  const Outcome physical = run_case("physical", kStrip, "--set mpm.solver=explicit");
  ASSERT_EQ(physical.exit_code, 0) << physical.output;
  EXPECT_NEAR(summary_value("scaled", "w_tip"), exact, 0.01 * exact);
  EXPECT_NEAR(summary_value("physical", "w_tip"), exact, 0.01 * exact);
  EXPECT_EQ(summary_value("scaled", "time_step"), 1.0);
  EXPECT_NEAR(summary_value("scaled", "energy_ratio"), 1.0, 0.05);
}

TEST(mpm_Cases, AdaptiveDampingNeedsMassScaling) {
  expect_refused("adaptive_physical", kStrip, "--set mpm.damping.adaptive=true", "mass_scaling");
  const Outcome bad = run_case("mass_scaling_word", kStrip, "--set mpm.mass_scaling=fictitious", true);
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
}

TEST(mpm_Cases, BendingHourglassCoefficientIsReadAndRangeChecked) {
  // the cantilever stores no hourglass energy, so the physical bending coefficient leaves it unchanged
  const Outcome ok = run_case("hg_bending", kStrip, "--set shell.hourglass=0.1 --set shell.hourglass_bending=1.0");
  ASSERT_EQ(ok.exit_code, 0) << ok.output;
  std::ifstream summary(fs::temp_directory_path() / "lamina_mpm_test_hg_bending" / "out" / "summary.json");
  const std::string text((std::istreambuf_iterator<char>(summary)), std::istreambuf_iterator<char>());
  const auto at = text.find("\"w_tip\":");
  ASSERT_NE(at, std::string::npos);
  const double exact = 0.004 * 1000.0 / 300.0 + 0.004 * 10.0 / (5.0 / 6.0 * 6.0e5 * 0.1);
  EXPECT_NEAR(std::stod(text.substr(at + 8)), exact, 0.01 * exact);
  const Outcome bad = run_case("hg_bending_bad", kStrip, "--set shell.hourglass=0.1 --set shell.hourglass_bending=3.0");
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("shell.hourglass_bending"), std::string::npos) << bad.output;
  // a per-mode coefficient without a coefficient model (the default is physical) is refused, not ignored
  const Outcome orphan = run_case("hg_bending_physical", kStrip, "--set shell.hourglass_bending=1.0");
  EXPECT_EQ(orphan.exit_code, 2) << orphan.output;
  EXPECT_NE(orphan.output.find("shell.hourglass_bending"), std::string::npos) << orphan.output;
  EXPECT_NE(orphan.output.find("physical"), std::string::npos) << orphan.output;
  const Outcome word = run_case("hg_word", kStrip, "--set shell.hourglass=viscous");
  EXPECT_EQ(word.exit_code, 2) << word.output;
  EXPECT_NE(word.output.find("physical"), std::string::npos) << word.output;
}

TEST(mpm_Cases, PhysicalHourglassIsTheDefaultAndMatchesTheCantilever) {
  // the physical stabilisation needs no coefficient: the cantilever tip within 1 % of beam theory
  const Outcome o = run_case("hg_physical", kStrip, "--set shell.hourglass=physical");
  ASSERT_EQ(o.exit_code, 0) << o.output;
  const double exact = 0.004 * 1000.0 / 300.0 + 0.004 * 10.0 / (5.0 / 6.0 * 6.0e5 * 0.1);
  EXPECT_NEAR(summary_value("hg_physical", "w_tip"), exact, 0.01 * exact);
}


TEST(mpm_Cases, InitialVelocityIsAnEnergyInput) {
  // the strip thrown sideways (all free nodes at 0.05 in z) vibrates about its clamped end: the energy
  // of the initial velocities is the only input, so total = KE + internal + hourglass - KE0 stays ~0
  const std::string yaml = kStrip.substr(0, kStrip.find("loads:")) + R"(loads:
  - {select: all, initial_velocity: [0, 0, 0.05]}
mpm: {analysis: dynamic, end_time: 2.0, output_points: 2}
probes:
  - {name: w_tip, field: displacement, component: z, at: [10, 0, 0]}
)";
  const Outcome o = run_case("initial_velocity", yaml);
  ASSERT_EQ(o.exit_code, 0) << o.output;
  const double internal = summary_value("initial_velocity", "energy_internal");
  const double kinetic = summary_value("initial_velocity", "energy_kinetic");
  const double total = summary_value("initial_velocity", "energy_total");
  EXPECT_GT(internal, 1e-4 * (internal + kinetic));  // it has deformed
  EXPECT_LT(std::abs(total), 0.01 * (internal + kinetic));
  EXPECT_NEAR(summary_value("initial_velocity", "energy_ratio"), 1.0, 0.01);
}

TEST(mpm_Cases, FlipKeepsTheVelocityTheGridDoesNotSee) {
  // the strip thrown with a velocity that alternates from node to node, on a grid of the element's size
  // (each grid node halfway between two shell nodes): the grid sees none of it. PIC (flip: 0, the default)
  // replaces the nodes' velocity by the grid's, which is zero: the whole kinetic energy is booked as
  // transfer loss and the balance stays closed. FLIP (flip: 1, seed eq (8)) carries the velocity from step
  // to step and books no transfer loss; the energy stays in the body. (Its balance drifts, 0.84 after 0.05
  // time units: a velocity the grid does not see never moves the nodes; docs/mpm.md "PIC/FLIP choice". Not
  // asserted: that is a limit of FLIP, not a property to keep.)
  const std::string yaml = kStrip.substr(0, kStrip.find("discretization:")) + R"yaml(discretization: {elements: [10, 1], grid: {cell: 1.0}}
boundary:
  - {select: {set: xmin}, fix: [x, y, z, rx, ry, rz]}
loads:
  - {select: all, initial_velocity: [0, 0, "0.05*cos(pi*x)"]}
mpm: {analysis: dynamic, end_time: 0.05, output_points: 1}
output: {vtu: false}
)yaml";
  const Outcome pic = run_case("alternating_pic", yaml);
  ASSERT_EQ(pic.exit_code, 0) << pic.output;
  EXPECT_NEAR(summary_value("alternating_pic", "energy_ratio"), 1.0, 0.01);
  EXPECT_LT(summary_value("alternating_pic", "energy_kinetic"), 1e-3 * summary_value("alternating_pic", "energy_transfer"));
  const Outcome flip = run_case("alternating_flip", yaml, "--set mpm.flip=1");
  ASSERT_EQ(flip.exit_code, 0) << flip.output;
  EXPECT_EQ(summary_value("alternating_flip", "energy_transfer"), 0.0);
  EXPECT_GT(summary_value("alternating_flip", "energy_kinetic") + summary_value("alternating_flip", "energy_internal"),
            0.5 * summary_value("alternating_pic", "energy_transfer"));  // kept in the body (0.84 of it)
}

TEST(mpm_Cases, RegularPlateDoesNotRebuildTheGridEveryStep) {
  // a flat 20 x 20 plate in z = 0 clamped on one edge and thrown out of its plane: its nodes move along z
  // only (in-plane motion at round-off). With the grid's origin a whole number of cells off the nodes, they
  // sat on cell faces, round-off flipped them between cells and the connectivity was rebuilt at almost
  // every one of the 100 steps; mid-cell, it is built once and rebuilt only as the plate leaves its layer
  const std::string yaml = R"(
title: thrown plate
method: mpm
materials: [{name: p, model: linear_elastic, E: 1.0e6, nu: 0.3, density: 1.0}]
geometry: {type: plate, min: [0, 0], max: [0.2, 0.2], thickness: 0.01}
discretization: {elements: [20, 20]}
boundary: [{select: {set: xmin}, fix: [x, y, z, rx, ry, rz]}]
loads: [{select: all, initial_velocity: [0, 0, "0.1*x"]}]
mpm: {analysis: dynamic, end_time: 1.0e-4, output_points: 1, time_step: {fixed: 1.0e-6}}
output: {vtu: false}
)";
  const Outcome o = run_case("thrown_plate", yaml);
  ASSERT_EQ(o.exit_code, 0) << o.output;
  EXPECT_EQ(summary_value("thrown_plate", "steps"), 100.0);
  const double rebuilds = summary_value("thrown_plate", "stage_grid_rebuilds");
  EXPECT_GE(rebuilds, 1.0);
  EXPECT_LE(rebuilds, 3.0);
}

TEST(mpm_Cases, RzFixedEverywhereIsWarnedAbout) {
  // a flat membrane with rz held at every node: the drilling penalty would hold the in-plane rotation
  std::string yaml = kStrip;
  const std::string clamp_line = "  - {select: {set: xmin}, fix: [x, y, z, rx, ry, rz]}\n";
  yaml.replace(yaml.find(clamp_line), clamp_line.size(), clamp_line + "  - {select: all, fix: [rz]}\n");
  const Outcome held = run_case("rz_everywhere", yaml, "", true);
  ASSERT_EQ(held.exit_code, 0) << held.output;
  EXPECT_NE(held.output.find("warning: rz is fixed at 22 of 22 nodes"), std::string::npos) << held.output;
  const Outcome clamp = run_case("rz_clamp_only", kStrip, "", true);
  ASSERT_EQ(clamp.exit_code, 0) << clamp.output;
  EXPECT_EQ(clamp.output.find("rz is fixed"), std::string::npos) << clamp.output;
}

TEST(mpm_Cases, PlasticSetUpsThatMisleadAreWarnedAbout) {
  const std::string yaml = R"(
title: plastic strip
method: mpm
materials:
  - {name: s, model: j2_plasticity, E: 2.0e5, nu: 0.3, density: 7.85e-9, yield: 200}
geometry: {type: plate, min: [0, 0], max: [100, 10], thickness: 1.0}
discretization: {elements: [10, 2]}
boundary:
  - {select: {set: xmin}, fix: [x, y, z, rx, ry, rz]}
loads:
  - {select: {set: xmax}, traction: [250, 0, 0]}
)";
  const Outcome plain = run_case("plastic_warnings", yaml, "--set mpm.solver=explicit --set shell.thickness_points=3", true);
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  EXPECT_NE(plain.output.find("warning: shell.thickness_points = 3"), std::string::npos) << plain.output;
  EXPECT_NE(plain.output.find("warning: mpm.level_ramp_steps = 0"), std::string::npos) << plain.output;
  // the Newton levels (the default) are static: no overshoot, no ramp advice
  const Outcome newton = run_case("plastic_warnings_newton", yaml, "", true);
  ASSERT_EQ(newton.exit_code, 0) << newton.output;
  EXPECT_EQ(newton.output.find("level_ramp_steps"), std::string::npos) << newton.output;
  // with a plastic material the default is 7 Lobatto points: no thickness-point warning
  EXPECT_EQ(newton.output.find("thickness_points"), std::string::npos) << newton.output;
  EXPECT_EQ(plain.output.find("shell.hourglass_membrane"), std::string::npos) << plain.output;  // physical: no advice
  const Outcome springs = run_case("plastic_warnings_springs", yaml, "--set mpm.solver=explicit --set shell.hourglass=0.1", true);
  ASSERT_EQ(springs.exit_code, 0) << springs.output;
  EXPECT_NE(springs.output.find("shell.hourglass_membrane"), std::string::npos) << springs.output;
  const Outcome advised = run_case("plastic_warnings_advised", yaml,
                                   "--set mpm.solver=explicit --set shell.thickness_points=7 --set mpm.level_ramp_steps=2000", true);
  ASSERT_EQ(advised.exit_code, 0) << advised.output;
  EXPECT_EQ(advised.output.find("warning"), std::string::npos) << advised.output;
}

// Newton (the quasi-static default) and damped explicit dynamics reach the same linear answer.
TEST(mpm_Cases, NewtonAndExplicitQuasiStaticAgree) {
  const double exact = 0.004 * 1000.0 / 300.0 + 0.004 * 10.0 / (5.0 / 6.0 * 6.0e5 * 0.1);
  const Outcome newton = run_case("newton_linear", kStrip);
  ASSERT_EQ(newton.exit_code, 0) << newton.output;
  const Outcome dynamics = run_case("explicit_linear", kStrip, "--set mpm.solver=explicit");
  ASSERT_EQ(dynamics.exit_code, 0) << dynamics.output;
  EXPECT_NEAR(summary_value("newton_linear", "w_tip"), exact, 0.01 * exact);
  EXPECT_NEAR(summary_value("newton_linear", "w_tip"), summary_value("explicit_linear", "w_tip"), 0.005 * exact);
  EXPECT_GT(summary_value("newton_linear", "newton_iterations"), 0.0);
  EXPECT_EQ(summary_value("explicit_linear", "newton_iterations"), 0.0);
  EXPECT_LT(summary_value("newton_linear", "residual_ratio"), 1e-5);
}

// The elastica: an end moment M = pi EI / L bends the strip into a half circle (kappa = M / EI), tip at
// u = L (sin(pi) / pi - 1) = -L, w = L (1 - cos(pi)) / pi = 2 L / pi; the rotations are large (pi at the tip).
TEST(mpm_Cases, NewtonRollsTheStripIntoAHalfCircle) {
  const std::string yaml = kStrip.substr(0, kStrip.find("loads:")) + R"(loads: []
mpm:
  load_levels: 4
  tolerance: 1.0e-6
  moments:
    - {select: {set: xmax}, edge_moment: [0, -31.4159265358979, 0]}   # per unit width: pi EI / L, EI = 100
probes:
  - {name: u_tip, field: displacement, component: x, at: [10, 0, 0]}
  - {name: w_tip, field: displacement, component: z, at: [10, 0, 0]}
)";
  const Outcome o = run_case("half_circle", yaml);
  ASSERT_EQ(o.exit_code, 0) << o.output;
  const double pi = std::acos(-1.0);
  EXPECT_NEAR(summary_value("half_circle", "u_tip"), -10.0, 0.01 * 10.0);
  EXPECT_NEAR(summary_value("half_circle", "w_tip"), 20.0 / pi, 0.01 * 20.0 / pi);
  EXPECT_NEAR(summary_value("half_circle", "energy_ratio"), 1.0, 0.01);
  EXPECT_EQ(summary_value("half_circle", "newton_stopped_levels"), 0.0);
}

TEST(mpm_Cases, NewtonInputIsChecked) {
  expect_refused("newton_dynamic", kStrip, "--set mpm.analysis=dynamic --set mpm.solver=newton", "mpm.solver");
  expect_refused("newton_word", kStrip, "--set mpm.solver=implicit", "newton");
  const Outcome scaled = run_case("newton_scaled", kStrip, "--set mpm.solver=newton --set mpm.mass_scaling=stiffness", true);
  EXPECT_EQ(scaled.exit_code, 2) << scaled.output;
  // an explicit-dynamics setting left in a Newton run is pointed out
  const Outcome unused = run_case("newton_unused", kStrip, "--set mpm.time_step.fixed=0.001", true);
  ASSERT_EQ(unused.exit_code, 0) << unused.output;
  EXPECT_NE(unused.output.find("warning: mpm.time_step.fixed set with the Newton"), std::string::npos) << unused.output;
}

// Beyond the collapse load there is no static state: Newton stops, the level goes on by explicit
// dynamics (here cut short by max_steps_per_level) and both facts are reported.
TEST(mpm_Cases, NewtonFallsBackToExplicitDynamicsBeyondCollapse) {
  const std::string yaml = R"(
title: strip pulled past its yield load
method: mpm
materials:
  - {name: s, model: j2_plasticity, E: 1.2e6, nu: 0.0, density: 1.0, yield: 600, hardening: 0}
geometry: {type: plate, min: [0, 0], max: [10, 1], thickness: 0.1}
discretization: {elements: [10, 1]}
boundary:
  - {select: {set: xmin}, fix: [x, y, z, rx, ry, rz]}
loads:
  - {select: {set: xmax}, traction: [90, 0, 0]}   # 1.5 x the yield load 600 x 0.1 x 1
shell: {thickness_points: 5}
mpm: {load_levels: 1, max_steps_per_level: 200}
probes:
  - {name: u_tip, field: displacement, component: x, at: [10, 0, 0]}
)";
  const Outcome o = run_case("collapse", yaml);
  ASSERT_EQ(o.exit_code, 0) << o.output;
  EXPECT_EQ(summary_value("collapse", "newton_stopped_levels"), 1.0);
  EXPECT_GT(summary_value("collapse", "newton_first_stop_load"), 0.6);  // yield at 2 / 3 of the load
  EXPECT_LT(summary_value("collapse", "newton_first_stop_load"), 0.7);
  EXPECT_EQ(summary_value("collapse", "unconverged_levels"), 1.0);
  EXPECT_GT(summary_value("collapse", "u_tip"), 10.0 * 600.0 / 1.2e6);  // past the yield elongation
  // the stop is said in the run's log, with where and why
  const std::string log_text = output_file("collapse", "log.txt");
  EXPECT_NE(log_text.find("NOTE: Newton stopped at load factor 0.6"), std::string::npos) << log_text;
}

// Past a limit point a load-controlled static path jumps: Sze's hinged roof (t = 12.7, first limit at
// P / P_max ~ 0.742, W_C ~ -10.4 to -11.3; after the snap W_C ~ -27). On this coarse quarter Newton
// converges on the far branch; the sub-increment that jumped stores far less energy than the work done
// on it, which is reported (newton_jumps, newton_first_jump_load just below the limit).
// A stiffening path is no jump: a thin clamped plate under pressure takes the load as a membrane
// (w ~ p^(1/3)), so one increment from the flat plate leaves a large trapezoidal-rule energy gap, but its
// displacement per unit load falls; Newton takes it whole, and the elastic answer does not depend on the
// number of levels.
TEST(mpm_Cases, NewtonTakesAStiffeningMembranePathWithoutJumps) {
  const std::string yaml = R"(
title: thin clamped plate under pressure
method: mpm
materials: [{name: p, model: linear_elastic, E: 1.0e6, nu: 0.3, density: 1.0}]
geometry: {type: plate, min: [0, 0], max: [1, 1], thickness: 0.002}
discretization: {elements: [8, 8]}
boundary:
  - {select: {set: xmin}, fix: [x, y, z, rx, ry, rz]}
  - {select: {set: xmax}, fix: [x, y, z, rx, ry, rz]}
  - {select: {set: ymin}, fix: [x, y, z, rx, ry, rz]}
  - {select: {set: ymax}, fix: [x, y, z, rx, ry, rz]}
loads: [{select: all, pressure: 1.0}]
mpm: {load_levels: 1}
probes: [{name: w_c, field: displacement, component: z, at: [0.5, 0.5, 0]}]
output: {vtu: false}
)";
  const Outcome one = run_case("membrane_one", yaml);
  ASSERT_EQ(one.exit_code, 0) << one.output;
  EXPECT_EQ(summary_value("membrane_one", "newton_jumps"), 0.0);
  EXPECT_EQ(summary_value("membrane_one", "newton_stopped_levels"), 0.0);
  EXPECT_GT(summary_value("membrane_one", "newton_largest_energy_gap"), 0.25);  // the trapezoidal gap is there
  const double w_one = summary_value("membrane_one", "w_c");
  EXPECT_LT(w_one, -5 * 0.002);  // a membrane: deflection several thicknesses
  const Outcome ten = run_case("membrane_ten", yaml, "--set mpm.load_levels=10");
  ASSERT_EQ(ten.exit_code, 0) << ten.output;
  EXPECT_EQ(summary_value("membrane_ten", "newton_jumps"), 0.0);
  EXPECT_NEAR(summary_value("membrane_ten", "w_c"), w_one, 0.005 * std::abs(w_one));
}

TEST(mpm_Cases, NewtonRefusesAJumpAcrossALimitPoint) {
  const std::string yaml = R"(
title: hinged roof
method: mpm
materials:
  - {name: shell, model: linear_elastic, E: 3102.75, nu: 0.3, density: 1.0}
geometry: {type: cylinder, radius: 2540, length: 254, axis: y, angle: 5.729577951308232, thickness: 12.7}
discretization: {elements: [8, 8]}
boundary:
  - {select: {set: end1}, fix: [y, rx, rz]}
  - {select: {set: edge0}, fix: [x, ry, rz]}
  - {select: {set: edge1}, fix: [x, y, z]}
loads:
  - {select: {nearest: [0, 254, 2540]}, force: [0, 0, -750]}
mpm: {load_levels: 10}
probes:
  - {name: w_C, field: displacement, component: z, at: [0, 254, 2540]}
)";
  // 10 levels: increments large enough that a sub-increment converges on the far branch (with 40 the
  // present element's Newton closes in on the limit point without one, so the refusal would go untested)
  const Outcome o = run_case("roof_jump", yaml);
  ASSERT_EQ(o.exit_code, 0) << o.output;
  // the sub-increment that converged on the far branch is refused: Newton closes in on the limit point
  // (Sze et al.: 0.742 P_max on the 16 x 16 quarter), stops there, and explicit dynamics does the snap
  EXPECT_GE(summary_value("roof_jump", "newton_jumps"), 1.0);
  EXPECT_GT(summary_value("roof_jump", "newton_first_jump_load"), 0.70);
  EXPECT_LT(summary_value("roof_jump", "newton_first_jump_load"), 0.742);
  EXPECT_EQ(summary_value("roof_jump", "newton_stopped_levels"), 1.0);
  EXPECT_NEAR(summary_value("roof_jump", "newton_first_stop_load"), 0.742, 0.03);
  EXPECT_LT(summary_value("roof_jump", "newton_largest_energy_gap"), 0.05);  // no jump committed
  EXPECT_LT(summary_value("roof_jump", "w_C"), -25.0);  // on the far branch at P_max
  // no jump on a smooth path: the linear cantilever
  const Outcome smooth = run_case("no_jump", kStrip);
  ASSERT_EQ(smooth.exit_code, 0) << smooth.output;
  EXPECT_EQ(summary_value("no_jump", "newton_jumps"), 0.0);
  EXPECT_LT(summary_value("no_jump", "newton_largest_energy_gap"), 0.01);
}

}  // namespace
