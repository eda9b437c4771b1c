#pragma once
// Mass scaling of a quasi-static MPM shell run: fictitious, stiffness-proportional node masses and
// rotational inertias from the Gershgorin row sums of the element tangents (seed 002 eq (5), dt = 1).
#include <vector>

#include "core/shell_mesh.hpp"
#include "core/types.hpp"
#include "shell/belytschko_tsay_shell.hpp"

namespace lamina::mpm {

using HourglassState = Eigen::Matrix<Real, shell::BelytschkoTsayShell::kHourglassSize, Eigen::Dynamic>;

/// m_i = s/4 max_a sum_j |K_(ia),j| and I_i = s/4 max_a sum_j |K_(i theta_a),j| (s = 1.5), so that every
/// eigenvalue of M^-1 K is below 4 / s and the central-difference step dt = 1 is stable. The element
/// tangents are finite differences of element.update from copies of each element's state (stress,
/// hourglass resultants, thickness) at the mid-step configuration of the perturbation (the frame
/// change, i.e. the geometric stiffness, is in them); incidence_begin / incidence: node -> element * 4 + corner.
void stiffness_proportional_masses(const shell::BelytschkoTsayShell& element, const ShellMesh& mesh, const PointMatrix& x,
                                   const Eigen::MatrixXd& stress, const HourglassState& hourglass,
                                   const Eigen::VectorXd& thickness, const std::vector<Index>& incidence_begin,
                                   const std::vector<Index>& incidence, Eigen::VectorXd& mass, Eigen::VectorXd& inertia);

}  // namespace lamina::mpm
