#include "efg/galerkin_assembly.hpp"

#include <omp.h>

#include <algorithm>
#include <exception>

namespace lamina::efg {

Index chunk_begin(Index count, int parts, int t) { return count * t / parts; }

namespace {

/// Remembers the exception of the lowest failing item of a parallel loop.
struct FirstError {
  Index item = -1;
  std::exception_ptr error;
  void record(Index i) {
#pragma omp critical(lamina_efg_first_error)
    {
      if (item < 0 || i < item) {
        item = i;
        error = std::current_exception();
      }
    }
  }
  void rethrow() const {
    if (error) std::rethrow_exception(error);
  }
};

}  // namespace

std::vector<IndexList> cell_neighbours(const mls::MlsShapeFunctions& shapes, const VolumeQuadrature& quadrature,
                                       VolumeIntegrals* integrals, std::vector<IndexList>* point_groups) {
  const Index cells = static_cast<Index>(quadrature.cell_begin.size()) - 1;
  const Index n = shapes.node_count();
  std::vector<IndexList> result(static_cast<std::size_t>(cells));
  std::vector<std::vector<IndexList>> groups_of_cell(point_groups ? static_cast<std::size_t>(cells) : 0);
  const int threads = omp_get_max_threads();
  std::vector<VolumeIntegrals> partial(integrals ? static_cast<std::size_t>(threads) : 0);
  FirstError failure;
#pragma omp parallel num_threads(threads)
  {
    const int t = omp_get_thread_num();
    const int team = omp_get_num_threads();
    VolumeIntegrals* mine = nullptr;
    if (integrals) {
      mine = &partial[static_cast<std::size_t>(t)];
      mine->gradient = Eigen::Matrix3Xd::Zero(3, n);
      mine->value = Eigen::VectorXd::Zero(n);
    }
    mls::ShapeFunctionValues sv;
    IndexList merged;
    const Index first = chunk_begin(cells, team, t), last = chunk_begin(cells, team, t + 1);
    for (Index c = first; c < last; ++c) {
      try {
        IndexList& nodes = result[static_cast<std::size_t>(c)];
        for (Index q = quadrature.cell_begin[static_cast<std::size_t>(c)]; q < quadrature.cell_begin[static_cast<std::size_t>(c + 1)]; ++q) {
          shapes.evaluate(quadrature.points.col(q), integrals ? 1 : 0, sv);
          merged.clear();
          std::set_union(nodes.begin(), nodes.end(), sv.neighbours.begin(), sv.neighbours.end(), std::back_inserter(merged));
          nodes.swap(merged);
          if (point_groups) {
            auto& groups = groups_of_cell[static_cast<std::size_t>(c)];
            if (std::find(groups.begin(), groups.end(), sv.neighbours) == groups.end()) groups.push_back(sv.neighbours);
          }
          if (mine) {
            const Real w = quadrature.weights[q];
            for (std::size_t k = 0; k < sv.neighbours.size(); ++k) {
              const Index I = sv.neighbours[k];
              mine->value[I] += w * sv.phi[static_cast<Index>(k)];
              mine->gradient.col(I) += w * sv.dphi.col(static_cast<Index>(k));
            }
          }
        }
      } catch (...) {
        failure.record(c);
        break;
      }
    }
  }
  failure.rethrow();
  if (point_groups)
    for (auto& groups : groups_of_cell)
      for (auto& g : groups) point_groups->push_back(std::move(g));
  if (integrals) {
    integrals->gradient = Eigen::Matrix3Xd::Zero(3, n);
    integrals->value = Eigen::VectorXd::Zero(n);
    for (const auto& p : partial) {
      if (p.value.size() != n) continue;
      integrals->gradient += p.gradient;
      integrals->value += p.value;
    }
  }
  return result;
}

Eigen::Matrix3Xd vci_correction(const VolumeIntegrals& volume, const Eigen::Matrix3Xd& boundary) {
  const Index n = volume.value.size();
  Eigen::Matrix3Xd xi = Eigen::Matrix3Xd::Zero(3, n);
  const Real scale = volume.value.cwiseAbs().maxCoeff();
  for (Index I = 0; I < n; ++I) {
    const Real v = volume.value[I];
    if (std::abs(v) > 1e-12 * scale) xi.col(I) = (boundary.col(I) - volume.gradient.col(I)) / v;
  }
  return xi;
}

void assemble_volume(const VolumeAssembly& in, const solve::BlockPattern& pattern, std::vector<Real>& values,
                     Eigen::VectorXd& f) {
  const VolumeQuadrature& quadrature = *in.quadrature;
  const Index cells = static_cast<Index>(quadrature.cell_begin.size()) - 1;
  const Index n_nodes = in.shapes->node_count();
  const bool symmetric = pattern.symmetric();
  const int threads = omp_get_max_threads();
  std::vector<std::vector<Real>> partial_values(static_cast<std::size_t>(threads));
  std::vector<std::pair<Index, Index>> ranges(static_cast<std::size_t>(threads), {0, 0});
  std::vector<Eigen::VectorXd> partial_f(static_cast<std::size_t>(threads));
  FirstError failure;
  int team_size = 1;
#pragma omp parallel num_threads(threads)
  {
    const int t = omp_get_thread_num();
    const int team = omp_get_num_threads();
#pragma omp single
    team_size = team;
    const Index first = chunk_begin(cells, team, t), last = chunk_begin(cells, team, t + 1);
    // value range of this chunk
    Index lo = std::numeric_limits<Index>::max(), hi = 0;
    for (Index c = first; c < last; ++c) {
      const auto r = pattern.value_range((*in.cell_nodes)[static_cast<std::size_t>(c)]);
      if (r.second > r.first) {
        lo = std::min(lo, r.first);
        hi = std::max(hi, r.second);
      }
    }
    if (hi <= lo) lo = hi = 0;
    ranges[static_cast<std::size_t>(t)] = {lo, hi};
    std::vector<Real>& mine = partial_values[static_cast<std::size_t>(t)];
    mine.assign(static_cast<std::size_t>(hi - lo), 0.0);
    Eigen::VectorXd& my_f = partial_f[static_cast<std::size_t>(t)];
    my_f = Eigen::VectorXd::Zero(3 * n_nodes);

    std::vector<int> local_index(static_cast<std::size_t>(n_nodes), -1);
    std::vector<mls::ShapeFunctionValues> sv;
    Eigen::MatrixXd X[3], Xt[3], WX[3], S[9], SM[9];
    Eigen::VectorXd w, wl, wm;
    const bool full = !symmetric || in.vci;
    // Loads the gradients of the points [q0, q0 + Q) of a rule into X (trial) and Xt (test, VCI).
    auto load_points = [&](const VolumeQuadrature& rule, Index q0, Index Q, Index n, bool with_body_force,
                           const Eigen::Matrix3Xd* xi) {
      if (static_cast<Index>(sv.size()) < Q) sv.resize(static_cast<std::size_t>(Q));
      for (int a = 0; a < 3; ++a) X[a].setZero(Q, n);
      w.resize(Q);
      for (Index q = 0; q < Q; ++q) {
        auto& s = sv[static_cast<std::size_t>(q)];
        in.shapes->evaluate(rule.points.col(q0 + q), 1, s);
        w[q] = rule.weights[q0 + q];
        for (std::size_t k = 0; k < s.neighbours.size(); ++k) {
          const int i = local_index[static_cast<std::size_t>(s.neighbours[k])];
          if (i < 0) throw std::logic_error("EFG assembly: neighbour outside the cell's node list");
          for (int a = 0; a < 3; ++a) X[a](q, i) = s.dphi(a, static_cast<Index>(k));
        }
        if (with_body_force && in.body_force) {
          const Vec3 b = in.body_force->col(q0 + q) * w[q];
          if (b.squaredNorm() > 0)
            for (std::size_t k = 0; k < s.neighbours.size(); ++k)
              my_f.segment<3>(3 * s.neighbours[k]) += s.phi[static_cast<Index>(k)] * b;
        }
      }
      if (xi) {
        for (int a = 0; a < 3; ++a) Xt[a] = X[a];
        for (Index q = 0; q < Q; ++q) {
          const auto& s = sv[static_cast<std::size_t>(q)];
          for (std::size_t k = 0; k < s.neighbours.size(); ++k) {
            const Index I = s.neighbours[k];
            const int i = local_index[static_cast<std::size_t>(I)];
            for (int a = 0; a < 3; ++a) Xt[a](q, i) += (*xi)(a, I) * s.phi[static_cast<Index>(k)];
          }
        }
      }
    };
    // out[3a + b] = T_a^T diag(weight) X_b (T = test gradients)
    auto products = [&](const Eigen::VectorXd& weight, Eigen::MatrixXd* out) {
      const Eigen::MatrixXd* T = in.vci ? Xt : X;
      for (int b = 0; b < 3; ++b) WX[b].noalias() = weight.asDiagonal() * X[b];
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
          if (!full && b < a) continue;
          out[3 * a + b].noalias() = T[a].transpose() * WX[b];
        }
      if (!full)
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < a; ++b) out[3 * a + b] = out[3 * b + a].transpose();
    };
    auto material_weights = [&](const std::vector<int>& ids, Index q0, Index Q, Eigen::VectorXd& lambda_w,
                                 Eigen::VectorXd& mu_w) {
      lambda_w.resize(Q);
      mu_w.resize(Q);
      for (Index q = 0; q < Q; ++q) {
        const auto& mat = (*in.materials)[static_cast<std::size_t>(ids[static_cast<std::size_t>(q0 + q)])];
        lambda_w[q] = w[q] * mat.lambda();
        mu_w[q] = w[q] * mat.mu();
      }
    };
    for (Index c = first; c < last; ++c) {
      try {
        const IndexList& nodes = (*in.cell_nodes)[static_cast<std::size_t>(c)];
        const Index n = static_cast<Index>(nodes.size());
        const Index q0 = quadrature.cell_begin[static_cast<std::size_t>(c)];
        const Index Q = quadrature.cell_begin[static_cast<std::size_t>(c + 1)] - q0;
        if (Q == 0 || n == 0) continue;
        for (Index i = 0; i < n; ++i) local_index[static_cast<std::size_t>(nodes[static_cast<std::size_t>(i)])] = static_cast<int>(i);
        load_points(quadrature, q0, Q, n, true, in.vci);
        if (in.reduced) {
          // selective reduced integration: mu part on the full rule, lambda part on the reduced rule
          material_weights(*in.material_of_point, q0, Q, wl, wm);
          products(wm, SM);
          const VolumeQuadrature& reduced = *in.reduced;
          const Index r0 = reduced.cell_begin[static_cast<std::size_t>(c)];
          const Index R = reduced.cell_begin[static_cast<std::size_t>(c + 1)] - r0;
          load_points(reduced, r0, R, n, false, in.vci_reduced ? in.vci_reduced : in.vci);
          material_weights(*in.material_of_reduced_point, r0, R, wl, wm);
          products(wl, S);
        } else {
          const int m0 = (*in.material_of_point)[static_cast<std::size_t>(q0)];
          bool uniform = true;
          for (Index q = 0; q < Q; ++q)
            if ((*in.material_of_point)[static_cast<std::size_t>(q0 + q)] != m0) uniform = false;
          if (uniform) {
            const auto& mat = (*in.materials)[static_cast<std::size_t>(m0)];
            products(w, SM);
            for (int k = 0; k < 9; ++k) {
              S[k] = SM[k] * mat.lambda();
              SM[k] *= mat.mu();
            }
          } else {
            material_weights(*in.material_of_point, q0, Q, wl, wm);
            products(wl, S);
            products(wm, SM);
          }
        }
        // K_IJ(a, b) = S_ab(I, J) + SM_ba(I, J) + delta_ab tr SM(I, J), added straight into the
        // pattern (upper triangle when symmetric); node pairs that no quadrature point couples
        // have exactly zero blocks and are not in the pattern.
        for (Index jj = 0; jj < n; ++jj) {
          const Index J = nodes[static_cast<std::size_t>(jj)];
          const Index* first_neighbour = pattern.neighbours_begin(J);
          const Index* last_neighbour = pattern.neighbours_end(J);
          const Index* it = first_neighbour;
          const Index end = symmetric ? jj + 1 : n;
          Index column[3];
          for (int b = 0; b < 3; ++b) column[b] = pattern.column_start(3 * J + b) - lo;
          for (Index ii = 0; ii < end; ++ii) {
            const Index I = nodes[static_cast<std::size_t>(ii)];
            while (it != last_neighbour && *it < I) ++it;
            if (it == last_neighbour) break;
            if (*it != I) continue;
            const Index r = 3 * static_cast<Index>(it - first_neighbour);
            const Real trace = SM[0](ii, jj) + SM[4](ii, jj) + SM[8](ii, jj);
            const bool diagonal = symmetric && I == J;
            for (int b = 0; b < 3; ++b) {
              Real* target = mine.data() + column[b] + r;
              const int last_a = diagonal ? b : 2;
              for (int a = 0; a <= last_a; ++a)
                target[a] += S[3 * a + b](ii, jj) + SM[3 * b + a](ii, jj) + (a == b ? trace : 0.0);
            }
          }
        }
        for (Index i = 0; i < n; ++i) local_index[static_cast<std::size_t>(nodes[static_cast<std::size_t>(i)])] = -1;
      } catch (...) {
        failure.record(c);
        break;
      }
    }
  }
  failure.rethrow();
  // deterministic reduction: thread order
  values.assign(static_cast<std::size_t>(pattern.nonzeros()), 0.0);
  const Index total = pattern.nonzeros();
#pragma omp parallel for schedule(static)
  for (Index v = 0; v < total; ++v) {
    Real sum = 0.0;
    for (int t = 0; t < team_size; ++t) {
      const auto [lo, hi] = ranges[static_cast<std::size_t>(t)];
      if (v >= lo && v < hi) sum += partial_values[static_cast<std::size_t>(t)][static_cast<std::size_t>(v - lo)];
    }
    values[static_cast<std::size_t>(v)] = sum;
  }
  if (f.size() != 3 * n_nodes) f = Eigen::VectorXd::Zero(3 * n_nodes);
  for (int t = 0; t < team_size; ++t)
    if (partial_f[static_cast<std::size_t>(t)].size() == f.size()) f += partial_f[static_cast<std::size_t>(t)];
}

}  // namespace lamina::efg
