#include "app/run_command.hpp"

#include <fmt/format.h>
#include <omp.h>

#include <chrono>
#include <csignal>
#include <cmath>
#include <iostream>
#include <sstream>

#include "app/checkpointing.hpp"
#include "app/model.hpp"
#include "app/progress_line.hpp"
#include "core/error.hpp"
#include "core/memory.hpp"
#include "core/stopwatch.hpp"
#include "core/version.hpp"
#include "io/case_reader.hpp"
#include "io/checkpoint_file.hpp"
#include "io/omll_deck.hpp"
#include "io/result_set.hpp"
#include "parallel/communicator.hpp"

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

/// The piece of a whole-body frame rank `part` of `parts` writes: a contiguous block of the points for
/// point clouds (vertex cells); a frame with cells stays whole on rank 0 (empty pieces elsewhere).
OutputFrame rank_piece(const OutputFrame& whole, int part, int parts) {
  const Index n = whole.points.cols();
  Index first = n * part / parts, last = n * (part + 1) / parts;
  if (whole.cell_vertices > 1) {
    if (part == 0) return whole;
    first = last = 0;
  }
  OutputFrame piece;
  piece.points = whole.points.middleCols(first, last - first);
  for (const PointField& field : whole.point_fields)
    piece.point_fields.push_back(PointField{
        field.name, field.components,
        std::vector<Real>(field.values.begin() + first * field.components, field.values.begin() + last * field.components)});
  return piece;
}

/// Thrown out of Analysis::run by the sink when RunOptions::on_output asked to stop.
struct RunStopped {};

/// Receives output points from the analysis: evaluates probes, appends history, writes VTU.
class RunSink : public OutputSink {
 public:
  /// results: the result set on rank 0, null on the other ranks of a distributed run (which write their
  /// VTU pieces into `staging`, rank 0's staging folder).
  RunSink(Analysis& analysis, const io::Case& c, const Model& model, io::ResultSet* results, std::filesystem::path staging,
          ProgressLine& progress, const RunOptions& options, RunResult& result)
      : analysis_(analysis), case_(c), model_(model), results_(results), staging_(std::move(staging)), progress_(progress),
        options_(options), result_(result) {}

  void start() {
    result_.history_columns = {"step", "time", "load_factor"};
    for (const auto& p : model_.probes) names_.push_back(p.name);
    for (const auto& [name, value] : analysis_.builtin_probes()) builtin_names_.push_back(name);
    std::vector<std::string> all = names_;
    all.insert(all.end(), builtin_names_.begin(), builtin_names_.end());
    result_.history_columns.insert(result_.history_columns.end(), all.begin(), all.end());
    if (results_) results_->begin_history(all);
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
    if (results_) results_->history_row(step, time, load_factor, values);
    std::vector<Real> row{static_cast<Real>(step), time, load_factor};
    row.insert(row.end(), values.begin(), values.end());
    result_.history_rows.push_back(row);
    last_values_ = values;
    const bool vtu = case_.output.vtu && (output_count_ % case_.output.every == 0);
    if (vtu || options_.keep_last_frame) {
      OutputFrame frame = analysis_.frame();
      const auto& comm = parallel::Communicator::world();
      if (vtu && !comm.distributed()) results_->write_frame(frame, time);
      if (vtu && comm.distributed()) {  // one piece per rank, the .pvtu and .pvd on rank 0
        if (!analysis_.frame_is_rank_piece()) frame = rank_piece(frame, comm.rank(), comm.size());
        if (results_) results_->write_parallel_frame(frame, time, comm.size());
        else io::ResultSet::write_piece(staging_, frames_written_, comm.rank(), frame);
        ++frames_written_;
      }
      if (options_.keep_last_frame) result_.last_frame = std::move(frame);
    }
    ++output_count_;
    ++outputs_since_checkpoint_;
    if (options_.on_output) {
      std::vector<std::string> all = names_;
      all.insert(all.end(), builtin_names_.begin(), builtin_names_.end());
      if (!options_.on_output(OutputPointReport{step, time, load_factor, &all, &values})) throw RunStopped{};
    }
  }

