#include "app/method_registry.hpp"

#include "app/efg_method.hpp"
#include "app/mls_options_reader.hpp"
#include "core/error.hpp"
#include "efg/mls_fit_analysis.hpp"

namespace lamina::app {

namespace {

struct MlsFitMethodOptions : MethodOptions {
  efg::MlsFitOptions options;
};

std::unique_ptr<MethodOptions> read_mls_fit(const io::Case&, const io::NodeReader& section) {
  auto result = std::make_unique<MlsFitMethodOptions>();
  if (!section.defined()) {
    section.sink().report(YAML::Node(), "mls_fit", "an mls_fit: section (field, basis, weight, support)", "nothing");
    return result;
  }
  if (!section.expect_map()) return result;
  io::NodeReader field = section.required("field");
  if (field.defined()) {
    geometry::ScalarField f = io::read_scalar_field(field);
    result->options.field = f.is_constant() ? std::to_string(f.constant) : f.expression;
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
      MethodEntry{io::MethodKeys{"mls_fit", {"nodes", "jitter"}, false},
                  "MLS fit of an analytic field: errU, errDU, errDDU (seed 004 eqs 3-3..3-5)", read_mls_fit,
                  create_mls_fit},
  };
  return entries;
}

const MethodEntry* find_method(const std::string& name) {
  for (const auto& m : methods())
    if (m.keys.method == name) return &m;
  return nullptr;
}

const std::vector<std::string>& planned_methods() {
  static const std::vector<std::string> names{"pd", "mpm", "mpfem"};
  return names;
}

}  // namespace lamina::app
