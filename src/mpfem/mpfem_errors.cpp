// MpfemAnalysis: the triangles of the t3 reference element and of the error norms, and the errors
// against an exact displacement field (mpfem.exact_displacement: L2, energy and particle norms).
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "core/error.hpp"
#include "mpfem/mpfem_analysis.hpp"
#include "mpfem/triangle_strain.hpp"

namespace lamina::mpfem {

namespace {

/// Dunavant's 6-point rule (degree 4) on a triangle: barycentric points and weights (sum 1).
struct TrianglePoint {
  std::array<Real, 3> bary;
  Real weight;
};
const std::array<TrianglePoint, 6>& triangle_rule() {
  static const std::array<TrianglePoint, 6> rule = [] {
    const Real a = 0.445948490915965, wa = 0.223381589678011;
    const Real b = 0.091576213509771, wb = 0.109951743655322;
    return std::array<TrianglePoint, 6>{TrianglePoint{{a, a, 1 - 2 * a}, wa}, TrianglePoint{{a, 1 - 2 * a, a}, wa},
                                        TrianglePoint{{1 - 2 * a, a, a}, wa}, TrianglePoint{{b, b, 1 - 2 * b}, wb},
                                        TrianglePoint{{b, 1 - 2 * b, b}, wb}, TrianglePoint{{1 - 2 * b, b, b}, wb}};
  }();
  return rule;
}

}  // namespace

std::vector<MpfemAnalysis::Triangle> MpfemAnalysis::grid_triangles() const {
  const auto& g = *problem_.layout.grid;
  const Points2& x = problem_.layout.positions;
  std::vector<Triangle> result;
  const int cells1 = g.periodic1 ? g.n1 : g.n1 - 1;
  for (int j = 0; j < cells1; ++j)
    for (int i = 0; i + 1 < g.n0; ++i) {
      auto id = [&](int a, int b) { return static_cast<Index>(a) + static_cast<Index>(g.n0) * (b % g.n1); };
      const Index a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      for (const auto& nodes : {std::array<Index, 3>{a, b, c}, std::array<Index, 3>{a, c, d}}) {
        Triangle t;
        t.nodes = nodes;
        t.gradient = triangle_gradient(x.col(nodes[0]), x.col(nodes[1]), x.col(nodes[2]), t.area);
        t.weight = 1.0;
        if (!(t.area > 0))
          throw InputError("discretization.particles", "a particle grid whose cells are not tangled (t3 reference)",
                           fmt::format("an inverted triangle at particles {}, {}, {}", nodes[0], nodes[1], nodes[2]));
        result.push_back(t);
      }
    }
  return result;
}

std::vector<MpfemAnalysis::Triangle> MpfemAnalysis::error_triangles() const {
  if (problem_.options.element == ElementKind::t3) return grid_triangles();
  std::vector<Triangle> result;
  for (const auto& e : discretization_.elements)
    for (int k = 0; k < e.triangle_count; ++k) {
      const auto& tri = e.triangles[static_cast<std::size_t>(k)];
      Triangle t;
      for (int v = 0; v < 3; ++v) {
        t.nodes[static_cast<std::size_t>(v)] = e.nodes[static_cast<std::size_t>(tri.local[static_cast<std::size_t>(v)])];
        t.gradient.col(v) = tri.gradient.col(tri.local[static_cast<std::size_t>(v)]);
      }
      t.area = tri.area;
      t.weight = 1.0 / discretization_.covering;
      result.push_back(t);
    }
  return result;
}

void MpfemAnalysis::compute_errors() {
  if (!problem_.options.exact_displacement) return;
  const Points2& x = problem_.layout.positions;
  const Index n = x.cols();
  const geometry::Expression ux((*problem_.options.exact_displacement)[0]), uy((*problem_.options.exact_displacement)[1]);
  const Real z = problem_.z_mid;
  auto exact_u = [&](const Vec2& p) { return Vec2(ux.evaluate(Vec3(p.x(), p.y(), z)), uy.evaluate(Vec3(p.x(), p.y(), z))); };
  const Real delta = 1e-4 * (x.rowwise().maxCoeff() - x.rowwise().minCoeff()).norm();
  auto exact_strain = [&](const Vec2& p) {
    const Vec2 dx(delta, 0), dy(0, delta);
    const Vec2 du_dx = (exact_u(p + dx) - exact_u(p - dx)) / (2 * delta);
    const Vec2 du_dy = (exact_u(p + dy) - exact_u(p - dy)) / (2 * delta);
    return Eigen::Vector3d(du_dx.x(), du_dy.y(), du_dy.x() + du_dx.y());
  };
  Real l2_error = 0, l2_norm = 0, energy_error = 0, energy_norm = 0;
  for (const auto& t : error_triangles()) {
    const Eigen::Matrix3d c = materials_[static_cast<std::size_t>(problem_.material_of_particle[static_cast<std::size_t>(t.nodes[0])])].matrix();
    Eigen::Matrix<Real, 6, 1> ul;
    for (int a = 0; a < 3; ++a) ul.segment<2>(2 * a) = u_.segment<2>(2 * t.nodes[static_cast<std::size_t>(a)]);
    const Eigen::Vector3d eps_h = triangle_strain_operator(t.gradient) * ul;
    for (const auto& q : triangle_rule()) {
      Vec2 p = Vec2::Zero(), uh = Vec2::Zero();
      for (int a = 0; a < 3; ++a) {
        p += q.bary[static_cast<std::size_t>(a)] * x.col(t.nodes[static_cast<std::size_t>(a)]);
        uh += q.bary[static_cast<std::size_t>(a)] * ul.segment<2>(2 * a);
      }
      const Real w = q.weight * t.area * t.weight;
      const Vec2 ue = exact_u(p);
      const Eigen::Vector3d eps = exact_strain(p);
      l2_error += w * (uh - ue).squaredNorm();
      l2_norm += w * ue.squaredNorm();
      energy_error += w * (eps_h - eps).dot(c * (eps_h - eps));
      energy_norm += w * eps.dot(c * eps);
    }
  }
  Real particle_error = 0, particle_norm = 0, max_u_error = 0, max_u = 0, max_s_error = 0, max_s = 0;
  for (Index p = 0; p < n; ++p) {
    const Eigen::Matrix3d c = materials_[static_cast<std::size_t>(problem_.material_of_particle[static_cast<std::size_t>(p)])].matrix();
    const Real dv = discretization_.area_weight[p];
    const Eigen::Vector3d eps = exact_strain(x.col(p));
    const Eigen::Vector3d e = strain_.col(p) - eps;
    particle_error += dv * e.dot(c * e);
    particle_norm += dv * eps.dot(c * eps);
    const Vec2 ue = exact_u(x.col(p));
    max_u_error = std::max(max_u_error, (u_.segment<2>(2 * p) - ue).norm());
    max_u = std::max(max_u, ue.norm());
    const Eigen::Vector3d se = c * eps;
    max_s_error = std::max(max_s_error, (stress_.col(p) - se).norm());
    max_s = std::max(max_s, se.norm());
  }
  auto ratio = [](Real a, Real b) { return b > 0 ? std::sqrt(a / b) : std::sqrt(a); };
  errors_.l2 = ratio(l2_error, l2_norm);
  errors_.energy = ratio(energy_error, energy_norm);
  errors_.energy_particles = ratio(particle_error, particle_norm);
  errors_.max_displacement = max_u > 0 ? max_u_error / max_u : max_u_error;
  errors_.max_stress = max_s > 0 ? max_s_error / max_s : max_s_error;
}

}  // namespace lamina::mpfem
