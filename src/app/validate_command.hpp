#pragma once
// `lamina validate`: runs the validation cases (validation/<name>/ with case.yaml, reference CSV
// and check.yaml), prints a table, writes report.md and PNG plots (reference markers vs lamina line).
#include <string>
#include <vector>

namespace lamina::app {

struct ValidateOptions {
  std::vector<std::string> names;  // empty => all (or all fast ones with --fast)
  std::string output_directory = "out/validation";
  std::string validation_directory;  // empty => <source>/validation
  bool fast = false;
  int threads = 0;
};

/// Exit code: 0 all passed, 1 a check failed, 2 a validation folder is invalid or unknown.
int validate(const ValidateOptions& options);

}  // namespace lamina::app
