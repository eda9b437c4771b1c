#include "app/run_command.hpp"

#include <fmt/format.h>
#include <omp.h>

#include <chrono>
#include <cmath>
#include <iostream>
#include <sstream>

#include "app/model.hpp"
#include "app/progress_line.hpp"
#include "core/error.hpp"
#include "core/version.hpp"
#include "io/case_reader.hpp"
#include "io/omll_deck.hpp"
#include "io/result_set.hpp"

namespace lamina::app {

namespace {

std::vector<io::MethodKeys> method_keys() {
  std::vector<io::MethodKeys> keys;
  for (const auto& m : methods()) keys.push_back(m.keys);
  return keys;
}

std::string resolved_yaml(const io::Case& c) {
  YAML::Emitter out;
  out << c.resolved;
  return out.c_str();
}

/// Receives output points from the analysis: evaluates probes, appends history, writes VTU.
class RunSink : public OutputSink {
 public:
  RunSink(const Analysis& analysis, const io::Case& c, const Model& model, io::ResultSet& results, ProgressLine& progress,
          RunResult& result)
      : analysis_(analysis), case_(c), model_(model), results_(results), progress_(progress), result_(result) {}

  void start() {
    result_.history_columns = {"step", "time", "load_factor"};
    for (const auto& p : model_.probes) names_.push_back(p.name);
    for (const auto& [name, value] : analysis_.builtin_probes()) builtin_names_.push_back(name);
    std::vector<std::string> all = names_;
    all.insert(all.end(), builtin_names_.begin(), builtin_names_.end());
    result_.history_columns.insert(result_.history_columns.end(), all.begin(), all.end());
    results_.begin_history(all);
  }

  void output_point(Index step, Real time, Real load_factor) override {
    std::vector<Real> values;
    for (const auto& p : model_.probes) {
      const Real v = analysis_.probe(p);
      if (!std::isfinite(v))
        throw AnalysisError(fmt::format("probe '{}' became non-finite at step {} (time {})", p.name, step, time));
      values.push_back(v);
    }
    const auto builtin = analysis_.builtin_probes();
    for (const auto& name : builtin_names_) values.push_back(builtin.at(name));
    results_.history_row(step, time, load_factor, values);
    std::vector<Real> row{static_cast<Real>(step), time, load_factor};
    row.insert(row.end(), values.begin(), values.end());
    result_.history_rows.push_back(row);
    last_values_ = values;
    if (case_.output.vtu && (output_count_ % case_.output.every == 0)) results_.write_frame(analysis_.frame(), time);
    ++output_count_;
  }

  void progress(Real fraction, const std::string& status) override { progress_.update(fraction, status); }

  nlohmann::json probes_json() const {
    nlohmann::json probes = nlohmann::json::object();
    std::vector<std::string> all = names_;
    all.insert(all.end(), builtin_names_.begin(), builtin_names_.end());
    for (std::size_t i = 0; i < all.size() && i < last_values_.size(); ++i) probes[all[i]] = last_values_[i];
    return probes;
  }

