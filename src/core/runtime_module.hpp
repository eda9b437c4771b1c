#pragma once
// lamina's run-time modules: libraries with heavy dependencies (the Gmsh reader, the PETSc solvers) are
// shared modules opened with dlopen on first use, so that a process loads them only when it needs them.
#include <string>

namespace lamina {

/// Opens the module file `file_name` (RTLD_NOW | RTLD_LOCAL): beside the running program (the installed
/// layout), one folder up (the test and bench programs), then at `build_path` (where the build put it; the
/// Python module). Returns the address of `symbol` in the first candidate that opens and has it (the module
/// then stays loaded), or nullptr with the reason in `why` (not found, dlerror(), or no such symbol).
void* open_runtime_module(const char* file_name, const char* build_path, const char* symbol, std::string& why);

}  // namespace lamina
