// Unit tests of the pd core: lattice, families, calibration, internal force vs stiffness.
#include <gtest/gtest.h>

#include <random>

#include "core/gauss_legendre.hpp"
#include "geometry/cell_lattice.hpp"
#include "pd/linear_peridynamic_solid.hpp"

using namespace lamina;
using namespace lamina::pd;
using lamina::geometry::lattice_point_cloud;
using lamina::geometry::make_cell_lattice;
using lamina::geometry::CellLattice;

namespace {

struct Fixture {
  PointCloud cloud;
  std::unique_ptr<PeridynamicBody> body;
  std::unique_ptr<LinearPeridynamicSolid> solid;
  Fixture(const Vec3& lower, const Vec3& upper, const Vec3& spacing, Real horizon, BodyOptions options = {}) {
    cloud = lattice_point_cloud(make_cell_lattice(lower, upper, spacing), false);
    options.horizon = horizon;
    if (options.cell_size <= 0)
      options.cell_size = options.kinematics == Kinematics::three_dimensional ? std::cbrt(spacing.prod())
                                                                              : std::sqrt(spacing.x() * spacing.y());
    const Index n = cloud.size();
    body = std::make_unique<PeridynamicBody>(cloud.positions, cloud.volumes, Eigen::VectorXd::Constant(n, 1000.0),
                                             Eigen::VectorXd::Constant(n, 0.3), options);
    solid = std::make_unique<LinearPeridynamicSolid>(*body);
  }
};

Eigen::MatrixXd dense(const solve::SparseMatrix& upper) {
  Eigen::MatrixXd k = Eigen::MatrixXd(upper);
  return Eigen::MatrixXd(k.selfadjointView<Eigen::Upper>());
}

/// Eigenvalues of Lambda^-1/2 K0 Lambda^-1/2 with the ADR density lambda = 1/4 sum_j |K0_ij|
/// (dt = 1 is stable when the largest is at most 4).
Eigen::VectorXd density_scaled_eigenvalues(const solve::SparseMatrix& k0) {
  const Eigen::VectorXd s = (0.25 * LinearPeridynamicSolid::absolute_row_sums(k0)).cwiseInverse().cwiseSqrt();
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(s.asDiagonal() * dense(k0) * s.asDiagonal()).eigenvalues();
}

}  // namespace

TEST(PdLattice, CellCentresAndSets) {
  const CellLattice lattice = make_cell_lattice(Vec3(0, 0, -1), Vec3(300, 200, 1), Vec3(10, 10, 1));
  const PointCloud cloud = lattice_point_cloud(lattice, true);
  EXPECT_EQ(cloud.size(), 30 * 20 * 2);
  EXPECT_NEAR(cloud.volumes.sum(), 300.0 * 200.0 * 2.0, 1e-6);
  EXPECT_NEAR(cloud.positions.row(2).minCoeff(), -0.5, 1e-12);
  EXPECT_EQ(cloud.sets.at("xmax").size(), 40u);
}

TEST(PdBody, NeighbourCountsOnCubicLattice) {
  BodyOptions options;
  options.partial_volume = false;
  Fixture f(Vec3::Zero(), Vec3(9, 9, 9), Vec3(1, 1, 1), 3.0 * (1 + 1e-9), options);
  const Index centre = 4 + 9 * (4 + 9 * 4);
  EXPECT_EQ(f.body->end_bond(centre) - f.body->first_bond(centre), 122);  // notes section 1.4
  for (Index b = 0; b < f.body->bonds(); ++b) EXPECT_EQ(f.body->reverse(f.body->reverse(b)), b);
}

TEST(PdBody, DilatationExactForNormalStrainsWithEnergyCorrection) {
  Fixture f(Vec3::Zero(), Vec3(6, 5, 4), Vec3(1, 1, 1), 3.015);
  EXPECT_LT(f.body->statistics().max_dilatation_error, 1e-10);
}

