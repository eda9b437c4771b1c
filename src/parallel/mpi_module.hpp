#pragma once
// The interface of the MPI module (src/mpi_transport, liblamina_mpi_transport.so): the MPI and Zoltan calls
// of a distributed run, behind a table of plain functions. Only a process started by mpirun loads it
// (Environment), so a one-process run loads neither OpenMPI nor Zoltan (about 5.5 ms of start-up here).
#include "core/types.hpp"

namespace lamina::parallel {

/// Element types on the wire: Real (MPI_DOUBLE), int (MPI_INT), Index (MPI_INT64_T or MPI_INT32_T), char.
enum class WireType : int { real, int32, index, character };
enum class Reduction : int { sum, max };

/// Functions of MPI_COMM_WORLD; counts and offsets in elements, as MPI's.
struct MpiModule {
  static constexpr int abi_version = 1;
  int abi;
  /// MPI_Init_thread (MPI_THREAD_FUNNELED); 0 on success.
  int (*start)(int* argc, char*** argv);
  /// MPI_Finalize unless already finalized.
  void (*finish)();
  int (*rank)();
  int (*size)();
  /// MPI_Allreduce in place.
  void (*all_reduce)(void* data, int count, WireType type, Reduction op);
  void (*all_gather)(const void* send, int count, WireType type, void* receive);
  /// MPI_Allgatherv; send == nullptr: in place (this rank's block already in `receive`).
  void (*all_gather_v)(const void* send, int count, WireType type, void* receive, const int* counts, const int* offsets);
  void (*all_to_all_v)(const void* send, const int* send_counts, const int* send_offsets, void* receive,
                       const int* receive_counts, const int* receive_offsets, WireType type);
  /// Non-blocking receives from and sends to the listed ranks (Real buffers), then waits for all.
  void (*exchange)(int receives, Real* const* receive_buffers, const int* receive_counts, const int* receive_ranks, int sends,
                   const Real* const* send_buffers, const int* send_counts, const int* send_ranks, int tag);
  void (*broadcast)(void* data, int count, WireType type, int root);
  void (*barrier)();
  /// Zoltan recursive coordinate bisection, one part per rank: this rank hands in the columns [first, last)
  /// of `points` (3 x N, column-major, the same on every rank) and gets their parts in `parts`
  /// (last - first entries). 0 on success, else a message in `error` (at most error_size characters).
  int (*bisect)(const Real* points, Index first, Index last, int* parts, char* error, int error_size);
};

/// The loaded module (Environment loads it in a process started by mpirun); throws SolverUnavailable
/// with the reason if it cannot be loaded.
const MpiModule& mpi_module();

}  // namespace lamina::parallel
