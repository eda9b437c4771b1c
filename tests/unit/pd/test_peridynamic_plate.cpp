// Unit tests of the director plate model (pd/peridynamic_plate.hpp): exact energy of homogeneous
// membrane strain, curvature and transverse shear; forces are the energy gradient; the stiffness is the
// force derivative; only rigid-body zero modes; a smooth bending mode converges to plate theory.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "geometry/cell_lattice.hpp"
#include "core/error.hpp"
#include "pd/peridynamic_analysis.hpp"
#include "pd/peridynamic_plate.hpp"
#include "pd/relaxation_coordinates.hpp"
#include "density_scaled_spectrum.hpp"

using namespace lamina;
using namespace lamina::pd;
using lamina::geometry::lattice_point_cloud;
using lamina::geometry::make_cell_lattice;
using lamina::geometry::CellLattice;

namespace {

constexpr Real young = 69000, poisson = 0.33;

struct PlateFixture {
  PointCloud cloud;
  std::unique_ptr<PeridynamicPlate> plate;
  /// held(x, component): whether that dof of the node at x is held (the clamped edges' mirrors).
  PlateFixture(Real side, Real dx, Real thickness, int layers, Real horizon_factor, Real stabilization = 0.25,
               const std::function<bool(const Vec3&, int)>& held = {}) {
    cloud = lattice_point_cloud(make_cell_lattice(Vec3(0, 0, -thickness / 2), Vec3(side, side, thickness / 2),
                                                  Vec3(dx, dx, thickness / layers)), true);
    BodyOptions options;
    options.horizon = horizon_factor * dx;
    options.plate_stabilization = stabilization;
    auto columns = find_plate_columns(cloud.positions, cloud.volumes);
    EXPECT_TRUE(columns.has_value());
    const Index n = cloud.size();
    std::vector<char> held_dofs;
    if (held) {
      held_dofs.assign(static_cast<std::size_t>(3 * n), 0);
      for (Index k = 0; k < n; ++k)
        for (int a = 0; a < 3; ++a) held_dofs[static_cast<std::size_t>(3 * k + a)] = held(cloud.positions.col(k), a);
    }
    plate = std::make_unique<PeridynamicPlate>(*columns, cloud.positions, cloud.positions, cloud.volumes,
                                               Eigen::VectorXd::Constant(n, young), Eigen::VectorXd::Constant(n, poisson),
                                               options, held_dofs);
  }
  Real energy(const PointMatrix& u) const { return plate->strain_energy(*plate->state_of(u)); }
  /// Displacement of a Kirchhoff plate field: mid-surface (u0, v0, w) and the normal rotation, at each node.
  template <class Field>
  PointMatrix kirchhoff(Field field) const {
    PointMatrix u(3, cloud.size());
    for (Index k = 0; k < cloud.size(); ++k) {
      const Vec3 x = cloud.positions.col(k);
      Real u0, v0, w, wx, wy;
      field(x.x(), x.y(), u0, v0, w, wx, wy);
      u.col(k) << u0 - x.z() * wx, v0 - x.z() * wy, w;
    }
    return u;
  }
};

Real bending_rigidity(Real t) { return young * t * t * t / (12 * (1 - poisson * poisson)); }

/// Largest |F + dPi/du| over every `stride`-th dof at u (central differences), over the largest |F|.
Real gradient_error(const PlateFixture& f, const PointMatrix& u, Index stride) {
  const PointMatrix force = f.plate->internal_force(*f.plate->state_of(u));
  const Real h = 1e-7;
  Real worst = 0;
  for (Index dof = 0; dof < u.size(); dof += stride) {
    PointMatrix up = u, um = u;
    up.data()[dof] += h, um.data()[dof] -= h;
    const Real numeric = -(f.energy(up) - f.energy(um)) / (2 * h);
    worst = std::max(worst, std::abs(numeric - force.data()[dof]));
  }
  return worst / force.cwiseAbs().maxCoeff();
}

/// Largest |K0 column + dF/du| over every `stride`-th dof at the reference, over the largest |K0| entry.
Real stiffness_error(const PlateFixture& f, Index stride) {
  const Index n = f.cloud.size();
  const solve::SparseMatrix k0 = f.plate->stiffness(*f.plate->state_of(PointMatrix::Zero(3, n)), true, false);
  const Eigen::MatrixXd k = Eigen::MatrixXd(Eigen::MatrixXd(k0).selfadjointView<Eigen::Upper>());
  Real worst = 0;
  for (Index dof = 0; dof < 3 * n; dof += stride) {
    PointMatrix up = PointMatrix::Zero(3, n), um = up;
    const Real e = 1e-6;
    up.data()[dof] += e, um.data()[dof] -= e;
    const PointMatrix df = (f.plate->internal_force(*f.plate->state_of(up)) - f.plate->internal_force(*f.plate->state_of(um))) / (2 * e);
    const Eigen::Map<const Eigen::VectorXd> column(df.data(), 3 * n);
    worst = std::max(worst, (column + k.col(dof)).cwiseAbs().maxCoeff());
  }
  return worst / k.cwiseAbs().maxCoeff();
}

/// Per node dof, 1 = free: the 40 mm square plate supported with w = 0 on its outer columns, one in-plane
/// pin (17.5, 17.5) and one roller (37.5, 17.5) on the bottom layer (the rigid motions).
std::vector<char> supported_square_free_dofs(const PointCloud& cloud) {
  const Index n = cloud.size();
  Index pin = -1, roller = -1;
  for (Index node = 0; node < n; ++node) {
    const Vec3 x = cloud.positions.col(node);
    if (pin < 0 && x.z() < 0 && std::abs(x.x() - 17.5) < 1e-9 && std::abs(x.y() - 17.5) < 1e-9) pin = node;
    if (roller < 0 && x.z() < 0 && std::abs(x.x() - 37.5) < 1e-9 && std::abs(x.y() - 17.5) < 1e-9) roller = node;
  }
  std::vector<char> free(static_cast<std::size_t>(3 * n), 1);
  for (Index node = 0; node < n; ++node) {
    const Vec3 x = cloud.positions.col(node);
    const bool edge = x.x() < 3 || x.x() > 37 || x.y() < 3 || x.y() > 37;
    for (int a = 0; a < 3; ++a)
      if ((a == 2 && edge) || (node == pin && a < 2) || (node == roller && a == 1)) free[static_cast<std::size_t>(3 * node + a)] = 0;
  }
  return free;
}

}  // namespace

