#pragma once
// `lamina run` and `lamina check`: read and validate a case, build the model, run the method,
// write the result set. Returns PRODUCT.md exit codes (0 ok, 1 internal, 2 input, 3 analysis; 128 + signal
// when SIGTERM / SIGINT stopped the run after writing a checkpoint).
#include <nlohmann/json.hpp>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "app/method_registry.hpp"
#include "io/case.hpp"

namespace lamina::app {

struct RunOptions {
  std::string case_path;
  std::string output_directory;  // empty => out/<stem>
  int threads = 0;               // 0 => OpenMP default
  std::vector<std::string> overrides;
  bool quiet = false;
  std::string restart_directory;  // --restart: continue from its newest valid checkpoint
};

/// A case read and validated, with its method's options.
struct PreparedCase {
  io::Case case_data;
  const MethodEntry* method = nullptr;
  std::unique_ptr<MethodOptions> options;
};

/// The case keys of every method name a case may give: those of this build, and the planned
/// ones (PRODUCT.md section 5) so that their cases are read without false errors.
std::vector<io::MethodKeys> all_method_keys();

/// Read + validate everything that can be checked without running (throws InputError).
/// `path` is a YAML case, or an OMLL macro deck (*.omll, io/omll_deck.hpp) converted on the fly.
PreparedCase prepare_case(const std::string& path, const std::vector<std::string>& overrides);

struct RunResult {
  int exit_code = 0;
  std::string error;
  nlohmann::json summary;
  std::vector<std::string> history_columns;
  std::vector<std::vector<Real>> history_rows;
  std::filesystem::path output_directory;
};

RunResult run_case(const RunOptions& options);
int check_case(const std::string& path, const std::vector<std::string>& overrides);

}  // namespace lamina::app