// Internal force is -dPi/dU and the stiffness matrix its negative derivative: central differences.
TEST(PdSolid, StiffnessMatchesFiniteDifferencesOfInternalForce) {
  for (Kinematics kin : {Kinematics::three_dimensional, Kinematics::plane_stress}) {
    BodyOptions options;
    options.kinematics = kin;
    const bool planar = kin != Kinematics::three_dimensional;
    Fixture f(Vec3::Zero(), Vec3(5, 4, planar ? 1 : 3), Vec3(1, 1, 1), 2.015, options);
    const Index n = f.body->nodes();
    std::mt19937 gen(7);
    std::uniform_real_distribution<Real> uniform(-0.05, 0.05);
    PointMatrix u(3, n);
    for (Index k = 0; k < u.size(); ++k) u.data()[k] = uniform(gen);
    if (planar) u.row(2).setZero();
    const Eigen::MatrixXd k = dense(f.solid->stiffness(f.solid->bond_state(u)));
    const Real h = 1e-6;
    Real worst = 0;
    for (Index d = 0; d < 3 * n; ++d) {
      if (planar && d % 3 == 2) continue;
      PointMatrix up = u, um = u;
      up.data()[d] += h;
      um.data()[d] -= h;
      const PointMatrix df = (f.solid->internal_force(up) - f.solid->internal_force(um)) / (2 * h);
      const Eigen::Map<const Eigen::VectorXd> column(df.data(), 3 * n);
      for (Index r = 0; r < 3 * n; ++r) {
        if (planar && r % 3 == 2) continue;
        worst = std::max(worst, std::abs(-column[r] - k(r, d)));
      }
    }
    EXPECT_LT(worst, 1e-6 * k.cwiseAbs().maxCoeff()) << "kinematics " << static_cast<int>(kin);
  }
}

// Linear static stiffness = linearised internal force; Gershgorin ADR density bounds the spectrum.
TEST(PdSolid, LinearisedForceEqualsStiffnessTimesDisplacement) {
  Fixture f(Vec3::Zero(), Vec3(5, 4, 3), Vec3(1, 1, 1), 2.015);
  const Index n = f.body->nodes();
  std::mt19937 gen(3);
  std::uniform_real_distribution<Real> uniform(-1, 1);
  PointMatrix u(3, n);
  for (Index k = 0; k < u.size(); ++k) u.data()[k] = uniform(gen);
  const PointMatrix zero = PointMatrix::Zero(3, n);
  const solve::SparseMatrix k0 = f.solid->stiffness(f.solid->bond_state(zero, true), true, false);
  const PointMatrix fl = f.solid->internal_force(f.solid->bond_state(u, true));
  const Eigen::VectorXd ku = solve::multiply_symmetric_upper(k0, Eigen::Map<const Eigen::VectorXd>(u.data(), u.size()));
  EXPECT_LT((Eigen::Map<const Eigen::VectorXd>(fl.data(), fl.size()) + ku).norm(), 1e-10 * ku.norm());
  // Largest eigenvalue of Lambda^-1 K0 with lambda = 1/4 sum |K| is at most 4 (dt = 1 stable).
  const Eigen::VectorXd eigenvalues = density_scaled_eigenvalues(k0);
  EXPECT_LE(eigenvalues.maxCoeff(), 4.0 + 1e-9);
  EXPECT_GT(eigenvalues.minCoeff(), -1e-9);  // positive semi-definite (six rigid modes)
}

// The seed's plate lattice (10 x 10 x 1 cells, two layers, horizon = cell diagonal): the corrected
// stiffness is positive semi-definite and the ADR density bounds it.
TEST(PdSolid, PlateLatticeStiffnessBoundedByFictitiousDensity) {
  Fixture f(Vec3(0, 0, -1), Vec3(60, 40, 1), Vec3(10, 10, 1), 14.2);
  const Index n = f.body->nodes();
  const solve::SparseMatrix k0 = f.solid->stiffness(f.solid->bond_state(PointMatrix::Zero(3, n), true), true, false);
  const Eigen::VectorXd eigenvalues = density_scaled_eigenvalues(k0);
  EXPECT_LE(eigenvalues.maxCoeff(), 4.0 + 1e-9);
  EXPECT_GT(eigenvalues.minCoeff(), -1e-9);
}

