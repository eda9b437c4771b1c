#pragma once
// Stiffness changes along a quasi-static load path P(Delta) (seed 002 section 4.2: first buckling,
// secondary bifurcation and snap show as drops of the axial stiffness dP/dDelta).
//
// Tangent stiffness of increment n: k_n = (P_n - P_(n-1)) / (Delta_n - Delta_(n-1)); relative drop rate
// per unit load q_n = ln(k_(n-1) / k_n) / (Pbar_n - Pbar_(n-1)) (Pbar: mid-increment load). An event
// is a local maximum of q, at least twice the slowest rate since the previous event, whose stiffness
// falls by at least min_drop across it; its extent runs to
// the increments where q is back below half the peak on either side (after the peak: or where q
// starts to rise again), and its load is the
// intersection of the two tangents there (the usual two-tangent reading of an imperfect
// structure's knee; a snap under load control gives one increment of near-zero stiffness). The
// stiffness after the event is read where the drop has settled (q below a tenth of the peak, or
// rising again; past the recovery that follows a snap).
#include <vector>

#include "core/types.hpp"

namespace lamina::pd {

struct StiffnessChange {
  Real load = 0;             // two-tangent intersection load
  Real displacement = 0;     // and its generalized displacement
  Real stiffness_ratio = 0;  // settled tangent stiffness after the event / initial tangent stiffness
  Real peak_load = 0;        // mid-increment load of the steepest drop
};

/// load[0] = displacement[0] = 0 is the unloaded state; one entry per converged increment after it.
std::vector<StiffnessChange> detect_stiffness_changes(const std::vector<Real>& load, const std::vector<Real>& displacement,
                                                      Real min_drop = 0.15);

}  // namespace lamina::pd
