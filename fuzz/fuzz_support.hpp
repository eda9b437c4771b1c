#pragma once
// Shared pieces of the libFuzzer targets (see fuzz/README.md): a private scratch folder for the
// files the readers take by path, and the verdict on an exception.
//
// Verdict: lamina::InputError (exit 2 in the program) is the expected outcome of invalid input;
// each of its diagnostics must name a key path or a file. Anything else escaping the code under
// test (exit 1, "internal error", in the program) is a finding: the harness prints it and calls
// abort() so that libFuzzer keeps the input.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include "core/error.hpp"

namespace lamina::fuzz {

/// A folder of this process (created on first use, under $TMPDIR).
inline const std::filesystem::path& scratch_dir() {
  static const std::filesystem::path dir = [] {
    std::string pattern = (std::filesystem::temp_directory_path() / "lamina-fuzz-XXXXXX").string();
    if (!::mkdtemp(pattern.data())) {
      std::perror("lamina fuzz target: mkdtemp");
      std::abort();
    }
    return std::filesystem::path(pattern);
  }();
  return dir;
}

/// Write `size` bytes to scratch_dir()/name (truncating) and return the path.
inline std::string write_scratch(const std::string& name, const uint8_t* data, size_t size) {
  const std::filesystem::path path = scratch_dir() / name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  out.close();
  if (!out) {
    std::fprintf(stderr, "lamina fuzz target: cannot write %s\n", path.c_str());
    std::abort();
  }
  return path.string();
}

inline std::string write_scratch(const std::string& name, std::string_view text) {
  return write_scratch(name, reinterpret_cast<const uint8_t*>(text.data()), text.size());
}

[[noreturn]] inline void finding(const char* target, const std::string& what) {
  std::fprintf(stderr, "%s: %s\n", target, what.c_str());
  std::abort();
}

/// Run `body`; InputError is fine (with located diagnostics), so is AnalysisError when
/// `analysis_errors_ok` (the body ran an analysis: exit 3 in the program); anything else aborts.
template <class Body>
void expect_input_errors(const char* target, Body&& body, bool analysis_errors_ok = false) {
  try {
    body();
  } catch (const InputError& e) {
    for (const auto& d : e.diagnostics())
      if (d.key_path.empty() && d.file.empty()) finding(target, "diagnostic without key path or file: " + d.format());
  } catch (const AnalysisError& e) {
    if (!analysis_errors_ok) finding(target, std::string("unexpected AnalysisError: ") + e.what());
  } catch (const std::exception& e) {
    finding(target, std::string("unexpected exception (lamina would exit 1): ") + e.what());
  } catch (...) {
    finding(target, "unexpected non-standard exception");
  }
}

}  // namespace lamina::fuzz
