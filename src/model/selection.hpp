#pragma once
// A part of the body chosen in the case file (PRODUCT.md section 4: all / where / box / set / nearest)
// and, once the model is built, the node (particle) indices it picked; with where it came from.
#include <string>

#include "core/types.hpp"
#include "geometry/selection.hpp"

namespace lamina::model {

/// Where something came from in the case file (for messages raised after parsing).
struct SourceLocation {
  std::string file;
  int line = 0, column = 0;
  std::string key_path;
};

struct Selection {
  geometry::SelectionSpec spec;  // the geometric definition (kind all / where / box / set / nearest)
  SourceLocation location;       // of the `select` key
  IndexList nodes;               // resolved on the discretised body when the model is built (app/model.cpp)
  std::string label;             // key path of the owner in messages, e.g. "boundary.0", "loads.2"
};

}  // namespace lamina::model
