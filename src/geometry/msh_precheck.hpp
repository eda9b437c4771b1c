#pragma once
// Structural pre-check of a Gmsh .msh file, run by import_gmsh before libgmsh reads the file.
//
// libgmsh 4.8 (gmsh::open) trusts the counts and node references of a .msh file: an msh 2 element
// naming the node one past a too small $Nodes count is read out of bounds and the process dies
// with SIGSEGV (fuzz/README.md, G1); a count of 7e13 is allocated as such (G2); node or element
// blocks holding more entries than their section header announced overflow its buffers (G3); an
// msh 4 physical name of dimension 7 is stored out of bounds. Bad input must be an InputError
// (exit 2), so the file is checked here first, without Gmsh:
// - the first line is $MeshFormat, version 2.x or 4.x, ASCII or binary (binary msh 4 only as 4.1
//   with 8-byte sizes, as Gmsh requires), then $EndMeshFormat; a file that is no .msh file at all
//   is reported without a position (the caller locates it at its key);
// - one $Nodes section: every count at most the file's size in bytes; the msh 4 blocks add up to
//   the header's count; the entries fill the section exactly up to $EndNodes (G1: a count of 7
//   before 8 node lines is refused); node tags unique (msh 2: 0 .. 2^31-1, msh 4: >= 1);
//   coordinates numbers;
// - at most one $Elements section, after $Nodes: the same for its counts; element types that
//   libgmsh 4.8 reads (checked type by type: 1-33, 36-66, 71-75, 79-83, 92-99, 118-124, 137:
//   points, lines, triangles, quadrangles, tetrahedra, hexahedra, prisms, pyramids of the orders
//   Gmsh writes; not polygons, polyhedra, the one-node types 84-89); each element with its
//   type's number of nodes, each of them in $Nodes; msh 2: at most 3 tags, a third one 0;
// - $PhysicalNames: its count matches its lines; dimensions 0-3 (msh > 2.0);
// - binary msh 4.1 $Entities: the counts fit in the file;
// - refused, as lamina reads neither partitions nor data and Gmsh trusts their counts: $NodeData,
//   $ElementData, $ElementNodeData; msh 2 $InterpolationScheme; msh 4 $Periodic, $GhostElements,
//   $PartitionedEntities, $Parametrizations (msh 2 $Periodic is skipped by Gmsh: allowed); msh 2
//   $ParametricNodes (nodes classified on entities by tag: an unknown entity crashes libgmsh, G5).
// Sections are found as Gmsh finds them: lines read in pieces of 255 (msh 2) or 1023 (msh 4)
// bytes, the name a C string (up to a NUL byte) recognised by its prefix (msh 2 also $NO...,
// $ELM...); other sections skipped, in msh 2 to the next line starting with '$' (itself taken as a
// section name, as _readMSH2 does), in msh 4 to the first piece that continues with "End" + that name.
// Inside the checked sections: one entry per line (as Gmsh writes them), at most 255 characters
// (msh 4 element lines 9990; msh 2 element lines any). Not checked: ASCII msh 4 $Entities and
// the sections Gmsh stores as text.
// A problem -> InputError with one Diagnostic {path, line, column, key, expected, found}; in
// binary data the diagnostic has no line, `found` names the byte offset.
#include <string>

namespace lamina::geometry {

void precheck_msh_file(const std::string& path, const std::string& key = "geometry.file");

}  // namespace lamina::geometry
