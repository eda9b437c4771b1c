#include "core/runtime_module.hpp"

#include <dlfcn.h>

#include <filesystem>
#include <vector>

namespace lamina {

void* open_runtime_module(const char* file_name, const char* build_path, const char* symbol, std::string& why) {
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
