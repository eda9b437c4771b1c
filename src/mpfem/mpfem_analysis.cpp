#include "mpfem/mpfem_analysis.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <optional>
#include <set>

#include "core/error.hpp"
#include "core/step_stage.hpp"
#include "core/stopwatch.hpp"
#include "mpfem/dof_assembly.hpp"
#include "mpfem/gradient_list.hpp"
#include "mpfem/strain_fit.hpp"
#include "mpfem/triangle_strain.hpp"
#include "solve/petsc_linear_solver.hpp"

namespace lamina::mpfem {

namespace {

constexpr int kElementDofs = 2 * kElementNodes;
using ElementStrainOperator = Eigen::Matrix<Real, 3, kElementDofs>;
using ElementStiffness = Eigen::Matrix<Real, kElementDofs, kElementDofs>;

/// Strain operator [exx, eyy, gxy] of the element's dofs (u_x, u_y per local node).
ElementStrainOperator strain_operator(const ElementGradient& g) {
  ElementStrainOperator b = ElementStrainOperator::Zero();
  for (int a = 0; a < kElementNodes; ++a) {
    b(0, 2 * a) = g(0, a);
    b(1, 2 * a + 1) = g(1, a);
    b(2, 2 * a) = g(1, a);
    b(2, 2 * a + 1) = g(0, a);
  }
  return b;
}


}  // namespace

Eigen::Matrix3d PlaneMaterial::matrix() const {
  Eigen::Matrix3d c = Eigen::Matrix3d::Zero();
  if (plane == PlaneKind::stress) {
    c = elastic.plane_stress_matrix();
  } else {
    const Real l = elastic.lambda(), m = elastic.mu();
    c << l + 2 * m, l, 0, l, l + 2 * m, 0, 0, 0, m;
  }
  return c;
}

Real PlaneMaterial::out_of_plane(const Eigen::Vector3d& strain) const {
  if (plane == PlaneKind::stress) return -elastic.nu / (1 - elastic.nu) * (strain[0] + strain[1]);
  return elastic.lambda() * (strain[0] + strain[1]);
}

MpfemAnalysis::MpfemAnalysis(MpfemProblem problem, std::vector<Probe> probes, const parallel::Communicator& comm)
    : problem_(std::move(problem)), probes_(std::move(probes)), comm_(comm) {
  problem_.options.solver.check_ranks(comm_.size());
  const auto start = Clock::now();
  const Index n = problem_.layout.positions.cols();
  if (problem_.materials.empty()) throw InputError("materials", "at least one linear_elastic material", "none");
  if (static_cast<Index>(problem_.material_of_particle.size()) != n)
    problem_.material_of_particle.assign(static_cast<std::size_t>(n), 0);
  const bool large = problem_.options.analysis == MpfemAnalysisKind::large_deformation;
  for (std::size_t i = 0; i < problem_.materials.size(); ++i) {
    const auto& m = problem_.materials[i];
    materials_.push_back(PlaneMaterial{m, problem_.options.plane});
    const bool neo = i < problem_.material_models.size() && problem_.material_models[i] == material::MaterialModel::neo_hookean;
    if (neo && !large)
      throw InputError(fmt::format("materials.{}.model", i), "linear_elastic (or mpfem.analysis: large_deformation)",
                       "neo_hookean with mpfem.analysis: linear_static");
    hyperelastic_.push_back(material::Hyperelastic::from(
        neo ? material::HyperelasticKind::neo_hookean : material::HyperelasticKind::saint_venant_kirchhoff, m));
  }
  if (large && problem_.options.element == ElementKind::t3)
    throw InputError("mpfem.element", "element: five_node for mpfem.analysis: large_deformation", "element: t3");
  if (!(problem_.thickness > 0) || !std::isfinite(problem_.thickness))
    throw InputError("geometry", "a positive z extent (the out-of-plane thickness)", fmt::format("{}", problem_.thickness));
  if (problem_.options.element == ElementKind::t3 && !problem_.layout.grid)
    throw InputError("mpfem.element", "element: five_node for particle sets without a generator grid (t3 triangulates the grid)",
                     "element: t3");
  discretization_ = build_particle_elements(problem_.layout, problem_.options.elements);
  cell_strain_ = problem_.options.element == ElementKind::five_node &&
                 problem_.options.particle_strain != ParticleStrain::star;
  if (cell_strain_) {
    if (problem_.options.particle_strain == ParticleStrain::cell &&
        (!problem_.layout.grid || discretization_.rule != NeighbourRule::logical_grid))
      throw InputError("mpfem.particle_strain",
                       "particle_strain: voronoi or star for particle sets without a generator grid (or neighbours: sectors)", "cell");
    build_cell_operators();
  }
  if (problem_.options.element == ElementKind::t3) {
    discretization_.area_weight.setZero();
    for (const auto& t : grid_triangles())
      for (Index p : t.nodes) discretization_.area_weight[p] += t.area / 3;
  }
  for (const auto& p : probes_) {
    const bool vector_field = p.field == "displacement" || p.field == "reaction_force";
    const bool tensor_field = p.field == "stress" || p.field == "strain";
    if (vector_field) {
      if (vector_component(p.component) < 0 && p.component != "magnitude")
        throw InputError("probes." + p.name, "component x, y, z or magnitude", p.component);
      if (p.field == "reaction_force" && p.nodes.empty())
        throw InputError("probes." + p.name, "a select: for reaction_force", "none");
      if (p.field == "displacement" && !p.at && p.nodes.empty())
        throw InputError("probes." + p.name, "at: [x, y, z] or a selection", "neither");
    } else if (tensor_field) {
      if (tensor_component(p.component) < 0 && !(p.field == "stress" && p.component == "von_mises"))
        throw InputError("probes." + p.name, "component xx, yy, zz, xy, yz, zx (stress also von_mises)", p.component);
      if (!p.at && p.nodes.empty()) throw InputError("probes." + p.name, "at: [x, y, z] or a selection", "neither");
    } else if (p.field == "energy") {
      if (p.component != "internal" && p.component != "external" && p.component != "kinetic" && p.component != "total")
        throw InputError("probes." + p.name, "energy component internal, external, kinetic or total", p.component);
    } else {
      throw InputError("probes." + p.name,
                       "field displacement, strain, stress, reaction_force or energy (mpfem is a linear static analysis)",
                       p.field);
    }
  }
  timings_["setup_s"] = seconds_since(start);
}

void MpfemAnalysis::rebuild(const Points2& positions) {
  if (positions.cols() != problem_.layout.positions.cols())
    throw InputError("mpfem", fmt::format("{} particle positions", problem_.layout.positions.cols()),
                     fmt::format("{}", positions.cols()));
  problem_.layout.positions = positions;
  problem_.options.body_area.reset();  // the reference body's area no longer applies to moved particles
  discretization_ = build_particle_elements(problem_.layout, problem_.options.elements);
  if (cell_strain_) build_cell_operators();
  energy_points_.clear();
  solved_ = false;
}

namespace {

Eigen::Matrix<Real, 3, 2> gradient_block(const Vec2& g) {
  Eigen::Matrix<Real, 3, 2> b;
  b << g.x(), 0, 0, g.y(), g.y(), g.x();
  return b;
}

void add_block(std::vector<std::pair<Index, Eigen::Matrix<Real, 3, 2>>>& list, Index particle,
               const Eigen::Matrix<Real, 3, 2>& block) {
  for (auto& [p, b] : list)
    if (p == particle) {
      b += block;
      return;
    }
  list.emplace_back(particle, block);
}

}  // namespace

void MpfemAnalysis::build_cell_operators() {
  if (problem_.options.particle_strain == ParticleStrain::voronoi) {
    const Real reach = problem_.options.elements.max_neighbour_distance * discretization_.typical_spacing;
    VoronoiCells voronoi = build_voronoi_cells(problem_.layout, discretization_, reach, problem_.body_boundary);
    const auto& area = problem_.options.body_area;
    if (area && std::abs(voronoi.hull_area - *area) > 1e-9 * *area)
      throw InputError("discretization.particles",
                       "particles on the body's corners and edges (particle_strain: voronoi integrates over the "
                       "particles' convex hull)",
                       fmt::format("a convex hull of area {:.9g} for a body of area {:.9g}", voronoi.hull_area, *area));
    cells_ = std::move(voronoi.cells);
    discretization_.boundary = std::move(voronoi.boundary);
    discretization_.boundary_weight = std::move(voronoi.boundary_weight);
  } else {
    cells_ = build_tributary_cells(problem_.layout);
  }
  const Index n = problem_.layout.positions.cols();
  discretization_.area_weight = cells_.area;
  cell_strain_ops_.assign(static_cast<std::size_t>(n), {});
  strain_gradient_.assign(static_cast<std::size_t>(n), {});
  strain_gradient_vectors_.assign(static_cast<std::size_t>(n), {});
  for (Index p = 0; p < n; ++p)
    for (const auto& [q, g] : cells_.mean_gradient[static_cast<std::size_t>(p)])
      cell_strain_ops_[static_cast<std::size_t>(p)].emplace_back(q, gradient_block(g));
#pragma omp parallel for schedule(static)
  for (Index p = 0; p < n; ++p) {
    const ParticleElement& e = discretization_.elements[static_cast<std::size_t>(p)];
    // the five-node element on the cell centroids (falls back to the particles if it folds)
    ElementGradient d = ElementGradient::Zero();
    Real area = 0;
    bool folded = false;
    for (int t = 0; t < e.triangle_count; ++t) {
      const auto& tri = e.triangles[static_cast<std::size_t>(t)];
      std::array<Vec2, 3> c;
      for (int k = 0; k < 3; ++k)
        c[static_cast<std::size_t>(k)] = cells_.centroid.col(e.nodes[static_cast<std::size_t>(tri.local[static_cast<std::size_t>(k)])]);
      Real a = 0;
      const Eigen::Matrix<Real, 2, 3> g = triangle_gradient(c[0], c[1], c[2], a);
      if (!(a > 0)) {
        folded = true;
        break;
      }
      for (int k = 0; k < 3; ++k) d.col(tri.local[static_cast<std::size_t>(k)]) += a * g.col(k);
      area += a;
    }
    d = folded ? e.mean_gradient : ElementGradient(d / area);
    for (int axis = 0; axis < 2; ++axis) {
      auto& g = strain_gradient_[static_cast<std::size_t>(p)][static_cast<std::size_t>(axis)];
      for (int a = 0; a < kElementNodes; ++a) {
        const Index j = e.nodes[static_cast<std::size_t>(a)];
        if (j < 0 || d(axis, a) == 0.0) continue;
        for (const auto& [q, block] : cell_strain_ops_[static_cast<std::size_t>(j)]) add_block(g, q, d(axis, a) * block);
        auto& gv = strain_gradient_vectors_[static_cast<std::size_t>(p)][static_cast<std::size_t>(axis)];
        for (const auto& [q, v] : cells_.mean_gradient[static_cast<std::size_t>(j)]) add_gradient(gv, q, d(axis, a) * v);
      }
    }
  }
}

void MpfemAnalysis::assemble_cell_stiffness(std::vector<Eigen::Triplet<Real, int>>& triplets) const {
  const Index n = problem_.layout.positions.cols();
  const Real thickness = problem_.thickness, beta = problem_.options.stabilization;
  constexpr Index kChunk = 512;
  for (Index begin = 0; begin < n; begin += kChunk) {
    const Index end = std::min(n, begin + kChunk);
    std::vector<IndexList> particles(static_cast<std::size_t>(end - begin));
    std::vector<Eigen::MatrixXd> local(static_cast<std::size_t>(end - begin));
#pragma omp parallel for schedule(static)
    for (Index p = begin; p < end; ++p) {
      const ParticleElement& e = discretization_.elements[static_cast<std::size_t>(p)];
      IndexList& list = particles[static_cast<std::size_t>(p - begin)];
      auto slot = [&](Index q) {
        for (std::size_t k = 0; k < list.size(); ++k)
          if (list[k] == q) return static_cast<Index>(k);
        list.push_back(q);
        return static_cast<Index>(list.size() - 1);
      };
      const auto& b_ops = cell_strain_ops_[static_cast<std::size_t>(p)];
      const auto& g_ops = strain_gradient_[static_cast<std::size_t>(p)];
      for (const auto& [q, block] : b_ops) slot(q);
      for (const auto& ops : g_ops)
        for (const auto& [q, block] : ops) slot(q);
      for (Index q : e.nodes)
        if (q >= 0) slot(q);
      const Index m = static_cast<Index>(list.size());
      auto dense = [&](const StrainBlocks& ops) {
        Eigen::MatrixXd b = Eigen::MatrixXd::Zero(3, 2 * m);
        for (const auto& [q, block] : ops) b.middleCols<2>(2 * slot(q)) += block;
        return b;
      };
      const Eigen::Matrix3d c =
          materials_[static_cast<std::size_t>(problem_.material_of_particle[static_cast<std::size_t>(p)])].matrix();
      const Real omega = cells_.area[p];
      const Eigen::MatrixXd b = dense(b_ops);
      const std::array<Eigen::MatrixXd, 2> g{dense(g_ops[0]), dense(g_ops[1])};
      const Eigen::Matrix2d& moment = cells_.second_moment[static_cast<std::size_t>(p)];
      Eigen::MatrixXd k = omega * b.transpose() * c * b;
      for (int a = 0; a < 2; ++a)
        for (int bb = 0; bb < 2; ++bb) k += moment(a, bb) * g[static_cast<std::size_t>(a)].transpose() * c * g[static_cast<std::size_t>(bb)];
      for (int t = 0; t < e.triangle_count; ++t) {
        const auto& tri = e.triangles[static_cast<std::size_t>(t)];
        Eigen::MatrixXd deviation = -b;
        for (int a = 0; a < kElementNodes; ++a) {
          const Index q = e.nodes[static_cast<std::size_t>(a)];
          if (q >= 0) deviation.middleCols<2>(2 * slot(q)) += gradient_block(tri.gradient.col(a));
        }
        k += (beta * omega * tri.area / e.area) * deviation.transpose() * c * deviation;
      }
      local[static_cast<std::size_t>(p - begin)] = thickness * k;
    }
    for (Index p = begin; p < end; ++p)
      add_local_stiffness(particles[static_cast<std::size_t>(p - begin)], local[static_cast<std::size_t>(p - begin)], triplets);
  }
}

Eigen::VectorXd MpfemAnalysis::load_vector() const {
  const Points2& x = problem_.layout.positions;
  const Index n = x.cols();
  Eigen::VectorXd f = Eigen::VectorXd::Zero(2 * n);
  const Real thickness = problem_.thickness;
  auto at3 = [&](const Vec2& p) { return Vec3(p.x(), p.y(), problem_.z_mid); };
  for (const auto& load : problem_.loads) {
    std::set<Index> selected(load.select.nodes.begin(), load.select.nodes.end());
    if (load.kind == model::Load::Kind::force) {
      const geometry::FieldEvaluator fx(load.vector[0], 1.0), fy(load.vector[1], 1.0);
      const Real share = 1.0 / static_cast<Real>(load.select.nodes.size());
      for (Index p : load.select.nodes) {
        f[2 * p] += share * fx(at3(x.col(p)));
        f[2 * p + 1] += share * fy(at3(x.col(p)));
      }
    } else if (load.kind == model::Load::Kind::body_force) {
      const geometry::FieldEvaluator bx(load.vector[0], 1.0), by(load.vector[1], 1.0);
      for (Index p : load.select.nodes) {
        const Real dv = thickness * discretization_.area_weight[p];
        f[2 * p] += dv * bx(at3(x.col(p)));
        f[2 * p + 1] += dv * by(at3(x.col(p)));
      }
    } else {
      const bool pressure = load.kind == model::Load::Kind::pressure;
      const geometry::FieldEvaluator tx(load.vector[0], 1.0), ty(load.vector[1], 1.0), pr(load.scalar, 1.0);
      auto traction = [&](const Vec2& p, const Vec2& normal) -> Vec2 {
        if (pressure) return -pr(at3(p)) * normal;
        return Vec2(tx(at3(p)), ty(at3(p)));
      };
      int segments = 0;
      for (const auto& s : discretization_.boundary) {
        if (!selected.count(s.a) || !selected.count(s.b)) continue;
        ++segments;
        const Vec2 xa = x.col(s.a), xb = x.col(s.b);
        if (problem_.options.traction_quadrature == TractionQuadrature::particle) {
          // seed eq (6): t(x_I) dS_I, dS_I = half of each selected segment at I
          f.segment<2>(2 * s.a) += traction(xa, s.normal) * 0.5 * s.length * thickness;
          f.segment<2>(2 * s.b) += traction(xb, s.normal) * 0.5 * s.length * thickness;
        } else {
          for (Real g : {0.5 - 0.5 / std::sqrt(3.0), 0.5 + 0.5 / std::sqrt(3.0)}) {
            const Vec2 t = traction((1 - g) * xa + g * xb, s.normal) * 0.5 * s.length * thickness;
            f.segment<2>(2 * s.a) += (1 - g) * t;
            f.segment<2>(2 * s.b) += g * t;
          }
        }
      }
      if (segments == 0)
        throw InputError(load.select.label + ".select",
                         "a selection containing two adjacent boundary particles (traction and pressure act on "
                         "boundary segments between selected particles)",
                         fmt::format("{} particle(s), no boundary segment", load.select.nodes.size()));
    }
  }
  return f;
}

void MpfemAnalysis::assemble_linear() {
  const Points2& x = problem_.layout.positions;
  const Index n = x.cols();
  const Real thickness = problem_.thickness;
  std::vector<Eigen::Triplet<Real, int>> triplets;
  if (cell_strain_) {
    assemble_cell_stiffness(triplets);
  } else if (problem_.options.element == ElementKind::five_node) {
    const Real beta = problem_.options.stabilization;
    std::vector<ElementStiffness> local(static_cast<std::size_t>(n));
#pragma omp parallel for schedule(static)
    for (Index p = 0; p < n; ++p) {
      const ParticleElement& e = discretization_.elements[static_cast<std::size_t>(p)];
      const Eigen::Matrix3d c = materials_[static_cast<std::size_t>(problem_.material_of_particle[static_cast<std::size_t>(p)])].matrix();
      const Real dv = thickness * discretization_.area_weight[p];
      const ElementStrainOperator mean = strain_operator(e.mean_gradient);
      ElementStiffness k = dv * mean.transpose() * c * mean;
      for (int t = 0; t < e.triangle_count; ++t) {
        const auto& tri = e.triangles[static_cast<std::size_t>(t)];
        const ElementStrainOperator deviation = strain_operator(tri.gradient) - mean;
        k += (beta * dv * tri.area / e.area) * deviation.transpose() * c * deviation;
      }
      local[static_cast<std::size_t>(p)] = k;
    }
    triplets.reserve(static_cast<std::size_t>(n) * 100);
    for (Index p = 0; p < n; ++p) {
      const ParticleElement& e = discretization_.elements[static_cast<std::size_t>(p)];
      add_local_stiffness(e.nodes, local[static_cast<std::size_t>(p)], triplets);
    }
  } else {
    for (const auto& t : grid_triangles()) {
      const Eigen::Matrix3d c = materials_[static_cast<std::size_t>(problem_.material_of_particle[static_cast<std::size_t>(t.nodes[0])])].matrix();
      const Eigen::Matrix<Real, 3, 6> b = triangle_strain_operator(t.gradient);
      const Eigen::Matrix<Real, 6, 6> k = (thickness * t.area) * b.transpose() * c * b;
      add_local_stiffness(t.nodes, k, triplets);
    }
  }
  stiffness_.resize(static_cast<int>(2 * n), static_cast<int>(2 * n));
  stiffness_.setFromTriplets(triplets.begin(), triplets.end());
  f_ = load_vector();
}

Eigen::VectorXd MpfemAnalysis::solve_system(const solve::SparseMatrix& upper, const Eigen::VectorXd& rhs,
                                            const solve::SolverOptions& options, bool positive_definite) {
  if (problem_.options.solver.uses_petsc(comm_.distributed()))
    return solve::solve_symmetric_petsc(upper, rhs, problem_.options.solver, comm_, solver_report_,
                                        solve::SystemShares::replicated, positive_definite, 2);
  return solve::solve_symmetric(upper, rhs, solver_report_, options);
}

void MpfemAnalysis::solve_linear() {
  const Index n = problem_.layout.positions.cols();
  // essential conditions: eliminate the prescribed particle dofs
  const FreeDofs dofs = number_free_dofs(problem_.prescribed, n);
  const std::vector<char>& prescribed = dofs.prescribed;
  const std::vector<int>& free_id = dofs.free_id;
  const int free_count = dofs.count;
  Eigen::VectorXd u = dofs.values;
  if (free_count > 0) {
    Eigen::VectorXd rhs(free_count);
    for (Index i = 0; i < 2 * n; ++i)
      if (free_id[static_cast<std::size_t>(i)] >= 0) rhs[free_id[static_cast<std::size_t>(i)]] = f_[i];
    const solve::SparseMatrix k = reduce_to_free_dofs(stiffness_, dofs, &u, &rhs);
    if (!rhs.allFinite()) throw AnalysisError("mpfem: non-finite load vector; check the load expressions");
    Eigen::VectorXd uf;
    try {
      // a free rigid-body motion leaves only round-off pivots: (min/max pivot)^2 ~ 1e-16 and below,
      // while a well-posed particle model stays above ~ (h / L)^4 >> 1e-13
      solve::SolverOptions solver;
      solver.min_rcond = 1e-13;
      solver.allow_fallback = false;
      uf = solve_system(k, rhs, solver, true);
    } catch (const SolverUnavailable&) {
      throw;  // nothing about this system: no advice on its supports
    } catch (const AnalysisError& e) {
      throw AnalysisError(std::string(e.what()) +
                          " (mpfem: fix enough particle dofs (boundary: fix / displacement) to remove the rigid-body "
                          "motions of every disconnected part, or raise mpfem.stabilization if it is very small)");
    }
    for (Index i = 0; i < 2 * n; ++i)
      if (free_id[static_cast<std::size_t>(i)] >= 0) u[i] = uf[free_id[static_cast<std::size_t>(i)]];
  }
  if (!u.allFinite()) throw AnalysisError("mpfem: non-finite displacements; the system is singular");
  u_ = u;
  const Eigen::VectorXd ku = stiffness_ * u_;
  reactions_ = ku - f_;
  for (Index i = 0; i < 2 * n; ++i)
    if (!prescribed[static_cast<std::size_t>(i)]) reactions_[i] = 0;
  energy_internal_ = 0.5 * u_.dot(ku);
  energy_external_ = 0.5 * (f_.dot(u_) + reactions_.dot(u_));
}

void MpfemAnalysis::particle_strains_and_stresses() {
  const Index n = problem_.layout.positions.cols();
  // particle strains and stresses
  strain_.resize(3, n);
  stress_.resize(3, n);
  out_of_plane_.resize(n);
  if (cell_strain_) {
#pragma omp parallel for schedule(static)
    for (Index p = 0; p < n; ++p) {
      const auto sp = static_cast<std::size_t>(p);
      Eigen::Vector3d eps = Eigen::Vector3d::Zero();
      for (const auto& [q, block] : cell_strain_ops_[sp]) eps += block * u_.segment<2>(2 * q);
      const Vec2 offset = problem_.layout.positions.col(p) - cells_.centroid.col(p);
      for (int a = 0; a < 2; ++a)
        for (const auto& [q, block] : strain_gradient_[sp][static_cast<std::size_t>(a)])
          eps += offset[a] * (block * u_.segment<2>(2 * q));
      strain_.col(p) = eps;
    }
    if (problem_.options.particle_strain == ParticleStrain::voronoi) {
      // unstructured sets: the least-squares fit of the neighbouring cells' mean strains (strain_fit.hpp)
      Eigen::Matrix3Xd mean(3, n);
#pragma omp parallel for schedule(static)
      for (Index p = 0; p < n; ++p) {
        Eigen::Vector3d eps = Eigen::Vector3d::Zero();
        for (const auto& [q, block] : cell_strain_ops_[static_cast<std::size_t>(p)]) eps += block * u_.segment<2>(2 * q);
        mean.col(p) = eps;
      }
      strain_ = fit_particle_strains(problem_.layout.positions, cells_.centroid, discretization_.elements, mean);
    }
  } else if (problem_.options.element == ElementKind::five_node) {
#pragma omp parallel for schedule(static)
    for (Index p = 0; p < n; ++p) {
      const ParticleElement& e = discretization_.elements[static_cast<std::size_t>(p)];
      Eigen::Vector3d eps = Eigen::Vector3d::Zero();
      for (int a = 0; a < kElementNodes; ++a) {
        const Index j = e.nodes[static_cast<std::size_t>(a)];
        if (j < 0) continue;
        const Vec2 uj = u_.segment<2>(2 * j);
        eps[0] += e.mean_gradient(0, a) * uj.x();
        eps[1] += e.mean_gradient(1, a) * uj.y();
        eps[2] += e.mean_gradient(1, a) * uj.x() + e.mean_gradient(0, a) * uj.y();
      }
      strain_.col(p) = eps;
    }
  } else {
    strain_.setZero();
    Eigen::VectorXd area = Eigen::VectorXd::Zero(n);
    for (const auto& t : grid_triangles()) {
      Eigen::Matrix<Real, 6, 1> ul;
      for (int a = 0; a < 3; ++a) ul.segment<2>(2 * a) = u_.segment<2>(2 * t.nodes[static_cast<std::size_t>(a)]);
      const Eigen::Vector3d eps = triangle_strain_operator(t.gradient) * ul;
      for (Index p : t.nodes) strain_.col(p) += t.area * eps, area[p] += t.area;
    }
    for (Index p = 0; p < n; ++p) strain_.col(p) /= area[p];
  }
  for (Index p = 0; p < n; ++p) {
    const PlaneMaterial& m = materials_[static_cast<std::size_t>(problem_.material_of_particle[static_cast<std::size_t>(p)])];
    stress_.col(p) = m.matrix() * strain_.col(p);
    out_of_plane_[p] = m.out_of_plane(strain_.col(p));
  }
  if (!stress_.allFinite()) throw AnalysisError("mpfem: non-finite particle stresses");
}

void MpfemAnalysis::solve() { solve_with(nullptr); }

std::vector<StepStage> MpfemAnalysis::stages(OutputSink* sink) {
  std::vector<StepStage> list;
  if (problem_.options.analysis == MpfemAnalysisKind::large_deformation)
    list.push_back({"large_deformation", [this, sink] { solve_large_deformation(sink); }});
  else
    list.insert(list.end(), {{"assemble", [this] { assemble_linear(); }},
                             {"solve", [this] { solve_linear(); }},
                             {"strains", [this] { particle_strains_and_stresses(); }}});
  list.push_back({"errors", [this] { compute_errors(); }});
  return list;
}

void MpfemAnalysis::solve_with(OutputSink* sink) {
  const auto start = Clock::now();
  const std::vector<StepStage> list = stages(sink);
  std::vector<Real> seconds(list.size(), 0.0);
  run_stages(list, seconds);
  for (std::size_t k = 0; k < list.size(); ++k) timings_[std::string(list[k].name) + "_s"] = seconds[k];
  solved_ = true;
  timings_["total_s"] = seconds_since(start) + timings_["setup_s"];
}

void MpfemAnalysis::run(OutputSink& sink) {
  sink.progress(0.0, "assembling");
  solve_with(&sink);
  sink.progress(1.0, "solved");
  sink.output_point(1, 1.0, 1.0);
}

Real MpfemAnalysis::total_volume() const { return problem_.thickness * discretization_.area_weight.sum(); }

}  // namespace lamina::mpfem
