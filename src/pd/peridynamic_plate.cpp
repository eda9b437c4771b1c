#include "pd/peridynamic_plate.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include <omp.h>

#include "core/error.hpp"
#include "material/linear_elastic.hpp"
#include "pd/plate_fit.hpp"

namespace lamina::pd {

namespace {

using Mat32 = Eigen::Matrix<Real, 3, 2>;
using Mat6 = Eigen::Matrix<Real, 6, 6>;

Mat3 plane_stress_voigt(Real e, Real nu) { return material::LinearElastic{e, nu}.plane_stress_matrix(); }

}  // namespace

PeridynamicPlate::PeridynamicPlate(PlateColumns columns, const PointMatrix& reference, const PointMatrix& lattice,
                                   const Eigen::VectorXd& volumes, const Eigen::VectorXd& young,
                                   const Eigen::VectorXd& poisson, const BodyOptions& options)
    : columns_(std::move(columns)), reference_(reference), nodes_(reference.cols()) {
  const PlateColumns& pc = columns_;
  const Index nc = pc.columns();
  thickness_ = pc.thickness;
  bending_factor_ = thickness_ * thickness_ / 12.0;
  // Column centres (in-plane, from the lattice), volumes and moduli.
  PointMatrix centre = PointMatrix::Zero(3, nc);
  volume_.setZero(nc);
  young_.setZero(nc);
  poisson_.setZero(nc);
  for (Index c = 0; c < nc; ++c) {
    const Real count = static_cast<Real>(pc.first[c + 1] - pc.first[c]);
    for (Index p = pc.first[c]; p < pc.first[c + 1]; ++p) {
      const Index i = pc.node[p];
      centre.col(c).head<2>() += lattice.col(i).head<2>() / count;
      volume_[c] += volumes[i];
      young_[c] += young[i] / count;
      poisson_[c] += poisson[i] / count;
    }
  }
  family_ = column_families(centre, volume_, young_, poisson_, options, thickness_);
  const PeridynamicBody& fam = *family_;
  const Index nb = fam.bonds();
  xi_.resize(2, nb);
  shape_b_.resize(2, nb);
  v_.resize(nb);
  stabilizer_.resize(nb);
  bond_shear_.resize(nb);
  shear_modulus_.resize(nc);
  plane_stress_.resize(static_cast<std::size_t>(nc));
  const Real stabilization = options.plate_stabilization;
  Real family_sum = 0, family_min = INFINITY;
  for (Index i = 0; i < nc; ++i) {
    Eigen::Matrix2d k = Eigen::Matrix2d::Zero();
    Real sum_v = 0;
    for (Index b = fam.first_bond(i); b < fam.end_bond(i); ++b) {
      const Index j = fam.neighbour(b);
      xi_.col(b) = (centre.col(j) - centre.col(i)).head<2>();
      const Real length = xi_.col(b).norm();
      const Real omega = options.influence == Influence::one ? 1.0 : options.horizon / length;
      v_[b] = omega * fam.bond_volume()[b];
      k += v_[b] * xi_.col(b) * xi_.col(b).transpose();
      sum_v += v_[b];
    }
    const Index count = fam.end_bond(i) - fam.first_bond(i);
    family_sum += static_cast<Real>(count);
    family_min = std::min(family_min, static_cast<Real>(count));
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(k);
    if (count < 2 || !(eig.eigenvalues()[0] > 1e-8 * eig.eigenvalues()[1]))
      throw InputError("discretization.horizon",
                       "a horizon whose in-plane family spans the plane at every node column (a larger horizon)",
                       fmt::format("{:.4g}: the column at ({:.4g}, {:.4g}) has {} neighbours in a line", options.horizon,
                                   centre(0, i), centre(1, i), count));
    const int degree = gradient_weights(fam.first_bond(i), fam.end_bond(i), options.horizon);
    statistics_.fit_degree_min = std::min(statistics_.fit_degree_min, degree);
    const Real mu = material::LinearElastic{young_[i], poisson_[i]}.mu();
    for (Index b = fam.first_bond(i); b < fam.end_bond(i); ++b) {
      stabilizer_[b] = stabilization * mu * v_[b] / (xi_.col(b).squaredNorm() * sum_v);
      // bond shear: the non-affine transverse deformation, scaled by (t / |xi|)^2 so that its
      // share of a smooth bending field (the trapezoidal error ~ |xi|^2 w_xxx / 12) stays O(t^2 |xi|^2 / L^4)
      bond_shear_[b] = stabilization * (5.0 / 6.0) * mu * thickness_ * thickness_ / (xi_.col(b).squaredNorm() * 0.5 * sum_v);
    }
    shear_modulus_[i] = (5.0 / 6.0) * mu;
    plane_stress_[static_cast<std::size_t>(i)] = plane_stress_voigt(young_[i], poisson_[i]);
  }
  statistics_.mean_family = family_sum / static_cast<Real>(nc);
  statistics_.min_family = family_min;
  statistics_.thickness = thickness_;
  statistics_.layers = pc.layers;
  residual_modulus_ = young_.maxCoeff() * std::pow(pc.layers / thickness_, 2);
  // Reference quantities (stress-free configuration, possibly imperfect).
  metric0_.setZero(3, nc);
  curvature0_.setZero(3, nc);
  shear0_.setZero(2, nc);
  a0_norm_.setOnes(nc);
  layer_volume_ = volumes;
  gamma0_.setZero(nb);
  z0_.setZero(3, nb);
  y0_.setZero(3, nb);
  bond_constants_.resize(static_cast<std::size_t>(nb));
  for (Index b = 0; b < nb; ++b) {
    BondConstants& k = bond_constants_[static_cast<std::size_t>(b)];
    k.weighted_shape = v_[b] * shape_b_.col(b);
    k.xi = xi_.col(b);
    k.inverse_length = 1.0 / xi_.col(b).norm();
    k.membrane = membrane_factor_ * stabilizer_[b];
    k.director = bending_factor_ * stabilizer_[b];
    k.shear = bond_shear_[b] * v_[b];
    k.neighbour = fam.neighbour(b);
  }
  PlateState s;
  update(PointMatrix::Zero(3, nodes_), s, false);  // with zero reference corrections: the raw measures
  reference_residual_ = s.residual;
  a0_norm_ = s.a_norm;
  length0_.resize(nb);
  f0_.resize(6, nc);
  dd0_.resize(6, nc);
  for (Index i = 0; i < nc; ++i) {
    Mat32 f = Mat32::Zero(), d = Mat32::Zero();
    for (Index b = fam.first_bond(i); b < fam.end_bond(i); ++b) {
      const Index j = fam.neighbour(b);
      f += v_[b] * (s.m.col(j) - s.m.col(i)) * shape_b_.col(b).transpose();
      d += v_[b] * (s.d.col(j) - s.d.col(i)) * shape_b_.col(b).transpose();
    }
    f0_.col(i) = Eigen::Map<const Eigen::Matrix<Real, 6, 1>>(f.data());
    dd0_.col(i) = Eigen::Map<const Eigen::Matrix<Real, 6, 1>>(d.data());
    const Eigen::Matrix2d ftf = f.transpose() * f, ftd = f.transpose() * d;
    metric0_.col(i) << ftf(0, 0), ftf(1, 1), ftf(0, 1);
    Eigen::Vector2d gamma_raw = Eigen::Vector2d::Zero();
    for (Index b = fam.first_bond(i); b < fam.end_bond(i); ++b) {
      const Index j = fam.neighbour(b);
      gamma_raw += v_[b] * 0.5 * (s.m.col(j) - s.m.col(i)).dot(s.d.col(i) + s.d.col(j)) * shape_b_.col(b);
    }
    shear0_.col(i) = gamma_raw;
    curvature0_.col(i) << ftd(0, 0), ftd(1, 1), ftd(0, 1) + ftd(1, 0);
    const Vec3 di = s.d.col(i);
    const Mat3 p = Mat3::Identity() - di * di.transpose();
    for (Index b = fam.first_bond(i); b < fam.end_bond(i); ++b) {
      const Index j = fam.neighbour(b);
      const Vec3 dm = s.m.col(j) - s.m.col(i);
      length0_[b] = dm.norm();
      gamma0_[b] = (0.5 * dm.dot(s.d.col(i) + s.d.col(j)) - gamma_raw.dot(xi_.col(b))) / xi_.col(b).norm();
      z0_.col(b) = p * (dm - f * xi_.col(b));
      y0_.col(b) = s.d.col(j) - s.d.col(i) - d * xi_.col(b);
    }
  }
  d0_ = s.d;
  m0_ = s.m;
}

int PeridynamicPlate::gradient_weights(Index b0, Index b1, Real horizon) {
  // degree 3 where the family carries it (exact gradients of cubic fields: no nonlocal softening of a
  // smooth bending mode, no one-sided bias at an edge), else 2, else 1 (plain correspondence)
  Eigen::Matrix2Xd first;
  const int degree = plate_fit_weights(xi_.middleCols(b0, b1 - b0), v_.segment(b0, b1 - b0), horizon, 3, first);
  shape_b_.middleCols(b0, b1 - b0) = first;
  return degree;
}

void PeridynamicPlate::update(const PointMatrix& u, ModelState& state, bool /*linearised*/) const {
  PlateState& s = static_cast<PlateState&>(state);
  const PlateColumns& pc = columns_;
  const PeridynamicBody& fam = *family_;
  const Index nc = pc.columns(), nb = fam.bonds();
  s.m.setZero(3, nc);
  s.a.setZero(3, nc);
  s.d.resize(3, nc);
  s.a_norm.resize(nc);
  s.residual.setZero(3, pc.layers > 2 ? nodes_ : 0);
  s.energy.resize(nc);
  s.membrane_stress.resize(3, nc);
  s.membrane_trace.resize(nc);
  s.membrane_strain.resize(3, nc);
  s.curvature.resize(3, nc);
  s.shear.resize(2, nc);
  s.bond_m.resize(3, nb);
  s.bond_d.resize(3, nb);
  s.bond_dj.resize(3, nb);
  s.self_d.resize(3, nc);
  s.self_a.resize(3, nc);
#pragma omp parallel for schedule(static)
  for (Index c = 0; c < nc; ++c) {
    if (!marked(kinematic_column_, c)) continue;
    Vec3 m = Vec3::Zero(), a = Vec3::Zero();
    for (Index p = pc.first[c]; p < pc.first[c + 1]; ++p) {
      const Index k = pc.node[p];
      const Vec3 x = reference_.col(k) + u.col(k);
      m += pc.phi[k] * x;
      a += pc.psi[k] * x;
    }
    s.m.col(c) = m;
    s.a.col(c) = a;
    s.a_norm[c] = a.norm();
    s.d.col(c) = a / s.a_norm[c];
    if (pc.layers > 2)
      for (Index p = pc.first[c]; p < pc.first[c + 1]; ++p) {
        const Index k = pc.node[p];
        s.residual.col(k) = reference_.col(k) + u.col(k) - m - pc.zeta[k] * a;
        if (reference_residual_.cols() == nodes_) s.residual.col(k) -= reference_residual_.col(k);
      }
  }
  // Per column: the bond vectors are read once into a per-thread scratch (m_j - m_i, d_j, s_b, eta_b).
  struct BondScratch {
    Vec3 dm, dj;
    Real shear = 0, eta = 0;
  };
#pragma omp parallel
  {
    std::vector<BondScratch> scratch;
#pragma omp for schedule(dynamic, 64)
    for (Index i = 0; i < nc; ++i) {
      if (!marked(bond_column_, i)) continue;
      const Index b0 = fam.first_bond(i), b1 = fam.end_bond(i);
      scratch.resize(static_cast<std::size_t>(b1 - b0));
      const BondConstants* bc = bond_constants_.data() + b0;
      BondScratch* bs = scratch.data();
      const Index nf = b1 - b0;
      const Vec3 mi = s.m.col(i), di = s.d.col(i);
      Mat32 f = Mat32::Zero(), d = Mat32::Zero();
      // transverse shear: bond measures s_b = (m_j - m_i) . (d_i + d_j) / 2 (exact zero for quadratic w
      // with linear d), the column shear gamma = sum_b v_b s_b B_b - gamma0 (their fit: exact for uniform
      // shear and pure bending on any family) and the non-affine bond parts eta_b = (s_b - gamma_raw . xi_b) / |xi_b|
      Eigen::Vector2d gamma_raw = Eigen::Vector2d::Zero();
      for (Index t = 0; t < nf; ++t) {
        const Index j = bc[t].neighbour;
        const Vec3 dm = s.m.col(j) - mi, dj = s.d.col(j);
        f += dm * bc[t].weighted_shape.transpose();
        d += (dj - di) * bc[t].weighted_shape.transpose();
        const Real sb = 0.5 * dm.dot(di + dj);
        gamma_raw += sb * bc[t].weighted_shape;
        bs[t].dm = dm;
        bs[t].dj = dj;
        bs[t].shear = sb;
      }
      const Eigen::Matrix2d ftf = f.transpose() * f, ftd = f.transpose() * d;
      const Vec3 e(0.5 * (ftf(0, 0) - metric0_(0, i)), 0.5 * (ftf(1, 1) - metric0_(1, i)), ftf(0, 1) - metric0_(2, i));
      const Vec3 k = Vec3(ftd(0, 0), ftd(1, 1), ftd(0, 1) + ftd(1, 0)) - curvature0_.col(i);
      const Real nu = poisson_[i], alpha = nu / (1 - nu), et = young_[i];
      const Real q = s.a_norm[i] - a0_norm_[i] + alpha * (e[0] + e[1]);
      const Mat3& cps = plane_stress_[static_cast<std::size_t>(i)];
      const Vec3 ce = cps * e, ck = bending_factor_ * (cps * k);
      const Vec3 sigma = ce + Vec3(et * q * alpha, et * q * alpha, 0);
      Real w = 0.5 * e.dot(ce) + 0.5 * et * q * q + 0.5 * k.dot(ck);
      Eigen::Matrix2d S, M;
      S << sigma[0], sigma[2], sigma[2], sigma[1];
      M << ck[0], ck[2], ck[2], ck[1];
      Mat32 pf = f * S + d * M, pd = f * M;
      const Eigen::Vector2d gamma_c = gamma_raw - shear0_.col(i);
      const Eigen::Vector2d tau = shear_modulus_[i] * gamma_c;
      w += 0.5 * tau.dot(gamma_c);
      Eigen::Vector2d lambda = Eigen::Vector2d::Zero();
      for (Index t = 0; t < nf; ++t) {
        const Real eta = (bs[t].shear - gamma_raw.dot(bc[t].xi)) * bc[t].inverse_length - gamma0_[b0 + t];
        bs[t].eta = eta;
        w += 0.5 * bc[t].shear * eta * eta;
        lambda += bc[t].shear * eta * bc[t].inverse_length * bc[t].xi;
      }
      const Eigen::Vector2d tau_lambda = tau - lambda;
      Vec3 self_d = Vec3::Zero();
      for (Index t = 0; t < nf; ++t) {
        const Index b = b0 + t;
        const Vec3& dm = bs[t].dm;
        const Vec3& dj = bs[t].dj;
        // d W / d s_b, then s_b's dependence on m_j - m_i, d_i and d_j
        const Real sigma_b = bc[t].weighted_shape.dot(tau_lambda) + bc[t].shear * bs[t].eta * bc[t].inverse_length;
        Vec3 force_m = (0.5 * sigma_b) * (di + dj);
        self_d += (0.5 * sigma_b) * dm;
        s.bond_dj.col(b) = (volume_[i] * 0.5 * sigma_b) * dm;
        // in-plane non-affine stabilisation (tangent projection P = I - d d^T)
        const Vec3 z_raw = dm - f * bc[t].xi;
        const Real dz = di.dot(z_raw);
        const Vec3 zeta = z_raw - dz * di - z0_.col(b);
        const Real kb = bc[t].membrane;
        const Real dzeta = zeta.dot(di);
        const Vec3 y = kb * (zeta - dzeta * di);
        w += 0.5 * kb * zeta.squaredNorm();
        self_d -= kb * (dz * zeta + dzeta * z_raw);
        pf -= y * bc[t].xi.transpose();
        force_m += y;
        // director non-affine stabilisation
        const Vec3 yd = dj - di - d * bc[t].xi - y0_.col(b);
        const Real kd = bc[t].director;
        w += 0.5 * kd * yd.squaredNorm();
        pd -= kd * yd * bc[t].xi.transpose();
        s.bond_m.col(b) = force_m;
        s.bond_d.col(b) = kd * yd;
      }
      for (Index t = 0; t < nf; ++t) {
        const Index b = b0 + t;
        s.bond_m.col(b) = volume_[i] * (s.bond_m.col(b) + pf * bc[t].weighted_shape);
        s.bond_d.col(b) = volume_[i] * (s.bond_d.col(b) + pd * bc[t].weighted_shape);
      }
      s.self_d.col(i) = volume_[i] * self_d;
      s.self_a.col(i) = volume_[i] * et * q * di;
      s.energy[i] = volume_[i] * w;
      s.membrane_stress.col(i) = sigma;
      s.membrane_trace[i] = e[0] + e[1];
      s.membrane_strain.col(i) = e;
      s.curvature.col(i) = k;
      s.shear.col(i) = gamma_c;
    }
  }
}

void PeridynamicPlate::restrict_to_nodes(const std::vector<char>& nodes) {
  force_column_.clear();
  bond_column_.clear();
  kinematic_column_.clear();
  if (nodes.empty()) return;
  const PlateColumns& pc = columns_;
  const PeridynamicBody& fam = *family_;
  const Index nc = pc.columns();
  auto grow = [&](const std::vector<char>& from) {  // from and the families of its columns
    std::vector<char> to = from;
    for (Index c = 0; c < nc; ++c)
      if (from[static_cast<std::size_t>(c)])
        for (Index b = fam.first_bond(c); b < fam.end_bond(c); ++b) to[static_cast<std::size_t>(fam.neighbour(b))] = 1;
    return to;
  };
  force_column_.assign(static_cast<std::size_t>(nc), 0);
  for (Index c = 0; c < nc; ++c)
    for (Index p = pc.first[c]; p < pc.first[c + 1]; ++p)
      if (nodes[static_cast<std::size_t>(pc.node[p])]) force_column_[static_cast<std::size_t>(c)] = 1;
  bond_column_ = grow(force_column_);
  kinematic_column_ = grow(bond_column_);
}

PointMatrix PeridynamicPlate::internal_force(const ModelState& state) const {
  const PlateState& s = static_cast<const PlateState&>(state);
  const PlateColumns& pc = columns_;
  const PeridynamicBody& fam = *family_;
  const Index nc = pc.columns();
  PointMatrix force(3, nodes_);
#pragma omp parallel for schedule(static)
  for (Index c = 0; c < nc; ++c) {
    if (!marked(force_column_, c)) continue;
    Vec3 gm = Vec3::Zero(), gd = s.self_d.col(c);
    for (Index b = fam.first_bond(c); b < fam.end_bond(c); ++b) {
      const Index r = fam.reverse(b);
      gm += s.bond_m.col(r) - s.bond_m.col(b);
      gd += s.bond_d.col(r) + s.bond_dj.col(r) - s.bond_d.col(b);
    }
    const Vec3 d = s.d.col(c);
    const Vec3 ga = (gd - d * d.dot(gd)) / s.a_norm[c] + s.self_a.col(c);
    for (Index p = pc.first[c]; p < pc.first[c + 1]; ++p) {
      const Index k = pc.node[p];
      force.col(k) = -(pc.phi[k] * gm + pc.psi[k] * ga);
      if (pc.layers > 2) force.col(k) -= residual_modulus_ * layer_volume_[k] * s.residual.col(k);
    }
  }
  return force;
}

solve::SparseMatrix PeridynamicPlate::stiffness(const ModelState& state, bool material, bool geometric) const {
  const PlateState& s = static_cast<const PlateState&>(state);
  const PlateColumns& pc = columns_;
  const PeridynamicBody& fam = *family_;
  const Index nc = pc.columns();
  // Block pattern: the columns within two families of each column; blocks (K, J) are 6 x 6 over
  // (m, a) of K (rows) and J (columns), stored for every J over its sorted pattern.
  std::vector<std::vector<Index>> pattern(static_cast<std::size_t>(nc));
  {
    const int threads = omp_get_max_threads();
    std::vector<std::vector<Index>> markers(static_cast<std::size_t>(threads), std::vector<Index>(static_cast<std::size_t>(nc), -1));
#pragma omp parallel for schedule(dynamic, 32)
    for (Index j = 0; j < nc; ++j) {
      auto& marker = markers[static_cast<std::size_t>(omp_get_thread_num())];
      auto& list = pattern[static_cast<std::size_t>(j)];
      auto add = [&](Index k) {
        if (marker[static_cast<std::size_t>(k)] != j) marker[static_cast<std::size_t>(k)] = j, list.push_back(k);
      };
      add(j);
      for (Index b = fam.first_bond(j); b < fam.end_bond(j); ++b) {
        const Index i = fam.neighbour(b);
        add(i);
        for (Index bb = fam.first_bond(i); bb < fam.end_bond(i); ++bb) add(fam.neighbour(bb));
      }
      std::sort(list.begin(), list.end());
    }
  }
  // Colours: columns whose closed families are disjoint (not within each other's pattern) share one,
  // so the local matrices of one colour are added without races, in a fixed order.
  std::vector<int> colour(static_cast<std::size_t>(nc), -1);
  int colours = 0;
  {
    std::vector<char> used;
    for (Index j = 0; j < nc; ++j) {
      used.assign(static_cast<std::size_t>(colours) + 1, 0);
      for (Index k : pattern[static_cast<std::size_t>(j)])
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
      const Real vi = volume_[i];
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
        for (Index u = 0; u < slots; ++u) block(slot_column(t), slot_column(u)) += h.block<6, 6>(6 * t, 6 * u);
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

Real PeridynamicPlate::strain_energy(const ModelState& state) const {
  const PlateState& s = static_cast<const PlateState&>(state);
  Real w = s.energy.sum();
  if (columns_.layers > 2)
    for (Index k = 0; k < nodes_; ++k) w += 0.5 * residual_modulus_ * layer_volume_[k] * s.residual.col(k).squaredNorm();
  return w;
}

bool PeridynamicPlate::node_strain(const ModelState& state, Index node, Mat3& strain) const {
  const PlateState& s = static_cast<const PlateState&>(state);
  const Index c = columns_.column_of[node];
  if (c < 0 || s.membrane_strain.cols() != columns_.columns()) return false;
  const Real z = columns_.zeta[node];
  const Vec3 e = s.membrane_strain.col(c) + z * s.curvature.col(c);
  // thickness strain: the plane-stress value at this height (sigma_zz = 0 through the thickness), plus
  // the director's residual q (zero in equilibrium)
  const Real alpha = poisson_[c] / (1 - poisson_[c]);
  const Real q = s.a_norm[c] - a0_norm_[c] + alpha * s.membrane_trace[c];
  strain << e[0], 0.5 * e[2], 0.5 * s.shear(0, c), 0.5 * e[2], e[1], 0.5 * s.shear(1, c), 0.5 * s.shear(0, c),
      0.5 * s.shear(1, c), q - alpha * (e[0] + e[1]);
  return true;
}

Eigen::VectorXd PeridynamicPlate::nodal_dilatation(const ModelState& state) const {
  const PlateState& s = static_cast<const PlateState&>(state);
  Eigen::VectorXd out(nodes_);
  for (Index k = 0; k < nodes_; ++k) {
    const Index c = columns_.column_of[k];
    out[k] = s.membrane_trace[c] + s.a_norm[c] - a0_norm_[c];
  }
  return out;
}

}  // namespace lamina::pd
