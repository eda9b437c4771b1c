#include "mls/neighbour_search.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace lamina::mls {

CellList::CellList(const PointMatrix& points, Real cell_size) {
  const Index count = points.cols();
  if (count == 0) return;
  if (!(cell_size > 0.0) || !std::isfinite(cell_size)) throw std::invalid_argument("CellList: cell size must be positive");
  origin_ = points.rowwise().minCoeff();
  top_ = points.rowwise().maxCoeff();
  const Vec3 extent = top_ - origin_;
  // Cap the number of cells at about 2 N + 64 so memory stays linear in N.
  const double cap = 2.0 * static_cast<double>(count) + 64.0;
  for (;;) {
    double cells = 1.0;
    for (int d = 0; d < 3; ++d) cells *= std::floor(extent[d] / cell_size) + 1.0;
    if (cells <= cap) break;
    cell_size *= 1.25;
  }
  cell_size_ = cell_size;
  inverse_cell_size_ = 1.0 / cell_size;
  for (int d = 0; d < 3; ++d) counts_[d] = static_cast<int>(std::floor(extent[d] / cell_size)) + 1;

  const Index cells = static_cast<Index>(counts_[0]) * counts_[1] * counts_[2];
  std::vector<Index> cell_of(count);
  cell_start_.assign(cells + 1, 0);
  for (Index i = 0; i < count; ++i) {
    const Index cell = (static_cast<Index>(cell_coordinate(points(2, i), 2)) * counts_[1] +
                        cell_coordinate(points(1, i), 1)) * counts_[0] +
                       cell_coordinate(points(0, i), 0);
    cell_of[i] = cell;
    ++cell_start_[cell + 1];
  }
  for (Index c = 0; c < cells; ++c) max_per_cell_ = std::max(max_per_cell_, cell_start_[c + 1]);
  for (Index c = 0; c < cells; ++c) cell_start_[c + 1] += cell_start_[c];
  order_.resize(count);
  std::vector<Index> fill(cell_start_.begin(), cell_start_.end() - 1);
  for (Index i = 0; i < count; ++i) order_[fill[cell_of[i]]++] = i;  // stable: ascending index per cell
  sorted_points_.resize(3, count);
  for (Index k = 0; k < count; ++k) sorted_points_.col(k) = points.col(order_[k]);
}

void CellList::points_in_box(const Vec3& low, const Vec3& high, IndexList& out) const {
  out.clear();
  for_each_candidate(low, high, [&](Index k) {
    const auto p = sorted_points_.col(k);
    if ((p.array() >= low.array()).all() && (p.array() <= high.array()).all()) out.push_back(order_[k]);
  });
  std::sort(out.begin(), out.end());
}

void CellList::points_in_sphere(const Vec3& centre, Real radius, IndexList& out) const {
  out.clear();
  const Vec3 reach = Vec3::Constant(radius);
  const Real radius_squared = radius * radius;
  for_each_candidate(centre - reach, centre + reach, [&](Index k) {
    if ((sorted_points_.col(k) - centre).squaredNorm() <= radius_squared) out.push_back(order_[k]);
  });
  std::sort(out.begin(), out.end());
}

void CellList::nearest(const Vec3& x, Index k, std::vector<std::pair<Real, Index>>& out, Index exclude) const {
  out.clear();
  if (k <= 0 || order_.empty()) return;
  // Max-heap of the best k candidates, ordered by (squared distance, index).
  auto worse = [](const std::pair<Real, Index>& a, const std::pair<Real, Index>& b) { return a < b; };
  int centre[3];
  for (int d = 0; d < 3; ++d) centre[d] = cell_coordinate(x[d], d);
  const int max_ring = std::max({counts_[0], counts_[1], counts_[2]});
  auto visit_cell_range = [&](int z, int y, int x_first, int x_last) {
    const Index row = (static_cast<Index>(z) * counts_[1] + y) * counts_[0];
    const Index begin = cell_start_[row + x_first];
    const Index end = cell_start_[row + x_last + 1];
    for (Index position = begin; position < end; ++position) {
      const Index index = order_[position];
      if (index == exclude) continue;
      const std::pair<Real, Index> candidate{(sorted_points_.col(position) - x).squaredNorm(), index};
      if (static_cast<Index>(out.size()) < k) {
        out.push_back(candidate);
        std::push_heap(out.begin(), out.end(), worse);
      } else if (candidate < out.front()) {
        std::pop_heap(out.begin(), out.end(), worse);
        out.back() = candidate;
        std::push_heap(out.begin(), out.end(), worse);
      }
    }
  };
  for (int ring = 0; ring <= max_ring; ++ring) {
    const int z_first = std::max(0, centre[2] - ring), z_last = std::min(counts_[2] - 1, centre[2] + ring);
    const int y_first = std::max(0, centre[1] - ring), y_last = std::min(counts_[1] - 1, centre[1] + ring);
    const int x_first = std::max(0, centre[0] - ring), x_last = std::min(counts_[0] - 1, centre[0] + ring);
    for (int z = z_first; z <= z_last; ++z) {
      const bool z_face = std::abs(z - centre[2]) == ring;
      for (int y = y_first; y <= y_last; ++y) {
        if (z_face || std::abs(y - centre[1]) == ring) {
          visit_cell_range(z, y, x_first, x_last);
        } else {
          if (centre[0] - ring >= 0) visit_cell_range(z, y, centre[0] - ring, centre[0] - ring);
          if (ring > 0 && centre[0] + ring < counts_[0]) visit_cell_range(z, y, centre[0] + ring, centre[0] + ring);
        }
      }
    }
    // Every point in ring + 1 or further is at least ring * cell_size away from x (the factor
    // guards against points rounded into the neighbouring cell).
    if (static_cast<Index>(out.size()) == k) {
      const Real bound = ring * cell_size_ * (1.0 - 1e-9);
      if (out.front().first < bound * bound) break;
    }
  }
  std::sort_heap(out.begin(), out.end(), worse);
}

}  // namespace lamina::mls
