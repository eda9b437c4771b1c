#include "mpm/mpm_analysis.hpp"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "mpm/mass_scaling.hpp"

namespace lamina::mpm {

namespace {

class StageTimer {
 public:
  StageTimer(std::map<std::string, Real>& table, const char* name) : table_(table), name_(name), start_(omp_get_wtime()) {}
  ~StageTimer() { table_[name_] += omp_get_wtime() - start_; }

 private:
  std::map<std::string, Real>& table_;
  const char* name_;
  double start_;
};

// mass scaling: the fictitious masses are recomputed from the current tangent this often (and at each level)
constexpr Index kMassRefreshSteps = 1000;

Real field_value(const geometry::ScalarField& f, const geometry::Expression* e, const Vec3& x, Real t) {
  return f.is_constant() ? f.constant : e->evaluate(x, t);
}

}  // namespace

MpmAnalysis::~MpmAnalysis() = default;

MpmAnalysis::MpmAnalysis(MpmProblem problem, std::vector<Probe> probes)
    : problem_(std::move(problem)), probes_(std::move(probes)), grid_(Vec3::Zero(), 1.0) {
  const ShellMesh& mesh = problem_.mesh;
  const MpmOptions& o = problem_.options;
  if (!(problem_.density > 0)) throw InputError("materials.0.density", "a positive density (mpm is a dynamic method)", "none or <= 0");
  if (problem_.material == MpmProblem::Material::j2_plasticity && !(problem_.yield_stress > 0))
    throw InputError("materials.0.yield", "a positive yield stress", fmt::format("{}", problem_.yield_stress));
  for (std::size_t k = 0; k < probes_.size(); ++k)
    if (probes_[k].field == "plastic_strain" && problem_.material != MpmProblem::Material::j2_plasticity)
      throw InputError(fmt::format("probes.{}.field", k), "a field of this material (plastic_strain needs model: j2_plasticity)",
                       "plastic_strain");
  if (!(mesh.thickness > 0)) throw InputError("geometry.thickness", "a positive shell thickness", fmt::format("{}", mesh.thickness));
  if (problem_.poisson <= -1.0 || problem_.poisson >= 0.5 || !(problem_.young > 0))
    throw InputError("materials.0", "E > 0 and -1 < nu < 0.5", fmt::format("E = {}, nu = {}", problem_.young, problem_.poisson));
  Cpdi2Domains domains(mesh, problem_.density);
  if (!domains.defects().empty()) {
    std::vector<Diagnostic> problems;
    for (const auto& d : domains.defects()) {
      problems.push_back(Diagnostic{"", 0, 0, "discretization.elements",
                                    "a shell mesh of valid quadrilaterals (positive area, convex, consistently oriented)",
                                    fmt::format("element {}: {}", d.element, d.what)});
      if (problems.size() >= 10) break;
    }
    throw InputError(problems);
  }
  const Index n = mesh.node_count(), e_count = mesh.element_count();
  for (Index i = 0; i < n; ++i)
    if (!(domains.node_mass()[i] > 0))
      throw InputError("discretization.elements", "every node in at least one element", fmt::format("node {} belongs to no element", i));

  // grid: cell from the options or the median edge; must resolve the elements (and the thickness)
  const Real cell = o.grid_cell > 0 ? o.grid_cell : 0.5 * domains.median_edge();
  const Real coarsest = 1.5 * domains.median_edge();
  if (cell > coarsest)
    throw InputError("discretization.grid.cell",
                     fmt::format("a grid cell of at most 1.5 x the median element edge ({:.4g}): a coarser grid lumps "
                                 "several shell nodes into one grid node, filters the bending of the shell (thickness {:.4g}) "
                                 "and makes its two faces and neighbouring folds stick",
                                 coarsest, mesh.thickness),
                     fmt::format("{:.4g}", cell));
  if (cell < 1e-3 * domains.shortest_edge())
    throw InputError("discretization.grid.cell", fmt::format("a grid cell above 1e-3 x the shortest element edge ({:.4g})",
                                                             1e-3 * domains.shortest_edge()),
                     fmt::format("{:.4g}", cell));
  const Vec3 lower = mesh.nodes.rowwise().minCoeff();
  grid_ = BackgroundGrid(lower - Vec3::Constant(cell), cell);

  if (problem_.material == MpmProblem::Material::neo_hookean)
    material_ = std::make_unique<shell::NeoHookeanShellMaterial>(problem_.young, problem_.poisson, problem_.density);
  else if (problem_.material == MpmProblem::Material::j2_plasticity)
    material_ = std::make_unique<shell::J2PlasticShellMaterial>(problem_.young, problem_.poisson, problem_.density,
                                                                problem_.yield_stress, problem_.hardening);
  else
    material_ = std::make_unique<shell::LinearElasticShellMaterial>(problem_.young, problem_.poisson, problem_.density);
  element_ = std::make_unique<shell::BelytschkoTsayShell>(problem_.section, *material_);
  wave_speed_ = material_->dilatational_wave_speed();

  reference_ = mesh.nodes;
  x_ = mesh.nodes;
  v_ = PointMatrix::Zero(3, n);
  vpos_ = PointMatrix::Zero(3, n);
  omega_ = PointMatrix::Zero(3, n);
  mass_ = domains.node_mass();
  inertia_ = domains.node_inertia();
  free_ = Eigen::Matrix3Xd::Ones(3, n);
  rotation_free_ = Eigen::Matrix3Xd::Ones(3, n);
  f_int_ = m_int_ = f_ext_ = m_ext_ = f_net_ = Eigen::Matrix3Xd::Zero(3, n);

  for (const auto& c : problem_.constraints)
    for (Index node : c.nodes)
      for (int a = 0; a < 3; ++a) {
        if (c.fixed[static_cast<std::size_t>(a)] || c.velocity[static_cast<std::size_t>(a)]) free_(a, node) = 0.0;
        if (c.fixed[static_cast<std::size_t>(a + 3)]) rotation_free_(a, node) = 0.0;
      }
  for (const auto& l : problem_.loads) {
    if (l.kind == NodalLoad::Kind::mass) {
      const Real each = l.scalar.constant / static_cast<Real>(l.nodes.size());
      for (Index node : l.nodes) mass_[node] += each;
    } else if (l.kind == NodalLoad::Kind::initial_velocity) {
      for (Index node : l.nodes)
        for (int a = 0; a < 3; ++a) {
          const auto& f = l.vector[static_cast<std::size_t>(a)];
          const Real value = f.is_constant() ? f.constant : geometry::Expression(f.expression).evaluate(reference_.col(node), 0.0);
          v_(a, node) = value * free_(a, node);
          vpos_(a, node) = v_(a, node);
        }
    }
  }

  // node -> (element, corner) incidence
  incidence_begin_.assign(static_cast<std::size_t>(n + 1), 0);
  for (Index e = 0; e < e_count; ++e)
    for (int a = 0; a < 4; ++a) ++incidence_begin_[static_cast<std::size_t>(mesh.quads(a, e) + 1)];
  for (Index i = 0; i < n; ++i) incidence_begin_[static_cast<std::size_t>(i + 1)] += incidence_begin_[static_cast<std::size_t>(i)];
  incidence_.assign(static_cast<std::size_t>(4 * e_count), 0);
  std::vector<Index> fill(incidence_begin_.begin(), incidence_begin_.end() - 1);
  for (Index e = 0; e < e_count; ++e)
    for (int a = 0; a < 4; ++a) incidence_[static_cast<std::size_t>(fill[static_cast<std::size_t>(mesh.quads(a, e))]++)] = 4 * e + a;

  stress_ = Eigen::MatrixXd::Zero(element_->stress_size(), e_count);
  hourglass_.setZero(shell::BelytschkoTsayShell::kHourglassSize, e_count);
  thickness_ = Eigen::VectorXd::Constant(e_count, mesh.thickness);
  element_power_ = element_hourglass_power_ = element_length_ = Eigen::VectorXd::Zero(e_count);
  element_force_ = element_moment_ = Eigen::Matrix<Real, 12, Eigen::Dynamic>::Zero(12, e_count);
  grid_.locate(x_);
  prepare_loads();
  dyn_mass_ = mass_;
  dyn_inertia_ = inertia_;
  scaled_ = o.analysis == MpmOptions::Kind::quasi_static && o.mass_scaling;
  if (scaled_) {
    level_start_ = x_;
    theta_ = PointMatrix::Zero(3, n);
    f_int_previous_ = m_int_previous_ = Eigen::Matrix3Xd::Zero(3, n);
  }
  energy_.kinetic = energy_.initial_kinetic = 0.5 * (v_.colwise().squaredNorm() * dyn_mass_)(0);
}

void MpmAnalysis::compute_fictitious_masses() {
  StageTimer timer(stage_seconds_, "mass_scaling");
  stiffness_proportional_masses(*element_, problem_.mesh, x_, stress_, hourglass_, thickness_, incidence_begin_, incidence_,
                                dyn_mass_, dyn_inertia_);
  node_mass_.resize(3, 0);  // the grid's copy is rebuilt from the new masses
  masses_age_ = 0;
  masses_stale_ = false;
}

Real MpmAnalysis::adaptive_damping_coefficient() const {
  // u: the increment since the level started; local stiffness k_d = (f_d^n - f_d^{n-1}) / (m_d dt v_d^{n-1/2})
  const Index n = x_.cols();
  Real numerator = 0, denominator = 0;
  for (Index i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) {
      if (free_(a, i) > 0) {
        const Real u = x_(a, i) - level_start_(a, i), v = vpos_(a, i);
        denominator += u * u;
        if (v != 0) numerator += u * u * (f_int_(a, i) - f_int_previous_(a, i)) / (dyn_mass_[i] * dt_previous_ * v);
      }
      if (rotation_free_(a, i) > 0) {
        const Real u = theta_(a, i), w = omega_(a, i);
        denominator += u * u;
        if (w != 0) numerator += u * u * (m_int_(a, i) - m_int_previous_(a, i)) / (dyn_inertia_[i] * dt_previous_ * w);
      }
    }
  if (!(denominator > 0) || !(numerator > 0)) return 0.0;
  return std::min(1.9, 2.0 * std::sqrt(numerator / denominator));
}

void MpmAnalysis::begin_level() {
  if (!scaled_) return;
  level_start_ = x_;
  theta_.setZero();
  masses_stale_ = true;
}

void MpmAnalysis::compute_internal_forces(Real dt_stress) {
  const ShellMesh& mesh = problem_.mesh;
  const Index e_count = mesh.element_count();
  Index bad = -1;
  {
    StageTimer t(stage_seconds_, "element");
    // mid-step configuration x^{n-1/2}: the chord velocity of a finite rigid rotation is a rigid
    // velocity field there (no spurious strain), and the strain increments integrate to second order
    x_mid_ = x_ - 0.5 * dt_stress * vpos_;
#pragma omp parallel for schedule(static) reduction(max : bad) if (e_count > 256)
    for (Index e = 0; e < e_count; ++e) {
      shell::NodeMatrix x, v, w;
      for (int a = 0; a < 4; ++a) {
        const Index node = mesh.quads(a, e);
        x.col(a) = x_mid_.col(node);
        v.col(a) = vpos_.col(node);
        w.col(a) = omega_.col(node);
      }
      Real h = thickness_[e];
      const shell::ShellElementResult r = element_->update(x, v, w, dt_stress, stress_.col(e).data(), hourglass_.col(e).data(), h);
      if (!r.valid || !std::isfinite(h) || !(h > 0)) {
        bad = std::max(bad, e);
        continue;
      }
      thickness_[e] = h;
      element_power_[e] = r.internal_power;
      element_hourglass_power_[e] = r.hourglass_power;
      element_length_[e] = r.characteristic_length;
      element_force_.col(e) = Eigen::Map<const Eigen::Matrix<Real, 12, 1>>(r.force.data());
      element_moment_.col(e) = Eigen::Map<const Eigen::Matrix<Real, 12, 1>>(r.moment.data());
    }
  }
  if (bad >= 0)
    throw AnalysisError(fmt::format("element {} became degenerate or inverted at step {} (time {:.6g}): the run is unstable "
                                    "or the deformation too large for the mesh",
                                    bad, steps_, time_));
  StageTimer t(stage_seconds_, "gather");
  const Index n = x_.cols();
#pragma omp parallel for schedule(static) if (n > 1024)
  for (Index i = 0; i < n; ++i) {
    Vec3 f = Vec3::Zero(), m = Vec3::Zero();
    for (Index k = incidence_begin_[static_cast<std::size_t>(i)]; k < incidence_begin_[static_cast<std::size_t>(i + 1)]; ++k) {
      const Index entry = incidence_[static_cast<std::size_t>(k)], e = entry / 4;
      const int a = static_cast<int>(entry % 4);
      f += element_force_.block<3, 1>(3 * a, e);
      m += element_moment_.block<3, 1>(3 * a, e);
    }
    f_int_.col(i) = f;
    m_int_.col(i) = m;
  }
}

void MpmAnalysis::prepare_loads() {
  const ShellMesh& mesh = problem_.mesh;
  std::map<std::pair<Index, Index>, int> uses;
  for (Index e = 0; e < mesh.element_count(); ++e)
    for (int a = 0; a < 4; ++a) {
      const Index p = mesh.quads(a, e), q = mesh.quads((a + 1) % 4, e);
      ++uses[{std::min(p, q), std::max(p, q)}];
    }
  for (const auto& l : problem_.loads) {
    PreparedLoad prepared;
    for (int a = 0; a < 3; ++a)
      if (!l.vector[static_cast<std::size_t>(a)].is_constant())
        prepared.expressions[static_cast<std::size_t>(a)] = std::make_shared<geometry::Expression>(l.vector[static_cast<std::size_t>(a)].expression);
    if (!l.scalar.is_constant()) prepared.scalar_expression = std::make_shared<geometry::Expression>(l.scalar.expression);
    std::vector<char> selected(static_cast<std::size_t>(x_.cols()), 0);
    for (Index node : l.nodes) selected[static_cast<std::size_t>(node)] = 1;
    const Real share = 1.0 / static_cast<Real>(l.nodes.size());
    switch (l.kind) {
      case NodalLoad::Kind::force:
      case NodalLoad::Kind::moment:
        for (Index node : l.nodes) prepared.weights.push_back({node, share});
        break;
      case NodalLoad::Kind::body_force:
        for (Index node : l.nodes) prepared.weights.push_back({node, mass_[node]});
        break;
      case NodalLoad::Kind::traction:
      case NodalLoad::Kind::edge_moment: {
        // force (moment) per unit length on the boundary edges whose two nodes are selected (reference lengths)
        std::map<Index, Real> length_share;
        for (const auto& [edge, count] : uses) {
          if (count != 1 || !selected[static_cast<std::size_t>(edge.first)] || !selected[static_cast<std::size_t>(edge.second)]) continue;
          const Real length = (reference_.col(edge.first) - reference_.col(edge.second)).norm();
          length_share[edge.first] += 0.5 * length;
          length_share[edge.second] += 0.5 * length;
        }
        for (const auto& [node, w] : length_share) prepared.weights.push_back({node, w});
        break;
      }
      case NodalLoad::Kind::pressure:
        for (Index e = 0; e < mesh.element_count(); ++e) {
          bool all = true;
          for (int a = 0; a < 4; ++a) all = all && selected[static_cast<std::size_t>(mesh.quads(a, e))];
          if (all) prepared.elements.push_back(e);
        }
        break;
      default: break;
    }
    const bool per_edge = l.kind == NodalLoad::Kind::traction || l.kind == NodalLoad::Kind::edge_moment;
    if ((per_edge && prepared.weights.empty()) || (l.kind == NodalLoad::Kind::pressure && prepared.elements.empty()))
      throw InputError(l.label, per_edge ? "a selection holding at least one free edge of the shell (both end nodes)"
                                                                      : "a selection holding all four nodes of at least one element",
                       fmt::format("{} nodes and none", l.nodes.size()));
    prepared_loads_.push_back(std::move(prepared));
  }
}

void MpmAnalysis::compute_external_forces(Real load) {
  StageTimer timer(stage_seconds_, "loads");
  f_ext_.setZero();
  m_ext_.setZero();
  const ShellMesh& mesh = problem_.mesh;
  const Real s = problem_.options.analysis == MpmOptions::Kind::quasi_static ? load : time_ / problem_.options.end_time;
  for (std::size_t k = 0; k < problem_.loads.size(); ++k) {
    const NodalLoad& l = problem_.loads[k];
    const PreparedLoad& prepared = prepared_loads_[k];
    const Real factor = l.ramp.factor(s);
    if (factor == 0.0) continue;
    auto vector_at = [&](Index node) {
      Vec3 value;
      for (int a = 0; a < 3; ++a)
        value[a] = field_value(l.vector[static_cast<std::size_t>(a)], prepared.expressions[static_cast<std::size_t>(a)].get(),
                               reference_.col(node), time_);
      return value;
    };
    switch (l.kind) {
      case NodalLoad::Kind::force:
      case NodalLoad::Kind::traction:
      case NodalLoad::Kind::body_force:
        for (const auto& [node, w] : prepared.weights) f_ext_.col(node) += factor * w * vector_at(node);
        break;
      case NodalLoad::Kind::moment:
      case NodalLoad::Kind::edge_moment:
        for (const auto& [node, w] : prepared.weights) m_ext_.col(node) += factor * w * vector_at(node);
        break;
      case NodalLoad::Kind::pressure:
        for (Index e : prepared.elements) {
          const Vec3 d1 = x_.col(mesh.quads(2, e)) - x_.col(mesh.quads(0, e)), d2 = x_.col(mesh.quads(3, e)) - x_.col(mesh.quads(1, e));
          const Vec3 area_normal = 0.5 * d1.cross(d2);  // |.| = area of a planar quad, outward by the mesh orientation
          Vec3 centre = Vec3::Zero();
          for (int a = 0; a < 4; ++a) centre += 0.25 * reference_.col(mesh.quads(a, e));
          const Real p = field_value(l.scalar, prepared.scalar_expression.get(), centre, time_);
          for (int a = 0; a < 4; ++a) f_ext_.col(mesh.quads(a, e)) -= factor * 0.25 * p * area_normal;
        }
        break;
      default: break;
    }
  }
}

void MpmAnalysis::apply_prescribed(Real load) {
  const Real s = problem_.options.analysis == MpmOptions::Kind::quasi_static ? load : time_ / problem_.options.end_time;
  for (const auto& c : problem_.constraints) {
    const Real factor = c.ramp.factor(s);
    for (int a = 0; a < 3; ++a) {
      const auto& f = c.velocity[static_cast<std::size_t>(a)];
      if (!f) continue;
      std::unique_ptr<geometry::Expression> e;
      if (!f->is_constant()) e = std::make_unique<geometry::Expression>(f->expression);
      for (Index node : c.nodes) {
        v_(a, node) = factor * field_value(*f, e.get(), reference_.col(node), time_);
        vpos_(a, node) = v_(a, node);
      }
    }
  }
}

Real MpmAnalysis::node_velocity_limit() const { return 10.0 * wave_speed_; }

Real MpmAnalysis::advance(Real load) {
  const MpmOptions& o = problem_.options;
  const Index n = x_.cols();
  current_load_ = load;

  // 1. element stage: stresses advanced over the step that brought the nodes to x^n
  compute_internal_forces(dt_previous_);
  energy_.internal += dt_previous_ * element_power_.sum();
  energy_.hourglass += dt_previous_ * element_hourglass_power_.sum();
  if (scaled_) {
    if (masses_stale_ || masses_age_ >= kMassRefreshSteps) compute_fictitious_masses();
    ++masses_age_;
    if (o.adaptive_damping) adaptive_c_ = steps_ > 0 ? adaptive_damping_coefficient() : 0.0;
    f_int_previous_ = f_int_;
    m_int_previous_ = m_int_;
  }

  // 2. time step (eqs (38)-(40)) combined with the shell stable step
  const Real vmax = vpos_.cwiseAbs().maxCoeff();
  if (!std::isfinite(vmax) || vmax > node_velocity_limit())
    throw AnalysisError(fmt::format("unstable: a node velocity of {:.3g} exceeds 10 x the wave speed ({:.3g}) at step {} "
                                    "(time {:.6g}); reduce mpm.time_step",
                                    vmax, wave_speed_, steps_, time_));
  const Real dt_grid = o.alpha * grid_.cell() / (wave_speed_ + vmax);
  const Real dt_shell = o.shell_safety * element_->stable_time_step(element_length_.minCoeff());
  Real dt = std::min(dt_grid, dt_shell);
  dt_control_ = dt_grid < dt_shell ? "grid" : "shell";
  if (o.fixed_time_step > 0) {
    dt = o.fixed_time_step;
    dt_control_ = "fixed";
  }
  if (scaled_) {  // the fictitious masses make dt = 1 stable (Gershgorin bound)
    dt = 1.0;
    dt_control_ = "mass_scaling";
  }
  if (!(dt > 0) || !std::isfinite(dt)) throw AnalysisError(fmt::format("time step {} at step {}: degenerate elements", dt, steps_));
  dt_ = dt;

  // 3. external forces, damping, residual
  compute_external_forces(load);
  const Real c = scaled_ && o.adaptive_damping ? adaptive_c_ : o.mass_damping;
  f_net_ = f_ext_ - f_int_;
  Eigen::Matrix3Xd& m_net = m_net_;
  m_net = m_ext_ - m_int_;
  {
    Real r2 = 0, ext2 = 0, int2 = 0;
    for (Index i = 0; i < n; ++i) {
      r2 += f_net_.col(i).cwiseProduct(free_.col(i)).squaredNorm() / mass_[i] +
            m_net.col(i).cwiseProduct(rotation_free_.col(i)).squaredNorm() / inertia_[i];
      ext2 += f_ext_.col(i).squaredNorm() / mass_[i] + m_ext_.col(i).squaredNorm() / inertia_[i];
      int2 += f_int_.col(i).cwiseProduct(free_.col(i)).squaredNorm() / mass_[i] +
              m_int_.col(i).cwiseProduct(rotation_free_.col(i)).squaredNorm() / inertia_[i];
    }
    if (scaled_ && o.adaptive_damping && c > 0) {
      // adaptive damping: the damping force c m v joins the imbalance, so that a node swinging through
      // equilibrium (zero residual at full velocity) does not end the level
      for (Index i = 0; i < n; ++i)
        r2 += (c * dyn_mass_[i]) * (c * dyn_mass_[i]) * v_.col(i).cwiseProduct(free_.col(i)).squaredNorm() / mass_[i] +
              (c * dyn_inertia_[i]) * (c * dyn_inertia_[i]) * omega_.col(i).cwiseProduct(rotation_free_.col(i)).squaredNorm() / inertia_[i];
    }
    const Real scale = std::max({ext2, int2, std::numeric_limits<Real>::min()});
    residual_ratio_ = std::sqrt(r2 / scale);
  }
  // adaptive damping is central (seed 002 eq (7)): v^{n+1/2} = ((1 - c dt/2) v^{n-1/2} + dt f / m) / (1 + c dt/2),
  // applied in the grid update and the rotation update (an explicit -c m v^{n-1/2} would shrink the
  // stable step to omega^2 dt^2 < 4 - 2 c dt)
  const bool central_damping = scaled_ && o.adaptive_damping;
  const Real keep = central_damping ? 1.0 - 0.5 * c * dt : 1.0, divide = central_damping ? 1.0 + 0.5 * c * dt : 1.0;
  if (c > 0 && !central_damping) {
    for (Index i = 0; i < n; ++i) {
      f_net_.col(i) -= c * dyn_mass_[i] * v_.col(i);
      m_net.col(i) -= c * dyn_inertia_[i] * omega_.col(i);
    }
  }

  // 4. P2G: mass, momentum and force per free component
  // (work arrays are members, reused across steps: no per-step allocation)
  Eigen::Matrix3Xd &grid_mass = grid_mass_, &grid_momentum = grid_momentum_, &grid_force = grid_force_;
  {
    StageTimer t(stage_seconds_, "p2g");
    if (node_mass_.cols() != n) node_mass_ = (Eigen::Matrix3Xd::Ones(3, n).array().rowwise() * dyn_mass_.transpose().array()).matrix();
    momentum_.resize(3, n);
    for (Index i = 0; i < n; ++i) momentum_.col(i) = dyn_mass_[i] * v_.col(i);
    grid_.scatter(node_mass_, free_, grid_mass);
    grid_.scatter(momentum_, free_, grid_momentum);
    grid_.scatter(f_net_, free_, grid_force);
  }
  // 5. grid update (eqs (5)-(7))
  Eigen::Matrix3Xd &grid_velocity = grid_velocity_, &grid_acceleration = grid_acceleration_;
  grid_velocity.resize(3, grid_mass.cols());
  grid_acceleration.resize(3, grid_mass.cols());
  {
    StageTimer t(stage_seconds_, "grid");
    const Index slots = grid_mass.cols();
#pragma omp parallel for schedule(static) if (slots > 4096)
    for (Index s = 0; s < slots; ++s)
      for (int a = 0; a < 3; ++a) {
        const Real m = grid_mass(a, s);
        if (m > 0) {
          if (central_damping) {
            grid_velocity(a, s) = (keep * grid_momentum(a, s) + dt * grid_force(a, s)) / (divide * m);
            grid_acceleration(a, s) = (grid_velocity(a, s) - grid_momentum(a, s) / m) / dt;
          } else {
            grid_acceleration(a, s) = grid_force(a, s) / m;
            grid_velocity(a, s) = (grid_momentum(a, s) + dt * grid_force(a, s)) / m;
          }
        } else {
          grid_acceleration(a, s) = grid_velocity(a, s) = 0.0;  // no free mass: fixed grid node (eq (7))
        }
      }
  }
  // 6. G2P velocities; rotations at the nodes
  {
    StageTimer t(stage_seconds_, "g2p");
    PointMatrix &v_pic = v_pic_, &a_grid = a_grid_;
    grid_.gather(grid_velocity, v_pic);
    grid_.gather(grid_acceleration, a_grid);
    const Real flip = o.flip;
    transfer_loss_.setZero(n);
#pragma omp parallel for schedule(static) if (n > 1024)
    for (Index i = 0; i < n; ++i) {
      for (int a = 0; a < 3; ++a) {
        if (free_(a, i) > 0) {
          const Real v_flip = v_(a, i) + dt * a_grid(a, i);
          v_(a, i) = flip * v_flip + (1.0 - flip) * v_pic(a, i);
          transfer_loss_[i] += 0.5 * dyn_mass_[i] * (v_flip * v_flip - v_(a, i) * v_(a, i));
          vpos_(a, i) = v_pic(a, i);
        } else {
          v_(a, i) = vpos_(a, i) = 0.0;
        }
        if (central_damping)
          omega_(a, i) = rotation_free_(a, i) > 0 ? (keep * omega_(a, i) + dt * m_net(a, i) / dyn_inertia_[i]) / divide : 0.0;
        else
          omega_(a, i) = rotation_free_(a, i) > 0 ? omega_(a, i) + dt * m_net(a, i) / dyn_inertia_[i] : 0.0;
      }
    }
  }
  apply_prescribed(load);

  // 7. damping bookkeeping and kinetic-energy damping
  Real kinetic = 0.0;
  for (Index i = 0; i < n; ++i) kinetic += 0.5 * (dyn_mass_[i] * v_.col(i).squaredNorm() + dyn_inertia_[i] * omega_.col(i).squaredNorm());
  if (c > 0) {
    Real p = 0;
    for (Index i = 0; i < n; ++i) p += c * (dyn_mass_[i] * v_.col(i).squaredNorm() + dyn_inertia_[i] * omega_.col(i).squaredNorm());
    energy_.damping += dt * p;
  }
  // kinetic damping: the option, or the fallback of adaptive damping where its estimate is zero (a
  // negative local stiffness, e.g. past a limit point: the motion would stay undamped)
  const bool kinetic_on = o.kinetic_damping || (scaled_ && o.adaptive_damping && c == 0.0);
  if (kinetic_on && kinetic < kinetic_previous_) {
    energy_.damping += kinetic;
    for (Index i = 0; i < n; ++i)
      for (int a = 0; a < 3; ++a) {
        if (free_(a, i) > 0) v_(a, i) = vpos_(a, i) = 0.0;
        omega_(a, i) = 0.0;
      }
    kinetic_previous_ = 0.0;
    kinetic = 0.0;
    for (Index i = 0; i < n; ++i) kinetic += 0.5 * dyn_mass_[i] * v_.col(i).squaredNorm();
  } else {
    kinetic_previous_ = kinetic;
  }
  // external work over this step (loads at n, displacement with the velocity that moves the nodes,
  // after kinetic damping: a step whose velocities were zeroed at a peak moves nothing and does no work)
  {
    Real w = 0;
    for (Index i = 0; i < n; ++i) w += f_ext_.col(i).dot(vpos_.col(i)) + m_ext_.col(i).dot(omega_.col(i));
    energy_.external += dt * w;
  }
  energy_.kinetic = kinetic;
  energy_.transfer += transfer_loss_.sum();

  // 8. positions (eq (9)) and grid connectivity
  {
    StageTimer t(stage_seconds_, "update");
    x_ += dt * vpos_;
    if (scaled_) theta_ += dt * omega_;
    grid_.locate(x_);
  }
  if (!std::isfinite(kinetic) || !std::isfinite(energy_.internal))
    throw AnalysisError(fmt::format("non-finite energy at step {} (time {:.6g}): the run is unstable", steps_, time_));
  dt_previous_ = dt;
  time_ += dt;
  ++steps_;
  return dt;
}

void MpmAnalysis::run(OutputSink& sink) {
  const MpmOptions& o = problem_.options;
  if (!resumed_) {
    sink.output_point(0, 0.0, 0.0);
    loop_ = RunLoop{};
  }
  if (o.analysis == MpmOptions::Kind::quasi_static) {
    for (; loop_.level <= o.load_levels; ++loop_.level, loop_.level_steps = 0) {
      const int level = loop_.level;
      const Real load = static_cast<Real>(level) / o.load_levels, previous = static_cast<Real>(level - 1) / o.load_levels;
      Index& level_steps = loop_.level_steps;
      if (level_steps == 0) begin_level();
      while (true) {
        const bool ramping = level_steps < o.level_ramp_steps;
        advance(ramping ? previous + (load - previous) * static_cast<Real>(level_steps + 1) / static_cast<Real>(o.level_ramp_steps)
                        : load);
        ++level_steps;
        if (!ramping && level_steps > 2 && residual_ratio_ < o.tolerance) break;
        if (level_steps >= o.max_steps_per_level) {
          unconverged_levels_.push_back(level);
          break;
        }
        if (level_steps % 5000 == 0) {
          // within the level: steps against the mean of the finished levels (their cost is what the ETA
          // extrapolates); the first level only has the residual's decades to go by
          Real within = std::min(1.0, -std::log10(std::max(residual_ratio_, 1e-30)) / -std::log10(o.tolerance));
          if (!level_step_counts_.empty()) {
            Real mean = 0;
            for (int k : level_step_counts_) mean += static_cast<Real>(k);
            mean /= static_cast<Real>(level_step_counts_.size());
            within = std::min(0.95, static_cast<Real>(level_steps) / std::max(mean, 1.0));
          }
          sink.progress((level - 1 + within) / o.load_levels,
                        fmt::format("level {}/{} residual {:.2e} dt {:.3g}", level, o.load_levels, residual_ratio_, dt_));
        }
        sink.safe_point();
      }
      level_residual_.push_back(residual_ratio_);
      level_step_counts_.push_back(static_cast<int>(level_steps));
      sink.progress(static_cast<Real>(level) / o.load_levels,
                    fmt::format("level {}/{} residual {:.2e} steps {}", level, o.load_levels, residual_ratio_, steps_));
      sink.output_point(steps_, time_, load);
      loop_.level_done = true;  // a checkpoint here resumes at the next level
      sink.safe_point();
      loop_.level_done = false;
    }
  } else {
    while (loop_.next_output <= o.output_points) {
      const Real target = o.end_time * loop_.next_output / o.output_points;
      advance(time_ / o.end_time);
      if (steps_ >= o.max_steps) throw AnalysisError(fmt::format("more than {} steps before the end time", o.max_steps));
      if (time_ >= target * (1 - 1e-12)) {
        sink.output_point(steps_, time_, std::min(1.0, time_ / o.end_time));
        sink.progress(time_ / o.end_time, fmt::format("t {:.4g} dt {:.3g}", time_, dt_));
        ++loop_.next_output;
      }
      sink.safe_point();
    }
  }
}

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
          {"time_step_grid_controlled", dt_control_ == "grid" ? 1.0 : 0.0}};
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
  if (problem_.material != MpmProblem::Material::j2_plasticity) return out;
  if (s.thickness_points <= 3)
    out.push_back(fmt::format("shell.thickness_points = {} with j2_plasticity: so few points cannot represent plastic "
                              "bending (3 Lobatto points carry at most the first-yield moment, a real section 1.5 x); use 7",
                              s.thickness_points));
  if (problem_.options.analysis == MpmOptions::Kind::quasi_static && problem_.options.level_ramp_steps == 0)
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
  for (const auto& [name, seconds] : stage_seconds_) t[name + "_s"] = seconds;
  return t;
}

