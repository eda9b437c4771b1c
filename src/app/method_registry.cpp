#include "app/method_registry.hpp"

#include "app/efg_method.hpp"
#include "app/pd_method.hpp"
#include "app/mpfem_method.hpp"
#include "app/mpm_method.hpp"
#include "app/mls_options_reader.hpp"
#include "core/error.hpp"
#include "efg/mls_fit_analysis.hpp"
#include "geometry/expression.hpp"
#include "geometry/generators.hpp"

#include <fmt/format.h>

#include <cmath>

namespace lamina::app {

namespace {

struct MlsFitMethodOptions : MethodOptions {
  efg::MlsFitOptions options;
};

/// The nodes the fit will use when they can be known before the run (generated from the
/// geometry, without jitter), else a small sample grid of the body; empty for a mesh / nodes file.
Eigen::Matrix3Xd sample_points(const io::Case& c) {
  if (c.geometry.type == geometry::GeometryType::mesh || c.discretization.nodes_file) return {};
  if (const auto& list = c.discretization.node_coordinates) {
    Eigen::Matrix3Xd points(3, static_cast<Eigen::Index>(list->size()));
    for (std::size_t i = 0; i < list->size(); ++i) points.col(static_cast<Eigen::Index>(i)) = (*list)[i];
    return points;
  }
  std::array<int, 3> counts{5, 5, 5};
  if (c.discretization.nodes) {
    const auto& n = *c.discretization.nodes;
    if (static_cast<long long>(n[0]) * n[1] * n[2] <= 200000) counts = n;
  }
  try {
    return geometry::generate_volume_nodes(c.geometry, counts).positions;
  } catch (const std::exception&) {
    return {};  // a bad geometry or count is reported where it is read
  }
}

/// mls_fit fits the field at the nodes: a field that is not finite there is an input error.
void check_field_finite(const io::Case& c, const io::NodeReader& field, const std::string& expression) {
  if (!field.sink().empty()) return;  // no follow-on error on a case that is already invalid
  const Eigen::Matrix3Xd points = sample_points(c);
  try {
    geometry::Expression f(expression);
    for (Eigen::Index i = 0; i < points.cols(); ++i) {
      const Vec3 p = points.col(i);
      const Real value = f.evaluate(p);
      if (!std::isfinite(value)) {
        field.error("a field that is finite at every node",
                    fmt::format("{} at node ({:.6g}, {:.6g}, {:.6g})", std::isnan(value) ? "NaN" : fmt::format("{}", value),
                                p.x(), p.y(), p.z()));
        return;
      }
    }
  } catch (const geometry::ExpressionError&) {
    // reported by read_scalar_field
  }
}

/// mls_fit evaluates only the fitted field: every probe must be an approximation probe.
void check_probes_fitted(const io::Case& c, io::DiagnosticSink& sink) {
  for (const auto& p : c.probes) {
    if (p.field.empty() || p.field == "approximation") continue;
    sink.add(Diagnostic{p.location.file, p.location.line, p.location.column, p.location.key_path + ".field",
                        "field approximation (mls_fit evaluates only the fitted field: value or its derivatives x ... zx)",
                        "'" + p.field + "'"});
  }
}

std::unique_ptr<MethodOptions> read_mls_fit(const io::Case& c, const io::NodeReader& section) {
  auto result = std::make_unique<MlsFitMethodOptions>();
  check_probes_fitted(c, section.sink());
  if (!section.defined()) {
    section.sink().report(YAML::Node(), "mls_fit", "an mls_fit: section (field, basis, weight, support)", "nothing");
    return result;
  }
  if (!section.expect_map()) return result;
  io::NodeReader field = section.required("field");
  if (field.defined()) {
    geometry::ScalarField f = io::read_scalar_field(field);
    result->options.field = f.is_constant() ? std::to_string(f.constant) : f.expression;
    if (!f.is_constant()) check_field_finite(c, field, f.expression);
  }
  result->options.mls = read_mls_options(section, 3);
  result->options.difference_step = section.real("difference_step", 1e-3, 1e-8, 0.1);
  section.reject_unknown_keys();
  return result;
}

std::unique_ptr<Analysis> create_mls_fit(const io::Case& c, const Model& model, const MethodOptions& options) {
  const auto& o = static_cast<const MlsFitMethodOptions&>(options);
  return std::make_unique<efg::MlsFitAnalysis>(model.cloud, o.options, model.probes);
}

}  // namespace

const std::vector<MethodEntry>& methods() {
  static const std::vector<MethodEntry> entries{
      efg_method_entry(),
      mpm_method_entry(),
      pd_method_entry(),
      mpfem_method_entry(),
      MethodEntry{io::MethodKeys{"mls_fit", {"nodes", "jitter"}, false},
                  "MLS fit of an analytic field: errU, errDU, errDDU (seed 004 eqs 3-3..3-5)", read_mls_fit,
                  create_mls_fit, {}, /*distributed=*/true},  // on several ranks: replicated (every rank the whole fit)
  };
  return entries;
}

const MethodEntry* find_method(const std::string& name) {
  for (const auto& m : methods())
    if (m.keys.method == name) return &m;
  return nullptr;
}

}  // namespace lamina::app