  void progress(Real fraction, const std::string& status) override { progress_.update(fraction, status); }
  void notice(const std::string& text) override {
    if (results_) results_->log("NOTE: " + text);
    progress_.note(text);
  }

  /// output.checkpoint: every n-th output point and / or every s seconds; the case text the
  /// checkpoint must match on restart.
  void enable_checkpoints(int every, Real seconds, std::string case_text) {
    checkpoints_ = true;
    every_ = every;
    seconds_ = seconds;
    case_text_ = std::move(case_text);
    last_checkpoint_ = std::chrono::steady_clock::now();
  }

  void safe_point() override {
    if (!checkpoints_) return;
    int signal = stop_signal();
    bool due = signal != 0 || (every_ > 0 && outputs_since_checkpoint_ >= every_) ||
               (seconds_ > 0 && std::chrono::duration<double>(std::chrono::steady_clock::now() - last_checkpoint_).count() >= seconds_);
    const auto& comm = parallel::Communicator::world();
    if (comm.distributed()) {  // one decision for every rank: any rank's signal or clock
      std::vector<Real> flags{static_cast<Real>(signal), due ? 1.0 : 0.0};
      comm.max(flags);  // one reduction
      signal = static_cast<int>(flags[0]);
      due = flags[1] > 0;
    }
    if (due) write_checkpoint();
    if (signal != 0) throw RunInterrupted{signal};
  }

  void write_checkpoint() {
    StateWriter out;
    out.put("run.format", "lamina checkpoint");
    out.put("run.lamina_version", std::string(version));
    out.put("run.case", case_text_);
    out.put("run.threads", omp_get_max_threads());
    out.put("run.ranks", parallel::Communicator::world().size());
    out.put("run.sequence", ++sequence_);
    out.put("run.output_count", output_count_);
    const Index columns = static_cast<Index>(result_.history_columns.size());
    Eigen::MatrixXd history(columns, static_cast<Index>(result_.history_rows.size()));
    for (std::size_t r = 0; r < result_.history_rows.size(); ++r)
      for (Index k = 0; k < columns; ++k) history(k, static_cast<Index>(r)) = result_.history_rows[r][static_cast<std::size_t>(k)];
    out.put_matrix("run.history", history);
    out.put("run.frame_times", results_ ? results_->frame_times() : std::vector<Real>{});
    out.put("run.last_values", last_values_);
    analysis_.before_checkpoint();  // several ranks: collective; the state whole on every rank
    analysis_.save_state(out);
    analysis_.after_checkpoint();
    if (!results_) {  // rank 0 writes the checkpoint
      outputs_since_checkpoint_ = 0;
      last_checkpoint_ = std::chrono::steady_clock::now();
      return;
    }
    const auto file = results_->write_checkpoint(sequence_, out.bytes());
    const Index step = result_.history_rows.empty() ? 0 : static_cast<Index>(result_.history_rows.back().front());
    results_->log(fmt::format("checkpoint {} written after output step {} ({} bytes)", file.filename().string(), step,
                             out.bytes().size()));
    outputs_since_checkpoint_ = 0;
    last_checkpoint_ = std::chrono::steady_clock::now();
  }

  /// A restart: the history and counters of the run that wrote the checkpoint (after start()).
  void restore(const StateReader& in) {
    sequence_ = in.integer("run.sequence");
    output_count_ = in.integer("run.output_count");
    const Eigen::MatrixXd history = in.matrix("run.history");
    if (history.rows() != static_cast<Index>(result_.history_columns.size()))
      throw StateError(fmt::format("the checkpoint's history has {} columns, this run {}", history.rows(),
                                   result_.history_columns.size()));
    for (Index r = 0; r < history.cols(); ++r) {
      std::vector<Real> row(history.col(r).data(), history.col(r).data() + history.rows());
      if (results_) results_->history_row(static_cast<Index>(row[0]), row[1], row[2], std::vector<Real>(row.begin() + 3, row.end()));
      result_.history_rows.push_back(std::move(row));
    }
    last_values_ = in.reals("run.last_values");
    frames_written_ = in.reals("run.frame_times").size();
  }

