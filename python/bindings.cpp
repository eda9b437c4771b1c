// The compiled half of the Python API (PRODUCT.md section 6): YAML <-> Python objects with the
// case reader's scalar rules, and app::run_case with an on_output hook and the last frame kept.
// The user-facing module is python/lamina/__init__.py; this one is lamina._lamina.
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <optional>
#include <string>

#include "app/run_command.hpp"
#include "core/error.hpp"
#include "core/runtime_module.hpp"
#include "io/yaml_reader.hpp"

namespace py = pybind11;

namespace {

/// A plain YAML scalar as the case reader reads it: integer, real, boolean, null or text.
py::object scalar_object(const YAML::Node& node) {
  const std::string& text = node.Scalar();
  if (node.Tag() != "!") {  // "!" marks a quoted scalar: always text
    if (text.empty() || text == "~" || text == "null" || text == "Null" || text == "NULL") return py::none();
    if (text == "true" || text == "True" || text == "TRUE") return py::bool_(true);
    if (text == "false" || text == "False" || text == "FALSE") return py::bool_(false);
    long long integer = 0;
    if (YAML::convert<long long>::decode(node, integer)) return py::int_(integer);
    double real = 0;
    if (YAML::convert<double>::decode(node, real)) return py::float_(real);
  }
  return py::str(text);
}

py::object to_python(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Map: {
      py::dict d;
      for (const auto& kv : node) d[to_python(kv.first)] = to_python(kv.second);
      return d;
    }
    case YAML::NodeType::Sequence: {
      py::list l;
      for (const auto& item : node) l.append(to_python(item));
      return l;
    }
    case YAML::NodeType::Scalar:
      return scalar_object(node);
    default:
      return py::none();
  }
}

/// Whether text written plainly would be read back as something other than text.
bool needs_quotes(const std::string& text) {
  if (text.empty()) return true;
  try {
    YAML::Node plain = YAML::Load(text);
    return !plain.IsScalar() || !py::isinstance<py::str>(scalar_object(plain)) || plain.Scalar() != text;
  } catch (const YAML::Exception&) {
    return true;  // not valid as a plain scalar (e.g. "{x" or "a: [")
  }
}

void emit(YAML::Emitter& out, const py::handle& value, const std::string& path) {
  if (value.is_none()) {
    out << YAML::Null;
  } else if (py::isinstance<py::bool_>(value)) {
    out << (value.cast<bool>() ? "true" : "false");
  } else if (py::isinstance<py::int_>(value) || (py::hasattr(value, "__index__") && !py::isinstance<py::str>(value))) {
    out << py::int_(py::reinterpret_borrow<py::object>(value)).cast<long long>();
  } else if (py::isinstance<py::float_>(value) || py::hasattr(value, "__float__")) {
    const double x = py::float_(py::reinterpret_borrow<py::object>(value)).cast<double>();
    if (!std::isfinite(x)) throw lamina::InputError(path, "a finite number", py::str(value).cast<std::string>());
    out << YAML::Precision(17) << x;
  } else if (py::isinstance<py::str>(value)) {
    const std::string text = value.cast<std::string>();
    if (needs_quotes(text)) out << YAML::DoubleQuoted;
    out << text;
  } else if (py::isinstance<py::dict>(value)) {
    out << YAML::BeginMap;
    for (const auto& kv : value.cast<py::dict>()) {
      const std::string key = py::str(kv.first).cast<std::string>();
      out << YAML::Key << key << YAML::Value;
      emit(out, kv.second, path.empty() ? key : path + "." + key);
    }
    out << YAML::EndMap;
  } else if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value) || py::hasattr(value, "tolist")) {
    py::object items = py::hasattr(value, "tolist") ? value.attr("tolist")() : py::reinterpret_borrow<py::object>(value);
    bool flat = true;  // numbers only: one line, [a, b, c]
    for (const auto& item : items)
      if (py::isinstance<py::dict>(item) || py::isinstance<py::list>(item) || py::isinstance<py::tuple>(item)) flat = false;
    if (flat) out << YAML::Flow;
    out << YAML::BeginSeq;
    int k = 0;
    for (const auto& item : items) emit(out, item, path + "." + std::to_string(k++));
    out << YAML::EndSeq;
  } else {
    throw lamina::InputError(path.empty() ? "<case>" : path, "a number, text, list or dict",
                             "a Python " + py::str(value.get_type().attr("__name__")).cast<std::string>());
  }
}