TEST(PeridynamicPlate, FindsColumnsOfPlateLatticesOnly) {
  const PointCloud plate = lattice_point_cloud(make_cell_lattice(Vec3(0, 0, -1), Vec3(100, 50, 1), Vec3(5, 5, 1)), true);
  auto c = find_plate_columns(plate.positions, plate.volumes);
  ASSERT_TRUE(c.has_value());
  EXPECT_EQ(c->layers, 2);
  EXPECT_EQ(c->columns(), 20 * 10);
  EXPECT_NEAR(c->thickness, 2.0, 1e-12);
  const PointCloud block = lattice_point_cloud(make_cell_lattice(Vec3(0, 0, 0), Vec3(10, 10, 10), Vec3(1, 1, 1)), false);
  std::string why;
  EXPECT_FALSE(find_plate_columns(block.positions, block.volumes, &why).has_value());
  EXPECT_NE(why.find("layers"), std::string::npos) << why;
}

// Homogeneous membrane strain, curvature (Kirchhoff field with the rotated normal) and twist give the
// classical energy on the whole plate: every column reads the field exactly (the fits are exact for
// polynomials, the stabilisation sees no non-affine part).
TEST(PeridynamicPlate, HomogeneousStatesGiveThePlateEnergy) {
  for (Real factor : {1.4, 2.0, 3.015}) {
    const Real side = 60, dx = 5, t = 2;
    PlateFixture f(side, dx, t, 2, factor);
    const Real area = side * side, d = bending_rigidity(t), c = young * t / (1 - poisson * poisson);
    const Real e = 1e-5, k = 1e-6;
    // membrane: exx = e, eyy = -0.2 e, gxy = 0.5 e (linearised energy; Green strain adds O(e^3))
    PointMatrix u = f.kirchhoff([&](Real x, Real y, Real& u0, Real& v0, Real& w, Real& wx, Real& wy) {
      u0 = e * x + 0.25 * e * y, v0 = -0.2 * e * y + 0.25 * e * x, w = wx = wy = 0;
    });
    const Real membrane = 0.5 * c * area * (e * e + 0.04 * e * e - 2 * poisson * 0.2 * e * e + 0.5 * (1 - poisson) * 0.25 * e * e);
    // the thickness stretch relaxes to the plane-stress value only in equilibrium: compare with it free
    EXPECT_GT(f.energy(u), membrane * (1 - 1e-6)) << factor;
    // bending: w = (kx x^2 + ky y^2) / 2 + kxy x y
    u = f.kirchhoff([&](Real x, Real y, Real& u0, Real& v0, Real& w, Real& wx, Real& wy) {
      u0 = v0 = 0;
      w = 0.5 * k * x * x + 0.5 * 0.3 * k * y * y + 0.4 * k * x * y;
      wx = k * x + 0.4 * k * y, wy = 0.3 * k * y + 0.4 * k * x;
    });
    const Real bending = 0.5 * d * area * (k * k + 0.09 * k * k + 2 * poisson * 0.3 * k * k + 2 * (1 - poisson) * 0.16 * k * k);
    EXPECT_NEAR(f.energy(u) / bending, 1.0, 2e-3) << factor;
  }
}

