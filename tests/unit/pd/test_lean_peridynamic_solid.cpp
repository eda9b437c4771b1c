// LeanPeridynamicSolid (pd/lean_peridynamic_solid.hpp) against LinearPeridynamicSolid: the same forces,
// energy and dilatations from the neighbour index alone (plain and energy-corrected lattices, 3D and
// plane stress, exact and linearised kinematics, partial volumes and the inverse-distance influence).
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <random>

#include "core/error.hpp"
#include "geometry/cell_lattice.hpp"
#include "pd/lean_peridynamic_solid.hpp"
#include "pd/linear_peridynamic_solid.hpp"

using namespace lamina;
using namespace lamina::pd;

namespace {

struct Pair {
  PointCloud cloud;
  std::unique_ptr<PeridynamicBody> full_body, lean_body;
};

Pair make_pair(BodyOptions options, bool planar) {
  Pair p;
  const Vec3 spacing(1, 1, 1);
  p.cloud = geometry::lattice_point_cloud(geometry::make_cell_lattice(Vec3::Zero(), Vec3(6, 5, planar ? 1 : 4), spacing), false);
  options.horizon = 2.015;
  options.cell_size = 1.0;
  const Index n = p.cloud.size();
  // two materials, so that the families of neighbouring nodes differ in their constants
  Eigen::VectorXd young = Eigen::VectorXd::Constant(n, 1000.0), poisson = Eigen::VectorXd::Constant(n, 0.3);
  for (Index i = 0; i < n; ++i)
    if (p.cloud.positions(0, i) > 3) young[i] = 2500.0, poisson[i] = 0.2;
  options.lean_bonds = false;
  p.full_body = std::make_unique<PeridynamicBody>(p.cloud.positions, p.cloud.volumes, young, poisson, options);
  options.lean_bonds = true;
  p.lean_body = std::make_unique<PeridynamicBody>(p.cloud.positions, p.cloud.volumes, young, poisson, options);
  return p;
}

}  // namespace

TEST(PdLean, ForcesEnergyAndDilatationEqualTheFullStorage) {
  int cases = 0;
  for (const bool planar : {false, true})
    for (const auto correction : {SurfaceCorrection::none, SurfaceCorrection::energy})
      for (const auto influence : {Influence::one, Influence::inverse_distance})
        for (const bool partial : {false, true}) {
          BodyOptions options;
          options.kinematics = planar ? Kinematics::plane_stress : Kinematics::three_dimensional;
          options.surface_correction = correction;
          options.influence = influence;
          options.partial_volume = partial;
          const Pair p = make_pair(options, planar);
          ASSERT_TRUE(p.lean_body->lean());
          ASSERT_FALSE(p.full_body->lean());
          ASSERT_EQ(p.lean_body->bonds(), p.full_body->bonds());
          const LinearPeridynamicSolid full(*p.full_body);
          const LeanPeridynamicSolid lean(*p.lean_body);
          const Index n = p.cloud.size();
          std::mt19937 gen(11);
          std::uniform_real_distribution<Real> uniform(-0.05, 0.05);
          PointMatrix u(3, n);
          for (Index k = 0; k < u.size(); ++k) u.data()[k] = uniform(gen);
          if (planar) u.row(2).setZero();
          for (const bool linearised : {false, true}) {
            const auto a = full.state_of(u, linearised), b = lean.state_of(u, linearised);
            const PointMatrix fa = full.internal_force(*a), fb = lean.internal_force(*b);
            const std::string what = fmt::format("planar {} correction {} influence {} partial {} linearised {}", planar,
                                                 static_cast<int>(correction), static_cast<int>(influence), partial, linearised);
            EXPECT_LT((fa - fb).norm(), 1e-12 * fa.norm()) << what;
            EXPECT_NEAR(lean.strain_energy(*b), full.strain_energy(*a), 1e-12 * full.strain_energy(*a)) << what;
            EXPECT_LT((lean.nodal_dilatation(*b) - full.nodal_dilatation(*a)).norm(), 1e-12 * full.nodal_dilatation(*a).norm())
                << what;
            ++cases;
          }
          EXPECT_NEAR(p.lean_body->statistics().min_bond_modulus_ratio, p.full_body->statistics().min_bond_modulus_ratio, 1e-12);
          EXPECT_NEAR(p.lean_body->statistics().max_dilatation_error, p.full_body->statistics().max_dilatation_error, 1e-12);
        }
  EXPECT_EQ(cases, 32);
}

TEST(PdLean, HasNoStiffnessAndThePlateCorrectionKeepsFullStorage) {
  BodyOptions options;
  const Pair p = make_pair(options, false);
  const LeanPeridynamicSolid lean(*p.lean_body);
  EXPECT_THROW((void)lean.stiffness(*lean.state_of(PointMatrix::Zero(3, p.cloud.size())), true, false), AnalysisError);
  options.surface_correction = SurfaceCorrection::plate;
  options.horizon = 2.015;
  options.lean_bonds = true;
  const PeridynamicBody plate(p.cloud.positions, p.cloud.volumes, Eigen::VectorXd::Constant(p.cloud.size(), 1000.0),
                              Eigen::VectorXd::Constant(p.cloud.size(), 0.3), options);
  EXPECT_FALSE(plate.lean());
}
