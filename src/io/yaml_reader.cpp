#include "io/yaml_reader.hpp"

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <utility>

namespace lamina::io {

namespace {

std::string truncate(std::string text, std::size_t n = 40) {
  for (char& c : text)
    if (c == '\n' || c == '\r') c = ' ';
  if (text.size() > n) text = text.substr(0, n - 3) + "...";
  return text;
}

std::string join_words(const std::vector<std::string>& words) {
  std::string text;
  for (std::size_t i = 0; i < words.size(); ++i) {
    if (i) text += (i + 1 == words.size()) ? " or " : ", ";
    text += words[i];
  }
  return text;
}

}  // namespace

std::string describe(const YAML::Node& node) {
  if (!node.IsDefined()) return "nothing (key missing)";
  switch (node.Type()) {
    case YAML::NodeType::Null: return "an empty value";
    case YAML::NodeType::Scalar: return fmt::format("'{}'", truncate(node.Scalar()));
    case YAML::NodeType::Sequence: return fmt::format("a list of {} item{}", node.size(), node.size() == 1 ? "" : "s");
    case YAML::NodeType::Map: return "a mapping";
    default: return "an undefined value";
  }
}

void DiagnosticSink::report(const YAML::Node& node, const std::string& key_path, const std::string& expected,
                            const std::string& found) {
  Diagnostic d;
  d.file = file_;
  d.key_path = key_path;
  d.expected = expected;
  d.found = found;
  for (const auto& [path, text] : overrides_) {
    if (key_path == path || key_path.rfind(path + ".", 0) == 0) {
      d.file = "--set " + text;
      diagnostics_.push_back(d);
      return;
    }
  }
  if (node.IsDefined()) {
    const YAML::Mark mark = node.Mark();
    if (mark.line >= 0) {
      d.line = mark.line + 1;
      d.column = mark.column + 1;
    }
  }
  diagnostics_.push_back(d);
}

void DiagnosticSink::throw_if_any() const {
  if (!diagnostics_.empty()) throw InputError(diagnostics_);
}

NodeReader::NodeReader(YAML::Node node, std::string key_path, DiagnosticSink* sink)
    : node_(std::move(node)), path_(std::move(key_path)), sink_(sink), known_(std::make_shared<std::set<std::string>>()) {}

void NodeReader::error(const std::string& expected, const std::string& found) const {
  sink_->report(node_, path_, expected, found);
}

bool NodeReader::expect_map() const {
  if (node_.IsMap()) return true;
  error("a mapping (key: value pairs)");
  return false;
}

bool NodeReader::expect_sequence() const {
  if (node_.IsSequence()) return true;
  error("a list");
  return false;
}

static std::string child_path(const std::string& parent, const std::string& key) {
  return parent.empty() ? key : parent + "." + key;
}

bool NodeReader::has(const std::string& key) const {
  if (!node_.IsMap()) return false;
  const YAML::Node& self = node_;
  const YAML::Node c = self[key];
  known_->insert(key);
  return c.IsDefined() && !c.IsNull();
}

NodeReader NodeReader::child(const std::string& key) const {
  known_->insert(key);
  if (!node_.IsMap()) return NodeReader(YAML::Node(YAML::NodeType::Undefined), child_path(path_, key), sink_);
  const YAML::Node& self = node_;
  const YAML::Node found = self[key];
  // yaml-cpp returns an invalid ("zombie") node for a missing key; use a plain undefined node.
  if (!found.IsDefined()) return NodeReader(YAML::Node(YAML::NodeType::Undefined), child_path(path_, key), sink_);
  return NodeReader(found, child_path(path_, key), sink_);
}

NodeReader NodeReader::required(const std::string& key) const {
  NodeReader c = child(key);
  if (!c.node_.IsDefined()) sink_->report(node_, c.path_, "a value (required key is missing)", "nothing");
  else if (c.node_.IsNull()) c.error("a value", "an empty value");
  return c;
}

std::vector<NodeReader> NodeReader::elements() const {
  std::vector<NodeReader> out;
  if (!node_.IsSequence()) return out;
  for (std::size_t i = 0; i < node_.size(); ++i) out.emplace_back(node_[i], child_path(path_, std::to_string(i)), sink_);
  return out;
}

std::vector<std::string> NodeReader::keys() const {
  std::vector<std::string> out;
  if (!node_.IsMap()) return out;
  for (auto it = node_.begin(); it != node_.end(); ++it)
    out.push_back(it->first.IsScalar() ? it->first.Scalar() : std::string("<non-scalar key>"));
  return out;
}

std::optional<Real> NodeReader::as_real() const {
  if (!node_.IsScalar()) {
    error("a number");
    return std::nullopt;
  }
  const std::string& text = node_.Scalar();
  // Accept plain decimal/scientific numbers only; reject .nan/.inf and words.
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  std::string rest = end ? std::string(end) : std::string();
  while (!rest.empty() && (rest.back() == ' ' || rest.back() == '\t')) rest.pop_back();
  if (text.empty() || !rest.empty() || text.find_first_of("nNiI") != std::string::npos) {
    if (text == ".nan" || text == ".NaN" || text == ".inf" || text == "-.inf" || text == ".Inf" || text == "-.Inf" ||
        text == "nan" || text == "inf" || text == "-inf")
      error("a finite number");
    else
      error("a number");
    return std::nullopt;
  }
  if (!std::isfinite(value)) {
    error("a finite number");
    return std::nullopt;
  }
  return value;
}

std::optional<long long> NodeReader::as_integer() const {
  if (!node_.IsScalar()) {
    error("an integer");
    return std::nullopt;
  }
  const std::string& text = node_.Scalar();
  char* end = nullptr;
  errno = 0;
  const long long value = std::strtoll(text.c_str(), &end, 10);
  if (text.empty() || (end && *end != '\0') || errno == ERANGE) {
    error("an integer");
    return std::nullopt;
  }
  return value;
}

std::optional<bool> NodeReader::as_bool() const {
  bool value = false;
  if (node_.IsScalar() && YAML::convert<bool>::decode(node_, value)) return value;
  error("true or false");
  return std::nullopt;
}

std::optional<std::string> NodeReader::as_string() const {
  if (node_.IsScalar()) return node_.Scalar();
  error("a string");
  return std::nullopt;
}

std::optional<std::string> NodeReader::as_word(const std::vector<std::string>& allowed) const {
  if (node_.IsScalar()) {
    for (const auto& w : allowed)
      if (node_.Scalar() == w) return w;
  }
  error("one of " + join_words(allowed));
  return std::nullopt;
}

std::optional<std::vector<Real>> NodeReader::as_reals(std::size_t n) const {
  const std::string what = n ? fmt::format("a list of {} numbers", n) : std::string("a list of numbers");
  if (!node_.IsSequence() || (n && node_.size() != n) || node_.size() == 0) {
    error(what);
    return std::nullopt;
  }
  std::vector<Real> out;
  bool ok = true;
  for (const auto& e : elements()) {
    auto v = e.as_real();
    if (!v) ok = false;
    else out.push_back(*v);
  }
  if (!ok) return std::nullopt;
  return out;
}

std::optional<std::vector<long long>> NodeReader::as_integers(std::size_t n) const {
  const std::string what = n ? fmt::format("a list of {} integers", n) : std::string("a list of integers");
  if (!node_.IsSequence() || (n && node_.size() != n) || node_.size() == 0) {
    error(what);
    return std::nullopt;
  }
  std::vector<long long> out;
  bool ok = true;
  for (const auto& e : elements()) {
    auto v = e.as_integer();
    if (!v) ok = false;
    else out.push_back(*v);
  }
  if (!ok) return std::nullopt;
  return out;
}

static std::string range_text(Real lower, Real upper, bool lower_open, bool upper_open) {
  const bool has_lower = std::isfinite(lower), has_upper = std::isfinite(upper);
  if (has_lower && has_upper)
    return fmt::format("a number in {}{}, {}{}", lower_open ? "(" : "[", lower, upper, upper_open ? ")" : "]");
  if (has_lower) return fmt::format("a number {} {}", lower_open ? ">" : ">=", lower);
  if (has_upper) return fmt::format("a number {} {}", upper_open ? "<" : "<=", upper);
  return "a finite number";
}

Real NodeReader::real(const std::string& key, std::optional<Real> fallback, Real lower, Real upper, bool lower_open,
                      bool upper_open) const {
  NodeReader c = fallback ? child(key) : required(key);
  if (!c.defined()) return fallback.value_or(0.0);
  auto v = c.as_real();
  if (!v) return fallback.value_or(0.0);
  const bool below = lower_open ? !(*v > lower) : !(*v >= lower);
  const bool above = upper_open ? !(*v < upper) : !(*v <= upper);
  if (below || above) {
    c.error(range_text(lower, upper, lower_open, upper_open), fmt::format("{}", *v));
    return fallback.value_or(std::isfinite(lower) ? lower : 0.0);
  }
  return *v;
}

long long NodeReader::integer(const std::string& key, std::optional<long long> fallback, long long lower,
                              long long upper) const {
  NodeReader c = fallback ? child(key) : required(key);
  if (!c.defined()) return fallback.value_or(0);
  auto v = c.as_integer();
  if (!v) return fallback.value_or(0);
  if (*v < lower || *v > upper) {
    std::string expected = upper == LLONG_MAX ? fmt::format("an integer >= {}", lower)
                                              : fmt::format("an integer in [{}, {}]", lower, upper);
    c.error(expected, std::to_string(*v));
    return fallback.value_or(lower);
  }
  return *v;
}

bool NodeReader::boolean(const std::string& key, bool fallback) const {
  NodeReader c = child(key);
  if (!c.defined()) return fallback;
  return c.as_bool().value_or(fallback);
}

std::string NodeReader::word(const std::string& key, const std::vector<std::string>& allowed,
                             std::optional<std::string> fallback) const {
  NodeReader c = fallback ? child(key) : required(key);
  if (!c.defined()) return fallback.value_or(std::string());
  return c.as_word(allowed).value_or(fallback.value_or(std::string()));
}

std::string NodeReader::string(const std::string& key, std::optional<std::string> fallback) const {
  NodeReader c = fallback ? child(key) : required(key);
  if (!c.defined()) return fallback.value_or(std::string());
  return c.as_string().value_or(fallback.value_or(std::string()));
}

Vec3 NodeReader::vec3(const std::string& key, std::optional<Vec3> fallback) const {
  NodeReader c = fallback ? child(key) : required(key);
  if (!c.defined()) return fallback.value_or(Vec3::Zero());
  auto v = c.as_reals(3);
  if (!v) return fallback.value_or(Vec3::Zero());
  return Vec3((*v)[0], (*v)[1], (*v)[2]);
}

void NodeReader::reject_unknown_keys() const {
  if (!node_.IsMap()) return;
  std::map<std::string, int> seen;
  for (auto it = node_.begin(); it != node_.end(); ++it) {
    const std::string key = it->first.IsScalar() ? it->first.Scalar() : std::string("<non-scalar key>");
    if (++seen[key] == 2)
      sink_->report(it->first, child_path(path_, key), "each key once", "a duplicate key '" + key + "'");
    if (!known_->count(key)) {
      std::vector<std::string> names(known_->begin(), known_->end());
      sink_->report(it->first, child_path(path_, key),
                    names.empty() ? std::string("no keys here") : "one of the keys " + join_words(names),
                    "unknown key '" + truncate(key) + "'");
    }
  }
}

void apply_override(YAML::Node& root, const std::string& assignment, DiagnosticSink& sink) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0) {
    sink.report(YAML::Node(), "--set", "key.path=value", "'" + assignment + "'");
    return;
  }
  const std::string path = assignment.substr(0, eq);
  const std::string text = assignment.substr(eq + 1);
  YAML::Node value;
  try {
    value = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    sink.report(YAML::Node(), path, "a YAML value after '='", "'" + text + "' (" + e.msg + ")");
    return;
  }
  if (!value.IsDefined() || value.IsNull()) value = YAML::Node(text);

  std::vector<std::string> parts;
  std::stringstream ss(path);
  for (std::string part; std::getline(ss, part, '.');) parts.push_back(part);
  if (parts.empty() || std::any_of(parts.begin(), parts.end(), [](const std::string& p) { return p.empty(); })) {
    sink.report(YAML::Node(), path, "a dotted key path like materials.0.E", "'" + path + "'");
    return;
  }
  sink.mark_override(path, assignment);
  // Walk with node references (yaml-cpp nodes are handles: assigning through them edits the tree).
  std::vector<YAML::Node> chain{root};
  for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
    YAML::Node current = chain.back();
    const std::string& key = parts[i];
    if (current.IsSequence()) {
      char* end = nullptr;
      const long index = std::strtol(key.c_str(), &end, 10);
      if (*end != '\0' || index < 0 || static_cast<std::size_t>(index) >= current.size()) {
        sink.report(YAML::Node(), path, fmt::format("an index in [0, {}) at '{}'", current.size(), key), "'" + key + "'");
        return;
      }
      chain.push_back(current[static_cast<std::size_t>(index)]);
    } else {
      if (!current.IsMap() && current.IsDefined() && !current.IsNull()) {
        sink.report(YAML::Node(), path, "a mapping at '" + key + "'", describe(current));
        return;
      }
      YAML::Node next = current[key];
      if (!next.IsDefined() || next.IsNull()) next = YAML::Node(YAML::NodeType::Map), current[key] = next;
      chain.push_back(current[key]);
    }
  }
  YAML::Node parent = chain.back();
  const std::string& last = parts.back();
  if (parent.IsSequence()) {
    char* end = nullptr;
    const long index = std::strtol(last.c_str(), &end, 10);
    if (*end != '\0' || index < 0 || static_cast<std::size_t>(index) >= parent.size()) {
      sink.report(YAML::Node(), path, fmt::format("an index in [0, {})", parent.size()), "'" + last + "'");
      return;
    }
    parent[static_cast<std::size_t>(index)] = value;
  } else {
    parent[last] = value;
  }
}

YAML::Node load_yaml_file(const std::string& path, DiagnosticSink& sink) {
  std::ifstream in(path);
  if (!in) {
    sink.report(YAML::Node(), "<file>", "a readable case file", "'" + path + "' cannot be opened");
    return YAML::Node();
  }
  try {
    std::stringstream buffer;
    buffer << in.rdbuf();
    YAML::Node root = YAML::Load(buffer.str());
    return root;
  } catch (const YAML::ParserException& e) {
    Diagnostic d;
    d.file = path;
    d.line = e.mark.line >= 0 ? e.mark.line + 1 : 0;
    d.column = e.mark.column >= 0 ? e.mark.column + 1 : 0;
    d.key_path = "<yaml syntax>";
    d.expected = "valid YAML";
    d.found = e.msg;
    throw InputError(d);
  } catch (const YAML::Exception& e) {
    throw InputError("<yaml syntax>", "valid YAML", e.what());
  }
}

}  // namespace lamina::io
