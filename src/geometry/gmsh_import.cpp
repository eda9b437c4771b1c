#include "geometry/gmsh_import.hpp"

#include <dlfcn.h>

#include <filesystem>
#include <mutex>

#include "core/error.hpp"
#include "geometry/msh_precheck.hpp"

namespace lamina::geometry {

namespace {

using ImportFunction = void (*)(const std::string*, ImportedMesh*);

/// The module file: beside the running program (the installed layout), else where the build put it.
std::vector<std::filesystem::path> module_candidates() {
  std::vector<std::filesystem::path> candidates;
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    candidates.push_back(exe.parent_path() / LAMINA_GMSH_READER_NAME);
    candidates.push_back(exe.parent_path().parent_path() / LAMINA_GMSH_READER_NAME);  // tests/, bench/
  }
  candidates.push_back(LAMINA_GMSH_READER_PATH);
  return candidates;
}

ImportFunction load_import_function() {
  static std::mutex mutex;
  static ImportFunction function = nullptr;
  std::lock_guard<std::mutex> lock(mutex);
  if (function) return function;
  std::string why;
  for (const auto& candidate : module_candidates()) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(candidate, ec)) continue;
    void* handle = dlopen(candidate.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
      why = dlerror();
      continue;
    }
    function = reinterpret_cast<ImportFunction>(dlsym(handle, "lamina_gmsh_import"));
    if (function) return function;
    why = candidate.string() + " has no lamina_gmsh_import";
  }
  throw std::runtime_error("the Gmsh reader module " + std::string(LAMINA_GMSH_READER_NAME) + " could not be loaded" +
              (why.empty() ? " (not found beside the program or in the build tree)" : ": " + why));
}

}  // namespace

ImportedMesh import_gmsh(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw InputError("geometry.file", "an existing Gmsh .msh file", "'" + path + "' (no such file)");
  // libgmsh trusts the file's counts and node references (a wrong count can crash the process):
  // a structural check first, every problem an InputError naming file:line:column.
  precheck_msh_file(path, "geometry.file");
  ImportedMesh out;
  load_import_function()(&path, &out);
  return out;
}

}  // namespace lamina::geometry
