#include "mls/mls_options.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "core/error.hpp"

namespace lamina::mls {

namespace {

void require(bool condition, const char* key, const char* expected, const std::string& found,
             std::vector<Diagnostic>& problems) {
  if (!condition) problems.push_back(Diagnostic{"", 0, 0, std::string("mls.") + key, expected, found});
}

}  // namespace

void MlsOptions::validate() const {
  std::vector<Diagnostic> problems;
  require(dimension >= 1 && dimension <= 3, "dimension", "1, 2 or 3", fmt::format("{}", dimension), problems);
  require(std::isfinite(gauss_beta) && gauss_beta > 0.0, "gauss_beta", "a positive number",
          fmt::format("{}", gauss_beta), problems);
  if (mode == SupportMode::kappa)
  {
    require(std::isfinite(kappa) && kappa > 0.0, "kappa", "a positive number", fmt::format("{}", kappa), problems);
    require(std::isfinite(delta) && delta >= 0.0 && delta <= 1.0, "delta", "a number in [0, 1] (nodal spacings)",
            fmt::format("{}", delta), problems);
  }
  if (interface_enrichment)
    require(interface_point.allFinite() && interface_normal.allFinite() && std::abs(interface_normal.norm() - 1.0) < 1e-12,
            "interface", "a finite point and a unit normal", "a non-finite point or a normal that is not a unit vector",
            problems);
  if (kappa_axes != Vec3::Zero()) {
    require(mode == SupportMode::kappa && shape == SupportShape::box, "kappa", "a single number for a sphere support",
            "one factor per axis", problems);
    require(kappa_axes.allFinite() && (kappa_axes.head(dimension).array() > 0.0).all(), "kappa",
            "positive factors per axis", fmt::format("[{}, {}, {}]", kappa_axes[0], kappa_axes[1], kappa_axes[2]), problems);
  }
  if (mode == SupportMode::fixed_radius) {
    const int used = shape == SupportShape::sphere ? 1 : std::clamp(dimension, 1, 3);
    bool positive = true;
    for (int d = 0; d < used; ++d) positive = positive && std::isfinite(radius[d]) && radius[d] > 0.0;
    require(positive, "radius",
            shape == SupportShape::sphere ? "a positive radius[0]" : "positive radii for the used dimensions",
            fmt::format("[{}, {}, {}]", radius[0], radius[1], radius[2]), problems);
  }
  if (mode == SupportMode::nearest || mode == SupportMode::all || mode == SupportMode::variable) {
    require(nearest >= 1, "nearest", "a number of nodes >= 1", fmt::format("{}", nearest), problems);
    require(std::isfinite(scale) && scale > 0.0, "scale", "a positive number", fmt::format("{}", scale), problems);
  }
  require(remedy_max_steps >= 0, "remedy_max_steps", "a number >= 0", fmt::format("{}", remedy_max_steps), problems);
  require(max_condition > 1.0, "max_condition", "a number > 1", fmt::format("{}", max_condition), problems);
  if (!problems.empty()) throw InputError(std::move(problems));
}

int basis_size(int dimension, Basis basis) {
  return basis == Basis::linear ? dimension + 1 : (dimension + 1) * (dimension + 2) / 2;
}

std::string to_string(Basis basis) { return basis == Basis::linear ? "linear" : "quadratic"; }

std::string to_string(Weight weight) {
  switch (weight) {
    case Weight::gauss: return "gauss";
    case Weight::cubic_spline: return "cubic_spline";
    case Weight::quartic_spline: return "quartic_spline";
  }
  return "?";
}

std::string to_string(SupportShape shape) { return shape == SupportShape::box ? "box" : "sphere"; }

std::string to_string(SupportMode mode) {
  switch (mode) {
    case SupportMode::kappa: return "kappa";
    case SupportMode::fixed_radius: return "fixed_radius";
    case SupportMode::nearest: return "nearest";
    case SupportMode::all: return "all";
    case SupportMode::variable: return "variable";
  }
  return "?";
}

}  // namespace lamina::mls
