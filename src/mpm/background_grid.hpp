#pragma once
// Sparse uniform background grid with trilinear shape functions S_I(x) for the two-step CPDI2
// mapping (domain corners -> grid nodes), seed 000 eqs (1)-(9): only grid nodes touched by a corner exist.
//
// Storage: every corner c touches the 8 nodes of its cell; the (grid key, corner) pairs are sorted by
// key once per connectivity change, which gives each active grid node a slot and a contiguous list of
// the corners it receives from. P2G is then a gather per slot and G2P a gather per corner: no atomics,
// results independent of the thread count. The connectivity is rebuilt only when a corner changes cell.
#include <cstdint>
#include <vector>

#include "core/types.hpp"

namespace lamina::mpm {

class BackgroundGrid {
 public:
  static constexpr int kNodesPerCorner = 8;

  /// origin: a grid node; cell: the uniform cell size (> 0).
  BackgroundGrid(const Vec3& origin, Real cell);

  Real cell() const { return cell_; }
  const Vec3& origin() const { return origin_; }

  /// Locate the corners x (3 x N): weights always, connectivity when a corner changed cell.
  /// include (size N, optional): only the corners marked non-zero are located and scatter; the others
  /// have no entries and no weights (several ranks: the corners near a rank's block, docs/scaling.md).
  /// Every slot's sum runs over its located corners in corner order, so a slot all of whose corners are
  /// included sums the same bits as with every corner located. Returns true when the slots were rebuilt.
  bool locate(const PointMatrix& x, const std::vector<char>* include = nullptr);

  Index active_nodes() const { return static_cast<Index>(slot_begin_.size()) - 1; }
  /// Weight S_I(x_c) of the k-th grid node of corner c (k < 8) and that node's slot.
  Real weight(Index corner, int k) const { return weight_[static_cast<std::size_t>(corner * kNodesPerCorner + k)]; }
  Index slot(Index corner, int k) const { return slot_of_entry_[static_cast<std::size_t>(corner * kNodesPerCorner + k)]; }
  /// Entries (corner * 8 + k) that scatter to one slot, in a fixed order.
  const Index* slot_entries_begin(Index slot) const { return sorted_entries_.data() + slot_begin_[static_cast<std::size_t>(slot)]; }
  const Index* slot_entries_end(Index slot) const { return sorted_entries_.data() + slot_begin_[static_cast<std::size_t>(slot + 1)]; }
  /// Position of an active grid node.
  Vec3 node_position(Index slot) const;

  /// P2G: grid value g_I = sum_c S_I(x_c) q_c for a 3 x N corner array (mask: per component, 0 or 1).
  void scatter(const PointMatrix& q, const Eigen::Matrix3Xd& mask, Eigen::Matrix3Xd& grid) const;
  /// G2P: corner value q_c = sum_I S_I(x_c) g_I.
  void gather(const Eigen::Matrix3Xd& grid, PointMatrix& q) const;

  /// P2G of a step in one pass over the entries: mass m_c, momentum m_c v_c and force f_c per free
  /// component (mask), the same sums as three scatter() calls.
  void scatter_mass_momentum_force(const Eigen::VectorXd& mass, const PointMatrix& velocity, const PointMatrix& force,
                                   const Eigen::Matrix3Xd& mask, Eigen::Matrix3Xd& grid_mass, Eigen::Matrix3Xd& grid_momentum,
                                   Eigen::Matrix3Xd& grid_force) const;

