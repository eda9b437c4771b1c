#include "geometry/gmsh_import.hpp"

#include <filesystem>
#include <mutex>
#include <stdexcept>
#include <string>

#include "core/error.hpp"
#include "core/runtime_module.hpp"
#include "geometry/msh_precheck.hpp"

namespace lamina::geometry {

namespace {

using ImportFunction = void (*)(const std::string*, ImportedMesh*);

ImportFunction load_import_function() {
  static std::mutex mutex;
  static ImportFunction function = nullptr;
  std::lock_guard<std::mutex> lock(mutex);
  if (function) return function;
  std::string why;
  function = reinterpret_cast<ImportFunction>(
      open_runtime_module(LAMINA_GMSH_READER_NAME, LAMINA_GMSH_READER_PATH, "lamina_gmsh_import", why));
  if (!function)
    throw std::runtime_error("the Gmsh reader module " + std::string(LAMINA_GMSH_READER_NAME) + " could not be loaded: " + why);
  return function;
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
