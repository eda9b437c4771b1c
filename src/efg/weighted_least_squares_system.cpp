#include "efg/weighted_least_squares_system.hpp"

#include <omp.h>

#include <algorithm>

#include "core/error.hpp"
#include "efg/galerkin_assembly.hpp"
#include "solve/block_pattern.hpp"

namespace lamina::efg {

Real seed_displacement_weight(Real traction_weight, const material::LinearElastic& material) {
  const Real plane = material.E / (1.0 - material.nu * material.nu);
  return traction_weight * plane * plane;
}

Eigen::VectorXd solve_weighted_least_squares(const std::vector<PointResiduals>& point_residuals, Index nodes,
                                             const LeastSquaresWeights& weights, solve::SolverReport& report,
                                             Index& equations) {
  std::vector<IndexList> groups;
  groups.reserve(point_residuals.size());
  equations = 0;
  for (const auto& r : point_residuals) {
    groups.push_back(r.neighbours);
    equations += r.rows.rows();
  }
  const solve::BlockPattern pattern(nodes, 3, groups, true);
  groups.clear();
  std::vector<Real> values(static_cast<std::size_t>(pattern.nonzeros()), 0.0);
  Eigen::VectorXd f = Eigen::VectorXd::Zero(3 * nodes);
  // parallel and deterministic (as the Galerkin volume assembly): one contiguous chunk of points
  // per thread, each thread adds into its own copy of the value range its chunk touches, the copies
  // are summed in thread order
  const Index count = static_cast<Index>(point_residuals.size());
  const int max_threads = std::max(omp_get_max_threads(), 1);
  std::vector<std::vector<Real>> partial(static_cast<std::size_t>(max_threads));
  std::vector<Index> partial_offset(static_cast<std::size_t>(max_threads), 0);
  std::vector<Eigen::VectorXd> partial_f(static_cast<std::size_t>(max_threads));
  int used_threads = 1;
#pragma omp parallel
  {
    const int threads = omp_get_num_threads(), t = omp_get_thread_num();
#pragma omp single
    used_threads = threads;
    const Index begin = chunk_begin(count, threads, t), end = chunk_begin(count, threads, t + 1);
    Index lo = pattern.nonzeros(), hi = 0;
    for (Index p = begin; p < end; ++p) {
      const auto range = pattern.value_range(point_residuals[static_cast<std::size_t>(p)].neighbours);
      lo = std::min(lo, range.first);
      hi = std::max(hi, range.second);
    }
    std::vector<Real>& mine = partial[static_cast<std::size_t>(t)];
    mine.assign(static_cast<std::size_t>(std::max<Index>(hi - lo, 0)), 0.0);
    partial_offset[static_cast<std::size_t>(t)] = lo;
    Eigen::VectorXd& my_f = partial_f[static_cast<std::size_t>(t)];
    my_f = Eigen::VectorXd::Zero(3 * nodes);
    Eigen::MatrixXd weighted, local;
    for (Index p = begin; p < end; ++p) {
      const PointResiduals& r = point_residuals[static_cast<std::size_t>(p)];
      Eigen::VectorXd w(r.rows.rows());
      for (Index i = 0; i < w.size(); ++i) {
        switch (r.kinds[static_cast<std::size_t>(i)]) {
          case ResidualKind::equilibrium: w[i] = weights.equilibrium; break;
          case ResidualKind::traction: w[i] = weights.traction; break;
          case ResidualKind::displacement: w[i] = weights.displacement; break;
        }
      }
      weighted = w.asDiagonal() * r.rows;
      // coefficient-based product: small blocks, no (parallel) GEMM dispatch inside the loop
      local.noalias() = r.rows.transpose().lazyProduct(weighted);
      pattern.scatter(r.neighbours, local, mine.data(), lo);
      const Eigen::VectorXd g = weighted.transpose() * r.rhs;
      for (std::size_t k = 0; k < r.neighbours.size(); ++k)
        my_f.segment<3>(3 * r.neighbours[k]) += g.segment<3>(3 * static_cast<Index>(k));
    }
  }
  for (int t = 0; t < used_threads; ++t) {
    const std::vector<Real>& part = partial[static_cast<std::size_t>(t)];
    const Index offset = partial_offset[static_cast<std::size_t>(t)];
    for (std::size_t i = 0; i < part.size(); ++i) values[static_cast<std::size_t>(offset) + i] += part[i];
    f += partial_f[static_cast<std::size_t>(t)];
  }
  const solve::SparseMatrix M = pattern.matrix(values);
  try {
    return solve::solve_symmetric(M, f, report);
  } catch (const AnalysisError& e) {
    throw AnalysisError(std::string(e.what()) +
                        " (weighted least squares normal equations: check that the essential conditions remove every "
                        "rigid-body motion; a larger support, kappa 2.5 to 3, improves the conditioning)");
  }
}

}  // namespace lamina::efg
