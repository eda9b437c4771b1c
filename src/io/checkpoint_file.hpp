#pragma once
// Checkpoint files (PRODUCT.md section 2): checkpoint_NNNNN.bin holds one StateWriter payload behind a
// header - magic "LAMINACK", format version, byte-order tag, payload size, CRC-32 of the payload - written
// atomically (temporary file, fsync, rename, fsync of the folder); the newest two are kept.
#include <cstdint>
#include <filesystem>
#include <vector>

#include "core/types.hpp"

namespace lamina::io {

inline constexpr std::uint32_t kCheckpointFormatVersion = 1;

/// Writes folder/checkpoint_<sequence>.bin atomically and removes all but the newest `keep` checkpoints
/// of the folder. Throws std::runtime_error when the file cannot be written.
std::filesystem::path write_checkpoint(const std::filesystem::path& folder, Index sequence, const std::vector<char>& payload,
                                       int keep = 2);

/// The payload of a checkpoint file; throws StateError (core/state_archive.hpp) with the reason when
/// the file is missing, truncated, of another format version or fails its checksum.
std::vector<char> read_checkpoint(const std::filesystem::path& file);

/// Verify a checkpoint held in memory (the same checks as read_checkpoint; fuzzing and tests).
std::vector<char> parse_checkpoint(const std::vector<char>& file_bytes);

/// The checkpoints a restart from `output_directory` can use: those in the folder itself and in the
/// staging folders of runs that were killed (`<folder>.partial-PID` of a dead process), newest first.
std::vector<std::filesystem::path> find_checkpoints(const std::filesystem::path& output_directory);

}  // namespace lamina::io
