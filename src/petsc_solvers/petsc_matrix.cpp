#include "petsc_solvers/petsc_matrix.hpp"

#include <fmt/format.h>

#include <vector>

#include "core/error.hpp"
#include "petsc_solvers/petsc_solvers.hpp"

namespace lamina::solve::petsc {

namespace {
bool initialised_here = false;  // PetscInitialize called by ensure_started (finalize ends only that)
}  // namespace

void ensure_started() {  // PETSc starts a one-process MPI itself when lamina made none
  static bool started = false;
  if (started) return;
  PetscBool initialised = PETSC_FALSE;
  PetscInitialized(&initialised);
  if (!initialised) {
    PetscOptionsSetValue(nullptr, "-options_left", "false");
    if (PetscInitializeNoArguments() != 0) throw AnalysisError("PETSc could not be initialised");
    initialised_here = true;
  }
  started = true;
}

// Not parallel::Environment::before_finalize here: the module has its own copy of that static state,
// never run; the loader (solve/petsc_module.cpp) registers finalize with the program's Environment.
void finalize() {
  if (!initialised_here) return;
  PetscBool finalized = PETSC_FALSE;
  PetscFinalized(&finalized);
  if (!finalized) PetscFinalize();
}

void check(PetscErrorCode code, const char* what) {
  if (code != 0) throw AnalysisError(fmt::format("PETSc: {} failed (error {})", what, static_cast<int>(code)));
}

RowBlock row_block(PetscInt n, int dofs_per_node, const parallel::Communicator& comm) {
  RowBlock r;
  const int ranks = comm.size(), rank = comm.rank();
  r.block = n % dofs_per_node == 0 ? dofs_per_node : 1;
  const PetscInt nodes = n / r.block;
  r.first = r.block * (nodes * rank / ranks);
  r.last = r.block * (nodes * (rank + 1) / ranks);
  return r;
}

Mat assemble_matrix(const SparseMatrix& upper, bool mirror, SystemShares shares, const RowBlock& rows) {
  const PetscInt n = static_cast<PetscInt>(upper.rows()), block = rows.block, first = rows.first, last = rows.last;
  // a replicated system: this rank passes the entries of its rows only
  auto passes = [&](Index row) { return shares == SystemShares::summed || (row >= first && row < last); };
  // preallocation of the rows this rank owns from the pattern it holds: exact when every rank holds
  // the same pattern (one block pattern with summed shares, or a replicated system); more entries from
  // other ranks are still accepted (MAT_NEW_NONZERO_ALLOCATION_ERR off)
  Mat a;
  check(MatCreate(PETSC_COMM_WORLD, &a), "MatCreate");
  check(MatSetSizes(a, last - first, last - first, n, n), "MatSetSizes");
  check(MatSetType(a, MATAIJ), "MatSetType");
  check(MatSetBlockSize(a, block), "MatSetBlockSize");
  {
    std::vector<PetscInt> diagonal(static_cast<std::size_t>(last - first), 0), off(static_cast<std::size_t>(last - first), 0);
    for (Index col = 0; col < upper.outerSize(); ++col)
      for (SparseMatrix::InnerIterator it(upper, col); it; ++it) {
        const Index r = it.row();
        auto count = [&](Index row, Index c) {
          if (row < first || row >= last) return;
          auto& bucket = (c >= first && c < last) ? diagonal : off;
          ++bucket[static_cast<std::size_t>(row - first)];
        };
        count(r, col);
        if (mirror && r != col) count(col, r);
      }
    // every rank's shares have the same pattern when they come from one block pattern (efg, mpfem): the
    // local count is the row's count
    check(MatMPIAIJSetPreallocation(a, 0, diagonal.data(), 0, off.data()), "MatMPIAIJSetPreallocation");
    check(MatSeqAIJSetPreallocation(a, 0, diagonal.data()), "MatSeqAIJSetPreallocation");
    check(MatSetOption(a, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_FALSE), "MatSetOption");
  }
  for (Index col = 0; col < upper.outerSize(); ++col)
    for (SparseMatrix::InnerIterator it(upper, col); it; ++it) {
      const PetscInt r = static_cast<PetscInt>(it.row()), c = static_cast<PetscInt>(col);
      const PetscScalar v = it.value();
      if (v == 0.0 || !passes(r)) continue;
      check(MatSetValues(a, 1, &r, 1, &c, &v, ADD_VALUES), "MatSetValues");
      if (mirror && r != c) check(MatSetValues(a, 1, &c, 1, &r, &v, ADD_VALUES), "MatSetValues");
    }
  check(MatAssemblyBegin(a, MAT_FINAL_ASSEMBLY), "MatAssemblyBegin");
  check(MatAssemblyEnd(a, MAT_FINAL_ASSEMBLY), "MatAssemblyEnd");
  check(MatSetOption(a, MAT_SYMMETRIC, mirror ? PETSC_TRUE : PETSC_FALSE), "MatSetOption");
  return a;
}

}  // namespace lamina::solve::petsc
