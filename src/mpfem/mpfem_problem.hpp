#pragma once
// The MPFEM family's description of a 2D linear elastostatic problem (seed 001 eqs 1a-c, 2):
// particles in the x-y plane, thickness, materials, essential dofs, loads and options (no io types).
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "core/linear_solver_choice.hpp"
#include "core/prescribed_dof.hpp"
#include "core/types.hpp"
#include "geometry/expression.hpp"
#include "material/linear_elastic.hpp"
#include "material/material_spec.hpp"
#include "model/load.hpp"
#include "mpfem/particle_elements.hpp"

namespace lamina::mpfem {

enum class PlaneKind { stress, strain };

/// stress | five_node: the MPFEM particle elements; t3: reference linear triangles on the
/// same (grid) particles, one diagonal per grid cell, one-point Gauss (for comparisons).
enum class ElementKind { five_node, t3 };

/// Boundary traction quadrature: particle = seed eq (6), f_I = t(x_I) dS_I;
/// gauss = 2-point Gauss on every boundary segment with the segment's linear trace of phi.
enum class TractionQuadrature { gauss, particle };

/// The particle strain operator of the quadrature (seed eq 4):
///   cell: mean over the particle's tributary cell (tributary_cells.hpp) plus the strain-gradient
///     (second-moment) term; grid particle sets only. Default.
///   star: mean gradient of the particle's own five-node element, dV_I = A_I / 2.
///   voronoi: mean over the particle's Voronoi cell clipped to the body (the convex hull of the
///     particles, or MpfemProblem::body_boundary; voronoi_cells.hpp) plus the same strain-gradient
///     term; any particle set of a convex body, or a mesh's nodes.
enum class ParticleStrain { cell, star, voronoi };

/// linear_static: seed eqs (4)-(6); large_deformation: total-Lagrangian Newton on load increments
/// with the elements' neighbourhoods rebuilt from the current positions (docs/mpfem.md section 9).
enum class MpfemAnalysisKind { linear_static, large_deformation };

struct LargeDeformationOptions {
  int increments = 10;        // equal load increments (dead loads and prescribed displacements scaled)
  Real tolerance = 1e-8;      // Newton: |residual| <= tolerance x max(|external + reaction forces|)
  int max_iterations = 25;    // Newton iterations per increment before the increment is cut
  int bisections = 6;         // halvings of an increment before the run stops (exit 3)
  bool rebuild = true;        // rebuild the neighbourhoods from the current positions when they change
};

struct MpfemOptions {
  MpfemAnalysisKind analysis = MpfemAnalysisKind::linear_static;
  LinearSolverChoice solver;  // the case's `solver:`: CHOLMOD, or PETSc (several ranks: the whole system on
                              // every rank, each passing the rows of its block)
  LargeDeformationOptions large_deformation;
  PlaneKind plane = PlaneKind::stress;
  ElementKind element = ElementKind::five_node;
  ElementOptions elements;
  ParticleStrain particle_strain = ParticleStrain::cell;
  Real stabilization = 0.1;     // beta of the element-deviation stabilisation (docs/mpfem.md)
  TractionQuadrature traction_quadrature = TractionQuadrature::gauss;
  std::optional<std::array<std::string, 2>> exact_displacement;  // ux, uy of x y: error probes
  /// voronoi: the body's area when known (the particles' convex hull must cover it: corners and edges)
  std::optional<Real> body_area;
};

/// Plane elasticity matrix (3 x 3, engineering shear) and the out-of-plane response.
struct PlaneMaterial {
  material::LinearElastic elastic;
  PlaneKind plane = PlaneKind::stress;
  Eigen::Matrix3d matrix() const;
  /// eps_zz (plane stress) or sigma_zz (plane strain) from the in-plane strain.
  Real out_of_plane(const Eigen::Vector3d& strain) const;
};

struct MpfemProblem {
  ParticleLayout layout;
  /// voronoi: the body's boundary polygon (particle indices, counter-clockwise; mesh_boundary.hpp);
  /// empty = the particles' convex hull (a convex body)
  std::vector<Index> body_boundary;
  Real thickness = 1.0;
  Real z_mid = 0.5;                             // z of the particles in outputs
  std::vector<material::LinearElastic> materials;
  /// per material: neo_hookean (large_deformation only) or linear_elastic (Saint Venant-Kirchhoff
  /// in large_deformation); empty = all linear_elastic
  std::vector<material::MaterialModel> material_models;
  std::vector<int> material_of_particle;        // index into materials, per particle
  std::vector<PrescribedDof> prescribed;        // essential conditions on particle dofs
  std::vector<model::Load> loads;              // force, traction, pressure, body_force (x-y components)
  MpfemOptions options;
};

}  // namespace lamina::mpfem
