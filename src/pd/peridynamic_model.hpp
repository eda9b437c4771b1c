#pragma once
// PeridynamicModel: what the pd analyses (linear static, adaptive dynamic relaxation, explicit
// dynamics, linear buckling) need of a constitutive model over the nodes: internal forces, strain
// energy and stiffness of a displacement field. Implemented by LinearPeridynamicSolid (the node lattice,
// linear_peridynamic_solid.hpp; LeanPeridynamicSolid without stored bonds), PeridynamicPlate (the
// director plate model of 2-4 layer plate lattices, peridynamic_plate.hpp) and KirchhoffPlate (one-layer
// plate lattices, kirchhoff_plate.hpp).
#include <memory>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "solve/sparse_linear_solver.hpp"

namespace lamina::pd {

/// The kinematic state of one configuration, owned by the model that made it.
struct ModelState {
  virtual ~ModelState() = default;
};

class PeridynamicModel {
 public:
  virtual ~PeridynamicModel() = default;
  virtual std::string name() const = 0;
  virtual std::unique_ptr<ModelState> make_state() const = 0;
  /// State of displacement u (3 x N); linearised: small-displacement kinematics (used for the
  /// pre-buckling state of a linear buckling analysis).
  virtual void update(const PointMatrix& u, ModelState& state, bool linearised = false) const = 0;
  /// Internal nodal forces -dPi/du (3 x N).
  virtual PointMatrix internal_force(const ModelState& state) const = 0;
  virtual Real strain_energy(const ModelState& state) const = 0;
  /// Upper triangle of the 3N x 3N stiffness at a state: material part (d^2 Pi at the reference for
  /// a state of u = 0) and / or the geometric (initial stress) part.
  virtual solve::SparseMatrix stiffness(const ModelState& state, bool material, bool geometric) const = 0;
  /// A volumetric strain measure per node (output field `dilatation`).
  virtual Eigen::VectorXd nodal_dilatation(const ModelState& state) const = 0;
  /// The small-strain tensor at a node when the model defines one (the plate model: membrane strain
  /// plus height x curvature, thickness stretch, transverse shear); false: the analysis estimates it
  /// from the displacements of the node's family.
  virtual bool node_strain(const ModelState& /*state*/, Index /*node*/, Mat3& /*strain*/) const { return false; }

  std::unique_ptr<ModelState> state_of(const PointMatrix& u, bool linearised = false) const {
    auto s = make_state();
    update(u, *s, linearised);
    return s;
  }
};

/// Row sums of |K| of a symmetric matrix stored as its upper triangle.
Eigen::VectorXd absolute_row_sums(const solve::SparseMatrix& upper);

/// The dofs x dofs matrix of the triplets of every part, in part order (duplicates summed in that
/// order, so the result does not depend on which thread filled which part).
solve::SparseMatrix matrix_from_parts(const std::vector<std::vector<Eigen::Triplet<Real, int>>>& parts, Index dofs);

}  // namespace lamina::pd