// Transverse shear: w = g x with the director held vertical gives 5/6 mu t g^2 per area.
TEST(PeridynamicPlate, TransverseShearModulus) {
  const Real side = 60, dx = 5, t = 2, g = 1e-5;
  PlateFixture f(side, dx, t, 2, 3.015);
  PointMatrix u = PointMatrix::Zero(3, f.cloud.size());
  for (Index k = 0; k < f.cloud.size(); ++k) u(2, k) = g * f.cloud.positions(0, k);
  const Real mu = young / (2 * (1 + poisson));
  EXPECT_NEAR(f.energy(u) / (0.5 * (5.0 / 6.0) * mu * t * g * g * side * side), 1.0, 1e-3);
}

// Forces are -dPi/du and the material stiffness at the reference is dF/du (central differences).
TEST(PeridynamicPlate, ForceIsEnergyGradientAndStiffnessIsForceDerivative) {
  for (int layers : {2, 3}) {
    PlateFixture f(30, 5, 2, layers, 2.5);
    const PointMatrix u = PointMatrix::Random(3, f.cloud.size()) * 1e-3;
    EXPECT_LT(gradient_error(f, u, 7), 1e-5) << layers;
    EXPECT_LT(stiffness_error(f, 5), 1e-5) << layers;
  }
}

// The free plate has exactly six zero-energy modes (the rigid motions) for every horizon of the
// range, including a family of the four nearest columns only.
TEST(PeridynamicPlate, OnlyRigidBodyZeroModes) {
  for (Real factor : {1.4, 1.5, 2.0, 3.5}) {
    PlateFixture f(40, 5, 2, 2, factor);
    const Index n = f.cloud.size();
    const solve::SparseMatrix k0 = f.plate->stiffness(*f.plate->state_of(PointMatrix::Zero(3, n)), true, false);
    const Eigen::MatrixXd k = Eigen::MatrixXd(Eigen::MatrixXd(k0).selfadjointView<Eigen::Upper>());
    const Eigen::VectorXd values = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(k).eigenvalues();
    const Real largest = values.maxCoeff();
    EXPECT_LT(std::abs(values[5]), 1e-9 * largest) << factor;
    EXPECT_GT(values[6], 1e-9 * largest) << factor;
  }
}

