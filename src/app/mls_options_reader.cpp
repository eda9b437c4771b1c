#include "app/mls_options_reader.hpp"

namespace lamina::app {

mls::MlsOptions read_mls_options(const io::NodeReader& section, int dimension) {
  mls::MlsOptions o;
  o.dimension = dimension;
  const std::string basis = section.word("basis", {"linear", "quadratic"}, "quadratic");
  o.basis = basis == "linear" ? mls::Basis::linear : mls::Basis::quadratic;
  const std::string weight = section.word("weight", {"gauss", "cubic_spline", "quartic_spline"}, "quartic_spline");
  o.weight = weight == "gauss" ? mls::Weight::gauss : weight == "cubic_spline" ? mls::Weight::cubic_spline : mls::Weight::quartic_spline;
  if (section.has("gauss_beta")) o.gauss_beta = section.real("gauss_beta", o.gauss_beta, 0.0, 100.0, true);
  o.singular_remedy = section.boolean("singular_remedy", false);

  io::NodeReader interface = section.child("interface");
  const bool no_interface = interface.defined() && interface.is_scalar() && section.word("interface", {"none"}, "none") == "none";
  if (interface.defined() && !no_interface && interface.expect_map()) {
    // {point: [x, y, z], normal: [nx, ny, nz]}: interface enrichment across that plane (or `none`)
    o.interface_point = interface.vec3("point", std::nullopt);
    const Vec3 normal = interface.vec3("normal", std::nullopt);
    if (!(normal.norm() > 0.0)) interface.child("normal").error("a non-zero vector");
    else o.interface_normal = normal.normalized();
    o.interface_enrichment = true;
    interface.reject_unknown_keys();
  }

  io::NodeReader support = section.child("support");
  if (support.defined() && support.expect_map()) {
    // {shape: box|sphere, kappa: k} | {shape: box, kappa: [kx, ky, kz]} | {nearest: N, shape, kappa} | {radius: [rx, ry, rz]} | {mode: all|variable, nearest: N, scale: s}
    const bool has_nearest = support.has("nearest"), has_radius = support.has("radius");
    const std::string mode = support.word("mode", {"kappa", "fixed_radius", "nearest", "all", "variable"},
                                          has_radius ? "fixed_radius" : has_nearest ? "nearest" : "kappa");
    o.mode = mode == "fixed_radius" ? mls::SupportMode::fixed_radius
             : mode == "nearest"    ? mls::SupportMode::nearest
             : mode == "all"        ? mls::SupportMode::all
             : mode == "variable"   ? mls::SupportMode::variable
                                    : mls::SupportMode::kappa;
    const std::string default_shape = (o.mode == mls::SupportMode::kappa || o.mode == mls::SupportMode::fixed_radius) ? "box" : "sphere";
    const std::string shape = support.word("shape", {"box", "sphere"}, default_shape);
    o.shape = shape == "sphere" ? mls::SupportShape::sphere : mls::SupportShape::box;
    const int m = (o.basis == mls::Basis::linear ? dimension + 1 : (dimension + 1) * (dimension + 2) / 2);
    if (o.mode == mls::SupportMode::kappa || o.mode == mls::SupportMode::nearest) {
      // (nearest = the seed's SELECT: supports sized by kappa as in mode kappa, then the N nearest kept)
      if (support.child("kappa").is_sequence()) {
        // one factor per axis (box supports only)
        if (shape != "box") support.child("kappa").error("a single number for a sphere support");
        const Vec3 k = support.vec3("kappa", std::nullopt);
        if (!(k.head(dimension).array() > 0.0).all() || !(k.array() <= 100.0).all())
          support.child("kappa").error("factors in (0, 100]");
        o.kappa_axes = k;
        o.kappa = k.maxCoeff();
      } else {
        o.kappa = support.real("kappa", shape == "sphere" ? 2.5 : 2.0, 0.0, 100.0, true);
      }
      if (shape == "box") o.delta = support.real("delta", mls::default_support_delta, 0.0, 1.0, false);
      else if (support.has("delta")) support.child("delta").error("no delta for a sphere support (box supports only: radius (kappa + delta) h)");
    }
    if (o.mode == mls::SupportMode::fixed_radius) {
      Vec3 r = support.vec3("radius", std::nullopt);
      if ((r.array() <= 0).any()) support.child("radius").error("positive radii");
      o.radius = r;
    }
    if (o.mode == mls::SupportMode::nearest || o.mode == mls::SupportMode::all || o.mode == mls::SupportMode::variable)
      o.nearest = static_cast<int>(support.integer("nearest", 27, m + 1, 100000));
    if (o.mode == mls::SupportMode::all || o.mode == mls::SupportMode::variable)
      o.scale = support.real("scale", 1.0, 0.0, 100.0, true);
    support.reject_unknown_keys();
    if (o.mode == mls::SupportMode::fixed_radius && o.shape == mls::SupportShape::sphere) {
      // sphere with fixed radius uses the x radius
    }
  }
  return o;
}

}  // namespace lamina::app
