#include "pd/peridynamic_body.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include "core/error.hpp"
#include "material/linear_elastic.hpp"

namespace lamina::pd {

namespace {

/// Pseudo-inverse solve of a small symmetric positive semi-definite system (directions the
/// family cannot sense, e.g. z in a single layer, get no correction instead of a blow-up).
Eigen::VectorXd solve_gram(const Eigen::MatrixXd& a, const Eigen::VectorXd& b) {
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(a);
  const Eigen::VectorXd& values = eig.eigenvalues();
  const Real threshold = 1e-12 * std::max(values.cwiseAbs().maxCoeff(), 1e-300);
  Eigen::VectorXd coefficients = eig.eigenvectors().transpose() * b;
  for (Index k = 0; k < values.size(); ++k) coefficients[k] = values[k] > threshold ? coefficients[k] / values[k] : 0.0;
  return eig.eigenvectors() * coefficients;
}

/// Non-negative least squares min |W (G g - t)|^2, g >= 0, for a handful of unknowns: the best
/// feasible unconstrained minimiser over all supports (exact KKT enumeration; 2^k - 1 subsets).
Eigen::VectorXd nonnegative_fit(const Eigen::MatrixXd& g, const Eigen::VectorXd& target, const Eigen::VectorXd& weight) {
  const Index k = g.cols();
  const Eigen::MatrixXd wg = weight.asDiagonal() * g;
  const Eigen::VectorXd wt = weight.cwiseProduct(target);
  Eigen::VectorXd best = Eigen::VectorXd::Zero(k);
  Real best_cost = wt.squaredNorm();
  for (unsigned mask = 1; mask < (1u << k); ++mask) {
    std::vector<Index> support;
    for (Index c = 0; c < k; ++c)
      if (mask & (1u << c)) support.push_back(c);
    Eigen::MatrixXd a(wg.rows(), static_cast<Index>(support.size()));
    for (std::size_t c = 0; c < support.size(); ++c) a.col(static_cast<Index>(c)) = wg.col(support[c]);
    const Eigen::VectorXd x = solve_gram(a.transpose() * a, a.transpose() * wt);
    if ((x.array() < 0).any()) continue;
    Eigen::VectorXd full = Eigen::VectorXd::Zero(k);
    for (std::size_t c = 0; c < support.size(); ++c) full[support[c]] = x[static_cast<Index>(c)];
    const Real cost = (wg * full - wt).squaredNorm();
    if (cost < best_cost * (1 - 1e-12)) {
      best_cost = cost;
      best = full;
    }
  }
  return best;
}

/// Quartic monomials of a unit direction: n_a^4 (a < D), then n_a^2 n_b^2 (a < b).
template <int D>
Eigen::Matrix<Real, D*(D + 1) / 2, 1> quartic_monomials(const Vec3& n) {
  Eigen::Matrix<Real, D*(D + 1) / 2, 1> phi;
  int k = 0;
  for (int a = 0; a < D; ++a) phi[k++] = n[a] * n[a] * n[a] * n[a];
  for (int a = 0; a < D; ++a)
    for (int b = a + 1; b < D; ++b) phi[k++] = n[a] * n[a] * n[b] * n[b];
  return phi;
}

}  // namespace

PeridynamicBody::PeridynamicBody(PointMatrix positions, Eigen::VectorXd volumes, const Eigen::VectorXd& young,
                                 const Eigen::VectorXd& poisson, const BodyOptions& options)
    : positions_(std::move(positions)), volumes_(std::move(volumes)), options_(options) {
  if (!(options_.horizon > 0)) throw InputError("discretization.horizon", "a positive horizon", fmt::format("{}", options_.horizon));
  if (options_.cell_size <= 0) {
    const Real v = volumes_.size() ? volumes_.mean() : 1.0;
    options_.cell_size = dimension() == 3 ? std::cbrt(v) : std::sqrt(v);  // 2D: volume per unit... refined below
  }
  // lean storage serves the plain and energy-corrected lattices (the plate correction keeps fitted per-bond weights)
  if (options_.surface_correction == SurfaceCorrection::plate) options_.lean_bonds = false;
  build_families();
  calibrate(young, poisson);
}

void PeridynamicBody::build_families() {
  const Index n = nodes();
  const int dim = dimension();
  const Real reach = options_.partial_volume ? options_.horizon + 0.5 * options_.cell_size : options_.horizon;
  const Real cutoff = reach * (1.0 + 1e-10);
  // Cell list with bins of size `reach`.
  Vec3 lower = positions_.rowwise().minCoeff(), upper = positions_.rowwise().maxCoeff();
  std::array<Index, 3> bins{1, 1, 1};
  for (int d = 0; d < dim; ++d) bins[static_cast<std::size_t>(d)] = std::max<Index>(1, static_cast<Index>((upper[d] - lower[d]) / reach) + 1);
  auto bin_of = [&](const Vec3& p, int d) {
    return std::clamp<Index>(static_cast<Index>((p[d] - lower[d]) / reach), 0, bins[static_cast<std::size_t>(d)] - 1);
  };
  const Index bin_count = bins[0] * bins[1] * bins[2];
  std::vector<Index> bin_start(static_cast<std::size_t>(bin_count) + 1, 0), bin_nodes(static_cast<std::size_t>(n));
  std::vector<Index> node_bin(static_cast<std::size_t>(n));
  for (Index i = 0; i < n; ++i) {
    const Vec3 p = positions_.col(i);
    const Index b = bin_of(p, 0) + bins[0] * (bin_of(p, 1) + bins[1] * (dim == 3 ? bin_of(p, 2) : 0));
    node_bin[static_cast<std::size_t>(i)] = b;
    ++bin_start[static_cast<std::size_t>(b) + 1];
  }
  for (Index b = 0; b < bin_count; ++b) bin_start[static_cast<std::size_t>(b) + 1] += bin_start[static_cast<std::size_t>(b)];
  {
    std::vector<Index> fill(bin_start.begin(), bin_start.end() - 1);
    for (Index i = 0; i < n; ++i) bin_nodes[static_cast<std::size_t>(fill[static_cast<std::size_t>(node_bin[static_cast<std::size_t>(i)])]++)] = i;
  }
  std::vector<std::vector<std::int32_t>> families(static_cast<std::size_t>(n));
#pragma omp parallel for schedule(dynamic, 64)
  for (Index i = 0; i < n; ++i) {
    const Vec3 p = positions_.col(i);
    const Index bx = bin_of(p, 0), by = bin_of(p, 1), bz = dim == 3 ? bin_of(p, 2) : 0;
    auto& family = families[static_cast<std::size_t>(i)];
    for (Index z = std::max<Index>(bz - 1, 0); z <= std::min(bz + 1, bins[2] - 1); ++z)
      for (Index y = std::max<Index>(by - 1, 0); y <= std::min(by + 1, bins[1] - 1); ++y)
        for (Index x = std::max<Index>(bx - 1, 0); x <= std::min(bx + 1, bins[0] - 1); ++x) {
          const Index b = x + bins[0] * (y + bins[1] * z);
          for (Index k = bin_start[static_cast<std::size_t>(b)]; k < bin_start[static_cast<std::size_t>(b) + 1]; ++k) {
            const Index j = bin_nodes[static_cast<std::size_t>(k)];
            if (j == i) continue;
            Vec3 xi = positions_.col(j) - p;
            if (dim == 2) xi.z() = 0;
            if (xi.norm() <= cutoff) family.push_back(static_cast<std::int32_t>(j));
          }
        }
    std::sort(family.begin(), family.end());
  }
  family_start_.assign(static_cast<std::size_t>(n) + 1, 0);
  for (Index i = 0; i < n; ++i)
    family_start_[static_cast<std::size_t>(i) + 1] = family_start_[static_cast<std::size_t>(i)] + static_cast<Index>(families[static_cast<std::size_t>(i)].size());
  neighbour_.resize(static_cast<std::size_t>(family_start_.back()));
  if (lean()) {  // the neighbour index only
#pragma omp parallel for schedule(static)
    for (Index i = 0; i < n; ++i) {
      auto& family = families[static_cast<std::size_t>(i)];
      std::copy(family.begin(), family.end(), neighbour_.begin() + first_bond(i));
      std::vector<std::int32_t>().swap(family);
    }
  } else {
    reverse_.resize(neighbour_.size());
    length_.resize(static_cast<Index>(neighbour_.size()));
    bond_volume_.resize(length_.size());
    const Real h = options_.cell_size;
#pragma omp parallel for schedule(static)
    for (Index i = 0; i < n; ++i) {
      const auto& family = families[static_cast<std::size_t>(i)];
      for (std::size_t k = 0; k < family.size(); ++k) {
        const Index b = first_bond(i) + static_cast<Index>(k);
        const Index j = family[k];
        neighbour_[static_cast<std::size_t>(b)] = static_cast<std::int32_t>(j);
        Vec3 xi = positions_.col(j) - positions_.col(i);
        if (dim == 2) xi.z() = 0;
        const Real x = xi.norm();
        length_[b] = x;
        Real beta = 1.0;
        if (options_.partial_volume) beta = std::clamp((options_.horizon + 0.5 * h - x) / h, 0.0, 1.0);
        bond_volume_[b] = beta * volumes_[j];
        const auto& other = families[static_cast<std::size_t>(j)];
        const auto it = std::lower_bound(other.begin(), other.end(), static_cast<std::int32_t>(i));
        reverse_[static_cast<std::size_t>(b)] = static_cast<std::int32_t>(first_bond(j) + (it - other.begin()));
      }
    }
  }
  Real sum = 0, lo = INFINITY, hi = 0;
  for (Index i = 0; i < n; ++i) {
    const Real size = static_cast<Real>(end_bond(i) - first_bond(i));
    sum += size;
    lo = std::min(lo, size);
    hi = std::max(hi, size);
  }
  statistics_.mean_family = n ? sum / static_cast<Real>(n) : 0;
  statistics_.min_family = lo;
  statistics_.max_family = hi;
  for (Index i = 0; i < n; ++i)
    if (end_bond(i) == first_bond(i))
      throw InputError("discretization.horizon", "a horizon that gives every node at least one neighbour",
                       fmt::format("node {} at ({:g}, {:g}, {:g}) has none within {:g}", i, positions_(0, i), positions_(1, i),
                                   positions_(2, i), options_.horizon));
}

Eigen::MatrixXd PeridynamicBody::classical_stiffness(Index i) const {
  const Real e = young_[i], nu = poisson_[i];
  const material::LinearElastic elastic{e, nu};
  const Real mu = elastic.mu(), lambda = elastic.lambda();
  if (dimension() == 3) {
    Eigen::MatrixXd c = Eigen::MatrixXd::Zero(6, 6);
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) c(a, b) = lambda;
      c(a, a) = lambda + 2 * mu;
      c(a + 3, a + 3) = mu;
    }
    return c;
  }
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(3, 3);
  const bool stress = options_.kinematics == Kinematics::plane_stress;
  const Real c11 = stress ? elastic.plane_stress_modulus() : lambda + 2 * mu, c12 = stress ? elastic.plane_stress_coupling() : lambda;
  c << c11, c12, 0, c12, c11, 0, 0, 0, mu;
  return c;
}

