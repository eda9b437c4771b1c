// PeridynamicAnalysis: set-up (body, model: lattice solid or plate), loads and prescribed motion, the
// linear static and buckling analyses and the zero-energy check; the other analyses in peridynamic_*.cpp.
#include "pd/peridynamic_analysis.hpp"

#include <fmt/format.h>

#include <Spectra/MatOp/SparseSymMatProd.h>
#include <Spectra/SymGEigsSolver.h>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>

#include "core/error.hpp"
#include "core/memory.hpp"
#include "core/stopwatch.hpp"
#include "pd/force_split.hpp"
#include "pd/lean_peridynamic_solid.hpp"
#include "pd/kirchhoff_plate.hpp"
#include "pd/peridynamic_plate.hpp"
#include "pd/zero_energy_check.hpp"
#include "solve/sparse_cholesky.hpp"
#include "solve/petsc_linear_solver.hpp"
#include "solve/slepc_eigen_solver.hpp"

namespace lamina::pd {

namespace {

/// The free-free part of a symmetric matrix stored as its upper triangle (free dofs renumbered in order).
solve::SparseMatrix reduce_upper(const solve::SparseMatrix& upper, const std::vector<Index>& map, Index free_count) {
  std::vector<Eigen::Triplet<Real, int>> entries;
  entries.reserve(static_cast<std::size_t>(upper.nonZeros()));
  for (Index col = 0; col < upper.outerSize(); ++col) {
    const Index c = map[static_cast<std::size_t>(col)];
    if (c < 0) continue;
    for (solve::SparseMatrix::InnerIterator it(upper, col); it; ++it) {
      const Index r = map[static_cast<std::size_t>(it.row())];
      if (r >= 0) entries.emplace_back(static_cast<int>(r), static_cast<int>(c), it.value());
    }
  }
  solve::SparseMatrix reduced(free_count, free_count);
  reduced.setFromTriplets(entries.begin(), entries.end());
  return reduced;
}

/// B-operator of Spectra's regular-inverse mode for B = K0 (symmetric positive definite, given by its
/// upper triangle): CHOLMOD's supernodal Cholesky for y = B^-1 x, the symmetric product for y = B x.
class CholmodRegularInverse {
 public:
  using Scalar = Real;
  explicit CholmodRegularInverse(const solve::SparseMatrix& upper)
      : upper_(upper), llt_(solve::make_sparse_cholesky()), ok_(llt_->compute(upper_)) {}
  bool ok() const { return ok_; }
  Index rows() const { return upper_.rows(); }
  Index cols() const { return upper_.cols(); }
  void solve(const Scalar* x_in, Scalar* y_out) const {
    const Eigen::Map<const Eigen::VectorXd> x(x_in, rows());
    Eigen::Map<Eigen::VectorXd>(y_out, rows()) = llt_->solve(x);
  }
  void perform_op(const Scalar* x_in, Scalar* y_out) const {
    const Eigen::Map<const Eigen::VectorXd> x(x_in, rows());
    Eigen::Map<Eigen::VectorXd>(y_out, rows()).noalias() = upper_.selfadjointView<Eigen::Upper>() * x;
  }

