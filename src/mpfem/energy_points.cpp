#include "mpfem/energy_points.hpp"

#include <cmath>

#include "mpfem/gradient_list.hpp"

namespace lamina::mpfem {

namespace {

void add_scaled(GradientList& to, const GradientList& from, Real scale) {
  if (scale == 0.0) return;
  for (const auto& [p, g] : from) add_gradient(to, p, scale * g);
}

GradientList element_list(const ParticleElement& e, const ElementGradient& g) {
  GradientList list;
  for (int a = 0; a < kElementNodes; ++a) {
    const Index j = e.nodes[static_cast<std::size_t>(a)];
    if (j >= 0 && g.col(a).squaredNorm() > 0) add_gradient(list, j, g.col(a));
  }
  return list;
}

void add_stabilisation(std::vector<EnergyPoint>& points, const ParticleElement& e, const GradientList& centre,
                       Real scale, Real beta) {
  if (beta <= 0 || e.triangle_count == 0) return;
  for (int t = 0; t < e.triangle_count; ++t) {
    const auto& tri = e.triangles[static_cast<std::size_t>(t)];
    points.push_back({beta * scale * tri.area / e.area, element_list(e, tri.gradient)});
  }
  GradientList star = element_list(e, e.mean_gradient);
  GradientList middle;
  add_scaled(middle, star, 0.5);
  add_scaled(middle, centre, 0.5);
  points.push_back({beta * scale, std::move(star)});
  points.push_back({2 * beta * scale, centre});
  points.push_back({-4 * beta * scale, std::move(middle)});
}

}  // namespace

std::vector<EnergyPoint> cell_energy_points(const ParticleElement& e, const GradientList& cell_mean,
                                            const std::array<GradientList, 2>& strain_gradient, Real omega,
                                            const Eigen::Matrix2d& moment, Real beta) {
  std::vector<EnergyPoint> points;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(moment / omega);
  const Eigen::Vector2d s = eigen.eigenvalues().cwiseMax(0.0);
  if (s.maxCoeff() > 0) {
    for (int i = 0; i < 2; ++i)
      for (Real sign : {1.0, -1.0}) {
        const Vec2 d = sign * std::sqrt(2.0 * s[i]) * eigen.eigenvectors().col(i);
        EnergyPoint q{omega / 4, cell_mean};
        add_scaled(q.gradient, strain_gradient[0], d.x());
        add_scaled(q.gradient, strain_gradient[1], d.y());
        points.push_back(std::move(q));
      }
  } else {
    points.push_back({omega, cell_mean});
  }
  add_stabilisation(points, e, cell_mean, omega, beta);
  return points;
}

std::vector<EnergyPoint> star_energy_points(const ParticleElement& e, Real dv, Real beta) {
  std::vector<EnergyPoint> points;
  points.push_back({(1 - beta) * dv, element_list(e, e.mean_gradient)});
  for (int t = 0; t < e.triangle_count; ++t) {
    const auto& tri = e.triangles[static_cast<std::size_t>(t)];
    if (beta > 0) points.push_back({beta * dv * tri.area / e.area, element_list(e, tri.gradient)});
  }
  return points;
}

}  // namespace lamina::mpfem
