#include "pd/zero_energy_check.hpp"

#include <cmath>

#include "pd/peridynamic_model.hpp"
#include "solve/sparse_cholesky.hpp"

namespace lamina::pd {

namespace {

/// The largest share of a mode that is not a rigid motion of the nodes (0: rigid).
Real non_rigid_share(const Eigen::VectorXd& mode, const std::vector<Index>& dofs, const PointMatrix& positions) {
  const Index m = mode.size();
  Eigen::MatrixXd rigid(m, 6);
  const Vec3 centre = positions.rowwise().mean();
  for (Index k = 0; k < m; ++k) {
    const Index node = dofs[static_cast<std::size_t>(k)] / 3;
    const int a = static_cast<int>(dofs[static_cast<std::size_t>(k)] % 3);
    const Vec3 x = positions.col(node) - centre;
    for (int r = 0; r < 3; ++r) rigid(k, r) = a == r ? 1.0 : 0.0;
    for (int r = 0; r < 3; ++r) {
      Vec3 axis = Vec3::Zero();
      axis[r] = 1;
      rigid(k, 3 + r) = axis.cross(x)[a];
    }
  }
  const Eigen::VectorXd fit = rigid * rigid.colPivHouseholderQr().solve(mode);
  return (mode - fit).norm() / std::max(mode.norm(), 1e-300);
}

}  // namespace

ZeroEnergyReport find_zero_energy_modes(const solve::SparseMatrix& reduced_upper, const std::vector<Index>& dofs,
                                        const PointMatrix& positions, Real threshold) {
  ZeroEnergyReport report;
  const Index m = reduced_upper.rows();
  if (m == 0) return report;
  const Eigen::VectorXd scale = (0.25 * absolute_row_sums(reduced_upper)).cwiseMax(1e-300).cwiseInverse().cwiseSqrt();
  solve::SparseMatrix scaled = scale.asDiagonal() * reduced_upper * scale.asDiagonal();
  // a failed factorisation is an answer here, not a warning (CHOLMOD prints nothing)
  const std::unique_ptr<solve::SparseCholesky> llt = solve::make_sparse_cholesky();
  Eigen::VectorXd mode;
  if (!llt->compute(scaled)) {
    // singular: shift by the threshold and take the lowest mode of the shifted matrix
    solve::SparseMatrix shifted = scaled;
    for (Index k = 0; k < m; ++k) shifted.coeffRef(k, k) += 10 * threshold;
    report.singular = true;
    if (!llt->compute(shifted)) return report;  // cannot classify
  }
  // inverse iteration from a deterministic start
  Eigen::VectorXd x(m);
  for (Index k = 0; k < m; ++k) x[k] = 1.0 + 0.5 * std::sin(0.7 * static_cast<Real>(k) + 0.3);
  x.normalize();
  Real estimate = 0;
  for (int it = 0; it < 40; ++it) {
    Eigen::VectorXd y = llt->solve(x);
    const Real norm = y.norm();
    if (!(norm > 0) || !std::isfinite(norm)) break;
    const Real next = 1.0 / norm;  // |K^-1 x| ~ 1 / lambda_min
    x = y / norm;
    report.iterations = it + 1;
    if (it > 4 && std::abs(next - estimate) <= 1e-3 * next) {
      estimate = next;
      break;
    }
    estimate = next;
  }
  const Eigen::VectorXd kx = scaled.selfadjointView<Eigen::Upper>() * x;
  report.smallest = std::max(0.0, x.dot(kx));
  if (report.smallest < threshold) report.singular = true;
  if (report.singular) {
    const Eigen::VectorXd physical = scale.cwiseProduct(x);  // back to displacements
    report.rigid = non_rigid_share(physical, dofs, positions) < 1e-3;
    Index where = 0;
    Eigen::VectorXd per_node = Eigen::VectorXd::Zero(positions.cols());
    for (Index k = 0; k < m; ++k) per_node[dofs[static_cast<std::size_t>(k)] / 3] += physical[k] * physical[k];
    per_node.maxCoeff(&where);
    report.node = where;
  }
  return report;
}

}  // namespace lamina::pd
