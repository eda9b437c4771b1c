#include "io/yaml_reader.hpp"

#include <filesystem>
#include <fmt/format.h>

#include <algorithm>
#include <climits>
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
  const bool from_file = node.IsDefined() && node.Mark().line >= 0;
  for (const auto& [path, text] : overrides_) {
    // the overridden value or below it; or a mapping the override created on its way (no mark)
    const bool created_by_override = !from_file && !source_position(key_path) && path.rfind(key_path + ".", 0) == 0;
    if (key_path == path || key_path.rfind(path + ".", 0) == 0 || created_by_override) {
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
  if (d.line == 0) {
    // A node built in code: take the recorded position of the path or of its nearest ancestor.
    if (auto position = source_position(key_path)) {
      d.line = position->first;
      d.column = position->second;
    }
  }
  diagnostics_.push_back(d);
}

std::optional<std::pair<int, int>> DiagnosticSink::source_position(const std::string& key_path) const {
  for (std::string path = key_path; !path.empty() && !positions_.empty();) {
    if (auto it = positions_.find(path); it != positions_.end()) return it->second;
    const auto dot = path.rfind('.');
    path = dot == std::string::npos ? std::string() : path.substr(0, dot);
  }
  return std::nullopt;
}

void DiagnosticSink::report_override(const std::string& assignment, const std::string& key_path,
                                     const std::string& expected, const std::string& found) {
  Diagnostic d;
  d.file = "--set " + assignment;
  d.key_path = key_path;
  d.expected = expected;
  d.found = found;
  diagnostics_.push_back(d);
}

void sort_by_position(std::vector<Diagnostic>& diagnostics) {
  std::stable_sort(diagnostics.begin(), diagnostics.end(), [](const Diagnostic& a, const Diagnostic& b) {
    const long la = a.line > 0 ? a.line : INT_MAX, lb = b.line > 0 ? b.line : INT_MAX;
    if (la != lb) return la < lb;
    return a.line > 0 && a.column < b.column;
  });
}

void DiagnosticSink::throw_if_any() const {
  if (diagnostics_.empty()) return;
  std::vector<Diagnostic> ordered = diagnostics_;
  sort_by_position(ordered);
  throw InputError(ordered);
}

namespace {

/// The child of a mapping / sequence by key or index text (undefined when there is none).
/// Nodes are returned by value: yaml-cpp's operator= would assign through a handle.
YAML::Node child_of(const YAML::Node& parent, const std::string& part) {
  if (parent.IsMap()) {
    const YAML::Node found = parent[part];
    if (found.IsDefined()) return found;
  } else if (parent.IsSequence()) {
    char* end = nullptr;
    const long index = std::strtol(part.c_str(), &end, 10);
    if (!part.empty() && *end == '\0' && index >= 0 && static_cast<std::size_t>(index) < parent.size())
      return parent[static_cast<std::size_t>(index)];
  }
  return YAML::Node(YAML::NodeType::Undefined);
}

}  // namespace

std::optional<std::pair<int, int>> position_of(const YAML::Node& root, const std::string& key_path) {
  std::optional<std::pair<int, int>> best;
  auto take = [&](const YAML::Node& node) {
    if (node.IsDefined() && node.Mark().line >= 0) best = std::make_pair(node.Mark().line + 1, node.Mark().column + 1);
  };
  YAML::Node current(root);
  take(current);
  std::stringstream parts(key_path);
  for (std::string part; std::getline(parts, part, '.');) {
    const YAML::Node next = child_of(current, part);
    if (!next.IsDefined()) break;
    current.reset(next);  // rebind the handle (never assign through it)
    take(current);
  }
  return best;
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

std::string DiagnosticSink::base_directory() const {
  return base_directory_.empty() ? std::filesystem::path(file_).parent_path().string() : base_directory_;
}

std::string NodeReader::file_path(const std::string& key, const std::string& expected) const {
  const std::string name = string(key, std::nullopt);
  if (name.empty()) return name;
  std::filesystem::path path(name);
  if (path.is_relative()) path = std::filesystem::path(sink_->base_directory()) / path;
  std::error_code ignored;
  std::filesystem::path absolute = std::filesystem::absolute(path, ignored).lexically_normal();
  if (!absolute.has_filename() && absolute.has_parent_path()) absolute = absolute.parent_path();  // "dir/" -> "dir"
  if (!absolute.empty()) path = absolute;
  std::string problem;
  if (!std::filesystem::exists(path, ignored)) problem = "no such file";
  else if (std::filesystem::is_directory(path, ignored)) problem = "a directory";
  else if (!std::ifstream(path)) problem = "not readable";
  if (!problem.empty())
    child(key).error(expected, fmt::format("cannot open file '{}' (resolved to '{}': {})", name, path.string(), problem));
  return path.string();
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
    sink.report_override(assignment, "--set", "key.path=value", "'" + assignment + "'");
    return;
  }
  const std::string path = assignment.substr(0, eq);
  const std::string text = assignment.substr(eq + 1);
  YAML::Node value;
  try {
    value = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    sink.report_override(assignment, path, "a YAML value after '='", "'" + text + "' (" + e.msg + ")");
    return;
  }
  if (!value.IsDefined() || value.IsNull()) value = YAML::Node(text);

  std::vector<std::string> parts;
  std::stringstream ss(path);
  for (std::string part; std::getline(ss, part, '.');) parts.push_back(part);
  if (parts.empty() || path.back() == '.' ||
      std::any_of(parts.begin(), parts.end(), [](const std::string& p) { return p.empty(); })) {
    sink.report_override(assignment, path, "a dotted key path like materials.0.E", "'" + path + "'");
    return;
  }
  // A key below a scalar ("title.x" where title is a string) cannot be set.
  auto scalar_in_the_way = [&](const YAML::Node& node, std::size_t depth) {
    if (node.IsMap() || node.IsSequence() || !node.IsDefined() || node.IsNull()) return false;
    std::string at;
    for (std::size_t i = 0; i < depth; ++i) at += (i ? "." : "") + parts[i];
    sink.report_override(assignment, path,
                         fmt::format("a mapping at '{}' to hold the key '{}'", at.empty() ? "<root>" : at, parts[depth]),
                         describe(node));
    return true;
  };
  // Walk with node references (yaml-cpp nodes are handles: assigning through them edits the tree).
  std::vector<YAML::Node> chain{root};
  for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
    YAML::Node current = chain.back();
    const std::string& key = parts[i];
    if (current.IsSequence()) {
      char* end = nullptr;
      const long index = std::strtol(key.c_str(), &end, 10);
      if (*end != '\0' || index < 0 || static_cast<std::size_t>(index) >= current.size()) {
        sink.report_override(assignment, path, fmt::format("an index in [0, {}) at '{}'", current.size(), key), "'" + key + "'");
        return;
      }
      chain.push_back(current[static_cast<std::size_t>(index)]);
    } else {
      if (scalar_in_the_way(current, i)) return;
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
      sink.report_override(assignment, path, fmt::format("an index in [0, {})", parent.size()), "'" + last + "'");
      return;
    }
    sink.mark_override(path, assignment);
    parent[static_cast<std::size_t>(index)] = value;
  } else {
    if (scalar_in_the_way(parent, parts.size() - 1)) return;
    sink.mark_override(path, assignment);
    parent[last] = value;
  }
}

