#pragma once
// A part of the body chosen in the case file (PRODUCT.md section 4: all / where / box / set / nearest)
// and, once the model is built, the node (particle) indices it picked; with where it came from.
#include <string>

#include "core/error.hpp"
#include "core/types.hpp"
#include "geometry/selection.hpp"

namespace lamina::model {

/// Where something came from in the case file (for messages raised after parsing).
struct SourceLocation {
  std::string file;
  int line = 0, column = 0;
  std::string key_path;
};

/// A problem with the entry at `where` (key appended to its key path), for InputError.
inline Diagnostic diagnostic_at(const SourceLocation& where, const std::string& key, const std::string& expected,
                                const std::string& found) {
  return Diagnostic{where.file, where.line, where.column, where.key_path + key, expected, found};
}

struct Selection {
  geometry::SelectionSpec spec;  // the geometric definition (kind all / where / box / set / nearest)
  SourceLocation location;       // of the `select` key
  IndexList nodes;               // resolved on the discretised body when the model is built (app/model.cpp)
  std::string label;             // key path of the owner in messages, e.g. "boundary.0", "loads.2"
};

}  // namespace lamina::model
