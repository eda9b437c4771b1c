#include "solve/sparse_cholesky.hpp"

#include <mutex>
#include <string>

#include "core/error.hpp"
#include "core/runtime_module.hpp"

namespace lamina::solve {

namespace {

/// The module, loaded once per process (it stays loaded until the process ends).
const CholmodFactorModule& module() {
  static std::mutex mutex;
  static const CholmodFactorModule* table = nullptr;
  std::lock_guard<std::mutex> lock(mutex);
  if (table) return *table;
  std::string why;
  table = open_module_table<CholmodFactorModule>(LAMINA_CHOLMOD_FACTOR_NAME, LAMINA_CHOLMOD_FACTOR_PATH,
                                                 "lamina_cholmod_factor", cholmod_factor_abi, why);
  if (!table)
    throw SolverUnavailable("the CHOLMOD module " + std::string(LAMINA_CHOLMOD_FACTOR_NAME) + " could not be loaded: " + why);
  return *table;
}

}  // namespace

std::unique_ptr<SparseCholesky> make_sparse_cholesky() { return module().create(); }

}  // namespace lamina::solve
