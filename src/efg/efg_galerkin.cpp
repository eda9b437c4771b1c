// EfgAnalysis, Galerkin formulation (seed 004 eqs 1-30..1-33): the assemble, solve and energy stages.
// assemble: neighbours per background cell (and VCI integrals), the projected volumetric term, the
// block pattern, the volume stiffness and loads, the penalty scale and the constraint terms (penalty,
// Nitsche or Lagrange multipliers); solve: CHOLMOD (symmetric) or the general solver; energy: strain
// energy, Clapeyron external work and the constraint reactions.
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <iterator>

#include "core/error.hpp"
#include "core/stopwatch.hpp"
#include "efg/efg_analysis.hpp"
#include "efg/galerkin_assembly.hpp"
#include "efg/nodal_field.hpp"
#include "solve/block_pattern.hpp"
#include "solve/petsc_linear_solver.hpp"

namespace lamina::efg {

void EfgAnalysis::assemble_galerkin(OutputSink* sink) {
  system_ = std::make_unique<GalerkinSystem>();
  GalerkinSystem& system = *system_;
  const Index n = problem_.cloud.size();
  const auto& options = problem_.options;
  const bool vci = options.correction == IntegrationCorrection::vci;
  const bool lagrange = options.essential == EssentialMethod::lagrange;
  auto progress = [&](Real fraction, const std::string& status) {
    if (sink) sink->progress(fraction, status);
  };

  // pass 1: neighbours per cell (and VCI integrals)
  auto start = Clock::now();
  VolumeIntegrals integrals, reduced_integrals;
  const bool reduced = reduced_.size() > 0;
  std::vector<IndexList> groups;
  // gradient smoothing couples every pair of nodes of a cell (face points included)
  const bool smoothed = options.correction == IntegrationCorrection::smoothed;
  CellFaceQuadrature cell_faces;
  if (smoothed) cell_faces = cell_face_quadrature(*cells_, options.gauss);
  std::vector<IndexList> cell_nodes =
      cell_neighbours(*shapes_, volume_, vci ? &integrals : nullptr, smoothed ? nullptr : &groups, smoothed ? &cell_faces : nullptr,
                      grow_at_points_);
  if (smoothed) groups = cell_nodes;
  if (reduced && !smoothed) {  // (smoothed gradients at the reduced points involve the cell's nodes only)
    const std::vector<IndexList> extra = cell_neighbours(*shapes_, reduced_, vci ? &reduced_integrals : nullptr, &groups);
    IndexList merged;
    for (std::size_t c = 0; c < cell_nodes.size(); ++c) {
      merged.clear();
      std::set_union(cell_nodes[c].begin(), cell_nodes[c].end(), extra[c].begin(), extra[c].end(), std::back_inserter(merged));
      cell_nodes[c].swap(merged);
    }
  }
  Eigen::Matrix3Xd xi, xi_reduced;
  if (vci) {
    Eigen::Matrix3Xd boundary = Eigen::Matrix3Xd::Zero(3, n);
    const auto values = shapes_->evaluate_all(surface_.points, 0, grow_at_points_);
    for (Index s = 0; s < surface_.size(); ++s) {
      const auto& sv = values[static_cast<std::size_t>(s)];
      for (std::size_t k = 0; k < sv.neighbours.size(); ++k)
        boundary.col(sv.neighbours[k]) += surface_.weights[s] * sv.phi[static_cast<Index>(k)] * surface_.normals.col(s);
    }
    xi = vci_correction(integrals, boundary);
    if (reduced) xi_reduced = vci_correction(reduced_integrals, boundary);
  }
  timings_["neighbours_s"] = seconds_since(start);
  progress(0.2, "neighbours");

  // projected volumetric term (efg.integration.volumetric: projected): G, M and lambda per pressure node
  const bool projected = problem_.options.projected_volumetric;
  if (projected) {
    start = Clock::now();
    Eigen::VectorXd lambda(volume_.size());
    for (Index q = 0; q < volume_.size(); ++q)
      lambda[q] = materials_[static_cast<std::size_t>(material_of_point_[static_cast<std::size_t>(q)])].lambda();
    projection_ = std::make_unique<ProjectedVolumetric>(project_volumetric(*shapes_, *pressure_, volume_, lambda));
    for (const auto& list : projection_->nodes) groups.push_back(list);
    timings_["projection_s"] = seconds_since(start);
  }

  // shape functions at the constraint points
  start = Clock::now();
  PointMatrix constraint_x(3, static_cast<Index>(constraint_points_.size()));
  for (std::size_t i = 0; i < constraint_points_.size(); ++i) constraint_x.col(static_cast<Index>(i)) = constraint_points_[i].x;
  system.constraint_shapes = shapes_->evaluate_all(constraint_x, 1, grow_at_points_);
  const auto& constraint_shapes = system.constraint_shapes;
  grown_boundary_points_ += count_grown(constraint_shapes);

  // pattern
  if (!lagrange)
    for (std::size_t i = 0; i < constraint_shapes.size(); ++i)  // a boundary face's points share their neighbours
      if (i == 0 || constraint_shapes[i].neighbours != constraint_shapes[i - 1].neighbours)
        groups.push_back(constraint_shapes[i].neighbours);
  const bool symmetric = system.symmetric = !vci;
  solve::BlockPattern pattern(n, 3, groups, symmetric);
  groups.clear();
  groups.shrink_to_fit();
  timings_["pattern_s"] = seconds_since(start);
  progress(0.3, "pattern");

  // volume stiffness
  start = Clock::now();
  system.K = pattern.zero_matrix();
  Real* values = system.K.valuePtr();
  system.f = Eigen::VectorXd::Zero(3 * n);
  Eigen::VectorXd& f = system.f;
  VolumeAssembly input;
  input.shapes = shapes_.get();
  input.quadrature = &volume_;
  input.cell_nodes = &cell_nodes;
  input.material_of_point = &material_of_point_;
  input.materials = projected ? &deviatoric_materials_ : &materials_;
  input.body_force = body_force_.cols() == volume_.size() ? &body_force_ : nullptr;
  input.vci = vci ? &xi : nullptr;
  input.smoothing = smoothed ? &cell_faces : nullptr;
  input.grow_at_faces = grow_at_points_;
  if (reduced) {
    input.reduced = &reduced_;
    input.material_of_reduced_point = &material_of_reduced_point_;
    input.vci_reduced = vci ? &xi_reduced : nullptr;
  }
  // several ranks: this rank's slab of the cells; the boundary terms and loads are rank 0's (the shares
  // add up in the distributed matrix)
  input.part = comm_.rank();
  input.parts = comm_.size();
  const bool adds_boundary = comm_.root();
  const VolumeAssemblyReport volume_report = assemble_volume(input, pattern, values, f);
  const Real volume_seconds = seconds_since(start);
  timings_["assembly_volume_s"] = volume_seconds;
  timings_["assembly_direct_writes"] = volume_report.direct ? 1.0 : 0.0;
  grown_boundary_points_ += comm_.sum(volume_report.grown_face_points);
  timings_["gauss_points_per_second"] =
      static_cast<Real>(volume_.size()) / std::max(volume_seconds + timings_["neighbours_s"], 1e-12);
  progress(0.6, "assembled");

  // loads
  start = Clock::now();
  if (adds_boundary) {
    PointMatrix load_x(3, static_cast<Index>(point_loads_.size()));
    for (std::size_t i = 0; i < point_loads_.size(); ++i) load_x.col(static_cast<Index>(i)) = point_loads_[i].x;
    const auto load_shapes = shapes_->evaluate_all(load_x, 0, grow_at_points_);
    grown_boundary_points_ += count_grown(load_shapes);
    for (std::size_t i = 0; i < point_loads_.size(); ++i) {
      const auto& sv = load_shapes[i];
      for (std::size_t k = 0; k < sv.neighbours.size(); ++k)
        f.segment<3>(3 * sv.neighbours[k]) += sv.phi[static_cast<Index>(k)] * point_loads_[i].force;
    }
  }
  f_loads_ = f;
  if (comm_.distributed()) {  // the whole load vector on every rank (external work)
    std::vector<Real> all(f_loads_.data(), f_loads_.data() + f_loads_.size());
    comm_.sum(all);
    f_loads_ = Eigen::Map<const Eigen::VectorXd>(all.data(), f_loads_.size());
  }

  // penalty scale: max diagonal of the volume stiffness over max nodal sum of w phi^2
  Real max_diagonal = 0;
  {
    std::vector<Real> diagonal(static_cast<std::size_t>(3 * n), 0.0);  // several ranks: their shares summed
    for (Index d = 0; d < 3 * n; ++d) {
      const Index p = pattern.position(d, d);
      if (p >= 0) diagonal[static_cast<std::size_t>(d)] = values[p];
    }
    comm_.sum(diagonal);
    for (const Real v : diagonal) max_diagonal = std::max(max_diagonal, std::abs(v));
  }
  {
    Eigen::VectorXd surface_sum = Eigen::VectorXd::Zero(n), point_sum = Eigen::VectorXd::Zero(n);
    for (std::size_t i = 0; i < constraint_points_.size(); ++i) {
      const auto& sv = constraint_shapes[i];
      Eigen::VectorXd& sum = constraint_points_[i].surface ? surface_sum : point_sum;
      for (std::size_t k = 0; k < sv.neighbours.size(); ++k)
        sum[sv.neighbours[k]] += constraint_points_[i].weight * sv.phi[static_cast<Index>(k)] * sv.phi[static_cast<Index>(k)];
    }
    const Real s_max = surface_sum.size() ? surface_sum.maxCoeff() : 0.0, p_max = point_sum.size() ? point_sum.maxCoeff() : 0.0;
    // scale with Young's modulus rather than the P-wave modulus lambda + 2 mu that dominates the
    // diagonal: a nearly incompressible body would otherwise get a penalty ~ lambda and lock at the
    // constrained faces
    Real stiffest = 0.0, ratio = 1.0;
    for (std::size_t i = 0; i < materials_.size(); ++i) {
      const auto& m = materials_[i];
      const Real assembled = projected ? deviatoric_materials_[i].p_wave_modulus() : m.p_wave_modulus();
      if (m.p_wave_modulus() > stiffest) {
        stiffest = m.p_wave_modulus();
        ratio = m.E / assembled;
      }
    }
    max_diagonal *= ratio;
    alpha_surface_ = options.penalty ? *options.penalty : (s_max > 0 ? options.penalty_factor * max_diagonal / s_max : 0.0);
    alpha_point_ = options.penalty ? *options.penalty : (p_max > 0 ? options.penalty_factor * max_diagonal / p_max : 0.0);
  }
  timings_["penalty_surface"] = alpha_surface_;
  timings_["penalty_point"] = alpha_point_;
  // after the penalty scale, which is taken from the mu part (a lambda-sized penalty locks the constrained faces)
  if (projected && adds_boundary) {
    const auto projection_start = Clock::now();
    projection_->add_stiffness(pattern, values);  // K += G^T diag(lambda_I / M_I) G
    timings_["projection_s"] += seconds_since(projection_start);
  }

  // constraint terms
  auto& multiplier_entries = system.multiplier_entries;
  Eigen::VectorXd& multiplier_rhs = system.multiplier_rhs;
  Index& multipliers = system.multipliers;
  if (lagrange) {
    for (const auto& p : constraint_points_)
      for (int a = 0; a < 3; ++a) multipliers += p.constrained[static_cast<std::size_t>(a)] ? 1 : 0;
    multiplier_rhs.resize(multipliers);
    Index row = 0;
    for (std::size_t i = 0; i < constraint_points_.size(); ++i) {
      const auto& p = constraint_points_[i];
      const auto& sv = constraint_shapes[i];
      for (int a = 0; a < 3; ++a) {
        if (!p.constrained[static_cast<std::size_t>(a)]) continue;
        for (std::size_t k = 0; k < sv.neighbours.size(); ++k)
          multiplier_entries.emplace_back(static_cast<int>(3 * n + row), static_cast<int>(3 * sv.neighbours[k] + a),
                                          sv.phi[static_cast<Index>(k)]);
        multiplier_rhs[row] = p.value[a];
        ++row;
      }
    }
  } else if (adds_boundary) {
    // Consecutive points with the same neighbours (the Gauss points of one boundary cell face) form a group
    // whose terms are added once: a Nitsche group straight into the matrix (scatter_nitsche_products), one
    // with penalty terms through a dense block. Each thread takes a contiguous share of the groups into its
    // own copy of the values they touch (a group's products stay in the cache of the core that formed
    // them); the copies are summed in thread order, so the result is deterministic for a thread count.
    // Nitsche where it is the method and the point is on a surface; the penalty form elsewhere
    const auto nitsche_point = [&](const ConstraintPoint& p) { return options.essential == EssentialMethod::nitsche && p.surface; };
    std::vector<std::pair<std::size_t, std::size_t>> groups;
    for (std::size_t i = 0; i < constraint_points_.size();) {
      std::size_t end = i;
      while (end < constraint_points_.size() && constraint_shapes[end].neighbours == constraint_shapes[i].neighbours) ++end;
      groups.emplace_back(i, end);
      i = end;
    }
    // the value range each thread's share touches; the copies only while they stay small (a boundary face's
    // nodes span most of the matrix: on a large body every copy is nearly a whole matrix), else one thread
    // adds straight into the values
    int threads = omp_get_max_threads();
    // share t: groups [share(t), share(t + 1))
    const auto share = [&](int t) { return groups.size() * static_cast<std::size_t>(t) / static_cast<std::size_t>(threads); };
    std::vector<std::pair<Index, Index>> ranges(static_cast<std::size_t>(threads), {0, 0});
    std::size_t copied = 0;
    for (int t = 0; t < threads; ++t) {
      Index low = pattern.nonzeros(), high = 0;
      for (std::size_t g = share(t); g < share(t + 1); ++g) {
        const auto [lo, hi] = pattern.value_range(constraint_shapes[groups[g].first].neighbours);
        low = std::min(low, lo);
        high = std::max(high, hi);
      }
      if (high < low) low = high = 0;
      ranges[static_cast<std::size_t>(t)] = {low, high};
      copied += static_cast<std::size_t>(high - low);
    }
    constexpr std::size_t most_copied = std::size_t{1} << 22;  // values (32 MiB)
    const bool copies = threads > 1 && copied <= most_copied;
    if (!copies) {
      threads = 1;
      ranges.assign(1, {0, pattern.nonzeros()});
    }
    std::vector<std::vector<Real>> partial(static_cast<std::size_t>(threads));
    std::vector<Eigen::VectorXd> partial_f(static_cast<std::size_t>(threads));
    std::exception_ptr failure;
#pragma omp parallel num_threads(threads)
    for (int t = omp_get_thread_num(); t < threads; t += omp_get_num_threads()) {  // share t (a smaller team: several)
      try {
        const Index low = ranges[static_cast<std::size_t>(t)].first, high = ranges[static_cast<std::size_t>(t)].second;
        std::vector<Real>& mine = partial[static_cast<std::size_t>(t)];
        if (copies) mine.assign(static_cast<std::size_t>(high - low), 0.0);
        Real* target = copies ? mine.data() : values;
        Eigen::VectorXd& my_f = partial_f[static_cast<std::size_t>(t)];
        my_f = Eigen::VectorXd::Zero(3 * n);
        NitscheColumns nitsche;
        Eigen::MatrixXd Kc;
        Eigen::VectorXd fc;
        for (std::size_t g = share(t); g < share(t + 1); ++g) {
          const auto [i, end] = groups[g];
          const auto& group = constraint_shapes[i];
          const Index size = 3 * static_cast<Index>(group.neighbours.size());
          bool penalty = false;
          for (std::size_t j = i; j < end; ++j) penalty |= !nitsche_point(constraint_points_[j]);
          nitsche.reset(size / 3, static_cast<Index>(end - i));
          fc.setZero(size);
          if (penalty) Kc.setZero(size, size);
          for (std::size_t j = i; j < end; ++j) {
            const auto& p = constraint_points_[j];
            const auto& sv = constraint_shapes[j];
            if (nitsche_point(p)) {
              const auto& mat = materials_[static_cast<std::size_t>(p.material)];
              const Real beta = options.nitsche_factor * mat.p_wave_modulus() / std::max(p.size, 1e-300);
              nitsche_columns(sv, p, mat, beta, nitsche, fc);
            } else {
              penalty_terms(sv, p, p.surface ? alpha_surface_ : alpha_point_, Kc, fc);
            }
          }
          if (penalty) {
            add_nitsche_products(nitsche, Kc);
            pattern.scatter(group.neighbours, Kc, target, low);
          } else {
            scatter_nitsche_products(nitsche, pattern, group.neighbours, target, low);
          }
          scatter_vector(group, fc, my_f);
        }
      } catch (...) {
#pragma omp critical(lamina_efg_boundary_failure)
        if (!failure) failure = std::current_exception();
      }
    }
    if (failure) std::rethrow_exception(failure);
    if (copies) add_thread_copies(values, partial, ranges);
    for (int t = 0; t < threads; ++t) f += partial_f[static_cast<std::size_t>(t)];
  }
  timings_["assembly_boundary_s"] = seconds_since(start);
  timings_["assembly_s"] = timings_["neighbours_s"] + timings_["pattern_s"] + volume_seconds + timings_["assembly_boundary_s"] +
                          (projected ? timings_["projection_s"] : 0.0);
  progress(0.7, "solving");
}

void EfgAnalysis::solve_galerkin(OutputSink* sink) {
  const Index n = problem_.cloud.size();
  const bool lagrange = problem_.options.essential == EssentialMethod::lagrange;
  GalerkinSystem& system = *system_;
  const solve::SparseMatrix& K = system.K;
  const Eigen::VectorXd& f = system.f;
  const bool symmetric = system.symmetric;
  const Index multipliers = system.multipliers;
  auto start = Clock::now();
  timings_["dofs"] = static_cast<Real>(3 * n + multipliers);
  timings_["nonzeros"] = static_cast<Real>(K.nonZeros());
  if (lagrange) {
    std::vector<Eigen::Triplet<Real>> entries;
    entries.reserve(static_cast<std::size_t>(symmetric ? 2 * K.nonZeros() : K.nonZeros()) + 2 * system.multiplier_entries.size());
    for (Index col = 0; col < K.outerSize(); ++col)
      for (solve::SparseMatrix::InnerIterator it(K, col); it; ++it) {
        entries.emplace_back(static_cast<int>(it.row()), static_cast<int>(col), it.value());
        if (symmetric && it.row() != col) entries.emplace_back(static_cast<int>(col), static_cast<int>(it.row()), it.value());
      }
    for (const auto& t : system.multiplier_entries) {
      entries.push_back(t);
      entries.emplace_back(t.col(), t.row(), t.value());
    }
    solve::SparseMatrix A(3 * n + multipliers, 3 * n + multipliers);
    A.setFromTriplets(entries.begin(), entries.end());
    Eigen::VectorXd rhs(3 * n + multipliers);
    rhs << f, system.multiplier_rhs;
    const Eigen::VectorXd x = solve::solve_general(A, rhs, solver_report_);
    u_ = x.head(3 * n);
    multipliers_ = x.tail(multipliers);
  } else if (problem_.options.solver.uses_petsc(comm_.distributed())) {
    u_ = symmetric ? solve::solve_symmetric_petsc(K, f, problem_.options.solver, comm_, solver_report_)
                   : solve::solve_general_petsc(K, f, problem_.options.solver, comm_, solver_report_);  // vci
  } else if (symmetric) {
    u_ = solve::solve_symmetric(K, f, solver_report_);
  } else {
    u_ = solve::solve_general(K, f, solver_report_);
  }
  record_solver_report();
  timings_["solve_total_s"] = seconds_since(start);
  if (sink) sink->progress(0.9, "solved (" + solver_report_.method + ")");
}

void EfgAnalysis::galerkin_energies() {
  const auto& options = problem_.options;
  const bool lagrange = options.essential == EssentialMethod::lagrange;
  const GalerkinSystem& system = *system_;
  const solve::SparseMatrix& K = system.K;
  const bool symmetric = system.symmetric;
  const auto& constraint_shapes = system.constraint_shapes;
  // energies: u^T K u over the whole system minus the constraint terms
  const Eigen::VectorXd Ku = symmetric ? solve::multiply_symmetric_upper(K, u_) : Eigen::VectorXd(K * u_);
  const auto points = static_cast<Index>(constraint_points_.size());
  reactions_.assign(constraint_points_.size(), Vec3::Zero());
  constraint_nearest_.assign(constraint_points_.size(), 0);
  std::vector<Real> point_energy(constraint_points_.size(), 0.0);  // summed in point order below
  // Lagrange multipliers: each point's first row (the rows of its held components, in point order)
  std::vector<Index> first_row(lagrange ? constraint_points_.size() : 0, 0);
  for (Index i = 0, row = 0; lagrange && i < points; ++i) {
    first_row[static_cast<std::size_t>(i)] = row;
    for (int a = 0; a < 3; ++a) row += constraint_points_[static_cast<std::size_t>(i)].constrained[static_cast<std::size_t>(a)] ? 1 : 0;
  }
#pragma omp parallel for schedule(static) if (points > 64)
  for (Index k = 0; k < points; ++k) {
    const auto i = static_cast<std::size_t>(k);
    const auto& p = constraint_points_[i];
    const auto& sv = constraint_shapes[i];
    constraint_nearest_[i] = nearest_node(p.x);
    const Vec3 uh = value_of(sv, u_);
    Vec3 r = Vec3::Zero();
    Real& constraint_energy = point_energy[i];
    if (lagrange) {
      Index row = first_row[i];
      for (int a = 0; a < 3; ++a)
        if (p.constrained[static_cast<std::size_t>(a)]) r[a] = -multipliers_[row++];
    } else if (options.essential == EssentialMethod::nitsche && p.surface) {
      const auto& mat = materials_[static_cast<std::size_t>(p.material)];
      const Real beta = options.nitsche_factor * mat.p_wave_modulus() / std::max(p.size, 1e-300);
      const Vec3 t = material::traction(mat.stress(material::strain_from_gradient(gradient_of(sv, u_))), p.normal);
      // u^T K_c u of the Nitsche K_c (add_nitsche_products) = sum over held a of w (-2 u_a t_a(u) + beta u_a^2), t = T u
      for (int a = 0; a < 3; ++a)
        if (p.constrained[static_cast<std::size_t>(a)]) {
          r[a] = p.weight * (t[a] - beta * (uh[a] - p.value[a]));
          constraint_energy += p.weight * (beta * uh[a] * uh[a] - 2.0 * uh[a] * t[a]);
        }
    } else {
      const Real alpha = p.surface ? alpha_surface_ : alpha_point_;
      for (int a = 0; a < 3; ++a)
        if (p.constrained[static_cast<std::size_t>(a)]) r[a] = -alpha * p.weight * (uh[a] - p.value[a]);
      for (int a = 0; a < 3; ++a)
        if (p.constrained[static_cast<std::size_t>(a)]) constraint_energy += alpha * p.weight * uh[a] * uh[a];
    }
    reactions_[i] = r;
  }
  Real constraint_energy = 0.0;
  for (const Real e : point_energy) constraint_energy += e;
  energy_internal_ = 0.5 * (comm_.sum(u_.dot(Ku)) - constraint_energy);  // several ranks: K is the sum of their shares
  if (projection_) nodal_pressure_ = projection_->lambda.cwiseProduct(projection_->nodal_divergence(u_));
  Real reaction_work = 0.0;
  for (std::size_t i = 0; i < constraint_points_.size(); ++i) reaction_work += reactions_[i].dot(constraint_points_[i].value);
  energy_external_ = 0.5 * (f_loads_.dot(u_) + reaction_work);
  system_.reset();  // the system is released before the post-processing
}

}  // namespace lamina::efg