 private:
  const Analysis& analysis_;
  const io::Case& case_;
  const Model& model_;
  io::ResultSet& results_;
  ProgressLine& progress_;
  RunResult& result_;
  std::vector<std::string> names_, builtin_names_;
  std::vector<Real> last_values_;
  Index output_count_ = 0;
};

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

namespace {

/// The case keys of a method that is part of the product (PRODUCT.md section 5) but not
/// registered in this build: read like the others, so that only the method line is an error.
io::MethodKeys planned_method_keys(const std::string& name) {
  if (name == "pd") return io::MethodKeys{name, {"spacing", "horizon", "horizon_factor"}, true, {"imperfection"}};
  if (name == "mpm") return io::MethodKeys{name, {"elements", "grid"}, true, {"shell"}};
  if (name == "mpfem") return io::MethodKeys{name, {"particles", "jitter"}, true};
  return io::MethodKeys{name, {}, true};
}

std::string implemented_method_names() {
  std::string names;
  for (const auto& m : methods()) names += (names.empty() ? "" : ", ") + m.keys.method;
  return names;
}

PreparedCase prepare(io::CaseReader& reader) {
  PreparedCase prepared;
  prepared.case_data = reader.read();
  prepared.method = find_method(prepared.case_data.method);
  if (!prepared.method && !prepared.case_data.method.empty()) {
    const std::string& name = prepared.case_data.method;
    reader.top_level("method").error(
        fmt::format("a method implemented in this build ({}); '{}' is part of the product but not implemented yet",
                    implemented_method_names(), name),
        "'" + name + "'");
  }
  if (prepared.method) prepared.options = prepared.method->read_options(prepared.case_data, reader.method_section(prepared.case_data.method));
  reader.finish();
  return prepared;
}

}  // namespace

std::vector<io::MethodKeys> all_method_keys() {
  std::vector<io::MethodKeys> keys = method_keys();
  for (const auto& name : planned_methods())
    if (!find_method(name)) keys.push_back(planned_method_keys(name));
  return keys;
}

PreparedCase prepare_case(const std::string& path, const std::vector<std::string>& overrides) {
  if (io::is_omll_deck(path)) {
    io::OmllCase deck = io::read_omll_deck(path);  // deck errors: InputError with deck lines
    io::CaseReader reader(path, deck.document, deck.positions, overrides, all_method_keys());
    return prepare(reader);
  }
  io::CaseReader reader(path, overrides, all_method_keys());
  return prepare(reader);
}

RunResult run_case(const RunOptions& options) {
  RunResult result;
  const auto start = std::chrono::steady_clock::now();
  PreparedCase prepared;
  try {
    prepared = prepare_case(options.case_path, options.overrides);
  } catch (const InputError& e) {
    result.exit_code = 2;
    result.error = e.what();
    return result;
  }
  const io::Case& c = prepared.case_data;
  if (options.threads > 0) omp_set_num_threads(options.threads);

  Model model;
  std::unique_ptr<Analysis> analysis;
  try {
    model = build_point_model(c);
    analysis = prepared.method->create(c, model, *prepared.options);
  } catch (const InputError& e) {
    result.exit_code = 2;
    result.error = locate(e, c).what();  // method set-up errors name a key: give its line
    return result;
  }
  const double setup_seconds = seconds_since(start);

  result.output_directory = options.output_directory.empty() ? std::filesystem::path("out") / c.stem
                                                              : std::filesystem::path(options.output_directory);
  io::ResultSet results(result.output_directory);
  std::ostringstream header;
  header << fmt::format("lamina {} ({} build, {} threads)\ncase: {} ({})\nmethod: {}\nunits: {}\nnodes: {}\n", version,
                        build_type, omp_get_max_threads(), c.file, c.title, c.method, c.units.empty() ? "(not given)" : c.units,
                        model.cloud.size());
  results.log(header.str());
  results.log("resolved case:\n" + resolved_yaml(c) + "\n");
  const std::vector<std::string> warnings = analysis->warnings();
  for (const auto& w : warnings) {
    results.log("WARNING: " + w);
    if (!options.quiet) fmt::print(stderr, "lamina: warning: {}\n", w);
  }

  ProgressLine progress(options.quiet);
  RunSink sink(*analysis, c, model, results, progress, result);
  nlohmann::json summary;
  summary["case"] = c.stem;
  summary["title"] = c.title;
  summary["method"] = c.method;
  summary["lamina_version"] = version;
  if (!c.units.empty()) summary["units"] = c.units;
  if (!warnings.empty()) summary["warnings"] = warnings;
  const auto run_start = std::chrono::steady_clock::now();
  try {
    sink.start();
    analysis->run(sink);
    summary["status"] = "ok";
  } catch (const InputError& e) {
    result.exit_code = 2;
    result.error = locate(e, c).what();
    return result;  // nothing committed: the staging folder is removed
  } catch (const AnalysisError& e) {
    result.exit_code = 3;
    result.error = e.what();
    summary["status"] = "failed";
    summary["error"] = e.what();
  }
  progress.finish();
  const RunCounts counts = analysis->counts();
  summary["probes"] = sink.probes_json();
  summary["counts"] = {{"nodes", counts.nodes}, {"dofs", counts.dofs}, {"steps", counts.steps}};
  nlohmann::json timing = {{"setup_s", setup_seconds}, {"solve_s", seconds_since(run_start)}, {"total_s", seconds_since(start)}};
  for (const auto& [name, value] : analysis->timings()) timing["stage_" + name] = value;
  summary["timing"] = timing;
  results.write_summary(summary);
  results.log(result.exit_code == 0 ? "NORMAL TERMINATION" : "ERROR TERMINATION: " + result.error);
  results.log(fmt::format("total time {:.3f} s", seconds_since(start)));
  results.commit();
  result.summary = summary;
  return result;
}

int check_case(const std::string& path, const std::vector<std::string>& overrides) {
  PreparedCase prepared = prepare_case(path, overrides);
  const io::Case& c = prepared.case_data;
  Model model = build_point_model(c);  // resolves every selection: empty ones are errors
  std::vector<std::string> warnings;
  try {
    // the method's set-up checks too (e.g. a traction selection without an edge), as `run` would do them
    warnings = prepared.method->create(c, model, *prepared.options)->warnings();
  } catch (const InputError& e) {
    throw locate(e, c);
  }
  for (const auto& w : warnings) fmt::print(stderr, "lamina: warning: {}\n", w);
  std::cout << "# lamina check: " << c.file << " is valid\n";
  std::cout << fmt::format("# method {}, {} nodes, {} boundary conditions, {} loads, {} probes\n", c.method,
                           model.cloud.size(), c.boundary.size(), c.loads.size(), c.probes.size());
  for (std::size_t i = 0; i < c.boundary.size(); ++i)
    std::cout << fmt::format("# boundary.{}: {} -> {} nodes\n", i, c.boundary[i].select.spec.describe(), model.boundary_nodes[i].size());
  for (std::size_t i = 0; i < c.loads.size(); ++i)
    std::cout << fmt::format("# loads.{}: {} -> {} nodes\n", i, c.loads[i].select.spec.describe(), model.load_nodes[i].size());
  std::cout << resolved_yaml(c) << "\n";
  return 0;
}

}  // namespace lamina::app