// The energy correction reproduces the classical energy density of homogeneous strains at nodes
// with mirror-symmetric families (interior of a cubic lattice; every in-plane interior node of the
// two-layer plate lattice for strains without transverse shear).
TEST(PdBody, EnergyDensityOfHomogeneousStrains) {
  struct Lattice {
    Vec3 upper, spacing;
    Real horizon;
    Vec3 centre;
    bool transverse_shear;
  };
  for (const Lattice& l : {Lattice{Vec3(9, 9, 9), Vec3(1, 1, 1), 3.015, Vec3(4.5, 4.5, 4.5), true},
                           Lattice{Vec3(90, 90, 2), Vec3(10, 10, 1), 14.2, Vec3(45, 45, 0.5), false}}) {
    Fixture f(Vec3::Zero(), l.upper, l.spacing, l.horizon);
    Index centre = 0;
    (f.cloud.positions.colwise() - l.centre).colwise().squaredNorm().minCoeff(&centre);
    const Real e = 1000.0, nu = 0.3, mu = e / (2 * (1 + nu)), lambda = e * nu / ((1 + nu) * (1 - 2 * nu));
    std::vector<Mat3> strains;
    for (int a = 0; a < 3; ++a) {
      Mat3 s = Mat3::Zero();
      s(a, a) = 1e-3;
      strains.push_back(s);
    }
    Mat3 shear = Mat3::Zero();
    shear(0, 1) = shear(1, 0) = 1e-3;
    strains.push_back(shear);
    Mat3 mixed;
    mixed << 1e-3, 2e-4, 0, 2e-4, -4e-4, 0, 0, 0, 3e-4;
    strains.push_back(mixed);
    if (l.transverse_shear) {
      Mat3 t = Mat3::Zero();
      t(0, 2) = t(2, 0) = 1e-3;
      strains.push_back(t);
    }
    for (const Mat3& eps : strains) {
      const PointMatrix u = eps * f.cloud.positions;
      const Eigen::VectorXd w = f.solid->energy_density(f.solid->bond_state(u, true));
      const Real classical = 0.5 * lambda * eps.trace() * eps.trace() + mu * eps.squaredNorm();
      const Real tolerance = l.transverse_shear ? 1e-4 : 2e-2;  // plate lattice: in-plane shear is a compromise (1.3 %)
      EXPECT_NEAR(w[centre], classical, tolerance * classical) << "lattice " << l.horizon << " strain\n" << eps;
    }
  }
}

TEST(PdLattice, GaussLayersThroughThePlateThickness) {
  std::vector<Real> points, weights;
  gauss_legendre(4, points, weights);
  EXPECT_NEAR(points[3], 0.8611363115940526, 1e-14);
  EXPECT_NEAR(weights[0], 0.3478548451374538, 1e-14);
  EXPECT_NEAR(weights[0] + weights[1] + weights[2] + weights[3], 2.0, 1e-14);
  const PointCloud two = lattice_point_cloud(make_cell_lattice(Vec3(0, 0, -1), Vec3(30, 20, 1), Vec3(10, 10, 1)), true, true);
  EXPECT_NEAR(two.positions.row(2).maxCoeff(), 1 / std::sqrt(3.0), 1e-14);  // +- t / (2 sqrt 3)
  EXPECT_NEAR(two.volumes.sum(), 30.0 * 20.0 * 2.0, 1e-9);
  const PointCloud four = lattice_point_cloud(make_cell_lattice(Vec3(0, 0, -1), Vec3(30, 20, 1), Vec3(10, 10, 0.5)), true, true);
  // sum V z^2 = t^3 / 12 per unit area: the lumped layers integrate the bending energy exactly
  EXPECT_NEAR(four.volumes.dot(four.positions.row(2).transpose().cwiseAbs2()) / (30.0 * 20.0), 8.0 / 12.0, 1e-12);
  EXPECT_EQ(four.sets.at("top").size(), 6u);
}

