#pragma once
// `lamina run` and `lamina check`: read and validate a case, build the model, run the method,
// write the result set. Returns PRODUCT.md exit codes (0 ok, 1 internal, 2 input, 3 analysis; 128 + signal
// when SIGTERM / SIGINT stopped the run after writing a checkpoint).
#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "app/method_registry.hpp"
#include "core/analysis.hpp"
#include "io/case.hpp"

namespace lamina::app {

/// What an output point reports to RunOptions::on_output: the history row just written.
struct OutputPointReport {
  Index step = 0;
  Real time = 0;
  Real load_factor = 0;
  const std::vector<std::string>* probe_names = nullptr;  // user probes, then the method's built-in ones
  const std::vector<Real>* probe_values = nullptr;
};

struct RunOptions {
  std::string case_path;
  std::string output_directory;  // empty => out/<stem>
  int threads = 0;               // 0 => OpenMP default
  std::vector<std::string> overrides;
  bool quiet = false;
  std::string restart_directory;  // --restart: continue from its newest valid checkpoint
  /// Folder the case's relative file names are resolved against (empty: the case file's folder).
  std::string case_directory;
  /// Called after each output point's history row; returning false ends the run there, cleanly (the
  /// result set is written, summary status "stopped"). Used by the Python API's on_output.
  std::function<bool(const OutputPointReport&)> on_output;
  /// Keep the last output point's frame (points and fields) in RunResult::last_frame.
  bool keep_last_frame = false;
};

/// A case read and validated, with its method's options.
struct PreparedCase {
  io::Case case_data;
  const MethodEntry* method = nullptr;
  std::unique_ptr<MethodOptions> options;
};

/// The case keys of every method of this build (the registry's).
std::vector<io::MethodKeys> all_method_keys();

/// Read + validate everything that can be checked without running (throws InputError).
/// `path` is a YAML case, or an OMLL macro deck (*.omll, io/omll_deck.hpp) converted on the fly.
/// `case_directory`: where relative file names are resolved (empty: the case file's folder).
PreparedCase prepare_case(const std::string& path, const std::vector<std::string>& overrides,
                          const std::string& case_directory = {});

struct RunResult {
  int exit_code = 0;
  std::string error;
  nlohmann::json summary;
  std::vector<std::string> history_columns;
  std::vector<std::vector<Real>> history_rows;
  std::filesystem::path output_directory;
  std::optional<OutputFrame> last_frame;  // with RunOptions::keep_last_frame
  bool single_process_only = false;       // exit 2 because the case runs on one process only (several ranks)
};

RunResult run_case(const RunOptions& options);
int check_case(const std::string& path, const std::vector<std::string>& overrides);

}  // namespace lamina::app
