#include "app/validate_command.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>

#include "app/run_command.hpp"
#include "core/error.hpp"
#include "io/csv_table.hpp"
#include "io/yaml_reader.hpp"
#include "parallel/communicator.hpp"

#ifndef LAMINA_SOURCE_DIR
#define LAMINA_SOURCE_DIR "."
#endif

namespace lamina::app {

namespace fs = std::filesystem;

namespace {

struct CheckSpec {
  std::string quantity;                      // probe name (scalar) or table column (curve)
  std::string reference_column;              // column of the reference CSV
  std::optional<Real> reference_value;       // literal reference instead of a column
  std::map<std::string, std::string> row;    // selects the reference row by column values
  std::optional<std::string> x, reference_x; // curve comparison: interpolate lamina's x->quantity at reference_x
  Real rel_tol = 0.0, abs_tol = 0.0;
  std::optional<Real> max;                   // upper bound instead of a reference
  bool report_only = false;                  // shown next to its reference, not a pass mark
};

struct PlotSpec {
  std::string x, reference_x, title, xlabel, ylabel;
  std::vector<std::string> y, reference_y;
  std::map<std::string, std::string> reference_row;  // plot only reference rows with these column values
  bool log_x = false, log_y = false;
  std::optional<Real> relative_error_to;  // plot |y / value - 1| instead of y (convergence plots)
};

// Field snapshots of a run's VTU frames (e.g. buckling mode shapes along a load path): one contour
// panel of the component per requested time / load factor (the nearest frame of result.pvd).
struct SnapshotSpec {
  std::string field = "displacement", title;
  int component = 2;
  std::vector<Real> at;
};

struct RunSpec {
  std::string name;
  bool fast = true;  // part of --fast when its case is
  std::vector<std::string> overrides;
  std::string sweep_key, sweep_name;
  std::vector<std::string> sweep_values;
  std::vector<CheckSpec> checks;
  std::optional<PlotSpec> plot;
  std::optional<SnapshotSpec> snapshots;
};

struct ValidationCase {
  std::string name, title, description;
  fs::path directory;
  bool fast = false;
  std::string reference_file;
  std::vector<RunSpec> runs;
};

ValidationCase read_validation_case(const fs::path& directory) {
  ValidationCase v;
  v.directory = directory;
  v.name = directory.filename().string();
  const fs::path check_file = directory / "check.yaml";
  io::DiagnosticSink sink(check_file.string());
  YAML::Node document = io::load_yaml_file(check_file.string(), sink);
  sink.throw_if_any();
  io::NodeReader root(document, "", &sink);
  if (root.expect_map()) {
    v.title = root.string("title", v.name);
    v.description = root.string("description", "");
    v.fast = root.boolean("fast", false);
    v.reference_file = root.string("reference", "reference.csv");
    io::NodeReader runs = root.required("runs");
    if (runs.defined() && runs.expect_sequence()) {
      for (const auto& r : runs.elements()) {
        if (!r.expect_map()) continue;
        RunSpec run;
        run.name = r.string("name", std::nullopt);
        run.fast = r.boolean("fast", true);
        io::NodeReader set = r.child("set");
        if (set.defined() && set.expect_sequence())
          for (const auto& s : set.elements())
            if (auto text = s.as_string()) run.overrides.push_back(*text);
        io::NodeReader sweep = r.child("sweep");
        if (sweep.defined() && sweep.expect_map()) {
          run.sweep_key = sweep.string("key", std::nullopt);
          run.sweep_name = sweep.string("name", run.sweep_key.substr(run.sweep_key.rfind('.') + 1));
          io::NodeReader values = sweep.required("values");
          if (values.defined() && values.expect_sequence())
            for (const auto& value : values.elements())
              if (auto text = value.as_string()) run.sweep_values.push_back(*text);
          sweep.reject_unknown_keys();
        }
        io::NodeReader checks = r.child("checks");
        if (checks.defined() && checks.expect_sequence()) {
          for (const auto& c : checks.elements()) {
            if (!c.expect_map()) continue;
            CheckSpec check;
            check.quantity = c.string("quantity", std::nullopt);
            if (c.has("reference")) {
              io::NodeReader ref = c.child("reference");
              char* end = nullptr;
              const std::string text = ref.is_scalar() ? ref.node().Scalar() : std::string();
              const double value = std::strtod(text.c_str(), &end);
              if (!text.empty() && end && *end == '\0') check.reference_value = value;
              else check.reference_column = ref.as_string().value_or("");
            }
            io::NodeReader row = c.child("row");
            if (row.defined() && row.expect_map())
              for (const auto& key : row.keys()) check.row[key] = row.string(key, std::nullopt);
            if (row.defined()) row.reject_unknown_keys();
            if (c.has("x")) check.x = c.string("x", std::nullopt);
            if (c.has("reference_x")) check.reference_x = c.string("reference_x", std::nullopt);
            check.rel_tol = c.real("rel_tol", 0.0, 0.0);
            check.abs_tol = c.real("abs_tol", 0.0, 0.0);
            if (c.has("max")) check.max = c.real("max", 0.0);
            check.report_only = c.boolean("report_only", false);
            if (!check.max && !check.reference_value && check.reference_column.empty())
              c.error("a reference (column name or number) or a max bound");
            if (!check.max && !check.report_only && check.rel_tol == 0.0 && check.abs_tol == 0.0)
              c.error("rel_tol and/or abs_tol (or report_only: true)");
            c.reject_unknown_keys();
            run.checks.push_back(check);
          }
        }
        io::NodeReader shots = r.child("snapshots");
        if (shots.defined() && shots.expect_map()) {
          SnapshotSpec sn;
          sn.field = shots.string("field", "displacement");
          sn.component = static_cast<int>(shots.integer("component", 2, 0, 2));
          if (auto at = shots.required("at").as_reals()) sn.at = *at;
          sn.title = shots.string("title", v.name + " / " + run.name + ": " + sn.field);
          shots.reject_unknown_keys();
          run.snapshots = sn;
        }
        io::NodeReader plot = r.child("plot");
        if (plot.defined() && plot.expect_map()) {
          PlotSpec p;
          p.x = plot.string("x", std::nullopt);
          for (const auto& y : plot.required("y").elements()) p.y.push_back(y.as_string().value_or(""));
          p.reference_x = plot.string("reference_x", "");
          if (plot.has("reference_y"))
            for (const auto& y : plot.child("reference_y").elements()) p.reference_y.push_back(y.as_string().value_or(""));
          p.title = plot.string("title", v.name + " / " + run.name);
          p.xlabel = plot.string("xlabel", p.x);
          p.ylabel = plot.string("ylabel", "");
          io::NodeReader row = plot.child("reference_row");
          if (row.defined() && row.expect_map()) {
            for (const auto& key : row.keys()) p.reference_row[key] = row.string(key, std::nullopt);
            row.reject_unknown_keys();
          }
          p.log_x = plot.boolean("log_x", false);
          p.log_y = plot.boolean("log_y", false);
          if (plot.has("relative_error_to")) p.relative_error_to = plot.real("relative_error_to", 0.0);
          plot.reject_unknown_keys();
          run.plot = p;
        }
        r.reject_unknown_keys();
        v.runs.push_back(run);
      }
    }
    root.reject_unknown_keys();
  }
  sink.throw_if_any();
  return v;
}

/// A lamina table: columns + numeric rows (a run's history, or a sweep's final probes).
struct Table {
  std::vector<std::string> columns;
  std::vector<std::vector<Real>> rows;
  int column(const std::string& name) const {
    auto it = std::find(columns.begin(), columns.end(), name);
    return it == columns.end() ? -1 : static_cast<int>(it - columns.begin());
  }
};

std::optional<Real> interpolate(const Table& t, const std::string& x, const std::string& y, Real at) {
  const int cx = t.column(x), cy = t.column(y);
  if (cx < 0 || cy < 0 || t.rows.empty()) return std::nullopt;
  std::vector<std::pair<Real, Real>> points;
  for (const auto& row : t.rows) points.emplace_back(row[cx], row[cy]);
  std::sort(points.begin(), points.end());
  const Real span = points.back().first - points.front().first;
  const Real slack = 1e-9 * std::max<Real>(1.0, std::abs(span));
  if (at < points.front().first - slack || at > points.back().first + slack) return std::nullopt;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (std::abs(points[i].first - at) <= slack) return points[i].second;
    if (i > 0 && at < points[i].first) {
      const Real s = (at - points[i - 1].first) / (points[i].first - points[i - 1].first);
      return points[i - 1].second + s * (points[i].second - points[i - 1].second);
    }
  }
  return points.back().second;
}

struct CheckRow {
  std::string case_name, run_name, quantity;
  Real lamina = NAN, reference = NAN, error = NAN, tolerance = NAN;
  std::string reference_text, error_kind;
  bool pass = false;
  bool report_only = false;
  double seconds = 0;
  std::string note;
};

std::string number(Real v) {
  if (std::isnan(v)) return "-";
  return fmt::format("{:.6g}", v);
}

bool within(Real lamina, Real reference, const CheckSpec& c, Real& error, Real& tolerance, std::string& kind) {
  const Real difference = std::abs(lamina - reference);
  if (c.rel_tol > 0 && c.abs_tol == 0) {
    error = reference != 0 ? difference / std::abs(reference) : difference;
    tolerance = c.rel_tol;
    kind = "rel";
  } else if (c.abs_tol > 0 && c.rel_tol == 0) {
    error = difference;
    tolerance = c.abs_tol;
    kind = "abs";
  } else {
    error = difference;
    tolerance = c.abs_tol + c.rel_tol * std::abs(reference);
    kind = "abs";
  }
  return std::isfinite(lamina) && error <= tolerance;
}

}  // namespace