namespace {

/// The simply supported 60 x 60 x 2 plate (5 mm cells, 2 layers) under equal and opposite edge
/// forces, as a pd buckling problem.
PeridynamicProblem square_buckling_problem(Real horizon, PlateModel model) {
  PeridynamicProblem p;
  const PointCloud cloud = lattice_point_cloud(make_cell_lattice(Vec3(0, 0, -1), Vec3(60, 60, 1), Vec3(5, 5, 1)), true);
  const Index n = cloud.size();
  p.positions = cloud.positions;
  p.volumes = cloud.volumes;
  p.young = Eigen::VectorXd::Constant(n, young);
  p.poisson = Eigen::VectorXd::Constant(n, poisson);
  p.density = Eigen::VectorXd::Constant(n, 2.7e-9);
  p.body.horizon = horizon;
  p.body.plate_model = model;
  p.analysis = PdAnalysisKind::buckling;
  Index centre = 0, right = 0;
  for (Index k = 0; k < n; ++k) {
    const Vec3 x = cloud.positions.col(k);
    if (x.x() < 3 || x.x() > 57 || x.y() < 3 || x.y() > 57) p.prescribed.push_back({k, 2, 0.0});
    if (x.x() > 57) p.forces.push_back({k, Vec3(-1.0 / 24, 0, 0)});
    if (x.x() < 3) p.forces.push_back({k, Vec3(1.0 / 24, 0, 0)});
    if ((x - Vec3(27.5, 27.5, -0.5)).norm() < 1e-9) centre = k;
    if ((x - Vec3(57.5, 27.5, -0.5)).norm() < 1e-9) right = k;
  }
  p.prescribed.push_back({centre, 0, 0.0});
  p.prescribed.push_back({centre, 1, 0.0});
  p.prescribed.push_back({right, 1, 0.0});
  return p;
}

}  // namespace

// A lattice whose horizon reaches the nearest neighbours only has zero-energy shear modes: the
// buckling analysis refuses it (InputError, exit 2) with the reason; the plate model of the same
// lattice and horizon has none and runs.
TEST(PeridynamicPlate, ZeroEnergyModeIsRefused) {
  PeridynamicAnalysis lattice(square_buckling_problem(5.5, PlateModel::lattice), {});
  try {
    lattice.solve();
    FAIL() << "a lattice with zero-energy modes was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("zero-energy mode of the lattice model"), std::string::npos) << e.what();
  }
  PeridynamicAnalysis plate(square_buckling_problem(5.5, PlateModel::automatic), {});
  EXPECT_NO_THROW(plate.solve());
  EXPECT_EQ(plate.model().name(), "plate");
  ASSERT_FALSE(plate.eigenvalues().empty());
  EXPECT_GT(plate.eigenvalues().front(), 0);
}

// Supports that leave a rigid motion free are named as such.
TEST(PeridynamicPlate, FreeRigidMotionIsRefused) {
  PeridynamicProblem p = square_buckling_problem(10, PlateModel::automatic);
  p.prescribed.resize(p.prescribed.size() - 1);  // the in-plane rotation is free
  PeridynamicAnalysis analysis(std::move(p), {});
  try {
    analysis.solve();
    FAIL() << "a free rigid-body motion was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("free rigid-body motion"), std::string::npos) << e.what();
  }
}

