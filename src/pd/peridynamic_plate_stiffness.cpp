// PeridynamicPlate::stiffness: the material stiffness K0 (the analytic Hessian of the plate energy at the
// reference: membrane, bending, thickness stretch, transverse shear, stabilisation) and the membrane
// geometric stiffness, assembled per column into 6 x 6 blocks over the columns' (m, a) - mirror columns
// mapped to the real columns they move with (plate_edge_mirror.hpp) - then mapped to the node dofs.
#include <omp.h>

#include <algorithm>

#include "pd/peridynamic_plate.hpp"

namespace lamina::pd {

namespace {

using Mat32 = Eigen::Matrix<Real, 3, 2>;
using Mat6 = Eigen::Matrix<Real, 6, 6>;

}  // namespace

solve::SparseMatrix PeridynamicPlate::stiffness(const ModelState& state, bool material, bool geometric) const {
  const PlateState& s = static_cast<const PlateState&>(state);
  const PlateColumns& pc = columns_;
  const PeridynamicBody& fam = *family_;
  const Index nc = pc.columns();
  // Block pattern: the columns within two families of each column; blocks (K, J) are 6 x 6 over
  // (m, a) of K (rows) and J (columns), stored for every J over its sorted pattern.
  // (with mirror columns: the family's real columns, families = expanded_families())
  const auto families = expanded_families();
  std::vector<std::vector<Index>> owners(static_cast<std::size_t>(nc));  // the columns whose family holds c
  for (Index i = 0; i < nc; ++i)
    for (Index c : families[static_cast<std::size_t>(i)]) owners[static_cast<std::size_t>(c)].push_back(i);
  std::vector<std::vector<Index>> pattern(static_cast<std::size_t>(nc));
  {
    const int threads = omp_get_max_threads();
    std::vector<std::vector<Index>> markers(static_cast<std::size_t>(threads), std::vector<Index>(static_cast<std::size_t>(nc), -1));
#pragma omp parallel for schedule(dynamic, 32)
    for (Index j = 0; j < nc; ++j) {
      auto& marker = markers[static_cast<std::size_t>(omp_get_thread_num())];
      auto& list = pattern[static_cast<std::size_t>(j)];
      for (Index i : owners[static_cast<std::size_t>(j)])
        for (Index k : families[static_cast<std::size_t>(i)])
          if (marker[static_cast<std::size_t>(k)] != j) marker[static_cast<std::size_t>(k)] = j, list.push_back(k);
      std::sort(list.begin(), list.end());
    }
  }
  // Colours: columns whose families share no column get one colour, so the local matrices of one
  // colour are added without races, in a fixed order.
  std::vector<int> colour(static_cast<std::size_t>(nc), -1);
  int colours = 0;
  {
    std::vector<char> used;
    for (Index j = 0; j < nc; ++j) {
      used.assign(static_cast<std::size_t>(colours) + 1, 0);
      for (Index c : families[static_cast<std::size_t>(j)])
        for (Index k : owners[static_cast<std::size_t>(c)])
          if (colour[static_cast<std::size_t>(k)] >= 0) used[static_cast<std::size_t>(colour[static_cast<std::size_t>(k)])] = 1;
      int c = 0;
      while (used[static_cast<std::size_t>(c)]) ++c;
      colour[static_cast<std::size_t>(j)] = c;
      colours = std::max(colours, c + 1);
    }
  }
  std::vector<std::vector<Index>> by_colour(static_cast<std::size_t>(colours));
  for (Index j = 0; j < nc; ++j) by_colour[static_cast<std::size_t>(colour[static_cast<std::size_t>(j)])].push_back(j);
  std::vector<std::vector<Mat6>> blocks(static_cast<std::size_t>(nc));
  for (Index j = 0; j < nc; ++j) blocks[static_cast<std::size_t>(j)].assign(pattern[static_cast<std::size_t>(j)].size(), Mat6::Zero());
  auto block = [&](Index row, Index col) -> Mat6& {
    const auto& list = pattern[static_cast<std::size_t>(col)];
    const auto it = std::lower_bound(list.begin(), list.end(), row);
    return blocks[static_cast<std::size_t>(col)][static_cast<std::size_t>(it - list.begin())];
  };
  for (const auto& members : by_colour) {
#pragma omp parallel for schedule(dynamic, 8)
    for (std::size_t idx = 0; idx < members.size(); ++idx) {
      const Index i = members[idx];
      const Index b0 = fam.first_bond(i), nf = fam.end_bond(i) - b0, slots = nf + 1;
      auto slot_column = [&](Index s) { return s == 0 ? i : fam.neighbour(b0 + s - 1); };
      Eigen::MatrixXd h = Eigen::MatrixXd::Zero(6 * slots, 6 * slots);
      // dF / dm_s = bvec_s (F_:a = sum_s bvec_s[a] m_s)
      Eigen::Matrix2Xd bvec(2, slots);
      bvec.col(0).setZero();
      for (Index t = 1; t < slots; ++t) {
        bvec.col(t) = v_[b0 + t - 1] * shape_b_.col(b0 + t - 1);
        bvec.col(0) -= bvec.col(t);
      }
      const Real vi = weight_[i];
      if (material) {
        const Eigen::Map<const Mat32> f0(f0_.col(i).data()), dd0(dd0_.col(i).data());
        std::vector<Mat3> r(static_cast<std::size_t>(slots));
        for (Index t = 0; t < slots; ++t) {
          const Index c = slot_column(t);
          r[static_cast<std::size_t>(t)] = (Mat3::Identity() - d0_.col(c) * d0_.col(c).transpose()) / a0_norm_[c];
        }
        // membrane strain, curvature and thickness rows (7 x 6 slots)
        Eigen::MatrixXd g = Eigen::MatrixXd::Zero(7, 6 * slots);
        for (Index t = 0; t < slots; ++t) {
          const Real b0t = bvec(0, t), b1t = bvec(1, t);
          const Mat3& rt = r[static_cast<std::size_t>(t)];
          g.block<1, 3>(0, 6 * t) = b0t * f0.col(0).transpose();
          g.block<1, 3>(1, 6 * t) = b1t * f0.col(1).transpose();
          g.block<1, 3>(2, 6 * t) = b1t * f0.col(0).transpose() + b0t * f0.col(1).transpose();
          g.block<1, 3>(3, 6 * t) = b0t * dd0.col(0).transpose();
          g.block<1, 3>(4, 6 * t) = b1t * dd0.col(1).transpose();
          g.block<1, 3>(5, 6 * t) = b0t * dd0.col(1).transpose() + b1t * dd0.col(0).transpose();
          g.block<1, 3>(3, 6 * t + 3) = b0t * f0.col(0).transpose() * rt;
          g.block<1, 3>(4, 6 * t + 3) = b1t * f0.col(1).transpose() * rt;
          g.block<1, 3>(5, 6 * t + 3) = (b1t * f0.col(0).transpose() + b0t * f0.col(1).transpose()) * rt;
        }
        const Real nu = poisson_[i], alpha = nu / (1 - nu), et = young_[i];
        g.row(6) = alpha * (g.row(0) + g.row(1));
        g.block<1, 3>(6, 3) += d0_.col(i).transpose();
        Eigen::Matrix<Real, 7, 7> wmat = Eigen::Matrix<Real, 7, 7>::Zero();
        const Mat3& cps = plane_stress_[static_cast<std::size_t>(i)];
        wmat.topLeftCorner<3, 3>() = cps;
        wmat.block<3, 3>(3, 3) = bending_factor_ * cps;
        wmat(6, 6) = et;
        for (int t = 0; t < 2; ++t) wmat(t, t) += mirror_.strip(t, i) * et;
        h.noalias() += vi * g.transpose() * (wmat * g);
        // transverse shear: s_b linear in (m_0, a_0, m_t, a_t); gamma = Bm^T s, eta = diag(1/|xi|) (I - X Bm^T) s;
        // energy 1/2 s^T A s with A = kappa mu Bm Bm^T + N^T diag(g v / |xi|^2) N
        const Vec3 di0 = d0_.col(i);
        std::vector<Eigen::Matrix<Real, 12, 1>> gs(static_cast<std::size_t>(nf));
        Eigen::MatrixXd bm(nf, 2), xm(nf, 2);
        Eigen::VectorXd bond_weight(nf);
        for (Index t = 1; t < slots; ++t) {
          const Index b = b0 + t - 1, j = slot_column(t);
          const Vec3 dm0 = m0_.col(j) - m0_.col(i), dbar = 0.5 * (di0 + d0_.col(j));
          auto& gb = gs[static_cast<std::size_t>(t - 1)];
          gb.segment<3>(0) = -dbar;
          gb.segment<3>(3) = r[0].transpose() * dm0 / 2;
          gb.segment<3>(6) = dbar;
          gb.segment<3>(9) = r[static_cast<std::size_t>(t)].transpose() * dm0 / 2;
          bm.row(t - 1) = v_[b] * shape_b_.col(b).transpose();
          xm.row(t - 1) = xi_.col(b).transpose();
          bond_weight[t - 1] = bond_shear_[b] * v_[b] / xi_.col(b).squaredNorm();
        }
        const Eigen::MatrixXd nmat = Eigen::MatrixXd::Identity(nf, nf) - xm * bm.transpose();
        const Eigen::MatrixXd amat = vi * (shear_modulus_[i] * bm * bm.transpose() + nmat.transpose() * bond_weight.asDiagonal() * nmat);
        for (Index bb = 0; bb < nf; ++bb)
          for (Index cc = 0; cc < nf; ++cc) {
            const Real w = amat(bb, cc);
            const Eigen::Matrix<Real, 12, 12> hs = w * gs[static_cast<std::size_t>(bb)] * gs[static_cast<std::size_t>(cc)].transpose();
            const Index tb = bb + 1, tc = cc + 1;
            h.block<6, 6>(0, 0) += hs.block<6, 6>(0, 0);
            h.block<6, 6>(0, 6 * tc) += hs.block<6, 6>(0, 6);
            h.block<6, 6>(6 * tb, 0) += hs.block<6, 6>(6, 0);
            h.block<6, 6>(6 * tb, 6 * tc) += hs.block<6, 6>(6, 6);
          }
        // stabilisation: z_b = sum_t alpha_bt m_t (projected), y_b = sum_t alpha_bt d_t
        Eigen::MatrixXd coefficient = Eigen::MatrixXd::Zero(nf, slots);
        for (Index bb = 0; bb < nf; ++bb) {
          const Eigen::Vector2d x = xi_.col(b0 + bb);
          for (Index t = 0; t < slots; ++t) coefficient(bb, t) = -bvec.col(t).dot(x);
          coefficient(bb, bb + 1) += 1.0;
          coefficient(bb, 0) -= 1.0;
        }
        const Eigen::MatrixXd stab = coefficient.transpose() * stabilizer_.segment(b0, nf).asDiagonal() * coefficient;
        const Mat3 p0 = Mat3::Identity() - di0 * di0.transpose();
        for (Index t = 0; t < slots; ++t)
          for (Index u = 0; u < slots; ++u) {
            const Real w = vi * stab(t, u);
            if (w == 0) continue;
            h.block<3, 3>(6 * t, 6 * u) += (w * membrane_factor_) * p0;
            h.block<3, 3>(6 * t + 3, 6 * u + 3) +=
                (w * bending_factor_) * (r[static_cast<std::size_t>(t)].transpose() * r[static_cast<std::size_t>(u)]);
          }
      }
      if (geometric) {
        const Vec3 sg = s.membrane_stress.col(i);
        Eigen::Matrix2d S;
        S << sg[0], sg[2], sg[2], sg[1];
        for (Index t = 0; t < slots; ++t)
          for (Index u = 0; u < slots; ++u)
            h.block<3, 3>(6 * t, 6 * u).diagonal().array() += vi * bvec.col(t).dot(S * bvec.col(u));
      }
      for (Index t = 0; t < slots; ++t)
        for (Index u = 0; u < slots; ++u)
          for_each_term(slot_column(t), [&](const MirrorTerm& row) {
            for_each_term(slot_column(u), [&](const MirrorTerm& col) {
              Eigen::Matrix<Real, 6, 1> rf, cf;
              rf << row.m, row.a;
              cf << col.m, col.a;
              block(row.column, col.column) += rf.asDiagonal() * h.block<6, 6>(6 * t, 6 * u) * cf.asDiagonal();
            });
          });
    }
  }
  // Node matrix: K_node = T^T K_col T, T_k = [phi_k I; psi_k I]; upper triangle.
  std::vector<std::vector<Eigen::Triplet<Real, int>>> parts(static_cast<std::size_t>(nc));
#pragma omp parallel for schedule(dynamic, 32)
  for (Index j = 0; j < nc; ++j) {
    auto& out = parts[static_cast<std::size_t>(j)];
    const auto& list = pattern[static_cast<std::size_t>(j)];
    for (std::size_t kk = 0; kk < list.size(); ++kk) {
      const Index kc = list[kk];
      const Mat6& bl = blocks[static_cast<std::size_t>(j)][kk];
      for (Index pl = pc.first[j]; pl < pc.first[j + 1]; ++pl) {
        const Index l = pc.node[pl];
        for (Index pk = pc.first[kc]; pk < pc.first[kc + 1]; ++pk) {
          const Index k = pc.node[pk];
          if (k > l) continue;
          const Mat3 nb3 = pc.phi[k] * pc.phi[l] * bl.topLeftCorner<3, 3>() + pc.phi[k] * pc.psi[l] * bl.topRightCorner<3, 3>() +
                           pc.psi[k] * pc.phi[l] * bl.bottomLeftCorner<3, 3>() + pc.psi[k] * pc.psi[l] * bl.bottomRightCorner<3, 3>();
          for (int a = 0; a < 3; ++a)
            for (int c = 0; c < 3; ++c)
              if (k < l || a <= c) out.emplace_back(static_cast<int>(3 * k + a), static_cast<int>(3 * l + c), nb3(a, c));
        }
      }
    }
    if (material && pc.layers > 2) {
      // layer residual: k_r (I - P)^T V (I - P), P_pl = phi_l + zeta_p psi_l
      const Index first = pc.first[j], count = pc.first[j + 1] - first;
      Eigen::MatrixXd ip = Eigen::MatrixXd::Identity(count, count);
      Eigen::VectorXd vol(count);
      for (Index p = 0; p < count; ++p) {
        vol[p] = layer_volume_[pc.node[first + p]];
        for (Index q = 0; q < count; ++q) {
          const Index l = pc.node[first + q];
          ip(p, q) -= pc.phi[l] + pc.zeta[pc.node[first + p]] * pc.psi[l];
        }
      }
      const Eigen::MatrixXd hr = residual_modulus_ * ip.transpose() * vol.asDiagonal() * ip;
      for (Index p = 0; p < count; ++p)
        for (Index q = 0; q < count; ++q) {
          const Index k = pc.node[first + p], l = pc.node[first + q];
          if (k > l) continue;
          for (int a = 0; a < 3; ++a) out.emplace_back(static_cast<int>(3 * k + a), static_cast<int>(3 * l + a), hr(p, q));
        }
    }
  }
  return matrix_from_parts(parts, 3 * nodes_);
}

}  // namespace lamina::pd
