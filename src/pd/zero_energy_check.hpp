#pragma once
// Zero-energy modes of the unloaded stiffness on the free degrees of freedom (issue 15): the
// smallest eigenvalue of the density-scaled stiffness S K0 S (S = lambda^-1/2, the ADR fictitious
// density, so the largest is at most 4) by inverse iteration with CHOLMOD; a value below
// `threshold` (or a failed factorisation) is a zero-energy mode, classified as a rigid-body motion
// (the mode is within 1e-3 of a rigid motion of the nodes) or a spurious mode of the discretisation.
#include "core/types.hpp"
#include "solve/sparse_linear_solver.hpp"

namespace lamina::pd {

struct ZeroEnergyReport {
  bool singular = false;        // a zero-energy mode exists
  bool rigid = false;           // ... and it is a rigid-body motion
  Real smallest = 0;            // smallest scaled eigenvalue (estimate; 0 when the factorisation failed)
  Index node = -1;              // the node where the mode is largest
  int iterations = 0;
};

/// reduced_upper: K0 on the free dofs (upper triangle); dofs: the global dof (3 node + component) of
/// each free dof; positions: the nodes (3 x N).
ZeroEnergyReport find_zero_energy_modes(const solve::SparseMatrix& reduced_upper, const std::vector<Index>& dofs,
                                        const PointMatrix& positions, Real threshold = 1e-11);

}  // namespace lamina::pd
