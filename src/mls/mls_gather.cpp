// The neighbours of an evaluation point: the nodes whose supports cover it (node-centred modes: a cell
// list query, the box or sphere test four candidates at a time) or its N nearest (VARIABLE), in ascending
// node index, with their offsets x - x_I and inverse radii as rows for the kernel (MlsShapeFunctions::gather).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

#include "mls/mls_shape_functions.hpp"
#include "mls/mls_workspace.hpp"
#include "mls/real4.hpp"

namespace lamina::mls {

namespace {
using namespace simd;  // Real4 and its helpers (mls/real4.hpp)
using detail::grow;

/// Whether values[0..n) is strictly ascending (std::adjacent_find with >=, but four comparisons at a
/// time with AVX2: it runs once per evaluation point).
bool is_ascending(const Index* values, std::size_t n) {
  std::size_t j = 1;
  bool ascending = true;
#ifdef __AVX2__
  __m256i in_order = _mm256_set1_epi64x(-1);
  for (; j + 4 <= n; j += 4) {
    const __m256i previous = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(values + j - 1));
    const __m256i current = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(values + j));
    in_order = _mm256_and_si256(in_order, _mm256_cmpgt_epi64(current, previous));
  }
  ascending = _mm256_movemask_pd(_mm256_castsi256_pd(in_order)) == 0b1111;
#endif
  for (; j < n; ++j) ascending &= values[j - 1] < values[j];
  return ascending;
}

}  // namespace

template <int Dim>
Index MlsShapeFunctions::gather(const Vec3& x, Real radius_factor, Index nearest_count,
                                detail::MlsWorkspace& workspace, Vec3& rho) const {
  const bool box = options_.shape == SupportShape::box;
  const PointMatrix& sorted = cells_.sorted_points();
  const Index* order = cells_.order().data();
  const Real inverse_factor = 1.0 / radius_factor;
  std::size_t count = 0;

  if (node_centred()) {
    // Pass 1 tests the candidates four at a time along each row of cells (lanes past the row's end are
    // masked off) and keeps the cell-order positions of the nodes whose supports cover x (about half of
    // the candidates). With AVX2 it also keeps their node indices, offsets x - x_I and inverse radii,
    // packed by a lane permutation (rows of `stride`); otherwise pass 2 writes them from the positions.
    const Vec3 reach = max_radius_ * radius_factor;
    const Vec3 low = x - reach, high = x + reach;
    const auto stride = static_cast<std::size_t>(cells_.candidate_bound(low, high) + 4);
    grow(workspace.positions, stride);
    grow(workspace.kept_nodes, stride);
    grow(workspace.offsets, 3 * stride);
    grow(workspace.inverse_radii, 3 * stride);
    Index* positions = workspace.positions.data();
    Index* kept_nodes = workspace.kept_nodes.data();
    const Index* node_of_position = sorted_order_.data();  // order() padded with 4 entries
    Real* offset_rows = workspace.offsets.data();
    Real* inverse_rows = workspace.inverse_radii.data();
    const Real* points = sorted.data();
    const Real* node_inverse_radii = sorted_inverse_radii_.data();
    const Real* rows[6];
    for (int r = 0; r < 6; ++r) rows[r] = sorted_rows_.data() + static_cast<std::size_t>(r) * row_stride_;
    const Real4 lane_index = {0.0, 1.0, 2.0, 3.0};
    cells_.for_each_candidate_range(low, high, [&](Index begin, Index end) {
      for (Index k = begin; k < end; k += 4) {
        Mask4 inside = lane_index < static_cast<Real>(end - k);
        Real4 offset[3], inverse[3];
        for (int d = 0; d < 3; ++d) {
          offset[d] = x[d] - load4(rows[d] + k);
          inverse[d] = load4(rows[3 + d] + k) * inverse_factor;
        }
        if (box) {
          for (int d = 0; d < Dim; ++d) inside &= (offset[d] < 0.0 ? -offset[d] : offset[d]) * inverse[d] < 1.0;
        } else {
          // a sphere, or an ellipsoid of per-axis radii (mode all on an anisotropic lattice)
          Real4 squared = {0.0, 0.0, 0.0, 0.0};
          for (int d = 0; d < Dim; ++d) {
            const Real4 scaled = offset[d] * inverse[d];
            squared += scaled * scaled;
          }
          inside &= squared < 1.0;
        }
#ifdef __AVX2__
        const int kept = _mm256_movemask_pd(reinterpret_cast<__m256d>(inside));
        const __m256i permutation = _mm256_load_si256(&compress_lanes[kept]);
        for (int d = 0; d < 3; ++d) {
          _mm256_storeu_pd(offset_rows + d * stride + count, compress(offset[d], permutation));
          _mm256_storeu_pd(inverse_rows + d * stride + count, compress(inverse[d], permutation));
        }
        const __m256i position = _mm256_add_epi64(_mm256_set1_epi64x(k), _mm256_setr_epi64x(0, 1, 2, 3));
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(positions + count),
                            _mm256_permutevar8x32_epi32(position, permutation));
        const __m256i node = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(node_of_position + k));
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(kept_nodes + count), _mm256_permutevar8x32_epi32(node, permutation));
        count += static_cast<std::size_t>(__builtin_popcount(static_cast<unsigned>(kept)));
#else
        for (int l = 0; l < 4; ++l) {
          positions[count] = k + l;  // branch-free: kept only if inside
          count += static_cast<std::size_t>(inside[l] & 1);
        }
#endif
      }
    });
