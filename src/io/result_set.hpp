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

/// The staging folders `<destination>.partial-PID` of processes that no longer run (killed runs).
std::vector<std::filesystem::path> staging_folders_of_dead_runs(const std::filesystem::path& destination);

class ResultSet {
 public:
  /// remove_stale: remove the staging folders of dead runs now (a restart first adopts what it needs
  /// from one, then calls remove_stale_staging()).
  explicit ResultSet(std::filesystem::path output_directory, bool remove_stale = true);
  ~ResultSet();  // removes the staging folder if commit() was not called

  const std::filesystem::path& staging() const { return staging_; }
  const std::filesystem::path& destination() const { return destination_; }

  void begin_history(const std::vector<std::string>& probe_names);
  void history_row(Index step, Real time, Real load_factor, const std::vector<Real>& probe_values);
  /// Writes frame_<k>.vtu and refreshes result.pvd.
  void write_frame(const OutputFrame& frame, Real time);
  /// A frame of a run on `ranks` ranks: this rank's piece (frame_<k>_p<rank>.vtu, written by every rank
  /// with write_piece) plus, on rank 0, frame_<k>.pvtu and result.pvd (call on rank 0 only).
  void write_parallel_frame(const OutputFrame& own_piece, Real time, int ranks);
  /// Writes rank `rank`'s piece of frame k into a staging folder (ranks other than 0).
  static void write_piece(const std::filesystem::path& staging, std::size_t k, int rank, const OutputFrame& piece);
  static std::string piece_name(std::size_t k, int rank);
  /// The parallel file of frame k of a run on several ranks (frame_00000.pvtu, ...).
  static std::string parallel_frame_name(std::size_t k);
  /// Times of the frames written so far (frame k is frame_<k>.vtu).
  std::vector<Real> frame_times() const;
  /// The file name of VTU frame k (frame_00000.vtu, ...).
  static std::string frame_name(std::size_t k);
  /// A restart: copy the first frame_times.size() frames (.vtu, or .pvtu with its pieces) and the
  /// checkpoints of a folder written by an earlier run of the case into the staging folder, and list
  /// those frames in result.pvd.
  void adopt(const std::filesystem::path& folder, const std::vector<Real>& frame_times);
  void remove_stale_staging();
  /// checkpoint_<sequence>.bin in the staging folder (io/checkpoint_file.hpp); the newest two are kept.
  std::filesystem::path write_checkpoint(Index sequence, const std::vector<char>& payload);
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
