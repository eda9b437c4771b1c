#include "pd/lean_peridynamic_solid.hpp"

#include "core/error.hpp"

namespace lamina::pd {

LeanPeridynamicSolid::LeanPeridynamicSolid(const PeridynamicBody& body) : body_(body) {
  components_ = body.options().surface_correction == SurfaceCorrection::none ? 1 : 3;
}

void LeanPeridynamicSolid::update(const PointMatrix& u, ModelState& state, bool linearised) const {
  auto& s = static_cast<LeanState&>(state);
  const Index n = body_.nodes();
  s.u = u;
  s.linearised = linearised;
  if (s.dilatation.cols() != n) {
    s.dilatation = Eigen::Matrix3Xd::Zero(3, n);
    s.dilatation_force = Eigen::Matrix3Xd::Zero(3, n);
  }
  if (s.bond_energy.size() != n) s.bond_energy = Eigen::VectorXd::Zero(n);
  if (components_ == 1) update_kernel<1>(s);
  else update_kernel<3>(s);
  body_.exchange_halo(s.dilatation_force.data(), 3);  // several ranks: the halo's Q theta from its owners
}

namespace {

/// A bond i -> j in a configuration: its reference geometry and direction n, extension e and deformed
/// direction M (exact, or linearised about the reference).
struct BondKinematics {
  PeridynamicBody::BondGeometry g;
  Vec3 n;
  Real e;
  Vec3 m;
};

inline BondKinematics bond_kinematics(const PeridynamicBody& body, const PointMatrix& u, Index i, Index j, bool planar,
                                      bool linearised) {
  BondKinematics k;
  k.g = body.bond_geometry(i, j);
  Vec3 du = u.col(j) - u.col(i);
  if (planar) du.z() = 0;
  k.n = k.g.xi / k.g.length;
  if (linearised) {
    k.m = k.n;
    k.e = k.m.dot(du);
  } else {
    const Vec3 y = k.g.xi + du;
    const Real length = y.norm();
    k.m = y / length;
    k.e = length - k.g.length;
  }
  return k;
}

}  // namespace

template <int K>
void LeanPeridynamicSolid::update_kernel(LeanState& s) const {
  using VecK = Eigen::Matrix<Real, K, 1>;
  const PeridynamicBody& body = body_;
  const bool planar = body.dimension() == 2;
#pragma omp parallel for schedule(static)
  for (Index i = 0; i < body.nodes(); ++i) {
    if (!body.computes_state(i)) continue;
    VecK theta = VecK::Zero();
    Real energy = 0;
    for (Index b = body.first_bond(i); b < body.end_bond(i); ++b) {
      const BondKinematics k = bond_kinematics(body, s.u, i, body.neighbour(b), planar, s.linearised);
      const auto& g = k.g;
      const Vec3& n = k.n;
      const Real e = k.e;
      if constexpr (K == 1) theta[0] += body.lean_weight_first(i, n, g.length, g.influence) * (e * g.volume);
      else theta += body.lean_weight(i, n, g.length, g.influence) * (e * g.volume);
      energy += body.lean_modulus(i, n, g.influence) * e * e * g.volume;
    }
    const VecK force = body.dilatation_coupling(i).template topLeftCorner<K, K>() * theta;
    s.dilatation.col(i).template head<K>() = theta;
    s.dilatation_force.col(i).template head<K>() = force;
    s.bond_energy[i] = energy;
  }
}

PointMatrix LeanPeridynamicSolid::internal_force(const ModelState& state) const {
  const auto& s = static_cast<const LeanState&>(state);
  PointMatrix f(3, body_.nodes());
  if (components_ == 1) force_kernel<1>(s, f);
  else force_kernel<3>(s, f);
  return f;
}

template <int K>
void LeanPeridynamicSolid::force_kernel(const LeanState& s, PointMatrix& f) const {
  using VecK = Eigen::Matrix<Real, K, 1>;
  const PeridynamicBody& body = body_;
  const bool planar = body.dimension() == 2;
#pragma omp parallel for schedule(static)
  for (Index i = 0; i < body.nodes(); ++i) {
    if (!body.owns(i)) {
      f.col(i).setZero();
      continue;
    }
    const VecK force_i = s.dilatation_force.col(i).template head<K>();
    Vec3 sum = Vec3::Zero();
    for (Index b = body.first_bond(i); b < body.end_bond(i); ++b) {
      const Index j = body.neighbour(b);
      const BondKinematics k = bond_kinematics(body, s.u, i, j, planar, s.linearised);
      const auto& g = k.g;
      const Vec3& n = k.n;
      const Real e = k.e;
      // both ends of the bond: the weights and modulus are even in the direction (n^2, n^4 monomials)
      Real tij, tji;
      if constexpr (K == 1) {
        tij = force_i[0] * body.lean_weight_first(i, n, g.length, g.influence) + body.lean_modulus(i, n, g.influence) * e;
        tji = s.dilatation_force(0, j) * body.lean_weight_first(j, n, g.length, g.influence) + body.lean_modulus(j, n, g.influence) * e;
      } else {
        tij = force_i.dot(body.lean_weight(i, n, g.length, g.influence)) + body.lean_modulus(i, n, g.influence) * e;
        tji = s.dilatation_force.col(j).dot(body.lean_weight(j, n, g.length, g.influence)) + body.lean_modulus(j, n, g.influence) * e;
      }
      sum += (body.volumes()[i] * g.volume * (tij + tji)) * k.m;
    }
    f.col(i) = sum;
  }
}

Real LeanPeridynamicSolid::strain_energy(const ModelState& state) const {
  const auto& s = static_cast<const LeanState&>(state);
  Real total = 0;
  for (Index i = 0; i < body_.nodes(); ++i)
    if (body_.owns(i))
      total += body_.volumes()[i] *
             (0.5 * s.dilatation.col(i).dot(s.dilatation_force.col(i)) + 0.5 * s.bond_energy[i]);
  return total;
}

solve::SparseMatrix LeanPeridynamicSolid::stiffness(const ModelState&, bool, bool) const {
  throw AnalysisError(
      "pd: the lean bond storage (pd.bond_storage: lean) keeps no stiffness; it serves explicit dynamics with a "
      "given pd.explicit.time_step");
}

Eigen::VectorXd LeanPeridynamicSolid::nodal_dilatation(const ModelState& state) const {
  return static_cast<const LeanState&>(state).dilatation.colwise().sum().transpose();
}

}  // namespace lamina::pd