// The state after a step: node motion, element stresses and hourglass resultants, clocks and the
// energy balance, listed once for writing and reading; the grid connectivity is rebuilt from the
// positions (a function of them alone).
template <class Self, class Archive>
void MpmAnalysis::state_fields(Self& self, Archive& a) {
  a.field("mpm.x", self.x_);
  a.field("mpm.v", self.v_);
  a.field("mpm.vpos", self.vpos_);
  a.field("mpm.omega", self.omega_);
  a.field("mpm.stress", self.stress_);
  a.field("mpm.hourglass", self.hourglass_);
  a.field("mpm.thickness", self.thickness_);
  a.field("mpm.element_length", self.element_length_);
  a.field("mpm.time", self.time_);
  a.field("mpm.dt", self.dt_);
  a.field("mpm.dt_previous", self.dt_previous_);
  a.field("mpm.residual_ratio", self.residual_ratio_);
  a.field("mpm.kinetic_previous", self.kinetic_previous_);
  a.field("mpm.current_load", self.current_load_);
  a.field("mpm.steps", self.steps_);
  a.field("mpm.dt_control", self.dt_control_);
  a.field("mpm.unconverged_levels", self.unconverged_levels_);
  a.field("mpm.level_residual", self.level_residual_);
  auto& e = self.energy_;
  a.field("mpm.energy.kinetic", e.kinetic);
  a.field("mpm.energy.internal", e.internal);
  a.field("mpm.energy.hourglass", e.hourglass);
  a.field("mpm.energy.external", e.external);
  a.field("mpm.energy.damping", e.damping);
  a.field("mpm.energy.transfer", e.transfer);
  a.field("mpm.energy.initial_kinetic", e.initial_kinetic);
  a.field("mpm.loop.level", self.loop_.level);
  a.field("mpm.loop.level_steps", self.loop_.level_steps);
  a.field("mpm.loop.level_done", self.loop_.level_done);
  a.field("mpm.loop.next_output", self.loop_.next_output);
  if (self.scaled_) {  // mass-scaled quasi-static: the fictitious masses and the damping estimate's state
    a.field("mpm.mass_scaling.mass", self.dyn_mass_);
    a.field("mpm.mass_scaling.inertia", self.dyn_inertia_);
    a.field("mpm.mass_scaling.level_start", self.level_start_);
    a.field("mpm.mass_scaling.theta", self.theta_);
    a.field("mpm.mass_scaling.f_int_previous", self.f_int_previous_);
    a.field("mpm.mass_scaling.m_int_previous", self.m_int_previous_);
    a.field("mpm.mass_scaling.damping", self.adaptive_c_);
    a.field("mpm.mass_scaling.age", self.masses_age_);
    a.field("mpm.mass_scaling.stale", self.masses_stale_);
    a.field("mpm.mass_scaling.level_steps", self.level_step_counts_);
  }
}

