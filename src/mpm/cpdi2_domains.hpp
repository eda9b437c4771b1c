#pragma once
// The shell mesh as CPDI2 material-point domains: every quadrilateral is one particle domain whose
// corners are the shell nodes; seed 000 eqs (15)-(16) (weights and gradients of the two-step mapping).
//
// For a quad domain with corners x1..x4 (in its own plane), eq (15):
//   phi_Ip = sum_c wf_c S_I(x_c) / (36 V_p),  wf = [4c1+2c2+2c3+c4, 2c1+4c2+c3+2c4, c1+2c2+2c3+4c4, 2c1+c2+4c3+2c4]
// and eq (16): grad phi_Ip = sum_c wg_c S_I(x_c) / (2 V_p), wg_1 = (y2-y4, x4-x2), wg_2 = (y3-y1, x1-x3),
// wg_3 = -wg_1, wg_4 = -wg_2. The corner mass share of a domain is wf_c / (36 V_p) (1/4 for a
// parallelogram); the corner gradient weights wg_c / (2 V_p) are exactly the Belytschko-Tsay B matrix,
// so BT nodal forces spread with S_I(x_c) are the CPDI2 internal forces.
#include <string>
#include <vector>

#include "core/shell_mesh.hpp"
#include "core/types.hpp"

namespace lamina::mpm {

/// CPDI2 corner weights of one planar quad domain (corners in 2D, counter-clockwise).
struct Cpdi2CornerWeights {
  Eigen::Matrix<Real, 1, 4> value;     // wf_c / (36 V_p): sum = 1
  Eigen::Matrix<Real, 2, 4> gradient;  // wg_c / (2 V_p): sum = 0, sum_c gradient_c x_c^T = identity
  Real area = 0.0;                     // V_p (shoelace)
};

Cpdi2CornerWeights cpdi2_corner_weights(const Eigen::Matrix<Real, 2, 4>& corners);

/// Projects a 3D quad onto its best plane (the Belytschko-Tsay corotational frame), in 2D.
Eigen::Matrix<Real, 2, 4> planar_corners(const Eigen::Matrix<Real, 3, 4>& corners);

/// A problem found in the mesh (element index and what is wrong).
struct DomainDefect {
  Index element = -1;
  std::string what;
};

/// The domains: the shell quads with their corner (node) masses and rotational inertias.
class Cpdi2Domains {
 public:
  /// Checks every element (zero area, non-convex or self-intersecting, orientation flipped against
  /// a neighbour); the defects are returned by defects() and no masses are computed if any exist.
  Cpdi2Domains(const ShellMesh& mesh, Real density);

  const std::vector<DomainDefect>& defects() const { return defects_; }
  Index node_count() const { return node_mass_.size(); }
  Index element_count() const { return element_area_.size(); }
  /// Lumped node mass sum_e rho h A_e phi_c (CPDI2 corner shares).
  const Eigen::VectorXd& node_mass() const { return node_mass_; }
  /// Node rotational inertia with the usual scaling: sum_e m_ec max(h^2/12, A_e/8).
  const Eigen::VectorXd& node_inertia() const { return node_inertia_; }
  const Eigen::VectorXd& element_area() const { return element_area_; }
  /// Edge lengths (shortest, median) over the mesh.
  Real shortest_edge() const { return shortest_edge_; }
  Real median_edge() const { return median_edge_; }

 private:
  std::vector<DomainDefect> defects_;
  Eigen::VectorXd node_mass_, node_inertia_, element_area_;
  Real shortest_edge_ = 0.0, median_edge_ = 0.0;
};

}  // namespace lamina::mpm
