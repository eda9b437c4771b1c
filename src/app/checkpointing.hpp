#pragma once
// Checkpoint and restart of a run (PRODUCT.md sections 1-2; docs/restart.md): the case text a
// checkpoint must match, the newest valid checkpoint a restart can use, and the stop request that
// SIGTERM / SIGINT leave for the next safe point of the analysis.
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/state_archive.hpp"
#include "io/case.hpp"

namespace lamina::app {

/// The resolved case as YAML text without the keys that may change on a restart: `output` and the
/// method's restart keys (dotted paths, e.g. the end time).
std::string restart_invariant_case(const io::Case& c, const std::vector<std::string>& restart_keys);

struct CaseDifference {
  std::string key_path;         // dotted
  std::string written, current;  // the two values as YAML
};
/// The first difference between two such case texts (none when they agree).
std::optional<CaseDifference> first_case_difference(const std::string& written, const std::string& current);

struct LoadedCheckpoint {
  std::filesystem::path file;
  std::unique_ptr<StateReader> state;
  std::vector<std::string> refused;  // "file: reason" of newer checkpoints that could not be used
};

/// The newest checkpoint of `output_directory` (or of a killed run's staging folder for it) that
/// reads back intact; throws InputError (key --restart) when there is none, with the reasons.
LoadedCheckpoint load_newest_checkpoint(const std::filesystem::path& output_directory);

/// SIGTERM / SIGINT handlers that only record the signal (a second one ends the process at once).
void install_stop_handlers();
void restore_stop_handlers();
/// The signal received since install_stop_handlers(), or 0.
int stop_signal();

}  // namespace lamina::app
