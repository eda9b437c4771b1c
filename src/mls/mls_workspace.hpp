#pragma once
// Per-thread scratch memory of the MLS evaluation (the neighbour gather and the kernel share it), and
// the grow-only resize they use. Internal to src/mls.
#include <cstdint>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "core/types.hpp"

namespace lamina::mls::detail {

/// Per-thread scratch memory; vectors keep their capacity between evaluations.
struct MlsWorkspace {
  std::vector<std::pair<Index, Index>> candidates;  // SELECT: (rank key index, cell-order position); grow-only
  std::vector<std::pair<Real, Index>> nearest;
  std::vector<Index> positions;     // node-centred gather: cell-order positions of the neighbours
  std::vector<Index> kept_nodes;    // node-centred gather (AVX2): their node indices; grow-only
  std::vector<std::uint64_t> node_bits;  // node-centred gather: the neighbours as bits over their index range
  bool capped = false;              // SELECT: the last gather() kept only the N nearest covering nodes
  IndexList indices;                // neighbours, ascending
  // structure of arrays, n per row (row d at d * stride): x_d - x_I,d and 1 / R_I,d of the n neighbours
  std::vector<Real> offsets;
  std::vector<Real> inverse_radii;
  std::size_t stride = 0;
  std::vector<Real> weights;        // 10 arrays of n: w, w_x, w_y, w_z, w_xx, w_yy, w_zz, w_xy, w_yz, w_zx
  std::vector<Real> basis;          // n x m, column k = basis term k at the neighbours
  std::vector<Real> scratch;        // n x max(9, m): weight factors; p_I.r, p_I.r_,i, combined terms, weighted column / n x m
  // Output storage by neighbour count (slot k: empty, or k values / columns), see fit_size.
  std::vector<Eigen::VectorXd> phi_by_size;
  std::vector<Eigen::Matrix3Xd> dphi_by_size;
};

/// Resizes `vector` to at least `size` entries (never shrinks: the capacity is kept between points).
template <class Vector>
inline void grow(Vector& vector, std::size_t size) {
  if (vector.size() < size) vector.resize(size);
}

}  // namespace lamina::mls::detail
