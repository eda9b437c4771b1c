#pragma once
// Particle-centred five-node elements of the moving particle finite element method (seed 001:
// Hao, Park & Liu 2002): particle I and its four neighbours, the quadrature weights dV_I (eq 4-5) and dS_I (eq 6).
//
// Construction (docs/mpfem.md has the reasoning)
//   Neighbour rule. Each particle I takes four neighbours, one per direction sector, in the
//   counter-clockwise order E, N, W, S:
//     logical_grid: particles generated on a mapped n0 x n1 grid (index i + n0 j) take their grid
//       neighbours (i+1, j), (i, j+1), (i-1, j), (i, j-1) (j periodic for closed rings);
//     sectors: any particle set: the nearest particle in each of the four 90-degree sectors
//       centred on +x, +y, -x, -y, closer than max_neighbour_distance x the median
//       nearest-particle distance.
//   Boundary particles simply lack the neighbours beyond the boundary (an edge particle has 3, a
//   corner particle 2). The five-node element E_I is the star of the triangles (I, J_k, J_k+1)
//   between consecutive present neighbours whose angle at I is below 180 degrees (4 triangles
//   inside, 2 on an edge, 1 at a corner). Its shape functions N^I_J are the piecewise-linear
//   interpolants on that star: N^I_J(x_K) = delta_JK at its nodes, sum_J N^I_J = 1 and
//   sum_J N^I_J x_J = x on the star.
//   Elements overlap: on grid particle sets every point of the body lies in exactly two elements
//   (the triangles of all stars are the two diagonal triangulations of the grid cells).
//   The global shape functions are the equal-weight blend of the elements covering x,
//     phi_J(x) = (1 / m(x)) sum_{I: x in E_I} N^I_J(x),
//   which keeps the Kronecker delta property, the partition of unity and linear reproduction.
//   Particle strain: the element's mean gradient B_I = (1/A_I) sum_T A_T grad N_T (the smoothed
//   gradient of the element, exact for linear fields).
//   Quadrature weights: dV_I = thickness A_I / covering (covering = 2), which sums to the body
//   volume on grid particle sets; dS_I = thickness x half the lengths of the boundary segments at I.
//   Boundary segments: triangle edges with every triangle containing them on one side.
//   Everything is rebuilt from the positions passed in (the "moving" part of the method).
#include <Eigen/Dense>
#include <array>
#include <optional>
#include <vector>

#include "core/types.hpp"

namespace lamina::mpfem {

using Vec2 = Eigen::Vector2d;
using Points2 = Eigen::Matrix2Xd;
constexpr int kElementNodes = 5;
using ElementGradient = Eigen::Matrix<Real, 2, kElementNodes>;  // column a: grad of node a's shape function

/// Structured particle sets: particle i + n0 * j (i = first generator direction).
struct LogicalGrid {
  int n0 = 0, n1 = 0;
  bool periodic1 = false;  // j wraps around (closed ring, e.g. an annulus without slit)
};

struct ParticleLayout {
  Points2 positions;                // 2 x N, x-y coordinates
  std::optional<LogicalGrid> grid;  // present for generated particle sets
};

enum class NeighbourRule { logical_grid, sectors };

struct ElementTriangle {
  std::array<int, 3> local{};       // local node numbers (0 = the centre particle)
  Real area = 0;
  ElementGradient gradient = ElementGradient::Zero();  // zero columns for nodes outside the triangle
};

struct ParticleElement {
  std::array<Index, kElementNodes> nodes{-1, -1, -1, -1, -1};  // [0] the particle, [1..4] E N W S (-1 absent)
  int triangle_count = 0;
  std::array<ElementTriangle, 4> triangles;
  Real area = 0;                                       // A_I: area of the star
  ElementGradient mean_gradient = ElementGradient::Zero();  // B_I = (1/A_I) sum_T A_T grad N_T
};

/// A boundary segment a -> b with the body on its left; outward unit normal.
struct BoundarySegment {
  Index a = 0, b = 0;
  Vec2 normal = Vec2::Zero();
  Real length = 0;
};

struct ElementOptions {
  NeighbourRule rule = NeighbourRule::logical_grid;
  Real max_neighbour_distance = 3.0;   // sectors rule: x median nearest-particle distance
  Real coincidence_tolerance = 1e-8;   // x typical spacing: closer particles are "coincident"
};

struct ParticleDiscretization {
  std::vector<ParticleElement> elements;   // one per particle
  Eigen::VectorXd area_weight;             // dV_I / thickness = A_I / covering
  Eigen::VectorXd boundary_weight;         // dS_I / thickness (0 inside)
  std::vector<BoundarySegment> boundary;
  Real covering = 2.0;
  Real typical_spacing = 0;                // sqrt(area / N)
  NeighbourRule rule = NeighbourRule::logical_grid;
};

/// Builds the five-node elements from the current positions. Throws lamina::InputError
/// (key "discretization.particles") for coincident particles or particles whose element has
/// no area (too few neighbours) and for inverted (tangled) elements.
/// `neighbours` (optional): use these E N W S neighbours instead of the rule's choice on
/// layout.positions (the large-deformation analysis: chosen on the current positions, element
/// geometry on the reference positions; reflex or flat star triangles are skipped as with sectors).
ParticleDiscretization build_particle_elements(const ParticleLayout& layout, const ElementOptions& options,
                                               const std::vector<std::array<Index, 4>>* neighbours = nullptr);

/// The neighbours E N W S (-1 absent) the rule chooses on layout.positions.
std::vector<std::array<Index, 4>> choose_neighbours(const ParticleLayout& layout, const ElementOptions& options);

/// One shape function value at a point: particle, phi, grad phi.
struct ShapeValue {
  Index particle = 0;
  Real value = 0;
  Vec2 gradient = Vec2::Zero();
};

/// Blended global shape functions at x (empty if x lies in no element). Brute force over the
/// triangles: for tests and probes, not for hot loops.
std::vector<ShapeValue> shape_functions_at(const ParticleDiscretization& d, const Points2& positions, const Vec2& x);

/// Gradient matrix of the linear interpolant on a triangle (columns: the three vertices).
Eigen::Matrix<Real, 2, 3> triangle_gradient(const Vec2& p0, const Vec2& p1, const Vec2& p2, Real& signed_area);

}  // namespace lamina::mpfem
