// Cell-list neighbour search against brute force, MLS neighbour lists against the support definitions,
// and the nodal spacing estimate.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "core/error.hpp"
#include "mls/mls_shape_functions.hpp"
#include "mls/nodal_spacing.hpp"
#include "mls/neighbour_search.hpp"
#include "test_helpers.hpp"

namespace lamina::mls {
namespace {

using testing::jittered_grid;
using testing::random_points;
using testing::regular_grid;

TEST(CellList, RangeQueriesMatchBruteForce) {
  const PointMatrix cloud = random_points(2000, Vec3::Zero(), Vec3(1.0, 2.0, 0.5), 3, 1);
  const PointMatrix queries = random_points(200, Vec3::Constant(-0.2), Vec3(1.2, 2.2, 0.7), 3, 2);
  for (Real cell : {0.01, 0.07, 0.3, 5.0}) {  // 0.01 exceeds the cell cap: the size grows
    const CellList cells(cloud, cell);
    EXPECT_EQ(cells.size(), cloud.cols());
    IndexList found, expected;
    for (Index q = 0; q < queries.cols(); ++q) {
      const Vec3 x = queries.col(q);
      const Real radius = 0.05 + 0.1 * (q % 3);
      const Vec3 low = x - Vec3(radius, 0.5 * radius, 2 * radius), high = x + Vec3(radius, radius, radius);
      cells.points_in_box(low, high, found);
      expected.clear();
      for (Index i = 0; i < cloud.cols(); ++i)
        if ((cloud.col(i).array() >= low.array()).all() && (cloud.col(i).array() <= high.array()).all())
          expected.push_back(i);
      EXPECT_EQ(found, expected) << "box query " << q << " cell " << cell;
      cells.points_in_sphere(x, radius, found);
      expected.clear();
      for (Index i = 0; i < cloud.cols(); ++i)
        if ((cloud.col(i) - x).norm() <= radius) expected.push_back(i);
      EXPECT_EQ(found, expected) << "sphere query " << q << " cell " << cell;
    }
  }
}

std::vector<std::pair<Real, Index>> brute_force_nearest(const PointMatrix& cloud, const Vec3& x, Index k, Index exclude) {
  std::vector<std::pair<Real, Index>> all;
  for (Index i = 0; i < cloud.cols(); ++i)
    if (i != exclude) all.emplace_back((cloud.col(i) - x).squaredNorm(), i);
  std::sort(all.begin(), all.end());
  all.resize(std::min<std::size_t>(all.size(), static_cast<std::size_t>(k)));
  return all;
}

TEST(CellList, NearestMatchesBruteForceIncludingTies) {
  const PointMatrix random_cloud = random_points(1500, Vec3::Zero(), Vec3(1.0, 1.0, 1.0), 3, 3);
  const PointMatrix grid = regular_grid({9, 8, 7}, Vec3(0.1, 0.1, 0.1));  // many equal distances
  const PointMatrix queries = random_points(100, Vec3::Constant(-0.3), Vec3::Constant(1.3), 3, 4);
  for (const PointMatrix* cloud : {&random_cloud, &grid})
    for (Real cell : {0.02, 0.1, 0.5}) {
      const CellList cells(*cloud, cell);
      std::vector<std::pair<Real, Index>> found;
      for (Index q = 0; q < queries.cols(); ++q)
        for (Index k : {1, 7, 27, 60}) {
          cells.nearest(queries.col(q), k, found);
          EXPECT_EQ(found, brute_force_nearest(*cloud, queries.col(q), k, -1)) << "query " << q << " k " << k;
        }
      // Nodes as queries (exact ties at grid distances), excluding the node itself.
      for (Index i = 0; i < cloud->cols(); i += 37) {
        cells.nearest(cloud->col(i), 26, found, i);
        EXPECT_EQ(found, brute_force_nearest(*cloud, cloud->col(i), 26, i)) << "node " << i;
      }
    }
  const CellList cells(grid, 0.1);
  std::vector<std::pair<Real, Index>> found;
  cells.nearest(Vec3(0.3, 0.3, 0.3), 100000, found);
  EXPECT_EQ(static_cast<Index>(found.size()), grid.cols());
}

/// Brute-force neighbours of x for the node-centred modes from the published support radii.
IndexList brute_force_neighbours(const MlsShapeFunctions& shape_functions, const Vec3& x) {
  const int dimension = shape_functions.options().dimension;
  const bool box = shape_functions.options().shape == SupportShape::box;
  IndexList result;
  for (Index i = 0; i < shape_functions.node_count(); ++i) {
    const Vec3 offset = x - shape_functions.nodes().col(i);
    const Vec3 radius = shape_functions.support_radii().col(i);
    bool inside = true;
    if (box) {
      for (int d = 0; d < dimension; ++d) inside = inside && std::abs(offset[d]) < radius[d];
    } else {
      Real squared = 0.0;
      for (int d = 0; d < dimension; ++d) squared += offset[d] * offset[d];
      inside = std::sqrt(squared) < radius[0];
    }
    if (inside) result.push_back(i);
  }
  return result;
}

TEST(MlsNeighbours, NodeCentredSupportsMatchBruteForce) {
  const Real h = 0.1;
  const PointMatrix nodes = jittered_grid({11, 9, 8}, Vec3(h, h, 1.3 * h), 0.3, 3, 5);
  // Heterogeneous caller-given spacing so that node radii differ strongly.
  std::mt19937 generator(6);
  std::uniform_real_distribution<Real> uniform(0.6, 1.8);
  Eigen::Matrix3Xd spacing(3, nodes.cols());
  for (Index i = 0; i < nodes.cols(); ++i) spacing.col(i) = Vec3(uniform(generator), uniform(generator), uniform(generator)) * h;
  const PointMatrix queries = random_points(150, Vec3::Zero(), Vec3(1.0, 0.8, 0.9), 3, 7);
  for (SupportShape shape : {SupportShape::box, SupportShape::sphere})
    for (SupportMode mode : {SupportMode::kappa, SupportMode::fixed_radius, SupportMode::all}) {
      MlsOptions options;
      options.shape = shape;
      options.mode = mode;
      options.kappa = 2.5;
      options.radius = Vec3(0.25, 0.2, 0.3);
      options.nearest = 25;
      options.scale = 1.1;
      options.basis = Basis::linear;
      const MlsShapeFunctions shape_functions(nodes, options, mode == SupportMode::kappa ? spacing : Eigen::Matrix3Xd());
      for (Index q = 0; q < queries.cols(); ++q) {
        const ShapeFunctionValues values = shape_functions.evaluate(queries.col(q), 0);
        EXPECT_EQ(values.neighbours, brute_force_neighbours(shape_functions, queries.col(q)))
            << to_string(shape) << " " << to_string(mode) << " query " << q;
      }
    }
}

TEST(MlsNeighbours, PerAxisKappaSetsBoxRadiiAxisByAxis) {
  const Real h = 0.1;
  const PointMatrix nodes = jittered_grid({9, 9, 5}, Vec3(h, h, 0.5 * h), 0.2, 3, 11);
  MlsOptions options;
  options.kappa_axes = Vec3(3.0, 2.5, 2.0);
  const Eigen::Matrix3Xd spacing = Eigen::Matrix3Xd::Constant(3, nodes.cols(), h);
  const MlsShapeFunctions shape_functions(nodes, options, spacing);
  for (Index i = 0; i < nodes.cols(); ++i)
    for (int d = 0; d < 3; ++d)
      EXPECT_NEAR(shape_functions.support_radii()(d, i),
                  (options.kappa_axes[d] + options.delta) * h * (1.0 + support_epsilon), 1e-15);
  const PointMatrix queries = random_points(60, Vec3::Constant(0.1), Vec3(0.7, 0.7, 0.15), 3, 12);
  for (Index q = 0; q < queries.cols(); ++q) {
    const ShapeFunctionValues values = shape_functions.evaluate(queries.col(q), 1);
    EXPECT_EQ(values.neighbours, brute_force_neighbours(shape_functions, queries.col(q))) << "query " << q;
    EXPECT_NEAR(values.phi.sum(), 1.0, 1e-12);
  }
  // a sphere support takes one factor only
  options.shape = SupportShape::sphere;
  EXPECT_THROW(MlsShapeFunctions(nodes, options, spacing), InputError);
}

TEST(MlsNeighbours, NeighbourQueryAloneMatchesTheEvaluation) {
  const PointMatrix nodes = jittered_grid({10, 8, 6}, Vec3(0.1, 0.1, 0.1), 0.3, 3, 13);
  const PointMatrix queries = random_points(80, Vec3::Zero(), Vec3(0.9, 0.7, 0.5), 3, 14);
  for (SupportMode mode : {SupportMode::kappa, SupportMode::nearest, SupportMode::variable}) {
    MlsOptions options;
    options.mode = mode;
    options.kappa = 2.2;
    options.nearest = 30;
    const MlsShapeFunctions shape_functions(nodes, options);
    IndexList alone;
    for (Index q = 0; q < queries.cols(); ++q) {
      shape_functions.neighbours(queries.col(q), alone);
      EXPECT_EQ(alone, shape_functions.evaluate(queries.col(q), 0).neighbours) << to_string(mode) << " query " << q;
    }
  }
}

TEST(MlsNeighbours, NearestCountModesMatchBruteForce) {
  // SELECT (mode nearest): of the nodes whose kappa supports cover x, the N nearest (ties by index).
  // VARIABLE: the N nearest nodes of x, weighted from x. An isotropic cloud: plain distances.
  const PointMatrix nodes = random_points(800, Vec3::Zero(), Vec3::Ones(), 3, 8);
  const PointMatrix queries = random_points(100, Vec3::Zero(), Vec3::Ones(), 3, 9);
  for (SupportShape shape : {SupportShape::box, SupportShape::sphere}) {
    MlsOptions options;
    options.shape = shape;
    options.mode = SupportMode::nearest;
    options.nearest = 30;
    options.kappa = shape == SupportShape::sphere ? 2.5 : 2.0;
    const MlsShapeFunctions nearest(nodes, options);
    ASSERT_EQ(nearest.support_radii().cols(), nodes.cols());
    options.mode = SupportMode::variable;
    options.scale = 1.2;
    const MlsShapeFunctions variable(nodes, options);
    Index capped = 0;
    for (Index q = 0; q < queries.cols(); ++q) {
      const Vec3 x = queries.col(q);
      std::vector<std::pair<Real, Index>> covering;
      for (Index i = 0; i < nodes.cols(); ++i) {
        const Vec3 offset = x - nodes.col(i);
        const Vec3 radius = nearest.support_radii().col(i);
        const bool inside = shape == SupportShape::box ? (offset.cwiseAbs().array() < radius.array()).all()
                                                       : offset.norm() < radius[0];
        if (inside) covering.emplace_back(offset.squaredNorm(), i);
      }
      std::sort(covering.begin(), covering.end());
      capped += covering.size() > 30 ? 1 : 0;
      if (covering.size() > 30) covering.resize(30);
      IndexList expected;
      for (const auto& entry : covering) expected.push_back(entry.second);
      std::sort(expected.begin(), expected.end());
      EXPECT_EQ(nearest.evaluate(x, 0).neighbours, expected) << "nearest, query " << q;
      // variable: the 30 nearest, all inside R(x) = 1.2 (1 + eps) d_30(x)
      expected.clear();
      for (const auto& entry : brute_force_nearest(nodes, x, 30, -1)) expected.push_back(entry.second);
      std::sort(expected.begin(), expected.end());
      EXPECT_EQ(variable.evaluate(x, 0).neighbours, expected) << "variable, query " << q;
    }
    EXPECT_GT(capped, 40) << "the cap of 30 should bind at many queries (both paths tested), bound at " << capped;
  }
}

TEST(MlsNeighbours, SelectWithACapThatNeverBindsIsModeKappa) {
  // SELECT (mode nearest) = the kappa supports that cover x, capped to the N nearest: with N above every
  // covering count the neighbours and the shape functions are those of mode kappa.
  const PointMatrix grid = regular_grid({7, 6, 5}, Vec3(0.2, 0.25, 0.3));
  const PointMatrix queries = random_points(40, Vec3::Zero(), Vec3(1.2, 1.25, 1.2), 3, 21);
  for (SupportShape shape : {SupportShape::box, SupportShape::sphere}) {
    MlsOptions options;
    options.shape = shape;
    options.kappa = 2.5;
    const MlsShapeFunctions kappa(grid, options);
    options.mode = SupportMode::nearest;
    options.nearest = 100000;
    const MlsShapeFunctions select(grid, options);
    for (Index q = 0; q < queries.cols(); ++q) {
      const ShapeFunctionValues a = kappa.evaluate(queries.col(q), 1), b = select.evaluate(queries.col(q), 1);
      ASSERT_EQ(a.neighbours, b.neighbours) << to_string(shape) << ", query " << q;
      EXPECT_LT((a.phi - b.phi).cwiseAbs().maxCoeff(), 1e-14);
      EXPECT_LT((a.dphi - b.dphi).cwiseAbs().maxCoeff(), 1e-12);
    }
  }
}

TEST(MlsNeighbours, NearestCountsSpacingsOnAPlateLattice) {
  // 9 x 9 x 3 nodes, in-plane spacing 0.5, through-thickness 0.1 (a plate): "the 27 nearest" are counted
  // in units of the spacing per axis, so every point's neighbours hold all three layers and the quadratic
  // basis is regular (in plain distances the 27 nearest of a point near a face lie in two layers).
  const PointMatrix grid = regular_grid({9, 9, 3}, Vec3(0.5, 0.5, 0.1));
  const PointMatrix queries = random_points(60, Vec3(0.5, 0.5, 0.0), Vec3(3.5, 3.5, 0.2), 3, 12);
  for (SupportMode mode : {SupportMode::nearest, SupportMode::variable, SupportMode::all}) {
    MlsOptions options;
    options.shape = SupportShape::sphere;
    options.mode = mode;
    options.nearest = 27;
    options.kappa = 2.5;
    options.scale = 1.5;
    const MlsShapeFunctions mls(grid, options);
    for (Index q = 0; q < queries.cols(); ++q) {
      const Vec3 x = queries.col(q);
      ShapeFunctionValues values;
      ASSERT_NO_THROW(mls.evaluate(x, 1, values)) << to_string(mode) << ", query " << q;
      bool layer[3] = {false, false, false};
      for (Index i : values.neighbours) layer[static_cast<int>(std::lround(grid(2, i) / 0.1))] = true;
      EXPECT_TRUE(layer[0] && layer[1] && layer[2]) << to_string(mode) << ", query " << q;
      // and the quadratic field 1 + x z - y^2 + 3 z^2 is reproduced
      Eigen::VectorXd u(grid.cols());
      for (Index i = 0; i < grid.cols(); ++i)
        u[i] = 1.0 + grid(0, i) * grid(2, i) - grid(1, i) * grid(1, i) + 3.0 * grid(2, i) * grid(2, i);
      const FieldValue field = approximate_field(values, u);
      EXPECT_NEAR(field.value, 1.0 + x[0] * x[2] - x[1] * x[1] + 3.0 * x[2] * x[2], 1e-9);
      EXPECT_NEAR(field.gradient[2], x[0] + 6.0 * x[2], 1e-7);
    }
  }
}

TEST(NodalSpacing, RegularGridGivesExactSpacingPerAxis) {
  const Vec3 h(0.1, 0.25, 0.04);
  const PointMatrix grid = regular_grid({6, 5, 4}, h);
  const Eigen::Matrix3Xd spacing = estimate_nodal_spacing(grid);
  ASSERT_EQ(spacing.cols(), grid.cols());
  for (Index i = 0; i < grid.cols(); ++i)
    for (int d = 0; d < 3; ++d) EXPECT_NEAR(spacing(d, i), h[d], 1e-12 * h[d]) << "node " << i << " axis " << d;
  // 2D and 1D: unused rows are zero.
  const PointMatrix plane = regular_grid({7, 4, 1}, Vec3(0.3, 0.2, 1.0));
  const Eigen::Matrix3Xd plane_spacing = estimate_nodal_spacing(plane, 2);
  for (Index i = 0; i < plane.cols(); ++i) {
    EXPECT_NEAR(plane_spacing(0, i), 0.3, 1e-12);
    EXPECT_NEAR(plane_spacing(1, i), 0.2, 1e-12);
    EXPECT_EQ(plane_spacing(2, i), 0.0);
  }
  const PointMatrix line = regular_grid({9, 1, 1}, Vec3(0.05, 1.0, 1.0));
  const Eigen::Matrix3Xd line_spacing = estimate_nodal_spacing(line, 1);
  for (Index i = 0; i < line.cols(); ++i) EXPECT_NEAR(line_spacing(0, i), 0.05, 1e-13);
}

TEST(NodalSpacing, JitteredAndFlatClouds) {
  const Real h = 0.1;
  const PointMatrix cloud = jittered_grid({8, 8, 8}, Vec3::Constant(h), 0.2, 3, 10);
  const Eigen::Matrix3Xd spacing = estimate_nodal_spacing(cloud);
  EXPECT_GT(spacing.minCoeff(), 0.5 * h);
  EXPECT_LT(spacing.maxCoeff(), 1.5 * h);
  // A single layer of nodes in 3D: the missing axis takes the largest in-plane spacing.
  const PointMatrix flat = regular_grid({4, 4, 1}, Vec3(0.1, 0.2, 1.0));
  const Eigen::Matrix3Xd flat_spacing = estimate_nodal_spacing(flat);
  EXPECT_NEAR(flat_spacing(2, 5), 0.2, 1e-12);
  EXPECT_THROW(estimate_nodal_spacing(PointMatrix::Zero(3, 1)), InputError);
}

}  // namespace
}  // namespace lamina::mls
