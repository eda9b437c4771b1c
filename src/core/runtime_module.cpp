#include "core/runtime_module.hpp"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <vector>

namespace lamina {

void select_blas_kernels() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (std::getenv("OPENBLAS_CORETYPE")) return;
#if defined(__x86_64__) || defined(__i386__)
    __builtin_cpu_init();
    const char* family = nullptr;
    if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512vl") &&
        __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512cd"))
      family = "SkylakeX";
    else if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"))
      family = "Haswell";
    if (family) setenv("OPENBLAS_CORETYPE", family, 0);
#endif
  });
}

void* open_runtime_module(const char* file_name, const char* build_path, const char* symbol, std::string& why) {
  select_blas_kernels();
  std::vector<std::filesystem::path> candidates;
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    candidates.push_back(exe.parent_path() / file_name);
    candidates.push_back(exe.parent_path().parent_path() / file_name);  // tests/, bench/
  }
  candidates.push_back(build_path);
  why.clear();
  for (const auto& candidate : candidates) {
    if (!std::filesystem::is_regular_file(candidate, ec)) continue;
    void* handle = dlopen(candidate.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
      const char* error = dlerror();
      why = error ? error : candidate.string() + " could not be opened";
      continue;
    }
    if (void* address = dlsym(handle, symbol)) return address;
    why = candidate.string() + " has no " + symbol;
    dlclose(handle);
  }
  if (why.empty()) why = std::string("not found beside the program or at ") + build_path;
  return nullptr;
}

}  // namespace lamina
