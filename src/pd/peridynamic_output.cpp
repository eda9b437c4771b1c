// PeridynamicAnalysis results: probes (nearest node, reactions, strain / stress from the family's
// least-squares displacement gradient), built-in probes, output frames and counts.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "material/linear_elastic.hpp"
#include "pd/load_path_events.hpp"
#include "pd/peridynamic_analysis.hpp"

namespace lamina::pd {

Index PeridynamicAnalysis::nearest_node(const Vec3& x, const IndexList& candidates) const {
  Index best = 0;
  Real best_distance = INFINITY;
  auto consider = [&](Index i) {
    const Real d = (problem_.positions.col(i) - x).squaredNorm();
    if (d < best_distance) {
      best_distance = d;
      best = i;
    }
  };
  if (candidates.empty())
    for (Index i = 0; i < body_->nodes(); ++i) consider(i);
  else
    for (Index i : candidates) consider(i);
  return best;
}

Vec3 PeridynamicAnalysis::reaction(const IndexList& nodes) const {
  Vec3 sum = Vec3::Zero();
  for (Index i : nodes) sum -= internal_force_.col(i) + external_force_.col(i);
  return sum;
}

Vec3 PeridynamicAnalysis::strain_gradient_at(Index i, Mat3& gradient) const {
  Mat3 shape = Mat3::Zero(), deformation = Mat3::Zero();
  const bool planar = body_->dimension() == 2;
  for (Index b = body_->first_bond(i); b < body_->end_bond(i); ++b) {
    const Index j = body_->neighbour(b);
    Vec3 xi = body_->positions().col(j) - body_->positions().col(i);
    Vec3 du = u_.col(j) - u_.col(i);
    if (planar) {
      xi.z() = 0;
      du.z() = 0;
    }
    shape += body_->bond_volume_of(i, b) * xi * xi.transpose();
    deformation += body_->bond_volume_of(i, b) * du * xi.transpose();
  }
  if (planar) shape(2, 2) = 1.0;
  gradient = deformation * shape.inverse();
  return gradient.diagonal();
}

Real PeridynamicAnalysis::probe(const Probe& p) const { return ranks_ ? distributed_probe(p) : local_probe(p); }

Real PeridynamicAnalysis::distributed_probe(const Probe& p) const {
  Probe local = p;  // the selection's nodes this rank owns, as local indices
  local.nodes.clear();
  for (Index g : p.nodes) {
    const Index k = ranks_->local_of(g);
    if (k >= 0 && ranks_->owns(k)) local.nodes.push_back(k);
  }
  if (p.field == "reaction_force") {
    const Vec3 r = reaction(local.nodes);
    std::vector<Real> sum{r.x(), r.y(), r.z()};
    comm_.sum(sum);
    const Vec3 total(sum[0], sum[1], sum[2]);
    if (p.component == "magnitude") return total.norm();
    return total[p.component == "x" ? 0 : p.component == "y" ? 1 : 2];
  }
  if (p.field == "energy" || p.field == "eigenvalue" || p.field == "critical_load") return local_probe(p);
  // a node's value: each rank's nearest owned candidate, the nearest of those (ties: the lower global
  // index, as one process takes the first), evaluated by its owner
  Real distance = INFINITY;
  Index node = -1;
  if (p.at) {
    auto consider = [&](Index k) {
      const Real d = (problem_.positions.col(k) - *p.at).squaredNorm();
      if (d < distance) distance = d, node = k;
    };
    if (p.nodes.empty()) {
      for (Index k = 0; k < body_->nodes(); ++k)
        if (ranks_->owns(k)) consider(k);
    } else {
      for (Index k : local.nodes) consider(k);
    }
  } else if (!p.nodes.empty()) {
    const Index k = ranks_->local_of(p.nodes.front());
    if (k >= 0 && ranks_->owns(k)) distance = 0, node = k;
  }
  const Real global_node = node >= 0 ? static_cast<Real>(ranks_->global[static_cast<std::size_t>(node)]) : INFINITY;
  const std::vector<Real> all = comm_.all_gather(std::vector<Real>{distance, global_node});
  int winner = 0;
  for (int r = 1; r < comm_.size(); ++r) {
    const Real d = all[2 * static_cast<std::size_t>(r)], g = all[2 * static_cast<std::size_t>(r) + 1];
    const Real bd = all[2 * static_cast<std::size_t>(winner)], bg = all[2 * static_cast<std::size_t>(winner) + 1];
    if (d < bd || (d == bd && g < bg)) winner = r;
  }
  Real value = 0;
  if (winner == comm_.rank() && node >= 0) {
    Probe single = p;
    single.at.reset();
    single.nodes = {node};
    value = local_probe(single);
  }
  return comm_.sum(value);
}

Real PeridynamicAnalysis::local_probe(const Probe& p) const {
  auto component_of = [&](const Vec3& v) {
    if (p.component == "magnitude") return v.norm();
    return v[p.component == "x" ? 0 : p.component == "y" ? 1 : 2];
  };
  if (p.field == "displacement" || p.field == "velocity") {
    const Index i = p.at ? nearest_node(*p.at, p.nodes) : p.nodes.front();
    return component_of(p.field == "displacement" ? Vec3(u_.col(i)) : Vec3(velocity_.col(i)));
  }
  if (p.field == "reaction_force") return component_of(reaction(p.nodes));
  if (p.field == "energy") {
    if (p.component == "internal") return energy_internal_;
    if (p.component == "kinetic") return energy_kinetic_;
    if (p.component == "external") return energy_external_;
    if (p.component == "damping") return energy_damping_;
    return energy_internal_ + energy_kinetic_;
  }
  if (p.field == "eigenvalue") {
    const std::size_t k = static_cast<std::size_t>(std::stoi(p.component)) - 1;
    return k < eigenvalues_.size() ? eigenvalues_[k] : std::nan("");
  }
  if (p.field == "critical_load") {
    // eigenvalue k times the force the selection carries in the reference pre-buckling state (the
    // buckling load of a displacement-controlled pre-load: prescribed edge shortening, clamped edges)
    const std::size_t k = static_cast<std::size_t>(std::stoi(p.component)) - 1;
    if (k >= eigenvalues_.size()) return std::nan("");
    Vec3 carried = Vec3::Zero();
    for (Index i : p.nodes) carried += external_force_.col(i);
    if (carried.norm() == 0) carried = reaction(p.nodes);
    return eigenvalues_[k] * carried.norm();
  }
  // strain / stress at the nearest node
  const Index i = p.at ? nearest_node(*p.at, p.nodes) : p.nodes.front();
  Mat3 eps;
  if (!state_ || !model_->node_strain(*state_, i, eps)) {
    Mat3 g;
    strain_gradient_at(i, g);
    eps = 0.5 * (g + g.transpose());
  }
  const std::map<std::string, std::pair<int, int>> index{{"xx", {0, 0}}, {"yy", {1, 1}}, {"zz", {2, 2}},
                                                          {"xy", {0, 1}}, {"yz", {1, 2}}, {"zx", {2, 0}}};
  if (p.field == "strain") {
    const auto [a, b] = index.at(p.component);
    return eps(a, b);
  }
  const Real e = problem_.young[i], nu = problem_.poisson[i];
  const material::LinearElastic elastic{e, nu};
  const Real mu = elastic.mu(), lambda = elastic.lambda();
  Mat3 sigma;
  if (body_->options().kinematics == Kinematics::plane_stress) {
    const Real c = elastic.plane_stress_modulus();
    sigma.setZero();
    sigma(0, 0) = c * (eps(0, 0) + nu * eps(1, 1));
    sigma(1, 1) = c * (eps(1, 1) + nu * eps(0, 0));
    sigma(0, 1) = sigma(1, 0) = 2 * mu * eps(0, 1);
  } else {
    Mat3 strain = eps;
    if (body_->dimension() == 2) strain.row(2).setZero(), strain.col(2).setZero();
    sigma = lambda * strain.trace() * Mat3::Identity() + 2 * mu * strain;
  }
  if (p.component == "von_mises") {
    const Mat3 dev = sigma - sigma.trace() / 3 * Mat3::Identity();
    return std::sqrt(1.5 * dev.squaredNorm());
  }
  const auto [a, b] = index.at(p.component);
  return sigma(a, b);
}

std::map<std::string, Real> PeridynamicAnalysis::builtin_probes() const {
  switch (problem_.analysis) {
    case PdAnalysisKind::quasi_static: {
      std::map<std::string, Real> values{{"iterations", static_cast<Real>(last_iterations_)},
                                         {"total_iterations", static_cast<Real>(total_iterations_)},
                                         {"residual", last_residual_},
                                         {"damping_energy", energy_damping_},
                                         {"path_load", path_load_.empty() ? 0.0 : path_load_.back()},
                                         {"path_displacement", path_displacement_.empty() ? 0.0 : path_displacement_.back()}};
      Real ratio = 1.0;
      const std::size_t m = path_load_.size();
      if (m >= 3) {
        const Real k0 = (path_load_[1] - path_load_[0]) / (path_displacement_[1] - path_displacement_[0]);
        const Real k = (path_load_[m - 1] - path_load_[m - 2]) / (path_displacement_[m - 1] - path_displacement_[m - 2]);
        ratio = k / k0;
      }
      values["tangent_stiffness_ratio"] = std::isfinite(ratio) ? ratio : 0.0;
      const auto events = detect_stiffness_changes(path_load_, path_displacement_);
      values["stiffness_changes"] = static_cast<Real>(events.size());
      // the linear buckling load of the case's loads (imperfection: buckling_mode), and the first
      // stiffness change relative to it
      const Real linear = imperfection_load_factor_ * path_total_;
      values["linear_buckling_load"] = linear;
      values["first_buckling_ratio"] = linear > 0 && !events.empty() ? events[0].load / linear : 0.0;
      for (std::size_t k = 0; k < 3; ++k) {
        values[fmt::format("stiffness_change_{}_load", k + 1)] = k < events.size() ? events[k].load : 0.0;
        values[fmt::format("stiffness_change_{}_ratio", k + 1)] = k < events.size() ? events[k].stiffness_ratio : 0.0;
      }
      return values;
    }
    case PdAnalysisKind::explicit_dynamics:
      return {{"kinetic_energy", energy_kinetic_},
              {"strain_energy", energy_internal_},
              {"external_work", energy_external_},
              {"energy_error", timings_.count("energy_error") ? timings_.at("energy_error") : energy_error_}};
    case PdAnalysisKind::buckling: {
      std::map<std::string, Real> values;
      for (int k = 0; k < problem_.buckling.modes; ++k)
        values[fmt::format("load_factor_{}", k + 1)] =
            static_cast<std::size_t>(k) < eigenvalues_.size() ? eigenvalues_[static_cast<std::size_t>(k)] : 0.0;
      return values;
    }
    default: return {};
  }
}

OutputFrame PeridynamicAnalysis::frame() const {
  OutputFrame f;
  const Index n = body_->nodes();
  f.points = problem_.positions;
  auto vector_field = [&](const std::string& name, const PointMatrix& values) {
    PointField field{name, 3, std::vector<Real>(values.data(), values.data() + values.size())};
    f.point_fields.push_back(std::move(field));
  };
  vector_field("displacement", u_);
  vector_field("velocity", velocity_);
  vector_field("internal_force", internal_force_);
  const Eigen::VectorXd total_dilatation = model_->nodal_dilatation(*state_);
  PointField dilatation{"dilatation", 1, std::vector<Real>(total_dilatation.data(), total_dilatation.data() + n)};
  f.point_fields.push_back(std::move(dilatation));
  for (std::size_t k = 0; k < modes_.size(); ++k) vector_field(fmt::format("mode_{}", k + 1), modes_[k]);
  if (!ranks_) return f;
  // several ranks: the rank's own nodes (its VTU piece)
  std::vector<Index> own;
  for (Index k = 0; k < n; ++k)
    if (ranks_->owns(k)) own.push_back(k);
  OutputFrame piece;
  piece.points.resize(3, static_cast<Index>(own.size()));
  for (std::size_t k = 0; k < own.size(); ++k) piece.points.col(static_cast<Index>(k)) = f.points.col(own[k]);
  for (const PointField& field : f.point_fields) {
    PointField part{field.name, field.components, {}};
    for (Index k : own)
      for (int c = 0; c < field.components; ++c) part.values.push_back(field.values[static_cast<std::size_t>(k * field.components + c)]);
    piece.point_fields.push_back(std::move(part));
  }
  return piece;
}

RunCounts PeridynamicAnalysis::counts() const {
  RunCounts c;
  c.nodes = ranks_ ? ranks_->global_count : body_->nodes();
  c.dofs = 3 * c.nodes;
  c.steps = steps_;
  return c;
}

}  // namespace lamina::pd
