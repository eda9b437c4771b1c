#pragma once
// Static equilibrium of a Belytschko-Tsay shell mesh by Newton's method on the node displacement and
// rotation increments of a load step (no background grid, no mass): the kernel of `mpm.solver: newton`.
//
// One increment (u, theta) from a converged state (x0, element stresses, hourglass resultants,
// thicknesses) is evaluated as the explicit step evaluates its elements, in two calls of
// BelytschkoTsayShell::update (seed 000 eqs (17)-(37)):
//   1. the stresses advance over the increment with "velocities" u, theta and dt = 1 at the mid-increment
//      configuration x0 + u / 2 (Hughes-Winget: the chord of a finite rigid rotation is a rigid velocity
//      field there, so it gives no strain; the increments integrate to second order);
//   2. the nodal forces and moments of those stresses at the end configuration x0 + u (dt = 0).
// The residual is r = f_ext(x0 + u) - f_int over the free components; the tangent K = d f_int / d(u, theta)
// is assembled from finite differences of this element map (24 columns per element: the material,
// stress (geometric) and frame terms; follower loads are left out of it). Each Newton correction
// solves K du = r (sparse LU).
// Drilling: the element's drilling penalty ties only the mean of its nodal drilling rotations to its
// in-plane rotation, so the differences between them have no stiffness (3 zero-energy modes per
// element, harmless in the explicit step, singular here). Each node therefore gets a spring of
// kDrillingSpring x D (D = E h^3 / 12 of each element at the node) on its rotation increment about each
// element normal, in the residual and the tangent alike (quadratic convergence); it acts on one
// sub-increment's rotation only and its work is counted with the stabilisation (hourglass) energy.
#include <Eigen/Sparse>
#include <memory>
#include <string>
#include <vector>

#include "core/shell_mesh.hpp"
#include "core/types.hpp"
#include "shell/belytschko_tsay_shell.hpp"

namespace lamina::mpm {

/// What an increment starts from and what a converged increment leaves (per element: stress points,
/// hourglass resultants, thickness).
struct ShellState {
  PointMatrix x;
  Eigen::MatrixXd stress;  // stress_size x E
  Eigen::Matrix<Real, shell::BelytschkoTsayShell::kHourglassSize, Eigen::Dynamic> hourglass;
  Eigen::VectorXd thickness;
};

/// Internal forces of an increment: nodal forces and moments at x0 + u, the work of the stresses and of
/// the stabilisation over the increment.
struct IncrementForces {
  Eigen::Matrix3Xd force, moment;
  Real internal_work = 0, hourglass_work = 0;
  Index invalid_element = -1;  // >= 0: an element became degenerate or inverted
};

class ShellStatics {
 public:
  /// free / rotation_free: 1 = free, 0 = held (3 x N each); held components do not move.
  ShellStatics(const shell::BelytschkoTsayShell& element, const ShellMesh& mesh, const Eigen::Matrix3Xd& free,
               const Eigen::Matrix3Xd& rotation_free);
  ~ShellStatics();

  /// Number of free components (unknowns): translations and rotations.
  Index unknowns() const { return unknowns_; }
  /// Equation of node i's component c (0-2 translation, 3-5 rotation); -1 if held.
  Index equation(Index node, int component) const { return equation_(component, node); }

  /// Relative stiffness of the drilling spring (see the file comment).
  static constexpr Real kDrillingSpring = 1e-6;

  /// The drilling springs of the increments from `start` (element normals and thicknesses at start);
  /// call before forces() and tangent() of a new sub-increment.
  void begin_increment(const ShellState& start);

  /// Forces of the increment (u, theta) from `start`; `end` (if given) receives the advanced state.
  IncrementForces forces(const ShellState& start, const PointMatrix& u, const PointMatrix& theta, ShellState* end) const;

  /// K = d f_int / d(u, theta) at the increment (u, theta) over the free components, by central
  /// differences of each element's forces (steps 1e-6 x the element diagonal and 1e-6 rad).
  Eigen::SparseMatrix<Real> tangent(const ShellState& start, const PointMatrix& u, const PointMatrix& theta) const;

  /// Solves K x = r by sparse LU (Eigen SparseLU, COLAMD; the symbolic analysis is kept while the pattern is the same).
  /// Returns false with a reason if K is singular or the solution misses r by more than 10 %.
  bool solve(const Eigen::SparseMatrix<Real>& k, const Eigen::VectorXd& r, Eigen::VectorXd& x, std::string& reason);

 private:
  using Vec24 = Eigen::Matrix<Real, 24, 1>;
  /// Element e's forces and moments (24: f of the 4 nodes, then m) for the element increment (ue, te).
  bool element_forces(const ShellState& start, Index e, const shell::NodeMatrix& ue, const shell::NodeMatrix& te, Vec24& out,
                      std::vector<Real>& stress, Real* hourglass, Real& thickness, Real* internal_work, Real* hourglass_work) const;

  const shell::BelytschkoTsayShell& element_;
  const ShellMesh& mesh_;
  Eigen::Matrix<Index, 6, Eigen::Dynamic> equation_;
  Index unknowns_ = 0;
  Eigen::Matrix<Real, 9, Eigen::Dynamic> drilling_spring_;  // per node: 3 x 3 spring matrix (column-major)
  struct LinearSolver;
  std::unique_ptr<LinearSolver> solver_;
};

}  // namespace lamina::mpm
