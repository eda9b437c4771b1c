#include "pd/linear_peridynamic_solid.hpp"

#include <algorithm>
#include <cmath>

#include <omp.h>

namespace lamina::pd {

LinearPeridynamicSolid::LinearPeridynamicSolid(const PeridynamicBody& body) : body_(body) {
  reverse_modulus_.resize(body.bonds());
#pragma omp parallel for schedule(static)
  for (Index b = 0; b < body.bonds(); ++b) reverse_modulus_[b] = body.bond_modulus()[body.reverse(b)];
  // Components in use: plain LPS has one dilatation (row 0), the energy correction three normal ones,
  // the plate correction all six.
  switch (body.options().surface_correction) {
    case SurfaceCorrection::none: components_ = 1; break;
    case SurfaceCorrection::energy: components_ = 3; break;
    default: components_ = 6; break;
  }
  const Index k = components_;
  weight_used_ = body.dilatation_weight().topRows(k);
  reverse_weight_used_.resize(k, body.bonds());
#pragma omp parallel for schedule(static)
  for (Index b = 0; b < body.bonds(); ++b) reverse_weight_used_.col(b) = weight_used_.col(body.reverse(b));
  coupling_used_.resize(k * k, body.nodes());
  for (Index i = 0; i < body.nodes(); ++i)
    coupling_used_.col(i) = Eigen::Map<const Eigen::VectorXd>(Eigen::MatrixXd(body.dilatation_coupling(i).topLeftCorner(k, k)).data(), k * k);
}

BondState LinearPeridynamicSolid::bond_state(const PointMatrix& u, bool linearised) const {
  BondState s;
  bond_state(u, s, linearised);
  return s;
}

void LinearPeridynamicSolid::bond_state(const PointMatrix& u, BondState& s, bool linearised) const {
  const PeridynamicBody& body = body_;
  const Index n = body.nodes();
  // resize is a no-op when s already has the sizes (explicit and ADR loops reuse one state)
  const bool fresh = s.dilatation_force.cols() != n;
  s.direction.resize(3, body.bonds());
  s.length.resize(body.bonds());
  s.extension.resize(body.bonds());
  s.dilatation.resize(3, n);
  s.shear_dilatation.resize(3, n);
  s.dilatation_force.resize(6, n);
  s.pair_force.resize(body.bonds());
  // dilatation rows beyond the components in use stay zero (set once, when the state is new)
  if (fresh && body.has_halo()) {  // the outer halo's bonds are never computed: zero, not garbage
    s.direction.setZero();
    s.length.setZero();
    s.extension.setZero();
    s.pair_force.setZero();
    s.dilatation.setZero();
    s.shear_dilatation.setZero();
    s.dilatation_force.setZero();
  }
  if (fresh && components_ < 6) {
    s.dilatation_force.setZero();
    s.shear_dilatation.setZero();
    if (components_ < 3) s.dilatation.setZero();
  }
  switch (components_) {
    case 1: bond_state_kernel<1>(u, s, linearised); break;
    case 3: bond_state_kernel<3>(u, s, linearised); break;
    default: bond_state_kernel<6>(u, s, linearised); break;
  }
}

template <int K>
void LinearPeridynamicSolid::bond_state_kernel(const PointMatrix& u, BondState& s, bool linearised) const {
  using VecK = Eigen::Matrix<Real, K, 1>;
  using MatK = Eigen::Matrix<Real, K, K>;
  const PeridynamicBody& body = body_;
  const Index n = body.nodes();
  const bool planar = body.dimension() == 2;
  const auto& x0 = body.bond_length();
  const auto& c = body.bond_modulus();
  const auto& bv = body.bond_volume();
  const Real* w = weight_used_.data();
  const Real* rw = reverse_weight_used_.data();
  const Real* q = coupling_used_.data();
  // Stage 1: extensions and dilatation (gather over each node's bonds).
#pragma omp parallel for schedule(static)
  for (Index i = 0; i < n; ++i) {
    if (!body.computes_state(i)) continue;
    VecK theta = VecK::Zero();
    const Vec3 pi = body.positions().col(i), ui = u.col(i);
    for (Index b = body.first_bond(i); b < body.end_bond(i); ++b) {
      const Index j = body.neighbour(b);
      Vec3 xi = body.positions().col(j) - pi;
      Vec3 du = u.col(j) - ui;
      if (planar) {
        xi.z() = 0;
        du.z() = 0;
      }
      Real e;
      Vec3 m;
      Real y;
      if (linearised) {
        m = xi / x0[b];
        e = m.dot(du);
        y = x0[b];
      } else {
        const Vec3 yv = xi + du;
        y = yv.norm();
        m = yv / y;
        e = y - x0[b];
      }
      s.direction.col(b) = m;
      s.length[b] = y;
      s.extension[b] = e;
      theta += Eigen::Map<const VecK>(w + K * b) * (e * bv[b]);
    }
    const VecK force = Eigen::Map<const MatK>(q + K * K * i) * theta;
    if constexpr (K == 1) {
      s.dilatation(0, i) = theta[0];
      s.dilatation_force(0, i) = force[0];
    } else if constexpr (K == 3) {
      s.dilatation.col(i) = theta;
      s.dilatation_force.col(i).template head<3>() = force;
    } else {
      s.dilatation.col(i) = theta.template head<3>();
      s.shear_dilatation.col(i) = theta.template tail<3>();
      s.dilatation_force.col(i) = force;
    }
  }
  body.exchange_halo(s.dilatation_force.data(), 6);  // several ranks: the halo's Q theta from its owners
  // Stage 2: pair forces P_ij = V_i beta V_j (t_ij + t_ji).
#pragma omp parallel for schedule(static)
  for (Index i = 0; i < n; ++i) {
    if (!body.owns(i)) continue;
    const VecK force_i = s.dilatation_force.col(i).template head<K>();
    for (Index b = body.first_bond(i); b < body.end_bond(i); ++b) {
      const Index j = body.neighbour(b);
      const Real tij = force_i.dot(Eigen::Map<const VecK>(w + K * b)) + c[b] * s.extension[b];
      const Real tji = s.dilatation_force.col(j).template head<K>().dot(Eigen::Map<const VecK>(rw + K * b)) +
                       reverse_modulus_[b] * s.extension[b];
      s.pair_force[b] = body.volumes()[i] * bv[b] * (tij + tji);
    }
  }
}

PointMatrix LinearPeridynamicSolid::internal_force(const BondState& s) const {
  const PeridynamicBody& body = body_;
  PointMatrix f(3, body.nodes());
#pragma omp parallel for schedule(static)
  for (Index i = 0; i < body.nodes(); ++i) {
    Vec3 sum = Vec3::Zero();
    if (body.owns(i))
      for (Index b = body.first_bond(i); b < body.end_bond(i); ++b) sum += s.pair_force[b] * s.direction.col(b);
    f.col(i) = sum;
  }
  return f;
}

Eigen::VectorXd LinearPeridynamicSolid::energy_density(const BondState& s) const {
  const PeridynamicBody& body = body_;
  Eigen::VectorXd w(body.nodes());
#pragma omp parallel for schedule(static)
  for (Index i = 0; i < body.nodes(); ++i) {
    if (!body.owns(i)) {
      w[i] = 0;
      continue;
    }
    Real bond = 0;
    for (Index b = body.first_bond(i); b < body.end_bond(i); ++b)
      bond += body.bond_modulus()[b] * s.extension[b] * s.extension[b] * body.bond_volume()[b];
    w[i] = 0.5 * (s.dilatation.col(i).dot(s.dilatation_force.col(i).head<3>()) +
                  s.shear_dilatation.col(i).dot(s.dilatation_force.col(i).tail<3>())) +
           0.5 * bond;
  }
  return w;
}

Real LinearPeridynamicSolid::strain_energy(const BondState& s) const {
  return energy_density(s).dot(body_.volumes());
}

solve::SparseMatrix LinearPeridynamicSolid::stiffness(const BondState& s, bool material, bool geometric) const {
  const PeridynamicBody& body = body_;
  const Index n = body.nodes();
  const auto& w = body.dilatation_weight();
  const auto& c = body.bond_modulus();
  const auto& bv = body.bond_volume();
  const auto& vol = body.volumes();
  const bool shear = body.options().surface_correction == SurfaceCorrection::plate;
  // grad theta_a,i (3 x D per node pair): self part -sum_j w^a beta V_j M_ij; neighbour part w^a_ij beta V_j M_ij.
  using Mat36 = Eigen::Matrix<Real, 3, 6>;
  std::vector<Mat36> self(static_cast<std::size_t>(n));
#pragma omp parallel for schedule(static)
  for (Index i = 0; i < n; ++i) {
    Mat36 sum = Mat36::Zero();
    for (Index b = body.first_bond(i); b < body.end_bond(i); ++b)
      sum += (bv[b] * s.direction.col(b)) * w.col(b).transpose();
    self[static_cast<std::size_t>(i)] = -sum;
  }
  auto gradient = [&](Index i, Index b_or_self) -> Mat36 {  // b_or_self < 0: the node itself
    if (b_or_self < 0) return self[static_cast<std::size_t>(i)];
    return Mat36((bv[b_or_self] * s.direction.col(b_or_self)) * w.col(b_or_self).transpose());
  };
  // Pass 1: the blocks of each column node J (nodes K <= J within two families).
  std::vector<std::vector<Index>> rows(static_cast<std::size_t>(n));
  const int threads = omp_get_max_threads();
  std::vector<std::vector<Index>> markers(static_cast<std::size_t>(threads), std::vector<Index>(static_cast<std::size_t>(n), -1));
#pragma omp parallel for schedule(dynamic, 16)
  for (Index J = 0; J < n; ++J) {
    auto& marker = markers[static_cast<std::size_t>(omp_get_thread_num())];
    auto& list = rows[static_cast<std::size_t>(J)];
    auto add = [&](Index K) {
      if (K <= J && marker[static_cast<std::size_t>(K)] != J) {
        marker[static_cast<std::size_t>(K)] = J;
        list.push_back(K);
      }
    };
    add(J);
    for (Index b = body.first_bond(J); b < body.end_bond(J); ++b) {
      const Index i = body.neighbour(b);
      add(i);
      if (material)
        for (Index bb = body.first_bond(i); bb < body.end_bond(i); ++bb) add(body.neighbour(bb));
    }
    std::sort(list.begin(), list.end());
  }
  // Column starts.
  std::vector<Index> start(static_cast<std::size_t>(3 * n) + 1, 0);
  for (Index J = 0; J < n; ++J) {
    const Index blocks = static_cast<Index>(rows[static_cast<std::size_t>(J)].size());
    for (int b = 0; b < 3; ++b) start[static_cast<std::size_t>(3 * J + b) + 1] = 3 * (blocks - 1) + b + 1;
  }
  for (std::size_t k = 1; k < start.size(); ++k) start[k] += start[k - 1];
  solve::SparseMatrix K(3 * n, 3 * n);
  K.resizeNonZeros(start.back());
  for (std::size_t k = 0; k < start.size(); ++k) K.outerIndexPtr()[k] = static_cast<int>(start[k]);
  // Pass 2: values, gathered per column node J.
#pragma omp parallel for schedule(dynamic, 16)
  for (Index J = 0; J < n; ++J) {
    auto& marker = markers[static_cast<std::size_t>(omp_get_thread_num())];
    const auto& list = rows[static_cast<std::size_t>(J)];
    for (std::size_t k = 0; k < list.size(); ++k) marker[static_cast<std::size_t>(list[k])] = static_cast<Index>(k);
    std::vector<Mat3> blocks(list.size(), Mat3::Zero());
    auto block = [&](Index K) -> Mat3* {
      return K <= J ? &blocks[static_cast<std::size_t>(marker[static_cast<std::size_t>(K)])] : nullptr;
    };
    // Bond terms of J's own bonds.
    for (Index b = body.first_bond(J); b < body.end_bond(J); ++b) {
      const Index j = body.neighbour(b), r = body.reverse(b);
      const Vec3 m = s.direction.col(b);
      const Mat3 mm = m * m.transpose();
      Mat3 S = Mat3::Zero();
      if (material) S += vol[J] * bv[b] * (c[b] + c[r]) * mm;
      if (geometric) S += s.pair_force[b] / s.length[b] * (Mat3::Identity() - mm);
      *block(J) += S;
      if (Mat3* kj = block(j)) *kj -= S;
    }
    // Dilatation terms: every node i whose theta depends on u_J (i = J or J in family(i)).
    if (material) {
      // gradient(i, bb) qg = (beta V M)(w^T qg): an outer product; without shear dilatations (every
      // correction but plate) only the normal 3 x 3 part of Q and w is non-zero
      auto add_dilatation = [&](Index i, const Mat36& gJ) {
        if (shear) {
          const Eigen::Matrix<Real, 6, 3> qg = vol[i] * body.dilatation_coupling(i) * gJ.transpose();
          if (Mat3* ki = block(i)) *ki += gradient(i, -1) * qg;
          for (Index bb = body.first_bond(i); bb < body.end_bond(i); ++bb)
            if (Mat3* kk = block(body.neighbour(bb))) *kk += (bv[bb] * s.direction.col(bb)) * (w.col(bb).transpose() * qg);
        } else {
          const Mat3 qg = vol[i] * body.dilatation_coupling(i).topLeftCorner<3, 3>() * gJ.leftCols<3>().transpose();
          if (Mat3* ki = block(i)) *ki += self[static_cast<std::size_t>(i)].leftCols<3>() * qg;
          for (Index bb = body.first_bond(i); bb < body.end_bond(i); ++bb)
            if (Mat3* kk = block(body.neighbour(bb)))
              *kk += (bv[bb] * s.direction.col(bb)) * (w.col(bb).head<3>().transpose() * qg);
        }
      };
      add_dilatation(J, gradient(J, -1));
      for (Index b = body.first_bond(J); b < body.end_bond(J); ++b) {
        const Index i = body.neighbour(b), r = body.reverse(b);  // r: bond i -> J
        add_dilatation(i, gradient(i, r));
      }
    }
    // Scatter into column J's three columns (rows K <= J; diagonal block upper part only).
    for (int bcol = 0; bcol < 3; ++bcol) {
      Index p = start[static_cast<std::size_t>(3 * J + bcol)];
      for (std::size_t k = 0; k < list.size(); ++k) {
        const Index Kn = list[k];
        const int rows_here = Kn == J ? bcol + 1 : 3;
        for (int a = 0; a < rows_here; ++a, ++p) {
          K.innerIndexPtr()[p] = static_cast<int>(3 * Kn + a);
          K.valuePtr()[p] = blocks[k](a, bcol);
        }
      }
    }
  }
  return K;
}

solve::SparseMatrix matrix_from_parts(const std::vector<std::vector<Eigen::Triplet<Real, int>>>& parts, Index dofs) {
  std::size_t total = 0;
  for (const auto& p : parts) total += p.size();
  std::vector<Eigen::Triplet<Real, int>> all;
  all.reserve(total);
  for (const auto& p : parts) all.insert(all.end(), p.begin(), p.end());
  solve::SparseMatrix k(dofs, dofs);
  k.setFromTriplets(all.begin(), all.end());
  return k;
}

Eigen::VectorXd absolute_row_sums(const solve::SparseMatrix& upper) {
  Eigen::VectorXd sums = Eigen::VectorXd::Zero(upper.rows());
  for (Index col = 0; col < upper.outerSize(); ++col)
    for (solve::SparseMatrix::InnerIterator it(upper, col); it; ++it) {
      sums[it.row()] += std::abs(it.value());
      if (it.row() != col) sums[col] += std::abs(it.value());
    }
  return sums;
}

}  // namespace lamina::pd
