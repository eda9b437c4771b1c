#include "io/result_set.hpp"

#include <fmt/format.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>

#include <stdexcept>

#include "io/checkpoint_file.hpp"
#include "io/vtu_writer.hpp"

namespace lamina::io {

namespace fs = std::filesystem;

/// A folder of a live process (another run writing to the same destination) is not listed. PIDs are
/// of this machine: a folder on a shared file system written by a run on another host whose PID
/// happens to be free here is listed too.
std::vector<fs::path> staging_folders_of_dead_runs(const fs::path& destination) {
  std::vector<fs::path> folders;
  const fs::path parent = destination.parent_path().empty() ? fs::path(".") : destination.parent_path();
  const std::string prefix = destination.filename().string() + ".partial-";
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(parent, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(prefix, 0) != 0) continue;
    const std::string digits = name.substr(prefix.size());
    if (digits.empty() || digits.find_first_not_of("0123456789") != std::string::npos || digits.size() > 9) continue;
    const pid_t pid = static_cast<pid_t>(std::stol(digits));
    if (pid == ::getpid()) continue;
    if (::kill(pid, 0) == 0 || errno != ESRCH) continue;  // alive, or not ours to judge
    folders.push_back(entry.path());
  }
  std::sort(folders.begin(), folders.end());
  return folders;
}

ResultSet::ResultSet(fs::path output_directory, bool remove_stale) : destination_(std::move(output_directory)) {
  if (destination_.filename().empty()) destination_ = destination_.parent_path();
  fs::create_directories(destination_.parent_path().empty() ? fs::path(".") : destination_.parent_path());
  if (remove_stale) remove_stale_staging();
  staging_ = destination_;
  staging_ += fmt::format(".partial-{}", ::getpid());
  fs::remove_all(staging_);
  fs::create_directories(staging_);
  log_.open(staging_ / "log.txt");
}

ResultSet::~ResultSet() {
  if (!committed_) {
    std::error_code ignored;
    fs::remove_all(staging_, ignored);
  }
}

void ResultSet::begin_history(const std::vector<std::string>& probe_names) {
  history_.open(staging_ / "history.csv");
  history_ << "step,time,load_factor";
  for (const auto& name : probe_names) history_ << ',' << name;
  history_ << '\n';
  history_.flush();
}

void ResultSet::history_row(Index step, Real time, Real load_factor, const std::vector<Real>& probe_values) {
  history_ << step << ',' << fmt::format("{:.12g}", time) << ',' << fmt::format("{:.12g}", load_factor);
  for (Real v : probe_values) history_ << ',' << fmt::format("{:.12g}", v);
  history_ << '\n';
  history_.flush();
}

void ResultSet::write_frame(const OutputFrame& frame, Real time) {
  const std::string name = frame_name(frames_.size());
  write_vtu((staging_ / name).string(), frame);
  frames_.emplace_back(time, name);
  write_pvd((staging_ / "result.pvd").string(), frames_);
}

void ResultSet::write_parallel_frame(const OutputFrame& own_piece, Real time, int ranks) {
  const std::size_t k = frames_.size();
  write_piece(staging_, k, 0, own_piece);
  std::vector<std::string> pieces;
  for (int r = 0; r < ranks; ++r) pieces.push_back(piece_name(k, r));
  const std::string name = parallel_frame_name(k);
  write_pvtu((staging_ / name).string(), own_piece, pieces);
  frames_.emplace_back(time, name);
  write_pvd((staging_ / "result.pvd").string(), frames_);
}

void ResultSet::write_piece(const fs::path& staging, std::size_t k, int rank, const OutputFrame& piece) {
  write_vtu((staging / piece_name(k, rank)).string(), piece);
}

std::string ResultSet::piece_name(std::size_t k, int rank) { return fmt::format("frame_{:05d}_p{:04d}.vtu", k, rank); }

std::string ResultSet::parallel_frame_name(std::size_t k) { return fmt::format("frame_{:05d}.pvtu", k); }

std::vector<Real> ResultSet::frame_times() const {
  std::vector<Real> times;
  for (const auto& [time, name] : frames_) times.push_back(time);
  return times;
}

std::string ResultSet::frame_name(std::size_t k) { return fmt::format("frame_{:05d}.vtu", k); }

void ResultSet::adopt(const fs::path& folder, const std::vector<Real>& frame_times) {
  frames_.clear();
  for (std::size_t k = 0; k < frame_times.size(); ++k) {
    std::string name = frame_name(k);
    if (!fs::exists(folder / name) && fs::exists(folder / parallel_frame_name(k))) {
      name = parallel_frame_name(k);  // a run on several ranks: the .pvtu and its pieces
      const std::string pieces = fmt::format("frame_{:05d}_p", k);
      std::error_code ec;
      for (const auto& entry : fs::directory_iterator(folder, ec))
        if (entry.path().filename().string().rfind(pieces, 0) == 0)
          fs::copy_file(entry.path(), staging_ / entry.path().filename(), fs::copy_options::overwrite_existing);
    }
    if (!fs::exists(folder / name))
      throw std::runtime_error(fmt::format("restart: {} is missing from {}", name, folder.string()));
    fs::copy_file(folder / name, staging_ / name, fs::copy_options::overwrite_existing);
    frames_.emplace_back(frame_times[k], name);
  }
  if (!frames_.empty()) write_pvd((staging_ / "result.pvd").string(), frames_);
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("checkpoint_", 0) == 0 && entry.path().extension() == ".bin")
      fs::copy_file(entry.path(), staging_ / name, fs::copy_options::overwrite_existing);
  }
}

void ResultSet::remove_stale_staging() {
  for (const auto& folder : staging_folders_of_dead_runs(destination_)) {
    std::error_code ignored;
    fs::remove_all(folder, ignored);
  }
}

fs::path ResultSet::write_checkpoint(Index sequence, const std::vector<char>& payload) {
  return io::write_checkpoint(staging_, sequence, payload);
}

void ResultSet::log(const std::string& text) {
  log_ << text;
  if (!text.empty() && text.back() != '\n') log_ << '\n';
  log_.flush();
}

void ResultSet::write_summary(const nlohmann::json& summary) {
  std::ofstream out(staging_ / "summary.json");
  out << summary.dump(2) << '\n';
  if (!out) throw std::runtime_error("cannot write summary.json");
}

void ResultSet::commit() {
  history_.close();
  log_.close();
  fs::path old = destination_;
  old += fmt::format(".old-{}", ::getpid());
  const bool had_old = fs::exists(destination_);
  if (had_old) fs::rename(destination_, old);
  fs::rename(staging_, destination_);
  if (had_old) fs::remove_all(old);
  committed_ = true;
}

}  // namespace lamina::io
