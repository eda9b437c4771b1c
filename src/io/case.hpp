#pragma once
// The case file as typed data (PRODUCT.md section 3): the sections common to all methods.
// Method sections (efg:, pd:, mpm:, mpfem:, mls_fit:) stay as YAML and are read by the application.
#include <yaml-cpp/yaml.h>

#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/linear_solver_choice.hpp"
#include "core/ramp.hpp"
#include "core/types.hpp"
#include "geometry/expression.hpp"
#include "geometry/geometry_spec.hpp"
#include "geometry/selection.hpp"
#include "material/material_spec.hpp"
#include "model/constraint.hpp"
#include "model/load.hpp"
#include "model/selection.hpp"

namespace lamina::io {

using SourceLocation = model::SourceLocation;
using Selection = model::Selection;

struct MaterialEntry {
  material::MaterialSpec spec;
  std::optional<Selection> select;  // part of the body it applies to (none = everywhere)
};

struct ProbeEntry {
  std::string name;
  std::string field;
  std::string component;
  std::optional<Vec3> at;
  std::optional<std::string> set;
  std::optional<Selection> select;
  SourceLocation location;
};

struct Jitter {
  Real amount = 0.0;  // fraction of the local spacing
  unsigned seed = 1;
};

/// How the body is discretised: which generator builds the nodes (geometry/generators.hpp) and its
/// sizes. A method's own parameters under `discretization:` (pd horizon, mpm grid) are read by the
/// method (MethodKeys::own_discretization_keys); which keys a method accepts is its registry entry's.
struct Discretization {
  std::optional<std::array<int, 3>> nodes;       // a structured 3D point grid over the body
  std::optional<std::string> nodes_file;         // points from a CSV x,y,z
  std::optional<std::vector<Vec3>> node_coordinates;  // nodes: {coordinates: [[x,y,z], ...]}
  std::optional<Jitter> jitter;
  std::optional<Vec3> spacing;                   // a cell-centred lattice of these cell sizes
  std::optional<std::array<int, 2>> elements;    // a quadrilateral mesh of the mid-surface
  std::optional<std::array<int, 2>> particles;   // a 2D particle grid (x-y)
  std::optional<std::string> particles_file;     // 2D particles from a CSV x,y,z
};

struct OutputOptions {
  bool vtu = true;
  int every = 1;  // write every n-th output point as VTU (history gets all)
  // output.checkpoint (incremental analyses): every n-th output point and/or every s seconds of
  // wall-clock time; 0 = not by that measure; both 0 = no checkpoints (SIGTERM / SIGINT still write one).
  int checkpoint_every = 0;
  Real checkpoint_seconds = 0;
};

struct Case {
  std::string file;      // path of the case file
  std::string stem;      // file name without extension
  std::string title;
  std::string method;
  std::string units;
  std::vector<MaterialEntry> materials;
  geometry::GeometrySpec geometry;
  SourceLocation geometry_location;
  SourceLocation discretization_location;
  Discretization discretization;
  std::vector<model::Constraint> boundary;
  std::vector<model::Load> loads;
  std::vector<ProbeEntry> probes;
  OutputOptions output;
  LinearSolverChoice solver;   // `solver:` (efg, mpfem)
  YAML::Node method_section;   // the `<method>:` mapping (may be undefined)
  YAML::Node resolved;         // the whole document after --set overrides (for check / log)
  /// A case built in code (OMLL deck): key path -> line, column in `file` (io/omll_deck.hpp).
  std::map<std::string, std::pair<int, int>> source_positions;
};

}  // namespace lamina::io