  /// P2G with the grid update in the same pass: for every slot, the sums m_I, p_I, f_I of
  /// scatter_mass_momentum_force (Vec3 each, per free component) are handed to finish(slot, m, p, f),
  /// which turns them into the slot's grid values while they are in registers (no grid arrays of mass,
  /// momentum and force are written and read back). Threads split the slots; results do not depend on
  /// the thread count.
  template <class Finish>
  void scatter_and_finish(const Eigen::VectorXd& mass, const PointMatrix& velocity, const PointMatrix& force,
                          const Eigen::Matrix3Xd& mask, Finish&& finish) const {
    const Index active = active_nodes(), corners = mass.size();
    // each corner's three masked terms packed once into 9 adjacent values: a slot's entries then read one
    // record per corner instead of four arrays (the same products, so the same bits as forming them per entry)
    corner_terms_.resize(static_cast<std::size_t>(9 * corners));
    Real* terms = corner_terms_.data();
#pragma omp parallel if (active > 4096)
    {
#pragma omp for schedule(static)
      for (Index c = 0; c < corners; ++c) {
        const Vec3 free = mask.col(c);
        Eigen::Map<Vec3>(terms + 9 * c) = Vec3::Constant(mass[c]).cwiseProduct(free);
        Eigen::Map<Vec3>(terms + 9 * c + 3) = (mass[c] * velocity.col(c)).cwiseProduct(free);
        Eigen::Map<Vec3>(terms + 9 * c + 6) = force.col(c).cwiseProduct(free);
      }
#pragma omp for schedule(static)
      for (Index s = 0; s < active; ++s) {
        Vec3 m = Vec3::Zero(), p = Vec3::Zero(), f = Vec3::Zero();
        for (const Index* e = slot_entries_begin(s); e != slot_entries_end(s); ++e) {
          const Real* t = terms + 9 * (*e / kNodesPerCorner);
          const Real w = weight_[static_cast<std::size_t>(*e)];
          m += w * Eigen::Map<const Vec3>(t);
          p += w * Eigen::Map<const Vec3>(t + 3);
          f += w * Eigen::Map<const Vec3>(t + 6);
        }
        finish(s, m, p, f);
      }
    }
  }

  /// G2P of two grid arrays in one pass over the corners [first, last): a_c = sum_I S_I(x_c) a_I and
  /// b_c likewise are handed to finish(c, a_c, b_c) (no corner arrays written and read back). Threads
  /// split the corners.
  template <class Finish>
  void gather_and_finish(const Eigen::Matrix3Xd& grid_a, const Eigen::Matrix3Xd& grid_b, Index first, Index last,
                         Finish&& finish) const {
#pragma omp parallel for schedule(static) if (last - first > 1024)
    for (Index c = first; c < last; ++c) {
      Vec3 a = Vec3::Zero(), b = Vec3::Zero();
      for (int k = 0; k < kNodesPerCorner; ++k) {
        const Real w = weight(c, k);
        const Index s = slot(c, k);
        a += w * grid_a.col(s);
        b += w * grid_b.col(s);
      }
      finish(c, a, b);
    }
  }

  /// Counts the connectivity rebuilds of locate().
  Index connectivity_version() const { return connectivity_version_; }
  /// Throws AnalysisError when a corner of x is non-finite or outside the grid's index range (the
  /// check locate() makes, here for every corner however locate() is restricted).
  void check_range(const PointMatrix& x) const;
  /// Whether every point of the box [lowest, highest] lies in the grid's index range.
  bool covers(const Vec3& lowest, const Vec3& highest) const;
  /// gather() of the corners [first, last) only (q is sized to all corners; the others unspecified).
  void gather(const Eigen::Matrix3Xd& grid, PointMatrix& q, Index first, Index last) const;

 private:
  Vec3 origin_;
  Real cell_;
  std::vector<std::int64_t> cell_of_corner_;  // packed cell key of each corner
  std::vector<Real> weight_;                  // 8 per corner
  std::vector<std::int64_t> key_of_entry_;
  std::vector<Index> slot_of_entry_;
  std::vector<Index> sorted_entries_;
  std::vector<std::pair<std::int64_t, Index>> key_entry_;  // (cell key, entry), sorted
  std::vector<std::pair<std::int64_t, Index>> moved_, merged_;  // scratch of locate()'s re-sort
  std::vector<char> corner_moved_;                            // corner changed cell in this locate()
  std::vector<Index> slot_begin_{0};
  mutable std::vector<Real> corner_terms_;  // scatter_and_finish's packed corner terms (kept: no allocation per step)
  Index connectivity_version_ = 0;
  std::vector<std::int64_t> slot_key_;
};

}  // namespace lamina::mpm