namespace {

struct FamilyFit {
  Eigen::MatrixXd d;  // column a: d^a
  Eigen::MatrixXd q;  // dilatation coupling
  Eigen::VectorXd g;  // bond-modulus coefficients of the quartic monomials
};

/// Energy matching of one family (see the header): exact dilatations, non-negative bond moduli fitted
/// to the shear moduli, Q = C_normal - B_normal. Shear targets the family cannot reach without
/// making Q indefinite are given up step by step (their weight divided by 10).
FamilyFit fit_family(const Eigen::MatrixXd& moment, const Eigen::MatrixXd& gram, const Eigen::MatrixXd& c, Real mu, int dim) {
  const int monomials = dim * (dim + 1) / 2;
  FamilyFit fit;
  fit.d = Eigen::MatrixXd::Zero(dim, dim);
  for (int a = 0; a < dim; ++a) fit.d.col(a) = solve_gram(moment, Eigen::VectorXd::Unit(dim, a));
  Eigen::VectorXd target = Eigen::VectorXd::Zero(monomials), weight(monomials);
  for (int k = 0; k < monomials; ++k) {
    target[k] = k < dim ? 0.0 : mu;
    weight[k] = (k < dim ? 1e-3 : 1.0) / mu;
  }
  const Eigen::MatrixXd c_normal = c.topLeftCorner(dim, dim);
  for (int attempt = 0;; ++attempt) {
    fit.g = nonnegative_fit(gram, target, weight);
    const Eigen::VectorXd bsum = gram * fit.g;
    Eigen::MatrixXd b_normal(dim, dim);
    int k = dim;
    for (int a = 0; a < dim; ++a) b_normal(a, a) = bsum[a];
    for (int a = 0; a < dim; ++a)
      for (int b = a + 1; b < dim; ++b) b_normal(a, b) = b_normal(b, a) = bsum[k++];
    fit.q = c_normal - b_normal;
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(fit.q);
    const Real scale = c_normal.norm();
    if (eig.eigenvalues().minCoeff() >= -1e-9 * scale || attempt == 12) {
      fit.q = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() * eig.eigenvectors().transpose();
      return fit;
    }
    bool reduced = false;
    for (int kk = dim; kk < monomials; ++kk)
      if (std::abs(bsum[kk] - mu) > 0.01 * mu) {
        weight[kk] *= 0.1;
        reduced = true;
      }
    if (!reduced)
      for (int a = 0; a < dim; ++a) weight[a] *= 10.0;
  }
}

}  // namespace

