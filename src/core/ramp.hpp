#pragma once
// How a load or prescribed value grows over an analysis: linear, a step, or a piecewise-linear
// table of (s, factor). One type for every family (read once, in io/case_reader.cpp).
#include <array>
#include <vector>

#include "core/types.hpp"

namespace lamina {

/// s is the analysis' progress: the load factor of an incremental static run, or the time of a
/// dynamic one; a table's first column is in the same measure (rows increasing in s).
struct Ramp {
  enum class Kind { linear, step, table };
  Kind kind = Kind::linear;
  std::vector<std::array<Real, 2>> table;  // (s, factor) rows for Kind::table
  /// The factor at progress s of a run that ends at s = end: linear s / end clamped to [0, 1] (1 when
  /// end <= 0), step 1, table interpolated linearly and held constant beyond its ends (1 when empty).
  Real factor(Real s, Real end = 1.0) const;
};

}  // namespace lamina
