#pragma once
// Typed, validating access to a YAML case file: every read records the key as known, checks
// type and range, and reports problems as Diagnostics (file:line:column, key path, expected, found).
#include <yaml-cpp/yaml.h>

#include <array>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/types.hpp"

namespace lamina::io {

/// The diagnostics of one reading pass, shared by all NodeReaders of a document.
class DiagnosticSink {
 public:
  explicit DiagnosticSink(std::string file) : file_(std::move(file)) {}
  void report(const YAML::Node& node, const std::string& key_path, const std::string& expected,
              const std::string& found);
  /// A problem with its position already known (e.g. from a location recorded while reading).
  void add(Diagnostic diagnostic) { diagnostics_.push_back(std::move(diagnostic)); }
  /// A problem in a --set assignment itself: reported as coming from the command line.
  void report_override(const std::string& assignment, const std::string& key_path, const std::string& expected,
                       const std::string& found);
  /// Paths that came from --set overrides (reported as such instead of a file position).
  void mark_override(const std::string& key_path, const std::string& text) { overrides_.push_back({key_path, text}); }
  /// Positions for nodes built in code (no YAML mark), e.g. a case converted from an OMLL deck:
  /// a key path (or its longest listed prefix) -> 1-based line and column in file().
  void set_source_positions(std::map<std::string, std::pair<int, int>> positions) { positions_ = std::move(positions); }
  /// The recorded position of a key path or of its nearest recorded ancestor.
  std::optional<std::pair<int, int>> source_position(const std::string& key_path) const;
  const std::map<std::string, std::pair<int, int>>& source_positions() const { return positions_; }
  const std::vector<Diagnostic>& diagnostics() const { return diagnostics_; }
  bool empty() const { return diagnostics_.empty(); }
  /// Throw InputError with all diagnostics if there are any, in file order (by line; problems
  /// without a position, such as --set errors, last).
  void throw_if_any() const;
  const std::string& file() const { return file_; }
  /// The folder relative file names in the case are resolved against: the case file's folder,
  /// unless set (a case built from a Python dict stands for the file it was loaded from).
  std::string base_directory() const;
  void set_base_directory(std::string directory) { base_directory_ = std::move(directory); }

 private:
  std::string file_;
  std::string base_directory_;
  std::vector<Diagnostic> diagnostics_;
  std::vector<std::pair<std::string, std::string>> overrides_;
  std::map<std::string, std::pair<int, int>> positions_;
};

/// Diagnostics ordered by line and column (stable; those without a line last).
void sort_by_position(std::vector<Diagnostic>& diagnostics);

/// The 1-based line and column of the node at a dotted key path (materials.0.E) in a loaded
/// document, or of its deepest existing ancestor; nullopt when nothing along the path has a mark.
std::optional<std::pair<int, int>> position_of(const YAML::Node& root, const std::string& key_path);

/// Short description of what a YAML node holds, for "found ..." messages.
std::string describe(const YAML::Node& node);

/// A view of one mapping / sequence / scalar in the case, with its dotted key path.
class NodeReader {
 public:
  NodeReader(YAML::Node node, std::string key_path, DiagnosticSink* sink);

  const YAML::Node& node() const { return node_; }
  const std::string& path() const { return path_; }
  DiagnosticSink& sink() const { return *sink_; }
  bool defined() const { return node_.IsDefined() && !node_.IsNull(); }
  bool is_map() const { return node_.IsMap(); }
  bool is_sequence() const { return node_.IsSequence(); }
  bool is_scalar() const { return node_.IsScalar(); }

  /// Report a problem at this node.
  void error(const std::string& expected, const std::string& found) const;
  void error(const std::string& expected) const { error(expected, describe(node_)); }

  /// Require this node to be a mapping (reports and returns false otherwise).
  bool expect_map() const;
  bool expect_sequence() const;

  bool has(const std::string& key) const;
  /// The child under key (marks the key as known). Missing => undefined reader.
  NodeReader child(const std::string& key) const;
  /// Child that must exist: reports "missing key" when absent.
  NodeReader required(const std::string& key) const;
  /// Elements of a sequence.
  std::vector<NodeReader> elements() const;
  std::vector<std::string> keys() const;

  // Scalars at this node (report and return nullopt on failure).
  std::optional<Real> as_real() const;
  std::optional<long long> as_integer() const;
  std::optional<bool> as_bool() const;
  std::optional<std::string> as_string() const;
  /// One of the allowed words.
  std::optional<std::string> as_word(const std::vector<std::string>& allowed) const;
  /// A sequence of exactly n numbers (n = 0: any length >= 1).
  std::optional<std::vector<Real>> as_reals(std::size_t n = 0) const;
  std::optional<std::vector<long long>> as_integers(std::size_t n = 0) const;

  // Keyed reads with defaults / requirement and range checks.
  Real real(const std::string& key, std::optional<Real> fallback, Real lower = -INFINITY, Real upper = INFINITY,
            bool lower_open = false, bool upper_open = false) const;
  long long integer(const std::string& key, std::optional<long long> fallback, long long lower = LLONG_MIN,
                    long long upper = LLONG_MAX) const;
  bool boolean(const std::string& key, bool fallback) const;
  std::string word(const std::string& key, const std::vector<std::string>& allowed,
                   std::optional<std::string> fallback) const;
  std::string string(const std::string& key, std::optional<std::string> fallback) const;
  /// A file name at key (required), resolved against the case file's folder unless absolute: every
  /// file a case names is found relative to the case. Returns the absolute path; empty if the key is
  /// missing or not a string. A file that cannot be opened for reading (missing, a directory, no
  /// permission) is reported at the key: expected `expected`, found "cannot open file 'X' (resolved to '/abs/X')".
  std::string file_path(const std::string& key, const std::string& expected) const;
  Vec3 vec3(const std::string& key, std::optional<Vec3> fallback) const;

  /// Report every key of this mapping that was never asked for ("unknown key").
  void reject_unknown_keys() const;

 private:
  YAML::Node node_;
  std::string path_;
  DiagnosticSink* sink_;
  std::shared_ptr<std::set<std::string>> known_;  // keys asked for (shared between copies)
};

/// Apply `--set a.b.0.c=value` to a document (value parsed as YAML: numbers, strings, lists).
/// Problems (bad syntax, index out of range) go to the sink.
void apply_override(YAML::Node& root, const std::string& assignment, DiagnosticSink& sink);

/// Load a YAML file; a syntax error becomes a Diagnostic with its line and column. Also rejects
/// a quoted scalar that is never closed (yaml-cpp silently ends it at the end of the file).
YAML::Node load_yaml_file(const std::string& path, DiagnosticSink& sink);

}  // namespace lamina::io
