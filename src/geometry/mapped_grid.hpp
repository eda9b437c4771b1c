#pragma once
// Structured node grids over mapped (curvilinear) bodies and surfaces: the machinery behind the
// geometry generators. A body is the image of a parametric box [lo0,hi0] x [lo1,hi1] x [lo2,hi2]
// under a smooth map X(u); a surface the image of a parametric rectangle.
//
// Volume grids
//   Nodes sit at equally spaced parameter values. A non-periodic axis with n >= 2 nodes has
//   them at lo + i (hi - lo) / (n - 1); with n = 1 a single node at the middle that represents
//   the whole interval. A periodic axis (the map repeats with period hi - lo) has n >= 3
//   nodes at lo + i (hi - lo) / n (no duplicate seam node).
//   Each node's volume is the exact integral of |det dX/du| over its tributary parametric box
//   (half cells at the ends of non-periodic axes, whole cells elsewhere), supplied by the map as
//   a closed-form `measure(lo, hi)`. The node volumes therefore sum to the exact body volume.
//   Ordering: axis 0 fastest, then axis 1, then axis 2 (index i + n0 * (j + n1 * k)), with the
//   duplicates of a collapsed axis skipped (see `collapse_axis`).
//   Local spacing per node along x, y, z: the largest absolute coordinate difference between
//   the node and its grid neighbours (along each parametric axis; for a single-node axis, the
//   chord across the whole interval).
//
// Surface grids (shell meshes)
//   Element counts e per axis; n = e + 1 nodes on a non-periodic axis, n = e on a periodic one.
//   Element (i, j) has nodes (i,j) (i+1,j) (i+1,j+1) (i,j+1): counter-clockwise in (u, v), so
//   the element normal is dX/du x dX/dv. Same node ordering and collapse rule as volume grids.
#include <array>
#include <functional>
#include <string>
#include <vector>

#include "core/point_cloud.hpp"
#include "core/shell_mesh.hpp"

namespace lamina::geometry {

/// One parametric direction of a mapped grid.
struct GridAxis {
  std::string name;          // for messages, e.g. "circumferential"
  Real lo = 0.0, hi = 1.0;
  bool periodic = false;     // the map repeats with period hi - lo: no duplicate seam nodes
  int min_count = 1;         // fewest nodes (volume) / elements (surface) accepted on this axis
};

/// A named node set defined on the structured indices: the nodes whose index along `axis` is
/// the first (side 0) or last (side 1) one; side -1 means every node.
struct GridSet {
  std::string name;
  int axis = 0;
  int side = 0;
};

/// Parameter values of n nodes on an axis (see the header comment).
std::vector<Real> axis_nodes(const GridAxis& axis, int n);
/// Tributary parametric interval [a, b] of node i of n on an axis.
std::array<Real, 2> axis_tributary(const GridAxis& axis, int n, int i);

struct VolumeMap {
  std::array<GridAxis, 3> axes;
  /// If >= 0: every node with index 0 along `collapse_axis` maps to one point whatever its
  /// index along `collapse_over` (the axis of a solid cylinder, the pole of a closed cap); only
  /// the node with index 0 along `collapse_over` is kept and it receives the others' volumes.
  int collapse_axis = -1;
  int collapse_over = -1;
  std::function<Vec3(const Vec3& u)> position;
  /// Exact integral of |det dX/du| over the parametric box [lo, hi].
  std::function<Real(const Vec3& lo, const Vec3& hi)> measure;
  std::vector<GridSet> sets;
};

struct SurfaceMap {
  std::array<GridAxis, 2> axes;
  int collapse_axis = -1;    // as in VolumeMap; collapses over the other axis
  std::function<Vec3(Real u, Real v)> position;
  Real thickness = 0.0;
  std::vector<GridSet> sets;
};

/// Structured nodes of a mapped body; `counts` are nodes per parametric axis. Throws InputError
/// at `key_path` for counts below an axis's minimum.
PointCloud build_volume_grid(const VolumeMap& map, const std::array<int, 3>& counts, const std::string& key_path);

/// Quadrilateral mesh of a mapped surface; `elements` per parametric axis.
ShellMesh build_surface_grid(const SurfaceMap& map, const std::array<int, 2>& elements, const std::string& key_path);

}  // namespace lamina::geometry
