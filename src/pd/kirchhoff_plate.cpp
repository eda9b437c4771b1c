#include "pd/kirchhoff_plate.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "material/linear_elastic.hpp"
#include "pd/plate_fit.hpp"

namespace lamina::pd {

namespace {

using Mat32 = Eigen::Matrix<Real, 3, 2>;

/// The fit's kinematics of one node: F, the second derivatives H (xx, yy, xy), the unit normal and
/// |F_1 x F_2|, from the bond vectors dm_t = m_j - m_i.
struct FitKinematics {
  Mat32 f = Mat32::Zero();
  Vec3 h[3] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
  Vec3 n = Vec3::UnitZ();
  Real area = 1;
};

FitKinematics fit_kinematics(const Vec3* dm, Index count, const Eigen::Matrix2Xd& first, const Eigen::Matrix3Xd& second,
                             Index b0) {
  FitKinematics k;
  for (Index t = 0; t < count; ++t) {
    const Index b = b0 + t;
    k.f.col(0) += first(0, b) * dm[t];
    k.f.col(1) += first(1, b) * dm[t];
    for (int a = 0; a < 3; ++a) k.h[a] += second(a, b) * dm[t];
  }
  const Vec3 c = k.f.col(0).cross(k.f.col(1));
  k.area = c.norm();
  k.n = c / k.area;
  return k;
}

}  // namespace

KirchhoffPlate::KirchhoffPlate(PlateColumns columns, const PointMatrix& reference, const PointMatrix& lattice,
                               const Eigen::VectorXd& volumes, const Eigen::VectorXd& young, const Eigen::VectorXd& poisson,
                               const BodyOptions& options)
    : columns_(std::move(columns)), reference_(reference), nodes_(reference.cols()) {
  const PlateColumns& pc = columns_;
  const Index nc = pc.columns();
  if (pc.layers != 1) throw std::invalid_argument("KirchhoffPlate: a one-layer plate lattice");
  thickness_ = pc.thickness;
  bending_factor_ = thickness_ * thickness_ / 12.0;
  PointMatrix centre = PointMatrix::Zero(3, nc);
  volume_.resize(nc);
  young_.resize(nc);
  poisson_.resize(nc);
  for (Index c = 0; c < nc; ++c) {
    const Index node = pc.node[pc.first[c]];
    centre.col(c).head<2>() = lattice.col(node).head<2>();
    volume_[c] = volumes[node];
    young_[c] = young[node];
    poisson_[c] = poisson[node];
  }
  family_ = column_families(centre, volume_, young_, poisson_, options, thickness_);
  const PeridynamicBody& fam = *family_;
  const Index nb = fam.bonds();
  xi_.resize(2, nb);
  first_.resize(2, nb);
  second_.resize(3, nb);
  membrane_stabilizer_.resize(nb);
  transverse_stabilizer_.resize(nb);
  inverse_length_.resize(nb);
  plane_stress_.resize(static_cast<std::size_t>(nc));
  const Real s = options.plate_stabilization;
  for (Index i = 0; i < nc; ++i) {
    const Index b0 = fam.first_bond(i), count = fam.end_bond(i) - b0;
    Eigen::VectorXd v(count);
    Real sum_v = 0;
    for (Index t = 0; t < count; ++t) {
      const Index b = b0 + t, j = fam.neighbour(b);
      xi_.col(b) = (centre.col(j) - centre.col(i)).head<2>();
      const Real length = xi_.col(b).norm();
      v[t] = (options.influence == Influence::one ? 1.0 : options.horizon / length) * fam.bond_volume()[b];
      sum_v += v[t];
      inverse_length_[b] = 1.0 / length;
    }
    Eigen::Matrix2Xd first;
    Eigen::Matrix3Xd second;
    const int degree = count > 0 ? plate_fit_weights(xi_.middleCols(b0, count), v, options.horizon, 3, first, &second) : 0;
    if (degree < 2)
      throw InputError("discretization.horizon",
                       "a horizon whose in-plane family carries a quadratic fit at every node of a one-layer plate "
                       "(at least 7 neighbours around the node: a horizon above the in-plane cell diagonal, e.g. "
                       "horizon_factor 3.015)",
                       fmt::format("{:.4g}: the node at ({:.4g}, {:.4g}) has {} neighbours", options.horizon,
                                   centre(0, i), centre(1, i), count));
    fit_degree_min_ = std::min(fit_degree_min_, degree);
    const Real mu = material::LinearElastic{young_[i], poisson_[i]}.mu();
    for (Index t = 0; t < count; ++t) {
      const Index b = b0 + t;
      first_.col(b) = v[t] * first.col(t);
      second_.col(b) = v[t] * second.col(t);
      const Real xi2 = xi_.col(b).squaredNorm();
      // the director model's moduli (peridynamic_plate.cpp): in-plane 4 s mu, transverse s (5/6) mu (t / |xi|)^2
      membrane_stabilizer_[b] = 4.0 * s * mu * v[t] / (xi2 * sum_v);
      transverse_stabilizer_[b] = v[t] * s * (5.0 / 6.0) * mu * thickness_ * thickness_ / (xi2 * 0.5 * sum_v);
    }
    plane_stress_[static_cast<std::size_t>(i)] = material::LinearElastic{young_[i], poisson_[i]}.plane_stress_matrix();
  }
  // Reference (stress-free, possibly imperfect) measures.
  metric0_.setZero(3, nc);
  curvature0_.setZero(3, nc);
  z0_.setZero(3, nb);
  r0_.setZero(nb);
  std::vector<Vec3> dm;
  for (Index i = 0; i < nc; ++i) {
    const Index b0 = fam.first_bond(i), count = fam.end_bond(i) - b0;
    const Vec3 mi = reference_.col(pc.node[pc.first[i]]);
    dm.resize(static_cast<std::size_t>(count));
    for (Index t = 0; t < count; ++t) dm[static_cast<std::size_t>(t)] = reference_.col(pc.node[pc.first[fam.neighbour(b0 + t)]]) - mi;
    const FitKinematics k = fit_kinematics(dm.data(), count, first_, second_, b0);
    metric0_.col(i) << k.f.col(0).squaredNorm(), k.f.col(1).squaredNorm(), k.f.col(0).dot(k.f.col(1));
    curvature0_.col(i) << -k.n.dot(k.h[0]), -k.n.dot(k.h[1]), -2.0 * k.n.dot(k.h[2]);
    for (Index t = 0; t < count; ++t) {
      const Index b = b0 + t;
      const Vec3 u = dm[static_cast<std::size_t>(t)] - k.f * xi_.col(b);
      const Real x = xi_(0, b), y = xi_(1, b);
      const Vec3 q = x * x * k.h[0] + y * y * k.h[1] + 2.0 * x * y * k.h[2];
      z0_.col(b) = u - k.n.dot(u) * k.n;
      r0_[b] = k.n.dot(u - 0.5 * q) * inverse_length_[b];
    }
  }
}

Real KirchhoffPlate::node_energy(Index i, const Vec3* slot, Vec3* bond_gradient, Measures* measures) const {
  const PeridynamicBody& fam = *family_;
  const Index b0 = fam.first_bond(i), count = fam.end_bond(i) - b0;
  thread_local std::vector<Vec3> dm;
  dm.resize(static_cast<std::size_t>(count));
  for (Index t = 0; t < count; ++t) dm[static_cast<std::size_t>(t)] = slot[1 + t] - slot[0];
  const FitKinematics k = fit_kinematics(dm.data(), count, first_, second_, b0);
  const Mat32& f = k.f;
  const Vec3& n = k.n;
  const Vec3 e(0.5 * (f.col(0).squaredNorm() - metric0_(0, i)), 0.5 * (f.col(1).squaredNorm() - metric0_(1, i)),
               f.col(0).dot(f.col(1)) - metric0_(2, i));
  const Vec3 kappa = Vec3(-n.dot(k.h[0]), -n.dot(k.h[1]), -2.0 * n.dot(k.h[2])) - curvature0_.col(i);
  const Mat3& c = plane_stress_[static_cast<std::size_t>(i)];
  const Vec3 sigma = c * e, moment = bending_factor_ * (c * kappa);
  Real w = 0.5 * e.dot(sigma) + 0.5 * kappa.dot(moment);
  // gradients with respect to F, H and n
  Eigen::Matrix2d stress;
  stress << sigma[0], sigma[2], sigma[2], sigma[1];
  Mat32 grad_f = f * stress;
  Vec3 grad_h[3] = {-moment[0] * n, -moment[1] * n, -2.0 * moment[2] * n};
  Vec3 grad_n = -(moment[0] * k.h[0] + moment[1] * k.h[1] + 2.0 * moment[2] * k.h[2]);
  // stabilisation of what the fit leaves: in-plane z_b, transverse r_b
  for (Index t = 0; t < count; ++t) {
    const Index b = b0 + t;
    const Eigen::Vector2d xi = xi_.col(b);
    const Vec3 u = dm[static_cast<std::size_t>(t)] - f * xi;
    const Real nu = n.dot(u);
    const Vec3 z = u - nu * n - z0_.col(b);
    const Vec3 y = membrane_stabilizer_[b] * z;
    w += 0.5 * y.dot(z);
    const Real ny = n.dot(y);
    const Vec3 py = y - ny * n;
    Vec3 g = py;
    grad_f -= py * xi.transpose();
    grad_n -= nu * y + ny * u;
    const Vec3 q = xi[0] * xi[0] * k.h[0] + xi[1] * xi[1] * k.h[1] + 2.0 * xi[0] * xi[1] * k.h[2];
    const Vec3 rest = u - 0.5 * q;
    const Real r = n.dot(rest) * inverse_length_[b] - r0_[b];
    w += 0.5 * transverse_stabilizer_[b] * r * r;
    const Real rho = transverse_stabilizer_[b] * r * inverse_length_[b];
    grad_n += rho * rest;
    g += rho * n;
    grad_f -= (rho * n) * xi.transpose();
    grad_h[0] -= (0.5 * rho * xi[0] * xi[0]) * n;
    grad_h[1] -= (0.5 * rho * xi[1] * xi[1]) * n;
    grad_h[2] -= (rho * xi[0] * xi[1]) * n;
    bond_gradient[t] = g;
  }
  // held rotations: the penalty on the change of the tangents out of the plane (the slopes)
  if (!held_axes_.empty() && held_axes_[static_cast<std::size_t>(i)]) {
    const std::uint8_t axes = held_axes_[static_cast<std::size_t>(i)];
    const Mat32& f0 = held_tangents0_[static_cast<std::size_t>(i)];
    const Vec3 d1 = f.col(0) - f0.col(0), d2 = f.col(1) - f0.col(1);
    const Real k_held = kRotationPenalty * bending_factor_ * plane_stress_[static_cast<std::size_t>(i)](0, 0) /
                        (columns_.spacing * columns_.spacing);
    if (axes & 1u) {  // rx: the tangent along y stays in the plane
      w += 0.5 * k_held * d2.z() * d2.z();
      grad_f.col(1).z() += k_held * d2.z();
    }
    if (axes & 2u) {  // ry: the tangent along x
      w += 0.5 * k_held * d1.z() * d1.z();
      grad_f.col(0).z() += k_held * d1.z();
    }
  }
  // n = F_1 x F_2 / |F_1 x F_2|: dn = (I - n n^T) (dF_1 x F_2 + F_1 x dF_2) / |F_1 x F_2|
  const Vec3 perpendicular = (grad_n - n.dot(grad_n) * n) / k.area;
  grad_f.col(0) += f.col(1).cross(perpendicular);
  grad_f.col(1) += perpendicular.cross(f.col(0));
  const Real v = volume_[i];
  for (Index t = 0; t < count; ++t) {
    const Index b = b0 + t;
    bond_gradient[t] = v * (bond_gradient[t] + grad_f * first_.col(b) + second_(0, b) * grad_h[0] +
                            second_(1, b) * grad_h[1] + second_(2, b) * grad_h[2]);
  }
  if (measures) *measures = {sigma, e, kappa};
  return v * w;
}

void KirchhoffPlate::hold_rotations(const HeldRotations& held, const std::vector<char>& prescribed) {
  const PlateColumns& pc = columns_;
  const PeridynamicBody& fam = *family_;
  const Index nc = pc.columns();
  held_axes_.assign(static_cast<std::size_t>(nc), 0);
  held_tangents0_.assign(static_cast<std::size_t>(nc), Mat32::Zero());
  auto is_prescribed = [&](Index column, int a) {
    return prescribed[static_cast<std::size_t>(3 * pc.node[pc.first[column]] + a)] != 0;
  };
  std::vector<Vec3> dm;
  for (std::size_t e = 0; e < held.nodes.size(); ++e) {
    const Index node = held.nodes[e];
    const Index c = node >= 0 && node < static_cast<Index>(pc.column_of.size()) ? pc.column_of[node] : -1;
    if (c < 0) continue;
    const Index b0 = fam.first_bond(c), count = fam.end_bond(c) - b0;
    // the lattice neighbours one spacing away along x and along y: are their w prescribed?
    bool w_fixed_along[2] = {true, true};
    int found[2] = {0, 0};
    for (Index t = 0; t < count; ++t) {
      const Index b = b0 + t, j = fam.neighbour(b);
      for (int a = 0; a < 2; ++a) {
        const Real along = std::abs(xi_(a, b)), across = std::abs(xi_(1 - a, b));
        if (std::abs(along - pc.spacing) > 1e-6 * pc.spacing || across > 1e-6 * pc.spacing) continue;
        ++found[a];
        w_fixed_along[a] = w_fixed_along[a] && is_prescribed(j, 2);
      }
    }
    std::uint8_t axes = held.axes[e] & 3u;  // rz: no drilling rotation (the in-plane rotation follows x, y)
    if (found[1] > 0 && w_fixed_along[1]) axes &= static_cast<std::uint8_t>(~1u);  // rx: the slope along y
    if (found[0] > 0 && w_fixed_along[0]) axes &= static_cast<std::uint8_t>(~2u);  // ry: the slope along x
    held_axes_[static_cast<std::size_t>(c)] |= axes;
    const Vec3 mc = reference_.col(pc.node[pc.first[c]]);
    dm.resize(static_cast<std::size_t>(count));
    for (Index t = 0; t < count; ++t) dm[static_cast<std::size_t>(t)] = reference_.col(pc.node[pc.first[fam.neighbour(b0 + t)]]) - mc;
    const FitKinematics k = fit_kinematics(dm.data(), count, first_, second_, b0);
    held_tangents0_[static_cast<std::size_t>(c)] = k.f;
  }
}

Real KirchhoffPlate::transverse_wavenumber(const PointMatrix& field) const {
  const PlateColumns& pc = columns_;
  const PeridynamicBody& fam = *family_;
  Real curvature = 0, slope = 0;
  for (Index i = 0; i < pc.columns(); ++i) {
    const Real wi = field(2, pc.node[pc.first[i]]);
    Eigen::Vector2d g = Eigen::Vector2d::Zero();
    Vec3 h = Vec3::Zero();
    for (Index b = fam.first_bond(i); b < fam.end_bond(i); ++b) {
      const Real dw = field(2, pc.node[pc.first[fam.neighbour(b)]]) - wi;
      g += dw * first_.col(b);
      h += dw * second_.col(b);
    }
    curvature += volume_[i] * (h[0] * h[0] + h[1] * h[1] + 2 * h[2] * h[2]);
    slope += volume_[i] * g.squaredNorm();
  }
  return slope > 0 ? std::sqrt(curvature / slope) : 0.0;
}

void KirchhoffPlate::update(const PointMatrix& u, ModelState& state, bool /*linearised*/) const {
  auto& s = static_cast<KirchhoffPlateState&>(state);
  const PlateColumns& pc = columns_;
  const PeridynamicBody& fam = *family_;
  const Index nc = pc.columns();
  s.m.resize(3, nc);
  for (Index c = 0; c < nc; ++c) {
    const Index node = pc.node[pc.first[c]];
    s.m.col(c) = reference_.col(node) + u.col(node);
  }
  s.energy.resize(nc);
  s.membrane_stress.resize(3, nc);
  s.membrane_strain.resize(3, nc);
  s.curvature.resize(3, nc);
  s.bond_gradient.resize(3, fam.bonds());
#pragma omp parallel
  {
    std::vector<Vec3> slot, gradient;
#pragma omp for schedule(dynamic, 64)
    for (Index i = 0; i < nc; ++i) {
      const Index b0 = fam.first_bond(i), count = fam.end_bond(i) - b0;
      slot.resize(static_cast<std::size_t>(count + 1));
      gradient.resize(static_cast<std::size_t>(count));
      slot[0] = s.m.col(i);
      for (Index t = 0; t < count; ++t) slot[static_cast<std::size_t>(t + 1)] = s.m.col(fam.neighbour(b0 + t));
      Measures measures;
      s.energy[i] = node_energy(i, slot.data(), gradient.data(), &measures);
      for (Index t = 0; t < count; ++t) s.bond_gradient.col(b0 + t) = gradient[static_cast<std::size_t>(t)];
      s.membrane_stress.col(i) = measures.stress;
      s.membrane_strain.col(i) = measures.strain;
      s.curvature.col(i) = measures.curvature;
    }
  }
}

PointMatrix KirchhoffPlate::internal_force(const ModelState& state) const {
  const auto& s = static_cast<const KirchhoffPlateState&>(state);
  const PlateColumns& pc = columns_;
  const PeridynamicBody& fam = *family_;
  const Index nc = pc.columns();
  PointMatrix force = PointMatrix::Zero(3, nodes_);
#pragma omp parallel for schedule(static)
  for (Index c = 0; c < nc; ++c) {
    Vec3 g = Vec3::Zero();
    for (Index b = fam.first_bond(c); b < fam.end_bond(c); ++b) g += s.bond_gradient.col(fam.reverse(b)) - s.bond_gradient.col(b);
    force.col(pc.node[pc.first[c]]) = -g;
  }
  return force;
}

Real KirchhoffPlate::strain_energy(const ModelState& state) const {
  return static_cast<const KirchhoffPlateState&>(state).energy.sum();
}

solve::SparseMatrix KirchhoffPlate::stiffness(const ModelState& state, bool material, bool geometric) const {
  const auto& s = static_cast<const KirchhoffPlateState&>(state);
  const PlateColumns& pc = columns_;
  const PeridynamicBody& fam = *family_;
  const Index nc = pc.columns();
  const Real step = 1e-5 * pc.spacing;
  std::vector<std::vector<Eigen::Triplet<Real, int>>> parts(static_cast<std::size_t>(nc));
#pragma omp parallel
  {
    std::vector<Vec3> slot, plus, minus;
#pragma omp for schedule(dynamic, 16)
    for (Index i = 0; i < nc; ++i) {
      const Index b0 = fam.first_bond(i), count = fam.end_bond(i) - b0, slots = count + 1;
      auto column_of_slot = [&](Index t) { return t == 0 ? i : fam.neighbour(b0 + t - 1); };
      Eigen::MatrixXd h = Eigen::MatrixXd::Zero(3 * slots, 3 * slots);
      if (material) {
        // central differences of the exact gradient at the reference configuration
        slot.resize(static_cast<std::size_t>(slots));
        plus.resize(static_cast<std::size_t>(count));
        minus.resize(static_cast<std::size_t>(count));
        for (Index t = 0; t < slots; ++t) slot[static_cast<std::size_t>(t)] = reference_.col(pc.node[pc.first[column_of_slot(t)]]);
        for (Index t = 0; t < slots; ++t)
          for (int a = 0; a < 3; ++a) {
            Vec3& x = slot[static_cast<std::size_t>(t)];
            const Real saved = x[a];
            x[a] = saved + step;
            node_energy(i, slot.data(), plus.data(), nullptr);
            x[a] = saved - step;
            node_energy(i, slot.data(), minus.data(), nullptr);
            x[a] = saved;
            const Index column = 3 * t + a;
            for (Index q = 0; q < count; ++q) {
              const Vec3 d = (plus[static_cast<std::size_t>(q)] - minus[static_cast<std::size_t>(q)]) / (2 * step);
              h.block<3, 1>(3 * (q + 1), column) += d;
              h.block<3, 1>(0, column) -= d;
            }
          }
        h = (0.5 * (h + h.transpose())).eval();
      }
      if (geometric) {
        const Vec3 sg = s.membrane_stress.col(i);
        Eigen::Matrix2d stress;
        stress << sg[0], sg[2], sg[2], sg[1];
        Eigen::Matrix2Xd bvec(2, slots);
        bvec.col(0).setZero();
        for (Index t = 1; t < slots; ++t) {
          bvec.col(t) = first_.col(b0 + t - 1);
          bvec.col(0) -= bvec.col(t);
        }
        for (Index t = 0; t < slots; ++t)
          for (Index q = 0; q < slots; ++q)
            h.block<3, 3>(3 * t, 3 * q).diagonal().array() += volume_[i] * bvec.col(t).dot(stress * bvec.col(q));
      }
      auto& out = parts[static_cast<std::size_t>(i)];
      for (Index t = 0; t < slots; ++t)
        for (Index q = 0; q < slots; ++q) {
          const Index k = pc.node[pc.first[column_of_slot(t)]], l = pc.node[pc.first[column_of_slot(q)]];
          if (k > l) continue;
          for (int a = 0; a < 3; ++a)
            for (int c = 0; c < 3; ++c)
              if ((k < l || a <= c) && h(3 * t + a, 3 * q + c) != 0.0)
                out.emplace_back(static_cast<int>(3 * k + a), static_cast<int>(3 * l + c), h(3 * t + a, 3 * q + c));
        }
    }
  }
  return matrix_from_parts(parts, 3 * nodes_);
}

Eigen::VectorXd KirchhoffPlate::nodal_dilatation(const ModelState& state) const {
  const auto& s = static_cast<const KirchhoffPlateState&>(state);
  Eigen::VectorXd out = Eigen::VectorXd::Zero(nodes_);
  for (Index c = 0; c < columns_.columns(); ++c) {
    const Real alpha = poisson_[c] / (1 - poisson_[c]);
    const Real trace = s.membrane_strain(0, c) + s.membrane_strain(1, c);
    out[columns_.node[columns_.first[c]]] = (1 - alpha) * trace;
  }
  return out;
}

bool KirchhoffPlate::node_strain(const ModelState& state, Index node, Mat3& strain) const {
  const auto& s = static_cast<const KirchhoffPlateState&>(state);
  const Index c = columns_.column_of[node];
  if (c < 0 || s.membrane_strain.cols() != columns_.columns()) return false;
  // the mid-surface strain (plane stress through the thickness; no transverse shear)
  const Vec3 e = s.membrane_strain.col(c);
  const Real alpha = poisson_[c] / (1 - poisson_[c]);
  strain << e[0], 0.5 * e[2], 0, 0.5 * e[2], e[1], 0, 0, 0, -alpha * (e[0] + e[1]);
  return true;
}

}  // namespace lamina::pd
