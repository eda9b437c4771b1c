#include "io/result_set.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <stdexcept>

#include "io/vtu_writer.hpp"

namespace lamina::io {

namespace fs = std::filesystem;

ResultSet::ResultSet(fs::path output_directory) : destination_(std::move(output_directory)) {
  if (destination_.filename().empty()) destination_ = destination_.parent_path();
  fs::create_directories(destination_.parent_path().empty() ? fs::path(".") : destination_.parent_path());
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
