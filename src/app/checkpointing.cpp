#include "app/checkpointing.hpp"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <csignal>
#include <optional>
#include <set>

#include "core/error.hpp"
#include "io/checkpoint_file.hpp"

namespace lamina::app {

namespace {

void remove_key(YAML::Node node, const std::string& dotted) {
  const std::size_t dot = dotted.find('.');
  if (!node.IsMap()) return;
  if (dot == std::string::npos) {
    node.remove(dotted);
    return;
  }
  const std::string head = dotted.substr(0, dot);
  if (node[head]) remove_key(node[head], dotted.substr(dot + 1));
}

std::string shown(const YAML::Node& node) {
  if (!node) return "(absent)";
  if (node.IsScalar()) return "'" + node.Scalar() + "'";
  YAML::Emitter out;
  out << YAML::Flow << node;
  return out.c_str();
}

std::optional<CaseDifference> difference(const YAML::Node& a, const YAML::Node& b, const std::string& path) {
  auto here = [&](const std::string& key) { return path.empty() ? key : path + "." + key; };
  auto differs = [&](const std::string& at, const YAML::Node& x, const YAML::Node& y) {
    return CaseDifference{at.empty() ? "(the whole case)" : at, shown(x), shown(y)};
  };
  if (a.Type() != b.Type()) return differs(path, a, b);
  if (a.IsScalar()) return a.Scalar() == b.Scalar() ? std::nullopt : std::optional(differs(path, a, b));
  if (a.IsSequence()) {
    for (std::size_t k = 0; k < std::min(a.size(), b.size()); ++k)
      if (auto d = difference(a[k], b[k], here(std::to_string(k)))) return d;
    if (a.size() == b.size()) return std::nullopt;
    const std::size_t k = std::min(a.size(), b.size());
    return differs(here(std::to_string(k)), k < a.size() ? a[k] : YAML::Node(), k < b.size() ? b[k] : YAML::Node());
  }
  if (a.IsMap()) {
    std::set<std::string> keys;
    for (const auto& kv : a) keys.insert(kv.first.Scalar());
    for (const auto& kv : b) keys.insert(kv.first.Scalar());
    for (const auto& key : keys) {
      const YAML::Node x = a[key], y = b[key];
      if (!x || !y) return differs(here(key), x, y);
      if (auto d = difference(x, y, here(key))) return d;
    }
  }
  return std::nullopt;
}

volatile std::sig_atomic_t received_signal = 0;

extern "C" void record_stop_signal(int signal) {
  received_signal = signal;
  std::signal(signal, SIG_DFL);  // a second SIGINT / SIGTERM ends the process at once
}

}  // namespace

std::string restart_invariant_case(const io::Case& c, const std::vector<std::string>& restart_keys) {
  YAML::Node copy = YAML::Clone(c.resolved);
  if (copy.IsMap()) copy.remove("output");
  for (const auto& key : restart_keys) remove_key(copy, key);
  YAML::Emitter out;
  out << copy;
  return out.c_str();
}

std::optional<CaseDifference> first_case_difference(const std::string& written, const std::string& current) {
  if (written == current) return std::nullopt;
  const CaseDifference whole{"(the case text)", "another case", "this one"};
  try {
    return difference(YAML::Load(written), YAML::Load(current), "").value_or(whole);
  } catch (const YAML::Exception&) {
    return whole;
  }
}

LoadedCheckpoint load_newest_checkpoint(const std::filesystem::path& output_directory) {
  LoadedCheckpoint loaded;
  const auto files = io::find_checkpoints(output_directory);
  for (const auto& file : files) {
    try {
      loaded.state = std::make_unique<StateReader>(io::read_checkpoint(file));
      if (loaded.state->text("run.format") != "lamina checkpoint") throw StateError("not a lamina run checkpoint");
      loaded.file = file;
      return loaded;
    } catch (const StateError& e) {
      loaded.refused.push_back(fmt::format("{}: {}", file.string(), e.what()));
    }
  }
  std::string reasons;
  for (const auto& r : loaded.refused) reasons += "; " + r;
  throw InputError("--restart",
                   fmt::format("a folder holding a valid checkpoint_NNNNN.bin (a run with output.checkpoint, or one stopped "
                               "by SIGTERM / SIGINT)"),
                   files.empty() ? fmt::format("no checkpoint in {}", output_directory.string())
                                 : fmt::format("no readable checkpoint{}", reasons));
}

void install_stop_handlers() {
  received_signal = 0;
  std::signal(SIGTERM, record_stop_signal);
  std::signal(SIGINT, record_stop_signal);
}

void restore_stop_handlers() {
  std::signal(SIGTERM, SIG_DFL);
  std::signal(SIGINT, SIG_DFL);
}

int stop_signal() { return received_signal; }

}  // namespace lamina::app