// The unloaded stiffness of the supported plate is positive definite and bounded by the ADR
// fictitious density of seed 002 eq (5): with lambda = 1/4 sum_j |K0_ij| the density-scaled
// stiffness has its eigenvalues in (0, 4] (dt = 1 is stable); one-sided and mirrored supported edges.
TEST(PeridynamicPlate, SupportedStiffnessPositiveAndBoundedByFictitiousDensity) {
  const auto simply_supported = [](const Vec3& x, int component) {  // the edges of supported_square_free_dofs
    return component == 2 && (x.x() < 3 || x.x() > 37 || x.y() < 3 || x.y() > 37);
  };
  for (Real factor : {1.4, 3.015})
    for (bool mirrored : {false, true}) {
      std::function<bool(const Vec3&, int)> held;
      if (mirrored) held = simply_supported;
      PlateFixture f(40, 5, 2, 2, factor, 0.25, held);
      ASSERT_EQ(f.plate->mirror().edges.size(), mirrored ? 4u : 0u);
      const Index n = f.cloud.size();
      const solve::SparseMatrix k0 = f.plate->stiffness(*f.plate->state_of(PointMatrix::Zero(3, n)), true, false);
      // supports: w = 0 on the outer columns, one in-plane pin and one roller (the rigid motions)
      const std::vector<char> free_flags = supported_square_free_dofs(f.cloud);
      std::vector<Index> free;
      for (Index d = 0; d < 3 * n; ++d)
        if (free_flags[static_cast<std::size_t>(d)]) free.push_back(d);
      const Eigen::VectorXd values = test_support::density_scaled_spectrum(k0, free);
      EXPECT_GT(values.minCoeff(), 1e-9) << factor << " " << mirrored;
      EXPECT_LE(values.maxCoeff(), 4.0 + 1e-9) << factor << " " << mirrored;
    }
}

// ADR column coordinates (pd/relaxation_coordinates.hpp): T^-1 T = I, the column modes are a uniform
// translation and a linear through-thickness field, the Gershgorin density of T^T K0 T keeps the
// central-difference bound (eigenvalues of the density-scaled stiffness in (0, 4]), and it makes the
// relaxed system better conditioned than the node coordinates (the reason for the coordinates).
TEST(PeridynamicPlate, ColumnCoordinatesInvertKeepTheDensityBoundAndConditionBetter) {
  for (int layers : {2, 3}) {
    PlateFixture f(40, 5, 2, layers, 3.015);
    const Index n = f.cloud.size(), dofs = 3 * n;
    auto columns = find_plate_columns(f.cloud.positions, f.cloud.volumes);
    ASSERT_TRUE(columns.has_value());
    const std::vector<char> node_free = supported_square_free_dofs(f.cloud);
    const RelaxationCoordinates rc = column_coordinates(*columns, n, node_free);
    EXPECT_GT(rc.mapped_groups, 0);
    const Eigen::MatrixXd identity = Eigen::MatrixXd(rc.from_nodes * rc.to_nodes);
    EXPECT_LT((identity - Eigen::MatrixXd::Identity(dofs, dofs)).cwiseAbs().maxCoeff(), 1e-12) << layers;
    // the first mode of an interior column (all nodes free) is a translation of the whole column
    const Index c = columns->columns() / 2 + 2, first = columns->node[static_cast<std::size_t>(columns->first[static_cast<std::size_t>(c)])];
    Eigen::VectorXd q = Eigen::VectorXd::Zero(dofs);
    q[3 * first + 2] = 1.0;
    const Eigen::VectorXd u = rc.to_nodes * q;
    for (Index p = columns->first[static_cast<std::size_t>(c)]; p < columns->first[static_cast<std::size_t>(c) + 1]; ++p)
      EXPECT_NEAR(u[3 * columns->node[static_cast<std::size_t>(p)] + 2], 1.0, 1e-12);
    EXPECT_NEAR(u.cwiseAbs().sum(), static_cast<Real>(layers), 1e-12);
    // density bound and conditioning, nodes versus column coordinates
    const solve::SparseMatrix k0 = f.plate->stiffness(*f.plate->state_of(PointMatrix::Zero(3, n)), true, false);
    const Eigen::MatrixXd k = Eigen::MatrixXd(Eigen::MatrixXd(k0).selfadjointView<Eigen::Upper>());
    auto spectrum = [&](const Eigen::MatrixXd& matrix, const Eigen::VectorXd& lambda) {
      std::vector<Index> free;
      for (Index d = 0; d < dofs; ++d)
        if (node_free[static_cast<std::size_t>(d)]) free.push_back(d);
      Eigen::MatrixXd scaled(free.size(), free.size());
      for (std::size_t r = 0; r < free.size(); ++r)
        for (std::size_t s = 0; s < free.size(); ++s)
          scaled(r, s) = matrix(free[r], free[s]) / std::sqrt(lambda[free[r]] * lambda[free[s]]);
      return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(scaled).eigenvalues();
    };
    const Eigen::VectorXd nodes = spectrum(k, 0.25 * absolute_row_sums(k0));
    const Eigen::MatrixXd t = Eigen::MatrixXd(rc.to_nodes);
    const Eigen::VectorXd mapped = spectrum(t.transpose() * k * t, 0.25 * generalised_absolute_row_sums(k0, rc));
    EXPECT_GT(mapped.minCoeff(), 1e-9) << layers;
    EXPECT_LE(mapped.maxCoeff(), 4.0 + 1e-9) << layers;
    // the slowest mode relaxes faster: its density-scaled eigenvalue (omega^2) is larger
    EXPECT_GT(mapped.minCoeff(), 2.0 * nodes.minCoeff()) << layers << ": " << mapped.minCoeff() << " vs " << nodes.minCoeff();
  }
}

