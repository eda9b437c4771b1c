#include "geometry/selection.hpp"

#include <fmt/format.h>

#include <stdexcept>

#include "geometry/expression.hpp"

namespace lamina::geometry {

std::string SelectionSpec::describe() const {
  switch (kind) {
    case Kind::all: return "all";
    case Kind::where: return fmt::format("where '{}'", expression);
    case Kind::nearest: return fmt::format("nearest [{}, {}, {}]", point.x(), point.y(), point.z());
    case Kind::box:
      return fmt::format("box [{}, {}, {}]..[{}, {}, {}]", box_min.x(), box_min.y(), box_min.z(), box_max.x(),
                         box_max.y(), box_max.z());
    case Kind::set: return fmt::format("set '{}'", set_name);
  }
  return "?";
}

Index nearest_point(const PointMatrix& points, const Vec3& x) {
  Index best = -1;
  Real best_distance = INFINITY;
  for (Index i = 0; i < points.cols(); ++i) {
    const Real d = (points.col(i) - x).squaredNorm();
    if (d < best_distance) best_distance = d, best = i;
  }
  return best;
}

IndexList resolve_selection(const SelectionSpec& spec, const PointMatrix& points,
                            const std::map<std::string, IndexList>& sets) {
  IndexList selected;
  const Index n = points.cols();
  switch (spec.kind) {
    case SelectionSpec::Kind::all:
      selected.resize(n);
      for (Index i = 0; i < n; ++i) selected[i] = i;
      break;
    case SelectionSpec::Kind::where: {
      Expression expression(spec.expression);
      for (Index i = 0; i < n; ++i)
        if (expression.evaluate(points.col(i)) != 0.0) selected.push_back(i);
      break;
    }
    case SelectionSpec::Kind::nearest:
      if (n > 0) selected.push_back(nearest_point(points, spec.point));
      break;
    case SelectionSpec::Kind::box: {
      const Real tolerance = 1e-12 * std::max<Real>(1.0, (spec.box_max - spec.box_min).norm());
      for (Index i = 0; i < n; ++i) {
        const Vec3 p = points.col(i);
        if ((p.array() >= spec.box_min.array() - tolerance).all() && (p.array() <= spec.box_max.array() + tolerance).all())
          selected.push_back(i);
      }
      break;
    }
    case SelectionSpec::Kind::set: {
      auto it = sets.find(spec.set_name);
      if (it == sets.end()) {
        std::string names;
        for (const auto& [name, nodes] : sets) names += (names.empty() ? "" : ", ") + name;
        throw std::out_of_range(fmt::format("one of the named sets {}", names.empty() ? "(none defined)" : names));
      }
      selected = it->second;
      std::sort(selected.begin(), selected.end());
      selected.erase(std::unique(selected.begin(), selected.end()), selected.end());
      break;
    }
  }
  return selected;
}

}  // namespace lamina::geometry
