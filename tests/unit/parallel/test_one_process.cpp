// The parallel building blocks on one process (no mpirun: no MPI call), and PETSc's and SLEPc's solvers
// (the module src/petsc_solvers, loaded at the first call) on one process against closed-form solutions.
// The runs on 2-3 ranks are tests/mpi/run_rank_tests.py.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "parallel/communicator.hpp"
#include "parallel/halo_exchange.hpp"
#include "parallel/recursive_bisection.hpp"
#include "solve/petsc_linear_solver.hpp"
#include "solve/slepc_eigen_solver.hpp"

namespace lamina {
namespace {

/// True if the environment this process was started with (/proc/self/environ) defines `name`.
bool started_with(const std::string& name) {
  std::ifstream file("/proc/self/environ", std::ios::binary);
  const std::string block((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  return ("\0" + block).find("\0" + name + "=") != std::string::npos;
}

// src/openmp_defaults: idle OpenMP threads spin 10,000 times unless the user's environment says how long.
TEST(OpenMpDefaults, IdleThreadsSpinBrieflyUnlessTheEnvironmentSaysOtherwise) {
  if (started_with("OMP_WAIT_POLICY") || started_with("GOMP_SPINCOUNT")) GTEST_SKIP() << "set by the environment";
  const char* spin = std::getenv("GOMP_SPINCOUNT");
  ASSERT_NE(spin, nullptr);
  EXPECT_STREQ(spin, "10000");
}

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

TEST(ParallelOneProcess, PetscMumpsLuSolvesAnUnsymmetricSystem) {
  // A = tridiag(-1, 3, -0.5) stored whole, b = A x for a known x
  const Index n = 20;
  std::vector<Eigen::Triplet<Real, int>> entries;
  for (Index i = 0; i < n; ++i) {
    entries.emplace_back(static_cast<int>(i), static_cast<int>(i), 3.0);
    if (i + 1 < n) entries.emplace_back(static_cast<int>(i), static_cast<int>(i + 1), -0.5);
    if (i > 0) entries.emplace_back(static_cast<int>(i), static_cast<int>(i - 1), -1.0);
  }
  solve::SparseMatrix a(n, n);
  a.setFromTriplets(entries.begin(), entries.end());
  const Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(n, 1, 2);
  LinearSolverChoice choice;
  choice.type = LinearSolverChoice::Type::mumps;
  solve::SolverReport report;
  const Eigen::VectorXd u = solve::solve_general_petsc(a, a * x, choice, parallel::Communicator::world(), report,
                                                       solve::SystemShares::summed, 1);
  EXPECT_EQ(report.method, "petsc_mumps_lu");
  EXPECT_LT((u - x).norm(), 1e-12 * x.norm());
}

TEST(ParallelOneProcess, SlepcFindsTheLargestEigenvaluesOfADiagonalPencil) {
  // A = diag(1 .. n), B = 2 I: mu_i = i / 2, the eigenvectors unit vectors scaled to x^T B x = 1
  const Index n = 50;
  std::vector<Eigen::Triplet<Real, int>> a_entries, b_entries;
  for (Index i = 0; i < n; ++i) {
    a_entries.emplace_back(static_cast<int>(i), static_cast<int>(i), static_cast<Real>(i + 1));
    b_entries.emplace_back(static_cast<int>(i), static_cast<int>(i), 2.0);
  }
  solve::SparseMatrix a(n, n), b(n, n);
  a.setFromTriplets(a_entries.begin(), a_entries.end());
  b.setFromTriplets(b_entries.begin(), b_entries.end());
  const solve::EigenPairs pairs = solve::largest_generalized_eigenpairs(a, b, 3, parallel::Communicator::world());
  ASSERT_EQ(pairs.values.size(), 3);
  for (Index k = 0; k < 3; ++k) {
    EXPECT_NEAR(pairs.values[k], 0.5 * static_cast<Real>(n - k), 1e-8);
    EXPECT_NEAR(std::abs(pairs.vectors(n - 1 - k, k)), std::sqrt(0.5), 1e-8);
  }
}

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
  // thrown inside the module, caught here as lamina::AnalysisError (type_info compared by name)
  try {
    solve::solve_symmetric_petsc(upper, Eigen::VectorXd::LinSpaced(n, -1, 1), choice, parallel::Communicator::world(), report,
                                 solve::SystemShares::summed, true, 1);
    ADD_FAILURE() << "no AnalysisError";
  } catch (const AnalysisError& e) {
    EXPECT_NE(std::string(e.what()).find("PETSc"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace lamina
