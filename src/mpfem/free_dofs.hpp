#pragma once
// The particle dofs left free by the essential conditions (seed 001 eq 2): which dofs are prescribed,
// their values and the numbering of the free ones, for the eliminated K_ff u_f = f_f - K_fp u_p of the
// linear solve and of every Newton iteration of the large-deformation analysis.
#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "mpfem/mpfem_problem.hpp"

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
    dofs.prescribed[static_cast<std::size_t>(2 * d.particle + d.component)] = 1;
    dofs.values[2 * d.particle + d.component] = d.value;
  }
  dofs.free_id.assign(size, -1);
  for (std::size_t i = 0; i < size; ++i)
    if (!dofs.prescribed[i]) dofs.free_id[i] = dofs.count++;
  return dofs;
}

}  // namespace lamina::mpfem
