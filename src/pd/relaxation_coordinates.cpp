#include "pd/relaxation_coordinates.hpp"

#include <Eigen/Dense>

namespace lamina::pd {

RelaxationCoordinates column_coordinates(const PlateColumns& columns, Index nodes, const std::vector<char>& node_free) {
  RelaxationCoordinates rc;
  const Index dofs = 3 * nodes;
  rc.free = node_free;
  std::vector<char> mapped(static_cast<std::size_t>(dofs), 0);
  std::vector<Eigen::Triplet<Real, int>> t, ti;
  for (Index c = 0; c < columns.columns(); ++c) {
    const Index p0 = columns.first[static_cast<std::size_t>(c)], count = columns.first[static_cast<std::size_t>(c) + 1] - p0;
    if (count < 2) continue;  // a one-layer column has no modes to map: its node keeps its own dofs
    // the column modes: uniform (mid-surface), linear in the height (director), and an orthonormal
    // completion (layer residuals); T's block maps mode amplitudes to the layer displacements
    Eigen::MatrixXd block(count, count);
    Eigen::MatrixXd two(count, 2);
    for (Index k = 0; k < count; ++k) {
      two(k, 0) = 1.0;
      two(k, 1) = columns.zeta[columns.node[static_cast<std::size_t>(p0 + k)]];
    }
    block.leftCols(2) = two;
    if (count > 2) {
      Eigen::HouseholderQR<Eigen::MatrixXd> qr(two);
      const Eigen::MatrixXd q = qr.householderQ() * Eigen::MatrixXd::Identity(count, count);
      block.rightCols(count - 2) = q.rightCols(count - 2);
    }
    const Eigen::MatrixXd inverse = block.inverse();
    for (int a = 0; a < 3; ++a) {
      bool all_free = true;
      for (Index k = 0; k < count; ++k)
        all_free = all_free && node_free[static_cast<std::size_t>(3 * columns.node[static_cast<std::size_t>(p0 + k)] + a)];
      if (!all_free) continue;
      ++rc.mapped_groups;
      for (Index r = 0; r < count; ++r) {
        const Index row = 3 * columns.node[static_cast<std::size_t>(p0 + r)] + a;
        mapped[static_cast<std::size_t>(row)] = 1;
        for (Index s = 0; s < count; ++s) {
          // generalised dof s of this group lives at the dof of the group's s-th node
          const Index col = 3 * columns.node[static_cast<std::size_t>(p0 + s)] + a;
          if (block(r, s) != 0.0) t.emplace_back(static_cast<int>(row), static_cast<int>(col), block(r, s));
          if (inverse(s, r) != 0.0) ti.emplace_back(static_cast<int>(col), static_cast<int>(row), inverse(s, r));
        }
      }
    }
  }
  for (Index d = 0; d < dofs; ++d)
    if (!mapped[static_cast<std::size_t>(d)]) {
      t.emplace_back(static_cast<int>(d), static_cast<int>(d), 1.0);
      ti.emplace_back(static_cast<int>(d), static_cast<int>(d), 1.0);
    }
  rc.to_nodes.resize(dofs, dofs);
  rc.to_nodes.setFromTriplets(t.begin(), t.end());
  rc.from_nodes.resize(dofs, dofs);
  rc.from_nodes.setFromTriplets(ti.begin(), ti.end());
  return rc;
}

Eigen::VectorXd generalised_absolute_row_sums(const solve::SparseMatrix& upper, const RelaxationCoordinates& coordinates) {
  const solve::SparseMatrix full = upper.selfadjointView<Eigen::Upper>();
  const solve::SparseMatrix mapped = coordinates.to_nodes.transpose() * full * coordinates.to_nodes;
  return mapped.cwiseAbs() * Eigen::VectorXd::Ones(mapped.cols());
}

}  // namespace lamina::pd
