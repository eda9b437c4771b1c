#include "pd/force_split.hpp"

#include <algorithm>
#include <numeric>

#include "parallel/recursive_bisection.hpp"

namespace lamina::pd {

ForceSplit::ForceSplit(const PointMatrix& positions, const PlateColumns* columns, const parallel::Communicator& comm)
    : comm_(comm) {
  const Index n = positions.cols();
  PointMatrix centres;
  if (columns) {
    nodes_per_item_ = columns->layers;
    centres = PointMatrix::Zero(3, columns->columns());
    for (Index c = 0; c < columns->columns(); ++c) {
      for (Index p = columns->first[c]; p < columns->first[c + 1]; ++p) centres.col(c) += positions.col(columns->node[p]);
      centres.col(c) /= static_cast<Real>(columns->first[c + 1] - columns->first[c]);
    }
  }
  const PointMatrix& points = columns ? centres : positions;
  const Index items = points.cols();
  // the bisection's parts, then the items of each part in index order: rank r's block of this order is
  // (about) its part
  const std::vector<int> part = parallel::recursive_coordinate_bisection(points, comm);
  std::vector<Index> order(static_cast<std::size_t>(items));
  std::iota(order.begin(), order.end(), Index{0});
  std::stable_sort(order.begin(), order.end(), [&](Index a, Index b) {
    return part[static_cast<std::size_t>(a)] < part[static_cast<std::size_t>(b)];
  });
  item_nodes_.reserve(static_cast<std::size_t>(n));
  for (Index k : order) {
    if (!columns) {
      item_nodes_.push_back(k);
      continue;
    }
    for (Index p = columns->first[k]; p < columns->first[k + 1]; ++p) item_nodes_.push_back(columns->node[p]);
  }
  mine_.assign(static_cast<std::size_t>(n), 0);
  const std::size_t per = static_cast<std::size_t>(nodes_per_item_);
  for (Index k = comm.block_begin(items, comm.rank()); k < comm.block_begin(items, comm.rank() + 1); ++k)
    for (std::size_t l = 0; l < per; ++l) mine_[static_cast<std::size_t>(item_nodes_[static_cast<std::size_t>(k) * per + l])] = 1;
  buffer_.resize(3 * nodes_per_item_, items);
}

void ForceSplit::complete(PointMatrix& force) const {
  const Index items = buffer_.cols();
  const std::size_t per = static_cast<std::size_t>(nodes_per_item_);
  for (Index k = comm_.block_begin(items, comm_.rank()); k < comm_.block_begin(items, comm_.rank() + 1); ++k)
    for (std::size_t l = 0; l < per; ++l)
      buffer_.col(k).segment<3>(3 * static_cast<Index>(l)) = force.col(item_nodes_[static_cast<std::size_t>(k) * per + l]);
  comm_.all_gather_blocks(buffer_.data(), static_cast<int>(buffer_.rows()), items);
  for (Index k = 0; k < items; ++k)
    for (std::size_t l = 0; l < per; ++l)
      force.col(item_nodes_[static_cast<std::size_t>(k) * per + l]) = buffer_.col(k).segment<3>(3 * static_cast<Index>(l));
}

}  // namespace lamina::pd
