#include "efg/region_test.hpp"

#include <algorithm>

namespace lamina::efg {

RegionTest::RegionTest(const model::Selection& region, const geometry::VolumeMap* map, NearestNode nearest, Real tolerance)
    : region_(&region), nearest_(std::move(nearest)), tolerance_(tolerance) {
  using Kind = geometry::SelectionSpec::Kind;
  if (region.spec.kind == Kind::where) expression_ = std::make_unique<geometry::Expression>(region.spec.expression);
  if (region.spec.kind == Kind::set && map) {
    for (const auto& s : map->sets) {
      if (s.name != region.spec.set_name) continue;
      if (s.side < 0) {
        for (int f = 0; f < 6; ++f) faces_.push_back(f);
      } else {
        faces_.push_back(2 * s.axis + s.side);
      }
    }
  }
}

bool RegionTest::nearest_in_nodes(const Vec3& x) const {
  if (!nearest_) return false;
  const Index i = nearest_(x);
  return std::binary_search(region_->nodes.begin(), region_->nodes.end(), i);
}

bool RegionTest::in_volume(const Vec3& x) const {
  using Kind = geometry::SelectionSpec::Kind;
  switch (region_->spec.kind) {
    case Kind::all:
      return true;
    case Kind::where:
      return expression_->evaluate(x) != 0.0;
    case Kind::box:
      return (x.array() >= region_->spec.box_min.array() - tolerance_).all() &&
             (x.array() <= region_->spec.box_max.array() + tolerance_).all();
    case Kind::set:
    case Kind::nearest:
      return nearest_in_nodes(x);
  }
  return false;
}

bool RegionTest::on_surface(const Vec3& x, int face) const {
  using Kind = geometry::SelectionSpec::Kind;
  switch (region_->spec.kind) {
    case Kind::nearest:
      return false;
    case Kind::set:
      if (!faces_.empty()) return std::find(faces_.begin(), faces_.end(), face) != faces_.end();
      return nearest_in_nodes(x);
    default:
      return in_volume(x);
  }
}

bool RegionTest::can_select_surface() const { return region_->spec.kind != geometry::SelectionSpec::Kind::nearest; }


}  // namespace lamina::efg
