#pragma once
// Recursive coordinate bisection of a point set over the ranks (Zoltan's RCB, Berger-Bokhari): the
// partition of the particles / nodes of a distributed run. The points are known to every rank.
#include <vector>

#include "core/types.hpp"
#include "parallel/communicator.hpp"

namespace lamina::parallel {

/// The owning rank of each column of `points` (3 x N, identical on every rank), the same list on every
/// rank: Zoltan RCB with one part per rank, each part holding N / ranks points (+- 1). One rank: all 0.
std::vector<int> recursive_coordinate_bisection(const PointMatrix& points, const Communicator& comm);

}  // namespace lamina::parallel
