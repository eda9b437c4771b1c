// ResultSet staging: a run writes into OUTDIR.partial-PID and renames it on commit; the staging
// folders of dead processes (a killed run) are removed by the next run, a live one's are kept.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "io/result_set.hpp"

namespace lamina::io {
namespace {

namespace fs = std::filesystem;

pid_t a_dead_pid() {
  const pid_t child = fork();
  if (child == 0) _exit(0);
  int status = 0;
  waitpid(child, &status, 0);
  return child;  // reaped: no such process now
}

TEST(io_ResultSet, StaleStagingOfDeadRunsIsRemovedAndLiveOnesKept) {
  const fs::path root = fs::temp_directory_path() / ("lamina_result_set_test_" + std::to_string(getpid()));
  fs::remove_all(root);
  fs::create_directories(root);
  const fs::path out = root / "out";
  const fs::path stale = root / ("out.partial-" + std::to_string(a_dead_pid()));
  const fs::path live = root / ("out.partial-" + std::to_string(getppid()));  // the parent runs
  const fs::path other = root / "other.partial-1";                           // another destination
  for (const auto& dir : {stale, live, other}) {
    fs::create_directories(dir);
    std::ofstream(dir / "log.txt") << "partial\n";
  }
  {
    ResultSet results(out);
    EXPECT_FALSE(fs::exists(stale));
    EXPECT_TRUE(fs::exists(live));
    EXPECT_TRUE(fs::exists(other));
  }
  // an uncommitted result set removes its own staging folder and leaves no destination
  EXPECT_FALSE(fs::exists(root / ("out.partial-" + std::to_string(getpid()))));
  EXPECT_FALSE(fs::exists(out));
  fs::remove_all(root);
}

}  // namespace
}  // namespace lamina::io
