#pragma once
// Sparsity pattern of a global matrix with `block` degrees of freedom per node (3 for 3D
// elasticity), built from "groups": sorted node lists whose nodes all couple with each other
// (the neighbours of a background cell, of a boundary point ...). Column-major storage as an
// Eigen::SparseMatrix (int indices); symmetric patterns hold the upper triangle only.
//
// Layout: column block*J + b holds, for every node I adjacent to J (I <= J when symmetric), the
// rows block*I .. block*I + block-1 (only rows <= the column on the diagonal block), in increasing I.
// Hence the value of (row block*I + a, column block*J + b) sits at
//   column_start(block*J + b) + block * rank_J(I) + a,     rank_J(I) = position of I among J's neighbours.
#include <vector>

#include "core/types.hpp"
#include "solve/sparse_linear_solver.hpp"

namespace lamina::solve {

class BlockPattern {
 public:
  BlockPattern() = default;
  /// groups: each sorted ascending, duplicates not allowed within a group. Parallel (OpenMP).
  BlockPattern(Index nodes, int block, const std::vector<IndexList>& groups, bool symmetric);

  Index nodes() const { return nodes_; }
  int block() const { return block_; }
  bool symmetric() const { return symmetric_; }
  Index dofs() const { return nodes_ * block_; }
  Index nonzeros() const { return static_cast<Index>(rows_.size()); }

  /// Position in the value array of block (I, J)'s entry (0, 0) relative to column block*J + b:
  /// value index = column_start(block*J + b) + block * rank + a. Returns -1 if not in the pattern
  /// (or, for symmetric patterns, if I > J).
  Index rank(Index I, Index J) const;
  Index column_start(Index column) const { return column_start_[static_cast<std::size_t>(column)]; }
  /// Value index of (row, column) dofs, -1 if absent (symmetric: absent below the diagonal).
  Index position(Index row, Index column) const;

  /// A matrix with this pattern and the given values (size nonzeros()).
  SparseMatrix matrix(const std::vector<Real>& values) const;
  /// A matrix with this pattern and zero values (zeroed in parallel), to assemble into in place.
  SparseMatrix zero_matrix() const;

  /// Adds a dense local matrix (block*n x block*n) over the nodes `local` (sorted ascending) to
  /// values[index - offset]. Symmetric patterns take the upper triangle (I < J, or I == J and a <= b).
  /// Node pairs outside the pattern are skipped; their block must be exactly zero (else logic_error).
  void scatter(const IndexList& local, const Eigen::MatrixXd& k, Real* values, Index offset = 0) const;
  /// Sorted neighbours of node J (only I <= J when symmetric): [first, last).
  const Index* neighbours_begin(Index J) const { return adjacency_.data() + adjacency_start_[static_cast<std::size_t>(J)]; }
  const Index* neighbours_end(Index J) const { return adjacency_.data() + adjacency_start_[static_cast<std::size_t>(J + 1)]; }
  /// Value-index range [first, last) touched by scatter() for a local node list.
  std::pair<Index, Index> value_range(const IndexList& local) const;

 private:
  Index nodes_ = 0;
  int block_ = 3;
  bool symmetric_ = true;
  std::vector<Index> adjacency_start_;  // nodes + 1
  std::vector<Index> adjacency_;        // sorted neighbours of each node (<= J if symmetric)
  std::vector<int> column_start_;       // dofs + 1
  std::vector<int> rows_;               // row index of every stored value
};

}  // namespace lamina::solve
