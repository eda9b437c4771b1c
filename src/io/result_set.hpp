#pragma once
// The files of one run (PRODUCT.md section 2): summary.json, history.csv, VTU frames + result.pvd,
// log.txt. Everything is written into a staging folder that replaces OUTDIR only in commit(),
// so an interrupted run never leaves a half-written result set in place of a good one.
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "core/analysis.hpp"

namespace lamina::io {

class ResultSet {
 public:
  explicit ResultSet(std::filesystem::path output_directory);
  ~ResultSet();  // removes the staging folder if commit() was not called

  const std::filesystem::path& staging() const { return staging_; }
  const std::filesystem::path& destination() const { return destination_; }

  void begin_history(const std::vector<std::string>& probe_names);
  void history_row(Index step, Real time, Real load_factor, const std::vector<Real>& probe_values);
  /// Writes frame_<k>.vtu and refreshes result.pvd.
  void write_frame(const OutputFrame& frame, Real time);
  void log(const std::string& text);
  void write_summary(const nlohmann::json& summary);
  /// Move the staging folder into place (replacing an older result set).
  void commit();

 private:
  std::filesystem::path destination_, staging_;
  std::ofstream history_, log_;
  std::vector<std::pair<Real, std::string>> frames_;
  bool committed_ = false;
};

}  // namespace lamina::io
