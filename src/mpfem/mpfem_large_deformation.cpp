// MpfemAnalysis, large deformation (docs/mpfem.md section 9): total-Lagrangian Newton iterations on
// load increments over the energy points of energy_points.hpp, with the particle neighbourhoods
// rebuilt from the current positions when they change ("moving particles", seed 001).
//   Energy      Pi(u) = t sum_I sum_{q in I} w_q W(F_q) - lambda f.u,   F_q = I + sum_J u_J b_qJ^T
//   Residual    r_Ji  = t sum_q w_q P_iJ(F_q) b_qJ,J - lambda f_Ji
//   Tangent     K_(Ji)(Kk) = t sum_q w_q A_iJkL(F_q) b_qJ,J b_qK,L   (material + geometric: A = dP/dF)
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "core/error.hpp"
#include "core/stopwatch.hpp"
#include "mpfem/dof_assembly.hpp"
#include "mpfem/mpfem_analysis.hpp"

namespace lamina::mpfem {

namespace {


Eigen::Matrix2d deformation_gradient(const GradientList& list, const Eigen::VectorXd& u) {
  Eigen::Matrix2d F = Eigen::Matrix2d::Identity();
  for (const auto& [j, b] : list) F += u.segment<2>(2 * j) * b.transpose();
  return F;
}

}  // namespace

void MpfemAnalysis::build_energy_points() {
  const Index n = problem_.layout.positions.cols();
  const Real beta = problem_.options.stabilization;
  energy_points_.assign(static_cast<std::size_t>(n), {});
#pragma omp parallel for schedule(static)
  for (Index p = 0; p < n; ++p) {
    const auto sp = static_cast<std::size_t>(p);
    const ParticleElement& e = discretization_.elements[sp];
    energy_points_[sp] = cell_strain_ ? cell_energy_points(e, cells_.mean_gradient[sp], strain_gradient_vectors_[sp],
                                                           cells_.area[p], cells_.second_moment[sp], beta)
                                      : star_energy_points(e, discretization_.area_weight[p], beta);
  }
}

bool MpfemAnalysis::internal_forces(const Eigen::VectorXd& u, Eigen::VectorXd& force, solve::SparseMatrix* tangent,
                                    Real* energy) const {
  const Index n = problem_.layout.positions.cols();
  const bool plane_stress = problem_.options.plane == PlaneKind::stress;
  const Real thickness = problem_.thickness;
  force = Eigen::VectorXd::Zero(2 * n);
  std::vector<Eigen::Triplet<Real, int>> triplets;
  Real total = 0;
  bool valid = true;
  constexpr Index kChunk = 512;
  for (Index begin = 0; begin < n && valid; begin += kChunk) {
    const Index end = std::min(n, begin + kChunk);
    const auto count = static_cast<std::size_t>(end - begin);
    std::vector<IndexList> particles(count);
    std::vector<Eigen::VectorXd> local_force(count);
    std::vector<Eigen::MatrixXd> local_tangent(count);
    std::vector<Real> local_energy(count, 0.0);
    std::vector<char> ok(count, 1);
#pragma omp parallel for schedule(static)
    for (Index p = begin; p < end; ++p) {
      const auto s = static_cast<std::size_t>(p - begin);
      const auto& points = energy_points_[static_cast<std::size_t>(p)];
      const material::Hyperelastic& m =
          hyperelastic_[static_cast<std::size_t>(problem_.material_of_particle[static_cast<std::size_t>(p)])];
      IndexList& list = particles[s];
      auto slot = [&](Index q) {
        for (std::size_t k = 0; k < list.size(); ++k)
          if (list[k] == q) return static_cast<Index>(k);
        list.push_back(q);
        return static_cast<Index>(list.size() - 1);
      };
      for (const auto& q : points)
        for (const auto& [j, b] : q.gradient) slot(j);
      const Index size = static_cast<Index>(list.size());
      Eigen::VectorXd f = Eigen::VectorXd::Zero(2 * size);
      Eigen::MatrixXd k;
      if (tangent) k = Eigen::MatrixXd::Zero(2 * size, 2 * size);
      Real w_total = 0;
      for (const auto& q : points) {
        const Eigen::Matrix2d F = deformation_gradient(q.gradient, u);
        const material::HyperelasticResponse2 r = material::hyperelastic_response_2d(m, F, plane_stress);
        if (!r.valid) {
          ok[s] = 0;
          break;
        }
        const Real w = thickness * q.weight;
        w_total += w * r.energy;
        // gradient operator: dF_iJ / du_(slot a, k) = delta_ik b_aJ
        for (const auto& [j, b] : q.gradient) {
          const Index a = slot(j);
          f.segment<2>(2 * a) += w * (r.stress * b);
        }
        if (!tangent) continue;
        for (const auto& [j, bj] : q.gradient) {
          const Index a = slot(j);
          for (const auto& [l, bl] : q.gradient) {
            const Index c = slot(l);
            for (int i = 0; i < 2; ++i)
              for (int kk = 0; kk < 2; ++kk) {
                Real v = 0;
                for (int J = 0; J < 2; ++J)
                  for (int L = 0; L < 2; ++L) v += r.tangent(2 * i + J, 2 * kk + L) * bj[J] * bl[L];
                k(2 * a + i, 2 * c + kk) += w * v;
              }
          }
        }
      }
      local_force[s] = std::move(f);
      local_tangent[s] = std::move(k);
      local_energy[s] = w_total;
    }
    for (std::size_t s = 0; s < count; ++s) {
      if (!ok[s]) {
        valid = false;
        break;
      }
      const IndexList& list = particles[s];
      total += local_energy[s];
      for (std::size_t a = 0; a < list.size(); ++a) force.segment<2>(2 * list[a]) += local_force[s].segment<2>(2 * static_cast<Index>(a));
      if (!tangent) continue;
      add_local_stiffness(list, local_tangent[s], triplets);
    }
  }
  if (!valid) return false;
  if (energy) *energy = total;
  if (tangent) {
    tangent->resize(static_cast<int>(2 * n), static_cast<int>(2 * n));
    tangent->setFromTriplets(triplets.begin(), triplets.end());
  }
  return force.allFinite();
}

Index MpfemAnalysis::changed_neighbourhoods(const Eigen::VectorXd& u, std::vector<std::array<Index, 4>>& chosen) const {
  if (problem_.options.elements.rule == NeighbourRule::logical_grid) return 0;  // logical neighbours never change
  ParticleLayout current = problem_.layout;
  for (Index p = 0; p < current.positions.cols(); ++p) current.positions.col(p) += u.segment<2>(2 * p);
  chosen = choose_neighbours(current, problem_.options.elements);
  // a new neighbour set is taken only if its star is sound on the reference positions (where the element
  // geometry is built): every triangle between consecutive neighbours either clearly positive (sine of
  // the angle at the particle >= 0.1) or reflex / flat (skipped); at least one triangle
  const Points2& X = problem_.layout.positions;
  auto sound = [&](std::size_t p, const std::array<Index, 4>& set) {
    int triangles = 0;
    for (int k = 0; k < 4; ++k) {
      const Index a = set[static_cast<std::size_t>(k)], b = set[static_cast<std::size_t>((k + 1) % 4)];
      if (a < 0 || b < 0) continue;
      const Vec2 da = X.col(a) - X.col(static_cast<Index>(p)), db = X.col(b) - X.col(static_cast<Index>(p));
      const Real sine = (da.x() * db.y() - da.y() * db.x()) / (da.norm() * db.norm());
      if (sine >= 0.1) ++triangles;
      else if (sine > 0) return false;
    }
    return triangles > 0;
  };
  Index changed = 0;
  for (std::size_t p = 0; p < chosen.size(); ++p) {
    std::array<Index, 4> now = chosen[p], before{}, current{};
    for (int k = 0; k < 4; ++k)
      current[static_cast<std::size_t>(k)] = discretization_.elements[p].nodes[static_cast<std::size_t>(k + 1)];
    before = current;
    std::sort(now.begin(), now.end());
    std::sort(before.begin(), before.end());
    if (now == before) continue;
    if (!sound(p, chosen[p])) {
      chosen[p] = current;
      continue;
    }
    ++changed;
  }
  return changed;
}

void MpfemAnalysis::solve_large_deformation(OutputSink* sink) {
  const auto start = Clock::now();
  const auto& options = problem_.options.large_deformation;
  const Index n = problem_.layout.positions.cols();
  build_energy_points();
  f_ = load_vector();  // dead loads on the reference configuration
  const FreeDofs dofs = number_free_dofs(problem_.prescribed, n);
  const std::vector<char>& prescribed = dofs.prescribed;
  const Eigen::VectorXd& u_prescribed = dofs.values;
  const std::vector<int>& free_id = dofs.free_id;
  const int free_count = dofs.count;
  if (!f_.allFinite()) throw AnalysisError("mpfem: non-finite load vector; check the load expressions");

  // the residual's round-off floor: 1e-12 x the force of a unit strain on one particle (E t h)
  Real modulus = 0;
  for (const auto& m : problem_.materials) modulus = std::max(modulus, m.E);
  const Real round_off = 1e-12 * modulus * problem_.thickness * discretization_.typical_spacing;
  // Newton iterations at load factor `level` from u; false if not converged
  std::string failure;
  auto newton = [&](Eigen::VectorXd& u, Real level) {
    for (Index i = 0; i < 2 * n; ++i)
      if (prescribed[static_cast<std::size_t>(i)]) u[i] = level * u_prescribed[i];
    Eigen::VectorXd force;
    solve::SparseMatrix tangent;
    Real last_correction = INFINITY;
    for (int iteration = 0; iteration <= options.max_iterations; ++iteration) {
      if (!internal_forces(u, force, &tangent, nullptr)) {
        failure = "a particle's deformation gradient has J <= 0 (the particles are turned inside out)";
        return false;
      }
      Eigen::VectorXd residual(free_count);
      Real reference = 0;
      for (Index i = 0; i < 2 * n; ++i) {
        const int f = free_id[static_cast<std::size_t>(i)];
        if (f >= 0) residual[f] = force[i] - level * f_[i], reference = std::max(reference, std::abs(level * f_[i]));
        else reference = std::max(reference, std::abs(force[i]));
      }
      const Real norm = residual.lpNorm<Eigen::Infinity>();
      // converged: the residual below tolerance x the force scale, or (loads so small that round-off in the
      // stresses dominates the residual) a last correction at round-off level of the displacements
      if (iteration > 0 && (norm <= std::max(options.tolerance * reference, round_off) ||
                            last_correction <= 1e-4 * options.tolerance * u.lpNorm<Eigen::Infinity>()))
        return true;
      if (iteration == options.max_iterations) {
        failure = fmt::format("Newton did not converge in {} iterations (residual {:.3g} x the largest force)",
                              options.max_iterations, norm / std::max(reference, 1e-300));
        return false;
      }
      const solve::SparseMatrix k = reduce_to_free_dofs(tangent, dofs);
      Eigen::VectorXd du;
      try {
        solve::SolverOptions solver;
        solver.min_rcond = 1e-13;
        solver.allow_fallback = true;  // the tangent may be indefinite away from equilibrium
        du = solve_system(k, -residual, solver, false);
      } catch (const SolverUnavailable&) {
        throw;  // no solver at all: not a failed increment to cut back
      } catch (const AnalysisError& e) {
        failure = std::string("the tangent system could not be solved: ") + e.what();
        return false;
      }
      if (!du.allFinite()) {
        failure = "non-finite Newton correction";
        return false;
      }
      ++stats_.newton_iterations;
      last_correction = du.lpNorm<Eigen::Infinity>();
      for (Index i = 0; i < 2 * n; ++i)
        if (free_id[static_cast<std::size_t>(i)] >= 0) u[i] += du[free_id[static_cast<std::size_t>(i)]];
    }
    return false;
  };

  Eigen::VectorXd u = Eigen::VectorXd::Zero(2 * n);
  Real level = 0, step = 1.0 / options.increments;
  int cuts_in_a_row = 0;
  while (level < 1.0 - 1e-12) {
    const Real target = std::min(1.0, level + step);
    Eigen::VectorXd trial = u;
    bool converged = newton(trial, target);
    if (converged && options.rebuild) {
      // moving particles: rebuild the elements when the neighbourhoods on the current positions differ
      std::vector<std::array<Index, 4>> chosen;
      const Index changed = changed_neighbourhoods(trial, chosen);
      if (changed > 0) {
        ++stats_.rebuilds;
        stats_.rebuilt_particles += changed;
        try {
          discretization_ = build_particle_elements(problem_.layout, problem_.options.elements, &chosen);
          if (cell_strain_) build_cell_operators();
        } catch (const InputError& e) {
          throw AnalysisError(fmt::format("mpfem: rebuilding the particle elements on the deformed positions at load "
                                          "factor {:.4g} failed: {}", target, e.what()));
        }
        build_energy_points();
        converged = newton(trial, target);  // re-solve the increment on the rebuilt elements
      }
    }
    if (!converged) {
      ++stats_.cuts;
      if (++cuts_in_a_row > options.bisections)
        throw AnalysisError(fmt::format("mpfem: large_deformation diverged at load factor {:.6g} (last converged "
                                        "{:.6g}) after {} halvings of the increment: {}",
                                        target, level, options.bisections, failure));
      step *= 0.5;
      continue;
    }
    cuts_in_a_row = 0;
    u = trial;
    level = target;
    ++stats_.increments;
    if (sink) sink->progress(level, fmt::format("load factor {:.3g}", level));
  }
  u_ = u;
  Eigen::VectorXd force;
  internal_forces(u_, force, nullptr, &energy_internal_);
  reactions_ = force - f_;
  for (Index i = 0; i < 2 * n; ++i)
    if (!prescribed[static_cast<std::size_t>(i)]) reactions_[i] = 0;
  energy_external_ = f_.dot(u_) + reactions_.dot(u_);  // work of the dead loads and reactions (not 1/2)
  large_deformation_results();
  timings_["solve_s"] = std::chrono::duration<double>(Clock::now() - start).count();
}

void MpfemAnalysis::large_deformation_results() {
  // particle values at the cell-mean (star-mean) deformation gradient: Green-Lagrange strain,
  // Cauchy stress; out of plane: E_zz (plane stress) or sigma_zz (plane strain)
  const Index n = problem_.layout.positions.cols();
  const bool plane_stress = problem_.options.plane == PlaneKind::stress;
  strain_.resize(3, n);
  stress_.resize(3, n);
  out_of_plane_.resize(n);
  for (Index p = 0; p < n; ++p) {
    const auto sp = static_cast<std::size_t>(p);
    GradientList list;
    if (cell_strain_) list = cells_.mean_gradient[sp];
    else list = energy_points_[sp].front().gradient;
    const Eigen::Matrix2d F2 = deformation_gradient(list, u_);
    const material::Hyperelastic& m = hyperelastic_[static_cast<std::size_t>(problem_.material_of_particle[sp])];
    const material::HyperelasticResponse2 r = material::hyperelastic_response_2d(m, F2, plane_stress);
    Mat3 F = Mat3::Identity(), P = Mat3::Zero();
    F.topLeftCorner<2, 2>() = F2;
    F(2, 2) = r.stretch33;
    P.topLeftCorner<2, 2>() = r.stress;
    P(2, 2) = r.stress33;
    const Mat3 E = 0.5 * (F.transpose() * F - Mat3::Identity());
    const Mat3 sigma = r.valid ? material::cauchy_stress(P, F) : Mat3::Constant(NAN);
    strain_.col(p) << E(0, 0), E(1, 1), 2 * E(0, 1);
    stress_.col(p) << sigma(0, 0), sigma(1, 1), sigma(0, 1);
    out_of_plane_[p] = plane_stress ? E(2, 2) : sigma(2, 2);
  }
  if (!stress_.allFinite()) throw AnalysisError("mpfem: non-finite particle stresses");
}

}  // namespace lamina::mpfem
