#pragma once
// PeridynamicProblem: everything a `method: pd` analysis needs, translated from the case by the
// application (this module knows no files and no YAML): nodes, materials, body options,
// prescribed degrees of freedom, nodal loads, the analysis kind and its solver parameters.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/linear_solver_choice.hpp"
#include "core/prescribed_dof.hpp"
#include "core/ramp.hpp"
#include "pd/peridynamic_body.hpp"

namespace lamina::pd {

/// A nodal force (N) at ramp factor 1.
struct NodalForce {
  Index node = 0;
  Vec3 force = Vec3::Zero();
  int ramp = -1;
};

/// Rotations held at nodes (`fix: [rx, ry, rz]`). Peridynamic nodes have no rotations: only the
/// one-layer plate model holds them, on the slopes of its fitted surface (docs/pd.md, "One node layer").
struct HeldRotations {
  std::vector<Index> nodes;          // nodes with at least one rotation held
  std::vector<std::uint8_t> axes;    // per entry: bit a set = rotation about global axis a (x, y, z) held
  std::optional<Diagnostic> where;   // the first `fix` that holds one (for the refusal on other bodies)
  bool empty() const { return nodes.empty(); }
};

enum class PdAnalysisKind { linear_static, quasi_static, explicit_dynamics, buckling };

/// Adaptive dynamic relaxation parameters (seed 002 section 3).
struct AdaptiveDynamicRelaxationOptions {
  int increments = 10;
  Real tolerance = 1e-5;            // relative: max|R^k| / max|R^0|
  Real absolute_tolerance = -1.0;   // max|R| (N); < 0: tolerance x max nodal internal/external force
  int switch_iteration = 2000;      // k_switch: relative test only before it, relative OR absolute after
  int max_iterations = 20000;
  int max_cuts = 6;                 // halvings of one increment before giving up
  int continuations = 4;            // further max_iterations blocks from the reached state before a halving
  Real density_factor = 1.0;        // lambda_ii = density_factor / 4 dt^2 sum_j |K0_ij|
  Real velocity_guard = 1e-10;      // 1K_ii = 0 where |Udot_i| < guard |U_i|
  enum class Predictor { previous, secant, quadratic };
  Predictor predictor = Predictor::secant;  // start of an increment: the previous field, or its extrapolation
                                            // through the last two (secant) or three (quadratic) states
  enum class DampingEstimate { total, increment };
  // the displacement in the Rayleigh quotient of seed eq (6): U (the seed) or U - U_start (the part
  // still being relaxed in this increment; the quotient then follows the slow buckling mode)
  DampingEstimate damping_estimate = DampingEstimate::increment;
  enum class Coordinates { nodes, columns };
  // the relaxed coordinates on a plate lattice: the column modes (mid-surface, director, layer
  // residuals; relaxation_coordinates.hpp) or the node displacements of the seed
  Coordinates coordinates = Coordinates::columns;
  bool linear_start = false;        // first increment starts from the linear solution (else interpolated)
  bool kinetic_fallback = true;     // kinetic-energy damping while the adaptive damping c is zero
};

struct ExplicitOptions {
  Real end_time = 1e-3;
  Real safety_factor = 0.8;
  Real time_step = 0.0;             // > 0: fixed (checked against the critical step)
  int outputs = 20;
  Real damping = 0.0;               // mass-proportional damping (1/s)
};

struct BucklingOptions {
  int modes = 3;
};

/// Geometric imperfection of the reference configuration (stress free).
struct Imperfection {
  enum class Kind { none, shape, buckling_mode };
  Kind kind = Kind::none;
  PointMatrix shape;               // Kind::shape: displacement field (scaled to amplitude)
  int mode = 1;                    // Kind::buckling_mode
  Real amplitude = 0.0;            // largest displacement magnitude of the scaled field
};

struct PeridynamicProblem {
  PointMatrix positions;
  Eigen::VectorXd volumes, young, poisson, density;
  BodyOptions body;
  std::vector<PrescribedDof> prescribed;
  HeldRotations held_rotations;
  std::vector<NodalForce> forces;
  PointMatrix initial_velocity;     // empty or 3 x N
  std::vector<Ramp> ramps;  // non-linear ramps referred to by index (progress: the load factor or t / end)
  PdAnalysisKind analysis = PdAnalysisKind::quasi_static;
  AdaptiveDynamicRelaxationOptions relaxation;
  ExplicitOptions explicit_options;
  BucklingOptions buckling;
  Imperfection imperfection;
  bool check_zero_energy = true;    // quasi_static and buckling: refuse a stiffness with a zero-energy mode
  LinearSolverChoice solver;        // `solver:` for linear_static (PETSc on several ranks or when asked)
};

}  // namespace lamina::pd
