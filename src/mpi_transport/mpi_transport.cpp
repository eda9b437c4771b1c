// The MPI module (parallel/mpi_module.hpp): MPI_COMM_WORLD collectives and Zoltan RCB for a process
// started by mpirun. Loaded with dlopen by parallel::Environment; a one-process run never opens it.
#include <dlfcn.h>
#include <mpi.h>
#include <zoltan.h>

#include <algorithm>
#include <cstdio>
#include <vector>

#include "parallel/mpi_module.hpp"

namespace lamina::parallel {

namespace {

MPI_Datatype mpi_type(WireType type) {
  switch (type) {
    case WireType::real: return MPI_DOUBLE;
    case WireType::int32: return MPI_INT;
    case WireType::index: return sizeof(Index) == 8 ? MPI_INT64_T : MPI_INT32_T;
    case WireType::character: return MPI_CHAR;
  }
  return MPI_DATATYPE_NULL;
}

int start(int* argc, char*** argv) {
  // OpenMPI opens its components with dlopen and resolves them against libmpi's symbols: make those global
  // (this module, and so libmpi, was opened RTLD_LOCAL).
  Dl_info info{};
  if (dladdr(reinterpret_cast<void*>(&MPI_Init_thread), &info) != 0 && info.dli_fname != nullptr)
    dlopen(info.dli_fname, RTLD_NOW | RTLD_GLOBAL | RTLD_NOLOAD);
  int provided = 0;
  return MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided) == MPI_SUCCESS ? 0 : 1;
}

void finish() {
  int finalized = 0;
  MPI_Finalized(&finalized);
  if (!finalized) MPI_Finalize();
}

int rank() {
  int r = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}

int size() {
  int s = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &s);
  return s;
}

void all_reduce(void* data, int count, WireType type, Reduction op) {
  MPI_Allreduce(MPI_IN_PLACE, data, count, mpi_type(type), op == Reduction::sum ? MPI_SUM : MPI_MAX, MPI_COMM_WORLD);
}

void all_gather(const void* send, int count, WireType type, void* receive) {
  MPI_Allgather(send, count, mpi_type(type), receive, count, mpi_type(type), MPI_COMM_WORLD);
}

void all_gather_v(const void* send, int count, WireType type, void* receive, const int* counts, const int* offsets) {
  if (send == nullptr)
    MPI_Allgatherv(MPI_IN_PLACE, 0, MPI_DATATYPE_NULL, receive, counts, offsets, mpi_type(type), MPI_COMM_WORLD);
  else
    MPI_Allgatherv(send, count, mpi_type(type), receive, counts, offsets, mpi_type(type), MPI_COMM_WORLD);
}

void all_to_all_v(const void* send, const int* send_counts, const int* send_offsets, void* receive, const int* receive_counts,
                  const int* receive_offsets, WireType type) {
  MPI_Alltoallv(send, send_counts, send_offsets, mpi_type(type), receive, receive_counts, receive_offsets, mpi_type(type),
                MPI_COMM_WORLD);
}

void exchange(int receives, Real* const* receive_buffers, const int* receive_counts, const int* receive_ranks, int sends,
              const Real* const* send_buffers, const int* send_counts, const int* send_ranks, int tag) {
  std::vector<MPI_Request> requests(static_cast<std::size_t>(receives + sends));
  for (int k = 0; k < receives; ++k)
    MPI_Irecv(receive_buffers[k], receive_counts[k], MPI_DOUBLE, receive_ranks[k], tag, MPI_COMM_WORLD,
              &requests[static_cast<std::size_t>(k)]);
  for (int k = 0; k < sends; ++k)
    MPI_Isend(send_buffers[k], send_counts[k], MPI_DOUBLE, send_ranks[k], tag, MPI_COMM_WORLD,
              &requests[static_cast<std::size_t>(receives + k)]);
  MPI_Waitall(static_cast<int>(requests.size()), requests.data(), MPI_STATUSES_IGNORE);
}

void broadcast(void* data, int count, WireType type, int root) { MPI_Bcast(data, count, mpi_type(type), root, MPI_COMM_WORLD); }

void barrier() { MPI_Barrier(MPI_COMM_WORLD); }

// ---------------------------------------------------------------------------------------- Zoltan RCB
/// The block of points a rank hands to Zoltan (its initial part): columns [first, last).
struct Block {
  const Real* points;
  Index first, last;
};

