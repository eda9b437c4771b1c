#include "solve/sparse_cholesky.hpp"

#include <mutex>
#include <string>

#include "core/error.hpp"
#include "core/runtime_module.hpp"

namespace lamina::solve {

namespace {

using EntryPoint = const CholmodFactorModule* (*)();

/// The module, loaded once per process (it stays loaded until the process ends).
const CholmodFactorModule& module() {
  static std::mutex mutex;
  static const CholmodFactorModule* table = nullptr;
  std::lock_guard<std::mutex> lock(mutex);
  if (table) return *table;
  std::string why;
  const auto entry = reinterpret_cast<EntryPoint>(
      open_runtime_module(LAMINA_CHOLMOD_FACTOR_NAME, LAMINA_CHOLMOD_FACTOR_PATH, "lamina_cholmod_factor", why));
  const CholmodFactorModule* loaded = entry ? entry() : nullptr;
  if (entry && !loaded) why = "its entry point returned nothing";
  if (loaded && loaded->abi != cholmod_factor_abi)
    why = "it is from another lamina build (interface version " + std::to_string(loaded->abi) + ", expected " +
          std::to_string(cholmod_factor_abi) + ")";
  if (!loaded || loaded->abi != cholmod_factor_abi)
    throw SolverUnavailable("the CHOLMOD module " + std::string(LAMINA_CHOLMOD_FACTOR_NAME) + " could not be loaded: " + why);
  table = loaded;
  return *table;
}

}  // namespace

std::unique_ptr<SparseCholesky> make_sparse_cholesky() { return module().create(); }

}  // namespace lamina::solve
