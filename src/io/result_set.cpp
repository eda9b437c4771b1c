#include "io/result_set.hpp"

#include <fmt/format.h>
#include <signal.h>
#include <unistd.h>

#include <cerrno>

#include <stdexcept>

#include "io/vtu_writer.hpp"

namespace lamina::io {

namespace fs = std::filesystem;

namespace {

/// Remove the staging folders `<destination>.partial-PID` left by processes that no longer run (a
/// killed run cannot clean up after itself). A folder of a live process (another run writing to the
/// same destination) is kept. PIDs are of this machine: a folder on a shared file system written by a
/// run on another host whose PID happens to be free here would be removed too.
void remove_stale_staging(const fs::path& destination) {
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
    std::error_code ignored;
    fs::remove_all(entry.path(), ignored);
  }
}

}  // namespace

ResultSet::ResultSet(fs::path output_directory) : destination_(std::move(output_directory)) {
  if (destination_.filename().empty()) destination_ = destination_.parent_path();
  fs::create_directories(destination_.parent_path().empty() ? fs::path(".") : destination_.parent_path());
  remove_stale_staging(destination_);
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
  const std::string name = fmt::format("frame_{:05d}.vtu", frames_.size());
  write_vtu((staging_ / name).string(), frame);
  frames_.emplace_back(time, name);
  write_pvd((staging_ / "result.pvd").string(), frames_);
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