py::object load_yaml(const std::string& path) {
  lamina::io::DiagnosticSink sink(path);
  YAML::Node root = lamina::io::load_yaml_file(path, sink);
  sink.throw_if_any();
  return to_python(root);
}

std::string dump_yaml(const py::object& value) {
  YAML::Emitter out;
  out.SetIndent(2);
  emit(out, value, "");
  return std::string(out.c_str()) + "\n";
}

py::array_t<double> matrix(const std::vector<lamina::Real>& values, py::ssize_t rows, py::ssize_t columns) {
  py::array_t<double> a = columns == 1 ? py::array_t<double>({rows}) : py::array_t<double>({rows, columns});
  std::copy(values.begin(), values.begin() + rows * columns, a.mutable_data());
  return a;
}

py::dict run_case(const std::string& path, const std::string& output, int threads, const std::vector<std::string>& overrides,
                  const std::string& case_directory, const std::optional<py::function>& on_output, bool quiet) {
  lamina::app::RunOptions options;
  options.case_path = path;
  options.output_directory = output;
  options.threads = threads;
  options.overrides = overrides;
  options.quiet = quiet;
  options.case_directory = case_directory;
  options.keep_last_frame = true;
  if (on_output) {
    py::function callback = *on_output;
    options.on_output = [callback](const lamina::app::OutputPointReport& report) {
      py::dict probes;
      for (std::size_t i = 0; i < report.probe_names->size(); ++i) probes[py::str((*report.probe_names)[i])] = (*report.probe_values)[i];
      py::object answer = callback(report.step, report.time, report.load_factor, probes);
      return answer.is_none() || answer.cast<bool>();
    };
  }
  lamina::app::RunResult r = lamina::app::run_case(options);
  py::dict d;
  d["exit_code"] = r.exit_code;
  d["error"] = r.error;
  d["summary"] = r.summary.is_null() ? std::string("{}") : r.summary.dump();
  d["history_columns"] = r.history_columns;
  d["history_rows"] = r.history_rows;
  d["output_directory"] = r.output_directory.string();
  if (r.last_frame) {
    const lamina::OutputFrame& f = *r.last_frame;
    const auto n = static_cast<py::ssize_t>(f.points.cols());
    py::array_t<double> points({n, static_cast<py::ssize_t>(3)});
    for (py::ssize_t i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k) points.mutable_at(i, k) = f.points(k, i);
    py::dict fields;
    for (const auto& field : f.point_fields) fields[py::str(field.name)] = matrix(field.values, n, field.components);
    d["points"] = points;
    d["fields"] = fields;
  }
  return d;
}

}  // namespace

PYBIND11_MODULE(_lamina, m) {
  lamina::select_blas_kernels();  // before any module loads OpenBLAS (core/runtime_module.hpp)
  m.doc() = "lamina's compiled core; use the package lamina (python/lamina/__init__.py)";
  static py::exception<lamina::InputError> input_error(m, "InputErrorBase");
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const lamina::InputError& e) {
      input_error(e.what());
    }
  });
  m.def("load_yaml", &load_yaml, py::arg("path"), "A YAML case file as Python objects (the reader's scalar rules).");
  m.def("dump_yaml", &dump_yaml, py::arg("value"), "Python objects as YAML text that the case reader reads back unchanged.");
  m.def("run_case", &run_case, py::arg("path"), py::arg("output"), py::arg("threads"), py::arg("overrides"),
        py::arg("case_directory"), py::arg("on_output"), py::arg("quiet"));
}
