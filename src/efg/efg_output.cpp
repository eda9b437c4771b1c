// EfgAnalysis results: nodal fields after the solve (u^h, strain, stress; error norms against an exact
// displacement), values at a point, probes, reactions, the output frame (VTU fields) and counts.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include "core/error.hpp"
#include "efg/efg_analysis.hpp"
#include "efg/mls_fit_analysis.hpp"
#include "efg/nodal_field.hpp"

namespace lamina::efg {

void EfgAnalysis::postprocess() {
  const Index n = problem_.cloud.size();
  // the nodes include the body's edges and corners (grow_at_points_: see efg_analysis.hpp)
  const auto values = shapes_->evaluate_all(problem_.cloud.positions, 1, grow_at_points_);
  grown_boundary_points_ += count_grown(values);
  node_displacement_.resize(3, n);
  node_strain_.resize(6, n);
  node_stress_.resize(6, n);
  node_material_.assign(static_cast<std::size_t>(n), 0);
  for (Index i = 0; i < n; ++i) {
    const Vec3 x = problem_.cloud.positions.col(i);
    const int m = material_at(x);
    node_material_[static_cast<std::size_t>(i)] = m < 0 ? 0 : m;
  }
#pragma omp parallel for schedule(static)
  for (Index i = 0; i < n; ++i) {
    const auto& sv = values[static_cast<std::size_t>(i)];
    node_displacement_.col(i) = value_of(sv, u_);
    const material::Voigt e = material::strain_from_gradient(gradient_of(sv, u_));
    node_strain_.col(i) = e;
    node_stress_.col(i) = stress_of(node_material_[static_cast<std::size_t>(i)], e, problem_.cloud.positions.col(i));
  }
  if (problem_.options.exact_displacement) {
    const auto& exact = *problem_.options.exact_displacement;
    const Vec3 lower = problem_.cloud.positions.rowwise().minCoeff(), upper = problem_.cloud.positions.rowwise().maxCoeff();
    const Real h = 1e-3 * std::max((upper - lower).maxCoeff(), 1e-300);
    Real du = 0, umax = 0, ds = 0, smax = 0;
    for (Index i = 0; i < n; ++i) {
      const Vec3 x = problem_.cloud.positions.col(i);
      Vec3 ue;
      Mat3 G;
      for (int a = 0; a < 3; ++a) {
        const FieldDerivatives d = differentiate_expression(exact[static_cast<std::size_t>(a)], x, h);
        ue[a] = d.value;
        G.row(a) = d.gradient.transpose();
      }
      const material::Voigt se = materials_[static_cast<std::size_t>(node_material_[static_cast<std::size_t>(i)])].stress(
          material::strain_from_gradient(G));  // the exact stress (full lambda tr eps)
      du = std::max(du, (node_displacement_.col(i) - ue).norm());
      umax = std::max(umax, ue.norm());
      ds = std::max(ds, (node_stress_.col(i) - se).norm());
      smax = std::max(smax, se.norm());
    }
    error_displacement_ = umax > 0 ? du / umax : du;
    error_stress_ = smax > 0 ? ds / smax : ds;
  }
}

Vec3 EfgAnalysis::displacement_at(const Vec3& x) const {
  mls::ShapeFunctionValues sv;
  shapes_->evaluate(x, 0, sv, grow_at_points_);
  return value_of(sv, u_);
}

material::Voigt EfgAnalysis::strain_at(const Vec3& x) const {
  mls::ShapeFunctionValues sv;
  shapes_->evaluate(x, 1, sv, grow_at_points_);
  return material::strain_from_gradient(gradient_of(sv, u_));
}

material::Voigt EfgAnalysis::stress_at(const Vec3& x) const {
  int m = material_at(x);
  if (m < 0) m = node_material_.empty() ? 0 : node_material_[static_cast<std::size_t>(nearest_node(x))];
  return stress_of(m, strain_at(x), x);
}

material::Voigt EfgAnalysis::stress_of(int m, const material::Voigt& strain, const Vec3& x) const {
  if (!projection_ || nodal_pressure_.size() == 0) return materials_[static_cast<std::size_t>(m)].stress(strain);
  // sigma = 2 mu eps + p I with the projected pressure p(x) = sum_I psi_I(x) lambda_I theta_I
  material::Voigt s = deviatoric_materials_[static_cast<std::size_t>(m)].stress(strain);
  mls::ShapeFunctionValues pv;
  if (!pressure_->evaluate(x, pv)) return s;  // outside every pressure support
  Real p = 0.0;
  for (std::size_t k = 0; k < pv.neighbours.size(); ++k) p += pv.phi[static_cast<Index>(k)] * nodal_pressure_[pv.neighbours[k]];
  s.head<3>().array() += p;
  return s;
}

Vec3 EfgAnalysis::reaction(const IndexList& nodes) const {
  Vec3 sum = Vec3::Zero();
  for (std::size_t i = 0; i < reactions_.size(); ++i)
    if (nodes.empty() || std::binary_search(nodes.begin(), nodes.end(), constraint_nearest_[i])) sum += reactions_[i];
  return sum;
}

Real EfgAnalysis::field_probe(const Probe& p) const {
  auto component_of = [&](const Vec3& u, const material::Voigt& e, const material::Voigt& s) -> Real {
    if (p.field == "displacement") return p.component == "magnitude" ? u.norm() : u[vector_component(p.component)];
    if (p.field == "strain") return e[tensor_component(p.component)];
    return p.component == "von_mises" ? material::von_mises(s) : s[tensor_component(p.component)];
  };
  auto at_point = [&](const Vec3& x) {
    if (p.field == "displacement") return component_of(displacement_at(x), material::Voigt::Zero(), material::Voigt::Zero());
    const material::Voigt e = strain_at(x);
    return component_of(Vec3::Zero(), e, p.field == "stress" ? stress_at(x) : material::Voigt::Zero());
  };
  if (p.at && !p.nearest_in_set) return at_point(*p.at);
  if (p.at && p.nearest_in_set) {
    Index best = p.nodes.front();
    Real distance = INFINITY;
    for (Index i : p.nodes) {
      const Real d = (problem_.cloud.positions.col(i) - *p.at).squaredNorm();
      if (d < distance) {
        distance = d;
        best = i;
      }
    }
    return component_of(node_displacement_.col(best), node_strain_.col(best), node_stress_.col(best));
  }
  // selection without a point: the value of largest magnitude over the selected nodes
  Real result = 0.0;
  for (Index i : p.nodes) {
    const Real v = component_of(node_displacement_.col(i), node_strain_.col(i), node_stress_.col(i));
    if (std::abs(v) > std::abs(result)) result = v;
  }
  return result;
}

Real EfgAnalysis::probe(const Probe& p) const {
  if (!solved_) return 0.0;
  if (p.field == "reaction_force") {
    const Vec3 r = reaction(p.nodes);
    return p.component == "magnitude" ? r.norm() : r[vector_component(p.component)];
  }
  if (p.field == "energy") {
    if (p.component == "internal" || p.component == "total") return energy_internal_;
    if (p.component == "external") return energy_external_;
    return 0.0;
  }
  return field_probe(p);
}

std::map<std::string, Real> EfgAnalysis::builtin_probes() const {
  if (!problem_.options.exact_displacement) return {};
  return {{"err_displacement", error_displacement_}, {"err_stress", error_stress_}};
}

OutputFrame EfgAnalysis::frame() const {
  OutputFrame f;
  f.points = problem_.cloud.positions;
  const Index n = problem_.cloud.size();
  if (node_displacement_.cols() != n) return f;
  auto add = [&](const std::string& name, int components, const Real* data) {
    f.point_fields.push_back(PointField{name, components, std::vector<Real>(data, data + components * n)});
  };
  add("displacement", 3, node_displacement_.data());
  add("strain", 6, node_strain_.data());
  add("stress", 6, node_stress_.data());
  std::vector<Real> vm(static_cast<std::size_t>(n)), id(static_cast<std::size_t>(n));
  for (Index i = 0; i < n; ++i) {
    vm[static_cast<std::size_t>(i)] = material::von_mises(node_stress_.col(i));
    id[static_cast<std::size_t>(i)] = node_material_[static_cast<std::size_t>(i)];
  }
  add("von_mises", 1, vm.data());
  add("material_id", 1, id.data());
  add("nodal_parameter", 3, u_.data());
  if (problem_.cloud.volumes.size() == n) add("volume", 1, problem_.cloud.volumes.data());
  return f;
}

RunCounts EfgAnalysis::counts() const {
  const Index n = problem_.cloud.size();
  return RunCounts{n, 3 * n + multipliers_.size(), 1};
}

}  // namespace lamina::efg
