#include "mpm/background_grid.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/error.hpp"

namespace lamina::mpm {

namespace {

constexpr std::int64_t kOffset = std::int64_t(1) << 20;
constexpr std::int64_t kMask = (std::int64_t(1) << 21) - 1;
constexpr std::int64_t kNotLocated = -1;  // cell_of_corner_ of a corner locate() left out (never a packed key)

std::int64_t pack(std::int64_t i, std::int64_t j, std::int64_t k) {
  return ((i + kOffset) & kMask) | (((j + kOffset) & kMask) << 21) | (((k + kOffset) & kMask) << 42);
}

}  // namespace

BackgroundGrid::BackgroundGrid(const Vec3& origin, Real cell) : origin_(origin), cell_(cell) {}

Vec3 BackgroundGrid::node_position(Index slot) const {
  const std::int64_t key = slot_key_[static_cast<std::size_t>(slot)];
  const std::int64_t i = (key & kMask) - kOffset, j = ((key >> 21) & kMask) - kOffset, k = ((key >> 42) & kMask) - kOffset;
  return origin_ + cell_ * Vec3(static_cast<Real>(i), static_cast<Real>(j), static_cast<Real>(k));
}

bool BackgroundGrid::locate(const PointMatrix& x, const std::vector<char>* include) {
  const Index n = x.cols();
  const std::size_t entries = static_cast<std::size_t>(n) * kNodesPerCorner;
  const bool resized = cell_of_corner_.size() != static_cast<std::size_t>(n);
  if (resized) {
    cell_of_corner_.assign(static_cast<std::size_t>(n), kNotLocated);
    weight_.assign(entries, 0.0);
    key_of_entry_.assign(entries, 0);
    slot_of_entry_.assign(entries, 0);
  }
  int changed = resized ? 1 : 0;
  corner_moved_.resize(static_cast<std::size_t>(n));
  const Real inv = 1.0 / cell_;
  bool finite = true;
#pragma omp parallel for schedule(static) reduction(| : changed) reduction(&& : finite) if (n > 1024)
  for (Index c = 0; c < n; ++c) {
    const auto cs = static_cast<std::size_t>(c);
    corner_moved_[cs] = 0;
    if (include && !(*include)[cs]) {  // left out: no entries, no weights
      if (cell_of_corner_[cs] != kNotLocated) {
        cell_of_corner_[cs] = kNotLocated;
        corner_moved_[cs] = 1;
        changed = 1;
      }
      continue;
    }
    const Vec3 s = (x.col(c) - origin_) * inv;
    if (!s.allFinite() || s.cwiseAbs().maxCoeff() > static_cast<Real>(kOffset - 2)) {
      finite = false;
      continue;
    }
    const std::int64_t i = static_cast<std::int64_t>(std::floor(s.x())), j = static_cast<std::int64_t>(std::floor(s.y())),
                       k = static_cast<std::int64_t>(std::floor(s.z()));
    const Real fx = s.x() - static_cast<Real>(i), fy = s.y() - static_cast<Real>(j), fz = s.z() - static_cast<Real>(k);
    const std::int64_t key = pack(i, j, k);
    if (key != cell_of_corner_[cs]) {
      cell_of_corner_[cs] = key;
      corner_moved_[cs] = 1;
      changed = 1;
      for (int a = 0; a < kNodesPerCorner; ++a)
        key_of_entry_[static_cast<std::size_t>(c * kNodesPerCorner + a)] = pack(i + (a & 1), j + ((a >> 1) & 1), k + ((a >> 2) & 1));
    }
    for (int a = 0; a < kNodesPerCorner; ++a) {
      const Real wx = (a & 1) ? fx : 1.0 - fx, wy = ((a >> 1) & 1) ? fy : 1.0 - fy, wz = ((a >> 2) & 1) ? fz : 1.0 - fz;
      weight_[static_cast<std::size_t>(c * kNodesPerCorner + a)] = wx * wy * wz;
    }
  }
  if (!finite) check_range(x);  // throws
  if (!changed) return false;
  // (key, entry) pairs of the located corners in sorted order (unique pairs: the order is deterministic).
  // After the first sort only the entries of corners that changed cell (or joined) are sorted and merged
  // into the rest, whose pairs are compacted in place (those of corners that moved or left dropped).
  moved_.clear();
  for (Index c = 0; c < n; ++c)
    if ((resized || corner_moved_[static_cast<std::size_t>(c)]) && cell_of_corner_[static_cast<std::size_t>(c)] != kNotLocated)
      for (Index e = c * kNodesPerCorner; e < (c + 1) * kNodesPerCorner; ++e) moved_.emplace_back(key_of_entry_[static_cast<std::size_t>(e)], e);
  std::sort(moved_.begin(), moved_.end());
  if (resized) {
    key_entry_.swap(moved_);
  } else {
    const auto kept_end = std::remove_if(key_entry_.begin(), key_entry_.end(), [&](const std::pair<std::int64_t, Index>& ke) {
      return corner_moved_[static_cast<std::size_t>(ke.second / kNodesPerCorner)] != 0;
    });
    merged_.resize(static_cast<std::size_t>(kept_end - key_entry_.begin()) + moved_.size());
    std::merge(key_entry_.begin(), kept_end, moved_.begin(), moved_.end(), merged_.begin());
    key_entry_.swap(merged_);
  }
  // slots: one per distinct key, in key order; one pass over the sorted pairs
  const std::size_t located = key_entry_.size();
  sorted_entries_.resize(located);
  slot_begin_.resize(located + 1);
  slot_key_.resize(located);
  std::size_t slots = 0;
  for (std::size_t s = 0; s < located; ++s) {
    const auto& [key, entry] = key_entry_[s];
    sorted_entries_[s] = entry;
    if (slots == 0 || slot_key_[slots - 1] != key) {
      slot_key_[slots] = key;
      slot_begin_[slots] = static_cast<Index>(s);
      ++slots;
    }
    slot_of_entry_[static_cast<std::size_t>(entry)] = static_cast<Index>(slots) - 1;
  }
  slot_key_.resize(slots);
  slot_begin_.resize(slots + 1);
  slot_begin_[slots] = static_cast<Index>(located);
  ++connectivity_version_;
  return true;
}

void BackgroundGrid::scatter(const PointMatrix& q, const Eigen::Matrix3Xd& mask, Eigen::Matrix3Xd& grid) const {
  const Index slots = active_nodes();
  grid.resize(3, slots);
#pragma omp parallel for schedule(static) if (slots > 4096)
  for (Index s = 0; s < slots; ++s) {
    Vec3 sum = Vec3::Zero();
    for (const Index* e = slot_entries_begin(s); e != slot_entries_end(s); ++e) {
      const Index c = *e / kNodesPerCorner;
      sum += weight_[static_cast<std::size_t>(*e)] * q.col(c).cwiseProduct(mask.col(c));
    }
    grid.col(s) = sum;
  }
}

void BackgroundGrid::scatter_mass_momentum_force(const Eigen::VectorXd& mass, const PointMatrix& velocity,
                                                 const PointMatrix& force, const Eigen::Matrix3Xd& mask,
                                                 Eigen::Matrix3Xd& grid_mass, Eigen::Matrix3Xd& grid_momentum,
                                                 Eigen::Matrix3Xd& grid_force) const {
  const Index active = active_nodes();
  grid_mass.resize(3, active);
  grid_momentum.resize(3, active);
  grid_force.resize(3, active);
  scatter_and_finish(mass, velocity, force, mask, [&](Index s, const Vec3& m, const Vec3& p, const Vec3& f) {
    grid_mass.col(s) = m;
    grid_momentum.col(s) = p;
    grid_force.col(s) = f;
  });
}

bool BackgroundGrid::covers(const Vec3& lowest, const Vec3& highest) const {
  const Real limit = static_cast<Real>(kOffset - 2);
  const Vec3 low = (lowest - origin_) / cell_, high = (highest - origin_) / cell_;
  return low.allFinite() && high.allFinite() && (low.array() >= -limit).all() && (high.array() <= limit).all();
}

void BackgroundGrid::check_range(const PointMatrix& x) const {
  if (x.cols() == 0) return;
  const Real limit = static_cast<Real>(kOffset - 2);  // the extreme corners decide (as locate()'s test per corner)
  const Vec3 low = (x.rowwise().minCoeff() - origin_) / cell_, high = (x.rowwise().maxCoeff() - origin_) / cell_;
  if (!x.allFinite() || (low.array() < -limit).any() || (high.array() > limit).any())
    throw AnalysisError("a shell node left the background grid's range (non-finite or runaway position)");
}

void BackgroundGrid::gather(const Eigen::Matrix3Xd& grid, PointMatrix& q, Index first, Index last) const {
  q.resize(3, static_cast<Index>(cell_of_corner_.size()));
#pragma omp parallel for schedule(static) if (last - first > 1024)
  for (Index c = first; c < last; ++c) {
    Vec3 sum = Vec3::Zero();
    for (int a = 0; a < kNodesPerCorner; ++a) sum += weight(c, a) * grid.col(slot(c, a));
    q.col(c) = sum;
  }
}

void BackgroundGrid::gather(const Eigen::Matrix3Xd& grid, PointMatrix& q) const {
  const Index n = static_cast<Index>(cell_of_corner_.size());
  q.resize(3, n);
#pragma omp parallel for schedule(static) if (n > 1024)
  for (Index c = 0; c < n; ++c) {
    Vec3 sum = Vec3::Zero();
    for (int a = 0; a < kNodesPerCorner; ++a) sum += weight(c, a) * grid.col(slot(c, a));
    q.col(c) = sum;
  }
}

}  // namespace lamina::mpm
