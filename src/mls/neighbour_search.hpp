#pragma once
// Uniform-bin cell list over a point set for box/sphere range queries and k-nearest queries; used to
// find the nodes whose supports contain an evaluation point (the MLS neighbours of seed 004).
#include <algorithm>
#include <utility>
#include <vector>

#include "core/types.hpp"

namespace lamina::mls {

/// Points are copied into cell order (cells are x-fastest, so the cells of one x-row are contiguous).
/// Query methods are const and thread-safe.
class CellList {
 public:
  CellList() = default;
  /// cell_size > 0: edge of the cubic bins. The number of cells is capped at about 2 N + 64
  /// (the edge grows when needed), so a too small cell size only costs speed.
  CellList(const PointMatrix& points, Real cell_size);

  Index size() const { return static_cast<Index>(order_.size()); }
  Real cell_size() const { return cell_size_; }
  /// order()[k] = index of the point stored at cell-order position k.
  const std::vector<Index>& order() const { return order_; }
  /// Points in cell order (column k = point order()[k]).
  const PointMatrix& sorted_points() const { return sorted_points_; }

  /// Calls visit(k) for every cell-order position k whose cell overlaps the box [low, high]
  /// (a superset of the points inside; the caller filters).
  template <class Visitor>
  void for_each_candidate(const Vec3& low, const Vec3& high, Visitor&& visit) const {
    for_each_candidate_range(low, high, [&](Index begin, Index end) {
      for (Index k = begin; k < end; ++k) visit(k);
    });
  }

  /// The same by contiguous ranges: calls visit(begin, end) once per row of cells (positions
  /// begin..end-1, possibly empty).
  template <class Visitor>
  void for_each_candidate_range(const Vec3& low, const Vec3& high, Visitor&& visit) const {
    if (order_.empty()) return;
    int first[3];
    int last[3];
    for (int d = 0; d < 3; ++d) {
      if (high[d] < origin_[d] || low[d] > top_[d]) return;
      first[d] = cell_coordinate(low[d], d);
      last[d] = cell_coordinate(high[d], d);
    }
    for (int z = first[2]; z <= last[2]; ++z) {
      for (int y = first[1]; y <= last[1]; ++y) {
        const Index row = (static_cast<Index>(z) * counts_[1] + y) * counts_[0];
        visit(cell_start_[row + first[0]], cell_start_[row + last[0] + 1]);
      }
    }
  }

  /// An upper bound of the number of points for_each_candidate(low, high, ...) visits, from the number
  /// of cells the box overlaps times the most points in one cell (no walk over the cells; for buffers).
  Index candidate_bound(const Vec3& low, const Vec3& high) const {
    if (order_.empty()) return 0;
    Index cells = 1;
    for (int d = 0; d < 3; ++d) {
      if (high[d] < origin_[d] || low[d] > top_[d]) return 0;
      cells *= cell_coordinate(high[d], d) - cell_coordinate(low[d], d) + 1;
    }
    return std::min(size(), cells * max_per_cell_);
  }

  /// Indices of the points with low <= p <= high (componentwise), sorted ascending.
  void points_in_box(const Vec3& low, const Vec3& high, IndexList& out) const;
  /// Indices of the points with |p - centre| <= radius, sorted ascending.
  void points_in_sphere(const Vec3& centre, Real radius, IndexList& out) const;
  /// The k nearest points of x (ties broken by the lower index), as (squared distance, index)
  /// sorted by increasing distance; `exclude` (if >= 0) is skipped. Returns min(k, size()) entries
  /// (fewer if `exclude` is a point).
  void nearest(const Vec3& x, Index k, std::vector<std::pair<Real, Index>>& out, Index exclude = -1) const;

 private:
  int cell_coordinate(Real value, int d) const {
    const Real scaled = (value - origin_[d]) * inverse_cell_size_;
    if (!(scaled > 0.0)) return 0;
    const Real last = counts_[d] - 1;
    return scaled >= last ? counts_[d] - 1 : static_cast<int>(scaled);
  }

  Real cell_size_ = 1.0;
  Real inverse_cell_size_ = 1.0;
  Vec3 origin_ = Vec3::Zero();
  Vec3 top_ = Vec3::Zero();
  int counts_[3] = {1, 1, 1};
  Index max_per_cell_ = 0;  // the most points in one cell
  std::vector<Index> cell_start_;  // cells + 1 offsets into order_
  std::vector<Index> order_;
  PointMatrix sorted_points_;
};

}  // namespace lamina::mls
