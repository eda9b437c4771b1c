#pragma once
// CellLattice: the point generator of a box or plate as a regular lattice of cells (the peridynamic lattice)
// with per-direction spacing (seed 002 section 4.1 "plate lattice": 10 x 10 x 1 mm cells, two layers).
//
// Nodes sit at the cell centres; each carries its cell volume dx dy dz. The number of cells per
// direction is round(extent / spacing) (at least 1), and the cells are stretched to fill the body
// exactly, so the actual spacing can differ slightly from the requested one (reported back).
// Named sets: xmin xmax ymin ymax zmin zmax = the first / last cell layer along each axis
// (for a plate also top = zmax, bottom = zmin).
#include <array>

#include "core/point_cloud.hpp"
#include "core/types.hpp"

namespace lamina::geometry {

struct CellLattice {
  Vec3 lower = Vec3::Zero();  // body bounding box
  Vec3 upper = Vec3::Ones();
  std::array<Index, 3> cells{1, 1, 1};
  Vec3 spacing = Vec3::Ones();  // actual cell size per direction
};

/// The lattice filling [lower, upper] with cells close to the requested spacing.
CellLattice make_cell_lattice(const Vec3& lower, const Vec3& upper, const Vec3& requested_spacing);

/// Nodes at the cell centres (x fastest, then y, then z), volumes, spacing and named sets.
/// gauss_layers (plates, surface_correction: plate): the nz node layers sit at the nz-point
/// Gauss-Legendre points of [lower.z, upper.z] and carry the Gauss weights as volumes
/// (dx dy w_k (zmax - zmin) / 2), so layer sums integrate through-thickness polynomials up to degree
/// 2 nz - 1 exactly (bending stiffness sum V_k z_k^2 = t^3 / 12 per unit area from 2 layers on).
PointCloud lattice_point_cloud(const CellLattice& lattice, bool plate_sets, bool gauss_layers = false);

}  // namespace lamina::geometry
