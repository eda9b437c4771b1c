#pragma once
// The boundary of a 2D triangle mesh as one closed polygon of its nodes: the edges used by one
// triangle only, chained counter-clockwise (the body on the left); the Voronoi cells' body.
#include <array>
#include <vector>

#include "mpfem/particle_elements.hpp"

namespace lamina::mpfem {

/// Node indices of the boundary loop, counter-clockwise, each node once (collinear nodes kept).
/// InputError (key "discretization.particles") if the triangles have no area, an edge is shared
/// by more than two triangles, or the boundary is not one closed loop (holes, separate parts,
/// a node where the boundary touches itself).
std::vector<Index> mesh_boundary_loop(const Points2& x, const std::vector<std::array<Index, 3>>& triangles);

/// Signed area of the polygon through the points `loop` (positive when counter-clockwise).
Real polygon_area(const Points2& x, const std::vector<Index>& loop);

}  // namespace lamina::mpfem
