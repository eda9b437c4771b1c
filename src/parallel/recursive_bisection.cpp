#include "parallel/recursive_bisection.hpp"

#include <mpi.h>
#include <zoltan.h>

#include <stdexcept>

namespace lamina::parallel {

namespace {

/// The block of points a rank hands to Zoltan (its initial part): [first, last).
struct Block {
  const PointMatrix* points;
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
    for (int d = 0; d < 3; ++d) xyz[3 * k + d] = (*b->points)(d, static_cast<Index>(global[k]));
  *error = ZOLTAN_OK;
}

}  // namespace

std::vector<int> recursive_coordinate_bisection(const PointMatrix& points, const Communicator& comm) {
  const Index n = points.cols();
  if (!comm.distributed()) return std::vector<int>(static_cast<std::size_t>(n), 0);
  static bool initialised = false;
  if (!initialised) {
    float version = 0;
    if (Zoltan_Initialize(0, nullptr, &version) != ZOLTAN_OK) throw std::runtime_error("Zoltan_Initialize failed");
    initialised = true;
  }
  const int ranks = comm.size(), rank = comm.rank();
  Block block{&points, n * rank / ranks, n * (rank + 1) / ranks};
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
    throw std::runtime_error("Zoltan RCB partitioning failed");
  }
  // my block's owners (those not exported stay here), then every rank's blocks in rank order
  std::vector<Index> owners(static_cast<std::size_t>(block.last - block.first), rank);
  for (int k = 0; k < exports; ++k) owners[static_cast<std::size_t>(export_global[k] - static_cast<ZOLTAN_ID_TYPE>(block.first))] = export_part[k];
  Zoltan_LB_Free_Part(&import_global, &import_local, &import_rank, &import_part);
  Zoltan_LB_Free_Part(&export_global, &export_local, &export_rank, &export_part);
  Zoltan_Destroy(&zz);
  const std::vector<Index> all = comm.all_gather_lists(owners);
  return std::vector<int>(all.begin(), all.end());
}

}  // namespace lamina::parallel