  nlohmann::json probes_json() const {
    nlohmann::json probes = nlohmann::json::object();
    std::vector<std::string> all = names_;
    all.insert(all.end(), builtin_names_.begin(), builtin_names_.end());
    for (std::size_t i = 0; i < all.size() && i < last_values_.size(); ++i) probes[all[i]] = last_values_[i];
    return probes;
  }

 private:
  Analysis& analysis_;
  const io::Case& case_;
  const Model& model_;
  io::ResultSet* results_;
  std::filesystem::path staging_;
  std::size_t frames_written_ = 0;
  ProgressLine& progress_;
  const RunOptions& options_;
  RunResult& result_;
  std::vector<std::string> names_, builtin_names_;
  std::vector<Real> last_values_;
  Index output_count_ = 0;
  // checkpoints
  bool checkpoints_ = false;
  int every_ = 0;
  Real seconds_ = 0;
  std::string case_text_;
  Index sequence_ = 0, outputs_since_checkpoint_ = 0;
  std::chrono::steady_clock::time_point last_checkpoint_;
};

}  // namespace

namespace {

std::string implemented_method_names() {
  std::string names;
  for (const auto& m : methods()) names += (names.empty() ? "" : ", ") + m.keys.method;
  return names;
}

PreparedCase prepare(io::CaseReader& reader, const std::string& case_directory) {
  if (!case_directory.empty()) reader.sink().set_base_directory(case_directory);
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
  return method_keys();
}

PreparedCase prepare_case(const std::string& path, const std::vector<std::string>& overrides,
                          const std::string& case_directory) {
  if (io::is_omll_deck(path)) {
    io::OmllCase deck = io::read_omll_deck(path);  // deck errors: InputError with deck lines
    io::CaseReader reader(path, deck.document, deck.positions, overrides, all_method_keys());
    return prepare(reader, case_directory);
  }
  io::CaseReader reader(path, overrides, all_method_keys());
  return prepare(reader, case_directory);
}

RunResult run_case(const RunOptions& options) {
  RunResult result;
  const auto start = std::chrono::steady_clock::now();
  PreparedCase prepared;
  try {
    prepared = prepare_case(options.case_path, options.overrides, options.case_directory);
  } catch (const InputError& e) {
    result.exit_code = 2;
    result.error = e.what();
    return result;
  }
  const io::Case& c = prepared.case_data;
  if (options.threads > 0) omp_set_num_threads(options.threads);
  const auto& comm = parallel::Communicator::world();
  if (comm.distributed() && !prepared.method->distributed) {
    result.exit_code = 2;
    result.single_process_only = true;
    std::string distributed;
    for (const auto& m : methods())
      if (m.distributed) distributed += (distributed.empty() ? "" : ", ") + m.keys.method;
    result.error = locate(InputError("method", fmt::format("a method that runs on several ranks ({}) for a run on {} ranks; "
                                                           "run this case on one process (without mpirun / --ranks)",
                                                           distributed, comm.size()),
                                     c.method),
                          c)
                       .what();
    return result;
  }

  Model model;
  std::unique_ptr<Analysis> analysis;
  try {
    model = build_point_model(c, prepared.options ? prepared.options->model_request() : ModelRequest{});
    analysis = prepared.method->create(c, model, *prepared.options);
  } catch (const InputError& e) {
    result.single_process_only = dynamic_cast<const SingleProcessOnly*>(&e) != nullptr;
    result.exit_code = 2;
    result.error = locate(e, c).what();  // method set-up errors name a key: give its line
    return result;
  }
  const double setup_seconds = seconds_since(start);

  // --restart: the newest intact checkpoint, written by this case (apart from the restart keys)
  const std::string case_text = restart_invariant_case(c, prepared.method->restart_keys);
  LoadedCheckpoint checkpoint;
  const bool restart = !options.restart_directory.empty();
  std::vector<std::string> warnings = analysis->warnings();
  if (restart) {
    try {
      if (!analysis->can_checkpoint())
        throw InputError("--restart", "an incremental analysis (pd quasi_static / explicit, mpm)",
                         fmt::format("a {} analysis without a step-by-step state", c.method));
      checkpoint = load_newest_checkpoint(options.restart_directory);
      for (const auto& refused : checkpoint.refused) warnings.push_back("checkpoint refused, an older one used: " + refused);
      if (const auto d = first_case_difference(checkpoint.state->text("run.case"), case_text)) {
        std::string changeable = "output";
        for (const auto& k : prepared.method->restart_keys) changeable += ", " + k;
        throw locate(InputError(d->key_path,
                                fmt::format("{}, the value of the run that wrote {} (a restart may change only {})",
                                            d->written, checkpoint.file.filename().string(), changeable),
                                d->current),
                     c);
      }
      const auto written_ranks = checkpoint.state->has("run.ranks") ? checkpoint.state->integer("run.ranks") : 1;
      if (written_ranks != comm.size())
        warnings.push_back(fmt::format("the checkpoint was written by {} ranks, this run has {}: the continued run is not "
                                       "bit-identical to an uninterrupted one", written_ranks, comm.size()));
      const auto written_threads = checkpoint.state->integer("run.threads");
      if (written_threads != omp_get_max_threads())
        warnings.push_back(fmt::format("the checkpoint was written with {} threads, this run has {}: the continued run "
                                       "is not bit-identical to an uninterrupted one",
                                       written_threads, omp_get_max_threads()));
      analysis->restore_state(*checkpoint.state);
      // the result set the checkpoint continues must still hold the frames it lists
      const auto frame_times = checkpoint.state->reals("run.frame_times");
      for (std::size_t k = 0; k < frame_times.size(); ++k)
        if (!std::filesystem::exists(checkpoint.file.parent_path() / io::ResultSet::frame_name(k)) &&
            !std::filesystem::exists(checkpoint.file.parent_path() / io::ResultSet::parallel_frame_name(k)))
          throw InputError("--restart",
                           fmt::format("the result frames the checkpoint lists ({} VTU files) in {}", frame_times.size(),
                                       checkpoint.file.parent_path().string()),
                           fmt::format("no {}", io::ResultSet::frame_name(k)));
    } catch (const InputError& e) {
      result.exit_code = 2;
      result.error = e.what();
      return result;
    } catch (const StateError& e) {
      result.exit_code = 2;
      result.error = fmt::format("--restart: {} does not fit this case: {}", checkpoint.file.string(), e.what());
      return result;
    }
  } else if ((c.output.checkpoint_every > 0 || c.output.checkpoint_seconds > 0) && !analysis->can_checkpoint()) {
    warnings.push_back(fmt::format("output.checkpoint is ignored: a {} analysis of this kind has no incremental state",
                                   c.method));
  }

  result.output_directory = options.output_directory.empty() ? std::filesystem::path("out") / c.stem
                                                              : std::filesystem::path(options.output_directory);
  // the result set is rank 0's; the other ranks of a distributed run write their VTU pieces into its staging folder
  std::unique_ptr<io::ResultSet> result_set;
  if (comm.root()) result_set = std::make_unique<io::ResultSet>(result.output_directory, !restart);
  const std::filesystem::path staging = comm.broadcast(result_set ? result_set->staging().string() : std::string());
  struct RootLog {  // log lines and files: rank 0 only
    io::ResultSet* set;
    void log(const std::string& text) const {
      if (set) set->log(text);
    }
  } results{result_set.get()};
  if (restart && result_set) {
    result_set->adopt(checkpoint.file.parent_path(), checkpoint.state->reals("run.frame_times"));
    result_set->remove_stale_staging();
  }
  std::ostringstream header;
  header << fmt::format("lamina {} ({} build, {} threads{})\ncase: {} ({})\nmethod: {}\nunits: {}\nnodes: {}\n", version,
                        build_type, omp_get_max_threads(),
                        comm.distributed() ? fmt::format(" per rank, {} MPI ranks", comm.size()) : std::string(), c.file, c.title, c.method, c.units.empty() ? "(not given)" : c.units,
                        model.cloud.size());
  results.log(header.str());
  if (restart) results.log(fmt::format("restarted from {}", checkpoint.file.string()));
  results.log("resolved case:\n" + resolved_yaml(c) + "\n");
  for (const auto& w : warnings) {
    results.log("WARNING: " + w);
    if (!options.quiet && comm.root()) fmt::print(stderr, "lamina: warning: {}\n", w);
  }

  ProgressLine progress(options.quiet || !comm.root());
  RunSink sink(*analysis, c, model, result_set.get(), staging, progress, options, result);
  nlohmann::json summary;
  summary["case"] = c.stem;
  summary["title"] = c.title;
  summary["method"] = c.method;
  if (comm.distributed()) summary["ranks"] = comm.size();
  summary["lamina_version"] = version;
  if (!c.units.empty()) summary["units"] = c.units;
  if (!warnings.empty()) summary["warnings"] = warnings;
  const auto run_start = std::chrono::steady_clock::now();
  struct StopHandlers {  // SIGTERM / SIGINT recorded for the next safe point while the analysis runs
    explicit StopHandlers(bool on) : on(on) {
      if (on) install_stop_handlers();
    }
    ~StopHandlers() {
      if (on) restore_stop_handlers();
    }
    bool on;
  } stop_handlers(analysis->can_checkpoint());
  if (analysis->can_checkpoint())
    sink.enable_checkpoints(c.output.checkpoint_every, c.output.checkpoint_seconds, case_text);
  if (restart) summary["restarted_from"] = checkpoint.file.string();
  try {
    sink.start();
    if (restart) sink.restore(*checkpoint.state);
    analysis->run(sink);
    summary["status"] = "ok";
  } catch (const RunInterrupted& stop) {
    result.exit_code = 128 + stop.signal;
    result.error = fmt::format("stopped by {} after writing a checkpoint; continue with --restart {}",
                               stop.signal == SIGTERM ? "SIGTERM" : stop.signal == SIGINT ? "SIGINT" : "a signal",
                               result.output_directory.string());
    summary["status"] = "interrupted";
    summary["error"] = result.error;
  } catch (const RunStopped&) {
    summary["status"] = "stopped";  // on_output returned false: a clean end at that output point
  } catch (const StateError& e) {
    result.exit_code = 2;
    result.error = fmt::format("--restart: {} does not fit this case: {}", checkpoint.file.string(), e.what());
    return result;
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
  // peak resident memory: this process, and on several ranks their sum and largest
  const Real peak = static_cast<Real>(peak_resident_bytes());
  summary["memory"] = {{"peak_bytes", comm.sum(peak)}, {"peak_bytes_largest_rank", comm.max(peak)}};
  comm.barrier();  // every rank's pieces are written before rank 0 moves the folder into place
  if (!result_set) {
    result.summary = summary;
    return result;
  }
  result_set->write_summary(summary);
  results.log(result.exit_code == 0    ? "NORMAL TERMINATION"
              : result.exit_code >= 128 ? "INTERRUPTED: " + result.error
                                        : "ERROR TERMINATION: " + result.error);
  results.log(fmt::format("total time {:.3f} s", seconds_since(start)));
  result_set->commit();
  result.summary = summary;
  return result;
}

int check_case(const std::string& path, const std::vector<std::string>& overrides) {
  PreparedCase prepared = prepare_case(path, overrides);
  const io::Case& c = prepared.case_data;
  // resolves every selection: empty ones are errors
  Model model = build_point_model(c, prepared.options ? prepared.options->model_request() : ModelRequest{});
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
    std::cout << fmt::format("# boundary.{}: {} -> {} nodes\n", i, c.boundary[i].select.spec.describe(), model.constraints[i].select.nodes.size());
  for (std::size_t i = 0; i < c.loads.size(); ++i)
    std::cout << fmt::format("# loads.{}: {} -> {} nodes\n", i, c.loads[i].select.spec.describe(), model.loads[i].select.nodes.size());
  std::cout << resolved_yaml(c) << "\n";
  return 0;
}

}  // namespace lamina::app
