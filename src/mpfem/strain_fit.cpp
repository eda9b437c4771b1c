#include "mpfem/strain_fit.hpp"

#include <algorithm>

namespace lamina::mpfem {

Eigen::Matrix3Xd fit_particle_strains(const Points2& positions, const Points2& centroids,
                                      const std::vector<ParticleElement>& elements, const Eigen::Matrix3Xd& cell_mean) {
  const Index n = positions.cols();
  Eigen::Matrix3Xd fitted = cell_mean;
#pragma omp parallel for schedule(static)
  for (Index p = 0; p < n; ++p) {
    std::vector<Index> ring{p};
    auto add = [&](Index q) {
      if (q >= 0 && std::find(ring.begin(), ring.end(), q) == ring.end()) ring.push_back(q);
    };
    for (Index a : elements[static_cast<std::size_t>(p)].nodes) add(a);
    const std::size_t first = ring.size();
    for (std::size_t k = 1; k < first; ++k)
      for (Index a : elements[static_cast<std::size_t>(ring[k])].nodes) add(a);
    if (ring.size() < 3) continue;
    const auto m = static_cast<Index>(ring.size());
    Eigen::MatrixXd a(m, 3), b(m, 3);
    Real scale = 0;
    for (Index k = 0; k < m; ++k) scale = std::max(scale, (centroids.col(ring[static_cast<std::size_t>(k)]) - positions.col(p)).norm());
    if (!(scale > 0)) continue;
    for (Index k = 0; k < m; ++k) {
      const Index q = ring[static_cast<std::size_t>(k)];
      const Vec2 d = (centroids.col(q) - positions.col(p)) / scale;
      a.row(k) << 1.0, d.x(), d.y();
      b.row(k) = cell_mean.col(q).transpose();
    }
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(a);
    if (qr.rank() < 3) continue;
    fitted.col(p) = qr.solve(b).row(0).transpose();
  }
  return fitted;
}

}  // namespace lamina::mpfem
