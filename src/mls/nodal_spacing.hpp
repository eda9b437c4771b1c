#pragma once
// Local nodal spacing h_I (one length per axis and node) that sizes the supports R_I,d = kappa h_I,d
// of the default "kappa" support mode (seed 004, OMLL supports: "radius s + delta").
#include "core/types.hpp"

namespace lamina::mls {

/// Per node I and axis d < dimension: among the 3^dimension - 1 nearest other nodes J, those "roughly
/// along d" (|dx_d| >= |dx| / sqrt(dimension)) are split into the + and - side of I; h_I,d is the larger
/// of the two one-sided minima of |dx_d| (one side only at a boundary). A regular grid with spacing
/// h_d therefore gives exactly h_d (up to the rounding of the coordinates). An axis with no such node
/// (e.g. a flat cloud) takes the largest spacing of the other axes; rows d >= dimension are zero.
/// Coincident nodes are ignored. Parallel over nodes (OpenMP). Throws lamina::InputError for fewer
/// than 2 distinct nodes.
Eigen::Matrix3Xd estimate_nodal_spacing(const PointMatrix& nodes, int dimension = 3);

/// Mean spacing of a cloud from its bounding box: (volume of the non-flat axes / N)^(1/axes), using the
/// first `dimension` coordinates; 0 if all nodes coincide.
Real mean_nodal_spacing(const PointMatrix& nodes, int dimension = 3);

}  // namespace lamina::mls
