// MpfemAnalysis results: values at a point, reactions, probes, built-in probes (error norms, large-
// deformation counters), the output frame (particle fields for VTU) and counts.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "mpfem/mpfem_analysis.hpp"

namespace lamina::mpfem {

namespace {

/// A plane strain or stress (xx, yy, engineering xy) with its out-of-plane zz value, as a 3D Voigt vector.
material::Voigt to_voigt(const Eigen::Vector3d& in_plane, Real zz) {
  material::Voigt v = material::Voigt::Zero();
  v << in_plane[0], in_plane[1], zz, in_plane[2], 0, 0;
  return v;
}

}  // namespace

Index MpfemAnalysis::nearest_particle(const Vec2& x) const {
  Index best = 0;
  Real distance = INFINITY;
  for (Index p = 0; p < problem_.layout.positions.cols(); ++p) {
    const Real d = (problem_.layout.positions.col(p) - x).squaredNorm();
    if (d < distance) distance = d, best = p;
  }
  return best;
}

Vec2 MpfemAnalysis::displacement_at(const Vec2& x) const {
  const auto values = shape_functions_at(discretization_, problem_.layout.positions, x);
  if (values.empty()) return u_.segment<2>(2 * nearest_particle(x));
  Vec2 u = Vec2::Zero();
  for (const auto& v : values) u += v.value * u_.segment<2>(2 * v.particle);
  return u;
}

Vec2 MpfemAnalysis::reaction(const IndexList& particles) const {
  Vec2 r = Vec2::Zero();
  for (Index p : particles) r += reactions_.segment<2>(2 * p);
  return r;
}

Real MpfemAnalysis::field_probe(const Probe& p) const {
  auto vector_value = [&](const Vec2& v) {
    if (p.component == "magnitude") return v.norm();
    const int c = vector_component(p.component);
    return c < 2 ? v[c] : 0.0;
  };
  auto tensor_value = [&](Index particle) {
    const PlaneMaterial& m = materials_[static_cast<std::size_t>(problem_.material_of_particle[static_cast<std::size_t>(particle)])];
    const bool stress = p.field == "stress";
    material::Voigt v;
    if (stress) v = to_voigt(stress_.col(particle), m.plane == PlaneKind::strain ? out_of_plane_[particle] : 0.0);
    else v = to_voigt(strain_.col(particle), m.plane == PlaneKind::stress ? out_of_plane_[particle] : 0.0);
    if (p.component == "von_mises") return material::von_mises(v);
    return v[tensor_component(p.component)];
  };
  if (p.field == "reaction_force") {
    const Vec2 r = reaction(p.nodes);
    return vector_value(r);
  }
  auto value_at_particle = [&](Index q) {
    return p.field == "displacement" ? vector_value(u_.segment<2>(2 * q)) : tensor_value(q);
  };
  if (p.at) {
    const Vec2 x(p.at->x(), p.at->y());
    if (p.nearest_in_set && !p.nodes.empty()) {
      Index best = p.nodes.front();
      for (Index q : p.nodes)
        if ((problem_.layout.positions.col(q) - x).squaredNorm() < (problem_.layout.positions.col(best) - x).squaredNorm()) best = q;
      return value_at_particle(best);
    }
    if (p.field == "displacement") return vector_value(displacement_at(x));
    return value_at_particle(nearest_particle(x));
  }
  Real best = 0;
  for (Index q : p.nodes) {
    const Real v = value_at_particle(q);
    if (std::abs(v) > std::abs(best)) best = v;
  }
  return best;
}

Real MpfemAnalysis::probe(const Probe& requested) const {
  if (!solved_) return NAN;
  // the application may hold the probes resolved on the case's original particles; the ones given
  // to the constructor are resolved on this analysis' particles (refine / hole regenerate them)
  const Probe* own = &requested;
  for (const auto& q : probes_)
    if (q.name == requested.name) own = &q;
  const Probe& p = *own;
  if (p.field == "energy") {
    if (p.component == "kinetic") return 0.0;
    if (p.component == "external") return energy_external_;
    return energy_internal_;
  }
  return field_probe(p);
}

std::map<std::string, Real> MpfemAnalysis::builtin_probes() const {
  std::map<std::string, Real> result;
  result["h"] = discretization_.typical_spacing;
  if (problem_.options.analysis == MpfemAnalysisKind::large_deformation) {
    result["neighbourhood_rebuilds"] = static_cast<Real>(stats_.rebuilds);
    result["rebuilt_particles"] = static_cast<Real>(stats_.rebuilt_particles);
    result["newton_iterations"] = static_cast<Real>(stats_.newton_iterations);
    result["load_increments"] = static_cast<Real>(stats_.increments);
    result["increment_cuts"] = static_cast<Real>(stats_.cuts);
  }
  if (problem_.options.exact_displacement) {
    result["err_displacement"] = errors_.max_displacement;
    result["err_stress"] = errors_.max_stress;
    result["err_l2"] = errors_.l2;
    result["err_energy"] = errors_.energy;
    result["err_energy_particles"] = errors_.energy_particles;
  }
  return result;
}

OutputFrame MpfemAnalysis::frame() const {
  const Points2& x = problem_.layout.positions;
  const Index n = x.cols();
  OutputFrame f;
  f.points.resize(3, n);
  f.points.topRows(2) = x;
  f.points.row(2).setConstant(problem_.z_mid);
  PointField displacement{"displacement", 3, std::vector<Real>(static_cast<std::size_t>(3 * n), 0.0)};
  PointField strain{"strain", 6, std::vector<Real>(static_cast<std::size_t>(6 * n), 0.0)};
  PointField stress{"stress", 6, std::vector<Real>(static_cast<std::size_t>(6 * n), 0.0)};
  PointField mises{"von_mises", 1, std::vector<Real>(static_cast<std::size_t>(n), 0.0)};
  PointField volume{"particle_volume", 1, std::vector<Real>(static_cast<std::size_t>(n), 0.0)};
  PointField material_id{"material_id", 1, std::vector<Real>(static_cast<std::size_t>(n), 0.0)};
  for (Index p = 0; p < n; ++p) {
    const auto s = static_cast<std::size_t>(p);
    volume.values[s] = problem_.thickness * discretization_.area_weight[p];
    material_id.values[s] = problem_.material_of_particle[s];
    if (!solved_) continue;
    displacement.values[3 * s] = u_[2 * p];
    displacement.values[3 * s + 1] = u_[2 * p + 1];
    const PlaneMaterial& m = materials_[static_cast<std::size_t>(problem_.material_of_particle[s])];
    const material::Voigt e = to_voigt(strain_.col(p), m.plane == PlaneKind::stress ? out_of_plane_[p] : 0.0);
    const material::Voigt sg = to_voigt(stress_.col(p), m.plane == PlaneKind::strain ? out_of_plane_[p] : 0.0);
    for (int c = 0; c < 6; ++c) strain.values[6 * s + c] = e[c], stress.values[6 * s + c] = sg[c];
    mises.values[s] = material::von_mises(sg);
  }
  f.point_fields = {displacement, strain, stress, mises, volume, material_id};
  return f;
}

RunCounts MpfemAnalysis::counts() const {
  RunCounts c;
  c.nodes = problem_.layout.positions.cols();
  c.dofs = 2 * c.nodes;
  c.steps = problem_.options.analysis == MpfemAnalysisKind::large_deformation ? std::max<Index>(1, stats_.increments) : 1;
  return c;
}

}  // namespace lamina::mpfem