namespace {

/// The line (1-based) of a single- or double-quoted scalar that is still open at the end of
/// the text, or 0. yaml-cpp accepts such a file and ends the scalar at the end of the input.
/// A quote opens a scalar only where a scalar can start (after indentation, "- ", ": ", "? ",
/// "[", "{" or ","); comments and block scalars (| and >) are skipped.
int unclosed_quote_line(const std::string& text) {
  std::vector<std::string> lines;
  {
    std::stringstream in(text);
    for (std::string line; std::getline(in, line);) lines.push_back(line);
  }
  char open_quote = 0;
  int open_line = 0;
  int block_indent = -1;  // inside a block scalar: lines indented more than this belong to it
  for (std::size_t n = 0; n < lines.size(); ++n) {
    const std::string& line = lines[n];
    std::size_t i = 0;
    if (!open_quote) {
      const std::size_t first = line.find_first_not_of(" \t");
      if (block_indent >= 0) {
        if (first == std::string::npos || static_cast<int>(first) > block_indent) continue;
        block_indent = -1;
      }
    }
    bool scalar_can_start = true;
    char previous = ' ';
    for (; i < line.size(); ++i) {
      const char c = line[i];
      if (open_quote) {
        if (open_quote == '"' && c == '\\') {
          ++i;
          continue;
        }
        if (c == open_quote) {
          if (open_quote == '\'' && i + 1 < line.size() && line[i + 1] == '\'') {
            ++i;
            continue;
          }
          open_quote = 0;
          scalar_can_start = false;
        }
        previous = c;
        continue;
      }
      if (c == '#' && (previous == ' ' || previous == '\t' || i == 0)) break;
      if ((c == '"' || c == '\'') && scalar_can_start) {
        open_quote = c;
        open_line = static_cast<int>(n) + 1;
        previous = c;
        continue;
      }
      if (c == '|' || c == '>') {
        // a block scalar indicator where a value starts: its content lines follow
        std::string rest = line.substr(i + 1);
        const auto hash = rest.find(" #");
        if (hash != std::string::npos) rest = rest.substr(0, hash);
        if (scalar_can_start && rest.find_first_not_of("+-0123456789 \t") == std::string::npos) {
          block_indent = static_cast<int>(line.find_first_not_of(" \t"));
          break;
        }
      }
      if (c == ' ' || c == '\t') {
        // whitespace keeps the state
      } else if (c == '[' || c == '{' || c == ',') {
        scalar_can_start = true;
      } else if ((c == '-' || c == ':' || c == '?') && (i + 1 == line.size() || line[i + 1] == ' ' || line[i + 1] == '\t')) {
        scalar_can_start = true;
      } else {
        scalar_can_start = false;
      }
      previous = c;
    }
  }
  return open_quote ? open_line : 0;
}

}  // namespace

YAML::Node load_yaml_file(const std::string& path, DiagnosticSink& sink) {
  std::ifstream in(path);
  if (!in) {
    sink.report(YAML::Node(), "<file>", "a readable case file", "'" + path + "' cannot be opened");
    return YAML::Node();
  }
  try {
    std::stringstream buffer;
    buffer << in.rdbuf();
    const std::string text = buffer.str();
    YAML::Node root = YAML::Load(text);
    if (const int line = unclosed_quote_line(text)) {
      Diagnostic d;
      d.file = path;
      d.line = line;
      d.column = 1;
      d.key_path = "<yaml syntax>";
      d.expected = "valid YAML";
      d.found = "a quoted string that is never closed (no closing quote before the end of the file)";
      throw InputError(d);
    }
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
