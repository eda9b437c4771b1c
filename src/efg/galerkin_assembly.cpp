#include "efg/galerkin_assembly.hpp"

#include <omp.h>

#include <Eigen/Cholesky>

#include <algorithm>
#include <limits>
#include <array>
#include <cmath>
#include <exception>
#include <stdexcept>

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
                                       VolumeIntegrals* integrals, std::vector<IndexList>* point_groups,
                                       const CellFaceQuadrature* faces, bool grow_at_faces) {
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
          // the neighbour lists alone need only the support search; VCI also needs the shape functions
          if (mine) shapes.evaluate(quadrature.points.col(q), 1, sv);
          else shapes.neighbours(quadrature.points.col(q), sv.neighbours);
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
        if (faces)
          for (Index f = faces->cell_begin[static_cast<std::size_t>(c)]; f < faces->cell_begin[static_cast<std::size_t>(c + 1)]; ++f) {
            shapes.neighbours(faces->faces.points.col(f), sv.neighbours, grow_at_faces);
            merged.clear();
            std::set_union(nodes.begin(), nodes.end(), sv.neighbours.begin(), sv.neighbours.end(), std::back_inserter(merged));
            nodes.swap(merged);
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

VolumeAssemblyReport assemble_volume(const VolumeAssembly& in, const solve::BlockPattern& pattern, Real* values, Eigen::VectorXd& f) {
  const VolumeQuadrature& quadrature = *in.quadrature;
  Index cells = static_cast<Index>(quadrature.cell_begin.size()) - 1;
  const Index n_nodes = in.shapes->node_count();
  const bool symmetric = pattern.symmetric();
  const int threads = omp_get_max_threads();
  Index grown_face_points = 0;
  // Processing order: the cells sorted along the axis of largest extent of their centres, so that
  // contiguous chunks are slabs of the body whatever the cell numbering.
  std::vector<Index> order(static_cast<std::size_t>(cells));
  {
    PointMatrix centres = PointMatrix::Zero(3, cells);
    for (Index c = 0; c < cells; ++c) {
      const Index q0 = quadrature.cell_begin[static_cast<std::size_t>(c)], q1 = quadrature.cell_begin[static_cast<std::size_t>(c + 1)];
      for (Index q = q0; q < q1; ++q) centres.col(c) += quadrature.points.col(q);
      if (q1 > q0) centres.col(c) /= static_cast<Real>(q1 - q0);
    }
    // axes by decreasing extent: slabs along the first, the thinnest direction innermost (cells
    // that share most of their nodes follow each other, so their matrix entries stay in cache)
    std::array<int, 3> axes{0, 1, 2};
    if (cells > 0) {
      const Vec3 extent = centres.rowwise().maxCoeff() - centres.rowwise().minCoeff();
      std::stable_sort(axes.begin(), axes.end(), [&](int a, int b) { return extent[a] > extent[b]; });
    }
    for (Index c = 0; c < cells; ++c) order[static_cast<std::size_t>(c)] = c;
    const Real tolerance = 1e-9 * std::max<Real>(1.0, centres.cwiseAbs().maxCoeff());
    std::stable_sort(order.begin(), order.end(), [&](Index a, Index b) {
      for (const int axis : axes) {
        const Real difference = centres(axis, a) - centres(axis, b);
        if (std::abs(difference) > tolerance) return difference < 0;
      }
      return false;
    });
  }
  if (in.parts > 1) {  // this part's slab of the ordered cells
    const Index first = cells * in.part / in.parts, last = cells * (in.part + 1) / in.parts;
    order = std::vector<Index>(order.begin() + first, order.begin() + last);
    cells = last - first;
  }
  // phase p of thread t: cells order[bounds[3t + p] .. bounds[3t + p + 1])
  std::vector<Index> bounds;
  std::vector<std::vector<Real>> partial_values(static_cast<std::size_t>(threads));
  std::vector<std::pair<Index, Index>> partial_ranges(static_cast<std::size_t>(threads), {0, 0});
  std::vector<Eigen::VectorXd> partial_f(static_cast<std::size_t>(threads));
  FirstError failure;
  int team_size = 1;
  bool direct = true;
  auto cell_nodes_of = [&](Index k) -> const IndexList& {
    return (*in.cell_nodes)[static_cast<std::size_t>(order[static_cast<std::size_t>(k)])];
  };
#pragma omp parallel num_threads(threads)
  {
    const int t = omp_get_thread_num();
    const int team = omp_get_num_threads();
#pragma omp single
    {
      team_size = team;
      bounds.resize(static_cast<std::size_t>(3 * team));
      for (int k = 0; k < team; ++k) {
        const Index first = chunk_begin(cells, team, k), last = chunk_begin(cells, team, k + 1);
        bounds[static_cast<std::size_t>(3 * k)] = first;
        bounds[static_cast<std::size_t>(3 * k + 1)] = first + (last - first) / 2;
        bounds[static_cast<std::size_t>(3 * k + 2)] = last;
      }
      // Direct writes are safe when no node belongs to the cells of two threads in the same phase
      // (two cells share matrix entries only through common nodes).
      std::vector<int> owner(static_cast<std::size_t>(n_nodes));
      for (int phase = 0; phase < 2 && direct && team > 1; ++phase) {
        std::fill(owner.begin(), owner.end(), -1);
        for (int k = 0; k < team && direct; ++k)
          for (Index c = bounds[static_cast<std::size_t>(3 * k + phase)]; c < bounds[static_cast<std::size_t>(3 * k + phase + 1)] && direct; ++c)
            for (const Index node : cell_nodes_of(c)) {
              int& o = owner[static_cast<std::size_t>(node)];
              if (o >= 0 && o != k) {
                direct = false;
                break;
              }
              o = k;
            }
      }
    }
    const Index* bound = bounds.data() + 3 * t;
    // Where the values go: straight into `values`, or this thread's copy of its range.
    Real* target = values;
    Index offset = 0;
    if (!direct) {
      Index lo = std::numeric_limits<Index>::max(), hi = 0;
      for (Index c = bound[0]; c < bound[2]; ++c) {
        const auto r = pattern.value_range(cell_nodes_of(c));
        if (r.second > r.first) {
          lo = std::min(lo, r.first);
          hi = std::max(hi, r.second);
        }
      }
      if (hi <= lo) lo = hi = 0;
      partial_ranges[static_cast<std::size_t>(t)] = {lo, hi};
      std::vector<Real>& mine = partial_values[static_cast<std::size_t>(t)];
      mine.assign(static_cast<std::size_t>(hi - lo), 0.0);
      target = mine.data();
      offset = lo;
    }
    Eigen::VectorXd& my_f = partial_f[static_cast<std::size_t>(t)];
    my_f = Eigen::VectorXd::Zero(3 * n_nodes);

    std::vector<int> local_index(static_cast<std::size_t>(n_nodes), -1);
    std::vector<int> rank_of(static_cast<std::size_t>(n_nodes), -1);
    std::vector<mls::ShapeFunctionValues> sv;
    // Y(q, 3i + a) = phi_i,a(x_q) (trial), Yt the test gradients (VCI); C = Yt^T diag(weight) Y, so that
    // the 3 x 3 block (i, j) of C is c_ab = sum_q weight_q phi_i,a phi_j,b. The mu part's rule is the
    // cell's rule; the lambda part's is the reduced rule with selective reduced integration, else the same.
    Eigen::MatrixXd Y, Yt, Y_lambda, Yt_lambda, WY_mu, WY_lambda, C_lambda, C_mu;
    Eigen::VectorXd w, wl, wm;
    // Loads the gradients of the points [q0, q0 + Q) of a rule into Y (trial) and Yt (test, VCI).
    auto load_points = [&](const VolumeQuadrature& rule, Index q0, Index Q, Index n, bool with_body_force,
                           const Eigen::Matrix3Xd* xi) {
      if (static_cast<Index>(sv.size()) < Q) sv.resize(static_cast<std::size_t>(Q));
      Y.setZero(Q, 3 * n);
      w.resize(Q);
      for (Index q = 0; q < Q; ++q) {
        auto& s = sv[static_cast<std::size_t>(q)];
        in.shapes->evaluate(rule.points.col(q0 + q), 1, s);
        w[q] = rule.weights[q0 + q];
        for (std::size_t k = 0; k < s.neighbours.size(); ++k) {
          const int i = local_index[static_cast<std::size_t>(s.neighbours[k])];
          if (i < 0) throw std::logic_error("EFG assembly: neighbour outside the cell's node list");
          for (int a = 0; a < 3; ++a) Y(q, 3 * i + a) = s.dphi(a, static_cast<Index>(k));
        }
        if (with_body_force && in.body_force) {
          const Vec3 b = in.body_force->col(q0 + q) * w[q];
          if (b.squaredNorm() > 0)
            for (std::size_t k = 0; k < s.neighbours.size(); ++k)
              my_f.segment<3>(3 * s.neighbours[k]) += s.phi[static_cast<Index>(k)] * b;
        }
      }
      if (xi) {
        Yt = Y;
        for (Index q = 0; q < Q; ++q) {
          const auto& s = sv[static_cast<std::size_t>(q)];
          for (std::size_t k = 0; k < s.neighbours.size(); ++k) {
            const Index I = s.neighbours[k];
            const int i = local_index[static_cast<std::size_t>(I)];
            for (int a = 0; a < 3; ++a) Yt(q, 3 * i + a) += (*xi)(a, I) * s.phi[static_cast<Index>(k)];
          }
        }
      }
    };
    // Gradient smoothing (see the header): per cell the moments R_a (4 x n, one per direction a) and
    // M^-1 of the linear fields q on the cell's rule; then grad phi_i,a at x = R_a(:, i) . M^-1 q(x).
    Eigen::Matrix<Real, 4, Eigen::Dynamic> moments[3];
    Eigen::Matrix4d inverse_mass;
    Vec3 cell_centre = Vec3::Zero();
    Real cell_scale = 1.0;
    auto linear_fields = [&](const Vec3& x) {
      Eigen::Vector4d q;
      q << 1.0, (x - cell_centre) / cell_scale;
      return q;
    };
    auto smooth_cell = [&](Index c, Index n) {
      const CellFaceQuadrature& faces = *in.smoothing;
      const Index q0 = quadrature.cell_begin[static_cast<std::size_t>(c)];
      const Index Q = quadrature.cell_begin[static_cast<std::size_t>(c + 1)] - q0;
      cell_centre.setZero();
      for (Index q = 0; q < Q; ++q) cell_centre += quadrature.points.col(q0 + q);
      cell_centre /= static_cast<Real>(Q);
      cell_scale = 0.0;
      for (Index q = 0; q < Q; ++q) cell_scale = std::max(cell_scale, (quadrature.points.col(q0 + q) - cell_centre).cwiseAbs().maxCoeff());
      if (!(cell_scale > 0.0)) cell_scale = 1.0;
      Eigen::Matrix4d mass = Eigen::Matrix4d::Zero();
      Eigen::RowVectorXd volume_phi = Eigen::RowVectorXd::Zero(n);
      if (static_cast<Index>(sv.size()) < 1) sv.resize(1);
      auto& s = sv[0];
      for (int a = 0; a < 3; ++a) moments[a].setZero(4, n);
      // the cell's divergence defect for q (below): sum_f w_f q(x_f) n_f^T - sum_q w_q grad q^T
      Eigen::Matrix<Real, 4, 3> defect = Eigen::Matrix<Real, 4, 3>::Zero();
      for (Index q = 0; q < Q; ++q) {
        const Vec3 x = quadrature.points.col(q0 + q);
        const Real weight = quadrature.weights[q0 + q];
        const Eigen::Vector4d p = linear_fields(x);
        mass.noalias() += weight * p * p.transpose();
        in.shapes->evaluate(x, 0, s);
        for (std::size_t k = 0; k < s.neighbours.size(); ++k) {
          const int i = local_index[static_cast<std::size_t>(s.neighbours[k])];
          if (i < 0) throw std::logic_error("EFG assembly: neighbour outside the cell's node list");
          volume_phi[i] += weight * s.phi[static_cast<Index>(k)];
        }
        if (in.body_force) {
          const Vec3 b = in.body_force->col(q0 + q) * weight;
          if (b.squaredNorm() > 0)
            for (std::size_t k = 0; k < s.neighbours.size(); ++k)
              my_f.segment<3>(3 * s.neighbours[k]) += s.phi[static_cast<Index>(k)] * b;
        }
      }
      for (Index f = faces.cell_begin[static_cast<std::size_t>(c)]; f < faces.cell_begin[static_cast<std::size_t>(c + 1)]; ++f) {
        const Vec3 x = faces.faces.points.col(f);
        const Vec3 wn = faces.faces.weights[f] * faces.faces.normals.col(f);
        const Eigen::Vector4d p = linear_fields(x);
        defect.noalias() += p * wn.transpose();
        in.shapes->evaluate(x, 0, s, in.grow_at_faces);
        if (s.remedy_steps > 0) {
#pragma omp atomic
          ++grown_face_points;
        }
        for (std::size_t k = 0; k < s.neighbours.size(); ++k) {
          const int i = local_index[static_cast<std::size_t>(s.neighbours[k])];
          if (i < 0) throw std::logic_error("EFG assembly: face neighbour outside the cell's node list");
          const Real phi = s.phi[static_cast<Index>(k)];
          for (int a = 0; a < 3; ++a) moments[a].col(i) += (wn[a] * phi) * p;
        }
      }
      // - sum_q w_q phi_i grad q_k: grad q_(a+1) = e_a / s
      for (int a = 0; a < 3; ++a) moments[a].row(a + 1) -= volume_phi / cell_scale;
      // On a curved cell the face and volume rules satisfy the divergence theorem for q only to their
      // quadrature error (the defect D_a = sum_f w_f n_f,a q(x_f) - sum_q w_q grad_a q): that would give a
      // rigid translation a small smoothed gradient. Shared out in proportion to sum_q w_q phi_i (which
      // adds up to the cell volume, phi being a partition of unity), it cancels for constant fields.
      const Real volume = quadrature.weights.segment(q0, Q).sum();
      for (int a = 0; a < 3; ++a) defect(a + 1, a) -= volume / cell_scale;
      for (int a = 0; a < 3; ++a) moments[a].noalias() -= defect.col(a) * (volume_phi / volume);
      Eigen::LDLT<Eigen::Matrix4d> factor(mass);
      if (factor.info() != Eigen::Success || !(factor.vectorD().minCoeff() > 1e-12 * factor.vectorD().maxCoeff()))
        throw std::runtime_error("EFG gradient smoothing: the cell's quadrature does not determine linear fields "
                                 "(use at least 2 Gauss points per direction)");
      inverse_mass = factor.solve(Eigen::Matrix4d::Identity());
    };
    // Y (points of `rule` in cell c) from the smoothed gradients of smooth_cell.
    auto load_smoothed = [&](const VolumeQuadrature& rule, Index r0, Index R, Index n) {
      Y.setZero(R, 3 * n);
      w.resize(R);
      for (Index q = 0; q < R; ++q) {
        w[q] = rule.weights[r0 + q];
        const Eigen::Vector4d p = inverse_mass * linear_fields(rule.points.col(r0 + q));
        for (Index i = 0; i < n; ++i)
          for (int a = 0; a < 3; ++a) Y(q, 3 * i + a) = p.dot(moments[a].col(i));
      }
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
    auto assemble_cell = [&](Index c) {
      const IndexList& nodes = (*in.cell_nodes)[static_cast<std::size_t>(c)];
      const Index n = static_cast<Index>(nodes.size());
      const Index q0 = quadrature.cell_begin[static_cast<std::size_t>(c)];
      const Index Q = quadrature.cell_begin[static_cast<std::size_t>(c + 1)] - q0;
      if (Q == 0 || n == 0) return;
      for (Index i = 0; i < n; ++i) local_index[static_cast<std::size_t>(nodes[static_cast<std::size_t>(i)])] = static_cast<int>(i);
      if (in.smoothing) {
        smooth_cell(c, n);
        load_smoothed(quadrature, q0, Q, n);
      } else {
        load_points(quadrature, q0, Q, n, true, in.vci);
      }
      // K block (i, j) = lambda_scale c_lambda + mu_scale (c_mu^T + tr(c_mu) I)
      Real lambda_scale = 1.0, mu_scale = 1.0;
      bool shared = false;  // the lambda part is the mu product (uniform material, one rule)
      if (in.reduced) {
        // selective reduced integration: mu part on the full rule, lambda part on the reduced rule
        material_weights(*in.material_of_point, q0, Q, wl, wm);
        WY_mu.noalias() = wm.asDiagonal() * Y;
        Y.swap(Y_lambda);  // keeps the full rule's Y (and Yt) while the reduced rule is loaded
        Yt.swap(Yt_lambda);
        const VolumeQuadrature& reduced = *in.reduced;
        const Index r0 = reduced.cell_begin[static_cast<std::size_t>(c)];
        const Index R = reduced.cell_begin[static_cast<std::size_t>(c + 1)] - r0;
        if (in.smoothing) load_smoothed(reduced, r0, R, n);
        else load_points(reduced, r0, R, n, false, in.vci_reduced ? in.vci_reduced : in.vci);
        material_weights(*in.material_of_reduced_point, r0, R, wl, wm);
        WY_lambda.noalias() = wl.asDiagonal() * Y;
        Y.swap(Y_lambda);
        Yt.swap(Yt_lambda);
      } else {
        const int m0 = (*in.material_of_point)[static_cast<std::size_t>(q0)];
        bool uniform = true;
        for (Index q = 0; q < Q; ++q)
          if ((*in.material_of_point)[static_cast<std::size_t>(q0 + q)] != m0) uniform = false;
        if (uniform) {
          const auto& mat = (*in.materials)[static_cast<std::size_t>(m0)];
          WY_mu.noalias() = w.asDiagonal() * Y;
          shared = true;
          lambda_scale = mat.lambda();
          mu_scale = mat.mu();
        } else {
          material_weights(*in.material_of_point, q0, Q, wl, wm);
          WY_mu.noalias() = wm.asDiagonal() * Y;
          WY_lambda.noalias() = wl.asDiagonal() * Y;
        }
      }
      const Eigen::MatrixXd& test_mu = in.vci ? Yt : Y;
      const Eigen::MatrixXd& test_lambda = in.reduced ? ((in.vci_reduced || in.vci) ? Yt_lambda : Y_lambda) : test_mu;
      // The products are formed and added in column tiles of at most tile_entries values, so that a tile
      // stays in cache between its product and its scatter (a whole 3n x 3n product of a large support
      // is megabytes per cell: zeroing and reading it back cost more than the product).
      constexpr Index tile_entries = 16384;
      const Index size = 3 * n;
      const Index tile_nodes = std::max<Index>(1, tile_entries / (3 * size));
      for (Index j0 = 0; j0 < n; j0 += tile_nodes) {
        const Index j1 = std::min(n, j0 + tile_nodes);
        // rows 0 .. rows of columns 3 j0 .. 3 j1 (only the upper triangle is added when symmetric)
        const Index rows = symmetric ? 3 * j1 : size, cols = 3 * (j1 - j0);
        auto tile = [&](const Eigen::MatrixXd& test, const Eigen::MatrixXd& weighted, Eigen::MatrixXd& out) {
          if (test.rows() == 0) {
            out.setZero(rows, cols);  // no points (Eigen's blocking heuristic divides by the inner dimension)
            return;
          }
          out.resize(rows, cols);
          out.noalias() = test.leftCols(rows).transpose() * weighted.middleCols(3 * j0, cols);
        };
        tile(test_mu, WY_mu, C_mu);
        if (!shared) tile(test_lambda, WY_lambda, C_lambda);
        const Eigen::MatrixXd& lambda_part = shared ? C_mu : C_lambda;
        const Real* cl = lambda_part.data();
        const Real* cm = C_mu.data();
        const Index ld = rows;
        // Added straight into the pattern (upper triangle when symmetric); node pairs that no
        // quadrature point couples have exactly zero blocks and are not in the pattern.
        for (Index jj = j0; jj < j1; ++jj) {
          const Index J = nodes[static_cast<std::size_t>(jj)];
          // rank of every pattern neighbour I of J (a table lookup per pair instead of a merge, whose
          // data-dependent loop exits were mispredicted once per pair)
          const Index* neighbour = pattern.neighbours_begin(J);
          const Index count = static_cast<Index>(pattern.neighbours_end(J) - neighbour);
          for (Index k = 0; k < count; ++k) rank_of[static_cast<std::size_t>(neighbour[k])] = static_cast<int>(k);
          const Index end = symmetric ? jj + 1 : n;
          Index column[3];
          for (int b = 0; b < 3; ++b) column[b] = pattern.column_start(3 * J + b) - offset;
          for (Index ii = 0; ii < end; ++ii) {
            const Index I = nodes[static_cast<std::size_t>(ii)];
            const Index rank = rank_of[static_cast<std::size_t>(I)];
            if (rank < 0 || rank >= count || neighbour[rank] != I) continue;  // stale entry: not in the pattern
            const Index r = 3 * rank;
            // blocks (ii, jj) of the lambda and mu products: entry (a, b) at [(3 (jj - j0) + b) ld + 3 ii + a]
            const Real* bl = cl + 3 * (jj - j0) * ld + 3 * ii;
            const Real* bm = cm + 3 * (jj - j0) * ld + 3 * ii;
            const Real trace = bm[0] + bm[ld + 1] + bm[2 * ld + 2];
            if (symmetric && I == J) {
              // diagonal block: the products are symmetric here, only their upper triangle is stored
              for (int b = 0; b < 3; ++b) {
                Real* entry = target + column[b] + r;
                for (int a = 0; a <= b; ++a)
                  entry[a] += lambda_scale * bl[b * ld + a] + mu_scale * (bm[b * ld + a] + (a == b ? trace : 0.0));
              }
              continue;
            }
            for (int b = 0; b < 3; ++b) {
              Real* entry = target + column[b] + r;
              for (int a = 0; a < 3; ++a)
                entry[a] += lambda_scale * bl[b * ld + a] + mu_scale * (bm[a * ld + b] + (a == b ? trace : 0.0));
            }
          }
        }
      }
      for (Index i = 0; i < n; ++i) local_index[static_cast<std::size_t>(nodes[static_cast<std::size_t>(i)])] = -1;
    };
    for (int phase = 0; phase < 2; ++phase) {
      if (phase == 1 && direct) {
#pragma omp barrier
      }
      for (Index k = bound[phase]; k < bound[phase + 1]; ++k) {
        const Index c = order[static_cast<std::size_t>(k)];
        try {
          assemble_cell(c);
        } catch (...) {
          failure.record(c);
          break;
        }
      }
    }
  }
  failure.rethrow();
  if (!direct) add_thread_copies(values, partial_values, partial_ranges);  // threads past the team: empty ranges
  if (f.size() != 3 * n_nodes) f = Eigen::VectorXd::Zero(3 * n_nodes);
  for (int t = 0; t < team_size; ++t)
    if (partial_f[static_cast<std::size_t>(t)].size() == f.size()) f += partial_f[static_cast<std::size_t>(t)];
  VolumeAssemblyReport report;
  report.direct = direct;
  report.grown_face_points = grown_face_points;
  return report;
}

void add_thread_copies(Real* values, const std::vector<std::vector<Real>>& copies,
                       const std::vector<std::pair<Index, Index>>& ranges) {
  const auto threads = static_cast<int>(ranges.size());
  Index low = std::numeric_limits<Index>::max(), high = 0;
  for (const auto& [lo, hi] : ranges)
    if (hi > lo) {
      low = std::min(low, lo);
      high = std::max(high, hi);
    }
#pragma omp parallel for schedule(static)
  for (Index v = low; v < high; ++v) {
    Real sum = 0.0;
    for (int t = 0; t < threads; ++t) {
      const auto [lo, hi] = ranges[static_cast<std::size_t>(t)];
      if (v >= lo && v < hi) sum += copies[static_cast<std::size_t>(t)][static_cast<std::size_t>(v - lo)];
    }
    values[v] += sum;
  }
}

}  // namespace lamina::efg
