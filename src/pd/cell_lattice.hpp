#pragma once
// CellLattice: the peridynamic discretisation of a box or plate by a regular lattice of cells
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

namespace lamina::pd {

struct CellLattice {
  Vec3 lower = Vec3::Zero();  // body bounding box
  Vec3 upper = Vec3::Ones();
  std::array<Index, 3> cells{1, 1, 1};
  Vec3 spacing = Vec3::Ones();  // actual cell size per direction
};

/// The lattice filling [lower, upper] with cells close to the requested spacing.
CellLattice make_cell_lattice(const Vec3& lower, const Vec3& upper, const Vec3& requested_spacing);

/// Nodes at the cell centres (x fastest, then y, then z), volumes, spacing and named sets.
PointCloud lattice_point_cloud(const CellLattice& lattice, bool plate_sets);

}  // namespace lamina::pd
