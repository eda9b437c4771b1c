// The parallel building blocks on one process (no mpirun: no MPI call), and PETSc's solvers on one
// process against a closed-form solution. The runs on 2-3 ranks are tests/mpi/run_rank_tests.py.
#include <gtest/gtest.h>

#include <vector>

#include "core/error.hpp"
#include "parallel/communicator.hpp"
#include "parallel/halo_exchange.hpp"
#include "parallel/recursive_bisection.hpp"
#include "solve/petsc_linear_solver.hpp"

namespace lamina {
namespace {

TEST(ParallelOneProcess, CommunicatorIsOneRankWithoutMpirun) {
  const auto& comm = parallel::Communicator::world();
  EXPECT_EQ(comm.rank(), 0);
  EXPECT_EQ(comm.size(), 1);
  EXPECT_FALSE(comm.distributed());
  EXPECT_DOUBLE_EQ(comm.sum(2.5), 2.5);
  EXPECT_DOUBLE_EQ(comm.max(-1.0), -1.0);
  EXPECT_EQ(comm.block_begin(10, 0), 0);
  EXPECT_EQ(comm.block_begin(10, 1), 10);
  std::vector<Real> values{1, 2, 3};
  comm.sum(values);
  EXPECT_EQ(values, (std::vector<Real>{1, 2, 3}));
  comm.all_gather_blocks(values.data(), 1, 3);  // every block is this rank's: unchanged
  EXPECT_EQ(values, (std::vector<Real>{1, 2, 3}));
  EXPECT_EQ(comm.broadcast("text"), "text");
}

TEST(ParallelOneProcess, BisectionOwnsEverythingAndHaloIsEmpty) {
  PointMatrix points = PointMatrix::Random(3, 50);
  const std::vector<int> owner = parallel::recursive_coordinate_bisection(points, parallel::Communicator::world());
  ASSERT_EQ(owner.size(), 50u);
  for (int o : owner) EXPECT_EQ(o, 0);
  std::vector<Index> global(50);
  for (Index i = 0; i < 50; ++i) global[static_cast<std::size_t>(i)] = i;
  const parallel::HaloExchange halo(global, owner, parallel::Communicator::world());
  EXPECT_EQ(halo.halo_nodes(), 0);
  EXPECT_EQ(halo.sent_nodes(), 0);
  halo.exchange(points.data(), 3);  // no-op
}

/// K = tridiag(-1, 2, -1) of size n (upper triangle), b = 1: u_i = (i + 1)(n - i) / 2.
void solve_laplacian(LinearSolverChoice::Type type, Real tolerance) {
  const Index n = 30;
  std::vector<Eigen::Triplet<Real, int>> entries;
  for (Index i = 0; i < n; ++i) {
    entries.emplace_back(static_cast<int>(i), static_cast<int>(i), 2.0);
    if (i + 1 < n) entries.emplace_back(static_cast<int>(i), static_cast<int>(i + 1), -1.0);
  }
  solve::SparseMatrix upper(n, n);
  upper.setFromTriplets(entries.begin(), entries.end());
  LinearSolverChoice choice;
  choice.type = type;
  solve::SolverReport report;
  const Eigen::VectorXd u = solve::solve_symmetric_petsc(upper, Eigen::VectorXd::Ones(n), choice,
                                                         parallel::Communicator::world(), report, solve::SystemShares::summed,
                                                         true, 1);
  for (Index i = 0; i < n; ++i) EXPECT_NEAR(u[i], 0.5 * static_cast<Real>((i + 1) * (n - i)), tolerance) << report.method;
  EXPECT_LT(report.residual, 1e-9);
}

TEST(ParallelOneProcess, PetscMumpsSolvesTheLaplacian) { solve_laplacian(LinearSolverChoice::Type::mumps, 1e-10); }

TEST(ParallelOneProcess, PetscConjugateGradientsSolveTheLaplacian) { solve_laplacian(LinearSolverChoice::Type::cg, 1e-6); }

TEST(ParallelOneProcess, PetscReportsASingularSystem) {
  // K = tridiag(-1, 2, -1) with free ends is singular (a rigid translation): refused, not a wrong answer
  const Index n = 10;
  std::vector<Eigen::Triplet<Real, int>> entries;
  for (Index i = 0; i < n; ++i) {
    entries.emplace_back(static_cast<int>(i), static_cast<int>(i), (i == 0 || i == n - 1) ? 1.0 : 2.0);
    if (i + 1 < n) entries.emplace_back(static_cast<int>(i), static_cast<int>(i + 1), -1.0);
  }
  solve::SparseMatrix upper(n, n);
  upper.setFromTriplets(entries.begin(), entries.end());
  LinearSolverChoice choice;
  choice.type = LinearSolverChoice::Type::mumps;
  solve::SolverReport report;
  EXPECT_THROW(solve::solve_symmetric_petsc(upper, Eigen::VectorXd::LinSpaced(n, -1, 1), choice,
                                            parallel::Communicator::world(), report, solve::SystemShares::summed, true, 1),
               AnalysisError);
}

}  // namespace
}  // namespace lamina
