#pragma once
// HaloExchange: the copies of other ranks' nodes a rank keeps (its halo) refreshed from their owners -
// the ghost layer of a distributed particle method. Built once from the rank's local nodes; each
// exchange sends the owned columns the neighbour ranks hold as halo and overwrites the halo columns.
#include <vector>

#include "core/types.hpp"
#include "parallel/communicator.hpp"

namespace lamina::parallel {

class HaloExchange {
 public:
  HaloExchange() = default;
  /// global: the global index of each local node, ascending; owner: the owning rank of each local node
  /// (this rank for the owned ones). Collective.
  HaloExchange(const std::vector<Index>& global, const std::vector<int>& owner, const Communicator& comm);

  /// Overwrites the halo columns of a rows x (local nodes) column-major array with the owners' values.
  /// Collective (a no-op on one rank).
  void exchange(Real* data, int rows) const;
  /// Halo nodes received / owned nodes sent per exchange (all neighbours).
  Index halo_nodes() const;
  Index sent_nodes() const;

 private:
  const Communicator* comm_ = nullptr;
  // per rank: the local columns sent to it / overwritten from it, in ascending global order
  std::vector<std::vector<Index>> send_, receive_;
};

}  // namespace lamina::parallel
