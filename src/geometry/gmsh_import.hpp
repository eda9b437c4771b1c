#pragma once
// Import of a Gmsh mesh file (.msh v2 or v4, ASCII or binary) through the Gmsh C++ API.
//
// - cloud: every node of the file, ordered by Gmsh node tag. Node volumes: each linear
//   hexahedron (Gmsh type 5) gives its nodes the exact integrals of their trilinear shape
//   functions times |det J| (2x2x2 Gauss), each linear tetrahedron (type 4) a quarter of its
//   volume; other element types carry no volume (a surface-only mesh has zero volumes). The
//   volumes sum to the volume of the hexahedra and tetrahedra. counts = {0,0,0}, parametric
//   empty. spacing: per node, the largest |dx|, |dy|, |dz| over the element edges at the node
//   (nodes on no element edge: the distances to their nearest node).
// - shell: the 4-node quadrilaterals (type 3; of second-order quads, types 10 and 16, the 4
//   corners), with the node order of the file; shell.nodes are only the nodes those quads use,
//   in cloud order; thickness 0 (the caller sets it).
// - triangles: the corners of every triangle (Gmsh types 2 and 9, 3 x count, cloud indices; the
//   2D particle methods take a triangle mesh's boundary from them).
// - sets: each physical group (any dimension) becomes a node set named by its physical name,
//   or "group<tag>" when unnamed; groups with the same name are merged. The shell's sets are
//   the same sets restricted to the shell's nodes (renumbered), dropped when empty.
// Errors (missing or unreadable file, no nodes) -> InputError at "geometry.file" naming the file.
// Before Gmsh reads the file, precheck_msh_file (geometry/msh_precheck.hpp) checks its structure:
// libgmsh 4.8 crashes on some malformed files (a too small node count, huge counts), which are
// refused there with file:line:column.
// The function initialises and finalises the Gmsh API itself (serialised by a mutex): do not
// call it while the calling program has its own Gmsh session open.
#include <array>
#include <string>
#include <vector>

#include "core/point_cloud.hpp"
#include "core/shell_mesh.hpp"

namespace lamina::geometry {

struct ImportedMesh {
  PointCloud cloud;
  ShellMesh shell;
  bool has_hexahedra = false;
  bool has_quads = false;
  std::vector<std::array<Index, 3>> triangles;
  std::vector<std::size_t> node_tags;  // Gmsh tag of each cloud node
};

ImportedMesh import_gmsh(const std::string& path);

}  // namespace lamina::geometry