// Force decomposition (several ranks, docs/scaling.md): restricted to a block of nodes, the plate model's
// forces on those nodes are the whole computation's, bit for bit, for 2 and 3 layers and two blocks of
// different shape; lifting the restriction gives the whole force again.
TEST(PeridynamicPlate, RestrictedForcesEqualTheWholeForcesOnTheBlock) {
  for (int layers : {2, 3}) {
    PlateFixture f(40, 5, 2, layers, 3.015);
    const Index n = f.cloud.size();
    const PointMatrix u = PointMatrix::Random(3, n) * 1e-2;
    const PointMatrix whole = f.plate->internal_force(*f.plate->state_of(u));
    for (int shape = 0; shape < 2; ++shape) {
      std::vector<char> mine(static_cast<std::size_t>(n), 0);
      Index count = 0;
      for (Index k = 0; k < n; ++k) {
        const Vec3 x = f.cloud.positions.col(k);
        const bool in = shape == 0 ? x.y() < 15 : (x.x() > 20 && x.y() > 10 && x.y() < 30);
        if (in) mine[static_cast<std::size_t>(k)] = 1, ++count;
      }
      ASSERT_GT(count, 0);
      ASSERT_LT(count, n);
      // the state first holds another field, so that anything the restriction leaves out is stale
      auto state = f.plate->state_of(PointMatrix::Random(3, n) * 1e-2);
      f.plate->restrict_to_nodes(mine);
      f.plate->update(u, *state, false);
      const PointMatrix part = f.plate->internal_force(*state);
      for (Index k = 0; k < n; ++k) {
        if (mine[static_cast<std::size_t>(k)]) {
          EXPECT_EQ(part.col(k), whole.col(k)) << layers << " " << shape << " " << k;
        }
      }
      f.plate->restrict_to_nodes({});
      EXPECT_EQ(f.plate->internal_force(*f.plate->state_of(u)), whole) << layers;
    }
  }
}

namespace {

/// Every kind of mirrored edge (plate_edge_mirror.hpp) on the 30 mm square of 5 mm cells (column lines
/// 2.5 and 27.5), and corners between them: x = 2.5 clamped (x, y, z held), y = 2.5 clamped with its
/// tangential x motion free (y, z held), x = 27.5 simply supported (z held), y = 27.5 a symmetry plane
/// (y held).
bool four_kinds_of_edge(const Vec3& x, int component) {
  if (x.x() < 3) return true;
  if (x.y() < 3 && component > 0) return true;
  if (x.x() > 27 && component == 2) return true;
  return x.y() > 27 && component == 1;
}

}  // namespace

