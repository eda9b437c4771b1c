// Checkpoint files (io/checkpoint_file.hpp) and their payload (core/state_archive.hpp): a round trip
// is exact; truncation, a flipped bit, another format version and a wrong record shape are refused
// with the reason; only the newest two files are kept; a killed run's checkpoints are found.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include "core/state_archive.hpp"
#include "io/checkpoint_file.hpp"

namespace lamina::io {
namespace {

namespace fs = std::filesystem;

fs::path fresh_folder(const std::string& name) {
  const fs::path root = fs::temp_directory_path() / (name + "_" + std::to_string(getpid()));
  fs::remove_all(root);
  fs::create_directories(root);
  return root;
}

std::vector<char> sample_payload() {
  StateWriter out;
  Eigen::Matrix3Xd x(3, 4);
  x << 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 1.0 / 3.0;
  out.put_matrix("x", x);
  out.put("time", std::nextafter(0.1, 1.0));
  out.put("nan", std::numeric_limits<Real>::quiet_NaN());
  out.put("steps", static_cast<std::int64_t>(1) << 40);
  out.put("flag", true);
  out.put("label", "grid");
  out.put("levels", std::vector<int>{3, -1, 7});
  out.put("history", std::vector<Real>{});
  return out.bytes();
}

TEST(io_Checkpoint, RoundTripIsBitExact) {
  const fs::path folder = fresh_folder("lamina_checkpoint_roundtrip");
  const fs::path file = write_checkpoint(folder, 3, sample_payload());
  EXPECT_EQ(file.filename(), "checkpoint_00003.bin");
  const StateReader in(read_checkpoint(file));
  Eigen::Matrix3Xd x(3, 4);
  in.matrix_into("x", x);
  EXPECT_EQ(x(2, 3), 1.0 / 3.0);
  EXPECT_EQ(in.real("time"), std::nextafter(0.1, 1.0));
  EXPECT_TRUE(std::isnan(in.real("nan")));
  EXPECT_EQ(in.integer("steps"), static_cast<std::int64_t>(1) << 40);
  EXPECT_TRUE(in.boolean("flag"));
  EXPECT_EQ(in.text("label"), "grid");
  EXPECT_EQ(in.ints("levels"), (std::vector<int>{3, -1, 7}));
  EXPECT_TRUE(in.reals("history").empty());
  fs::remove_all(folder);
}

TEST(io_Checkpoint, WrongShapeOrMissingRecordIsNamed) {
  const StateReader in(sample_payload());
  Eigen::Matrix3Xd wrong(3, 5);
  try {
    in.matrix_into("x", wrong);
    FAIL() << "a 3 x 4 record read into 3 x 5";
  } catch (const StateError& e) {
    EXPECT_NE(std::string(e.what()).find("'x' is 3 x 4"), std::string::npos) << e.what();
  }
  EXPECT_THROW(in.real("absent"), StateError);
  EXPECT_THROW(in.integer("time"), StateError);  // a real, not an integer
}

TEST(io_Checkpoint, DamageIsRefusedWithTheReason) {
  const fs::path folder = fresh_folder("lamina_checkpoint_damage");
  const fs::path file = write_checkpoint(folder, 1, sample_payload());
  std::ifstream in(file, std::ios::binary);
  const std::vector<char> good((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto refused_with = [](const std::vector<char>& bytes, const std::string& reason) {
    try {
      parse_checkpoint(bytes);
      return false;
    } catch (const StateError& e) {
      return std::string(e.what()).find(reason) != std::string::npos;
    }
  };
  EXPECT_NO_THROW(parse_checkpoint(good));
  EXPECT_TRUE(refused_with(std::vector<char>(good.begin(), good.end() - 1), "truncated"));
  EXPECT_TRUE(refused_with(std::vector<char>(good.begin(), good.begin() + 10), "truncated"));
  for (std::size_t at : {std::size_t(40), good.size() / 2, good.size() - 1}) {
    std::vector<char> flipped = good;
    flipped[at] ^= 0x01;
    EXPECT_TRUE(refused_with(flipped, "checksum")) << "bit flipped at byte " << at;
  }
  std::vector<char> other_version = good;
  other_version[8] = 9;
  EXPECT_TRUE(refused_with(other_version, "format version 9"));
  std::vector<char> not_ours = good;
  not_ours[0] = 'X';
  EXPECT_TRUE(refused_with(not_ours, "bad magic"));
  EXPECT_THROW(read_checkpoint(folder / "checkpoint_00099.bin"), StateError);
  // a payload whose records run past its end (checksum fixed up: only the record parser can tell)
  StateWriter w;
  w.put("a", 1.0);
  std::vector<char> cut = w.bytes();
  cut.pop_back();
  EXPECT_THROW(StateReader{cut}, StateError);
  fs::remove_all(folder);
}

TEST(io_Checkpoint, MalformedRecordsAreRefused) {
  // an integer record claiming 2^60 rows and 0 columns (found by checkpoint_reader_fuzzer: it read as
  // 2^60 integers), a real record larger than the payload, an empty name
  auto record = [](char kind, std::uint64_t rows, std::uint64_t cols, std::uint32_t name_length = 1) {
    std::vector<char> b;
    auto raw = [&](const void* p, std::size_t n) { b.insert(b.end(), static_cast<const char*>(p), static_cast<const char*>(p) + n); };
    raw(&name_length, 4);
    b.insert(b.end(), name_length, 'a');
    raw(&kind, 1);
    raw(&rows, 8);
    raw(&cols, 8);
    return b;
  };
  EXPECT_THROW(StateReader{record('i', std::uint64_t(1) << 60, 0)}, StateError);
  EXPECT_THROW(StateReader{record('t', 5, 0)}, StateError);
  EXPECT_THROW(StateReader{record('r', 1000, 1000)}, StateError);
  EXPECT_THROW(StateReader{record('r', 1, 1, 0)}, StateError);
  EXPECT_THROW(StateReader{record('x', 0, 1)}, StateError);
  EXPECT_NO_THROW(StateReader{record('r', 0, 5)});  // an empty matrix is fine
}

TEST(io_Checkpoint, NewestTwoAreKeptAndKilledRunsAreSearched) {
  const fs::path root = fresh_folder("lamina_checkpoint_keep");
  const fs::path out = root / "out";
  fs::create_directories(out);
  for (int k = 1; k <= 4; ++k) write_checkpoint(out, k, sample_payload());
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(out)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"checkpoint_00003.bin", "checkpoint_00004.bin"}));
  // a killed run (a dead PID) wrote a newer one into its staging folder
  const pid_t child = fork();
  if (child == 0) _exit(0);
  int status = 0;
  waitpid(child, &status, 0);
  const fs::path staging = root / ("out.partial-" + std::to_string(child));
  fs::create_directories(staging);
  const fs::path newest = write_checkpoint(staging, 5, sample_payload());
  fs::last_write_time(newest, fs::last_write_time(out / "checkpoint_00004.bin") + std::chrono::seconds(1));
  const auto found = find_checkpoints(out);
  ASSERT_EQ(found.size(), 3u);
  EXPECT_EQ(found[0], newest);
  EXPECT_EQ(found[1].filename(), "checkpoint_00004.bin");
  fs::remove_all(root);
}

}  // namespace
}  // namespace lamina::io