#ifdef __AVX2__
    bool packed = true;  // the neighbours' offsets and inverse radii are in rows of `stride`
#else
    bool packed = false;
#endif
    // SELECT: of the nodes whose supports cover x, the N nearest (spacing units, ties by node index).
    workspace.capped = options_.mode == SupportMode::nearest && count > static_cast<std::size_t>(nearest_count);
    if (workspace.capped) {
      auto& ranked = workspace.nearest;  // (squared distance in spacing units, node index) per position
      ranked.resize(count);
      for (std::size_t c = 0; c < count; ++c) {
        const Real* p = points + 3 * positions[c];
        Real squared = 0.0;
        for (int d = 0; d < Dim; ++d) {
          const Real scaled = (x[d] - p[d]) * metric_[d];
          squared += scaled * scaled;
        }
        // rounded to float: nodes at equal distances on a lattice tie whatever the last bits of their
        // computed distances (rounding differs between builds), and ties go to the lower node index
        ranked[c] = {static_cast<Real>(static_cast<float>(squared)), order[positions[c]]};
      }
      grow(workspace.candidates, count);
      std::pair<Index, Index>* slots = workspace.candidates.data();  // (rank key index, position)
      for (std::size_t c = 0; c < count; ++c) slots[c] = {static_cast<Index>(c), positions[c]};
      std::nth_element(slots, slots + (nearest_count - 1), slots + count,
                       [&](const auto& a, const auto& b) { return ranked[a.first] < ranked[b.first]; });
      count = static_cast<std::size_t>(nearest_count);
      for (std::size_t c = 0; c < count; ++c) positions[c] = slots[c].second;
      packed = false;
    }
    // Pass 2: neighbour data in rows of n, ascending node index (the cells deliver structured grids
    // already sorted; otherwise the positions are sorted by node index and the data written from them).
    const auto n = count;
    workspace.indices.resize(n);
    Index* indices = workspace.indices.data();
    bool ascending = true;
    if (packed) {  // pass 1 kept the node indices as well
      std::copy(kept_nodes, kept_nodes + n, indices);
      ascending = is_ascending(indices, n);
    } else {
      for (std::size_t j = 0; j < n; ++j) {
        indices[j] = order[positions[j]];
        ascending &= j == 0 || indices[j - 1] < indices[j];
      }
    }
    const auto write = [&] {
      for (std::size_t j = 0; j < n; ++j) {
        const Index k = positions[j];
        indices[j] = order[k];
        for (int d = 0; d < 3; ++d) {
          offset_rows[d * n + j] = x[d] - points[3 * k + d];
          inverse_rows[d * n + j] = node_inverse_radii[3 * k + d] * inverse_factor;
        }
      }
    };
    Index lowest = std::numeric_limits<Index>::max(), highest = 0;
    if (!ascending)
      for (std::size_t j = 0; j < n; ++j) {
        lowest = std::min(lowest, indices[j]);
        highest = std::max(highest, indices[j]);
      }
    if (!ascending && n > 0 && highest - lowest < 64 * static_cast<Index>(n)) {
      // Ascending by a bit per node over the neighbours' index range, read back word by word: on a
      // lattice the range is a few node layers (a thin plate's cells hold every layer through the
      // thickness, so the candidates never come in node order there), and the scan of range / 64 words
      // costs less than sorting n keys.
      const auto words = static_cast<std::size_t>((highest - lowest) / 64 + 1);
      workspace.node_bits.assign(words, 0);
      std::uint64_t* bits = workspace.node_bits.data();
      for (std::size_t j = 0; j < n; ++j) {
        const auto bit = static_cast<std::uint64_t>(indices[j] - lowest);
        bits[bit / 64] |= std::uint64_t{1} << (bit % 64);
      }
      std::size_t j = 0;
      for (std::size_t w = 0; w < words; ++w)
        for (std::uint64_t word = bits[w]; word != 0; word &= word - 1)
          indices[j++] = lowest + static_cast<Index>(64 * w) + __builtin_ctzll(word);
      for (j = 0; j < n; ++j) positions[j] = position_of_node_[static_cast<std::size_t>(indices[j])];
      write();
    } else if (!ascending) {
      // sorted as (node index, candidate) keys: plain integer comparisons, where a comparator through
      // order[] loaded two node indices per comparison
      int shift = 1;
      while ((std::size_t{1} << shift) < n) ++shift;
      Index* keys = kept_nodes;  // free: the node indices are in `indices`
      for (std::size_t j = 0; j < n; ++j) keys[j] = (indices[j] << shift) | static_cast<Index>(j);
      std::sort(keys, keys + n);
      const Index mask = (Index{1} << shift) - 1;
      for (std::size_t j = 0; j < n; ++j) keys[j] = positions[keys[j] & mask];
      std::copy(keys, keys + n, positions);
      write();
    } else if (!packed) {
      write();
    }
    workspace.stride = ascending && packed ? stride : n;
    // Basis scaling rho_d: the largest support radius among the neighbours.
    // (four independent minima per direction: one serial chain of min would cost its latency per neighbour)
    constexpr Real infinity = std::numeric_limits<Real>::infinity();
    for (int d = 0; d < 3; ++d) {
      Real4 smallest = {infinity, infinity, infinity, infinity};
      const Real* inverse = inverse_rows + d * workspace.stride;
      std::size_t j = 0;
      for (; j + 4 <= n; j += 4) {
        const Real4 value = load4(inverse + j);
        smallest = value < smallest ? value : smallest;
      }
      for (; j < n; ++j) smallest[0] = std::min(smallest[0], inverse[j]);
      rho[d] = 1.0 / std::min(std::min(smallest[0], smallest[1]), std::min(smallest[2], smallest[3]));
      if (!(rho[d] > 0.0) || !std::isfinite(rho[d])) rho[d] = 1.0;
    }
    return static_cast<Index>(n);
  } else {
    // VARIABLE: the N nearest nodes of x in spacing units (metric_), weighted from x with the radius
    // scale x (distance to the N-th): a sphere or box there, an ellipsoid or box of radii
    // R_d = radius / metric_d in space.
    workspace.capped = false;
    const Vec3 scaled_x = metric_.cwiseProduct(x);
    cells_.nearest(scaled_x, nearest_count, workspace.nearest);
    const Real point_radius = workspace.nearest.empty()
                                  ? 0.0
                                  : options_.scale * (1.0 + support_epsilon) * std::sqrt(workspace.nearest.back().first);
    if (!(point_radius > 0.0)) return 0;
    const Real inverse = 1.0 / point_radius;
    Real inverses[3] = {0.0, 0.0, 0.0};
    for (int d = 0; d < Dim; ++d) inverses[d] = metric_[d] * inverse;
    // the N nearest inside that support (all of them for scale >= 1), in ascending node index
    IndexList& indices = workspace.indices;
    indices.clear();
    for (const auto& [distance_squared, index] : workspace.nearest) {
      bool inside = true;
      Real squared = 0.0;
      for (int d = 0; d < Dim; ++d) {
        const Real scaled = (x[d] - projected_(d, index)) * inverses[d];
        inside &= std::abs(scaled) < 1.0;
        squared += scaled * scaled;
      }
      if (box ? inside : squared < 1.0) indices.push_back(index);
    }
    std::sort(indices.begin(), indices.end());
    const std::size_t n = indices.size();
    grow(workspace.offsets, 3 * n);
    grow(workspace.inverse_radii, 3 * n);
    workspace.stride = n;
    for (std::size_t j = 0; j < n; ++j)
      for (int d = 0; d < 3; ++d) {
        workspace.offsets[d * n + j] = x[d] - projected_(d, indices[j]);
        workspace.inverse_radii[d * n + j] = inverses[d];
      }
    for (int d = 0; d < 3; ++d) rho[d] = d < Dim ? point_radius / metric_[d] : 1.0;
    return static_cast<Index>(n);
  }
}

template Index MlsShapeFunctions::gather<1>(const Vec3&, Real, Index, detail::MlsWorkspace&, Vec3&) const;
template Index MlsShapeFunctions::gather<2>(const Vec3&, Real, Index, detail::MlsWorkspace&, Vec3&) const;
template Index MlsShapeFunctions::gather<3>(const Vec3&, Real, Index, detail::MlsWorkspace&, Vec3&) const;

}  // namespace lamina::mls
