#include "solve/block_pattern.hpp"

#include <algorithm>
#include <limits>

#include "core/error.hpp"
#include "core/memory.hpp"

namespace lamina::solve {

BlockPattern::BlockPattern(Index nodes, int block, const std::vector<IndexList>& groups, bool symmetric)
    : nodes_(nodes), block_(block), symmetric_(symmetric) {
  // groups containing each node (CSR)
  std::vector<Index> member_start(static_cast<std::size_t>(nodes + 1), 0);
  for (const auto& g : groups)
    for (Index J : g) ++member_start[static_cast<std::size_t>(J + 1)];
  for (Index J = 0; J < nodes; ++J) member_start[static_cast<std::size_t>(J + 1)] += member_start[static_cast<std::size_t>(J)];
  std::vector<Index> members(static_cast<std::size_t>(member_start.back()));
  {
    std::vector<Index> fill(member_start.begin(), member_start.end() - 1);
    for (std::size_t g = 0; g < groups.size(); ++g)
      for (Index J : groups[g]) members[static_cast<std::size_t>(fill[static_cast<std::size_t>(J)]++)] = static_cast<Index>(g);
  }
  // adjacency of each node: union of its groups (parallel, per-node lists)
  std::vector<IndexList> adjacent(static_cast<std::size_t>(nodes));
#pragma omp parallel
  {
    std::vector<char> marker(static_cast<std::size_t>(nodes), 0);
#pragma omp for schedule(dynamic, 64)
    for (Index J = 0; J < nodes; ++J) {
      IndexList& list = adjacent[static_cast<std::size_t>(J)];
      for (Index m = member_start[static_cast<std::size_t>(J)]; m < member_start[static_cast<std::size_t>(J + 1)]; ++m) {
        for (Index I : groups[static_cast<std::size_t>(members[static_cast<std::size_t>(m)])]) {
          if (symmetric && I > J) break;  // groups are sorted
          if (!marker[static_cast<std::size_t>(I)]) {
            marker[static_cast<std::size_t>(I)] = 1;
            list.push_back(I);
          }
        }
      }
      if (!marker[static_cast<std::size_t>(J)]) list.push_back(J);  // the diagonal block always exists
      for (Index I : list) marker[static_cast<std::size_t>(I)] = 0;
      std::sort(list.begin(), list.end());
    }
  }
  adjacency_start_.assign(static_cast<std::size_t>(nodes + 1), 0);
  for (Index J = 0; J < nodes; ++J)
    adjacency_start_[static_cast<std::size_t>(J + 1)] = adjacency_start_[static_cast<std::size_t>(J)] + static_cast<Index>(adjacent[static_cast<std::size_t>(J)].size());
  adjacency_.resize(static_cast<std::size_t>(adjacency_start_.back()));
  for (Index J = 0; J < nodes; ++J)
    std::copy(adjacent[static_cast<std::size_t>(J)].begin(), adjacent[static_cast<std::size_t>(J)].end(),
              adjacency_.begin() + adjacency_start_[static_cast<std::size_t>(J)]);
  adjacent.clear();
  adjacent.shrink_to_fit();

  // columns
  const Index dofs = nodes * block;
  std::vector<Index> start(static_cast<std::size_t>(dofs + 1), 0);
  for (Index J = 0; J < nodes; ++J) {
    const Index count = adjacency_start_[static_cast<std::size_t>(J + 1)] - adjacency_start_[static_cast<std::size_t>(J)];
    for (int b = 0; b < block; ++b) {
      const Index column = J * block + b;
      const Index entries = symmetric ? (count - 1) * block + (b + 1) : count * block;
      start[static_cast<std::size_t>(column + 1)] = start[static_cast<std::size_t>(column)] + entries;
    }
  }
  if (start.back() > std::numeric_limits<int>::max())
    throw AnalysisError("the stiffness matrix has more than 2^31 stored entries: reduce the node count or the support size");
  column_start_.assign(start.begin(), start.end());
  rows_.resize(static_cast<std::size_t>(start.back()));
#pragma omp parallel for schedule(dynamic, 64)
  for (Index J = 0; J < nodes; ++J) {
    for (int b = 0; b < block; ++b) {
      const Index column = J * block + b;
      Index p = start[static_cast<std::size_t>(column)];
      for (Index k = adjacency_start_[static_cast<std::size_t>(J)]; k < adjacency_start_[static_cast<std::size_t>(J + 1)]; ++k) {
        const Index I = adjacency_[static_cast<std::size_t>(k)];
        const int last = (symmetric && I == J) ? b : block - 1;
        for (int a = 0; a <= last; ++a) rows_[static_cast<std::size_t>(p++)] = static_cast<int>(I * block + a);
      }
    }
  }
}

Index BlockPattern::rank(Index I, Index J) const {
  if (symmetric_ && I > J) return -1;
  const auto first = adjacency_.begin() + adjacency_start_[static_cast<std::size_t>(J)];
  const auto last = adjacency_.begin() + adjacency_start_[static_cast<std::size_t>(J + 1)];
  const auto it = std::lower_bound(first, last, I);
  if (it == last || *it != I) return -1;
  return static_cast<Index>(it - first);
}

Index BlockPattern::position(Index row, Index column) const {
  const Index I = row / block_, a = row % block_, J = column / block_, b = column % block_;
  if (symmetric_ && (I > J || (I == J && a > b))) return -1;
  const Index r = rank(I, J);
  if (r < 0) return -1;
  return column_start(column) + block_ * r + a;
  (void)b;
}

SparseMatrix BlockPattern::matrix(const std::vector<Real>& values) const {
  const Index dofs = nodes_ * block_;
  SparseMatrix m(dofs, dofs);
  m.resizeNonZeros(static_cast<Index>(rows_.size()));
  std::copy(column_start_.begin(), column_start_.end(), m.outerIndexPtr());
  std::copy(rows_.begin(), rows_.end(), m.innerIndexPtr());
  std::copy(values.begin(), values.end(), m.valuePtr());
  // mark as compressed (resizeNonZeros on a fresh matrix keeps it compressed)
  return m;
}

SparseMatrix BlockPattern::zero_matrix() const {
  const Index dofs = nodes_ * block_;
  SparseMatrix m(dofs, dofs);
  const Index count = static_cast<Index>(rows_.size());
  m.resizeNonZeros(count);
  std::copy(column_start_.begin(), column_start_.end(), m.outerIndexPtr());
  Real* values = m.valuePtr();
  int* rows = m.innerIndexPtr();
  advise_huge_pages(values, static_cast<std::size_t>(count) * sizeof(Real));
  advise_huge_pages(rows, static_cast<std::size_t>(count) * sizeof(int));
  // first touch in parallel: the pages are faulted in by both threads
#pragma omp parallel for schedule(static)
  for (Index k = 0; k < count; ++k) {
    values[k] = 0.0;
    rows[k] = rows_[static_cast<std::size_t>(k)];
  }
  return m;
}

void BlockPattern::scatter(const IndexList& local, const Eigen::MatrixXd& k, Real* values, Index offset) const {
  const Index n = static_cast<Index>(local.size());
  for (Index jj = 0; jj < n; ++jj) {
    const Index J = local[static_cast<std::size_t>(jj)];
    const auto first = adjacency_.begin() + adjacency_start_[static_cast<std::size_t>(J)];
    const auto last = adjacency_.begin() + adjacency_start_[static_cast<std::size_t>(J + 1)];
    auto it = first;
    const Index end = symmetric_ ? jj + 1 : n;
    for (Index ii = 0; ii < end; ++ii) {
      const Index I = local[static_cast<std::size_t>(ii)];
      it = std::lower_bound(it, last, I);  // local is sorted: search forward
      if (it == last || *it != I) {
        // pairs outside the pattern must not carry values
        for (int b = 0; b < block_; ++b)
          for (int a = 0; a < block_; ++a)
            if (k(block_ * ii + a, block_ * jj + b) != 0.0)
              throw std::logic_error("BlockPattern::scatter: non-zero value for a node pair outside the pattern");
        continue;
      }
      const Index r = static_cast<Index>(it - first);
      for (int b = 0; b < block_; ++b) {
        const Index base = column_start_[static_cast<std::size_t>(J * block_ + b)] + block_ * r - offset;
        const int last_a = (symmetric_ && I == J) ? b : block_ - 1;
        for (int a = 0; a <= last_a; ++a) values[base + a] += k(block_ * ii + a, block_ * jj + b);
      }
    }
  }
}

std::pair<Index, Index> BlockPattern::value_range(const IndexList& local) const {
  if (local.empty()) return {0, 0};
  return {column_start_[static_cast<std::size_t>(local.front() * block_)],
          column_start_[static_cast<std::size_t>((local.back() + 1) * block_)]};
}

}  // namespace lamina::solve
