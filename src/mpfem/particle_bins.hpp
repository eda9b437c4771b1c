#pragma once
// Uniform bins over a particle set's bounding box: the particles near a point, for neighbour
// searches (five-node elements, Voronoi cells). Holds a reference to the positions.
#include <algorithm>
#include <cmath>
#include <vector>

#include "mpfem/particle_elements.hpp"

namespace lamina::mpfem {

class ParticleBins {
 public:
  ParticleBins(const Points2& x, Real cell) : x_(x), cell_(cell) {
    lower_ = x.rowwise().minCoeff();
    const Vec2 upper = x.rowwise().maxCoeff();
    nx_ = std::max<Index>(1, static_cast<Index>((upper.x() - lower_.x()) / cell_) + 1);
    ny_ = std::max<Index>(1, static_cast<Index>((upper.y() - lower_.y()) / cell_) + 1);
    bins_.resize(static_cast<std::size_t>(nx_ * ny_));
    for (Index p = 0; p < x.cols(); ++p) bins_[static_cast<std::size_t>(bin_of(x.col(p)))].push_back(p);
  }
  /// Calls f(q) for every particle q in the bins within `radius` of point p (superset).
  template <class F>
  void for_each_near(const Vec2& p, Real radius, F&& f) const {
    const Index r = static_cast<Index>(std::ceil(radius / cell_));
    const Index bx = coord(p.x() - lower_.x(), nx_), by = coord(p.y() - lower_.y(), ny_);
    for (Index j = std::max<Index>(0, by - r); j <= std::min(ny_ - 1, by + r); ++j)
      for (Index i = std::max<Index>(0, bx - r); i <= std::min(nx_ - 1, bx + r); ++i)
        for (Index q : bins_[static_cast<std::size_t>(i + nx_ * j)]) f(q);
  }

 private:
  Index coord(Real offset, Index n) const { return std::clamp<Index>(static_cast<Index>(offset / cell_), 0, n - 1); }
  Index bin_of(const Vec2& p) const { return coord(p.x() - lower_.x(), nx_) + nx_ * coord(p.y() - lower_.y(), ny_); }
  const Points2& x_;
  Real cell_;
  Vec2 lower_;
  Index nx_ = 1, ny_ = 1;
  std::vector<IndexList> bins_;
};

}  // namespace lamina::mpfem
