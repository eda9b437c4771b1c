// libFuzzer target for the case-file reader (see fuzz/README.md).
//
// Each input is a case file. It is written to a private temporary folder (the reader only
// takes a path) and read with lamina::app::prepare_case, exactly as `lamina run/check` do. If
// it is valid, the resolved document is emitted again (as `lamina check` prints it) and, when the
// node count is small, the point model is built (generators, selections, named sets), as
// `lamina check` does.
//
// Leading comment lines of the form `#--set key.path=value` are also passed as --set
// overrides, so the fuzzer reaches apply_override too (they are plain comments to YAML).
//
// Expected outcome: success, or lamina::InputError (exit code 2 in the program). Anything
// else - another exception (exit 1, "internal error"), a crash, a sanitizer report, a hang -
// is a finding: the harness aborts so that libFuzzer saves the reproducer.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

#include "app/model.hpp"
#include "app/run_command.hpp"
#include "core/error.hpp"

namespace {

/// Largest node count for which the model is also built (keeps each execution fast).
constexpr long long kMaxModelNodes = 4000;

std::filesystem::path case_path() {
  static const std::filesystem::path path = [] {
    std::string pattern = (std::filesystem::temp_directory_path() / "lamina-fuzz-XXXXXX").string();
    if (!::mkdtemp(pattern.data())) {
      std::perror("case_parser_fuzzer: mkdtemp");
      std::abort();
    }
    return std::filesystem::path(pattern) / "case.yaml";
  }();
  return path;
}

std::vector<std::string> overrides_in(std::string_view text) {
  std::vector<std::string> overrides;
  constexpr std::string_view prefix = "#--set ";
  while (text.substr(0, prefix.size()) == prefix && overrides.size() < 8) {
    const auto end = text.find('\n');
    overrides.emplace_back(text.substr(prefix.size(), end == std::string_view::npos ? std::string_view::npos
                                                                                    : end - prefix.size()));
    if (end == std::string_view::npos) break;
    text.remove_prefix(end + 1);
  }
  return overrides;
}

bool small_model(const lamina::io::Case& c) {
  if (c.geometry.type == lamina::geometry::GeometryType::mesh) return false;  // Gmsh: not the parser's business
  if (c.discretization.nodes_file || !c.discretization.nodes) return false;
  long long total = 1;
  for (int n : *c.discretization.nodes) total *= n;
  return total <= kMaxModelNodes;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const std::filesystem::path path = case_path();
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
  }
  try {
    lamina::app::PreparedCase prepared = lamina::app::prepare_case(path.string(), overrides_in(text));
    YAML::Emitter emitter;
    emitter << prepared.case_data.resolved;
    if (!emitter.good()) {
      std::fprintf(stderr, "case_parser_fuzzer: emitting the resolved case failed: %s\n", emitter.GetLastError().c_str());
      std::abort();
    }
    if (small_model(prepared.case_data)) (void)lamina::app::build_point_model(prepared.case_data);
  } catch (const lamina::InputError& e) {
    // Expected for invalid input. Every diagnostic must at least name a key path or a file.
    for (const auto& d : e.diagnostics()) {
      if (d.key_path.empty() && d.file.empty()) {
        std::fprintf(stderr, "case_parser_fuzzer: diagnostic without key path or file: %s\n", d.format().c_str());
        std::abort();
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "case_parser_fuzzer: unexpected exception (lamina would exit 1): %s\n", e.what());
    std::abort();
  } catch (...) {
    std::fprintf(stderr, "case_parser_fuzzer: unexpected non-standard exception\n");
    std::abort();
  }
  return 0;
}