int validate(const ValidateOptions& options) {
  const fs::path root = options.validation_directory.empty() ? fs::path(LAMINA_SOURCE_DIR) / "validation"
                                                             : fs::path(options.validation_directory);
  if (!fs::is_directory(root)) {
    std::cerr << "lamina validate: no validation folder at " << root << "\n";
    return 2;
  }
  std::vector<fs::path> folders;
  for (const auto& entry : fs::directory_iterator(root))
    if (entry.is_directory() && fs::exists(entry.path() / "check.yaml")) folders.push_back(entry.path());
  std::sort(folders.begin(), folders.end());
  for (const auto& name : options.names) {
    if (std::none_of(folders.begin(), folders.end(), [&](const fs::path& p) { return p.filename() == name; })) {
      std::cerr << fmt::format("lamina validate: unknown validation case '{}' (no {}/{}/check.yaml)\n", name, root.string(), name);
      return 2;
    }
  }

  std::vector<ValidationCase> cases;
  int status = 0;
  for (const auto& folder : folders) {
    const std::string name = folder.filename().string();
    if (!options.names.empty() && std::find(options.names.begin(), options.names.end(), name) == options.names.end()) continue;
    try {
      ValidationCase v = read_validation_case(folder);
      if (options.fast && options.names.empty() && !v.fast) continue;
      // the reference table is read (and refused when malformed) before anything runs
      const fs::path reference_path = v.directory / v.reference_file;
      if (fs::exists(reference_path)) io::CsvTable::read(reference_path.string());
      cases.push_back(v);
    } catch (const InputError& e) {
      std::cerr << e.what() << "\n";
      status = 2;
    } catch (const std::runtime_error& e) {  // a malformed reference table (file:line: expected, found)
      std::cerr << "lamina validate: " << e.what() << "\n";
      status = 2;
    }
  }
  if (status) return status;

  const fs::path out = options.output_directory;
  const auto& comm = parallel::Communicator::world();
  if (comm.root()) fs::create_directories(out);
  comm.barrier();
  std::vector<CheckRow> table;
  nlohmann::json plots = nlohmann::json::array();
  std::map<std::string, std::string> descriptions;
  std::map<std::string, std::vector<std::string>> sweep_labels;  // "case/run" -> swept values as written
  struct SweepTable {
    std::string case_name, run_name, key;
    Table table;
    std::vector<std::string> quantities;  // shown in the report's convergence table
    std::optional<Real> exact;            // relative errors against this value
  };
  std::vector<SweepTable> sweep_tables;

  for (const auto& v : cases) {
    descriptions[v.name] = v.title + (v.description.empty() ? "" : ". " + v.description);
    std::optional<io::CsvTable> reference;
    std::string reference_source;
    const fs::path reference_path = v.directory / v.reference_file;
    if (fs::exists(reference_path)) {
      reference = io::CsvTable::read(reference_path.string());
      for (const auto& comment : reference->comments) reference_source += (reference_source.empty() ? "" : " ") + comment;
    }
    for (const auto& run : v.runs) {
      if (options.fast && !run.fast) continue;
      const auto start = std::chrono::steady_clock::now();
      Table lamina;
      std::string failure;
      bool single_process_only = false;
      auto run_once = [&](const std::vector<std::string>& overrides, const fs::path& directory) -> std::optional<RunResult> {
        RunOptions ro;
        ro.case_path = (v.directory / "case.yaml").string();
        ro.output_directory = directory.string();
        ro.overrides = overrides;
        ro.quiet = true;
        ro.threads = options.threads;
        RunResult r = run_case(ro);
        if (r.single_process_only) {  // several ranks: a case that runs on one process only is not a failure
          single_process_only = true;
          failure = "runs on one process only";
          return std::nullopt;
        }
        if (r.exit_code != 0) {
          failure = fmt::format("run failed (exit {}): {}", r.exit_code, r.error);
          return std::nullopt;
        }
        return r;
      };
      nlohmann::json final_probes;
      if (!run.sweep_key.empty()) {
        // columns: the swept value (its level 1, 2, ... when it is not a number), nodes, dofs, probes
        lamina.columns = {run.sweep_name, "level", "nodes", "dofs"};
        const std::size_t fixed_columns = lamina.columns.size();
        for (std::size_t level = 0; level < run.sweep_values.size(); ++level) {
          const std::string& value = run.sweep_values[level];
          auto overrides = run.overrides;
          overrides.push_back(run.sweep_key + "=" + value);
          std::string folder = fmt::format("{}_{}", run.name, level + 1);
          auto r = run_once(overrides, out / v.name / folder);
          if (!r) break;
          if (lamina.columns.size() == fixed_columns)
            for (auto it = r->summary["probes"].begin(); it != r->summary["probes"].end(); ++it) lamina.columns.push_back(it.key());
          char* end = nullptr;
          const Real numeric = std::strtod(value.c_str(), &end);
          const bool is_number = end && *end == '\0' && !value.empty();
          std::vector<Real> row{is_number ? numeric : Real(level + 1), Real(level + 1),
                                r->summary["counts"].value("nodes", Real(0)), r->summary["counts"].value("dofs", Real(0))};
          sweep_labels[v.name + "/" + run.name].push_back(value);
          for (std::size_t c = fixed_columns; c < lamina.columns.size(); ++c) row.push_back(r->summary["probes"][lamina.columns[c]].get<Real>());
          lamina.rows.push_back(row);
          final_probes = r->summary["probes"];
        }
      } else if (auto r = run_once(run.overrides, out / v.name / run.name)) {
        lamina.columns = r->history_columns;
        lamina.rows = r->history_rows;
        final_probes = r->summary["probes"];
      }
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

      // lamina's table next to the report (for the plots and for users; rank 0 of a distributed run)
      if (comm.root()) {
        std::ofstream csv(out / fmt::format("{}_{}.csv", v.name, run.name));
        for (std::size_t c = 0; c < lamina.columns.size(); ++c) csv << (c ? "," : "") << lamina.columns[c];
        csv << "\n";
        for (const auto& row : lamina.rows) {
          for (std::size_t c = 0; c < row.size(); ++c) csv << (c ? "," : "") << fmt::format("{:.12g}", row[c]);
          csv << "\n";
        }
      }

      for (const auto& check : run.checks) {
        CheckRow row;
        row.case_name = v.name;
        row.run_name = run.name;
        row.quantity = check.quantity;
        row.seconds = seconds;
        if (!failure.empty()) {
          row.note = failure;
          row.report_only = single_process_only;
          row.pass = single_process_only;
          table.push_back(row);
          continue;
        }
        // reference rows that match the row filter
        std::vector<std::size_t> reference_rows;
        if (reference)
          for (std::size_t i = 0; i < reference->rows.size(); ++i) {
            bool match = true;
            for (const auto& [column, value] : check.row) {
              const int c = reference->column(column);
              if (c < 0 || reference->rows[i][static_cast<std::size_t>(c)] != value) match = false;
            }
            if (match) reference_rows.push_back(i);
          }
        if (check.max) {
          row.lamina = final_probes.contains(check.quantity) ? final_probes[check.quantity].get<Real>() : NAN;
          row.reference_text = "<= " + number(*check.max);
          row.error = row.lamina;
          row.tolerance = *check.max;
          row.error_kind = "value";
          row.pass = std::isfinite(row.lamina) && row.lamina <= *check.max;
        } else if (check.x) {
          // curve: worst error over the reference points
          Real worst = -1;
          row.pass = !reference_rows.empty();
          for (std::size_t i : reference_rows) {
            auto at = reference->number(i, check.reference_x.value_or(*check.x));
            auto ref = reference->number(i, check.reference_column);
            if (!at || !ref) continue;
            auto value = interpolate(lamina, *check.x, check.quantity, *at);
            Real error = NAN, tolerance = NAN;
            std::string kind;
            const bool ok = value && within(*value, *ref, check, error, tolerance, kind);
            row.pass = row.pass && ok;
            if (!value) error = INFINITY;
            if (error > worst || std::isnan(error)) {
              worst = error, row.lamina = value.value_or(NAN), row.reference = *ref, row.error = error,
              row.tolerance = tolerance, row.error_kind = kind;
              row.note = fmt::format("worst of {} points, at {} = {}", reference_rows.size(), *check.x, number(*at));
            }
          }
          if (check.report_only) {
            // the worst difference is shown; the row never fails the run
            row.tolerance = NAN;
            row.pass = true;
            row.report_only = true;
          }
        } else {
          row.lamina = final_probes.contains(check.quantity) ? final_probes[check.quantity].get<Real>() : NAN;
          if (check.reference_value) row.reference = *check.reference_value;
          else if (reference_rows.size() == 1) row.reference = reference->number(reference_rows[0], check.reference_column).value_or(NAN);
          else row.note = fmt::format("{} reference rows match", reference_rows.size());
          if (std::isnan(row.lamina)) row.note = "lamina has no probe '" + check.quantity + "'";
          row.pass = !std::isnan(row.reference) && within(row.lamina, row.reference, check, row.error, row.tolerance, row.error_kind);
          if (check.report_only) {
            // the relative difference is shown; the row never fails the run
            row.error = row.reference != 0 ? std::abs(row.lamina - row.reference) / std::abs(row.reference) : NAN;
            row.error_kind = "rel";
            row.tolerance = NAN;
            row.pass = true;
            row.report_only = true;
          }
        }
        if (row.reference_text.empty()) row.reference_text = number(row.reference);
        table.push_back(row);
      }

      if (!run.sweep_key.empty() && !lamina.rows.empty()) {
        SweepTable st{v.name, run.name, run.sweep_key, lamina, {}, std::nullopt};
        if (run.plot) st.quantities = run.plot->y, st.exact = run.plot->relative_error_to;
        for (const auto& check : run.checks)
          if (std::find(st.quantities.begin(), st.quantities.end(), check.quantity) == st.quantities.end())
            st.quantities.push_back(check.quantity);
        sweep_tables.push_back(st);
      }

      if (run.snapshots && !lamina.rows.empty()) {
        nlohmann::json p;
        p["kind"] = "snapshots";
        p["png"] = (out / fmt::format("{}_{}_snapshots.png", v.name, run.name)).string();
        p["title"] = run.snapshots->title;
        p["run_directory"] = (out / v.name / run.name).string();
        p["field"] = run.snapshots->field;
        p["component"] = run.snapshots->component;
        p["at"] = run.snapshots->at;
        plots.push_back(p);
      }
      if (run.plot && !lamina.rows.empty()) {
        nlohmann::json p;
        p["png"] = (out / fmt::format("{}_{}.png", v.name, run.name)).string();
        p["title"] = run.plot->title;
        p["xlabel"] = run.plot->xlabel;
        p["ylabel"] = run.plot->ylabel;
        p["log_x"] = run.plot->log_x;
        p["log_y"] = run.plot->log_y;
        if (run.plot->relative_error_to) p["relative_error_to"] = *run.plot->relative_error_to;
        p["lamina_csv"] = (out / fmt::format("{}_{}.csv", v.name, run.name)).string();
        p["x"] = run.plot->x;
        p["y"] = run.plot->y;
        p["reference_csv"] = reference ? reference_path.string() : "";
        p["reference_x"] = run.plot->reference_x;
        p["reference_y"] = run.plot->reference_y;
        p["reference_row"] = run.plot->reference_row;
        p["reference_label"] = reference_source;
        plots.push_back(p);
      }
    }
  }

  // console table, plots and report: rank 0 (every rank ran the same cases and checks)
  bool all_pass = true;
  for (const auto& r : table) all_pass = all_pass && r.pass;
  if (!comm.root()) return all_pass ? 0 : 1;
  std::cout << fmt::format("{:<28} {:<18} {:<8} {:>13} {:>13} {:>10} {:>10} {:>5} {:>8}\n", "case", "run", "quantity",
                           "lamina", "reference", "error", "tolerance", "pass", "time_s");
  for (const auto& r : table) {
    all_pass = all_pass && r.pass;
    std::cout << fmt::format("{:<28} {:<18} {:<8} {:>13} {:>13} {:>10} {:>10} {:>5} {:>8.2f}{}\n", r.case_name, r.run_name,
                             r.quantity, number(r.lamina), r.reference_text, number(r.error), number(r.tolerance),
                             r.report_only ? "INFO" : r.pass ? "PASS" : "FAIL", r.seconds, r.note.empty() ? "" : "  (" + r.note + ")");
  }

  // plots through matplotlib (Debian python3-matplotlib)
  std::string plot_status;
  if (!plots.empty()) {
    const fs::path spec = out / "plots.json";
    std::ofstream(spec) << plots.dump(2);
    const fs::path script = fs::path(LAMINA_SOURCE_DIR) / "scripts" / "plot_validation.py";
    const std::string command = fmt::format("/usr/bin/python3 '{}' '{}' > '{}' 2>&1", script.string(), spec.string(),
                                            (out / "plots.log").string());
    if (std::system(command.c_str()) != 0) plot_status = "plotting failed, see plots.log";
  }

  // report.md
  std::ofstream report(out / "report.md");
  report << "# lamina validation report\n\n";
  report << fmt::format("{} checks, {} passed, {} failed{}.\n\n", table.size(),
                        std::count_if(table.begin(), table.end(), [](const CheckRow& r) { return r.pass; }),
                        std::count_if(table.begin(), table.end(), [](const CheckRow& r) { return !r.pass; }),
                        options.fast ? " (fast subset)" : "");
  report << "| case | run | quantity | lamina | reference | error | tolerance | result | time (s) |\n";
  report << "|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& r : table)
    report << fmt::format("| {} | {} | {} | {} | {} | {} {} | {} | {} | {:.2f} |\n", r.case_name, r.run_name, r.quantity,
                          number(r.lamina), r.reference_text, number(r.error), r.error_kind, number(r.tolerance),
                          r.report_only ? std::string("reported (not a pass mark)")
                          : r.pass      ? std::string("pass")
                                        : "**FAIL**" + (r.note.empty() ? std::string() : " (" + r.note + ")"),
                          r.seconds);
  report << "\n";
  for (const auto& v : cases) {
    report << fmt::format("## {}\n\n{}\n\n", v.name, descriptions[v.name]);
    const fs::path readme = v.directory / "README.md";
    for (const auto& p : plots) {
      const std::string png = p["png"].get<std::string>();
      if (fs::path(png).filename().string().rfind(v.name + "_", 0) == 0 && fs::exists(png))
        report << fmt::format("![{}]({})\n\n", p["title"].get<std::string>(), fs::path(png).filename().string());
    }
    for (const auto& st : sweep_tables) {
      if (st.case_name != v.name) continue;
      const auto& labels = sweep_labels[st.case_name + "/" + st.run_name];
      report << fmt::format("Convergence, run `{}` (swept `{}`):\n\n| {} | nodes | dofs |", st.run_name, st.key,
                            st.table.columns[0]);
      for (const auto& q : st.quantities) report << " " << q << " |" << (st.exact ? " rel. error |" : "");
      report << "\n|---|---|---|";
      for (std::size_t i = 0; i < st.quantities.size(); ++i) report << (st.exact ? "---|---|" : "---|");
      report << "\n";
      for (std::size_t r = 0; r < st.table.rows.size(); ++r) {
        const auto& row = st.table.rows[r];
        report << fmt::format("| {} | {} | {} |", r < labels.size() ? labels[r] : number(row[0]), number(row[2]),
                              number(row[3]));
        for (const auto& q : st.quantities) {
          const int c = st.table.column(q);
          const Real value = c >= 0 ? row[c] : NAN;
          report << " " << number(value) << " |";
          if (st.exact) report << fmt::format(" {:.3g} % |", 100.0 * std::abs(value / *st.exact - 1.0));
        }
        report << "\n";
      }
      report << "\n";
    }
    if (fs::exists(readme)) report << fmt::format("Case description: `validation/{}/README.md`.\n\n", v.name);
  }
  if (!plot_status.empty()) report << "Note: " << plot_status << "\n";
  std::cout << fmt::format("report: {}\n", (out / "report.md").string());
  if (!plot_status.empty()) std::cout << plot_status << "\n";
  return all_pass ? 0 : 1;
}

}  // namespace lamina::app
