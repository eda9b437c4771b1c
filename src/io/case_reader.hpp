#pragma once
// Reads and validates a case file (PRODUCT.md section 3) into io::Case, applying --set
// overrides first. All problems are collected and reported together (InputError, exit 2).
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
};

class CaseReader {
 public:
  /// Loads the file and applies overrides (syntax errors throw InputError immediately).
  CaseReader(const std::string& path, const std::vector<std::string>& overrides,
             std::vector<MethodKeys> methods);

  /// Reads every common section into the Case; problems are collected in sink().
  Case read();
  /// A reader on the method's own section (`efg:`, `mls_fit:` ...), sharing the diagnostics.
  NodeReader method_section(const std::string& name);
  /// Report unknown top-level keys, then throw InputError if anything was reported.
  void finish();
  DiagnosticSink& sink() { return *sink_; }

 private:
  std::string path_;
  std::vector<MethodKeys> methods_;
  std::unique_ptr<DiagnosticSink> sink_;
  YAML::Node document_;
  std::unique_ptr<NodeReader> root_;
};

/// Parse helpers shared with the method sections.
geometry::ScalarField read_scalar_field(const NodeReader& reader);
std::optional<Selection> read_selection(const NodeReader& reader);
SourceLocation location_of(const NodeReader& reader);

}  // namespace lamina::io
