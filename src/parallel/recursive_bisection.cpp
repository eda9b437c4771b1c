#include "parallel/recursive_bisection.hpp"

#include <stdexcept>

#include "parallel/mpi_module.hpp"

namespace lamina::parallel {

std::vector<int> recursive_coordinate_bisection(const PointMatrix& points, const Communicator& comm) {
  const Index n = points.cols();
  if (!comm.distributed()) return std::vector<int>(static_cast<std::size_t>(n), 0);
  const int ranks = comm.size(), rank = comm.rank();
  const Index first = n * rank / ranks, last = n * (rank + 1) / ranks;
  std::vector<int> parts(static_cast<std::size_t>(last - first));
  char error[256] = {};
  if (mpi_module().bisect(points.data(), first, last, parts.data(), error, static_cast<int>(sizeof error)) != 0)
    throw std::runtime_error(error);
  // this rank's block, then every rank's blocks in rank order
  const std::vector<Index> all = comm.all_gather_lists(std::vector<Index>(parts.begin(), parts.end()));
  return std::vector<int>(all.begin(), all.end());
}

}  // namespace lamina::parallel
