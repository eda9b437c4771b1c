#pragma once
// ForceSplit: force decomposition over the ranks of a pd analysis that keeps the whole body on every
// rank (quasi_static by adaptive dynamic relaxation): the items (nodes, or the plate model's node
// columns) in recursive-coordinate-bisection order, each rank computing the internal forces of one
// contiguous block of that order; complete() all-gathers the blocks into the whole force. Every rank
// then runs the same relaxation on the same numbers as one process (the forces are per-node gathers).
#include <vector>

#include "core/types.hpp"
#include "parallel/communicator.hpp"
#include "pd/plate_columns.hpp"

namespace lamina::pd {

class ForceSplit {
 public:
  /// columns: the plate model's columns (items of `layers` nodes), or null (items are nodes). Collective.
  ForceSplit(const PointMatrix& positions, const PlateColumns* columns, const parallel::Communicator& comm);
  /// Per node: 1 when this rank computes its force.
  const std::vector<char>& mine() const { return mine_; }
  /// force: this rank's nodes filled in; afterwards every node's. Collective.
  void complete(PointMatrix& force) const;

 private:
  const parallel::Communicator& comm_;
  int nodes_per_item_ = 1;
  std::vector<Index> item_nodes_;  // item k's nodes: [k x nodes_per_item, (k + 1) x nodes_per_item), split order
  std::vector<char> mine_;
  mutable Eigen::MatrixXd buffer_;  // 3 nodes_per_item x items
};

}  // namespace lamina::pd