int object_count(void* data, int* error) {
  const auto* b = static_cast<const Block*>(data);
  *error = ZOLTAN_OK;
  return static_cast<int>(b->last - b->first);
}

void object_list(void* data, int /*gid_size*/, int /*lid_size*/, ZOLTAN_ID_PTR global, ZOLTAN_ID_PTR local, int /*weights*/,
                 float* /*weight*/, int* error) {
  const auto* b = static_cast<const Block*>(data);
  for (Index k = 0; k < b->last - b->first; ++k) {
    global[k] = static_cast<ZOLTAN_ID_TYPE>(b->first + k);
    local[k] = static_cast<ZOLTAN_ID_TYPE>(k);
  }
  *error = ZOLTAN_OK;
}

int dimension(void*, int* error) {
  *error = ZOLTAN_OK;
  return 3;
}

void coordinates(void* data, int /*gid_size*/, int /*lid_size*/, int count, ZOLTAN_ID_PTR global, ZOLTAN_ID_PTR /*local*/,
                 int /*dim*/, double* xyz, int* error) {
  const auto* b = static_cast<const Block*>(data);
  for (int k = 0; k < count; ++k)
    for (int d = 0; d < 3; ++d) xyz[3 * k + d] = b->points[3 * static_cast<Index>(global[k]) + d];
  *error = ZOLTAN_OK;
}

int bisect(const Real* points, Index first, Index last, int* parts, char* error, int error_size) {
  static bool initialised = false;
  if (!initialised) {
    float version = 0;
    if (Zoltan_Initialize(0, nullptr, &version) != ZOLTAN_OK) {
      std::snprintf(error, static_cast<std::size_t>(error_size), "Zoltan_Initialize failed");
      return 1;
    }
    initialised = true;
  }
  const int me = rank();
  Block block{points, first, last};
  Zoltan_Struct* zz = Zoltan_Create(MPI_COMM_WORLD);
  Zoltan_Set_Param(zz, "DEBUG_LEVEL", "0");
  Zoltan_Set_Param(zz, "LB_METHOD", "RCB");
  Zoltan_Set_Param(zz, "NUM_GID_ENTRIES", "1");
  Zoltan_Set_Param(zz, "NUM_LID_ENTRIES", "1");
  Zoltan_Set_Param(zz, "OBJ_WEIGHT_DIM", "0");
  Zoltan_Set_Param(zz, "RETURN_LISTS", "EXPORT");
  Zoltan_Set_Param(zz, "RCB_RECOMPUTE_BOX", "1");
  Zoltan_Set_Num_Obj_Fn(zz, object_count, &block);
  Zoltan_Set_Obj_List_Fn(zz, object_list, &block);
  Zoltan_Set_Num_Geom_Fn(zz, dimension, &block);
  Zoltan_Set_Geom_Multi_Fn(zz, coordinates, &block);
  int changes = 0, gid_size = 0, lid_size = 0, imports = 0, exports = 0;
  ZOLTAN_ID_PTR import_global = nullptr, import_local = nullptr, export_global = nullptr, export_local = nullptr;
  int *import_rank = nullptr, *import_part = nullptr, *export_rank = nullptr, *export_part = nullptr;
  const int status = Zoltan_LB_Partition(zz, &changes, &gid_size, &lid_size, &imports, &import_global, &import_local,
                                         &import_rank, &import_part, &exports, &export_global, &export_local, &export_rank,
                                         &export_part);
  if (status != ZOLTAN_OK) {
    Zoltan_Destroy(&zz);
    std::snprintf(error, static_cast<std::size_t>(error_size), "Zoltan RCB partitioning failed");
    return 1;
  }
  // the points of this block stay here unless exported
  std::fill(parts, parts + (last - first), me);
  for (int k = 0; k < exports; ++k) parts[static_cast<Index>(export_global[k]) - first] = export_part[k];
  Zoltan_LB_Free_Part(&import_global, &import_local, &import_rank, &import_part);
  Zoltan_LB_Free_Part(&export_global, &export_local, &export_rank, &export_part);
  Zoltan_Destroy(&zz);
  return 0;
}

}  // namespace

}  // namespace lamina::parallel

extern "C" __attribute__((visibility("default"))) const lamina::parallel::MpiModule* lamina_mpi_transport() {
  using namespace lamina::parallel;
  static const MpiModule table{MpiModule::abi_version, &start, &finish, &rank, &size, &all_reduce, &all_gather,
                               &all_gather_v, &all_to_all_v, &exchange, &broadcast, &barrier, &bisect};
  return &table;
}