// Supported edges (plate_edge_mirror.hpp): the families reach into mirror columns, which move with real
// ones; the forces stay the exact energy gradient and the stiffness the force derivative, for every dof
// (held ones too: the mirror is a fixed linear map of the node positions).
TEST(PeridynamicPlate, MirroredEdgesKeepForceAndStiffnessConsistent) {
  for (int layers : {2, 3}) {
    PlateFixture f(30, 5, 2, layers, 2.5, 0.25, four_kinds_of_edge);
    ASSERT_EQ(f.plate->mirror().edges.size(), 4u);
    ASSERT_GT(f.plate->mirror().count(), 0);
    const Index n = f.cloud.size();
    const PointMatrix u = PointMatrix::Random(3, n) * 1e-3;
    EXPECT_LT(gradient_error(f, u, 5), 1e-5) << layers;
    EXPECT_LT(stiffness_error(f, 4), 1e-5) << layers;
    const PointMatrix force = f.plate->internal_force(*f.plate->state_of(u));
    // restricted to a block of nodes next to the corner, the forces there are the whole ones, bit for bit
    std::vector<char> mine(static_cast<std::size_t>(n), 0);
    for (Index node = 0; node < n; ++node) mine[static_cast<std::size_t>(node)] = f.cloud.positions(1, node) < 12;
    auto state = f.plate->state_of(PointMatrix::Random(3, n) * 1e-3);
    f.plate->restrict_to_nodes(mine);
    f.plate->update(u, *state, false);
    const PointMatrix part = f.plate->internal_force(*state);
    f.plate->restrict_to_nodes({});
    for (Index node = 0; node < n; ++node)
      if (mine[static_cast<std::size_t>(node)]) EXPECT_EQ(part.col(node), force.col(node)) << layers << " " << node;
  }
}

// A clamp continues the field evenly: the bending field w = k (x - x0)^2 / 2 (zero deflection and slope
// on the clamped line x0) reads as a uniform curvature at every column, the clamped column included, and
// the energy is the plate's over the area inside the clamp (the clamped column counts half its cell).
TEST(PeridynamicPlate, ClampedEdgeContinuesTheBendingFieldEvenly) {
  const Real side = 60, dx = 5, t = 2, x0 = 2.5, k = 1e-6;
  for (Real factor : {1.4, 3.015}) {
    PlateFixture f(side, dx, t, 2, factor, 0.25, [](const Vec3& x, int) { return x.x() < 3; });
    ASSERT_EQ(f.plate->mirror().edges.size(), 1u);
    const PointMatrix u = f.kirchhoff([&](Real x, Real, Real& u0, Real& v0, Real& w, Real& wx, Real& wy) {
      u0 = v0 = wy = 0;
      w = 0.5 * k * (x - x0) * (x - x0);
      wx = k * (x - x0);
    });
    const Real bending = 0.5 * bending_rigidity(t) * k * k * (side - x0) * side;
    EXPECT_NEAR(f.energy(u) / bending, 1.0, 2e-3) << factor;
  }
}

// A simple support continues the field oddly: the twist w = k (x - x0) y (zero deflection on the
// supported line x0, where a simply supported edge carries a twisting moment) reads as a uniform twist at
// every column, and the energy is the plate's over the area inside the support.
TEST(PeridynamicPlate, SimplySupportedEdgeContinuesTheTwistOddly) {
  const Real side = 60, dx = 5, t = 2, x0 = 2.5, k = 1e-6;
  for (Real factor : {1.4, 3.015}) {
    PlateFixture f(side, dx, t, 2, factor, 0.25, [](const Vec3& x, int component) { return x.x() < 3 && component == 2; });
    ASSERT_EQ(f.plate->mirror().edges.size(), 1u);
    const PointMatrix u = f.kirchhoff([&](Real x, Real y, Real& u0, Real& v0, Real& w, Real& wx, Real& wy) {
      u0 = v0 = 0;
      w = k * (x - x0) * y;
      wx = k * y;
      wy = k * (x - x0);
    });
    const Real twisting = bending_rigidity(t) * (1 - poisson) * k * k * (side - x0) * side;
    EXPECT_NEAR(f.energy(u) / twisting, 1.0, 2e-3) << factor;
  }
}
