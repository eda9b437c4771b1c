#include "efg/collocation_system.hpp"

#include <fmt/format.h>

#include "core/error.hpp"

namespace lamina::efg {

Eigen::VectorXd solve_collocation(const std::vector<PointResiduals>& node_residuals, solve::SolverReport& report) {
  const Index n = static_cast<Index>(node_residuals.size());
  std::vector<Eigen::Triplet<Real>> entries;
  Eigen::VectorXd rhs(3 * n);
  for (Index I = 0; I < n; ++I) {
    const PointResiduals& r = node_residuals[static_cast<std::size_t>(I)];
    if (r.rows.rows() != 3) throw std::logic_error("collocation needs exactly three rows per node");
    for (int i = 0; i < 3; ++i) {
      const Real scale = r.rows.row(i).cwiseAbs().maxCoeff();
      if (!(scale > 0) || !std::isfinite(scale))
        throw AnalysisError(fmt::format(
            "collocation: the {} row of node {} is zero or not finite (its MLS second derivatives vanish); use "
            "basis: quadratic with a larger support (kappa >= 2.5)",
            i == 0 ? "x" : i == 1 ? "y" : "z", I));
      const Index row = 3 * I + i;
      for (std::size_t k = 0; k < r.neighbours.size(); ++k)
        for (int b = 0; b < 3; ++b) {
          const Real v = r.rows(i, 3 * static_cast<Index>(k) + b);
          if (v != 0.0) entries.emplace_back(static_cast<int>(row), static_cast<int>(3 * r.neighbours[k] + b), v / scale);
        }
      rhs[row] = r.rhs[i] / scale;
    }
  }
  solve::SparseMatrix A(3 * n, 3 * n);
  A.setFromTriplets(entries.begin(), entries.end());
  try {
    return solve::solve_general(A, rhs, report);
  } catch (const AnalysisError& e) {
    throw AnalysisError(std::string(e.what()) +
                        " (collocation system: check that the essential conditions remove every rigid-body motion; a "
                        "larger support, kappa 2.5 to 3, or formulation: weighted_least_squares is more robust)");
  }
}

}  // namespace lamina::efg
