#include "mpm/mpm_analysis.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "mpm/mass_scaling.hpp"

namespace lamina::mpm {

namespace {

Real field_value(const geometry::ScalarField& f, const geometry::Expression* e, const Vec3& x, Real t) {
  return f.is_constant() ? f.constant : e->evaluate(x, t);
}

}  // namespace

MpmAnalysis::~MpmAnalysis() = default;

MpmAnalysis::MpmAnalysis(MpmProblem problem, std::vector<Probe> probes, const parallel::Communicator& comm)
    : problem_(std::move(problem)), probes_(std::move(probes)), comm_(comm), grid_(Vec3::Zero(), 1.0) {
  const ShellMesh& mesh = problem_.mesh;
  const MpmOptions& o = problem_.options;
  const material::MaterialSpec& m = problem_.material;
  if (!(m.density.value_or(0.0) > 0)) throw InputError("materials.0.density", "a positive density (mpm is a dynamic method)", "none or <= 0");
  for (std::size_t k = 0; k < probes_.size(); ++k)
    if (probes_[k].field == "plastic_strain" && m.model != material::MaterialModel::j2_plasticity)
      throw InputError(fmt::format("probes.{}.field", k), "a field of this material (plastic_strain needs model: j2_plasticity)",
                       "plastic_strain");
  if (!(mesh.thickness > 0)) throw InputError("geometry.thickness", "a positive shell thickness", fmt::format("{}", mesh.thickness));
  if (m.nu <= -1.0 || m.nu >= 0.5 || !(m.E > 0))
    throw InputError("materials.0", "E > 0 and -1 < nu < 0.5", fmt::format("E = {}, nu = {}", m.E, m.nu));
  Cpdi2Domains domains(mesh, *m.density);
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
  // origin half a cell off the nodes' lower bound: the nodes of a regular mesh (a plate in a coordinate
  // plane, a mesh whose spacing is a multiple of the cell) then sit mid-cell instead of on cell faces,
  // where round-off motion (1e-16 in a direction nothing moves) flipped them between cells and rebuilt
  // the grid's connectivity at almost every step
  const Vec3 lower = mesh.nodes.rowwise().minCoeff();
  grid_ = BackgroundGrid(lower - Vec3::Constant(1.5 * cell), cell);

  material_ = material::make_shell_material(problem_.material);
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

  if (problem_.options.solver == MpmOptions::Solver::newton)
    for (const auto& c : problem_.constraints)
      for (int a = 0; a < 3; ++a)
        if (c.velocity[static_cast<std::size_t>(a)] && !c.select.nodes.empty())
          throw InputError("mpm.solver", "fixed components only with newton (a prescribed velocity needs mpm.solver: explicit)",
                           "a prescribed velocity in boundary");
  for (const auto& c : problem_.constraints)
    for (Index node : c.select.nodes)
      for (int a = 0; a < 3; ++a) {
        if (c.fixed[static_cast<std::size_t>(a)] || c.velocity[static_cast<std::size_t>(a)]) free_(a, node) = 0.0;
        if (c.fixed[static_cast<std::size_t>(a + 3)]) rotation_free_(a, node) = 0.0;
      }
  for (const auto& l : problem_.loads) {
    if (l.kind == model::Load::Kind::mass) {
      const Real each = l.scalar.constant / static_cast<Real>(l.select.nodes.size());
      for (Index node : l.select.nodes) mass_[node] += each;
    } else if (l.kind == model::Load::Kind::initial_velocity) {
      for (Index node : l.select.nodes)
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

  // several ranks: the node block, the elements touching it, the elements it owns
  const Index chunks = (n + kSumChunk - 1) / kSumChunk;
  node_block_begins_.resize(static_cast<std::size_t>(comm_.size()) + 1);
  for (int r = 0; r <= comm_.size(); ++r)
    node_block_begins_[static_cast<std::size_t>(r)] = std::min(n, kSumChunk * comm_.block_begin(chunks, r));
  node_first_ = node_block_begins_[static_cast<std::size_t>(comm_.rank())];
  node_last_ = node_block_begins_[static_cast<std::size_t>(comm_.rank()) + 1];
  element_nodes_of_rank_.assign(static_cast<std::size_t>(comm_.size()), std::vector<char>());
  if (comm_.distributed())
    for (int q = 0; q < comm_.size(); ++q) {
      auto& nodes = element_nodes_of_rank_[static_cast<std::size_t>(q)];
      nodes.assign(static_cast<std::size_t>(n), 0);
      const Index first = node_block_begins_[static_cast<std::size_t>(q)], last = node_block_begins_[static_cast<std::size_t>(q) + 1];
      for (Index e = 0; e < e_count; ++e) {
        bool touches = false;
        for (int a = 0; a < 4; ++a) touches = touches || (mesh.quads(a, e) >= first && mesh.quads(a, e) < last);
        if (touches)
          for (int a = 0; a < 4; ++a) nodes[static_cast<std::size_t>(mesh.quads(a, e))] = 1;
      }
    }
  owns_element_.assign(static_cast<std::size_t>(e_count), 0);
  for (Index e = 0; e < e_count; ++e) {
    auto mine = [&](Index node) { return node >= node_first_ && node < node_last_; };
    bool touches = false;
    for (int a = 0; a < 4; ++a) touches = touches || mine(mesh.quads(a, e));
    if (touches) rank_elements_.push_back(e);
    owns_element_[static_cast<std::size_t>(e)] = mine(mesh.quads(0, e));
  }

  stress_ = Eigen::MatrixXd::Zero(element_->stress_size(), e_count);
  hourglass_.setZero(shell::BelytschkoTsayShell::kHourglassSize, e_count);
  thickness_ = Eigen::VectorXd::Constant(e_count, mesh.thickness);
  element_power_ = element_hourglass_power_ = element_length_ = Eigen::VectorXd::Zero(e_count);
  element_force_ = element_moment_ = Eigen::Matrix<Real, 12, Eigen::Dynamic>::Zero(12, e_count);
  locate_grid();
  prepare_loads();
  dyn_mass_ = mass_;
  dyn_inertia_ = inertia_;
  scaled_ = o.analysis == MpmOptions::Kind::quasi_static && o.mass_scaling;
  if (scaled_) {
    level_start_ = x_;
    theta_ = PointMatrix::Zero(3, n);
    f_int_previous_ = m_int_previous_ = Eigen::Matrix3Xd::Zero(3, n);
  }
  stages_ = step_stages(scaled_);
  stage_time_.assign(stages_.size(), 0.0);
  energy_.kinetic = energy_.initial_kinetic = 0.5 * (v_.colwise().squaredNorm() * dyn_mass_)(0);
}

void MpmAnalysis::gather_element_state() {
  if (!comm_.distributed()) return;
  // each element from its owner (the other ranks add zeros: exact), every rank all of them
  const Index e_count = problem_.mesh.element_count();
  const Index per = stress_.rows() + hourglass_.rows() + 2;
  std::vector<Real> all(static_cast<std::size_t>(per * e_count), 0.0);
  for (Index e = 0; e < e_count; ++e) {
    if (!owns_element_[static_cast<std::size_t>(e)]) continue;
    Real* out = all.data() + per * e;
    for (Index r = 0; r < stress_.rows(); ++r) *out++ = stress_(r, e);
    for (Index r = 0; r < hourglass_.rows(); ++r) *out++ = hourglass_(r, e);
    *out++ = thickness_[e];
    *out++ = element_length_[e];
  }
  comm_.sum(all);
  for (Index e = 0; e < e_count; ++e) {
    const Real* in = all.data() + per * e;
    for (Index r = 0; r < stress_.rows(); ++r) stress_(r, e) = *in++;
    for (Index r = 0; r < hourglass_.rows(); ++r) hourglass_(r, e) = *in++;
    thickness_[e] = *in++;
    element_length_[e] = *in++;
  }
}

void MpmAnalysis::gather_node_blocks(std::initializer_list<std::pair<Real*, int>> arrays) {
  // one in-place all-gather per array: measured faster than packing them into one message (the copies
  // cost more than the extra latency at these sizes)
  if (!comm_.distributed()) return;
  for (const auto& [data, rows] : arrays) comm_.all_gather_blocks(data, rows, node_block_begins_);
}

void MpmAnalysis::exchange_halo(std::initializer_list<std::pair<Real*, int>> arrays) {
  if (comm_.distributed()) comm_.exchange_columns(arrays, halo_send_, halo_receive_);
}

void MpmAnalysis::gather_state() {
  gather_element_state();
  gather_node_blocks({{v_.data(), 3}, {omega_.data(), 3}, {f_int_.data(), 3}, {m_int_.data(), 3}});
  if (scaled_) gather_node_blocks({{theta_.data(), 3}, {f_int_previous_.data(), 3}, {m_int_previous_.data(), 3}});
}

void MpmAnalysis::locate_grid() {
  if (!comm_.distributed()) {
    grid_.locate(x_);
    return;
  }
  // each rank's box: a node sharing a grid node with a block node lies within two cells of it in each
  // direction. Every rank holds every position, so every rank finds every rank's box alike. One pass
  // over the coordinates (flat, 3 per node), which also checks them for the grid's range on every rank
  // alike (locate() sees only the nodes near the block).
  const int ranks = comm_.size(), me = comm_.rank();
  const Index n = x_.cols();
  const Real* xs = x_.data();
  constexpr Real kInfinity = std::numeric_limits<Real>::infinity();
  std::vector<std::array<Real, 6>> box(static_cast<std::size_t>(ranks));  // low x, y, z, high x, y, z
  const Real margin = 2.01 * grid_.cell();
  Real sum = 0;  // of every coordinate: non-finite if one is (then check_range names it)
  for (int q = 0; q < ranks; ++q) {
    std::array<Real, 6> b{kInfinity, kInfinity, kInfinity, -kInfinity, -kInfinity, -kInfinity};
    for (Index i = node_block_begins_[static_cast<std::size_t>(q)]; i < node_block_begins_[static_cast<std::size_t>(q) + 1]; ++i)
      for (int d = 0; d < 3; ++d) {
        const Real v = xs[3 * i + d];
        b[static_cast<std::size_t>(d)] = std::min(b[static_cast<std::size_t>(d)], v);
        b[static_cast<std::size_t>(d) + 3] = std::max(b[static_cast<std::size_t>(d) + 3], v);
        sum += v;
      }
    for (std::size_t d = 0; d < 3; ++d) b[d] -= margin, b[d + 3] += margin;
    box[static_cast<std::size_t>(q)] = b;
  }
  Vec3 lowest = Vec3::Constant(kInfinity), highest = -lowest;
  for (const auto& b : box) lowest = lowest.cwiseMin(Vec3(b[0], b[1], b[2])), highest = highest.cwiseMax(Vec3(b[3], b[4], b[5]));
  if (!std::isfinite(sum) || !grid_.covers(lowest, highest)) grid_.check_range(x_);  // throws for the culprit
  auto near = [&](int q, Index c) {
    const auto& b = box[static_cast<std::size_t>(q)];
    const Real* p = xs + 3 * c;
    return p[0] >= b[0] && p[0] <= b[3] && p[1] >= b[1] && p[1] <= b[4] && p[2] >= b[2] && p[2] <= b[5];
  };
  near_block_.resize(static_cast<std::size_t>(n));
  for (Index c = 0; c < n; ++c) near_block_[static_cast<std::size_t>(c)] = near(me, c) ? 1 : 0;
  grid_.locate(x_, &near_block_);
  // the halo: what this rank needs of rank q's block (near this block, or on this block's elements), and
  // what rank q needs of this block (the same test with q's box and elements)
  halo_send_.resize(static_cast<std::size_t>(ranks));
  halo_receive_.resize(static_cast<std::size_t>(ranks));
  const auto& mine = element_nodes_of_rank_[static_cast<std::size_t>(me)];
  for (int q = 0; q < ranks; ++q) {
    if (q == me) continue;
    auto& receive = halo_receive_[static_cast<std::size_t>(q)];
    receive.clear();
    for (Index i = node_block_begins_[static_cast<std::size_t>(q)]; i < node_block_begins_[static_cast<std::size_t>(q) + 1]; ++i)
      if (near_block_[static_cast<std::size_t>(i)] || mine[static_cast<std::size_t>(i)]) receive.push_back(i);
    auto& send = halo_send_[static_cast<std::size_t>(q)];
    send.clear();
    const auto& theirs = element_nodes_of_rank_[static_cast<std::size_t>(q)];
    for (Index i = node_first_; i < node_last_; ++i)
      if (near(q, i) || theirs[static_cast<std::size_t>(i)]) send.push_back(i);
  }
}

void MpmAnalysis::compute_fictitious_masses() {
  gather_element_state();
  stiffness_proportional_masses(*element_, problem_.mesh, x_, stress_, hourglass_, thickness_, incidence_begin_, incidence_,
                                dyn_mass_, dyn_inertia_);
  masses_age_ = 0;
  masses_stale_ = false;
}

Real MpmAnalysis::adaptive_damping_coefficient() const {
  // u: the increment since the level started; local stiffness k_d = (f_d^n - f_d^{n-1}) / (m_d dt v_d^{n-1/2})
  const auto [numerator, denominator] = node_sums<2>([&](Index i, std::array<Real, 2>& s) {
    for (int a = 0; a < 3; ++a) {
      if (free_(a, i) > 0) {
        const Real u = x_(a, i) - level_start_(a, i), v = vpos_(a, i);
        s[1] += u * u;
        if (v != 0) s[0] += u * u * (f_int_(a, i) - f_int_previous_(a, i)) / (dyn_mass_[i] * dt_previous_ * v);
      }
      if (rotation_free_(a, i) > 0) {
        const Real u = theta_(a, i), w = omega_(a, i);
        s[1] += u * u;
        if (w != 0) s[0] += u * u * (m_int_(a, i) - m_int_previous_(a, i)) / (dyn_inertia_[i] * dt_previous_ * w);
      }
    }
  });
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
  const Index count = static_cast<Index>(rank_elements_.size());  // all elements on one process
  Index bad = -1;
  // mid-step configuration x^{n-1/2}: the chord velocity of a finite rigid rotation is a rigid
  // velocity field there (no spurious strain), and the strain increments integrate to second order
  const Real half_step = 0.5 * dt_stress;
#pragma omp parallel for schedule(static) reduction(max : bad) if (count > 256)
  for (Index k = 0; k < count; ++k) {
    const Index e = rank_elements_[static_cast<std::size_t>(k)];
    shell::NodeMatrix x, v, w;
    for (int a = 0; a < 4; ++a) {
      const Index node = mesh.quads(a, e);
      x.col(a) = x_.col(node) - half_step * vpos_.col(node);
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
  if (comm_.distributed()) {
    // the owned elements' powers (summed over the ranks: the energies agree with one process to
    // round-off) and the shortest element (exact), one reduction
    std::vector<Real> reduced{static_cast<Real>(bad), 0.0, 0.0, -std::numeric_limits<Real>::infinity()};
    for (Index e : rank_elements_) {
      if (owns_element_[static_cast<std::size_t>(e)]) reduced[1] += element_power_[e], reduced[2] += element_hourglass_power_[e];
      reduced[3] = std::max(reduced[3], -element_length_[e]);
    }
    const std::vector<Real> all = comm_.all_gather(reduced);  // rank order: the same sums on every rank
    power_sum_ = hourglass_power_sum_ = 0;
    Real largest = -std::numeric_limits<Real>::infinity();
    for (std::size_t r = 0; r < all.size(); r += 4) {
      bad = std::max(bad, static_cast<Index>(all[r]));
      power_sum_ += all[r + 1];
      hourglass_power_sum_ += all[r + 2];
      largest = std::max(largest, all[r + 3]);
    }
    shortest_element_ = -largest;
  } else {
    power_sum_ = element_power_.sum();
    hourglass_power_sum_ = element_hourglass_power_.sum();
    shortest_element_ = element_length_.minCoeff();
  }
  if (bad >= 0)
    throw AnalysisError(fmt::format("element {} became degenerate or inverted at step {} (time {:.6g}): the run is unstable "
                                    "or the deformation too large for the mesh",
                                    bad, steps_, time_));
  // gather: every node of the block sums its corners' forces and moments (no atomics, deterministic)
#pragma omp parallel for schedule(static) if (node_last_ - node_first_ > 1024)
  for (Index i = node_first_; i < node_last_; ++i) {
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
  exchange_halo({{f_int_.data(), 3}});  // several ranks: the halo's forces (P2G of the nodes near the block)
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
    for (Index node : l.select.nodes) selected[static_cast<std::size_t>(node)] = 1;
    const Real share = 1.0 / static_cast<Real>(l.select.nodes.size());
    switch (l.kind) {
      case model::Load::Kind::force:
      case model::Load::Kind::moment:
        for (Index node : l.select.nodes) prepared.weights.push_back({node, share});
        break;
      case model::Load::Kind::body_force:
        for (Index node : l.select.nodes) prepared.weights.push_back({node, mass_[node]});
        break;
      case model::Load::Kind::traction:
      case model::Load::Kind::edge_moment: {
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
      case model::Load::Kind::pressure:
        for (Index e = 0; e < mesh.element_count(); ++e) {
          bool all = true;
          for (int a = 0; a < 4; ++a) all = all && selected[static_cast<std::size_t>(mesh.quads(a, e))];
          if (all) prepared.elements.push_back(e);
        }
        break;
      default: break;
    }
    const bool per_edge = l.kind == model::Load::Kind::traction || l.kind == model::Load::Kind::edge_moment;
    if ((per_edge && prepared.weights.empty()) || (l.kind == model::Load::Kind::pressure && prepared.elements.empty()))
      throw InputError(l.select.label, per_edge ? "a selection holding at least one free edge of the shell (both end nodes)"
                                                                      : "a selection holding all four nodes of at least one element",
                       fmt::format("{} nodes and none", l.select.nodes.size()));
    prepared_loads_.push_back(std::move(prepared));
  }
}

void MpmAnalysis::compute_external_forces(Real load) {
  const Index n = f_ext_.cols();
#pragma omp parallel for schedule(static) if (n > 4096)
  for (Index i = 0; i < n; ++i) {
    f_ext_.col(i).setZero();
    m_ext_.col(i).setZero();
  }
  const ShellMesh& mesh = problem_.mesh;
  const Real s = problem_.options.analysis == MpmOptions::Kind::quasi_static ? load : time_ / problem_.options.end_time;
  for (std::size_t k = 0; k < problem_.loads.size(); ++k) {
    const model::Load& l = problem_.loads[k];
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
      case model::Load::Kind::force:
      case model::Load::Kind::traction:
      case model::Load::Kind::body_force:
        for (const auto& [node, w] : prepared.weights) f_ext_.col(node) += factor * w * vector_at(node);
        break;
      case model::Load::Kind::moment:
      case model::Load::Kind::edge_moment:
        for (const auto& [node, w] : prepared.weights) m_ext_.col(node) += factor * w * vector_at(node);
        break;
      case model::Load::Kind::pressure:
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
      for (Index node : c.select.nodes) {
        v_(a, node) = factor * field_value(*f, e.get(), reference_.col(node), time_);
        vpos_(a, node) = v_(a, node);
      }
    }
  }
}

Real MpmAnalysis::node_velocity_limit() const { return 10.0 * wave_speed_; }

void MpmAnalysis::run(OutputSink& sink) {
  const MpmOptions& o = problem_.options;
  if (!resumed_) {
    gather_state();
    sink.output_point(0, 0.0, 0.0);
    loop_ = RunLoop{};
  }
  if (o.analysis == MpmOptions::Kind::quasi_static) {
    const bool newton = o.solver == MpmOptions::Solver::newton;
    for (; loop_.level <= o.load_levels; ++loop_.level, loop_.level_steps = 0) {
      const int level = loop_.level;
      const Real load = static_cast<Real>(level) / o.load_levels, previous = static_cast<Real>(level - 1) / o.load_levels;
      Index& level_steps = loop_.level_steps;
      if (level_steps == 0) begin_level();
      // Newton (the default): the whole level, or up to where it stopped; explicit dynamics for the rest
      const bool explicit_steps = !newton || (level_steps == 0 && !solve_level_newton(previous, load, sink)) || level_steps > 0;
      while (explicit_steps) {
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
                    explicit_steps ? fmt::format("level {}/{} residual {:.2e} steps {}", level, o.load_levels, residual_ratio_, steps_)
                                   : fmt::format("level {}/{} residual {:.2e} Newton iterations {}", level, o.load_levels,
                                                 residual_ratio_, newton_iterations_));
      gather_state();
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
        gather_state();
        sink.output_point(steps_, time_, std::min(1.0, time_ / o.end_time));
        sink.progress(time_ / o.end_time, fmt::format("t {:.4g} dt {:.3g}", time_, dt_));
        ++loop_.next_output;
      }
      sink.safe_point();
    }
  }
}

}  // namespace lamina::mpm
