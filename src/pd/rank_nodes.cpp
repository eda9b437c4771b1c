#include "pd/rank_nodes.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "parallel/recursive_bisection.hpp"

namespace lamina::pd {

Index RankNodes::local_of(Index g) const {
  const auto it = std::lower_bound(global.begin(), global.end(), g);
  return it != global.end() && *it == g ? static_cast<Index>(it - global.begin()) : -1;
}

namespace {

/// Role of every node of the body on this rank: owned, inner halo (within `reach` of an owned node),
/// outer halo (within 2 reach), or absent (-1). Bins of size 2 reach; a node far from every owned
/// node's bin is skipped at once.
std::vector<int> node_roles(const PointMatrix& x, const std::vector<int>& owner, int rank, Real reach, bool planar) {
  const Index n = x.cols();
  const int dim = planar ? 2 : 3;
  const Real size = 2 * reach;
  const Vec3 lower = x.rowwise().minCoeff(), upper = x.rowwise().maxCoeff();
  std::array<Index, 3> bins{1, 1, 1};
  for (int d = 0; d < dim; ++d) bins[static_cast<std::size_t>(d)] = std::max<Index>(1, static_cast<Index>((upper[d] - lower[d]) / size) + 1);
  auto bin_of = [&](Index i, int d) {
    return std::clamp<Index>(static_cast<Index>((x(d, i) - lower[d]) / size), 0, bins[static_cast<std::size_t>(d)] - 1);
  };
  auto bin_index = [&](Index bx, Index by, Index bz) { return bx + bins[0] * (by + bins[1] * bz); };
  const Index bin_count = bins[0] * bins[1] * bins[2];
  // the owned nodes of each bin (CSR)
  std::vector<Index> start(static_cast<std::size_t>(bin_count) + 1, 0), members;
  for (Index i = 0; i < n; ++i)
    if (owner[static_cast<std::size_t>(i)] == rank)
      ++start[static_cast<std::size_t>(bin_index(bin_of(i, 0), bin_of(i, 1), dim == 3 ? bin_of(i, 2) : 0)) + 1];
  for (Index b = 0; b < bin_count; ++b) start[static_cast<std::size_t>(b) + 1] += start[static_cast<std::size_t>(b)];
  members.resize(static_cast<std::size_t>(start.back()));
  {
    std::vector<Index> fill(start.begin(), start.end() - 1);
    for (Index i = 0; i < n; ++i)
      if (owner[static_cast<std::size_t>(i)] == rank)
        members[static_cast<std::size_t>(fill[static_cast<std::size_t>(bin_index(bin_of(i, 0), bin_of(i, 1), dim == 3 ? bin_of(i, 2) : 0))]++)] = i;
  }
  const Real inner = reach * reach, outer = 4 * reach * reach;
  std::vector<int> role(static_cast<std::size_t>(n), -1);
#pragma omp parallel for schedule(dynamic, 256)
  for (Index i = 0; i < n; ++i) {
    if (owner[static_cast<std::size_t>(i)] == rank) {
      role[static_cast<std::size_t>(i)] = static_cast<int>(NodeRole::owned);
      continue;
    }
    const Index bx = bin_of(i, 0), by = bin_of(i, 1), bz = dim == 3 ? bin_of(i, 2) : 0;
    Real nearest = INFINITY;
    for (Index z = std::max<Index>(bz - 1, 0); z <= std::min(bz + 1, bins[2] - 1) && nearest > inner; ++z)
      for (Index y = std::max<Index>(by - 1, 0); y <= std::min(by + 1, bins[1] - 1) && nearest > inner; ++y)
        for (Index xb = std::max<Index>(bx - 1, 0); xb <= std::min(bx + 1, bins[0] - 1) && nearest > inner; ++xb) {
          const Index b = bin_index(xb, y, z);
          for (Index k = start[static_cast<std::size_t>(b)]; k < start[static_cast<std::size_t>(b) + 1]; ++k) {
            Vec3 d = x.col(members[static_cast<std::size_t>(k)]) - x.col(i);
            if (planar) d.z() = 0;
            nearest = std::min(nearest, d.squaredNorm());
            if (nearest <= inner) break;
          }
        }
    if (nearest <= inner) role[static_cast<std::size_t>(i)] = static_cast<int>(NodeRole::inner_halo);
    else if (nearest <= outer) role[static_cast<std::size_t>(i)] = static_cast<int>(NodeRole::outer_halo);
  }
  return role;
}

template <class Vector>
Vector restrict_entries(const Vector& v, const std::vector<Index>& global) {
  Vector out(static_cast<Index>(global.size()));
  for (std::size_t k = 0; k < global.size(); ++k) out[static_cast<Index>(k)] = v[global[k]];
  return out;
}

PointMatrix restrict_columns(const PointMatrix& m, const std::vector<Index>& global) {
  if (m.cols() == 0) return m;
  PointMatrix out(m.rows(), static_cast<Index>(global.size()));
  for (std::size_t k = 0; k < global.size(); ++k) out.col(static_cast<Index>(k)) = m.col(global[k]);
  return out;
}

}  // namespace

PeridynamicProblem distribute_problem(const PeridynamicProblem& problem, const parallel::Communicator& comm, RankNodes& nodes) {
  const Index n = problem.positions.cols();
  PeridynamicProblem local = problem;
  BodyOptions& o = local.body;
  const bool planar = o.kinematics != Kinematics::three_dimensional;
  if (o.cell_size <= 0) {  // as PeridynamicBody sets it, from the whole body
    const Real v = n ? problem.volumes.mean() : 1.0;
    o.cell_size = planar ? std::sqrt(v) : std::cbrt(v);
  }
  const Real reach = (o.partial_volume ? o.horizon + 0.5 * o.cell_size : o.horizon) * (1.0 + 1e-9);
  const std::vector<int> owner = parallel::recursive_coordinate_bisection(problem.positions, comm);
  const std::vector<int> role = node_roles(problem.positions, owner, comm.rank(), reach, planar);
  nodes = RankNodes{};
  nodes.global_count = n;
  std::vector<int> local_owner;
  for (Index i = 0; i < n; ++i) {
    const int r = role[static_cast<std::size_t>(i)];
    if (r < 0) continue;
    nodes.global.push_back(i);
    nodes.role.push_back(static_cast<NodeRole>(r));
    local_owner.push_back(owner[static_cast<std::size_t>(i)]);
    if (r == static_cast<int>(NodeRole::owned)) ++nodes.owned;
  }
  nodes.halo = parallel::HaloExchange(nodes.global, local_owner, comm);

  local.positions = restrict_columns(problem.positions, nodes.global);
  local.volumes = restrict_entries(problem.volumes, nodes.global);
  local.young = restrict_entries(problem.young, nodes.global);
  local.poisson = restrict_entries(problem.poisson, nodes.global);
  local.density = restrict_entries(problem.density, nodes.global);
  local.initial_velocity = restrict_columns(problem.initial_velocity, nodes.global);
  if (local.imperfection.shape.cols() == n) local.imperfection.shape = restrict_columns(problem.imperfection.shape, nodes.global);
  local.prescribed.clear();
  for (PrescribedDof p : problem.prescribed) {
    const Index k = nodes.local_of(p.node);
    if (k < 0) continue;
    p.node = k;
    local.prescribed.push_back(p);
  }
  local.forces.clear();
  for (NodalForce f : problem.forces) {
    const Index k = nodes.local_of(f.node);
    if (k < 0 || !nodes.owns(k)) continue;
    f.node = k;
    local.forces.push_back(f);
  }
  return local;
}

}  // namespace lamina::pd
