#pragma once
// Geometry generators (PRODUCT.md section 4): structured nodes filling a body (continuum
// methods) and mid-surface quadrilateral meshes (shell methods), the analytic volume and
// mid-surface area of every body, and a point-in-body test.
//
// ---------------------------------------------------------------------------------------------
// Volume nodes: generate_volume_nodes(spec, counts), counts = nodes per mapped direction.
//   type          counts                                   parametric (u0, u1, u2)
//   box           [nx, ny, nz]                             (x, y, z)
//   plate         [nx, ny, nz], z in [-t/2, t/2]           (x, y, z)
//   curved_beam   [radial, circumferential, z]             (r, theta [rad], z)
//   cylinder      solid (thickness = 0): [radial incl. the axis, circumferential, axial]
//                 tube (thickness > 0, radius = mid-surface radius): [through-thickness,
//                 circumferential, axial]                  (r, theta [rad], a)
//   sphere_cap    [through-thickness, meridional (hole -> base), circumferential]
//                                                          (rho, polar angle phi [rad], longitude [rad])
//   annulus       [radial, circumferential, through-thickness], z in [0, thickness]
//                                                          (r, theta [rad], z)
//   square_tube   [through-thickness, around the perimeter, axial]
//                                                          (offset from mid-surface, arc length s, z)
//   mesh          counts ignored: the nodes of the Gmsh file (see gmsh_import.hpp)
//
// Spacing along a direction: n >= 2 nodes equally spaced in the mapped coordinate from end to
// end; n = 1 puts one node at the middle representing the whole extent (it then belongs to
// the sets of both ends). Closed directions (a full 360-degree cylinder, cap or annulus
// without slit; the square tube's perimeter) are periodic: n >= 3 nodes at lo + i*period/n,
// no seam duplicates. The annulus with a slit is not periodic: the nodes at theta = 0 and 2 pi
// are distinct coincident pairs (sets slit_start, slit_end) - the only coincident nodes any
// generator makes. A solid cylinder's axis (r = 0) and a cap without hole's pole (phi = 0) are
// collapsed to one node per axial position / per layer (needs >= 2 nodes along that direction);
// that node carries the whole tributary volume around it.
// Node ordering: first count index fastest, i + n0*(j + n1*k), skipping collapsed duplicates.
// Node volumes: exact integrals of the map's Jacobian over each node's tributary parametric
// box (half cells at ends); they sum to body_volume() to rounding.
// spacing (3 x N): per node, the largest |dx|, |dy|, |dz| to its structured neighbours.
//
// Angles: curved_beam/annulus/sphere_cap longitude from +x towards +y. Cylinder: theta from
// e1 towards e2 with (e1, e2, axis) right-handed: axis z -> e1 = x, e2 = y; axis x -> e1 = y,
// e2 = z; axis y -> e1 = z, e2 = x. The square tube's arc length s starts at (width/2, 0) and
// runs counter-clockwise about +z; a count that is a multiple of 8 puts nodes on the
// corners / corner-arc midpoints (and a multiple of 4 on the side midpoints).
// Square tube section: width is the mid-surface width, corner_radius the mid-surface corner
// radius (0 = sharp corners: the wall is the exact square frame, mapped with mitred corners;
// otherwise corner_radius >= thickness/2 so the inner surface exists).
//
// Named sets of volume nodes (nodes on those faces):
//   box: xmin xmax ymin ymax zmin zmax        plate: xmin xmax ymin ymax bottom top
//   curved_beam: inner outer start end (+ zmin zmax)
//   cylinder: end0 end1, outer (+ inner for a tube), panels also edge0 (theta 0) edge1 (theta max)
//   sphere_cap: hole base inner outer, sectors also side0 (longitude 0) side1 (longitude max)
//   annulus: inner outer bottom top, with slit also slit_start slit_end
//   square_tube: end0 end1 inner outer
//
// ---------------------------------------------------------------------------------------------
// Shell meshes: generate_shell_mesh(spec, elements), elements per mid-surface direction (the
// volume counts without the through-thickness one):
//   plate         [ex, ey]; z = 0; normal +z
//   box           mid-surface normal to its thinnest extent (ties: z before y before x) through
//                 the middle; elements along the next two axes in cyclic order (thin z: [ex, ey];
//                 thin x: [ey, ez]; thin y: [ez, ex]); normal + that axis; thickness = extent
//   curved_beam   [circumferential, z] strip at the mean radius; thickness = outer - inner;
//                 normal radially outward
//   cylinder      tube only (thickness > 0): [circumferential, axial] at `radius`; normal outward
//   sphere_cap    [meridional, circumferential] at `radius`; normal outward. Without a hole the
//                 first ring of elements is degenerate (quads with the pole node repeated).
//   annulus       [radial, circumferential] at z = thickness/2 (the middle of the continuum
//                 body's z in [0, thickness]); normal +z; with slit the seam nodes are doubled
//   square_tube   [perimeter, axial]; normal outward
// Element nodes are counter-clockwise about the stated normal. Periodic directions need >= 3
// elements, the others >= 1.
// Shell sets (node sets on mid-surface edges): the same names as above for the edges; names of
// faces parallel to the mid-surface (plate top/bottom, box faces normal to the thin axis,
// curved_beam/cylinder/sphere_cap/square_tube inner/outer, annulus top/bottom) hold all nodes.
// Also curved_beam zmin zmax (edges at z0, z1).
// ---------------------------------------------------------------------------------------------
#include <array>
#include <string>

#include "core/point_cloud.hpp"
#include "core/shell_mesh.hpp"
#include "geometry/geometry_spec.hpp"

namespace lamina::geometry {

/// Throws InputError (key path "geometry.<parameter>") if the parameters do not describe a
/// valid body of spec.type.
void validate_geometry(const GeometrySpec& spec);

/// Structured nodes filling the body, with tributary volumes, parametric coordinates, counts,
/// local spacing and named sets. Bad counts -> InputError at "discretization.nodes.<i>".
PointCloud generate_volume_nodes(const GeometrySpec& spec, const std::array<int, 3>& counts);

/// Mid-surface quadrilateral mesh with the shell thickness. Bad element counts -> InputError at
/// "discretization.elements.<i>". For type mesh: the file's quadrilaterals, thickness = spec.thickness.
ShellMesh generate_shell_mesh(const GeometrySpec& spec, const std::array<int, 2>& elements);

/// Exact volume of the body (type mesh: sum of its volume elements' volumes).
Real body_volume(const GeometrySpec& spec);

/// Exact area of the shell mid-surface (type mesh: area of its quadrilaterals). A solid
/// cylinder has none (InputError).
Real mid_surface_area(const GeometrySpec& spec);

/// Whether x lies in the closed body, enlarged by `tolerance` (a distance). Always true for
/// type mesh (no analytic description).
bool body_contains(const GeometrySpec& spec, const Vec3& x, Real tolerance);

}  // namespace lamina::geometry