// surface_correction: plate on the seed's plate lattice (10 x 10 x 1 cells, 2 layers at the Gauss points
// of the 2 mm thickness) and on 4 layers: every interior node has the plane-stress energy density of
// every homogeneous strain; in Kirchhoff bending each node's strain estimate is the strain at its own
// height, and a column of nodes carries the bending energy D/2 kappa^2 of the plate formula
// (D = E t^3 / (12 (1 - nu^2))) less the cross-layer bonds' share. The default energy correction gives
// 37x the plate's bending energy for kappa_xx on the two-layer lattice (spurious theta_zz).
TEST(PdBody, PlateCorrectionHomogeneousStrainsAndBending) {
  for (const Real dz : {1.0, 0.5}) {
    BodyOptions options;
    options.horizon = dz == 1.0 ? 14.2 : 7.1;
    options.surface_correction = SurfaceCorrection::plate;
    const Real dx = dz == 1.0 ? 10.0 : 5.0;
    const PointCloud cloud =
        lattice_point_cloud(make_cell_lattice(Vec3(0, 0, -1), Vec3(12 * dx, 12 * dx, 1), Vec3(dx, dx, dz)), true, true);
    const Index n = cloud.size();
    const Real e = 69000.0, nu = 0.33, mu = e / (2 * (1 + nu)), t = 2.0;
    const PeridynamicBody body(cloud.positions, cloud.volumes, Eigen::VectorXd::Constant(n, e), Eigen::VectorXd::Constant(n, nu),
                               options);
    const LinearPeridynamicSolid solid(body);
    EXPECT_LT(body.statistics().max_dilatation_error, 1e-9);
    std::vector<Index> column;  // the nodes above (6 dx, 6 dx)
    for (Index i = 0; i < n; ++i)
      if (std::abs(cloud.positions(0, i) - 6.5 * dx) < 1e-9 && std::abs(cloud.positions(1, i) - 6.5 * dx) < 1e-9) column.push_back(i);
    ASSERT_EQ(column.size(), dz == 1.0 ? 2u : 4u);
    const Real c11 = e / (1 - nu * nu), c12 = nu * e / (1 - nu * nu);
    // homogeneous strains: plane stress in-plane, sigma_zz = E eps_zz, shear mu
    Mat3 mixed;
    mixed << 1e-3, 2e-4, -3e-4, 2e-4, -4e-4, 5e-4, -3e-4, 5e-4, 3e-4;
    for (const Mat3& eps : {mixed, Mat3(Vec3(1e-3, 0, 0).asDiagonal()), Mat3(Vec3(0, 0, 1e-3).asDiagonal())}) {
      const Eigen::VectorXd w = solid.energy_density(solid.bond_state(eps * cloud.positions, true));
      const Real classical = 0.5 * (c11 * (eps(0, 0) * eps(0, 0) + eps(1, 1) * eps(1, 1)) + 2 * c12 * eps(0, 0) * eps(1, 1) +
                                    e * eps(2, 2) * eps(2, 2)) +
                             2 * mu * (eps(0, 1) * eps(0, 1) + eps(0, 2) * eps(0, 2) + eps(1, 2) * eps(1, 2));
      for (const Index i : column) EXPECT_NEAR(w[i], classical, 1e-8 * classical) << "dz " << dz << " node " << i;
    }
    // Kirchhoff bending u = (-z w_x, -z w_y, w), w = -(kxx x^2 + 2 kxy x y + kyy y^2) / 2
    for (const Vec3& kappa : {Vec3(1e-4, 0, 0), Vec3(1e-4, 1e-4, 0), Vec3(1e-4, -5e-5, 0), Vec3(0, 0, 1e-4), Vec3(3e-5, -1e-4, 7e-5)}) {
      PointMatrix u(3, n);
      for (Index i = 0; i < n; ++i) {
        const Real x = cloud.positions(0, i), y = cloud.positions(1, i), z = cloud.positions(2, i);
        u.col(i) = Vec3(z * (kappa.x() * x + kappa.z() * y), z * (kappa.z() * x + kappa.y() * y),
                        -0.5 * (kappa.x() * x * x + 2 * kappa.z() * x * y + kappa.y() * y * y));
      }
      const BondState state = solid.bond_state(u, true);
      const Eigen::VectorXd w = solid.energy_density(state);
      for (const Index i : column) {  // the strain estimate is the strain at the node's height, no spurious components
        EXPECT_NEAR(state.dilatation(0, i), cloud.positions(2, i) * kappa.x(), 1e-6 * kappa.norm());
        EXPECT_NEAR(state.dilatation(1, i), cloud.positions(2, i) * kappa.y(), 1e-6 * kappa.norm());
        EXPECT_NEAR(state.dilatation(2, i), 0.0, 1e-6 * kappa.norm());
        EXPECT_NEAR(state.shear_dilatation.col(i).head<2>().norm(), 0.0, 1e-6 * kappa.norm());
        EXPECT_NEAR(state.shear_dilatation(2, i), cloud.positions(2, i) * kappa.z(), 1e-6 * kappa.norm());
      }
      Real energy = 0;  // per unit area
      for (const Index i : column) energy += w[i] * cloud.volumes[i] / (dx * dx);
      const Real plate = 0.5 * t * t * t / 12 *
                         (c11 * (kappa.x() * kappa.x() + kappa.y() * kappa.y()) + 2 * c12 * kappa.x() * kappa.y() +
                          4 * mu * kappa.z() * kappa.z());
      // never stiffer; softer by the in-plane share of the cross-layer bonds, which see the strain at
      // their mid-height (2 layers: the mid-plane, 8-15 %; 4 layers: 1-6 %)
      EXPECT_LE(energy, plate * (1 + 1e-9)) << "dz " << dz << " kappa " << kappa.transpose();
      EXPECT_GE(energy, plate * (dz == 1.0 ? 0.84 : 0.93)) << "dz " << dz << " kappa " << kappa.transpose();
    }
  }
}

