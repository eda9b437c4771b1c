#pragma once
// The MLS approximation of a vector field at one point from the nodal parameters u (3 per node):
// u^h = sum_I phi_I u_I, grad u^h = sum_I u_I dphi_I^T (seed 004 eq 1-14), and the local (3 per
// neighbour) gather / scatter of a global vector.
#include "core/types.hpp"
#include "mls/mls_shape_functions.hpp"

namespace lamina::efg {

inline Vec3 value_of(const mls::ShapeFunctionValues& sv, const Eigen::VectorXd& u) {
  Vec3 v = Vec3::Zero();
  for (std::size_t k = 0; k < sv.neighbours.size(); ++k) v += sv.phi[static_cast<Index>(k)] * u.segment<3>(3 * sv.neighbours[k]);
  return v;
}

inline Mat3 gradient_of(const mls::ShapeFunctionValues& sv, const Eigen::VectorXd& u) {
  Mat3 G = Mat3::Zero();
  for (std::size_t k = 0; k < sv.neighbours.size(); ++k)
    G += u.segment<3>(3 * sv.neighbours[k]) * sv.dphi.col(static_cast<Index>(k)).transpose();
  return G;
}

/// The local dofs (3 per neighbour) of a global vector.
inline Eigen::VectorXd gather(const mls::ShapeFunctionValues& sv, const Eigen::VectorXd& u) {
  Eigen::VectorXd local(3 * static_cast<Index>(sv.neighbours.size()));
  for (std::size_t k = 0; k < sv.neighbours.size(); ++k) local.segment<3>(3 * static_cast<Index>(k)) = u.segment<3>(3 * sv.neighbours[k]);
  return local;
}

/// global += the local vector (3 per neighbour).
inline void scatter_vector(const mls::ShapeFunctionValues& sv, const Eigen::VectorXd& local, Eigen::VectorXd& global) {
  for (std::size_t k = 0; k < sv.neighbours.size(); ++k)
    global.segment<3>(3 * sv.neighbours[k]) += local.segment<3>(3 * static_cast<Index>(k));
}

}  // namespace lamina::efg
