#include "mpm/mass_scaling.hpp"

#include <algorithm>
#include <array>
#include <limits>

namespace lamina::mpm {

void stiffness_proportional_masses(const shell::BelytschkoTsayShell& element, const ShellMesh& mesh, const PointMatrix& positions,
                                   const Eigen::MatrixXd& stresses, const HourglassState& hourglass_state,
                                   const Eigen::VectorXd& thickness, const std::vector<Index>& incidence_begin,
                                   const std::vector<Index>& incidence, Eigen::VectorXd& mass,
                                   Eigen::VectorXd& inertia) {
  const Index e_count = mesh.element_count(), n = positions.cols();
  const int stress_size = element.stress_size();
  mass.resize(n);
  inertia.resize(n);
  using Vec24 = Eigen::Matrix<Real, 24, 1>;
  Eigen::Matrix<Real, 24, Eigen::Dynamic> row_sums(24, e_count);
#pragma omp parallel for schedule(static) if (e_count > 64)
  for (Index e = 0; e < e_count; ++e) {
    shell::NodeMatrix x;
    for (int a = 0; a < 4; ++a) x.col(a) = positions.col(mesh.quads(a, e));
    std::vector<Real> stress(static_cast<std::size_t>(stress_size));
    std::array<Real, shell::BelytschkoTsayShell::kHourglassSize> hourglass{};
    // nodal forces and moments after a step of dt = 1 with velocities v, w from the current state
    // (at the mid-step configuration x + v / 2 of that step, as MpmAnalysis::compute_internal_forces does: the
    // difference then holds the change of the corotational frame, the geometric stiffness)
    auto forces = [&](const shell::NodeMatrix& v, const shell::NodeMatrix& w) {
      std::copy(stresses.col(e).data(), stresses.col(e).data() + stress_size, stress.begin());
      std::copy(hourglass_state.col(e).data(), hourglass_state.col(e).data() + hourglass.size(), hourglass.begin());
      Real h = thickness[e];
      const shell::NodeMatrix x_mid = x + 0.5 * v;
      const shell::ShellElementResult r = element.update(x_mid, v, w, 1.0, stress.data(), hourglass.data(), h);
      Vec24 f;
      f.head<12>() = Eigen::Map<const Eigen::Matrix<Real, 12, 1>>(r.force.data());
      f.tail<12>() = Eigen::Map<const Eigen::Matrix<Real, 12, 1>>(r.moment.data());
      return f;
    };
    const shell::NodeMatrix zero = shell::NodeMatrix::Zero();
    const Vec24 f0 = forces(zero, zero);
    const Real size = std::max({(x.col(2) - x.col(0)).norm(), (x.col(3) - x.col(1)).norm(), 1e-300});
    Vec24 sum = Vec24::Zero();
    for (int j = 0; j < 24; ++j) {  // column j of the tangent; |K_ij| summed into row i
      shell::NodeMatrix v = zero, w = zero;
      const Real eps = j < 12 ? 1e-6 * size : 1e-6;
      (j < 12 ? v : w)(j % 3, (j % 12) / 3) = eps;
      sum += ((forces(v, w) - f0) / eps).cwiseAbs();
    }
    row_sums.col(e) = sum;
  }
  // node rows: the sum over the elements at the node (an upper bound of the assembled row sum), the
  // largest of the three components (one mass per node, as the grid transfers need)
  constexpr Real kSafety = 1.5;  // the tangent stiffens within a refresh interval (membrane stress, rotation)
  Real largest_mass = 0, largest_inertia = 0;
  for (Index i = 0; i < n; ++i) {
    Vec3 t = Vec3::Zero(), r = Vec3::Zero();
    for (Index k = incidence_begin[static_cast<std::size_t>(i)]; k < incidence_begin[static_cast<std::size_t>(i + 1)]; ++k) {
      const Index entry = incidence[static_cast<std::size_t>(k)], e = entry / 4;
      const int a = static_cast<int>(entry % 4);
      t += row_sums.block<3, 1>(3 * a, e);
      r += row_sums.block<3, 1>(12 + 3 * a, e);
    }
    mass[i] = 0.25 * kSafety * t.maxCoeff();
    inertia[i] = 0.25 * kSafety * r.maxCoeff();
    largest_mass = std::max(largest_mass, mass[i]);
    largest_inertia = std::max(largest_inertia, inertia[i]);
  }
  for (Index i = 0; i < n; ++i) {
    mass[i] = std::max(mass[i], 1e-12 * largest_mass + std::numeric_limits<Real>::min());
    inertia[i] = std::max(inertia[i], 1e-12 * largest_inertia + std::numeric_limits<Real>::min());
  }
}

}  // namespace lamina::mpm
