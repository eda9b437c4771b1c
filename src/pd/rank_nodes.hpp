#pragma once
// RankNodes: the nodes one rank of a distributed pd run holds - the nodes it owns (Zoltan recursive
// coordinate bisection, parallel/recursive_bisection.hpp) and a halo of other ranks' nodes two
// reaches deep, all in ascending global order - and the problem restricted to them. The inner halo
// (within one reach of an owned node) gets its dilatations computed here, which needs its complete
// family: the outer halo. So a step exchanges the displacements of the halo once and computes forces
// on the owned nodes with the same bonds, in the same order, as one process does (docs/scaling.md).
#include <vector>

#include "parallel/communicator.hpp"
#include "parallel/halo_exchange.hpp"
#include "pd/peridynamic_problem.hpp"

namespace lamina::pd {

struct RankNodes {
  std::vector<Index> global;      // global index of each local node, ascending
  std::vector<NodeRole> role;     // per local node
  Index owned = 0;                // owned nodes on this rank
  Index global_count = 0;         // nodes of the whole body
  parallel::HaloExchange halo;

  /// The local index of a global node, or -1 when this rank holds no copy of it.
  Index local_of(Index global_index) const;
  bool owns(Index local) const { return role[static_cast<std::size_t>(local)] == NodeRole::owned; }
};

/// The part of `problem` (the whole body, known to every rank) this rank computes: its nodes, their
/// fields, the prescribed dofs of its nodes, the forces and initial velocities of its owned nodes.
/// Collective. The body's cell size is fixed from the whole body first, so every rank builds the same
/// bonds as one process would.
PeridynamicProblem distribute_problem(const PeridynamicProblem& problem, const parallel::Communicator& comm, RankNodes& nodes);

}  // namespace lamina::pd