void MpmAnalysis::save_state(StateWriter& out) const {
  out.put("mpm.nodes", static_cast<std::int64_t>(x_.cols()));
  out.put("mpm.elements", problem_.mesh.element_count());
  state_fields(*this, out);
}

void MpmAnalysis::restore_state(const StateReader& in) {
  if (in.integer("mpm.nodes") != x_.cols() || in.integer("mpm.elements") != problem_.mesh.element_count())
    throw StateError(fmt::format("written for {} nodes and {} elements, this mesh has {} and {}", in.integer("mpm.nodes"),
                                 in.integer("mpm.elements"), x_.cols(), problem_.mesh.element_count()));
  state_fields(*this, in);  // (every array has its size from the set-up)
  const MpmOptions& o = problem_.options;
  auto require = [](bool ok, const char* what) {
    if (!ok) throw StateError(std::string("checkpoint value out of range: ") + what);
  };
  require(std::isfinite(time_) && time_ >= 0 && std::isfinite(dt_previous_) && dt_previous_ >= 0 && std::isfinite(dt_), "time");
  require(steps_ >= 0 && loop_.level_steps >= 0, "step counts");
  require(loop_.level >= 1 && loop_.level <= o.load_levels + 1, "quasi-static level");
  require(loop_.next_output >= 1 && loop_.next_output <= o.output_points + 1, "next output point");
  if (scaled_) {
    require(dyn_mass_.allFinite() && dyn_mass_.minCoeff() > 0 && dyn_inertia_.allFinite() && dyn_inertia_.minCoeff() > 0,
            "fictitious masses");
    node_mass_.resize(3, 0);  // the grid's copy of the masses is rebuilt
  }
  if (loop_.level_done) {  // written after the level's output point: continue with the next level
    ++loop_.level;
    loop_.level_steps = 0;
    loop_.level_done = false;
  }
  try {
    grid_.locate(x_);
  } catch (const AnalysisError& e) {
    throw StateError(std::string("checkpoint record 'mpm.x': ") + e.what());
  }
  resumed_ = true;
}

}  // namespace lamina::mpm
