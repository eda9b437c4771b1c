#pragma once
// AdaptiveDynamicRelaxation: the quasi-static equilibrium solver of seed 002 section 3
// (Kilic & Madenci 2010 with the seed's changes), for one load increment.
//
//   Lambda U'' + c Lambda U' = F(U) = F_int(U) + F_ext,   dt = 1
//   lambda_ii = 1/4 dt^2 sum_j |K0_ij|                          (seed eq (5): Gershgorin bound of K0)
//   1K_ii = -(F_i^n - F_i^(n-1)) / (lambda_ii dt Udot_i^(n-1/2)), 0 where |Udot_i| < guard |U_i|
//   c^n = 2 sqrt(dU^T 1K dU / dU^T dU), dU = U - U_start (or U: seed eq (6), damping_estimate: total)
//         (0 if negative; 1.9 if above 2)
//   Udot^(n+1/2) = ((2 - c dt) Udot^(n-1/2) + 2 dt F^n / lambda) / (2 + c dt)  (seed eq (7))
//   Udot^(1/2) = dt F^0 / (2 lambda)                                          (start-up half step)
//   U^(n+1) = U^n + dt Udot^(n+1/2)
//   converged (seed eq (8)): max|R^k| <= tol_rel max|R^0| for k < k_switch; afterwards that OR
//   max|R^k| <= tol_abs. R = F_int + F_ext on the free degrees of freedom.
// Optionally in generalised coordinates q, U = T q (column modes of a plate lattice): the same
// updates with F -> T^T F and lambda the Gershgorin bound of T^T K0 T; the test (8) stays on R.
// The energy dissipated by the fictitious damping, sum c lambda Udot^2 dt, is accumulated.
// Extension (kinetic_fallback, default on): while c = 0 (negative local stiffness, e.g. during a
// snap-through) the velocities are zeroed at every peak of the fictitious kinetic energy.
#include <functional>
#include <memory>
#include <vector>

#include "pd/peridynamic_model.hpp"
#include "pd/peridynamic_problem.hpp"
#include "pd/relaxation_coordinates.hpp"

namespace lamina::pd {

struct RelaxationResult {
  bool converged = false;
  int iterations = 0;
  Real initial_residual = 0;    // max |R^0|
  Real residual = 0;            // max |R| at the end
  Real damping_energy = 0;      // dissipated in this increment
  std::unique_ptr<ModelState> state;  // at the final U
  PointMatrix internal_force;   // at the final U
};

class AdaptiveDynamicRelaxation {
 public:
  /// fictitious_density: lambda per dof (3N); free: 1 for unknown dofs, 0 for prescribed ones.
  /// coordinates (optional): relax in q with U = T q (relaxation_coordinates.hpp); lambda is then per
  /// generalised dof. The convergence test stays on the node residual.
  AdaptiveDynamicRelaxation(const PeridynamicModel& solid, Eigen::VectorXd fictitious_density,
                            std::vector<char> free, AdaptiveDynamicRelaxationOptions options,
                            const RelaxationCoordinates* coordinates = nullptr);

  /// Relax u (3 x N: prescribed values on constrained dofs, the start field elsewhere) to equilibrium
  /// under external_force (3 x N). Throws AnalysisError on non-finite values.
  /// reference_residual > 0: the max|R^0| of the relative test (a continued relaxation keeps the
  /// increment's own start residual instead of its current, dynamic one); the iteration budget is
  /// max_iterations per call.
  RelaxationResult relax(PointMatrix& u, const PointMatrix& external_force, Real reference_residual = -1.0) const;
  /// Force decomposition over ranks: the model computed the internal force of this rank's nodes only;
  /// complete(F) fills in the others' (an all-gather). Unset: the force is whole.
  void set_force_completion(std::function<void(PointMatrix&)> complete) { complete_force_ = std::move(complete); }
  /// Multiplies the fictitious density by factor (after a block that diverged: the tangent outgrew it).
  void scale_density(Real factor) { lambda_ *= factor; }

 private:
  const PeridynamicModel& solid_;
  Eigen::VectorXd lambda_;
  std::vector<char> free_;
  AdaptiveDynamicRelaxationOptions options_;
  const RelaxationCoordinates* coordinates_ = nullptr;
  std::function<void(PointMatrix&)> complete_force_;
};

}  // namespace lamina::pd
