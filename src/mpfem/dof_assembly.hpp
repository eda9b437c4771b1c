#pragma once
// Assembly over the particle dofs (2 per particle, x y): local stiffness blocks into global triplets, and
// the elimination of the essential conditions (seed 001 eq 2), K_ff u_f = f_f - K_fp u_p, for the linear
// solve and every Newton iteration of the large-deformation analysis.
#include <cstddef>
#include <iterator>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "mpfem/mpfem_problem.hpp"
#include "solve/sparse_linear_solver.hpp"  // SparseMatrix

namespace lamina::mpfem {

struct FreeDofs {
  std::vector<char> prescribed;  // 1 where the dof is prescribed (2 per particle: x, y)
  Eigen::VectorXd values;        // the prescribed values (0 on the free dofs)
  std::vector<int> free_id;      // the dof's index among the free dofs, -1 where prescribed
  int count = 0;                 // number of free dofs

  bool is_free(Index dof) const { return free_id[static_cast<std::size_t>(dof)] >= 0; }
  int id(Index dof) const { return free_id[static_cast<std::size_t>(dof)]; }
};

/// Number the free dofs of `particles` particles in dof order (2 p + component).
inline FreeDofs number_free_dofs(const std::vector<PrescribedDof>& conditions, Index particles) {
  FreeDofs dofs;
  const auto size = static_cast<std::size_t>(2 * particles);
  dofs.prescribed.assign(size, 0);
  dofs.values = Eigen::VectorXd::Zero(2 * particles);
  for (const auto& d : conditions) {
    dofs.prescribed[static_cast<std::size_t>(2 * d.node + d.component)] = 1;
    dofs.values[2 * d.node + d.component] = d.value;
  }
  dofs.free_id.assign(size, -1);
  for (std::size_t i = 0; i < size; ++i)
    if (!dofs.prescribed[i]) dofs.free_id[i] = dofs.count++;
  return dofs;
}

/// Appends the entries k(2a + r, 2b + s) of a local stiffness over `nodes` (a particle index per local
/// node, negative: absent) to the global triplets, in the order a, b, r, s.
template <class Nodes, class Matrix>
inline void add_local_stiffness(const Nodes& nodes, const Matrix& k, std::vector<Eigen::Triplet<Real, int>>& triplets) {
  const auto count = static_cast<Index>(std::size(nodes));
  for (Index a = 0; a < count; ++a) {
    const Index ja = nodes[static_cast<std::size_t>(a)];
    if (ja < 0) continue;
    for (Index b = 0; b < count; ++b) {
      const Index jb = nodes[static_cast<std::size_t>(b)];
      if (jb < 0) continue;
      for (int r = 0; r < 2; ++r)
        for (int s = 0; s < 2; ++s)
          triplets.emplace_back(static_cast<int>(2 * ja + r), static_cast<int>(2 * jb + s), k(2 * a + r, 2 * b + s));
    }
  }
}

/// K_ff of a full stiffness (upper triangle, in the free numbering). With `rhs`, also subtracts K_fp u_p
/// from it, u holding the prescribed values at the prescribed dofs.
inline solve::SparseMatrix reduce_to_free_dofs(const solve::SparseMatrix& k, const FreeDofs& dofs,
                                               const Eigen::VectorXd* u = nullptr, Eigen::VectorXd* rhs = nullptr) {
  std::vector<Eigen::Triplet<Real, int>> reduced;
  reduced.reserve(static_cast<std::size_t>(k.nonZeros() / 2 + dofs.count));
  for (int col = 0; col < k.outerSize(); ++col)
    for (solve::SparseMatrix::InnerIterator it(k, col); it; ++it) {
      const int fr = dofs.id(it.row()), fc = dofs.id(col);
      if (fr >= 0 && fc >= 0) {
        if (fr <= fc) reduced.emplace_back(fr, fc, it.value());
      } else if (fr >= 0 && rhs) {
        (*rhs)[fr] -= it.value() * (*u)[col];
      }
    }
  solve::SparseMatrix result(dofs.count, dofs.count);
  result.setFromTriplets(reduced.begin(), reduced.end());
  return result;
}

}  // namespace lamina::mpfem