void PeridynamicBody::calibrate(const Eigen::VectorXd& young, const Eigen::VectorXd& poisson) {
  young_ = young;
  poisson_ = poisson;
  if (options_.surface_correction == SurfaceCorrection::plate) {
    calibrate_plate();
    return;
  }
  const Index n = nodes();
  const int dim = dimension();
  const int monomials = dim * (dim + 1) / 2;
  const bool lean_storage = lean();
  if (lean_storage) {
    node_weight_.assign(static_cast<std::size_t>(n), Mat3::Zero());
    node_modulus_.assign(static_cast<std::size_t>(n), Vec6::Zero());
  } else {
    weight_ = Matrix6X::Zero(6, bonds());
    modulus_.resize(bonds());
  }
  coupling_.assign(static_cast<std::size_t>(n), Mat6::Zero());
  kappa_.resize(n);
  const bool energy = options_.surface_correction == SurfaceCorrection::energy;
  // the reference geometry of each bond, computed (the same values the full storage keeps)
  auto geometry = [&](Index i, Index b) { return bond_geometry(i, neighbour(b)); };
  auto phi = [&](const Vec3& nv) {
    // element by element: assigning the fixed-size result to a dynamic vector drew a false
    // -Warray-bounds (a 4-wide AVX load of 3 values on a path the size check excludes) from GCC 12
    Eigen::VectorXd p(monomials);
    if (dim == 3) {
      const auto q = quartic_monomials<3>(nv);
      for (int k = 0; k < q.size(); ++k) p[k] = q[k];
    } else {
      const auto q = quartic_monomials<2>(nv);
      for (int k = 0; k < q.size(); ++k) p[k] = q[k];
    }
    return p;
  };
  // Pass 1: moments of every family.
  std::vector<Eigen::MatrixXd> moments(static_cast<std::size_t>(n)), grams(static_cast<std::size_t>(n));
  Eigen::VectorXd weighted_volume(n);
#pragma omp parallel for schedule(static)
  for (Index i = 0; i < n; ++i) {
    Eigen::MatrixXd moment = Eigen::MatrixXd::Zero(dim, dim), gram = Eigen::MatrixXd::Zero(monomials, monomials);
    Real m = 0;
    for (Index b = first_bond(i); b < end_bond(i); ++b) {
      const BondGeometry g = geometry(i, b);
      const Vec3 nv = g.xi / g.length;
      const Real s = g.influence * g.length * g.length * g.volume;
      m += s;
      Eigen::VectorXd n2(dim);
      for (int a = 0; a < dim; ++a) n2[a] = nv[a] * nv[a];
      moment += s * n2 * n2.transpose();
      const Eigen::VectorXd p = phi(nv);
      gram += s * p * p.transpose();
    }
    moments[static_cast<std::size_t>(i)] = moment;
    grams[static_cast<std::size_t>(i)] = gram;
    weighted_volume[i] = m;
  }
  // Pass 2: families with equal moments and material share one fit (a lattice has few kinds).
  std::vector<Index> kind(static_cast<std::size_t>(n));
  std::vector<Index> representative;
  if (energy) {
    std::map<std::string, Index> kinds;
    for (Index i = 0; i < n; ++i) {
      std::string key = fmt::format("{:.10g} {:.10g}", young[i], poisson[i]);
      for (Index k = 0; k < moments[static_cast<std::size_t>(i)].size(); ++k)
        key += fmt::format(" {:.10g}", moments[static_cast<std::size_t>(i)].data()[k]);
      for (Index k = 0; k < grams[static_cast<std::size_t>(i)].size(); ++k)
        key += fmt::format(" {:.10g}", grams[static_cast<std::size_t>(i)].data()[k]);
      auto [it, inserted] = kinds.emplace(key, static_cast<Index>(representative.size()));
      if (inserted) representative.push_back(i);
      kind[static_cast<std::size_t>(i)] = it->second;
    }
  }
  std::vector<FamilyFit> fits(representative.size());
#pragma omp parallel for schedule(dynamic, 1)
  for (std::size_t k = 0; k < representative.size(); ++k) {
    const Index i = representative[k];
    fits[k] = fit_family(moments[static_cast<std::size_t>(i)], grams[static_cast<std::size_t>(i)], classical_stiffness(i),
                         material::LinearElastic{young[i], poisson[i]}.mu(), dim);
  }
  statistics_.family_kinds = static_cast<Real>(representative.size());
  // Pass 3: bond weights and moduli.
  Real max_dilatation_error = 0, modulus_sum = 0, modulus_min = INFINITY;
#pragma omp parallel for schedule(static) reduction(max : max_dilatation_error) reduction(+ : modulus_sum) reduction(min : modulus_min)
  for (Index i = 0; i < n; ++i) {
    const Eigen::MatrixXd c = classical_stiffness(i);
    const Real mu = material::LinearElastic{young[i], poisson[i]}.mu();
    kappa_[i] = c(0, 1) - mu;
    const Real m = weighted_volume[i];
    Eigen::MatrixXd d = Eigen::MatrixXd::Zero(dim, dim), q = Eigen::MatrixXd::Zero(dim, dim);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(monomials);
    if (energy) {
      const FamilyFit& fit = fits[static_cast<std::size_t>(kind[static_cast<std::size_t>(i)])];
      d = fit.d;
      q = fit.q;
      g = fit.g;
    } else {
      for (int a = 0; a < dim; ++a) d(a, 0) = static_cast<Real>(dim) / m;
      q(0, 0) = kappa_[i];
    }
    coupling_[static_cast<std::size_t>(i)].topLeftCorner(dim, dim) = q;
    const Real lps_modulus = (dim == 3 ? 15.0 : 8.0) * mu / m;
    if (lean_storage) {
      node_weight_[static_cast<std::size_t>(i)].topLeftCorner(dim, dim) = d;
      if (energy) node_modulus_[static_cast<std::size_t>(i)].head(monomials) = g;
      else node_modulus_[static_cast<std::size_t>(i)][0] = lps_modulus;
    }
    // the weights and modulus of bond b (stored, or computed from the per-node constants)
    auto bond_weight = [&](Index b, const BondGeometry& gb, const Vec3& nv) -> Vec3 {
      if (lean_storage) return lean_weight(i, nv, gb.length, gb.influence);
      return weight_.col(b).head<3>();
    };
    for (Index b = first_bond(i); b < end_bond(i); ++b) {
      const BondGeometry gb = geometry(i, b);
      const Vec3 nv = gb.xi / gb.length;
      const Real c = lean_storage ? lean_modulus(i, nv, gb.influence)
                                  : (energy ? gb.influence * g.dot(phi(nv)) : gb.influence * lps_modulus);
      if (!lean_storage) {
        Eigen::VectorXd n2(dim);
        for (int a = 0; a < dim; ++a) n2[a] = nv[a] * nv[a];
        for (int a = 0; a < dim; ++a) weight_(a, b) = gb.influence * gb.length * d.col(a).dot(n2);
        modulus_[b] = c;
      }
      modulus_sum += c;
      modulus_min = std::min(modulus_min, c);
    }
    for (int a = 0; a < dim; ++a) {
      Real theta = 0;
      for (Index b = first_bond(i); b < end_bond(i); ++b) {
        const BondGeometry gb = geometry(i, b);
        const Vec3 nv = gb.xi / gb.length;
        theta += bond_weight(b, gb, nv).sum() * gb.length * nv[a] * nv[a] * gb.volume;
      }
      max_dilatation_error = std::max(max_dilatation_error, std::abs(theta - 1.0));
    }
  }
  statistics_.max_dilatation_error = max_dilatation_error;
  if (lean_storage) {
    const Real mean = bonds() ? modulus_sum / static_cast<Real>(bonds()) : 1.0;
    statistics_.min_bond_modulus_ratio = bonds() ? modulus_min / mean : 1.0;
  } else {
    const Real mean = modulus_.size() ? modulus_.mean() : 1.0;
    statistics_.min_bond_modulus_ratio = modulus_.size() ? modulus_.minCoeff() / mean : 1.0;
  }
}

