#pragma once
// Reads and validates a case file (PRODUCT.md section 3) into io::Case, applying --set
// overrides first. All problems are collected and reported together (InputError, exit 2).
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "io/case.hpp"
#include "io/yaml_reader.hpp"

namespace lamina::io {

/// The method names a case may give, and the `discretization:` keys each one uses.
struct MethodKeys {
  std::string method;
  std::vector<std::string> discretization_keys;
  bool needs_materials = true;
  /// Top-level sections besides `<method>:` that belong to the method (pd: imperfection, mpm: shell);
  /// the reader leaves them to the method.
  std::vector<std::string> other_sections = {};
  /// Keys under `discretization:` that are the method's own parameters (pd: horizon, mpm: grid); the
  /// reader leaves them to the method, which reads them from the case's `discretization` node.
  std::vector<std::string> own_discretization_keys = {};
};

/// Upper limit of the total node / particle / element count of a discretization (about 2 GB of
/// node data alone; real analyses stay far below). Larger counts are input errors.
inline constexpr long long kMaxDiscretizationCount = 10'000'000;

class CaseReader {
 public:
  /// Loads the file and applies overrides (syntax errors throw InputError immediately).
  CaseReader(const std::string& path, const std::vector<std::string>& overrides,
             std::vector<MethodKeys> methods);
  /// A case built in code (e.g. converted from an OMLL deck) that stands for the file `path`;
  /// `positions` maps key paths to their line and column in that file (for the diagnostics).
  CaseReader(const std::string& path, YAML::Node document, std::map<std::string, std::pair<int, int>> positions,
             const std::vector<std::string>& overrides, std::vector<MethodKeys> methods);

  /// Reads every common section into the Case; problems are collected in sink().
  Case read();
  /// A reader on the method's own section (`efg:`, `mls_fit:` ...), sharing the diagnostics.
  NodeReader method_section(const std::string& name);
  /// A reader on any top-level key (e.g. `method`, to report at its line).
  NodeReader top_level(const std::string& key) { return root_->child(key); }
  /// Report unknown top-level keys, then throw InputError if anything was reported.
  void finish();
  DiagnosticSink& sink() { return *sink_; }

 private:
  void apply_overrides(const std::vector<std::string>& overrides);

  std::string path_;
  std::vector<MethodKeys> methods_;
  bool method_known_ = false;
  std::unique_ptr<DiagnosticSink> sink_;
  YAML::Node document_;
  std::unique_ptr<NodeReader> root_;
};

/// Parse helpers shared with the method sections.
geometry::ScalarField read_scalar_field(const NodeReader& reader);
std::optional<Selection> read_selection(const NodeReader& reader);
/// The `ramp` key under `parent`: linear (default), step, or a table [[s0, f0], [s1, f1], ...].
Ramp read_ramp(const NodeReader& parent);
SourceLocation location_of(const NodeReader& reader);

}  // namespace lamina::io
