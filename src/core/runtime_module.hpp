#pragma once
// lamina's run-time modules: libraries with heavy dependencies (the Gmsh reader, the PETSc solvers) are
// shared modules opened with dlopen on first use, so that a process loads them only when it needs them.
#include <string>

namespace lamina {

/// OpenBLAS (Debian's DYNAMIC_ARCH build, loaded with the sparse solver modules) picks its kernels from
/// the CPU model when it is loaded; version 0.3.21 does not know CPUs newer than it (Sapphire and Emerald
/// Rapids, models 143 / 207) and falls back to its generic Prescott (SSE3) kernels, which made CHOLMOD's
/// supernodal factorisation 2.3 x slower (bench/pd_plate_buckling.py: 9.5 s against 4.1 s). Unless the
/// user set OPENBLAS_CORETYPE, this names the kernel family from the CPU's own feature flags (AVX-512:
/// SkylakeX, AVX2 + FMA: Haswell, else OpenBLAS's own choice). Called once, at start-up (main, the Python
/// module) and before the first module opens; only the kernels' speed changes, not the arithmetic's order
/// within a kernel family.
void select_blas_kernels();

/// Opens the module file `file_name` (RTLD_NOW | RTLD_LOCAL): beside the running program (the installed
/// layout), one folder up (the test and bench programs), then at `build_path` (where the build put it; the
/// Python module). Returns the address of `symbol` in the first candidate that opens and has it (the module
/// then stays loaded), or nullptr with the reason in `why` (not found, dlerror(), or no such symbol).
void* open_runtime_module(const char* file_name, const char* build_path, const char* symbol, std::string& why);

/// The table of functions a module's entry point `symbol` (a function returning const Table*) hands out,
/// checked against this build's interface version `abi` (Table::abi); nullptr with the reason in `why`
/// if the module cannot be opened, returns nothing, or is from another build.
template <class Table>
const Table* open_module_table(const char* file_name, const char* build_path, const char* symbol, int abi, std::string& why) {
  using EntryPoint = const Table* (*)();
  const auto entry = reinterpret_cast<EntryPoint>(open_runtime_module(file_name, build_path, symbol, why));
  if (!entry) return nullptr;
  const Table* table = entry();
  if (!table) {
    why = "its entry point returned nothing";
    return nullptr;
  }
  if (table->abi != abi) {
    why = "it is from another lamina build (interface version " + std::to_string(table->abi) + ", expected " +
          std::to_string(abi) + ")";
    return nullptr;
  }
  return table;
}

}  // namespace lamina
