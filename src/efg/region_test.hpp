#pragma once
// Tests whether a point lies in a case selection (model::Selection), for quadrature points:
//   all      always
//   where    the expression is non-zero at the point
//   box      min - tol <= x <= max + tol (tol = 1e-9 x body size)
//   set      on a boundary surface: the point lies on the generator face of that name (sets are
//            faces of the parametric box, e.g. xmin, start, inner); in the volume, or for sets
//            that are not generator faces: the nearest node belongs to the set
//   nearest  never on a surface (a point selection); in the volume: the nearest node is that node
// Not thread-safe (muParser): use from one thread.
#include <functional>
#include <memory>
#include <vector>

#include "efg/efg_problem.hpp"
#include "geometry/mapped_grid.hpp"

namespace lamina::efg {

class RegionTest {
 public:
  using NearestNode = std::function<Index(const Vec3&)>;
  RegionTest(const model::Selection& region, const geometry::VolumeMap* map, NearestNode nearest, Real tolerance);

  bool in_volume(const Vec3& x) const;
  /// face = 2 * axis + side of the boundary face the point lies on.
  bool on_surface(const Vec3& x, int face) const;
  /// Whether the selection can hold on a surface at all (false for `nearest`).
  bool can_select_surface() const;

 private:
  bool nearest_in_nodes(const Vec3& x) const;
  const model::Selection* region_;
  NearestNode nearest_;
  Real tolerance_;
  std::vector<int> faces_;  // set kind: generator faces of the set (empty: not a face set)
  std::unique_ptr<geometry::Expression> expression_;
};

/// Value of a scalar field (constant or expression of x y z t) at a point, t = 1 (end of loading).

}  // namespace lamina::efg
