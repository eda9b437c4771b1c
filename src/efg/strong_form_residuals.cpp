#include "efg/strong_form_residuals.hpp"

#include <Eigen/Eigenvalues>
#include <fmt/format.h>

#include "core/error.hpp"
#include "efg/essential_boundary.hpp"

namespace lamina::efg {

namespace {

// Voigt order of ddphi: xx yy zz xy yz zx
constexpr int kHessianIndex[3][3] = {{0, 3, 5}, {3, 1, 4}, {5, 4, 2}};

void require_second_derivatives(const mls::ShapeFunctionValues& sv) {
  if (sv.ddphi.cols() != static_cast<Index>(sv.neighbours.size()))
    throw std::logic_error("strong-form residuals need shape functions with second derivatives");
}

struct RowBuilder {
  PointResiduals out;
  std::vector<Eigen::VectorXd> rows;
  std::vector<Real> rhs;
  void add(const Eigen::VectorXd& row, Real value, ResidualKind kind) {
    rows.push_back(row);
    rhs.push_back(value);
    out.kinds.push_back(kind);
  }
  PointResiduals finish(const mls::ShapeFunctionValues& sv) {
    const Index m = static_cast<Index>(sv.neighbours.size());
    out.neighbours = sv.neighbours;
    out.rows.resize(static_cast<Index>(rows.size()), 3 * m);
    out.rhs.resize(static_cast<Index>(rows.size()));
    for (std::size_t r = 0; r < rows.size(); ++r) {
      out.rows.row(static_cast<Index>(r)) = rows[r].transpose();
      out.rhs[static_cast<Index>(r)] = rhs[r];
    }
    return std::move(out);
  }
};

Eigen::VectorXd displacement_row(const mls::ShapeFunctionValues& sv, int component) {
  const Index m = static_cast<Index>(sv.neighbours.size());
  Eigen::VectorXd row = Eigen::VectorXd::Zero(3 * m);
  for (Index k = 0; k < m; ++k) row[3 * k + component] = sv.phi[k];
  return row;
}

}  // namespace

Eigen::Matrix<Real, 3, Eigen::Dynamic> navier_operator(const mls::ShapeFunctionValues& sv,
                                                       const material::LinearElastic& material) {
  require_second_derivatives(sv);
  const Index m = static_cast<Index>(sv.neighbours.size());
  const Real lambda = material.lambda(), mu = material.mu();
  Eigen::Matrix<Real, 3, Eigen::Dynamic> N(3, 3 * m);
  for (Index k = 0; k < m; ++k) {
    const auto h = sv.ddphi.col(k);
    const Real laplacian = h[0] + h[1] + h[2];
    for (int i = 0; i < 3; ++i)
      for (int b = 0; b < 3; ++b)
        N(i, 3 * k + b) = (i == b ? mu * laplacian : 0.0) + (lambda + mu) * h[kHessianIndex[i][b]];
  }
  return N;
}

std::pair<Vec3, Vec3> collocation_boundary_condition(const StrongFormPoint& p) {
  Vec3 n = Vec3::Zero(), t = Vec3::Zero();
  for (std::size_t f = 0; f < p.face_normals.size(); ++f) {
    n += p.face_normals[f];
    t += p.face_tractions[f];
  }
  const Real length = n.norm();
  if (!(length > 1e-6))
    throw AnalysisError(fmt::format(
        "collocation: the boundary faces at the node ({:.6g}, {:.6g}, {:.6g}) have opposite normals (a body one "
        "node thick); use at least two nodes through every direction, or formulation: galerkin",
        p.x[0], p.x[1], p.x[2]));
  return {n / length, t / length};
}

PointResiduals collocation_residuals(const StrongFormPoint& p, const mls::ShapeFunctionValues& sv,
                                     const material::LinearElastic& material) {
  require_second_derivatives(sv);
  RowBuilder rows;
  Eigen::Matrix<Real, 3, Eigen::Dynamic> traction, navier;
  Vec3 t_bar = Vec3::Zero();
  const bool free_components = !(p.constrained[0] && p.constrained[1] && p.constrained[2]);
  if (free_components) {
    if (p.on_boundary()) {
      const auto [n_bar, t] = collocation_boundary_condition(p);
      traction = traction_operator(sv, material, n_bar);
      t_bar = t;
    } else {
      navier = navier_operator(sv, material);
    }
  }
  for (int i = 0; i < 3; ++i) {
    if (p.constrained[static_cast<std::size_t>(i)])
      rows.add(displacement_row(sv, i), p.value[i], ResidualKind::displacement);
    else if (p.on_boundary())
      rows.add(traction.row(i).transpose(), t_bar[i], ResidualKind::traction);
    else
      rows.add(navier.row(i).transpose(), -p.body_force[i], ResidualKind::equilibrium);
  }
  return rows.finish(sv);
}

PointResiduals least_squares_residuals(const StrongFormPoint& p, const mls::ShapeFunctionValues& sv,
                                       const material::LinearElastic& material) {
  require_second_derivatives(sv);
  RowBuilder rows;
  const auto navier = navier_operator(sv, material);
  for (int i = 0; i < 3; ++i) rows.add(navier.row(i).transpose(), -p.body_force[i], ResidualKind::equilibrium);
  for (std::size_t f = 0; f < p.face_normals.size(); ++f) {
    const auto traction = traction_operator(sv, material, p.face_normals[f]);
    for (int i = 0; i < 3; ++i)
      if (!p.constrained[static_cast<std::size_t>(i)])
        rows.add(traction.row(i).transpose(), p.face_tractions[f][i], ResidualKind::traction);
  }
  for (int i = 0; i < 3; ++i)
    if (p.constrained[static_cast<std::size_t>(i)])
      rows.add(displacement_row(sv, i), p.value[i], ResidualKind::displacement);
  return rows.finish(sv);
}

void require_no_free_rigid_body_motion(const std::vector<StrongFormPoint>& points) {
  if (points.empty()) return;
  Vec3 centre = Vec3::Zero(), lower = points.front().x, upper = points.front().x;
  for (const auto& p : points) {
    centre += p.x;
    lower = lower.cwiseMin(p.x);
    upper = upper.cwiseMax(p.x);
  }
  centre /= static_cast<Real>(points.size());
  const Real size = std::max((upper - lower).norm(), 1e-300);
  Eigen::Matrix<Real, 6, 6> gram = Eigen::Matrix<Real, 6, 6>::Zero();
  for (const auto& p : points) {
    const Vec3 r = (p.x - centre) / size;
    Eigen::Matrix<Real, 3, 6> modes;  // columns: translations x y z, rotations about x y z
    modes.leftCols<3>().setIdentity();
    for (int k = 0; k < 3; ++k) modes.col(3 + k) = Vec3::Unit(k).cross(r);
    for (int i = 0; i < 3; ++i)
      if (p.constrained[static_cast<std::size_t>(i)]) gram += modes.row(i).transpose() * modes.row(i);
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<Real, 6, 6>> eigen(gram);
  const Real largest = eigen.eigenvalues().maxCoeff();
  if (!(largest > 0) || eigen.eigenvalues().minCoeff() < 1e-10 * largest) {
    const Eigen::Matrix<Real, 6, 1> mode = eigen.eigenvectors().col(0);
    throw AnalysisError(fmt::format(
        "the essential conditions leave a rigid-body motion free (translation ({:.2g}, {:.2g}, {:.2g}), rotation "
        "({:.2g}, {:.2g}, {:.2g})): the strong-form system is singular; constrain more displacement components "
        "(e.g. fix a face, or add symmetry conditions on three planes)",
        mode[0], mode[1], mode[2], mode[3], mode[4], mode[5]));
  }
}

}  // namespace lamina::efg
