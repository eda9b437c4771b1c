#pragma once
// The three kinds of failure lamina distinguishes, mapped to the exit codes of PRODUCT.md:
// InputError -> 2 (nothing ran), AnalysisError -> 3 (diverged/singular, last good state kept).
#include <stdexcept>
#include <string>
#include <vector>

namespace lamina {

/// One problem in the user's input: where it is and what was expected.
struct Diagnostic {
  std::string file;      // case file (or "--set" for a command-line override)
  int line = 0;          // 1-based; 0 when unknown
  int column = 0;        // 1-based; 0 when unknown
  std::string key_path;  // dotted path, e.g. materials.0.nu
  std::string expected;  // what a valid value looks like
  std::string found;     // what was there
  /// "file:line:column: key_path: expected X, found Y"
  std::string format() const;
};

/// Invalid input: one or more diagnostics; nothing has been run.
class InputError : public std::runtime_error {
 public:
  explicit InputError(std::vector<Diagnostic> diagnostics);
  explicit InputError(Diagnostic diagnostic) : InputError(std::vector<Diagnostic>{std::move(diagnostic)}) {}
  /// Convenience: a problem that is not tied to a file position.
  InputError(const std::string& key_path, const std::string& expected, const std::string& found);
  const std::vector<Diagnostic>& diagnostics() const { return diagnostics_; }

 private:
  std::vector<Diagnostic> diagnostics_;
};

/// A valid case that the rank count of this run cannot do (one that runs on one process only); exit 2.
class SingleProcessOnly : public InputError {
 public:
  using InputError::InputError;
};

/// The analysis itself failed (singular system, divergence, non-finite values).
class AnalysisError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A solver the case asks for is not available to this process (the PETSc module could not be loaded):
/// an AnalysisError that callers pass on as it is, without advice about the system being solved.
class SolverUnavailable : public AnalysisError {
 public:
  using AnalysisError::AnalysisError;
};

}  // namespace lamina
