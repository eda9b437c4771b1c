#pragma once
// The discretised body a method works on: nodes/particles generated from the case's geometry
// and discretization, with every selection of the case resolved to node indices.
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "core/point_cloud.hpp"
#include "core/error.hpp"
#include "core/probe.hpp"
#include "core/shell_mesh.hpp"
#include "io/case.hpp"

namespace lamina::app {

struct Model {
  PointCloud cloud;
  std::optional<ShellMesh> shell;         // shell methods (mpm): the mid-surface mesh; cloud = its nodes
  std::vector<std::array<Index, 3>> triangles;  // geometry mesh: its triangles' corners (cloud indices)
  std::vector<model::Constraint> constraints;  // case.boundary with their nodes resolved (select.nodes, select.label)
  std::vector<model::Load> loads;             // case.loads with their nodes resolved
  std::vector<IndexList> material_nodes;  // per case.materials entry (all nodes when unassigned)
  std::vector<Probe> probes;              // resolved probes, in case order
};

/// What a method asks of its discretised body beyond the case's keys (MethodOptions::model_request),
/// so that the model builder never tests a method name.
struct ModelRequest {
  bool shell_mesh = false;                      // the mid-surface quadrilateral mesh is the body (mpm)
  bool lattice_layers_at_gauss_points = false;  // a plate lattice's layers at the thickness' Gauss points (pd plate correction)
};

/// Generate nodes from geometry + discretization.nodes (or, with discretization.elements or a
/// shell_mesh request, the shell mid-surface mesh whose nodes become the cloud) (+ jitter, or a nodes
/// file) and resolve all selections. Empty selections and unknown sets are input errors (exit 2).
Model build_point_model(const io::Case& c, const ModelRequest& request = {});

/// Give the diagnostics that carry a key path but no file (generators, method set-up) the
/// case file and the line:column of that key (or of its nearest ancestor), in line order.
InputError locate(const InputError& e, const io::Case& c);

/// Resolve every selection of the case (boundary, loads, materials, probes) on model.cloud into the
/// model's node lists and probes; all problems are gathered into one InputError (file positions set).
/// A material without `select` gets every node.
void resolve_selections(const io::Case& c, Model& model);

/// Resolve one selection against a point cloud, throwing InputError at the selection's
/// file position if it is empty or invalid.
IndexList resolve_or_throw(const io::Selection& selection, const PointCloud& cloud);

}  // namespace lamina::app
