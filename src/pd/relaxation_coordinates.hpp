#pragma once
// RelaxationCoordinates: generalised coordinates q of adaptive dynamic relaxation, U = T q. On a plate
// lattice, per node column and displacement component, the mid-surface, director and layer-residual
// modes of the column (plate_columns.hpp) replace the node displacements, so that the diagonal
// fictitious density of seed eq (5), taken as the Gershgorin bound of T^T K0 T, no longer gives the
// deflection w the mass of the stiff thickness stretch of the column (docs/pd.md, "ADR coordinates").
#include <vector>

#include "pd/plate_columns.hpp"
#include "solve/sparse_linear_solver.hpp"

namespace lamina::pd {

struct RelaxationCoordinates {
  solve::SparseMatrix to_nodes;    // T (3N x 3N): U = T q
  solve::SparseMatrix from_nodes;  // T^-1: q = T^-1 U
  std::vector<char> free;          // per generalised dof: moves in the relaxation
  Index mapped_groups = 0;         // (column, component) pairs in column coordinates
};

/// Column coordinates for the (column, component) pairs whose nodes are all free (node_free: per node
/// dof, 1 = unknown); pairs with a prescribed node keep the node dofs (identity rows of T).
RelaxationCoordinates column_coordinates(const PlateColumns& columns, Index nodes, const std::vector<char>& node_free);

/// Row sums of |T^T K T| for K stored as its upper triangle (the Gershgorin bound in q).
Eigen::VectorXd generalised_absolute_row_sums(const solve::SparseMatrix& upper, const RelaxationCoordinates& coordinates);

}  // namespace lamina::pd
