#pragma once
// PlateColumns: the node columns of a plate lattice - nodes that share their in-plane position and
// differ only in height, 1-4 layers through the thickness - and the through-thickness maps of the
// director plate model of 2-4 layers (peridynamic_plate.hpp; one layer: kirchhoff_plate.hpp): mid-surface
// m = sum_k phi_k x_k (volume-weighted
// mean), director a = sum_k psi_k x_k (least-squares slope of x over the layer height zeta_k, so
// a = e_z on the undeformed plate), and the layer residual r_k = x_k - m - zeta_k a (3-4 layers).
#include <optional>
#include <string>
#include <vector>

#include "core/types.hpp"

namespace lamina::pd {

struct PlateColumns {
  std::vector<Index> first;       // column c has nodes node[first[c] .. first[c + 1]), bottom to top
  std::vector<Index> node;
  std::vector<Index> column_of;   // per node
  Eigen::VectorXd phi, psi, zeta; // per node: mid-surface and director weights, height above the mid-surface
  int layers = 0;
  Real thickness = 0;             // layers x layer spacing (nodes at the cell centres); one layer: volume / cell area
  Real spacing = 0;               // smallest in-plane distance between column centres
  Index columns() const { return static_cast<Index>(first.size()) - 1; }
};

/// The columns of a 3D node cloud that is a plate lattice: every node in a column of the same 2-4
/// layers at the same heights (1-4), evenly spaced, the in-plane extent at least 4 thicknesses both ways.
/// Returns nullopt (with why in *reason) otherwise - the lattice model then applies.
std::optional<PlateColumns> find_plate_columns(const PointMatrix& positions, const Eigen::VectorXd& volumes,
                                               std::string* reason = nullptr);

}  // namespace lamina::pd