// surface_correction: plate (six generalized dilatations): the stiffness is the derivative of the
// internal force, positive semi-definite, and bounded by the ADR density on the seed's plate lattice.
TEST(PdSolid, PlateCorrectionStiffnessConsistentAndBounded) {
  BodyOptions options;
  options.surface_correction = SurfaceCorrection::plate;
  {
    Fixture f(Vec3(0, 0, -1), Vec3(5, 4, 1), Vec3(1, 1, 0.5), 2.015, options);
    const Index n = f.body->nodes();
    std::mt19937 gen(11);
    std::uniform_real_distribution<Real> uniform(-0.05, 0.05);
    PointMatrix u(3, n);
    for (Index k = 0; k < u.size(); ++k) u.data()[k] = uniform(gen);
    const Eigen::MatrixXd k = dense(f.solid->stiffness(f.solid->bond_state(u)));
    const Real h = 1e-6;
    Real worst = 0;
    for (Index d = 0; d < 3 * n; ++d) {
      PointMatrix up = u, um = u;
      up.data()[d] += h;
      um.data()[d] -= h;
      const PointMatrix df = (f.solid->internal_force(up) - f.solid->internal_force(um)) / (2 * h);
      const Eigen::Map<const Eigen::VectorXd> column(df.data(), 3 * n);
      for (Index r = 0; r < 3 * n; ++r) worst = std::max(worst, std::abs(-column[r] - k(r, d)));
    }
    EXPECT_LT(worst, 1e-6 * k.cwiseAbs().maxCoeff());
  }
  Fixture f(Vec3(0, 0, -1), Vec3(60, 40, 1), Vec3(10, 10, 1), 14.2, options);
  const Index n = f.body->nodes();
  const solve::SparseMatrix k0 = f.solid->stiffness(f.solid->bond_state(PointMatrix::Zero(3, n), true), true, false);
  const Eigen::VectorXd eigenvalues = density_scaled_eigenvalues(k0);
  EXPECT_LE(eigenvalues.maxCoeff(), 4.0 + 1e-9);
  EXPECT_GT(eigenvalues.minCoeff(), -1e-9);
  EXPECT_EQ((eigenvalues.array() < 1e-9 * eigenvalues.maxCoeff()).count(), 6);  // rigid modes only
}
