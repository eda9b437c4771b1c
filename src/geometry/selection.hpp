#pragma once
// Selections of nodes/particles, the case file's `select:` forms: where (an expression over
// x y z r theta), nearest (the single closest node), box, set (a named node set), all.
#include <map>
#include <string>

#include "core/types.hpp"

namespace lamina::geometry {

struct SelectionSpec {
  enum class Kind { all, where, nearest, box, set };
  Kind kind = Kind::all;
  std::string expression;  // where
  Vec3 point = Vec3::Zero();  // nearest
  Vec3 box_min = Vec3::Zero(), box_max = Vec3::Zero();
  std::string set_name;
  std::string describe() const;
};

/// Indices of the points selected (sorted, unique). Throws ExpressionError for a bad
/// expression and std::out_of_range naming the set if `set` is unknown. May be empty.
IndexList resolve_selection(const SelectionSpec& spec, const PointMatrix& points,
                            const std::map<std::string, IndexList>& sets);

/// The index of the point closest to x (first one on ties).
Index nearest_point(const PointMatrix& points, const Vec3& x);

}  // namespace lamina::geometry
