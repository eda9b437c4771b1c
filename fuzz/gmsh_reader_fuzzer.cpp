// libFuzzer target for the Gmsh mesh reader (geometry::import_gmsh; see fuzz/README.md).
//
// The .msh text or binary file itself is parsed by libgmsh (gmsh::open), not by lamina: lamina's
// part is what it does with the Gmsh API's answers (src/gmsh_reader/gmsh_reader.cpp): node tags
// sorted and de-duplicated, element node tags looked up, hexahedron/tetrahedron volumes, spacing
// from element edges, quadrilaterals -> shell, physical groups -> node sets. That is what this
// target fuzzes, with the input written to scratch/mesh.msh (the reader takes a path).
//
// The program loads that code as a module (dlopen, src/geometry/gmsh_import.cpp); here
// gmsh_reader.cpp is compiled into the target with the fuzzing instrumentation and its function
// is called directly. Like import_gmsh, the target first runs the structural pre-check of
// src/geometry/msh_precheck (lamina's own code, instrumented), which refuses the files libgmsh
// crashed on (fuzz/README.md, G1-G3) before gmsh::open sees them.
//
// Expected outcome: success or lamina::InputError (Gmsh's own errors arrive as InputError too);
// on success the mesh must be consistent (sizes, indices in range, volumes >= 0).
// Anything else aborts (fuzz_support.hpp).
#include <cstdint>
#include <string>

#include "fuzz_support.hpp"
#include "geometry/gmsh_import.hpp"
#include "geometry/msh_precheck.hpp"

namespace lamina::geometry {
ImportedMesh import_gmsh_with_gmsh_api(const std::string& path);  // src/gmsh_reader/gmsh_reader.cpp
}

namespace {

constexpr const char* kTarget = "gmsh_reader_fuzzer";

void check(const lamina::geometry::ImportedMesh& mesh) {
  using lamina::Index;
  using lamina::fuzz::finding;
  const lamina::PointCloud& cloud = mesh.cloud;
  const Index n = cloud.size();
  if (n < 1) finding(kTarget, "a mesh without nodes was accepted");
  if (cloud.volumes.size() != n || cloud.spacing.cols() != n || static_cast<Index>(mesh.node_tags.size()) != n)
    finding(kTarget, "cloud arrays of different sizes");
  for (Index i = 0; i < n; ++i)
    if (cloud.volumes[i] < 0.0) finding(kTarget, "a negative node volume");
  for (std::size_t i = 1; i < mesh.node_tags.size(); ++i)
    if (!(mesh.node_tags[i - 1] < mesh.node_tags[i])) finding(kTarget, "node tags not strictly increasing");
  for (const auto& [name, set] : cloud.sets) {
    if (name.empty()) finding(kTarget, "a node set without a name");
    for (Index i : set)
      if (i < 0 || i >= n) finding(kTarget, "node set '" + name + "' holds an index out of range");
  }
  const Index shell_nodes = mesh.shell.nodes.cols();
  if (mesh.has_quads != (mesh.shell.quads.cols() > 0)) finding(kTarget, "has_quads disagrees with the shell");
  for (Index e = 0; e < mesh.shell.quads.cols(); ++e)
    for (int a = 0; a < 4; ++a)
      if (mesh.shell.quads(a, e) < 0 || mesh.shell.quads(a, e) >= shell_nodes)
        finding(kTarget, "a shell quadrilateral refers to a node out of range");
  for (const auto& [name, set] : mesh.shell.sets)
    for (Index i : set)
      if (i < 0 || i >= shell_nodes) finding(kTarget, "shell set '" + name + "' holds an index out of range");
  (void)mesh.shell.area();
}

}  // namespace

// libgmsh 4.8 leaks on some malformed files (e.g. a new[] buffer in GModel::_readMSH4 that an
// error path does not free; found by this target in its first seconds): its own allocations, not
// lamina's. LeakSanitizer reads these default suppressions (scripts/lsan.supp has the same line).
extern "C" const char* __lsan_default_suppressions() { return "leak:libgmsh.so\n"; }

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = lamina::fuzz::write_scratch("mesh.msh", data, size);
  lamina::fuzz::expect_input_errors(kTarget, [&] {
    lamina::geometry::precheck_msh_file(path);  // as import_gmsh does before loading the module
    check(lamina::geometry::import_gmsh_with_gmsh_api(path));
  });
  return 0;
}
