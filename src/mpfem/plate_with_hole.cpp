#include "mpfem/plate_with_hole.hpp"

#include <fmt/format.h>

#include <cmath>

#include "core/error.hpp"

namespace lamina::mpfem {

GeneratedParticles generate_plate_with_hole(const PlateWithHoleSpec& s) {
  if (!(s.radius > 0) || !(s.radius < std::min(s.width, s.height)))
    throw InputError("mpfem.hole.radius", fmt::format("a radius in (0, {})", std::min(s.width, s.height)),
                     fmt::format("{}", s.radius));
  if (s.n_radial < 2 || s.n_angular < 3)
    throw InputError("discretization.particles", "[n_radial >= 2, n_angular >= 3] for a plate with a hole",
                     fmt::format("[{}, {}]", s.n_radial, s.n_angular));
  if (!(s.grading >= 1.0 && s.grading <= 4.0))
    throw InputError("mpfem.hole.grading", "a grading exponent in [1, 4]", fmt::format("{}", s.grading));
  GeneratedParticles g;
  const Index n = static_cast<Index>(s.n_radial) * s.n_angular;
  g.layout.positions.resize(2, n);
  g.layout.grid = LogicalGrid{s.n_radial, s.n_angular, false};
  const Real half_pi = 2.0 * std::atan(1.0);
  for (int j = 0; j < s.n_angular; ++j) {
    const Real theta = half_pi * j / (s.n_angular - 1);
    const Vec2 direction(std::cos(theta), std::sin(theta));
    const Vec2 inner = s.radius * direction;
    // where the ray leaves the rectangle
    const Real tx = direction.x() > 1e-14 ? s.width / direction.x() : INFINITY;
    const Real ty = direction.y() > 1e-14 ? s.height / direction.y() : INFINITY;
    Vec2 outer = std::min(tx, ty) * direction;
    if (j == 0) outer = Vec2(s.width, 0);
    if (j == s.n_angular - 1) outer = Vec2(0, s.height);
    for (int i = 0; i < s.n_radial; ++i) {
      const Real f = std::pow(static_cast<Real>(i) / (s.n_radial - 1), s.grading);
      const Index p = i + static_cast<Index>(s.n_radial) * j;
      g.layout.positions.col(p) = s.origin + inner + f * (outer - inner);
      auto& sets = g.sets;
      if (i == 0) sets["hole"].push_back(p);
      if (i == s.n_radial - 1) {
        sets["outer"].push_back(p);
        const Vec2 local = g.layout.positions.col(p) - s.origin;
        if (std::abs(local.x() - s.width) < 1e-12 * s.width) sets["xmax"].push_back(p);
        if (std::abs(local.y() - s.height) < 1e-12 * s.height) sets["ymax"].push_back(p);
      }
      if (j == 0) sets["ymin"].push_back(p);
      if (j == s.n_angular - 1) sets["xmin"].push_back(p);
    }
  }
  // tributary areas: a quarter of each adjacent mapped cell (split into two triangles)
  g.area = Eigen::VectorXd::Zero(n);
  for (int j = 0; j + 1 < s.n_angular; ++j)
    for (int i = 0; i + 1 < s.n_radial; ++i) {
      auto id = [&](int a, int b) { return static_cast<Index>(a) + static_cast<Index>(s.n_radial) * b; };
      const std::array<Index, 4> c{id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)};
      const Vec2 d1 = g.layout.positions.col(c[2]) - g.layout.positions.col(c[0]);
      const Vec2 d2 = g.layout.positions.col(c[3]) - g.layout.positions.col(c[1]);
      const Real area = 0.5 * std::abs(d1.x() * d2.y() - d1.y() * d2.x());
      for (Index p : c) g.area[p] += area / 4;
    }
  return g;
}

}  // namespace lamina::mpfem
