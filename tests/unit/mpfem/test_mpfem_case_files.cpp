// `method: mpfem` end to end through the lamina binary (issue 21, criterion 4): a particle file is
// found relative to the case file's folder whatever the working directory (absolute names stay
// absolute), and a missing one is reported at discretization.particles.file with the path it was
// resolved to, exit 2, nothing written.
#include <gtest/gtest.h>

#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

namespace {

namespace fs = std::filesystem;

struct Outcome {
  int exit_code = -1;
  std::string output;
};

/// Runs `lamina ARGS` in working directory `cwd` (stdout and stderr together).
Outcome lamina_in(const fs::path& cwd, const std::string& args) {
  const std::string command = "cd '" + cwd.string() + "' && " + std::string(LAMINA_BINARY) + " " + args + " 2>&1";
  Outcome o;
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(command.c_str(), "r"), pclose);
  std::array<char, 4096> buffer{};
  while (fgets(buffer.data(), buffer.size(), pipe.get())) o.output += buffer.data();
  const int status = pclose(pipe.release());
  o.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return o;
}

std::string patch_case(const std::string& file) {
  return R"yaml(method: mpfem
materials: [{name: plate, model: linear_elastic, E: 1000.0, nu: 0.25}]
geometry: {type: box, min: [0, 0, 0], max: [2, 1, 0.1]}
discretization: {particles: {file: ')yaml" +
         file + R"yaml('}}
boundary:
  - select: {where: "x < 1e-9 or x > 2 - 1e-9 or y < 1e-9 or y > 1 - 1e-9"}
    displacement: {x: "1e-3*(1 + 2*x + 3*y)", y: "1e-3*(-1 + 1.5*x - y)"}
mpfem: {exact_displacement: ["1e-3*(1 + 2*x + 3*y)", "1e-3*(-1 + 1.5*x - y)"]}
output: {vtu: false}
)yaml";
}

class MpfemCaseFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("lamina_mpfem_paths_" + std::to_string(getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_ / "cases" / "cloud");
    fs::create_directories(root_ / "elsewhere");
    // a 5 x 3 grid with an interior particle moved off the grid lines
    std::ofstream csv(root_ / "cases" / "cloud" / "p.csv");
    csv << "x,y,z\n";
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 5; ++i) csv << (i == 2 && j == 1 ? 1.07 : 0.5 * i) << "," << (i == 2 && j == 1 ? 0.46 : 0.5 * j) << ",0.05\n";
  }
  void TearDown() override { fs::remove_all(root_); }
  void write_case(const std::string& name, const std::string& file) { std::ofstream(root_ / "cases" / name) << patch_case(file); }
  fs::path root_;
};

TEST_F(MpfemCaseFiles, ParticleFileIsFoundRelativeToTheCaseFile) {
  write_case("case.yaml", "cloud/p.csv");
  // absolute case path, another working directory
  Outcome o = lamina_in(root_ / "elsewhere", "run " + (root_ / "cases" / "case.yaml").string() + " -o out --quiet");
  ASSERT_EQ(o.exit_code, 0) << o.output;
  std::ifstream summary(root_ / "elsewhere" / "out" / "summary.json");
  const std::string text((std::istreambuf_iterator<char>(summary)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("\"err_displacement\""), std::string::npos) << text;
  // relative case path from the parent folder
  o = lamina_in(root_, "check cases/case.yaml");
  EXPECT_EQ(o.exit_code, 0) << o.output;
  // an absolute particle file name stays absolute
  write_case("absolute.yaml", (root_ / "cases" / "cloud" / "p.csv").string());
  o = lamina_in(root_ / "elsewhere", "check ../cases/absolute.yaml");
  EXPECT_EQ(o.exit_code, 0) << o.output;
}

TEST_F(MpfemCaseFiles, MissingParticleFileIsReportedWithItsResolvedPath) {
  write_case("missing.yaml", "cloud/missing.csv");
  const Outcome o = lamina_in(root_ / "elsewhere", "run ../cases/missing.yaml -o out --quiet");
  EXPECT_EQ(o.exit_code, 2) << o.output;
  EXPECT_NE(o.output.find("missing.yaml:4:"), std::string::npos) << o.output;
  EXPECT_NE(o.output.find("discretization.particles.file: expected an existing CSV file of x,y,z, found cannot open file "
                          "'cloud/missing.csv' (resolved to '" +
                          (root_ / "cases" / "cloud" / "missing.csv").string() + "': no such file)"),
            std::string::npos)
      << o.output;
  EXPECT_FALSE(fs::exists(root_ / "elsewhere" / "out"));
}

}  // namespace
