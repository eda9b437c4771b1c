#include "pd/peridynamic_plate.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include <omp.h>

#include "core/error.hpp"
#include "material/linear_elastic.hpp"
#include "pd/plate_edge_mirror.hpp"
#include "pd/plate_fit.hpp"

namespace lamina::pd {

namespace {

using Mat32 = Eigen::Matrix<Real, 3, 2>;

Mat3 plane_stress_voigt(Real e, Real nu) { return material::LinearElastic{e, nu}.plane_stress_matrix(); }

}  // namespace

PeridynamicPlate::PeridynamicPlate(PlateColumns columns, const PointMatrix& reference, const PointMatrix& lattice,
                                   const Eigen::VectorXd& volumes, const Eigen::VectorXd& young,
                                   const Eigen::VectorXd& poisson, const BodyOptions& options,
                                   const std::vector<char>& held)
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
  // mirror columns across supported edges (family members only: the image's volume and moduli)
  mirror_ = held.empty() || !options.plate_edge_mirror
                ? no_edge_mirror(nc)
                : mirror_supported_edges(pc, centre, held, options.horizon + 1.5 * pc.spacing);
  const Index ng = mirror_.count(), ne = nc + ng;
  PointMatrix family_centre(3, ne);
  family_centre << centre, mirror_.centre;
  volume_.conservativeResize(ne);
  young_.conservativeResize(ne);
  poisson_.conservativeResize(ne);
  for (Index g = 0; g < ng; ++g) {
    const Index image = mirror_.image_of[static_cast<std::size_t>(g)];
    volume_[nc + g] = volume_[image];
    young_[nc + g] = young_[image];
    poisson_[nc + g] = poisson_[image];
  }
  weight_ = volume_.head(nc).cwiseProduct(mirror_.energy_factor);
  family_ = column_families(family_centre, volume_, young_, poisson_, options, thickness_);
  const PeridynamicBody& fam = *family_;
  const Index nb = fam.bonds();
  // (bonds of mirror columns: never used, zero)
  xi_.setZero(2, nb);
  shape_b_.setZero(2, nb);
  v_.setZero(nb);
  stabilizer_.setZero(nb);
  bond_shear_.setZero(nb);
  shear_modulus_.resize(nc);
  plane_stress_.resize(static_cast<std::size_t>(nc));
  const Real stabilization = options.plate_stabilization;
  Real family_sum = 0, family_min = INFINITY;
  for (Index i = 0; i < nc; ++i) {
    Eigen::Matrix2d k = Eigen::Matrix2d::Zero();
    Real sum_v = 0;
    for (Index b = fam.first_bond(i); b < fam.end_bond(i); ++b) {
      const Index j = fam.neighbour(b);
      xi_.col(b) = (family_centre.col(j) - family_centre.col(i)).head<2>();
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
  a0_norm_.setOnes(ne);
  layer_volume_ = volumes;
  gamma0_.setZero(nb);
  z0_.setZero(3, nb);
  y0_.setZero(3, nb);
  bond_constants_.resize(static_cast<std::size_t>(nb));
  for (Index b = 0; b < nb; ++b) {
    BondConstants& k = bond_constants_[static_cast<std::size_t>(b)];
    k.weighted_shape = v_[b] * shape_b_.col(b);
    k.xi = xi_.col(b);
    k.inverse_length = xi_.col(b).norm() > 0 ? 1.0 / xi_.col(b).norm() : 0.0;
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
  const Index nc = pc.columns(), nb = fam.bonds(), ne = nc + mirror_.count();
  s.m.setZero(3, ne);
  s.a.setZero(3, ne);
  s.d.resize(3, ne);
  s.a_norm.resize(ne);
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
  // mirror columns: fixed combinations of real ones (m and a are linear in the node positions)
  for (Index g = 0; g < mirror_.count(); ++g) {
    const auto& motion = mirror_.motion[static_cast<std::size_t>(g)];
    if (!kinematic_column_.empty() &&
        !std::all_of(motion.begin(), motion.end(),
                     [&](const MirrorTerm& t) { return marked(kinematic_column_, t.column); }))
      continue;
    Vec3 m = Vec3::Zero(), a = Vec3::Zero();
    for (const MirrorTerm& t : motion) {
      m += t.m.cwiseProduct(s.m.col(t.column));
      a += t.a.cwiseProduct(s.a.col(t.column));
    }
    const Index c = nc + g;
    s.m.col(c) = m;
    s.a.col(c) = a;
    s.a_norm[c] = a.norm();
    s.d.col(c) = a / s.a_norm[c];
  }
  if (mirror_.count() > 0) {  // bonds owned by mirror columns carry nothing
    const Index b0 = fam.first_bond(nc);
    s.bond_m.rightCols(nb - b0).setZero();
    s.bond_d.rightCols(nb - b0).setZero();
    s.bond_dj.rightCols(nb - b0).setZero();
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
      Vec3 sigma = ce + Vec3(et * q * alpha, et * q * alpha, 0);
      Real w = 0.5 * e.dot(ce) + 0.5 * et * q * q + 0.5 * k.dot(ck);
      for (int t = 0; t < 2; ++t)  // the half-cell strip beyond a mirror line, free along it (a bar)
        if (const Real strip = mirror_.strip(t, i); strip > 0) {
          sigma[t] += strip * et * e[t];
          w += 0.5 * strip * et * e[t] * e[t];
        }
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
        s.bond_dj.col(b) = (weight_[i] * 0.5 * sigma_b) * dm;
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
        s.bond_m.col(b) = weight_[i] * (s.bond_m.col(b) + pf * bc[t].weighted_shape);
        s.bond_d.col(b) = weight_[i] * (s.bond_d.col(b) + pd * bc[t].weighted_shape);
      }
      s.self_d.col(i) = weight_[i] * self_d;
      s.self_a.col(i) = weight_[i] * et * q * di;
      s.energy[i] = weight_[i] * w;
      s.membrane_stress.col(i) = sigma;
      s.membrane_trace[i] = e[0] + e[1];
      s.membrane_strain.col(i) = e;
      s.curvature.col(i) = k;
      s.shear.col(i) = gamma_c;
    }
  }
}

std::vector<std::vector<Index>> PeridynamicPlate::expanded_families() const {
  const PeridynamicBody& fam = *family_;
  const Index nc = columns_.columns();
  std::vector<std::vector<Index>> out(static_cast<std::size_t>(nc));
#pragma omp parallel for schedule(dynamic, 64)
  for (Index i = 0; i < nc; ++i) {
    auto& list = out[static_cast<std::size_t>(i)];
    list.push_back(i);
    for (Index b = fam.first_bond(i); b < fam.end_bond(i); ++b)
      for_each_term(fam.neighbour(b), [&](const MirrorTerm& t) { list.push_back(t.column); });
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  return out;
}

void PeridynamicPlate::restrict_to_nodes(const std::vector<char>& nodes) {
  force_column_.clear();
  bond_column_.clear();
  kinematic_column_.clear();
  if (nodes.empty()) return;
  const PlateColumns& pc = columns_;
  const Index nc = pc.columns();
  force_column_.assign(static_cast<std::size_t>(nc), 0);
  for (Index c = 0; c < nc; ++c)
    for (Index p = pc.first[c]; p < pc.first[c + 1]; ++p)
      if (nodes[static_cast<std::size_t>(pc.node[p])]) force_column_[static_cast<std::size_t>(c)] = 1;
  // the columns whose energy reaches a force column, and the columns their energy depends on
  const auto families = expanded_families();
  bond_column_.assign(static_cast<std::size_t>(nc), 0);
  kinematic_column_.assign(static_cast<std::size_t>(nc), 0);
  for (Index i = 0; i < nc; ++i) {
    const auto& list = families[static_cast<std::size_t>(i)];
    if (std::none_of(list.begin(), list.end(),
                     [&](Index c) { return force_column_[static_cast<std::size_t>(c)] != 0; }))
      continue;
    bond_column_[static_cast<std::size_t>(i)] = 1;
    for (Index c : list) kinematic_column_[static_cast<std::size_t>(c)] = 1;
  }
}

PointMatrix PeridynamicPlate::internal_force(const ModelState& state) const {
  const PlateState& s = static_cast<const PlateState&>(state);
  const PlateColumns& pc = columns_;
  const PeridynamicBody& fam = *family_;
  const Index nc = pc.columns(), ng = mirror_.count();
  // d Pi / d m and d Pi / d a of every column (mirror columns: then added to the columns they move with)
  PointMatrix gradient_m(3, nc + ng), gradient_a(3, nc + ng);
  std::vector<char> mirror_needed(static_cast<std::size_t>(ng), 0);
  for (Index g = 0; g < ng; ++g)
    for (const MirrorTerm& t : mirror_.motion[static_cast<std::size_t>(g)])
      if (marked(force_column_, t.column)) mirror_needed[static_cast<std::size_t>(g)] = 1;
#pragma omp parallel for schedule(static)
  for (Index c = 0; c < nc + ng; ++c) {
    if (c < nc ? !marked(force_column_, c) : !mirror_needed[static_cast<std::size_t>(c - nc)]) continue;
    Vec3 gm = Vec3::Zero(), gd = c < nc ? Vec3(s.self_d.col(c)) : Vec3::Zero();
    for (Index b = fam.first_bond(c); b < fam.end_bond(c); ++b) {
      const Index r = fam.reverse(b);
      gm += s.bond_m.col(r) - s.bond_m.col(b);
      gd += s.bond_d.col(r) + s.bond_dj.col(r) - s.bond_d.col(b);
    }
    const Vec3 d = s.d.col(c);
    gradient_m.col(c) = gm;
    gradient_a.col(c) = (gd - d * d.dot(gd)) / s.a_norm[c];
    if (c < nc) gradient_a.col(c) += s.self_a.col(c);
  }
  for (Index g = 0; g < ng; ++g)  // in order: deterministic
    if (mirror_needed[static_cast<std::size_t>(g)])
      for (const MirrorTerm& t : mirror_.motion[static_cast<std::size_t>(g)]) {
        gradient_m.col(t.column) += t.m.cwiseProduct(gradient_m.col(nc + g));
        gradient_a.col(t.column) += t.a.cwiseProduct(gradient_a.col(nc + g));
      }
  PointMatrix force(3, nodes_);
#pragma omp parallel for schedule(static)
  for (Index c = 0; c < nc; ++c) {
    if (!marked(force_column_, c)) continue;
    const Vec3 gm = gradient_m.col(c), ga = gradient_a.col(c);
    for (Index p = pc.first[c]; p < pc.first[c + 1]; ++p) {
      const Index k = pc.node[p];
      force.col(k) = -(pc.phi[k] * gm + pc.psi[k] * ga);
      if (pc.layers > 2) force.col(k) -= residual_modulus_ * layer_volume_[k] * s.residual.col(k);
    }
  }
  return force;
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
