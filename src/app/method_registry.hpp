#pragma once
// The analyses lamina can run, by their `method:` name: which discretization keys each uses,
// how its own case section is read (with diagnostics) and how the analysis is created.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "app/model.hpp"
#include "core/analysis.hpp"
#include "io/case.hpp"
#include "io/case_reader.hpp"

namespace lamina::app {

/// A method's parsed section: an opaque, method-owned options object.
struct MethodOptions {
  virtual ~MethodOptions() = default;
  /// What the method needs of the discretised body (a shell mesh, lattice layers) beyond the case's keys.
  virtual ModelRequest model_request() const { return {}; }
};

struct MethodEntry {
  io::MethodKeys keys;
  std::string summary;  // one line for `lamina info`
  /// Read the method's own section (e.g. `mls_fit:`); problems go to the reader's sink.
  std::function<std::unique_ptr<MethodOptions>(const io::Case&, const io::NodeReader& section)> read_options;
  /// Build the analysis on the prepared model (nodes, selections resolved).
  std::function<std::unique_ptr<Analysis>(const io::Case&, const Model&, const MethodOptions&)> create;
  /// Dotted case keys that may differ between a run and its restart (`--restart`), besides output:
  /// e.g. the end time of an explicit run, so that a finished run can be continued.
  std::vector<std::string> restart_keys = {};
  /// Whether it runs on several MPI ranks (its analysis refuses, with InputError, what it cannot distribute).
  bool distributed = false;
};

/// All methods compiled into this binary.
const std::vector<MethodEntry>& methods();
const MethodEntry* find_method(const std::string& name);

}  // namespace lamina::app