Real PeridynamicBody::lean_modulus(Index i, const Vec3& n, Real omega) const {
  const Vec6& g = node_modulus_[static_cast<std::size_t>(i)];
  if (options_.surface_correction != SurfaceCorrection::energy) return omega * g[0];
  if (dimension() == 3) return omega * g.dot(quartic_monomials<3>(n));
  const auto q = quartic_monomials<2>(n);
  return omega * (g[0] * q[0] + g[1] * q[1] + g[2] * q[2]);
}

namespace {

/// Tensor-Voigt quadratic monomials of a bond direction: n^T eps n = phi2(n) . (xx, yy, zz, yz, xz, xy).
Vec6 quadratic_monomials(const Vec3& n) {
  Vec6 p;
  p << n.x() * n.x(), n.y() * n.y(), n.z() * n.z(), 2 * n.y() * n.z(), 2 * n.x() * n.z(), 2 * n.x() * n.y();
  return p;
}

constexpr Real kPlateInPlaneFraction = 0.5;  // share of the in-plane shear modulus on same-layer bonds
constexpr Real kPlateThicknessFraction = 0.5;  // share of E (eps_zz) on the vertical bonds
constexpr Real kPlateCrossFraction = 0.1;  // share of the in-plane normal modulus on all cross-layer bonds

struct PlateFit {
  Eigen::MatrixXd w;   // bonds x 6: dilatation weights
  Eigen::VectorXd c;   // bond moduli
  Mat6 q;              // dilatation coupling
  Real exactness_error = 0, gradient_residual = 0;
};

/// surface_correction: plate for one family (bond vectors xi, bond volumes beta V, influence omega).
/// Weights w = sqrt(s) v with s = omega |xi|^2 beta V: v = the minimum-norm solution of the six
/// exactness conditions sum_b w_b |xi| beta V phi2(n) = e_a plus the null-space correction that
/// minimises the response to the 18 linear strain gradients, sum_b w_b |xi| beta V phi2(n) xi_k / 2.
PlateFit fit_plate_family(const std::vector<Vec3>& xi, const std::vector<Real>& volume, const std::vector<Real>& omega,
                          Real e, Real nu, Real delta) {
  const Index m = static_cast<Index>(xi.size());
  const Real mu = material::LinearElastic{e, nu}.mu();
  Eigen::MatrixXd exact(6, m), gradient(54, m);
  Eigen::VectorXd root(m), s(m);
  std::vector<Vec6> phi(static_cast<std::size_t>(m));
  for (Index b = 0; b < m; ++b) {
    const Real length = xi[static_cast<std::size_t>(b)].norm();
    const Vec3 n = xi[static_cast<std::size_t>(b)] / length;
    const Vec6 p = quadratic_monomials(n);
    phi[static_cast<std::size_t>(b)] = p;
    s[b] = omega[static_cast<std::size_t>(b)] * length * length * volume[static_cast<std::size_t>(b)];
    root[b] = std::sqrt(s[b]);
    const Vec6 column = length * volume[static_cast<std::size_t>(b)] * root[b] * p;
    exact.col(b) = column;
    const Vec3& x = xi[static_cast<std::size_t>(b)];
    for (int k = 0; k < 3; ++k) gradient.col(b).segment<6>(6 * k) = column * (0.5 * x[k] / delta);
    // second strain gradients: e / |xi| = n^T (eps + xi.grad eps / 2 + xi xi : grad grad eps / 6) n; the
    // mixed ones (d/dz d/dx of the bending strain z kappa(x)) would otherwise read as transverse shear
    int row = 18;
    for (int k = 0; k < 3; ++k)
      for (int l = k; l < 3; ++l, row += 6) gradient.col(b).segment<6>(row) = column * (x[k] * x[l] / (6 * delta * delta));
  }
  PlateFit fit;
  fit.w = Eigen::MatrixXd::Zero(m, 6);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(exact, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::VectorXd& sigma = svd.singularValues();
  Index rank = 0;
  while (rank < sigma.size() && sigma[rank] > 1e-10 * sigma[0]) ++rank;
  const Eigen::MatrixXd null = svd.matrixV().rightCols(m - rank);
  const Eigen::MatrixXd gn = gradient * null;
  Eigen::MatrixXd h = gn.transpose() * gn;
  const Real regular = 1e-10 * (h.trace() / std::max<Index>(h.rows(), 1) + 1e-300);
  h.diagonal().array() += regular;
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(h);
  for (int a = 0; a < 6; ++a) {
    const Eigen::VectorXd ua = svd.matrixU().transpose().col(a);
    Eigen::VectorXd v0 = Eigen::VectorXd::Zero(m);
    for (Index r = 0; r < rank; ++r) v0 += svd.matrixV().col(r) * (ua[r] / sigma[r]);
    Eigen::VectorXd v = v0;
    if (null.cols() > 0) v -= null * ldlt.solve(gn.transpose() * (gradient * v0));
    fit.w.col(a) = root.cwiseProduct(v);
    fit.gradient_residual = std::max(fit.gradient_residual, (gradient * v).cwiseAbs().maxCoeff());
  }
  // exactness check (components the family cannot sense, rank < 6, stay zero)
  {
    Eigen::MatrixXd response = exact * root.cwiseInverse().asDiagonal() * fit.w;  // 6 x 6: theta_a of unit strain c
    for (Index r = 0; r < 6; ++r) {
      const Real target = rank == 6 ? 1.0 : response(r, r) > 0.5 ? 1.0 : 0.0;
      response(r, r) -= target;
    }
    fit.exactness_error = response.cwiseAbs().maxCoeff();
  }
  const material::LinearElastic elastic{e, nu};
  const Real c11 = elastic.plane_stress_modulus(), c12 = elastic.plane_stress_coupling();
  // Bond moduli: same-layer bonds isotropic (half the in-plane shear); the vertical bonds half of E for
  // eps_zz (n_z^4 over all cross-layer bonds if the family has no vertical bond); every cross-layer bond a
  // small isotropic part (kPlateCrossFraction). The dilatation coupling completes the plane-stress law.
  // Cross-layer bonds see the strain at their mid-height in bending, not at the node's, so their
  // in-plane share is what the bending stiffness of a two-layer lattice lacks (about that fraction).
  Real same_shear = 0, same_normal = 0, cross_normal = 0, vertical_normal = 0, cross_in_plane = 0;
  std::vector<bool> same(static_cast<std::size_t>(m));
  for (Index b = 0; b < m; ++b) {
    const Vec6& p = phi[static_cast<std::size_t>(b)];
    same[static_cast<std::size_t>(b)] = std::abs(p[2]) <= 1e-18;
    if (same[static_cast<std::size_t>(b)]) {
      same_shear += s[b] * p[5] * p[5];
      same_normal += s[b] * p[0] * p[0];
    } else {
      cross_normal += s[b] * std::pow(p[2], 4);
      cross_in_plane += s[b] * (p[0] * p[0] + p[1] * p[1]) / 2;
      if (p[2] >= 1 - 1e-12) vertical_normal += s[b];
    }
  }
  const bool vertical_only = vertical_normal > 0;
  if (vertical_only) cross_normal = vertical_normal;
  const Real in_plane = same_shear > 0   ? kPlateInPlaneFraction * 4 * mu / same_shear
                        : same_normal > 0 ? kPlateInPlaneFraction * c11 / same_normal
                                          : 0.0;
  const Real thickness = cross_normal > 0 ? kPlateThicknessFraction * e / cross_normal : 0.0;
  // all cross-layer bonds: 10 % of the in-plane normal modulus, against the zig-zag w mode (w alternating
  // from node to node, the same on every layer) that no same-layer bond and no strain estimate sees
  const Real cross = cross_in_plane > 0 ? kPlateCrossFraction * c11 / cross_in_plane : 0.0;
  fit.c.resize(m);
  Mat6 bond = Mat6::Zero();
  for (Index b = 0; b < m; ++b) {
    const Vec6& p = phi[static_cast<std::size_t>(b)];
    const Real thickness_part = (vertical_only ? (p[2] >= 1 - 1e-12 ? thickness : 0.0) : thickness * p[2] * p[2]) + cross;
    const Real c = omega[static_cast<std::size_t>(b)] * (same[static_cast<std::size_t>(b)] ? in_plane : thickness_part);
    fit.c[b] = c;
    bond += (c * s[b] / omega[static_cast<std::size_t>(b)]) * p * p.transpose();
  }
  Mat6 target = Mat6::Zero();
  target(0, 0) = target(1, 1) = c11;
  target(0, 1) = target(1, 0) = c12;
  target(2, 2) = e;
  for (int k = 3; k < 6; ++k) target(k, k) = 4 * mu;
  const Eigen::SelfAdjointEigenSolver<Mat6> eig(Mat6(target - bond));
  fit.q = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() * eig.eigenvectors().transpose();
  return fit;
}

}  // namespace

void PeridynamicBody::calibrate_plate() {
  if (dimension() != 3)
    throw InputError("pd.surface_correction", "plate with kinematics: three_dimensional (a plate lattice)", "plane kinematics");
  const Index n = nodes();
  weight_ = Matrix6X::Zero(6, bonds());
  coupling_.assign(static_cast<std::size_t>(n), Mat6::Zero());
  modulus_.resize(bonds());
  kappa_.resize(n);
  const Real delta = options_.horizon;
  const Real volume_scale = volumes_.size() ? volumes_.cwiseAbs().maxCoeff() : 1.0;
  auto omega = [&](Index b) { return options_.influence == Influence::one ? 1.0 : delta / length_[b]; };
  // Families with the same bond sequence (offsets, volumes) and material share one fit.
  std::map<std::vector<std::int64_t>, Index> kinds;
  std::vector<Index> kind(static_cast<std::size_t>(n)), representative;
  for (Index i = 0; i < n; ++i) {
    std::vector<std::int64_t> key{std::llround(young_[i] * 1e6), std::llround(poisson_[i] * 1e12)};
    key.reserve(static_cast<std::size_t>(4 * (end_bond(i) - first_bond(i)) + 2));
    for (Index b = first_bond(i); b < end_bond(i); ++b) {
      const Vec3 xi = positions_.col(neighbour(b)) - positions_.col(i);
      for (int d = 0; d < 3; ++d) key.push_back(std::llround(xi[d] / delta * 1e9));
      key.push_back(std::llround(bond_volume_[b] / volume_scale * 1e9));
    }
    auto [it, inserted] = kinds.emplace(std::move(key), static_cast<Index>(representative.size()));
    if (inserted) representative.push_back(i);
    kind[static_cast<std::size_t>(i)] = it->second;
  }
  std::vector<PlateFit> fits(representative.size());
#pragma omp parallel for schedule(dynamic, 1)
  for (std::size_t k = 0; k < representative.size(); ++k) {
    const Index i = representative[k];
    std::vector<Vec3> xi;
    std::vector<Real> volume, influence;
    for (Index b = first_bond(i); b < end_bond(i); ++b) {
      xi.push_back(positions_.col(neighbour(b)) - positions_.col(i));
      volume.push_back(bond_volume_[b]);
      influence.push_back(omega(b));
    }
    fits[k] = fit_plate_family(xi, volume, influence, young_[i], poisson_[i], delta);
  }
  statistics_.family_kinds = static_cast<Real>(representative.size());
  Real exactness = 0, residual = 0;
  for (const PlateFit& fit : fits) {
    exactness = std::max(exactness, fit.exactness_error);
    residual = std::max(residual, fit.gradient_residual);
  }
  statistics_.max_dilatation_error = exactness;
  statistics_.max_gradient_residual = residual;
#pragma omp parallel for schedule(static)
  for (Index i = 0; i < n; ++i) {
    const PlateFit& fit = fits[static_cast<std::size_t>(kind[static_cast<std::size_t>(i)])];
    const Real mu = material::LinearElastic{young_[i], poisson_[i]}.mu();
    kappa_[i] = classical_stiffness(i)(0, 1) - mu;
    coupling_[static_cast<std::size_t>(i)] = fit.q;
    for (Index b = first_bond(i); b < end_bond(i); ++b) {
      const Index k = b - first_bond(i);
      weight_.col(b) = fit.w.row(k).transpose();
      modulus_[b] = fit.c[k];
    }
  }
  const Real mean = modulus_.size() ? modulus_.mean() : 1.0;
  statistics_.min_bond_modulus_ratio = modulus_.size() ? modulus_.minCoeff() / mean : 1.0;
}

}  // namespace lamina::pd
