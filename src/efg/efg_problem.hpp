#pragma once
// The EFG method family's own description of a linear elastostatic problem (no io types: the
// application translates the case file into this). Selections stay geometric (where / box /
// set / nearest / all) so that they can be tested at quadrature points, and carry the node
// indices they selected on the node cloud.
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "core/linear_solver_choice.hpp"
#include "core/point_cloud.hpp"
#include "core/probe.hpp"
#include "geometry/expression.hpp"
#include "geometry/geometry_spec.hpp"
#include "geometry/selection.hpp"
#include "model/constraint.hpp"
#include "model/load.hpp"
#include "model/selection.hpp"
#include "material/linear_elastic.hpp"
#include "mls/mls_options.hpp"

namespace lamina::efg {

struct EfgMaterial {
  std::string name;
  material::LinearElastic elastic;
  std::optional<model::Selection> region;   // none = everywhere
};

/// How essential boundary conditions are imposed (see essential_boundary.hpp). automatic: Nitsche for the
/// Galerkin formulation unless a material is nearly incompressible (nu > 0.45) or the volumetric term is
/// projected, else penalty; resolved by the EfgAnalysis constructor (docs/efg.md section 6).
enum class EssentialMethod { automatic, penalty, penalty_nodes, nitsche, lagrange };

/// Discretisation of the weighted residual equation (seed 004 eq 1-31, section 1.2.2): Galerkin
/// (weak form, background quadrature), point collocation (collocation_system.hpp) or weighted
/// least squares (weighted_least_squares_system.hpp).
enum class Formulation { galerkin, collocation, weighted_least_squares };

/// Weights of the WLSM functional (seed 004 eq 1-35); defaults are the seed's.
struct WeightedLeastSquaresOptions {
  Real traction_weight = 1e5;                 // beta
  std::optional<Real> displacement_weight;    // alpha; none: beta [E / (1 - nu^2)]^2 of the stiffest material
  bool cell_centre_points = false;            // auxiliary equilibrium points at the background cell centres
};

/// Correction of the quadrature for consistency (see galerkin_assembly.hpp): none, VCI (linear,
/// Petrov-Galerkin), or gradients smoothed over the background cells (linear in each cell, symmetric).
/// automatic: smoothed where the nodes are not the background cells' grid (jittered, irregular), else
/// none; resolved by EfgAnalysis::setup (docs/efg.md section 6).
enum class IntegrationCorrection { automatic, none, vci, smoothed };

struct EfgOptions {
  Formulation formulation = Formulation::galerkin;
  LinearSolverChoice solver;                    // the case's `solver:` (galerkin: CHOLMOD or PETSc)
  WeightedLeastSquaresOptions least_squares;
  mls::MlsOptions mls;
  std::optional<std::array<int, 3>> cells;      // background cells per parametric axis (none: from the nodes)
  std::array<int, 3> gauss{2, 2, 2};            // Gauss points per cell and direction
  IntegrationCorrection correction = IntegrationCorrection::automatic;
  bool reduced_volumetric = false;              // selective reduced integration of the lambda term
  std::array<int, 3> volumetric_gauss{1, 1, 1}; // its Gauss order (default: gauss - 1, at least 1)
  bool projected_volumetric = false;            // lambda term with the divergence projected on nodal pressures
  Real pressure_kappa = 1.1;                    // box support of the Shepard pressure functions (x pressure node spacing)
  /// Pressure nodes per direction, generated on the same body (none: every other displacement node,
  /// n / 2 + 1 per direction, as the vertices of Taylor-Hood Q2/Q1 elements; the displacement nodes
  /// themselves if they are not a structured grid).
  std::optional<std::array<int, 3>> pressure_nodes;
  EssentialMethod essential = EssentialMethod::automatic;
  std::optional<Real> penalty;                  // absolute penalty value (none: penalty_factor x stiffness scale)
  Real penalty_factor = 1e5;
  Real nitsche_factor = 100.0;                  // beta = factor * (lambda + 2 mu) / h
  /// Optional exact displacement (expressions of x y z) for verification: builtin error probes.
  std::optional<std::array<std::string, 3>> exact_displacement;
};

struct EfgProblem {
  geometry::GeometrySpec geometry;
  PointCloud cloud;
  std::vector<EfgMaterial> materials;
  std::vector<model::Constraint> constraints;  // fix / displacement (velocity is refused by the reader of the case)
  std::vector<model::Load> loads;              // force, traction, pressure, body_force
  EfgOptions options;
};

std::string to_string(EssentialMethod method);
std::string to_string(Formulation formulation);

}  // namespace lamina::efg
