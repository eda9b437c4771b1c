#pragma once
// A mid-surface mesh of 4-node quadrilateral shell elements with a uniform thickness and
// named node sets on its edges.
#include <map>
#include <string>

#include "core/types.hpp"

namespace lamina {

struct ShellMesh {
  PointMatrix nodes;                                   // 3 x N mid-surface nodes
  Eigen::Matrix<Index, 4, Eigen::Dynamic> quads;       // 4 x E node indices, counter-clockwise
  Real thickness = 0.0;
  std::map<std::string, IndexList> sets;               // named node sets

  Index node_count() const { return nodes.cols(); }
  Index element_count() const { return quads.cols(); }
  /// Sum of the element areas (bilinear quads, 2x2 Gauss).
  Real area() const;
};

}  // namespace lamina
