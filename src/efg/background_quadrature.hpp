#pragma once
// Background integration cells of the Galerkin EFG method and their Gauss quadrature.
//
// Cells live in the parametric box of the generator's map X(u) (geometry::VolumeMap): each
// parametric axis [lo, hi] is cut into c equal intervals, so the cells are the images of
// parametric boxes and tile the body exactly (curved_beam, cylinder, ... included). On a cell the
// tensor Gauss-Legendre rule of order (g0, g1, g2) is mapped: point X(u(xi)), weight
// w0 w1 w2 * (half widths) * |det dX/du|. dX/du comes from 4th-order central differences of
// X (step 1e-3 of the cell width per axis; truncation ~1e-13 relative, so the weights sum to the
// body volume to ~1e-11 relative).
//
// Default cells ("derived from the node layout"): one cell per node interval of the structured
// node grid: c = n - 1 on an open axis with n >= 2 nodes, 1 for a single node, n on a periodic axis.
//
// Boundary faces: the cell faces on lo/hi of every non-periodic axis; faces whose area vanishes
// (a collapsed axis: cylinder axis, pole of a cap) are skipped. Surface quadrature: tensor Gauss of
// the two tangential orders on each face, area element |X_a x X_b|, outward unit normal.
#include <array>
#include <functional>
#include <vector>

#include "core/gauss_legendre.hpp"  // gauss_legendre (used by the cell rules)
#include "core/types.hpp"
#include "geometry/mapped_grid.hpp"

namespace lamina::efg {

struct BackgroundCells {
  geometry::VolumeMap map;
  std::array<int, 3> counts{1, 1, 1};
  std::array<std::vector<Real>, 3> breaks;  // counts[d] + 1 parametric breakpoints per axis

  Index size() const { return static_cast<Index>(counts[0]) * counts[1] * counts[2]; }
  /// Cell index of (i, j, k): i + c0 (j + c1 k).
  Index index(int i, int j, int k) const { return i + static_cast<Index>(counts[0]) * (j + static_cast<Index>(counts[1]) * k); }
  /// Parametric corners of a cell.
  void bounds(Index cell, Vec3& lo, Vec3& hi) const;
};

/// Cells per axis from the structured node counts (see the header comment).
std::array<int, 3> default_cell_counts(const geometry::VolumeMap& map, const std::array<Index, 3>& node_counts);

BackgroundCells make_background_cells(geometry::VolumeMap map, const std::array<int, 3>& counts);

/// How far the cells turn: the largest angle [rad] between two parallel edges of one cell (a cell has four
/// edges along each parametric direction), over all cells. 0 for the cells of a box or plate, the
/// sector's angle for a polar cell; edges of zero length (a collapsed axis or pole) are skipped.
Real largest_cell_turn(const BackgroundCells& cells);

/// dX/du (columns = derivatives along u0, u1, u2) by 4th-order central differences with steps h.
Mat3 map_jacobian(const geometry::VolumeMap& map, const Vec3& u, const Vec3& h);

struct VolumeQuadrature {
  PointMatrix points;             // 3 x Q physical points
  Eigen::VectorXd weights;        // Q
  std::vector<Index> cell_begin;  // size cells + 1: points of cell c are [cell_begin[c], cell_begin[c+1])
  Index size() const { return points.cols(); }
};

struct SurfaceQuadrature {
  PointMatrix points;             // 3 x S
  Eigen::VectorXd weights;        // S (area)
  Eigen::Matrix3Xd normals;       // outward unit normals
  Eigen::VectorXd cell_size;      // cell extent along the normal at the point (Nitsche h)
  std::vector<int> face;          // 2 * axis + side (side 0 = lo, 1 = hi)
  std::vector<Index> cell;        // owning cell
  Index size() const { return points.cols(); }
};

VolumeQuadrature volume_quadrature(const BackgroundCells& cells, const std::array<int, 3>& gauss);
SurfaceQuadrature boundary_quadrature(const BackgroundCells& cells, const std::array<int, 3>& gauss);

/// All faces of every cell (interior faces once per side, with the outward normal of that cell), for
/// gradient smoothing over the cells: the points of cell c are [cell_begin[c], cell_begin[c + 1]). Two
/// cells sharing a face get the same points with opposite normals, so face sums cancel between them.
struct CellFaceQuadrature {
  SurfaceQuadrature faces;
  std::vector<Index> cell_begin;
};
CellFaceQuadrature cell_face_quadrature(const BackgroundCells& cells, const std::array<int, 3>& gauss);

/// The part of the boundary where `selected(x, face)` holds, for loads and constraints on part of a
/// face: faces where the selection holds at every point of `base` (and at points set in from the face's
/// edges and corners) keep their points; every other face is split into split x split sub-faces with the
/// same Gauss rule. A sub-face inside the region keeps its Gauss points; one that the region's boundary
/// crosses is bisected 6 more levels to find the selected part's area and centroid, where it gets one
/// point (so a load's resultant and its moment follow the region to about 1 / (split 2^6) of the cell,
/// whatever the node spacing).
/// This form runs on one thread (`selected` need not be thread-safe).
SurfaceQuadrature refine_selected_faces(const BackgroundCells& cells, const SurfaceQuadrature& base,
                                        const std::array<int, 3>& gauss, int split,
                                        const std::function<bool(const Vec3&, int)>& selected);
/// Makes one selector per thread (a muParser expression is not thread-safe).
using SelectorFactory = std::function<std::function<bool(const Vec3&, int)>()>;
/// The same faces on the OpenMP threads, each testing with its own selector from `make_selected`; the
/// result does not depend on the thread count.
SurfaceQuadrature refine_selected_faces(const BackgroundCells& cells, const SurfaceQuadrature& base,
                                        const std::array<int, 3>& gauss, int split, const SelectorFactory& make_selected);

}  // namespace lamina::efg
