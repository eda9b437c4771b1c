#include "io/checkpoint_file.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>

#include "core/state_archive.hpp"
#include "io/result_set.hpp"

namespace lamina::io {

namespace fs = std::filesystem;

namespace {

constexpr char kMagic[8] = {'L', 'A', 'M', 'I', 'N', 'A', 'C', 'K'};
constexpr std::uint32_t kByteOrder = 0x01020304;
constexpr std::size_t kHeaderSize = 8 + 4 + 4 + 8 + 4 + 4;  // magic, version, byte order, size, crc, reserved

std::uint32_t checksum(const char* data, std::size_t size) {
  uLong crc = crc32(0L, Z_NULL, 0);
  while (size > 0) {  // zlib takes uInt lengths
    const uInt chunk = static_cast<uInt>(std::min<std::size_t>(size, 1u << 30));
    crc = crc32(crc, reinterpret_cast<const Bytef*>(data), chunk);
    data += chunk;
    size -= chunk;
  }
  return static_cast<std::uint32_t>(crc);
}

void write_all(int fd, const char* data, std::size_t size, const fs::path& file) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw std::runtime_error(fmt::format("cannot write {}: {}", file.string(), std::strerror(errno)));
    }
    data += n;
    size -= static_cast<std::size_t>(n);
  }
}

bool is_checkpoint_name(const std::string& name) {
  return name.size() > 15 && name.rfind("checkpoint_", 0) == 0 && name.substr(name.size() - 4) == ".bin" &&
         name.find_first_not_of("0123456789", 11) == name.size() - 4;
}

}  // namespace

fs::path write_checkpoint(const fs::path& folder, Index sequence, const std::vector<char>& payload, int keep) {
  std::vector<char> file(kHeaderSize);
  const std::uint32_t version = kCheckpointFormatVersion, order = kByteOrder, reserved = 0;
  const std::uint64_t size = payload.size();
  const std::uint32_t crc = checksum(payload.data(), payload.size());
  char* p = file.data();
  std::memcpy(p, kMagic, 8);
  std::memcpy(p + 8, &version, 4);
  std::memcpy(p + 12, &order, 4);
  std::memcpy(p + 16, &size, 8);
  std::memcpy(p + 24, &crc, 4);
  std::memcpy(p + 28, &reserved, 4);
  const fs::path target = folder / fmt::format("checkpoint_{:05d}.bin", sequence);
  fs::path temporary = target;
  temporary += ".tmp";
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error(fmt::format("cannot create {}: {}", temporary.string(), std::strerror(errno)));
  try {
    write_all(fd, file.data(), file.size(), temporary);
    write_all(fd, payload.data(), payload.size(), temporary);
    if (::fsync(fd) != 0) throw std::runtime_error(fmt::format("cannot sync {}: {}", temporary.string(), std::strerror(errno)));
  } catch (...) {
    ::close(fd);
    std::error_code ignored;
    fs::remove(temporary, ignored);
    throw;
  }
  ::close(fd);
  fs::rename(temporary, target);
  if (const int dir = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC); dir >= 0) {
    ::fsync(dir);  // the rename itself durable
    ::close(dir);
  }
  // keep the newest `keep` (by sequence number in the name)
  std::vector<fs::path> present;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(folder, ec))
    if (is_checkpoint_name(entry.path().filename().string())) present.push_back(entry.path());
  std::sort(present.begin(), present.end());
  for (std::size_t k = 0; k + static_cast<std::size_t>(std::max(keep, 1)) < present.size(); ++k) {
    std::error_code ignored;
    fs::remove(present[k], ignored);
  }
  return target;
}

std::vector<char> parse_checkpoint(const std::vector<char>& bytes) {
  if (bytes.size() < kHeaderSize) throw StateError(fmt::format("truncated: {} bytes, shorter than the header", bytes.size()));
  if (std::memcmp(bytes.data(), kMagic, 8) != 0) throw StateError("not a lamina checkpoint (bad magic)");
  std::uint32_t version = 0, order = 0, crc = 0;
  std::uint64_t size = 0;
  std::memcpy(&version, bytes.data() + 8, 4);
  std::memcpy(&order, bytes.data() + 12, 4);
  std::memcpy(&size, bytes.data() + 16, 8);
  std::memcpy(&crc, bytes.data() + 24, 4);
  if (order != kByteOrder) throw StateError("written on a machine of another byte order");
  if (version != kCheckpointFormatVersion)
    throw StateError(fmt::format("format version {}, this lamina reads version {}", version, kCheckpointFormatVersion));
  if (size != bytes.size() - kHeaderSize)
    throw StateError(fmt::format("truncated: the header states {} payload bytes, the file holds {}", size,
                                 bytes.size() - kHeaderSize));
  if (checksum(bytes.data() + kHeaderSize, bytes.size() - kHeaderSize) != crc)
    throw StateError("checksum mismatch (the file is damaged)");
  return std::vector<char>(bytes.begin() + static_cast<std::ptrdiff_t>(kHeaderSize), bytes.end());
}

std::vector<char> read_checkpoint(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw StateError("cannot be opened");
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return parse_checkpoint(bytes);
}

std::vector<fs::path> find_checkpoints(const fs::path& output_directory) {
  fs::path destination = output_directory;
  if (destination.filename().empty()) destination = destination.parent_path();
  std::vector<fs::path> folders{destination};
  for (const auto& folder : staging_folders_of_dead_runs(destination)) folders.push_back(folder);
  std::vector<std::pair<fs::file_time_type, fs::path>> found;
  for (const auto& folder : folders) {
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(folder, ec)) {
      if (!is_checkpoint_name(entry.path().filename().string())) continue;
      std::error_code time_error;
      const auto written = fs::last_write_time(entry.path(), time_error);
      if (!time_error) found.emplace_back(written, entry.path());
    }
  }
  std::sort(found.begin(), found.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first > b.first : a.second.filename() > b.second.filename();
  });
  std::vector<fs::path> paths;
  for (auto& [time, path] : found) paths.push_back(std::move(path));
  return paths;
}

}  // namespace lamina::io
