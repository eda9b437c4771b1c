#pragma once
// Voronoi cells of an arbitrary particle set clipped to the body (the particles' convex hull, or a
// given boundary polygon of particles), and the strain smoothed over them: stabilised conforming
// nodal integration (Chen et al. 2001) for MPFEM.
//
// Cell Omega_I: the points of the body closer to x_I than to any other particle (the body polygon
// clipped by the bisector half-planes of nearby particles). A half-plane clip of any simple polygon
// keeps exactly its part in the half-plane (a part cut in two is joined by a zero-width bridge along
// the cut whose two sides cancel in every edge integral), so a non-convex body is clipped exactly;
// on a convex hull the cells are convex. The cells tile the body exactly. Smoothed gradient of particle J's shape function over Omega_I
// (divergence theorem):
//   b_IJ = (1 / |Omega_I|) sum_{edges e of Omega_I} integral_e psi_J n ds,
// with on each edge a single-valued trace psi that reproduces linear fields:
//   - an interior edge shared by the cells of I and K: psi = (N^I + N^K) / 2, the mean of the two
//     particles' five-node element interpolants (particle_elements.hpp) extended linearly from the
//     star triangle nearest to the point; 2-point Gauss rule (exact for linear fields);
//   - an edge on the hull: the 1D linear interpolant between consecutive boundary particles (the
//     same trace the traction loads use), integrated exactly piece by piece.
// Both cells sharing an edge integrate the same function at the same points, so
// sum_I |Omega_I| b_IJ telescopes to the boundary integral of psi_J n (integration constraint),
// and b_IJ is exact for linear fields: the linear patch test passes on any particle set. Interior
// particles have psi = 0 on the hull, so a displacement patch test is exact too.
// Boundary particles: the particles on the hull's edges (within 1e-9 spacings); the hull's
// corners are particles. Also returned: cell centroids and second moments (tributary_cells.hpp).
#include <vector>

#include "mpfem/particle_elements.hpp"
#include "mpfem/tributary_cells.hpp"

namespace lamina::mpfem {

struct VoronoiCells {
  TributaryCells cells;
  std::vector<BoundarySegment> boundary;  // body (hull) segments between consecutive boundary particles (body on the left)
  Eigen::VectorXd boundary_weight;        // half the lengths of the segments at each particle (0 inside)
  Real hull_area = 0;  // the sum of the cell areas (the hull's, or the body polygon's)
};

/// Needs the five-node elements of every particle (d.elements). `body`: the body's boundary polygon,
/// particle indices counter-clockwise (mesh_boundary.hpp); empty = the particles' convex hull.
/// InputError (key "discretization.particles") naming the particle if its cell reaches farther than
/// `max_reach` from it (a cloud too sparse there, or a non-convex body whose hull is not the body),
/// or if the particles lie on one line.
VoronoiCells build_voronoi_cells(const ParticleLayout& layout, const ParticleDiscretization& d, Real max_reach,
                                 const std::vector<Index>& body = {});

/// Convex hull of 2D points, counter-clockwise, without collinear points (Andrew's monotone chain).
std::vector<Index> convex_hull(const Points2& x);

}  // namespace lamina::mpfem
