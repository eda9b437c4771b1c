// MpmAnalysis results: probes, built-in probes, output frames (nodal fields for VTU), warnings,
// counts and stage timings (the Analysis / output-sink interface, core/analysis.hpp).
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "mpm/mpm_analysis.hpp"

namespace lamina::mpm {

Real MpmAnalysis::probe(const Probe& p) const {
  auto component_of = [&](const Vec3& value) -> Real {
    if (p.component == "x") return value.x();
    if (p.component == "y") return value.y();
    if (p.component == "z") return value.z();
    if (p.component == "magnitude") return value.norm();
    throw InputError("probes." + p.name + ".component", "x, y, z or magnitude", p.component);
  };
  auto nearest = [&]() -> Index {
    const Vec3 at = p.at.value_or(Vec3::Zero());
    Index best = -1;
    Real best_d = INFINITY;
    auto consider = [&](Index i) {
      const Real d = (reference_.col(i) - at).squaredNorm();
      if (d < best_d) best_d = d, best = i;
    };
    if (p.nearest_in_set && !p.nodes.empty())
      for (Index i : p.nodes) consider(i);
    else
      for (Index i = 0; i < reference_.cols(); ++i) consider(i);
    return best;
  };
  if (p.field == "displacement") return component_of(x_.col(nearest()) - reference_.col(nearest()));
  if (p.field == "velocity") return component_of(vpos_.col(nearest()));
  if (p.field == "rotation_velocity") return component_of(omega_.col(nearest()));
  if (p.field == "reaction_force") {
    Vec3 sum = Vec3::Zero();
    for (Index i : p.nodes) sum += f_int_.col(i) - f_ext_.col(i);
    return component_of(sum);
  }
  if (p.field == "plastic_strain") {
    if (p.component == "max") {
      Real worst = 0.0;
      for (Index e = 0; e < problem_.mesh.element_count(); ++e) worst = std::max(worst, element_plastic_strain(e));
      return worst;
    }
    return nodal_plastic_strain(nearest());
  }
  if (p.field == "energy") {
    if (p.component == "internal") return energy_.internal;
    if (p.component == "kinetic") return energy_.kinetic;
    if (p.component == "external") return energy_.external;
    if (p.component == "hourglass") return energy_.hourglass;
    if (p.component == "damping") return energy_.damping;
    if (p.component == "transfer") return energy_.transfer;
    if (p.component == "total") return energy_.total();
    if (p.component == "contact") return 0.0;
    throw InputError("probes." + p.name + ".component", "internal, kinetic, external, hourglass, damping, transfer, total or contact", p.component);
  }
  throw InputError("probes." + p.name + ".field",
                   "displacement, velocity, rotation_velocity, reaction_force, plastic_strain or energy (mpm)", p.field);
}

Real MpmAnalysis::element_plastic_strain(Index e) const {
  Real worst = 0.0;
  const int stride = element_->point_stride();
  for (int q = 0; q < element_->thickness_points(); ++q)
    worst = std::max(worst, material_->plastic_strain(stress_.col(e).data() + q * stride));
  return worst;
}

Real MpmAnalysis::nodal_plastic_strain(Index i) const {
  const Index begin = incidence_begin_[static_cast<std::size_t>(i)], end = incidence_begin_[static_cast<std::size_t>(i + 1)];
  Real sum = 0.0;
  for (Index k = begin; k < end; ++k) sum += element_plastic_strain(incidence_[static_cast<std::size_t>(k)] / 4);
  return end > begin ? sum / static_cast<Real>(end - begin) : 0.0;
}

std::map<std::string, Real> MpmAnalysis::builtin_probes() const {
  return {{"energy_kinetic", energy_.kinetic},
          {"energy_internal", energy_.internal},
          {"energy_hourglass", energy_.hourglass},
          {"energy_external", energy_.external},
          {"energy_damping", energy_.damping},
          {"energy_transfer", energy_.transfer},
          {"energy_total", energy_.total()},
          {"energy_ratio", energy_.ratio()},
          {"hourglass_ratio", energy_.internal > 0 ? energy_.hourglass / energy_.internal : 0.0},
          {"residual_ratio", residual_ratio_},
          {"time_step", dt_},
          {"unconverged_levels", static_cast<Real>(unconverged_levels_.size())},
          {"time_step_grid_controlled", dt_control_ == "grid" ? 1.0 : 0.0},
          {"newton_iterations", static_cast<Real>(newton_iterations_)},
          {"newton_increments", static_cast<Real>(newton_increments_)},
          {"newton_stopped_levels", static_cast<Real>(newton_stopped_levels_)},
          {"newton_first_stop_load", newton_first_stop_load_},
          {"newton_jumps", static_cast<Real>(newton_jumps_)},
          {"newton_first_jump_load", newton_first_jump_load_},
          {"newton_largest_energy_gap", newton_largest_gap_}};
}

OutputFrame MpmAnalysis::frame() const {
  const ShellMesh& mesh = problem_.mesh;
  const Index n = x_.cols(), e_count = mesh.element_count();
  OutputFrame f;
  f.points = x_;
  f.cell_vertices = 4;
  f.cell_connectivity.resize(static_cast<std::size_t>(4 * e_count));
  for (Index e = 0; e < e_count; ++e)
    for (int a = 0; a < 4; ++a) f.cell_connectivity[static_cast<std::size_t>(4 * e + a)] = mesh.quads(a, e);
  auto vector_field = [&](const std::string& name, const Eigen::Matrix3Xd& m) {
    PointField p{name, 3, std::vector<Real>(static_cast<std::size_t>(3 * n))};
    for (Index i = 0; i < n; ++i)
      for (int a = 0; a < 3; ++a) p.values[static_cast<std::size_t>(3 * i + a)] = m(a, i);
    f.point_fields.push_back(std::move(p));
  };
  vector_field("displacement", x_ - reference_);
  vector_field("velocity", vpos_);
  vector_field("angular_velocity", omega_);
  // element resultants averaged to the nodes (local element frames)
  PointField thickness{"thickness", 1, std::vector<Real>(static_cast<std::size_t>(n), 0.0)};
  PointField membrane{"membrane_force", 6, std::vector<Real>(static_cast<std::size_t>(6 * n), 0.0)};
  PointField moment{"bending_moment", 6, std::vector<Real>(static_cast<std::size_t>(6 * n), 0.0)};
  for (Index i = 0; i < n; ++i) {
    const Index count = incidence_begin_[static_cast<std::size_t>(i + 1)] - incidence_begin_[static_cast<std::size_t>(i)];
    for (Index k = incidence_begin_[static_cast<std::size_t>(i)]; k < incidence_begin_[static_cast<std::size_t>(i + 1)]; ++k) {
      const Index e = incidence_[static_cast<std::size_t>(k)] / 4;
      const shell::ShellResultants r = element_->resultants(stress_.col(e).data(), thickness_[e]);
      const Real w = 1.0 / static_cast<Real>(count);
      thickness.values[static_cast<std::size_t>(i)] += w * thickness_[e];
      const Real nv[6] = {r.nxx, r.nyy, 0.0, r.nxy, r.qyz, r.qxz}, mv[6] = {r.mxx, r.myy, 0.0, r.mxy, 0.0, 0.0};
      for (int c = 0; c < 6; ++c) {
        membrane.values[static_cast<std::size_t>(6 * i + c)] += w * nv[c];
        moment.values[static_cast<std::size_t>(6 * i + c)] += w * mv[c];
      }
    }
  }
  f.point_fields.push_back(std::move(thickness));
  f.point_fields.push_back(std::move(membrane));
  f.point_fields.push_back(std::move(moment));
  if (material_->is_plastic()) {
    // equivalent plastic strain: per element the largest over the through-thickness points, averaged to the nodes
    PointField plastic{"plastic_strain", 1, std::vector<Real>(static_cast<std::size_t>(n), 0.0)};
    for (Index i = 0; i < n; ++i) plastic.values[static_cast<std::size_t>(i)] = nodal_plastic_strain(i);
    f.point_fields.push_back(std::move(plastic));
  }
  return f;
}

std::vector<std::string> MpmAnalysis::warnings() const {
  std::vector<std::string> out;
  const shell::ShellSection& s = problem_.section;
  // rz held at most nodes (a habit from codes without drilling stiffness): with the drilling penalty that
  // also holds the elements' in-plane rotation there
  if (s.hourglass_model == shell::HourglassModel::physical && s.drilling > 0.0 && rotation_free_.cols() > 0) {
    const Index held = (rotation_free_.row(2).array() == 0.0).count();
    if (2 * held > rotation_free_.cols())
      out.push_back(fmt::format("rz is fixed at {} of {} nodes: the drilling penalty (shell.drilling = {:g}) ties rz to the "
                                "in-plane rotation of the elements, so this also holds that rotation and stiffens "
                                "in-plane bending; leave rz free (the penalty already removes the drilling singularity) "
                                "or set shell.drilling: 0",
                                held, rotation_free_.cols(), s.drilling));
  }
  const MpmOptions& o = problem_.options;
  if (o.analysis == MpmOptions::Kind::quasi_static && o.solver == MpmOptions::Solver::newton) {
    std::vector<std::string> unused;  // explicit-dynamics settings a Newton level does not use
    if (o.fixed_time_step > 0) unused.push_back("time_step.fixed");
    if (o.level_ramp_steps > 0) unused.push_back("level_ramp_steps");
    if (o.mass_damping > 0) unused.push_back("damping.mass");
    if (o.flip > 0) unused.push_back("flip");
    if (!unused.empty())
      out.push_back(fmt::format("mpm.{} set with the Newton quasi-static solver (the default): it acts only in a level "
                                "Newton cannot finish, which goes on by explicit dynamics; mpm.solver: explicit runs every "
                                "level that way",
                                fmt::join(unused, ", mpm.")));
  }
  if (problem_.material.model != material::MaterialModel::j2_plasticity) return out;
  if (element_->thickness_points() <= 3)
    out.push_back(fmt::format("shell.thickness_points = {} with j2_plasticity: so few points cannot represent plastic "
                              "bending (3 Lobatto points carry at most the first-yield moment, a real section 1.5 x); use 7 "
                              "(the default with a plastic material)",
                              element_->thickness_points()));
  if (o.analysis == MpmOptions::Kind::quasi_static && o.solver == MpmOptions::Solver::explicit_dynamics && o.level_ramp_steps == 0)
    out.push_back("mpm.level_ramp_steps = 0 with j2_plasticity: each load increment is applied at once and its dynamic "
                  "overshoot yields the material early; ramp it over a few thousand steps");
  const Real membrane = s.hourglass_membrane >= 0.0 ? s.hourglass_membrane : s.hourglass;
  if (s.hourglass_model == shell::HourglassModel::coefficients && membrane >= 0.05)
    out.push_back(fmt::format("shell hourglass coefficient {:g} on the membrane modes with j2_plasticity: the elastic "
                              "hourglass resistance stiffens plastic folds (crush forces too high, watch hourglass_ratio); "
                              "shell.hourglass_membrane: 0.01 to 0.03 is usual for crush",
                              membrane));
  return out;
}

RunCounts MpmAnalysis::counts() const {
  RunCounts c;
  c.nodes = x_.cols();
  c.dofs = 6 * x_.cols();
  c.steps = steps_;
  return c;
}

std::map<std::string, Real> MpmAnalysis::timings() const {
  std::map<std::string, Real> t;
  for (std::size_t k = 0; k < stages_.size(); ++k) t[std::string(stages_[k].name) + "_s"] = stage_time_[k];
  // how often the grid's connectivity was built (this rank's grid; the first build included): a count, not a
  // time, beside the stage times that it explains (the `update` stage re-sorts the corners at each rebuild)
  t["grid_rebuilds"] = static_cast<Real>(grid_.connectivity_version());
  if (problem_.options.solver == MpmOptions::Solver::newton) {
    t["newton_forces_s"] = newton_time_[0];
    t["newton_tangent_s"] = newton_time_[1];
    t["newton_solve_s"] = newton_time_[2];
  }
  return t;
}

}  // namespace lamina::mpm
