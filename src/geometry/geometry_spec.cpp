#include "geometry/geometry_spec.hpp"

namespace lamina::geometry {

const char* to_string(GeometryType type) {
  switch (type) {
    case GeometryType::box: return "box";
    case GeometryType::plate: return "plate";
    case GeometryType::curved_beam: return "curved_beam";
    case GeometryType::cylinder: return "cylinder";
    case GeometryType::sphere_cap: return "sphere_cap";
    case GeometryType::annulus: return "annulus";
    case GeometryType::square_tube: return "square_tube";
    case GeometryType::mesh: return "mesh";
  }
  return "unknown";
}

}  // namespace lamina::geometry