 private:
  const solve::SparseMatrix& upper_;
  std::unique_ptr<solve::SparseCholesky> llt_;
  bool ok_ = false;
};

const std::vector<std::string> vector_components{"x", "y", "z", "magnitude"};
const std::vector<std::string> tensor_components{"xx", "yy", "zz", "xy", "yz", "zx", "von_mises"};

}  // namespace

PeridynamicAnalysis::PeridynamicAnalysis(PeridynamicProblem problem, std::vector<Probe> probes,
                                         const parallel::Communicator& comm)
    : problem_(std::move(problem)), probes_(std::move(probes)), comm_(comm) {
  for (std::size_t k = 0; k < probes_.size(); ++k) {
    const Probe& p = probes_[k];
    const std::string where = fmt::format("probes.{}", k);
    auto in = [](const std::vector<std::string>& list, const std::string& s) {
      return std::find(list.begin(), list.end(), s) != list.end();
    };
    if (p.field == "displacement" || p.field == "velocity") {
      if (!in(vector_components, p.component)) throw InputError(where + ".component", "x, y, z or magnitude", p.component);
      if (!p.at && p.nodes.empty()) throw InputError(where + ".at", "a point (at: [x, y, z]) or a set", "none");
    } else if (p.field == "strain" || p.field == "stress") {
      if (!in(tensor_components, p.component) || (p.field == "strain" && p.component == "von_mises"))
        throw InputError(where + ".component", "xx, yy, zz, xy, yz or zx (stress also von_mises)", p.component);
      if (!p.at && p.nodes.empty()) throw InputError(where + ".at", "a point (at: [x, y, z]) or a set", "none");
    } else if (p.field == "reaction_force") {
      if (!in(vector_components, p.component)) throw InputError(where + ".component", "x, y, z or magnitude", p.component);
      if (p.nodes.empty()) throw InputError(where + ".select", "a selection of nodes for a reaction_force probe", "none");
    } else if (p.field == "energy") {
      if (!in({"internal", "kinetic", "external", "total", "damping"}, p.component))
        throw InputError(where + ".component", "internal, kinetic, external, total or damping", p.component);
    } else if (p.field == "eigenvalue" || p.field == "critical_load") {
      if (p.field == "critical_load" && p.nodes.empty())
        throw InputError(where + ".select", "a selection of the loaded (or displaced) nodes for a critical_load probe", "none");
      int k = 0;
      try {
        k = std::stoi(p.component);
      } catch (...) {
      }
      if (k < 1 || k > problem_.buckling.modes || problem_.analysis != PdAnalysisKind::buckling)
        throw InputError(where + ".component",
                         fmt::format("a mode number 1..{} of a buckling analysis (pd.analysis: buckling)", problem_.buckling.modes),
                         p.component);
    } else {
      throw InputError(where + ".field",
                       "displacement, velocity, strain, stress, reaction_force, energy, eigenvalue or critical_load", p.field);
    }
  }
  const auto start = Clock::now();
  if (comm_.distributed()) check_distributable();
  // several ranks: explicit dynamics of a node lattice runs partitioned (owned nodes and halos); the other
  // analyses and the plate model keep the whole body on every rank (split_force_work)
  if (comm_.distributed() && problem_.analysis == PdAnalysisKind::explicit_dynamics && !plate_lattice()) {
    ranks_ = std::make_unique<RankNodes>();
    problem_ = distribute_problem(problem_, comm_, *ranks_);
    owned_dof_ = Eigen::VectorXd::Zero(3 * static_cast<Index>(ranks_->global.size()));
    for (std::size_t k = 0; k < ranks_->global.size(); ++k)
      if (ranks_->owns(static_cast<Index>(k))) owned_dof_.segment<3>(3 * static_cast<Index>(k)).setOnes();
  }
  PointMatrix positions = problem_.positions;
  const auto& imperfection = problem_.imperfection;
  auto scaled = [&](const PointMatrix& shape) {
    const Real largest = shape.colwise().norm().maxCoeff();
    if (!(largest > 0)) throw InputError("imperfection", "a non-zero imperfection shape", "a zero field");
    return PointMatrix(shape * (imperfection.amplitude / largest));
  };
  if (imperfection.kind == Imperfection::Kind::shape) positions += scaled(imperfection.shape);
  build_body(positions);
  if (imperfection.kind == Imperfection::Kind::buckling_mode) {
    buckling_modes(imperfection.mode);
    positions += scaled(modes_[static_cast<std::size_t>(imperfection.mode - 1)]);
    build_body(positions);
    imperfection_load_factor_ = eigenvalues_.empty() ? 0.0 : eigenvalues_.front();
    eigenvalues_.clear();
    modes_.clear();
  }
  const Index n = body_->nodes();
  u_ = PointMatrix::Zero(3, n);
  velocity_ = PointMatrix::Zero(3, n);
  internal_force_ = PointMatrix::Zero(3, n);
  external_force_ = PointMatrix::Zero(3, n);
  state_ = model_->state_of(u_);
  timings_["setup_s"] = seconds_since(start);
}

void PeridynamicAnalysis::build_body(const PointMatrix& positions) {
  model_.reset();
  plate_columns_ = nullptr;
  const BodyOptions& options = problem_.body;
  std::optional<PlateColumns> columns;
  if (options.plate_model == PlateModel::automatic && options.kinematics == Kinematics::three_dimensional &&
      options.surface_correction != SurfaceCorrection::plate)
    columns = find_plate_columns(problem_.positions, problem_.volumes, &model_reason_);
  if (columns) {
    // the node body only serves the strain probes (families, no calibration)
    BodyOptions probe_options = options;
    probe_options.surface_correction = SurfaceCorrection::none;
    body_ = std::make_unique<PeridynamicBody>(positions, problem_.volumes, problem_.young, problem_.poisson, probe_options);
    auto adopt = [&](auto plate) {  // one layer: the Kirchhoff model; 2-4 layers: the director model
      plate_columns_ = &plate->columns();
      model_ = std::move(plate);
    };
    if (columns->layers == 1) {
      auto plate = std::make_unique<KirchhoffPlate>(std::move(*columns), positions, problem_.positions, problem_.volumes,
                                                    problem_.young, problem_.poisson, options);
      std::vector<char> prescribed(static_cast<std::size_t>(3 * problem_.positions.cols()), 0);
      for (const auto& d : problem_.prescribed) prescribed[static_cast<std::size_t>(3 * d.node + d.component)] = 1;
      plate->hold_rotations(problem_.held_rotations, prescribed);
      adopt(std::move(plate));
      return;
    }
    if (!problem_.held_rotations.empty()) throw InputError(*problem_.held_rotations.where);
    std::vector<char> held(static_cast<std::size_t>(3 * problem_.positions.cols()), 0);
    for (const auto& d : problem_.prescribed) held[static_cast<std::size_t>(3 * d.node + d.component)] = 1;
    adopt(std::make_unique<PeridynamicPlate>(std::move(*columns), positions, problem_.positions, problem_.volumes,
                                             problem_.young, problem_.poisson, options, held));
  } else {
    if (!problem_.held_rotations.empty()) throw InputError(*problem_.held_rotations.where);
    BodyOptions body_options = options;
    body_options.lean_bonds = lean_bond_storage();
    body_ = std::make_unique<PeridynamicBody>(positions, problem_.volumes, problem_.young, problem_.poisson, body_options);
    if (ranks_) body_->set_node_roles(ranks_->role);
    if (body_->lean()) model_ = std::make_unique<LeanPeridynamicSolid>(*body_);
    else model_ = std::make_unique<LinearPeridynamicSolid>(*body_);
  }
}

bool PeridynamicAnalysis::lean_bond_storage() const {
  const BodyOptions& o = problem_.body;
  if (o.surface_correction == SurfaceCorrection::plate) return false;
  // lean needs no stiffness: explicit dynamics with a given time step (the critical step is not formed)
  const bool stiffness_free = problem_.analysis == PdAnalysisKind::explicit_dynamics && problem_.explicit_options.time_step > 0;
  if (o.bond_storage == BodyOptions::BondStorage::lean) {
    if (!stiffness_free)
      throw InputError("pd.bond_storage", "full or auto unless pd.analysis is explicit with pd.explicit.time_step given "
                                          "(lean storage keeps no stiffness)", "lean");
    return true;
  }
  if (o.bond_storage != BodyOptions::BondStorage::automatic || !stiffness_free) return false;
  // automatic: lean when the full storage (about 200 bytes per bond: lengths, volumes, weights, moduli,
  // reverse indices and the bond state) would take more than a quarter of this machine's memory; the
  // lean kernel recomputes each bond's constants (about 2.5 x the time per step of the full one)
  const Index n = ranks_ ? ranks_->global_count : problem_.volumes.size();  // the same choice on every rank
  if (n == 0) return false;
  const bool planar = o.kinematics != Kinematics::three_dimensional;
  const Real h = o.cell_size > 0 ? o.cell_size : (planar ? 1.0 : std::cbrt(problem_.volumes.mean()));
  const Real r = o.horizon / h;  // horizon in node spacings
  const Real family = planar ? M_PI * r * r : 4.0 / 3.0 * M_PI * r * r * r;
  const Real full_bytes = 200.0 * family * static_cast<Real>(n);
  return full_bytes > 0.25 * static_cast<Real>(physical_memory_bytes());
}

void PeridynamicAnalysis::check_distributable() const {
  // the linear static and buckling solves go through PETSc / SLEPc on several ranks
  if (problem_.analysis == PdAnalysisKind::linear_static || problem_.analysis == PdAnalysisKind::buckling)
    problem_.solver.check_ranks(comm_.size());
}

bool PeridynamicAnalysis::plate_lattice() const {
  const BodyOptions& o = problem_.body;
  return o.plate_model == PlateModel::automatic && o.kinematics == Kinematics::three_dimensional &&
         o.surface_correction != SurfaceCorrection::plate && find_plate_columns(problem_.positions, problem_.volumes);
}

void PeridynamicAnalysis::split_force_work(bool on) {
  if (!comm_.distributed() || ranks_) return;
  if (on && !force_split_) force_split_ = std::make_unique<ForceSplit>(body_->positions(), plate_columns_, comm_);
  static const std::vector<char> everything;
  const std::vector<char>& mine = on ? force_split_->mine() : everything;
  if (auto* plate = dynamic_cast<PeridynamicPlate*>(model_.get())) {
    plate->restrict_to_nodes(mine);
    return;
  }
  if (!on) {
    body_->set_node_roles({});
    return;
  }
  // the lattice: forces of the block's nodes, dilatations of the block and its families
  const Index n = body_->nodes();
  std::vector<NodeRole> roles(static_cast<std::size_t>(n), NodeRole::outer_halo);
  for (Index i = 0; i < n; ++i)
    if (mine[static_cast<std::size_t>(i)]) roles[static_cast<std::size_t>(i)] = NodeRole::owned;
  for (Index i = 0; i < n; ++i)
    if (mine[static_cast<std::size_t>(i)])
      for (Index b = body_->first_bond(i); b < body_->end_bond(i); ++b) {
        NodeRole& r = roles[static_cast<std::size_t>(body_->neighbour(b))];
        if (r == NodeRole::outer_halo) r = NodeRole::inner_halo;
      }
  body_->set_node_roles(std::move(roles));
}

Real PeridynamicAnalysis::ramp(int index, Real factor) const {
  return index < 0 ? factor : problem_.ramps[static_cast<std::size_t>(index)].factor(factor);
}

PointMatrix PeridynamicAnalysis::external_force(Real factor) const {
  PointMatrix f = PointMatrix::Zero(3, body_->nodes());
  for (const auto& load : problem_.forces) f.col(load.node) += load.force * ramp(load.ramp, factor);
  return f;
}

void PeridynamicAnalysis::apply_prescribed(PointMatrix& u, Real factor, bool velocities) const {
  for (const auto& p : problem_.prescribed)
    if (p.velocity == velocities) u(p.component, p.node) = p.value * ramp(p.ramp, factor);
}

std::vector<char> PeridynamicAnalysis::free_dofs(bool include_velocity) const {
  std::vector<char> free(static_cast<std::size_t>(3 * body_->nodes()), 1);
  for (const auto& p : problem_.prescribed)
    if (!p.velocity || include_velocity) free[static_cast<std::size_t>(3 * p.node + p.component)] = 0;
  if (body_->dimension() == 2)
    for (Index i = 0; i < body_->nodes(); ++i) free[static_cast<std::size_t>(3 * i + 2)] = 0;
  return free;
}

void PeridynamicAnalysis::solve() {
  struct NullSink : OutputSink {
    void output_point(Index, Real, Real) override {}
    void progress(Real, const std::string&) override {}
  } sink;
  run(sink);
}

void PeridynamicAnalysis::run(OutputSink& sink) {
  const auto start = Clock::now();
  if (plate_columns_ && plate_columns_->layers == 1) {
    // one layer holds no rotation: nodes with all three translations held are simply supported
    std::vector<int> held(static_cast<std::size_t>(body_->nodes()), 0);
    for (const auto& p : problem_.prescribed)
      if (!p.velocity) held[static_cast<std::size_t>(p.node)] |= 1 << p.component;
    bool drilling = false;
    for (std::size_t e = 0; e < problem_.held_rotations.nodes.size(); ++e) {
      held[static_cast<std::size_t>(problem_.held_rotations.nodes[e])] |= 8;
      drilling = drilling || (problem_.held_rotations.axes[e] & 4u);
    }
    if (drilling && comm_.rank() == 0)
      sink.notice("one-layer plate: rz has no effect - the plate has no drilling rotation (its in-plane rotation "
                  "follows the held x, y; rx and ry hold the slopes, docs/pd.md)");
    const auto fully = std::count(held.begin(), held.end(), 7);
    if (fully > 1 && comm_.rank() == 0)
      sink.notice(fmt::format("one-layer plate: {} nodes have x, y and z held and no rotation - a simple support, "
                              "not a clamp; to clamp them hold their rotations too (fix: [x, y, z, rx, ry], docs/pd.md)",
                              fully));
  }
  if (const auto* plate = dynamic_cast<const PeridynamicPlate*>(model_.get()); plate && comm_.rank() == 0) {
    const auto& edges = plate->mirror().edges;
    std::string list;
    for (const auto& edge : edges) list += (list.empty() ? "" : ", ") + edge;
    sink.notice(!problem_.body.plate_edge_mirror
                    ? std::string("plate model: one-sided families at every edge (pd.plate_edges: one_sided)")
                : edges.empty() ? std::string("plate model: no straight supported outer edge, every edge's families "
                                              "are one-sided (pd.plate_edges, docs/pd.md)")
                              : fmt::format("plate model: the families reach across the supported edges {} into mirror "
                                            "columns (pd.plate_edges: mirror, docs/pd.md)", list));
  }
  switch (problem_.analysis) {
    case PdAnalysisKind::linear_static: run_linear_static(&sink); break;
    case PdAnalysisKind::quasi_static: run_quasi_static(&sink); break;
    case PdAnalysisKind::explicit_dynamics: run_explicit(&sink); break;
    case PdAnalysisKind::buckling: run_buckling(&sink); break;
  }
  timings_["solve_s"] = seconds_since(start);
}

PointMatrix PeridynamicAnalysis::linear_solution(solve::SparseMatrix& k0_upper, bool check, bool petsc) {
  const Index n = body_->nodes();
  k0_upper = model_->stiffness(*model_->state_of(PointMatrix::Zero(3, n), true), true, false);
  if (check) check_unloaded_stiffness(k0_upper);
  const std::vector<char> free = free_dofs(true);
  std::vector<Index> map(free.size(), -1);
  Index count = 0;
  for (std::size_t d = 0; d < free.size(); ++d)
    if (free[d]) map[d] = count++;
  PointMatrix u = PointMatrix::Zero(3, n);
  apply_prescribed(u, 1.0, false);
  const PointMatrix f = external_force(1.0);
  const Eigen::Map<const Eigen::VectorXd> uc(u.data(), u.size()), fv(f.data(), f.size());
  const Eigen::VectorXd rhs_full = fv - solve::multiply_symmetric_upper(k0_upper, uc);
  Eigen::VectorXd rhs(count);
  for (std::size_t d = 0; d < free.size(); ++d)
    if (map[d] >= 0) rhs[map[d]] = rhs_full[static_cast<Index>(d)];
  const solve::SparseMatrix reduced = reduce_upper(k0_upper, map, count);
  solve::SolverReport report;
  const Eigen::VectorXd x = petsc ? solve::solve_symmetric_petsc(reduced, rhs, problem_.solver, comm_, report,
                                                                  solve::SystemShares::replicated, true, 1)
                                  : solve::solve_symmetric(reduced, rhs, report);
  timings_["factor_s"] = report.factor_seconds;
  for (std::size_t d = 0; d < free.size(); ++d)
    if (map[d] >= 0) u.data()[d] = x[map[d]];
  return u;
}

void PeridynamicAnalysis::check_unloaded_stiffness(const solve::SparseMatrix& k0_upper) {
  if (!problem_.check_zero_energy) return;
  const auto start = Clock::now();
  const std::vector<char> free = free_dofs(true);
  std::vector<Index> map(free.size(), -1), dofs;
  for (std::size_t d = 0; d < free.size(); ++d)
    if (free[d]) map[d] = static_cast<Index>(dofs.size()), dofs.push_back(static_cast<Index>(d));
  const ZeroEnergyReport r = find_zero_energy_modes(reduce_upper(k0_upper, map, static_cast<Index>(dofs.size())), dofs,
                                                    body_->positions());
  timings_["zero_energy_check_s"] = seconds_since(start);
  timings_["smallest_scaled_stiffness"] = r.smallest;
  if (!r.singular) return;
  const Vec3 x = r.node >= 0 ? Vec3(body_->positions().col(r.node)) : Vec3::Zero();
  if (r.rigid)
    throw InputError("boundary", "supports that hold every rigid-body motion of the body",
                     fmt::format("a free rigid-body motion of the unloaded body (largest at the node at ({:.4g}, {:.4g}, {:.4g}))",
                                 x.x(), x.y(), x.z()));
  throw InputError(
      "discretization.horizon", "a lattice and horizon whose unloaded stiffness has no zero-energy mode",
      fmt::format("a zero-energy mode of the {} model (smallest density-scaled stiffness eigenvalue {:.2g}, largest at the node at "
                  "({:.4g}, {:.4g}, {:.4g})): {}",
                  model_->name(), r.smallest, x.x(), x.y(), x.z(),
                  model_->name() == "plate"             ? "give the horizon at least 1.4 in-plane spacings"
                  : model_->name() == "kirchhoff_plate" ? "give the horizon about 3 in-plane spacings"
                                                        : "use a horizon above the cell diagonal, or the plate models for a "
                                                          "1-4 layer plate (pd.plate_model: auto)"));
}

void PeridynamicAnalysis::run_linear_static(OutputSink* sink) {
  sink->output_point(0, 0.0, 0.0);
  solve::SparseMatrix k0;
  u_ = linear_solution(k0, false, problem_.solver.uses_petsc(comm_.distributed()));
  state_ = model_->state_of(u_, true);
  internal_force_ = model_->internal_force(*state_);
  external_force_ = external_force(1.0);
  energy_internal_ = model_->strain_energy(*state_);
  // Clapeyron: 1/2 (f . u + reactions . prescribed displacements) = 1/2 sum (F_ext - F_int - F_ext) at constrained.
  const PointMatrix support = -(internal_force_ + external_force_);
  const std::vector<char> free = free_dofs(true);
  Real work = 0;
  for (Index d = 0; d < u_.size(); ++d)
    work += 0.5 * (external_force_.data()[d] + (free[static_cast<std::size_t>(d)] ? 0.0 : support.data()[d])) * u_.data()[d];
  energy_external_ = work;
  steps_ = 1;
  sink->output_point(1, 1.0, 1.0);
}

void PeridynamicAnalysis::buckling_modes(int count) {
  const Index n = body_->nodes();
  solve::SparseMatrix k0;
  const PointMatrix reference = linear_solution(k0, true);
  std::unique_ptr<ModelState> reference_state = model_->state_of(reference, true);
  const solve::SparseMatrix kg = model_->stiffness(*reference_state, false, true);
  const std::vector<char> free = free_dofs(true);
  std::vector<Index> map(free.size(), -1);
  Index dofs = 0;
  for (std::size_t d = 0; d < free.size(); ++d)
    if (free[d]) map[d] = dofs++;
  const solve::SparseMatrix k_upper = reduce_upper(k0, map, dofs), g_upper = reduce_upper(kg, map, dofs);
  const solve::SparseMatrix minus_g = -g_upper;
  // K0 phi = lambda (-K_G) phi  <=>  (-K_G) phi = (1 / lambda) K0 phi: the largest 1/lambda first
  const int nev = std::min<int>(count, static_cast<int>(dofs) - 1);
  Eigen::VectorXd mu;
  Eigen::MatrixXd vectors;
  if (problem_.solver.uses_petsc(comm_.distributed())) {
    // several ranks (or solver: mumps | cg): SLEPc's Krylov-Schur, K0 factorised by MUMPS Cholesky
    solve::EigenPairs pairs = solve::largest_generalized_eigenpairs(minus_g, k_upper, nev, comm_, 1e-10, 2000);
    mu = std::move(pairs.values);
    vectors = std::move(pairs.vectors);
  } else {
    // one process: Spectra's regular-inverse mode, K0-orthogonal Lanczos with CHOLMOD solves of K0
    using OpType = Spectra::SparseSymMatProd<Real, Eigen::Upper>;
    using BOpType = CholmodRegularInverse;
    OpType op(minus_g);
    BOpType bop(k_upper);
    if (!bop.ok())
      throw AnalysisError("buckling: the stiffness matrix is not positive definite (rigid-body motion left free?)");
    const int ncv = std::min<int>(std::max(2 * nev + 1, 40), static_cast<int>(dofs));
    Spectra::SymGEigsSolver<OpType, BOpType, Spectra::GEigsMode::RegularInverse> eigs(op, bop, nev, ncv);
    eigs.init();
    eigs.compute(Spectra::SortRule::LargestAlge, 2000, 1e-10);
    if (eigs.info() != Spectra::CompInfo::Successful) throw AnalysisError("buckling: the eigenvalue solver did not converge");
    mu = eigs.eigenvalues();
    vectors = eigs.eigenvectors();
  }
  eigenvalues_.clear();
  modes_.clear();
  for (Index k = 0; k < mu.size(); ++k) {
    if (!(mu[k] > 0)) throw AnalysisError("buckling: the reference load does not compress the structure (no positive load factor)");
    eigenvalues_.push_back(1.0 / mu[k]);
    PointMatrix mode = PointMatrix::Zero(3, n);
    for (std::size_t d = 0; d < free.size(); ++d)
      if (map[d] >= 0) mode.data()[d] = vectors(map[d], k);
    const Real largest = mode.colwise().norm().maxCoeff();
    Index where = 0;
    mode.colwise().norm().maxCoeff(&where);
    const Real sign = mode.col(where).sum() < 0 ? -1.0 : 1.0;
    modes_.push_back(mode * (sign / largest));
  }
  u_ = reference;
  state_ = std::move(reference_state);
  internal_force_ = model_->internal_force(*state_);
  external_force_ = external_force(1.0);
}

void PeridynamicAnalysis::run_buckling(OutputSink* sink) {
  buckling_modes(problem_.buckling.modes);
  // one layer: the curvature is a second derivative of a cubic fit over the horizon; say when a mode is
  // too short for it (docs/pd.md, "Clamped edges: held rotations")
  if (const auto* plate = dynamic_cast<const KirchhoffPlate*>(model_.get()); plate && comm_.rank() == 0)
    if (!modes_.empty()) {
      const Real wavenumber = plate->transverse_wavenumber(modes_.front());
      const Real resolution = wavenumber * problem_.body.horizon;
      timings_["mode_1_wavenumber_x_horizon"] = resolution;
      if (resolution > kShortModeResolution)
        sink->notice(fmt::format("one-layer plate: buckling mode 1 is short for the horizon (wavenumber x horizon = {:.2f}, "
                                 "a half-wave of about {:.3g} = {:.1f} horizons): the one-layer model reads the curvature by "
                                 "a cubic fit over the horizon and is soft for such modes (-1.9 % at 0.76 on the seed's R6 plate, "
                                 "-7.8 % at 1.05 on a square with clamped edges, docs/pd.md); refine the lattice keeping the "
                                 "horizon factor, or use 2-4 layers",
                                 resolution, M_PI / wavenumber, M_PI / resolution));
    }
  steps_ = 1;
  sink->output_point(1, 1.0, 1.0);
}

}  // namespace lamina::pd
