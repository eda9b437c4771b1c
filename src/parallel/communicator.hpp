#pragma once
// Communicator: the ranks of a run (MPI_COMM_WORLD when lamina was started by mpirun, else one rank
// with no MPI call at all; the MPI calls are in a module loaded only then, parallel/mpi_module.hpp) and the few collective operations the families need: sums, maxima,
// gathers and broadcasts. Reductions are plain MPI_Allreduce: their result depends on the rank count
// in the last bits only (docs/scaling.md).
#include <functional>
#include <initializer_list>
#include <utility>
#include <string>
#include <vector>

#include "core/types.hpp"

namespace lamina::parallel {

/// Starts MPI when this process was launched by mpirun / srun (OMPI_COMM_WORLD_SIZE, PMI_SIZE or
/// PMIX_RANK in the environment) and finalizes it on destruction; a process started on its own
/// never calls MPI (one rank). One per program, in main().
class Environment {
 public:
  Environment(int& argc, char**& argv);
  ~Environment();
  Environment(const Environment&) = delete;
  Environment& operator=(const Environment&) = delete;
  /// Called (last registered first) when the environment ends, before MPI_Finalize: libraries on top
  /// of MPI (PETSc) finalize there.
  static void before_finalize(std::function<void()> hook);
};

class Communicator {
 public:
  /// All ranks of the run (one rank without MPI).
  static const Communicator& world();
  /// This process alone (one rank, no MPI call): a computation every rank repeats whole (replicated).
  static const Communicator& single();

  int rank() const { return rank_; }
  int size() const { return size_; }
  bool root() const { return rank_ == 0; }
  bool distributed() const { return size_ > 1; }

  Real sum(Real value) const;
  /// Element-wise sums of equal-length vectors on every rank.
  void sum(std::vector<Real>& values) const;
  Real max(Real value) const;
  /// Element-wise maxima of equal-length vectors on every rank.
  void max(std::vector<Real>& values) const;
  Index sum(Index value) const;
  /// values of every rank, rank order, on every rank.
  std::vector<Real> all_gather(const std::vector<Real>& values) const;
  std::vector<int> all_gather(int value) const;
  /// The concatenation of every rank's list, rank order, on every rank.
  std::vector<Index> all_gather_lists(const std::vector<Index>& values) const;
  /// The block of items [count r / size, count (r + 1) / size) that rank r computes.
  Index block_begin(Index count, int rank) const { return count * rank / size_; }
  /// A rows x count column-major array of which each rank filled its block of columns (block_begin):
  /// afterwards every rank holds all columns. Collective.
  void all_gather_blocks(Real* data, int rows, Index count) const;
  /// The same with given blocks: rank r filled columns [begins[r], begins[r + 1]) (begins: size() + 1).
  void all_gather_blocks(Real* data, int rows, const std::vector<Index>& begins) const;
  /// Point-to-point refresh of copies: sends to each rank q the columns send[q] of every (data, rows)
  /// array (column-major, rows x nodes) and overwrites the columns receive[q] with q's. The lists (one
  /// per rank, ascending) must pair up: receive[q] here is send[this rank] on q. Collective among the
  /// ranks with non-empty lists.
  void exchange_columns(std::initializer_list<std::pair<Real*, int>> arrays, const std::vector<std::vector<Index>>& send,
                        const std::vector<std::vector<Index>>& receive) const;
  /// Entry q of every rank's `values` (one per rank) goes to rank q: entry r of the result is rank r's
  /// entry for this rank (MPI_Alltoall). Collective.
  std::vector<int> all_to_all(const std::vector<int>& values) const;
  /// Personalised exchange of lists: `values` holds this rank's lists for ranks 0, 1, ... one after the
  /// other (send_counts[q] entries for rank q); the result holds the lists received from ranks 0, 1, ...
  /// (receive_counts[r] from rank r, as all_to_all of send_counts gives). Collective.
  std::vector<Index> all_to_all_lists(const std::vector<Index>& values, const std::vector<int>& send_counts,
                                      const std::vector<int>& receive_counts) const;
  /// Rank 0's value on every rank.
  std::string broadcast(const std::string& value) const;
  void barrier() const;

 private:
  explicit Communicator(bool join_world);
  int rank_ = 0, size_ = 1;
};

}  // namespace lamina::parallel
