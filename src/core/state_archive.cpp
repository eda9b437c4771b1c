#include "core/state_archive.hpp"

#include <fmt/format.h>

#include <cstring>

namespace lamina {

// Record layout: u32 name length, name, u8 kind ('r' reals, 'i' int64, 't' text), u64 rows, u64 cols,
// then rows * cols values (8 bytes each) or rows bytes of text.
namespace {
constexpr char kReals = 'r', kIntegers = 'i', kText = 't';
constexpr std::uint32_t kMaxName = 256;
}  // namespace

void StateWriter::raw(const void* data, std::size_t size) {
  const char* p = static_cast<const char*>(data);
  bytes_.insert(bytes_.end(), p, p + size);
}

void StateWriter::header(const std::string& name, char kind, std::uint64_t rows, std::uint64_t cols) {
  const std::uint32_t length = static_cast<std::uint32_t>(name.size());
  raw(&length, sizeof length);
  raw(name.data(), name.size());
  raw(&kind, 1);
  raw(&rows, sizeof rows);
  raw(&cols, sizeof cols);
}

void StateWriter::put_reals(const std::string& name, const Real* data, std::size_t count, std::uint64_t rows,
                            std::uint64_t cols) {
  header(name, kReals, rows, cols);
  raw(data, count * sizeof(Real));
}

void StateWriter::put_integers(const std::string& name, const std::int64_t* data, std::size_t count) {
  header(name, kIntegers, count, 1);
  raw(data, count * sizeof(std::int64_t));
}

void StateWriter::put(const std::string& name, const std::string& text) {
  header(name, kText, text.size(), 1);
  raw(text.data(), text.size());
}

void StateWriter::put(const std::string& name, const std::vector<int>& values) {
  const std::vector<std::int64_t> wide(values.begin(), values.end());
  put(name, wide);
}

StateReader::StateReader(std::vector<char> bytes) : bytes_(std::move(bytes)) {
  std::size_t at = 0;
  auto take = [&](void* into, std::size_t size, const char* what) {
    if (bytes_.size() - at < size) throw StateError(fmt::format("truncated record ({} at byte {})", what, at));
    std::memcpy(into, bytes_.data() + at, size);
    at += size;
  };
  while (at < bytes_.size()) {
    std::uint32_t length = 0;
    take(&length, sizeof length, "name length");
    if (length == 0 || length > kMaxName) throw StateError(fmt::format("bad record name length {} at byte {}", length, at));
    std::string name(length, '\0');
    take(name.data(), length, "name");
    Record r;
    take(&r.kind, 1, "kind");
    take(&r.rows, sizeof r.rows, "rows");
    take(&r.cols, sizeof r.cols, "cols");
    if (r.kind != kReals && r.kind != kIntegers && r.kind != kText)
      throw StateError(fmt::format("record '{}' has an unknown kind", name));
    if (r.kind != kReals && r.cols != 1) throw StateError(fmt::format("record '{}' has a bad shape", name));
    const std::uint64_t limit = bytes_.size() - at;
    if (r.cols != 0 && r.rows > limit / r.cols) throw StateError(fmt::format("record '{}' is larger than the file", name));
    const std::uint64_t count = r.rows * r.cols;
    const std::uint64_t size = r.kind == kText ? count : count * 8;
    if ((r.kind != kText && count > limit / 8) || size > limit)
      throw StateError(fmt::format("record '{}' is larger than the file", name));
    r.offset = at;
    at += static_cast<std::size_t>(size);
    if (!records_.emplace(name, r).second) throw StateError(fmt::format("record '{}' appears twice", name));
  }
}

std::vector<std::string> StateReader::names() const {
  std::vector<std::string> names;
  for (const auto& [name, record] : records_) names.push_back(name);
  return names;
}

const StateReader::Record& StateReader::find(const std::string& name, char kind) const {
  const auto it = records_.find(name);
  if (it == records_.end()) throw StateError(fmt::format("the checkpoint has no '{}'", name));
  if (it->second.kind != kind) throw StateError(fmt::format("checkpoint record '{}' has another type", name));
  return it->second;
}

void StateReader::shape_error(const std::string& name, Index rows, Index cols, Index want_rows, Index want_cols) {
  throw StateError(fmt::format("checkpoint record '{}' is {} x {}, this analysis has {} x {}", name, rows, cols, want_rows,
                               want_cols));
}

Real StateReader::real(const std::string& name) const {
  const Record& r = find(name, kReals);
  if (r.rows * r.cols != 1) shape_error(name, static_cast<Index>(r.rows), static_cast<Index>(r.cols), 1, 1);
  Real v;
  std::memcpy(&v, bytes_.data() + r.offset, sizeof v);
  return v;
}

std::int64_t StateReader::integer(const std::string& name) const {
  const Record& r = find(name, kIntegers);
  if (r.rows != 1) shape_error(name, static_cast<Index>(r.rows), 1, 1, 1);
  std::int64_t v;
  std::memcpy(&v, bytes_.data() + r.offset, sizeof v);
  return v;
}

std::string StateReader::text(const std::string& name) const {
  const Record& r = find(name, kText);
  return std::string(bytes_.data() + r.offset, static_cast<std::size_t>(r.rows));
}

std::vector<Real> StateReader::reals(const std::string& name) const {
  const Record& r = find(name, kReals);
  std::vector<Real> v(static_cast<std::size_t>(r.rows * r.cols));
  if (!v.empty()) std::memcpy(v.data(), bytes_.data() + r.offset, v.size() * sizeof(Real));
  return v;
}

std::vector<std::int64_t> StateReader::integers(const std::string& name) const {
  const Record& r = find(name, kIntegers);
  std::vector<std::int64_t> v(static_cast<std::size_t>(r.rows));
  if (!v.empty()) std::memcpy(v.data(), bytes_.data() + r.offset, v.size() * sizeof(std::int64_t));
  return v;
}

std::vector<int> StateReader::ints(const std::string& name) const {
  const std::vector<std::int64_t> wide = integers(name);
  return std::vector<int>(wide.begin(), wide.end());
}

Eigen::MatrixXd StateReader::matrix(const std::string& name) const {
  const Record& r = find(name, kReals);
  Eigen::MatrixXd m(static_cast<Index>(r.rows), static_cast<Index>(r.cols));
  if (m.size() > 0) std::memcpy(m.data(), bytes_.data() + r.offset, static_cast<std::size_t>(m.size()) * sizeof(Real));
  return m;
}

}  // namespace lamina
