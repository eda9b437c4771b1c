// lamina — meshfree and particle analysis of thin-walled structures. Command-line entry point:
//   lamina run CASE.yaml [-o OUTDIR] [--threads N] [--set key.path=value ...] [--quiet] [--ranks N]
//   lamina check CASE.yaml [--set ...]
//   lamina convert DECK.omll                     (an OMLL macro deck as a lamina case, docs/omll.md)
//   lamina validate [NAME ...] [-o DIR] [--fast]
//   lamina info
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <omp.h>

#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <optional>

#include "app/method_registry.hpp"
#include "app/run_command.hpp"
#include "app/validate_command.hpp"
#include "core/memory.hpp"
#include "core/runtime_module.hpp"
#include "core/error.hpp"
#include "core/version.hpp"
#include "io/omll_deck.hpp"
#include "material/material_registry.hpp"
#include "parallel/communicator.hpp"

namespace {

int print_input_error(const lamina::InputError& e) {
  for (const auto& d : e.diagnostics()) std::cerr << "error: " << d.format() << "\n";
  return 2;
}

int info() {
  std::cout << fmt::format("lamina {}\nbuild type: {}\nthreads: {} (OpenMP, set OMP_NUM_THREADS or --threads)\n",
                           lamina::version, lamina::build_type, omp_get_max_threads());
  std::cout << "methods:\n";
  for (const auto& m : lamina::app::methods()) std::cout << fmt::format("  {:<8} {}\n", m.keys.method, m.summary);
  std::cout << "materials (E, nu, density and the constants listed):\n";
  for (const auto& m : lamina::material::material_models()) {
    std::string constants;
    for (const auto& k : m.constants)
      constants += fmt::format("{}{}{}", constants.empty() ? "" : ", ", k.key, k.fallback ? fmt::format(" = {:g}", *k.fallback) : "");
    std::cout << fmt::format("  {:<15} {}{}\n", m.name, m.description, constants.empty() ? "" : " [" + constants + "]");
  }
  std::cout << "features: yaml case files, --set overrides, VTU/PVD output, Gmsh .msh import, muParser expressions,\n"
               "          MLS shape functions (linear/quadratic, gauss/cubic/quartic spline, box/sphere/nearest/all/variable),\n"
               "          MPI ranks (OpenMPI; lamina run --ranks N: pd explicit partitioned by Zoltan RCB, mpm by elements,\n"
               "          efg / mpfem through PETSc: solver: mumps | cg with gamg | hypre; docs/scaling.md)\n";
  return 0;
}

/// `lamina run|validate ... --ranks N`: the same command on N processes under mpirun (which must be on the PATH);
/// threads per rank: --threads, else the cores shared out. Returns only when mpirun cannot be started.
int run_under_mpirun(int argc, char** argv, int ranks, int threads) {
  std::vector<std::string> args{"mpirun", "-np", std::to_string(ranks), "--oversubscribe", "--bind-to", "none", "--quiet"};
  if (::geteuid() == 0) args.push_back("--allow-run-as-root");
  std::error_code ec;
  const auto self = std::filesystem::read_symlink("/proc/self/exe", ec);
  args.push_back(ec ? std::string(argv[0]) : self.string());
  bool threads_given = false;
  for (int k = 1; k < argc; ++k) {
    const std::string a = argv[k];
    if (a == "--ranks") {
      ++k;  // and its value
      continue;
    }
    if (a.rfind("--ranks=", 0) == 0) continue;
    if (a == "--threads" || a.rfind("--threads=", 0) == 0) threads_given = true;
    args.push_back(a);
  }
  if (!threads_given) {
    args.push_back("--threads");
    args.push_back(std::to_string(std::max(1, threads > 0 ? threads : omp_get_num_procs() / ranks)));
  }
  std::vector<char*> raw;
  for (auto& a : args) raw.push_back(a.data());
  raw.push_back(nullptr);
  ::execvp("mpirun", raw.data());
  std::cerr << "error: --ranks: mpirun could not be started (install openmpi-bin): " << std::strerror(errno) << "\n";
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  lamina::use_huge_page_heap();  // before any thread starts (core/memory.hpp)
  lamina::select_blas_kernels();  // before any module loads OpenBLAS (core/runtime_module.hpp)
  std::optional<lamina::parallel::Environment> mpi;  // MPI only when started by mpirun
  try {
    mpi.emplace(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 3;
  }
  const auto& comm = lamina::parallel::Communicator::world();
  CLI::App cli{"lamina: meshfree and particle analysis of thin-walled structures"};
  cli.require_subcommand(1);
  cli.set_version_flag("--version", std::string(lamina::version));

  lamina::app::RunOptions run_options;
  auto* run = cli.add_subcommand("run", "run a case file and write its results");
  run->add_option("case", run_options.case_path, "case file (YAML), or an OMLL deck (*.omll)")->required();
  run->add_option("-o,--output", run_options.output_directory, "output folder (default out/<case stem>)");
  run->add_option("--threads", run_options.threads, "OpenMP threads (default: all)")->check(CLI::NonNegativeNumber);
  run->add_option("--set", run_options.overrides, "override a case value: key.path=value")->take_all();
  run->add_flag("--quiet", run_options.quiet, "no progress output");
  run->add_option("--restart", run_options.restart_directory,
                  "continue from the newest valid checkpoint in this result folder (docs/restart.md)");
  int ranks = 1;
  run->add_option("--ranks", ranks, "run on N MPI processes (starts mpirun; docs/scaling.md)")->check(CLI::PositiveNumber);

  std::string check_path;
  std::vector<std::string> check_overrides;
  auto* check = cli.add_subcommand("check", "validate a case file and print it resolved");
  check->add_option("case", check_path, "case file (YAML), or an OMLL deck (*.omll)")->required();
  check->add_option("--set", check_overrides, "override a case value: key.path=value")->take_all();

  std::string convert_path;
  auto* convert = cli.add_subcommand(
      "convert", "print an OMLL macro deck (seed 004, *.omll) as the equivalent lamina case YAML (docs/omll.md)");
  convert->add_option("deck", convert_path, "OMLL deck (*.omll)")->required();

  lamina::app::ValidateOptions validate_options;
  auto* validate = cli.add_subcommand("validate", "run the validation suite and write a report");
  validate->add_option("names", validate_options.names, "validation case names (default: all)");
  validate->add_option("-o,--output", validate_options.output_directory, "report folder (default out/validation)");
  validate->add_option("--dir", validate_options.validation_directory, "folder of validation cases");
  validate->add_flag("--fast", validate_options.fast, "only the fast subset (what CI runs)");
  validate->add_option("--threads", validate_options.threads, "OpenMP threads (default: all)");
  int validate_ranks = 1;
  validate->add_option("--ranks", validate_ranks,
                       "run every case on N MPI processes (starts mpirun); cases that run on one process only are "
                       "reported, not failed")
      ->check(CLI::PositiveNumber);

  auto* info_command = cli.add_subcommand("info", "version, build type, features, threads");

  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = cli.exit(e);
    return code == 0 ? 0 : 2;
  }

  try {
    if (*run) {
      if (ranks > 1 && !comm.distributed()) return run_under_mpirun(argc, argv, ranks, run_options.threads);
      if (ranks > 1 && comm.size() != ranks) {
        std::cerr << "error: --ranks " << ranks << " inside an mpirun of " << comm.size() << " processes\n";
        return 2;
      }
      const auto result = lamina::app::run_case(run_options);
      if (!comm.root()) return result.exit_code;  // rank 0 reports
      if (result.exit_code == 2) {
        std::cerr << "lamina run: invalid input, nothing was run\n";
        std::istringstream lines(result.error);
        for (std::string line; std::getline(lines, line);) std::cerr << "error: " << line << "\n";
      } else if (result.exit_code == 3) {
        std::cerr << "lamina run: the analysis failed: " << result.error << "\n"
                  << "the last good state is in " << result.output_directory.string() << "\n";
      } else if (result.exit_code >= 128) {
        std::cerr << "lamina run: " << result.error << "\n";
      } else if (!run_options.quiet) {
        std::cerr << "results: " << result.output_directory.string() << "\n";
      }
      return result.exit_code;
    }
    if (*check) return lamina::app::check_case(check_path, check_overrides);
    if (*convert) {
      if (!lamina::io::is_omll_deck(convert_path))
        throw lamina::InputError(lamina::Diagnostic{convert_path, 0, 0, "<file>", "an OMLL deck (*.omll)",
                                                    "'" + convert_path + "'"});
      std::cout << lamina::io::omll_case_yaml(lamina::io::read_omll_deck(convert_path), convert_path);
      return 0;
    }
    if (*validate) {
      if (validate_ranks > 1 && !comm.distributed()) return run_under_mpirun(argc, argv, validate_ranks, validate_options.threads);
      return lamina::app::validate(validate_options);
    }
    if (*info_command) return info();
  } catch (const lamina::InputError& e) {
    return print_input_error(e);
  } catch (const lamina::AnalysisError& e) {
    std::cerr << "lamina: the analysis failed: " << e.what() << "\n";
    return 3;
  } catch (const std::exception& e) {
    std::cerr << "lamina: internal error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
